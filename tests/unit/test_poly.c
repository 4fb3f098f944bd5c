/* test_poly.c — geo_poly storage and measures, topology (edges, fans,
 * boundary loops, non-manifold detection), plane fitting. */
#include "testutil.h"

#include <float.h>
#include <math.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "gen_garbage.h"
#include "gen_sphere.h"
#include "plane.h"
#include "poly.h"
#include "topo.h"
#include "vec.h"

static const double LO[3] = {0, 0, 0}, HI[3] = {1, 2, 3};

static void test_box_measures(void **state)
{
    (void)state;
    geo_poly *p = tu_box(LO, HI);
    assert_non_null(p);
    assert_int_equal(p->nverts, 8);
    assert_int_equal(p->nfacets, 6);
    assert_true(fabs(geo_poly_volume(p) - 6.0) < 1e-12);
    assert_true(fabs(geo_poly_area(p) - 22.0) < 1e-12);
    assert_true(geo_poly_max_nonplanarity(p) < 1e-15);
    /* planes are outward: the centre is inside every one */
    double c[3] = {0.5, 1, 1.5};
    for (uint32_t f = 0; f < p->nfacets; f++)
        assert_true(geo_plane_eval(p->planes[f], c) < 0);
    geo_poly_free(p);
}

static void test_notch_cube_volume(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    assert_non_null(p);
    assert_true(fabs(geo_poly_volume(p) - 936.0) < 1e-9);
    geo_poly_free(p);
}

static void test_from_arrays_rejects_bad_index_naming_place(void **state)
{
    (void)state;
    double v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t start[] = {0, 3}, idx[] = {0, 1, 7};
    geo_err err = {{0}};
    geo_poly *p = geo_poly_from_arrays(3, v, 1, start, idx, NULL, &err);
    assert_null(p);
    assert_string_equal(err.msg, "facets[0].vertices[2]: index 7 out of "
                                 "range (3 vertices)");
    uint32_t idx2[] = {0, 1, 1};
    p = geo_poly_from_arrays(3, v, 1, start, idx2, NULL, &err);
    assert_null(p);
    assert_non_null(strstr(err.msg, "repeated"));
    double bad[9] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    uint32_t idx3[] = {0, 1, 2};
    p = geo_poly_from_arrays(3, bad, 1, start, idx3, NULL, &err);
    assert_null(p);
    assert_string_equal(err.msg, "vertices[1][0]: not a finite number");
}

static void test_topo_box_is_closed_manifold(void **state)
{
    (void)state;
    geo_poly *p = tu_box(LO, HI);
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    assert_int_equal(t->nedges, 12);
    assert_true(geo_topo_is_closed_manifold(t));
    for (uint32_t c = 0; c < t->ncorners; c++) {
        uint32_t m = t->mate[c];
        assert_int_not_equal(m, GEO_NONE);
        assert_int_equal(t->mate[m], c);
        /* the mate runs the other way */
        assert_int_equal(p->fidx[m], p->fidx[geo_topo_next(p, t, c)]);
    }
    /* fans: every vertex has 3 corners, consecutive ones share an edge */
    for (uint32_t v = 0; v < p->nverts; v++) {
        assert_int_equal(t->vertex_kind[v], GEO_VERTEX_INTERIOR);
        uint32_t lo = t->vstart[v], hi = t->vstart[v + 1];
        assert_int_equal(hi - lo, 3);
        for (uint32_t i = lo; i < hi; i++) {
            uint32_t a = t->vcorners[i];
            uint32_t b = t->vcorners[i + 1 < hi ? i + 1 : lo];
            uint32_t fa = t->corner_facet[a], fb = t->corner_facet[b];
            bool adjacent =
                geo_topo_neighbor(t, a) == fb ||
                geo_topo_neighbor(t, geo_topo_prev(p, t, a)) == fb;
            assert_true(adjacent);
            assert_int_not_equal(fa, fb);
        }
    }
    geo_topo_free(t);
    geo_poly_free(p);
}

static void test_topo_flipped_facet_is_detected(void **state)
{
    (void)state;
    geo_poly *p = tu_box(LO, HI);
    geo_poly_flip_facet(p, 2);
    geo_topo *t = geo_topo_build(p, NULL);
    assert_int_equal(t->nflipped_edges, 4);
    assert_int_equal(t->nboundary_edges, 0);
    /* neighbours are still known across flipped edges */
    for (uint32_t c = p->fstart[2]; c < p->fstart[3]; c++)
        assert_int_not_equal(geo_topo_neighbor(t, c), GEO_NONE);
    assert_int_equal(t->nnonmanifold_vertices, 0);
    geo_topo_free(t);
    geo_poly_free(p);
}

static void test_topo_hole_gives_one_boundary_loop(void **state)
{
    (void)state;
    geo_poly *p = tu_box(LO, HI);
    bool keep[6] = {true, true, true, false, true, true};
    assert_int_equal(geo_poly_compact(p, keep, NULL, NULL), 0);
    assert_int_equal(p->nfacets, 5);
    assert_int_equal(p->nverts, 8);
    geo_topo *t = geo_topo_build(p, NULL);
    assert_int_equal(t->nboundary_edges, 4);
    uint32_t *start, *corners, n;
    assert_int_equal(geo_topo_boundary_loops(p, t, &start, &corners, &n), 0);
    assert_int_equal(n, 1);
    assert_int_equal(start[1], 4);
    for (uint32_t i = 0; i < 4; i++) {
        uint32_t c = corners[i], d = corners[(i + 1) % 4];
        /* each edge ends where the next begins */
        assert_int_equal(p->fidx[geo_topo_next(p, t, c)], p->fidx[d]);
    }
    for (uint32_t v = 0; v < p->nverts; v++)
        assert_int_not_equal(t->vertex_kind[v], GEO_VERTEX_NONMANIFOLD);
    free(start);
    free(corners);
    geo_topo_free(t);
    geo_poly_free(p);
}

/* Two boxes touching at one vertex: that vertex is non-manifold, every
 * edge is still interior. */
static void test_topo_pinched_vertex_is_nonmanifold(void **state)
{
    (void)state;
    geo_poly *a = tu_box(LO, (double[3]){1, 1, 1});
    geo_poly *b = tu_box((double[3]){1, 1, 1}, (double[3]){2, 2, 2});
    /* append b to a, sharing the vertex (1,1,1) */
    uint32_t map[8];
    for (uint32_t i = 0; i < 8; i++) {
        if (b->verts[i][0] == 1 && b->verts[i][1] == 1 && b->verts[i][2] == 1)
            map[i] = 7;
        else
            map[i] = (uint32_t)geo_poly_add_vertex(a, b->verts[i]);
    }
    for (uint32_t f = 0; f < b->nfacets; f++) {
        uint32_t idx[4];
        for (int k = 0; k < 4; k++)
            idx[k] = map[geo_poly_facet(b, f)[k]];
        geo_poly_add_facet(a, idx, 4);
    }
    geo_topo *t = geo_topo_build(a, NULL);
    assert_int_equal(t->nboundary_edges, 0);
    assert_int_equal(t->nnonmanifold_edges, 0);
    assert_int_equal(t->nnonmanifold_vertices, 1);
    assert_int_equal(t->vertex_kind[7], GEO_VERTEX_NONMANIFOLD);
    geo_topo_free(t);
    geo_poly_free(a);
    geo_poly_free(b);
}

static void test_plane_fit_recovers_plane(void **state)
{
    (void)state;
    double pts[20 * 3];
    uint64_t rng = 7;
    double n[3] = {1, 2, 2}; /* |n| = 3 */
    for (int i = 0; i < 20; i++) {
        double x = geo_rand_unit(&rng) * 10, y = geo_rand_unit(&rng) * 10;
        pts[3 * i] = x;
        pts[3 * i + 1] = y;
        pts[3 * i + 2] = (6 - x - 2 * y) / 2; /* x + 2y + 2z = 6 */
    }
    double pl[4];
    assert_int_equal(geo_plane_fit(pts, NULL, 20, n, pl), 0);
    assert_true(fabs(pl[0] - 1.0 / 3) < 1e-12);
    assert_true(fabs(pl[1] - 2.0 / 3) < 1e-12);
    assert_true(fabs(pl[2] - 2.0 / 3) < 1e-12);
    assert_true(fabs(pl[3] + 2.0) < 1e-12);
    /* collinear points are rejected */
    double line[9] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    assert_int_equal(geo_plane_fit(line, NULL, 3, NULL, pl), -EINVAL);
}

static void test_plane_intersect3_and_parallel(void **state)
{
    (void)state;
    double px[4] = {1, 0, 0, -1}, py[4] = {0, 1, 0, -2}, pz[4] = {0, 0, 1, -3};
    double r[3];
    assert_true(geo_plane_intersect3(px, py, pz, r));
    assert_true(fabs(r[0] - 1) < 1e-15 && fabs(r[1] - 2) < 1e-15 &&
                fabs(r[2] - 3) < 1e-15);
    double px2[4] = {1, 0, 0, 5};
    assert_false(geo_plane_intersect3(px, px2, pz, r));
}

static void test_sym3_eigen_and_spd_solve(void **state)
{
    (void)state;
    double m[3][3] = {{4, 1, 2}, {1, 3, 0.5}, {2, 0.5, 5}};
    double val[3], vec[3][3];
    geo_sym3_eigen(m, val, vec);
    assert_true(val[0] <= val[1] && val[1] <= val[2]);
    for (int k = 0; k < 3; k++) {
        double mv[3] = {0, 0, 0};
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                mv[i] += m[i][j] * vec[k][j];
        for (int i = 0; i < 3; i++)
            assert_true(fabs(mv[i] - val[k] * vec[k][i]) < 1e-12);
    }
    double b[3] = {1, 2, 3}, x[3];
    assert_true(geo_spd3_solve(m, b, x));
    for (int i = 0; i < 3; i++) {
        double s = 0;
        for (int j = 0; j < 3; j++)
            s += m[i][j] * x[j];
        assert_true(fabs(s - b[i]) < 1e-12);
    }
    double notpd[3][3] = {{1, 2, 0}, {2, 1, 0}, {0, 0, 1}};
    assert_false(geo_spd3_solve(notpd, b, x));
}

static double eig_rand(uint64_t *s) /* splitmix64, uniform in [0, 1) */
{
    uint64_t z = (*s += UINT64_C(0x9E3779B97F4A7C15));
    z = (z ^ (z >> 30)) * UINT64_C(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)) * UINT64_C(0x94D049BB133111EB);
    return (double)((z ^ (z >> 31)) >> 11) / 9007199254740992.0;
}

/* Eigenvalues, residuals and orthonormality of a solver's answer on m =
 * R·diag(l)·Rᵀ to rounding; with flat set, the normal as near R's first
 * column as the rounding of m allows (a few ulps of l₂ over l₁ − l₀). */
static void check_eigen(double m[3][3], const double l[3],
                        const double r[3][3], bool flat, bool jacobi)
{
    double val[3], vec[3][3];
    if (jacobi)
        geo_sym3_eigen_jacobi((const double(*)[3])m, val, vec);
    else
        geo_sym3_eigen(m, val, vec);
    double tol = 1e-13 * fmax(fabs(l[0]), fabs(l[2]));
    assert_true(val[0] <= val[1] && val[1] <= val[2]);
    for (int k = 0; k < 3; k++) {
        assert_true(fabs(val[k] - l[k]) <= tol);
        for (int i = 0; i < 3; i++) {
            double mv = 0;
            for (int j = 0; j < 3; j++)
                mv += m[i][j] * vec[k][j];
            assert_true(fabs(mv - val[k] * vec[k][i]) <= tol);
        }
        for (int j = 0; j < 3; j++)
            assert_true(fabs(geo_vdot(vec[k], vec[j]) - (j == k)) <= 1e-13);
    }
    if (flat) {
        double n[3] = {r[0][0], r[1][0], r[2][0]}, c[3];
        geo_vcross(vec[0], n, c);
        assert_true(geo_vlen(c) <= 8 * DBL_EPSILON * l[2] / (l[1] - l[0]));
    }
}

/* The closed form (with its Jacobi fallback) and Jacobi itself on the
 * matrices the plane fits give them — a facet's moments (one tiny
 * eigenvalue), a sliver's (two unequal small ones), a segment's (two
 * equal zeros), a disc's (two equal large ones), a scalar matrix,
 * anything — under random rotations. */
static void test_sym3_eigen_closed_form_on_every_spectrum(void **state)
{
    (void)state;
    uint64_t rng = 7;
    for (int trial = 0; trial < 6000; trial++) {
        double l[3];
        int kind = trial % 6;
        double big = 0.1 + eig_rand(&rng);
        switch (kind) {
        case 0: /* a facet: noise² against mm² */
            l[0] = 1e-12 * eig_rand(&rng), l[1] = 0.1 * big, l[2] = big;
            break;
        case 1: /* a sliver */
            l[0] = 1e-10 * eig_rand(&rng), l[1] = 1e-5 * big, l[2] = big;
            break;
        case 2: /* a segment */
            l[0] = l[1] = 0, l[2] = big;
            break;
        case 3: /* a disc */
            l[0] = 1e-9 * eig_rand(&rng), l[1] = l[2] = big;
            break;
        case 4: /* scalar, or nearly */
            l[0] = l[1] = big, l[2] = big * (1 + 1e-9 * eig_rand(&rng));
            break;
        default:
            for (int k = 0; k < 3; k++)
                l[k] = 2 * eig_rand(&rng) - 1;
            break;
        }
        for (int i = 0; i < 3; i++)
            for (int j = i + 1; j < 3; j++)
                if (l[j] < l[i]) {
                    double t = l[i];
                    l[i] = l[j];
                    l[j] = t;
                }
        /* R from a random unit quaternion */
        double qv[4], qn = 0;
        for (int k = 0; k < 4; k++) {
            qv[k] = 2 * eig_rand(&rng) - 1;
            qn += qv[k] * qv[k];
        }
        qn = sqrt(qn);
        double w = qv[0] / qn, x = qv[1] / qn, y = qv[2] / qn, z = qv[3] / qn;
        double r[3][3] = {
            {1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
            {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
            {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
        double m[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                m[i][j] = 0;
                for (int k = 0; k < 3; k++)
                    m[i][j] += r[i][k] * l[k] * r[j][k];
            }
        bool flat = kind <= 1 || kind == 3;
        check_eigen(m, l, (const double(*)[3])r, flat, false);
        check_eigen(m, l, (const double(*)[3])r, flat, true);
    }
}

static void test_compact_renumbers(void **state)
{
    (void)state;
    geo_poly *p = tu_box(LO, HI);
    double extra[3] = {9, 9, 9};
    geo_poly_add_vertex(p, extra); /* unused vertex 8 */
    uint32_t vmap[9], fmap[6];
    bool keep[6] = {true, true, true, true, true, true};
    assert_int_equal(geo_poly_compact(p, keep, vmap, fmap), 0);
    assert_int_equal(p->nverts, 8);
    assert_int_equal(vmap[8], UINT32_MAX);
    assert_int_equal(fmap[5], 5);
    assert_true(fabs(geo_poly_volume(p) - 6.0) < 1e-12);
    geo_poly_free(p);
}

/* geo_topo_build_lean is geo_topo_build_checked without corner_facet on
 * triangles: every other array and count the same, geo_topo_facet the
 * stored facet. */
static void check_lean(const geo_poly *p)
{
    geo_err err = {{0}};
    int rc = 0;
    geo_topo *a = geo_topo_build_checked(p, &rc, &err);
    geo_topo *b = geo_topo_build_lean(p, &rc, &err);
    assert_non_null(a);
    assert_non_null(b);
    bool tris = geo_poly_ncorners(p) == 3 * p->nfacets;
    assert_true((b->corner_facet == NULL) == tris);
    uint32_t nc = a->ncorners, nv = a->nverts;
    assert_int_equal(b->ncorners, nc);
    for (uint32_t c = 0; c < nc; c++) {
        assert_int_equal(geo_topo_facet(b, c), a->corner_facet[c]);
        assert_int_equal(geo_topo_next(p, b, c), geo_topo_next(p, a, c));
        assert_int_equal(geo_topo_prev(p, b, c), geo_topo_prev(p, a, c));
    }
    assert_memory_equal(a->mate, b->mate, nc * sizeof *a->mate);
    assert_memory_equal(a->edge_kind, b->edge_kind, nc);
    assert_memory_equal(a->vstart, b->vstart, (nv + 1) * sizeof *a->vstart);
    assert_memory_equal(a->vcorners, b->vcorners, nc * sizeof *a->vcorners);
    assert_memory_equal(a->vertex_kind, b->vertex_kind, nv);
    assert_int_equal(a->nedges, b->nedges);
    assert_int_equal(a->nboundary_edges, b->nboundary_edges);
    assert_int_equal(a->nnonmanifold_edges, b->nnonmanifold_edges);
    assert_int_equal(a->nflipped_edges, b->nflipped_edges);
    assert_int_equal(a->nnonmanifold_vertices, b->nnonmanifold_vertices);
    geo_topo_free(a);
    geo_topo_free(b);
}

static void test_lean_topology_is_the_same(void **state)
{
    (void)state;
    /* a sphere, then with a facet doubled, one flipped, one removed */
    geo_poly *s = gs_sphere(6, 1.0);
    assert_non_null(s);
    check_lean(s);
    uint32_t idx[3];
    memcpy(idx, geo_poly_facet(s, 5), sizeof idx);
    assert_true(geo_poly_add_facet(s, idx, 3) >= 0);
    geo_poly_flip_facet(s, 40);
    check_lean(s);
    bool *keep = malloc(s->nfacets * sizeof *keep);
    assert_non_null(keep);
    for (uint32_t f = 0; f < s->nfacets; f++)
        keep[f] = f != 77;
    assert_int_equal(geo_poly_compact(s, keep, NULL, NULL), 0);
    free(keep);
    check_lean(s);
    geo_poly_free(s);
    /* random facets on a 3x3x3 grid: every defect, polygons too */
    uint64_t rng = 7;
    for (int trial = 0; trial < 60; trial++) {
        geo_poly *g = gen_garbage_model(&rng);
        assert_non_null(g);
        check_lean(g);
        geo_poly_free(g);
    }
}

/* geo_plane_triples_meet answers as geo_plane_intersect3, bit for bit,
 * on random planes (normals of any length), parallel ones and repeated
 * sets of another size (the arrays reused). */
static void test_plane_triples_meet_as_intersect3(void **state)
{
    (void)state;
    uint64_t rng = 23;
    geo_plane_triples t = {0};
    double pl[40][4];
    for (int round = 0; round < 60; round++) {
        uint32_t k = 3 + (uint32_t)(geo_rand_next(&rng) % 38);
        for (uint32_t i = 0; i < k; i++)
            for (int c = 0; c < 4; c++)
                pl[i][c] = (geo_rand_unit(&rng) - 0.5) * (c == 3 ? 10 : 3);
        /* a parallel pair and a repeated plane */
        for (int c = 0; c < 4; c++)
            pl[1][c] = pl[0][c] * (c == 3 ? 1.5 : 2.0), pl[2][c] = pl[0][c];
        assert_int_equal(geo_plane_triples_set(&t, (const double(*)[4])pl, k),
                         0);
        for (uint32_t a = 0; a < k; a++)
            for (uint32_t b = a + 1; b < k; b++)
                for (uint32_t c = b + 1; c < k; c++) {
                    double x[3] = {7, 7, 7}, y[3] = {7, 7, 7};
                    bool u = geo_plane_intersect3(pl[a], pl[b], pl[c], x);
                    bool v = geo_plane_triples_meet(&t, a, b, c, y);
                    assert_int_equal(u, v);
                    for (int i = 0; i < 3; i++)
                        assert_true(x[i] == y[i]);
                }
    }
    geo_plane_triples_free(&t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_measures),
        cmocka_unit_test(test_sym3_eigen_closed_form_on_every_spectrum),
        cmocka_unit_test(test_plane_triples_meet_as_intersect3),
        cmocka_unit_test(test_notch_cube_volume),
        cmocka_unit_test(test_from_arrays_rejects_bad_index_naming_place),
        cmocka_unit_test(test_topo_box_is_closed_manifold),
        cmocka_unit_test(test_topo_flipped_facet_is_detected),
        cmocka_unit_test(test_topo_hole_gives_one_boundary_loop),
        cmocka_unit_test(test_topo_pinched_vertex_is_nonmanifold),
        cmocka_unit_test(test_plane_fit_recovers_plane),
        cmocka_unit_test(test_plane_intersect3_and_parallel),
        cmocka_unit_test(test_sym3_eigen_and_spd_solve),
        cmocka_unit_test(test_compact_renumbers),
        cmocka_unit_test(test_lean_topology_is_the_same),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
