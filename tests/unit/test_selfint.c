/* test_selfint.c — exact facet intersection tests: every kind of
 * self-intersection is found, every legal contact (shared vertex, shared
 * edge, neighbours meeting at an angle, slightly non-planar facets) is
 * not; the BVH search agrees with brute force and is independent of the
 * thread count; random convex polyhedra are clean until a vertex is pushed
 * through a facet. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "gen_convex.h"
#include "gen_sphere.h"
#include "parallel.h"
#include "selfint.h"
#include "vec.h"

/* A polyhedron (not necessarily closed) from vertex rows and facets
 * given as sizes + concatenated indices. */
static geo_poly *mk(const double (*v)[3], uint32_t nv, const uint32_t *sizes,
                    uint32_t nf, const uint32_t *idx)
{
    uint32_t start[64];
    start[0] = 0;
    for (uint32_t f = 0; f < nf; f++)
        start[f + 1] = start[f] + sizes[f];
    geo_poly *p = geo_poly_from_arrays(nv, &v[0][0], nf, start, idx, NULL,
                                       NULL);
    assert_non_null(p);
    return p;
}

static int pair(const geo_poly *p, uint32_t f, uint32_t g)
{
    geo_facet_shape sf, sg;
    geo_facet_shape_of(p, f, &sf);
    geo_facet_shape_of(p, g, &sg);
    int a = geo_facets_intersect(p, f, g, &sf, &sg);
    int b = geo_facets_intersect(p, g, f, &sg, &sf);
    assert_int_equal(a, b); /* symmetric */
    return a;
}

static uint64_t count_all(const geo_poly *p)
{
    geo_selfint r;
    geo_err err;
    assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &r, &err), 0);
    uint64_t c = r.count;
    geo_selfint_clear(&r);
    return c;
}

/* The square [0,2]² at z = 0 is facet 0 (vertices 0..3) in most cases. */
#define SQUARE {0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}

static void test_edge_piercing_facet_counts(void **state)
{
    (void)state;
    const double v[][3] = {SQUARE, {1, 0.5, -1}, {1, 1.5, -1}, {1, 1, 1}};
    const uint32_t sizes[] = {4, 3}, idx[] = {0, 1, 2, 3, 4, 5, 6};
    geo_poly *p = mk(v, 7, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 1);
    assert_int_equal(count_all(p), 1);
    geo_poly_free(p);
}

static void test_edge_passing_beside_facet_does_not_count(void **state)
{
    (void)state;
    const double v[][3] = {SQUARE, {3, 0.5, -1}, {3, 1.5, -1}, {3, 1, 1}};
    const uint32_t sizes[] = {4, 3}, idx[] = {0, 1, 2, 3, 4, 5, 6};
    geo_poly *p = mk(v, 7, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 0);
    geo_poly_free(p);
}

static void test_vertex_touching_interior_edge_or_vertex_counts(void **state)
{
    (void)state;
    /* the apex of a triangle above the square touches it at: its
     * interior, the middle of an edge (T-junction), a corner (another
     * index at the same position) */
    const double touch[3][3] = {{1, 1, 0}, {1, 0, 0}, {2, 2, 0}};
    for (int k = 0; k < 3; k++) {
        const double v[][3] = {SQUARE,
                               {touch[k][0], touch[k][1], touch[k][2]},
                               {0.5, 0.5, 1},
                               {1.5, 0.7, 1}};
        const uint32_t sizes[] = {4, 3}, idx[] = {0, 1, 2, 3, 4, 5, 6};
        geo_poly *p = mk(v, 7, sizes, 2, idx);
        assert_int_equal(pair(p, 0, 1), 1);
        geo_poly_free(p);
    }
}

static void test_coplanar_overlap_and_containment_count(void **state)
{
    (void)state;
    /* partial overlap; containment (no edges cross); touching along part
     * of an edge; touching at a single point of different index */
    const double quads[4][4][3] = {
        {{1, 1, 0}, {3, 1, 0}, {3, 3, 0}, {1, 3, 0}},
        {{0.5, 0.5, 0}, {1.5, 0.5, 0}, {1.5, 1.5, 0}, {0.5, 1.5, 0}},
        {{2, 0.5, 0}, {3, 0.5, 0}, {3, 1.5, 0}, {2, 1.5, 0}},
        {{2, 2, 0}, {3, 2, 0}, {3, 3, 0}, {2, 3, 0}},
    };
    for (int k = 0; k < 4; k++) {
        double v[8][3] = {SQUARE};
        memcpy(v[4], quads[k], sizeof quads[k]);
        const uint32_t sizes[] = {4, 4}, idx[] = {0, 1, 2, 3, 4, 5, 6, 7};
        geo_poly *p = mk((const double (*)[3])v, 8, sizes, 2, idx);
        assert_int_equal(pair(p, 0, 1), 1);
        geo_poly_free(p);
    }
    /* coplanar and apart: no contact */
    const double v[][3] = {SQUARE, {3, 0, 0}, {4, 0, 0}, {4, 1, 0}};
    const uint32_t sizes[] = {4, 3}, idx[] = {0, 1, 2, 3, 4, 5, 6};
    geo_poly *p = mk(v, 7, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 0);
    geo_poly_free(p);
}

static void test_adjacent_fold_and_duplicates_count(void **state)
{
    (void)state;
    const double v[][3] = {{0, 0, 0}, {2, 0, 0}, {1, 2, 0}, {1, 1, 0},
                           {1, -1, 0}};
    /* fold: both triangles on the same side of the shared edge 0-1 */
    const uint32_t sizes[] = {3, 3};
    const uint32_t fold[] = {0, 1, 2, 1, 0, 3};
    geo_poly *p = mk(v, 5, sizes, 2, fold);
    assert_int_equal(pair(p, 0, 1), 1);
    geo_poly_free(p);
    /* unfolded: on opposite sides, a legal flat neighbour */
    const uint32_t flat[] = {0, 1, 2, 1, 0, 4};
    p = mk(v, 5, sizes, 2, flat);
    assert_int_equal(pair(p, 0, 1), 0);
    geo_poly_free(p);
    /* a facet and its reverse; a facet listed twice */
    const uint32_t rev[] = {0, 1, 2, 2, 1, 0}, dup[] = {0, 1, 2, 1, 2, 0};
    p = mk(v, 5, sizes, 2, rev);
    assert_int_equal(pair(p, 0, 1), 1);
    geo_poly_free(p);
    p = mk(v, 5, sizes, 2, dup);
    assert_int_equal(pair(p, 0, 1), 1);
    geo_poly_free(p);
}

static void test_shared_vertex_only_is_legal(void **state)
{
    (void)state;
    /* two triangles meeting at vertex 0 at an angle; coplanar ones
     * meeting at vertex 0 only; a bow-tie of two tetrahedra sharing a
     * vertex is clean */
    const double v[][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 1},
                           {-1, -1, 1}, {-1, 0, 0}, {-1, -1, 0}};
    const uint32_t sizes[] = {3, 3};
    const uint32_t angled[] = {0, 1, 2, 0, 3, 4}, flat[] = {0, 1, 2, 0, 5, 6};
    geo_poly *p = mk(v, 7, sizes, 2, angled);
    assert_int_equal(pair(p, 0, 1), 0);
    geo_poly_free(p);
    p = mk(v, 7, sizes, 2, flat);
    assert_int_equal(pair(p, 0, 1), 0);
    geo_poly_free(p);
    /* coplanar, sharing vertex 0, the second wedge inside the first */
    const double w[][3] = {{0, 0, 0}, {4, 0, 0}, {0, 4, 0}, {1, 0.5, 0},
                           {0.5, 1, 0}};
    const uint32_t inside[] = {0, 1, 2, 0, 3, 4};
    p = mk(w, 5, sizes, 2, inside);
    assert_int_equal(pair(p, 0, 1), 1);
    geo_poly_free(p);
}

static void test_shared_vertex_with_crossing_counts(void **state)
{
    (void)state;
    /* G shares vertex 0 with the square but its far edge passes through
     * the square's interior */
    const double v[][3] = {SQUARE, {1.5, 1, -1}, {1.5, 1.5, 1}};
    const uint32_t sizes[] = {4, 3}, idx[] = {0, 1, 2, 3, 0, 4, 5};
    geo_poly *p = mk(v, 6, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 1);
    geo_poly_free(p);
    /* G shares vertex 0 and its edge from 0 runs inside the square's
     * plane into the square (G lies above) */
    const double w[][3] = {SQUARE, {1, 1, 0}, {0.2, 1.5, 1}};
    p = mk(w, 6, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 1);
    geo_poly_free(p);
    /* ... and the same edge leaving the square outward does not count */
    const double x[][3] = {SQUARE, {-1, -1, 0}, {-0.2, -1.5, 1}};
    p = mk(x, 6, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 0);
    geo_poly_free(p);
}

static void test_shared_edge_at_any_angle_is_legal(void **state)
{
    (void)state;
    for (int k = 0; k < 5; k++) {
        /* the second facet turns about the edge 0-1 (x axis) by an angle
         * from nearly flat to nearly folded, never through the square */
        double ang = (const double[]){1e-9, 0.3, 1.5, 3.0, 3.14159}[k];
        double v[][3] = {SQUARE, {2, -2 * cos(ang), 2 * sin(ang)},
                         {0, -2 * cos(ang), 2 * sin(ang)}};
        const uint32_t sizes[] = {4, 4}, idx[] = {0, 1, 2, 3, 1, 0, 5, 4};
        geo_poly *p = mk((const double (*)[3])v, 6, sizes, 2, idx);
        assert_int_equal(pair(p, 0, 1), 0);
        geo_poly_free(p);
    }
}

static void test_nonconvex_facets(void **state)
{
    (void)state;
    /* an L-shaped facet in z = 0; a vertical triangle pierces the notch
     * (outside the L) and then one arm (inside) */
    const double L[][3] = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0}, {1, 1, 0},
                           {1, 2, 0}, {0, 2, 0}};
    for (int k = 0; k < 2; k++) {
        double x = k ? 0.5 : 1.5, y = 1.5;
        double v[9][3];
        memcpy(v, L, sizeof L);
        double t[3][3] = {{x, y - 0.2, -1}, {x, y + 0.2, -1}, {x, y, 1}};
        memcpy(v[6], t, sizeof t);
        const uint32_t sizes[] = {6, 3}, idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
        geo_poly *p = mk((const double (*)[3])v, 9, sizes, 2, idx);
        assert_int_equal(pair(p, 0, 1), k);
        geo_poly_free(p);
    }
    /* coplanar non-convex neighbours sharing the edge 0-1 of the square:
     * a U-shaped G wraps around the corner and re-enters the square
     * (counts), or stays outside (legal) */
    for (int k = 0; k < 2; k++) {
        double x = k ? 1.5 : 2.5, y = k ? 0.5 : -0.5;
        double v[][3] = {SQUARE,   {0, -1, 0}, {3, -1, 0}, {3, 1, 0},
                         {x, 1, 0}, {x, y, 0}};
        const uint32_t sizes[] = {4, 7};
        const uint32_t idx[] = {0, 1, 2, 3, 1, 0, 4, 5, 6, 7, 8};
        geo_poly *p = mk((const double (*)[3])v, 9, sizes, 2, idx);
        assert_int_equal(pair(p, 0, 1), k);
        geo_poly_free(p);
    }
}

static void test_crossing_along_a_diagonal_counts(void **state)
{
    (void)state;
    /* quads (0,a,1,b) and (0,c,1,d) share opposite corners 0 and 1 and
     * cross each other along the diagonal 0-1 */
    const double v[][3] = {{0, 0, 0}, {2, 2, 0}, {2, 0, 0}, {0, 2, 0},
                           {1, 1, 1}, {1, 1, -1}};
    const uint32_t sizes[] = {4, 4}, idx[] = {0, 2, 1, 3, 0, 5, 1, 4};
    geo_poly *p = mk(v, 6, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 1);
    geo_poly_free(p);
}

static void test_edge_in_plane_across_facet_counts(void **state)
{
    (void)state;
    /* G's bottom edge lies in z = 0 and crosses the square; then lies in
     * z = 0 beside it */
    for (int k = 0; k < 2; k++) {
        double off = k ? 4 : 0;
        double v[][3] = {SQUARE, {off - 1, 1, 0}, {off + 3, 1, 0},
                         {off + 1, 1, 1}};
        const uint32_t sizes[] = {4, 3}, idx[] = {0, 1, 2, 3, 4, 5, 6};
        geo_poly *p = mk((const double (*)[3])v, 7, sizes, 2, idx);
        assert_int_equal(pair(p, 0, 1), k ? 0 : 1);
        geo_poly_free(p);
    }
}

static void test_segment_meets_facet_three_ways(void **state)
{
    (void)state;
    const double v[][3] = {SQUARE};
    const uint32_t sizes[] = {4}, idx[] = {0, 1, 2, 3};
    geo_poly *p = mk(v, 4, sizes, 1, idx);
    geo_facet_shape s;
    geo_facet_shape_of(p, 0, &s);
    static const struct {
        double a[3], b[3];
        int want;
    } cases[] = {
        {{1, 1, -1}, {1.2, 0.9, 1}, 1},  /* through the interior */
        {{3, 1, -1}, {3, 1, 1}, -1},     /* beside it */
        {{1, 0, -1}, {1, 0, 1}, 0},      /* through an edge */
        {{2, 2, -1}, {2, 2, 1}, 0},      /* through a corner */
        {{1, 1, 0}, {1, 1, 1}, 0},       /* an endpoint on the facet */
        {{3, 3, 0}, {3, 3, 1}, -1},      /* an endpoint on the plane only */
        {{-1, 1, 0}, {3, 1, 0}, 0},      /* in the plane, across it */
        {{-1, 3, 0}, {3, 3, 0}, -1},     /* in the plane, beside it */
        {{1, 1, 1}, {1, 1, 2}, -1},      /* short of the plane */
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++)
        assert_int_equal(geo_segment_meets_facet(p, 0, &s, cases[i].a,
                                                 cases[i].b),
                         cases[i].want);
    geo_poly_free(p);
}

static void test_own_polygon_self_intersection(void **state)
{
    (void)state;
    /* bow-tie; a spike folding back over its edge; a vertex listed twice */
    const double v[][3] = {{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0},
                           {2, 0, 0}, {3, 0, 0}, {3, 1, 0}, {0.5, 0.5, 0}};
    const uint32_t sizes[] = {4, 5, 6};
    const uint32_t idx[] = {0, 1, 2, 3,    0, 5, 4, 6, 3,
                            0, 2, 7, 1, 3, 7};
    geo_poly *p = mk(v, 8, sizes, 3, idx);
    for (uint32_t f = 0; f < 3; f++) {
        geo_facet_shape s;
        geo_facet_shape_of(p, f, &s);
        assert_false(s.degenerate);
        assert_true(geo_facet_self_intersects(p, f, &s));
        assert_false(s.simple);
        assert_false(s.convex);
    }
    geo_selfint r;
    assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &r, NULL), 0);
    for (uint32_t f = 0; f < 3; f++)
        assert_true(r.facet_flags[f] & GEO_SI_SELF);
    /* listed as (f, f) */
    uint32_t selfs = 0;
    for (uint32_t i = 0; i < r.npairs; i++)
        selfs += r.pairs[i][0] == r.pairs[i][1];
    assert_int_equal(selfs, 3);
    geo_selfint_clear(&r);
    geo_poly_free(p);
}

static void test_large_facet_sweep_matches_quadratic(void **state)
{
    (void)state;
    /* a 200-gon (star-shaped, simple) and the same with two vertices
     * swapped (crossing edges): the sweep used for large facets */
    enum { N = 200 };
    double v[N][3];
    uint32_t idx[N], start[2] = {0, N};
    for (uint32_t i = 0; i < N; i++) {
        double a = 2 * M_PI * i / N, r = (i % 2) ? 1.0 : 0.7;
        v[i][0] = r * cos(a), v[i][1] = r * sin(a), v[i][2] = 0;
        idx[i] = i;
    }
    geo_poly *p = geo_poly_from_arrays(N, &v[0][0], 1, start, idx, NULL, NULL);
    geo_facet_shape s;
    geo_facet_shape_of(p, 0, &s);
    assert_false(geo_facet_self_intersects(p, 0, &s));
    assert_true(s.simple);
    assert_false(s.convex);
    geo_poly_free(p);
    idx[50] = 52, idx[52] = 50;
    p = geo_poly_from_arrays(N, &v[0][0], 1, start, idx, NULL, NULL);
    geo_facet_shape_of(p, 0, &s);
    assert_true(geo_facet_self_intersects(p, 0, &s));
    geo_poly_free(p);
}

static void test_large_facet_pairs(void **state)
{
    (void)state;
    /* a 150-gon star in z = 0 and a triangle piercing its centre, then
     * one piercing the gap between two of its spikes */
    enum { N = 150 };
    for (int k = 0; k < 2; k++) {
        double v[N + 3][3];
        uint32_t idx[N + 3], start[3] = {0, N, N + 3};
        for (uint32_t i = 0; i < N; i++) {
            double a = 2 * M_PI * i / N, r = (i % 2) ? 1.0 : 0.5;
            v[i][0] = r * cos(a), v[i][1] = r * sin(a), v[i][2] = 0;
            idx[i] = i;
        }
        /* the gap: just outside the inner radius, between spikes 1 and 3 */
        double x = k ? 0.52 * cos(2 * M_PI * 2 / N) : 0.0;
        double y = k ? 0.52 * sin(2 * M_PI * 2 / N) : 0.0;
        double t[3][3] = {{x - 1e-3, y, -1}, {x + 1e-3, y, -1}, {x, y, 1}};
        memcpy(v[N], t, sizeof t);
        idx[N] = N, idx[N + 1] = N + 1, idx[N + 2] = N + 2;
        geo_poly *p = geo_poly_from_arrays(N + 3, &v[0][0], 2, start, idx,
                                           NULL, NULL);
        assert_non_null(p);
        assert_int_equal(pair(p, 0, 1), k ? 0 : 1);
        geo_poly_free(p);
    }
}

static void test_degenerate_facets_are_flagged_not_paired(void **state)
{
    (void)state;
    /* a collinear triangle crossing the square */
    const double v[][3] = {SQUARE, {1, 1, -1}, {1, 1, 0}, {1, 1, 1}};
    const uint32_t sizes[] = {4, 3}, idx[] = {0, 1, 2, 3, 4, 5, 6};
    geo_poly *p = mk(v, 7, sizes, 2, idx);
    geo_facet_shape s;
    geo_facet_shape_of(p, 1, &s);
    assert_true(s.degenerate);
    geo_selfint r;
    assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &r, NULL), 0);
    assert_int_equal(r.count, 0);
    assert_int_equal(r.ndegenerate, 1);
    assert_true(r.facet_flags[1] & GEO_SI_DEGENERATE);
    geo_selfint_clear(&r);
    geo_poly_free(p);
    /* two distinct positions only: 0,0,0 twice under different indices */
    const double w[][3] = {{0, 0, 0}, {1, 0, 0}, {0, 0, 0}};
    const uint32_t one[] = {3}, tri[] = {0, 1, 2};
    p = mk(w, 3, one, 1, tri);
    geo_facet_shape_of(p, 0, &s);
    assert_true(s.degenerate);
    geo_poly_free(p);
}

static void test_nonplanar_neighbours_are_not_false_contacts(void **state)
{
    (void)state;
    /* a fan of quads around a vertex, each lifted a rounding-size amount
     * off its plane, meeting at nearly flat angles */
    const double e = 1e-13;
    const double v[][3] = {{0, 0, 0},     {1, 0, e},      {1, 1, 0},
                           {0, 1, -e},    {-1, 1, 1e-7},  {-1, 0, e},
                           {-1, -1, 2e-7}, {0, -1, -e},   {1, -1, 1e-7}};
    const uint32_t sizes[] = {4, 4, 4, 4};
    const uint32_t idx[] = {0, 1, 2, 3, 0, 3, 4, 5, 0, 5, 6, 7, 0, 7, 8, 1};
    geo_poly *p = mk(v, 9, sizes, 4, idx);
    assert_int_equal(count_all(p), 0);
    geo_poly_free(p);
}

static void test_nearly_coplanar_facets_apart_do_not_touch(void **state)
{
    (void)state;
    /* Two new facets of a plane cut of a bumpy sphere (vertices on the
     * plane up to rounding) and a steep triangle whose top edge lies in
     * that plane too, 1e-3 away from the ten-gon but on a line through
     * it: seen along that edge, the ten-gon is a sliver as thin as its
     * non-planarity, yet the edge passes beside it. */
    const double v[][3] = {
        {0.04759205024934119, 0.33037707067431332, -0.80891720824489199},
        {0.049732520267453492, 0.41868068299049033, -0.84871268316656601},
        {2.9576554271328722e-17, 0.48302178704784227, -0.87439813184398074},
        {-0.0057222583479405913, 0.49582476569346162, -0.87977859792612145},
        {0.25878568090202408, -0.62476390058162212, -0.39359435913423624},
        {0.26115469444740902, -0.62568381558009123, -0.39333414445312187},
        {0.068692229469193636, 0.1870115297125054, -0.74589351788567582},
        {0.068570192069692795, 0.23366834641909726, -0.76683929831364039},
        {0.054440447279057877, 0.27369061057500271, -0.78390128657935954},
        {0.054142613670390048, 0.30667536662188777, -0.79869557293709681},
        {0.16509765352359723, 0.24708609966596587, -0.77909612027005948},
        {0.11923918974792158, 0.17845405851230312, -0.80099092417877538},
        {0.08246308291012068, 0.18088941329444197, -0.74403297868606988}};
    const uint32_t sizes[] = {10, 3};
    const uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    geo_poly *p = mk(v, 13, sizes, 2, idx);
    assert_int_equal(pair(p, 0, 1), 0);
    geo_poly_free(p);
}

static void test_closed_models_are_clean(void **state)
{
    (void)state;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
    geo_poly *p = tu_box(lo, hi);
    assert_int_equal(count_all(p), 0);
    geo_poly_free(p);
    p = tu_notch_cube();
    assert_int_equal(count_all(p), 0);
    geo_poly_free(p);
    p = gs_sphere(6, 2.0);
    assert_int_equal(p->nfacets, 12 * 36);
    assert_int_equal(count_all(p), 0);
    geo_poly_free(p);
    /* a square pyramid: four facets meet at the apex only */
    const double v[][3] = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0},
                           {1, 1, 1}};
    const uint32_t sizes[] = {4, 3, 3, 3, 3};
    const uint32_t idx[] = {0, 3, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    p = mk(v, 5, sizes, 5, idx);
    assert_int_equal(count_all(p), 0);
    geo_poly_free(p);
}

static void test_pushed_sphere_vertex_intersects(void **state)
{
    (void)state;
    geo_poly *p = gs_sphere(8, 1.0);
    /* push vertex 0 through the sphere and out beyond the far side */
    geo_vscale(p->verts[0], -1.5, p->verts[0]);
    geo_selfint r;
    assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &r, NULL), 0);
    assert_true(r.count > 0);
    /* every listed pair involves a facet around vertex 0 */
    for (uint32_t i = 0; i < r.npairs; i++) {
        bool has0 = false;
        for (int k = 0; k < 2; k++) {
            uint32_t f = r.pairs[i][k];
            for (uint32_t j = 0; j < geo_poly_facet_size(p, f); j++)
                has0 |= geo_poly_facet(p, f)[j] == 0;
        }
        assert_true(has0);
    }
    geo_selfint_clear(&r);
    geo_poly_free(p);
}

/* random triangles in a cube: many real intersections of every kind */
static geo_poly *triangle_soup(uint64_t seed, uint32_t n)
{
    double (*v)[3] = malloc(3 * n * sizeof *v);
    uint32_t *idx = malloc(3 * n * sizeof *idx), *start = malloc((n + 1) * 4);
    for (uint32_t i = 0; i < 3 * n; i++) {
        for (int k = 0; k < 3; k++)
            /* a coarse grid makes exact coplanarity and touching common */
            v[i][k] = (double)(geo_rand_next(&seed) % 9);
        idx[i] = i;
    }
    for (uint32_t f = 0; f <= n; f++)
        start[f] = 3 * f;
    /* share some vertices between triangles */
    for (uint32_t i = 3; i < 3 * n; i += 7)
        idx[i] = idx[i - 2];
    for (uint32_t f = 0; f < n; f++) { /* no consecutive repeats */
        uint32_t *t = idx + 3 * f;
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2])
            t[0] = t[1] = t[2] = 3 * f, t[1]++, t[2] += 2;
    }
    geo_poly *p = geo_poly_from_arrays(3 * n, &v[0][0], n, start, idx, NULL,
                                       NULL);
    free(v), free(idx), free(start);
    return p;
}

static void test_bvh_search_matches_brute_force(void **state)
{
    (void)state;
    geo_poly *p = triangle_soup(7, 300);
    assert_non_null(p);
    geo_facet_shape *s = malloc(p->nfacets * sizeof *s);
    for (uint32_t f = 0; f < p->nfacets; f++)
        geo_facet_shape_of(p, f, &s[f]);
    uint64_t brute = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (!s[f].degenerate && geo_facet_self_intersects(p, f, &s[f]))
            brute++;
        for (uint32_t g = f + 1; g < p->nfacets; g++)
            brute += geo_facets_intersect(p, f, g, &s[f], &s[g]) == 1;
    }
    geo_selfint_opts o;
    geo_selfint_opts_default(&o);
    o.max_pairs = 50;
    geo_selfint r;
    assert_int_equal(geo_selfint_find(p, NULL, &o, NULL, &r, NULL), 0);
    assert_true(brute > 100);
    assert_int_equal(r.count, brute);
    assert_int_equal(r.npairs, 50);
    for (uint32_t i = 1; i < r.npairs; i++)
        assert_true(r.pairs[i - 1][0] < r.pairs[i][0] ||
                    (r.pairs[i - 1][0] == r.pairs[i][0] &&
                     r.pairs[i - 1][1] < r.pairs[i][1]));
    geo_selfint_clear(&r);
    free(s);
    geo_poly_free(p);
}

static void test_result_independent_of_thread_count(void **state)
{
    (void)state;
    geo_poly *p = triangle_soup(11, 1000);
    geo_selfint_opts o;
    geo_selfint_opts_default(&o);
    o.max_pairs = 300;
    geo_selfint r1, r2;
    par_pool *pool = par_pool_new(2);
    assert_non_null(pool);
    geo_ctx ctx = {0};
    ctx.parallel_for = par_for;
    ctx.pf_user = pool;
    assert_int_equal(geo_selfint_find(p, NULL, &o, NULL, &r1, NULL), 0);
    assert_int_equal(geo_selfint_find(p, NULL, &o, &ctx, &r2, NULL), 0);
    assert_true(r1.count > 300);
    assert_int_equal(r1.count, r2.count);
    assert_int_equal(r1.npairs, r2.npairs);
    assert_memory_equal(r1.pairs, r2.pairs, r1.npairs * sizeof r1.pairs[0]);
    assert_memory_equal(r1.facet_flags, r2.facet_flags, p->nfacets);
    geo_selfint_clear(&r1);
    geo_selfint_clear(&r2);
    par_pool_free(pool);
    geo_poly_free(p);
}

/* A soup of triangles, parallelograms and darts (non-convex quads) on a
 * coarse integer grid, all exactly planar, sharing some vertices. */
static geo_poly *polygon_soup(uint64_t seed, uint32_t n)
{
    geo_poly *p = geo_poly_new();
    for (uint32_t f = 0; f < n; f++) {
        double pt[4][3];
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++)
                pt[c][k] = 3.0 * (double)(geo_rand_next(&seed) % 6);
        uint32_t kind = (uint32_t)(geo_rand_next(&seed) % 3), m = kind ? 4 : 3;
        for (int k = 0; k < 3; k++)
            pt[3][k] = kind == 1 ? pt[0][k] + pt[2][k] - pt[1][k]
                                 : (pt[0][k] + pt[1][k] + pt[2][k]) / 3;
        uint32_t idx[4];
        for (uint32_t c = 0; c < m; c++) {
            /* reuse an existing vertex at this position half the time */
            idx[c] = UINT32_MAX;
            if (geo_rand_next(&seed) % 2)
                for (uint32_t v = 0; v < p->nverts && idx[c] == UINT32_MAX; v++)
                    if (memcmp(p->verts[v], pt[c], sizeof pt[c]) == 0)
                        idx[c] = v;
            if (idx[c] == UINT32_MAX)
                idx[c] = (uint32_t)geo_poly_add_vertex(p, pt[c]);
        }
        bool ok = true;
        for (uint32_t c = 0; c < m; c++)
            for (uint32_t d = c + 1; d < m; d++)
                ok &= idx[c] != idx[d];
        if (ok)
            geo_poly_add_facet(p, idx, m);
    }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

static void test_exact_symmetries_do_not_change_the_answer(void **state)
{
    (void)state;
    geo_poly *p = polygon_soup(3, 250);
    geo_selfint r0;
    assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &r0, NULL), 0);
    assert_true(r0.count > 100);
    geo_poly *q = geo_poly_copy(p);
    static const int perms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},
                                    {1, 0, 2}, {0, 2, 1}, {2, 1, 0}};
    for (int t = 0; t < 48; t++) {
        const int *pm = perms[t % 6];
        int signs = t / 6;
        for (uint32_t v = 0; v < p->nverts; v++)
            for (int k = 0; k < 3; k++)
                q->verts[v][k] = ((signs >> k) & 1 ? -1 : 1) *
                                 p->verts[v][pm[k]];
        /* every other transform also reverses facets and rotates starts */
        for (uint32_t f = 0; f < p->nfacets; f++) {
            uint32_t n = geo_poly_facet_size(p, f);
            const uint32_t *src = geo_poly_facet(p, f);
            uint32_t *dst = q->fidx + q->fstart[f];
            for (uint32_t i = 0; i < n; i++)
                dst[i] = t % 2 ? src[(n - i + t) % n] : src[(i + t) % n];
        }
        geo_selfint r;
        assert_int_equal(geo_selfint_find(q, NULL, NULL, NULL, &r, NULL), 0);
        assert_int_equal(r.count, r0.count);
        assert_memory_equal(r.pairs, r0.pairs, r.npairs * sizeof r.pairs[0]);
        geo_selfint_clear(&r);
    }
    geo_selfint_clear(&r0);
    geo_poly_free(q);
    geo_poly_free(p);
}

static int cancel_at_half(void *user, double fraction)
{
    int *calls = user;
    (*calls)++;
    return fraction > 0.5;
}

static void test_cancel_stops_with_ecanceled(void **state)
{
    (void)state;
    geo_poly *p = gs_sphere(20, 1.0);
    int calls = 0;
    geo_ctx ctx = {0};
    ctx.progress = cancel_at_half;
    ctx.user = &calls;
    geo_selfint r;
    geo_err err = {{0}};
    assert_int_equal(geo_selfint_find(p, NULL, NULL, &ctx, &r, &err),
                     -ECANCELED);
    assert_true(calls > 1);
    assert_null(r.pairs);
    assert_non_null(strstr(err.msg, "canceled"));
    /* a hierarchy of another model is refused, not followed */
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *box = tu_box(lo, hi);
    geo_bvh *other = geo_bvh_build_facets(box, NULL);
    assert_int_equal(geo_selfint_find(p, other, NULL, NULL, &r, &err),
                     -EINVAL);
    geo_bvh_free(other);
    geo_poly_free(box);
    atomic_int flag = 1;
    geo_ctx c2 = {0};
    c2.cancel = &flag;
    assert_int_equal(geo_selfint_find(p, NULL, NULL, &c2, &r, &err),
                     -ECANCELED);
    geo_poly_free(p);
}

static void test_random_convex_clean_until_vertex_pushed_through(void **state)
{
    (void)state;
    for (uint64_t seed = 1; seed <= 40; seed++) {
        const double cen[3] = {0.1 * (double)seed, -0.2, 0.3};
        geo_poly *p = gen_convex_polyhedron(seed, 12 + (unsigned)(seed % 30),
                                            cen, 1.0);
        assert_non_null(p);
        assert_true(geo_poly_max_nonplanarity(p) <= geo_poly_eps(p));
        assert_int_equal(count_all(p), 0);
        /* vertex 0 goes just beyond the facet facing away from it most */
        double v0[3];
        geo_vsub(p->verts[0], cen, v0);
        uint32_t far = 0;
        double best = INFINITY;
        for (uint32_t f = 0; f < p->nfacets; f++) {
            bool has = false;
            for (uint32_t j = 0; j < geo_poly_facet_size(p, f); j++)
                has |= geo_poly_facet(p, f)[j] == 0;
            double d = geo_vdot(p->planes[f], v0);
            if (!has && d < best)
                best = d, far = f;
        }
        double c[3];
        geo_poly_facet_center(p, far, c);
        geo_vmadd(c, 0.05, p->planes[far], p->verts[0]);
        geo_selfint r;
        assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &r, NULL), 0);
        assert_true(r.count > 0);
        assert_true(r.facet_flags[far] & GEO_SI_PAIR);
        geo_selfint_clear(&r);
        geo_poly_free(p);
    }
}

/* The pairs, count and flags with the fans geo_selfint_simple_fans
 * certifies must be those of the full tests; returns how many vertices
 * were certified. */
static uint32_t assert_fans_change_nothing(const geo_poly *p)
{
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    uint8_t *fans = malloc(p->nverts + 1);
    geo_selfint_simple_fans(p, t, fans);
    geo_topo_free(t);
    uint32_t nfan = 0;
    for (uint32_t v = 0; v < p->nverts; v++)
        nfan += fans[v];
    geo_selfint_opts o;
    geo_selfint_opts_default(&o);
    o.max_pairs = 1u << 20;
    geo_selfint a, b;
    assert_int_equal(geo_selfint_find(p, NULL, &o, NULL, &a, NULL), 0);
    o.simple_fans = fans;
    assert_int_equal(geo_selfint_find(p, NULL, &o, NULL, &b, NULL), 0);
    assert_true(a.count == b.count);
    assert_int_equal(a.npairs, b.npairs);
    assert_memory_equal(a.pairs, b.pairs, a.npairs * sizeof *a.pairs);
    assert_memory_equal(a.facet_flags, b.facet_flags, p->nfacets);
    geo_selfint_clear(&a);
    geo_selfint_clear(&b);
    free(fans);
    return nfan;
}

/* Skipping the pairs of a certified fan never changes the answer: on
 * spheres whose vertices are moved a little (every fan simple), a lot
 * (folds, fans through each other and through the far side) and onto a
 * coarse grid (exact coplanar and collinear spokes), on a cube of flat
 * grids (spokes in opposite pairs: certified), and on a closed double
 * cone over a hexagon wound twice, whose two apex fans each cover their
 * plane twice and cross themselves: those two are never certified. */
static void test_simple_fans_change_no_answer(void **state)
{
    (void)state;
    uint64_t seed = 12345;
    for (int it = 0; it < 24; it++) {
        geo_poly *p = gs_sphere(6 + it % 5, 1.0);
        double amp = it % 3 == 0 ? 0.01 : it % 3 == 1 ? 0.4 : 0;
        for (uint32_t v = 0; v < p->nverts; v++)
            for (int k = 0; k < 3; k++) {
                double r = (double)(geo_rand_next(&seed) % 2001) / 1000 - 1;
                if (it % 3 == 2) /* a grid of 1/4: exact degeneracies */
                    p->verts[v][k] = round(4 * p->verts[v][k]) / 4;
                else if (geo_rand_next(&seed) % 4 == 0 || amp < 0.1)
                    p->verts[v][k] += amp * r;
            }
        geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
        uint32_t nfan = assert_fans_change_nothing(p);
        if (it % 3 == 0) /* small moves: the fans stay simple */
            assert_int_equal(nfan, p->nverts);
        geo_poly_free(p);
    }
    /* a cube of n × n grids: flat fans whose spokes come in opposite
     * pairs, every one of them simple */
    enum { N = 4 };
    geo_poly *g = geo_poly_new();
    uint32_t id[N + 1][N + 1][N + 1];
    for (int i = 0; i <= N; i++)
        for (int j = 0; j <= N; j++)
            for (int k = 0; k <= N; k++) {
                id[i][j][k] = UINT32_MAX;
                if (i % N && j % N && k % N)
                    continue; /* inside the cube */
                double x[3] = {i, j, k};
                id[i][j][k] = (uint32_t)geo_poly_add_vertex(g, x);
            }
    for (int a = 0; a < 3; a++)
        for (int side = 0; side <= N; side += N)
            for (int i = 0; i < N; i++)
                for (int j = 0; j < N; j++) {
                    int q[4][3];
                    int di[4] = {0, 1, 1, 0}, dj[4] = {0, 0, 1, 1};
                    for (int c = 0; c < 4; c++) {
                        q[c][a] = side;
                        q[c][(a + 1) % 3] = i + di[c];
                        q[c][(a + 2) % 3] = j + dj[c];
                    }
                    uint32_t v[4];
                    for (int c = 0; c < 4; c++)
                        v[c] = id[q[c][0]][q[c][1]][q[c][2]];
                    /* (a+1, a+2) turn about +a: outward on the far side */
                    uint32_t t1[3] = {v[0], v[1], v[2]}, t2[3] = {v[0], v[2], v[3]};
                    if (side == 0) {
                        uint32_t x = t1[1];
                        t1[1] = t1[2], t1[2] = x;
                        x = t2[1], t2[1] = t2[2], t2[2] = x;
                    }
                    geo_poly_add_facet(g, t1, 3);
                    geo_poly_add_facet(g, t2, 3);
                }
    geo_poly_compute_planes(g, GEO_PLANE_UNWEIGHTED);
    geo_topo *tg = geo_topo_build(g, NULL);
    assert_true(geo_topo_is_closed_manifold(tg));
    uint8_t *gf = malloc(g->nverts);
    geo_selfint_simple_fans(g, tg, gf);
    geo_topo_free(tg);
    for (int i = 1; i < N; i++) /* the top face's inner vertices */
        for (int j = 1; j < N; j++)
            assert_int_equal(gf[id[i][j][N]], 1);
    free(gf);
    assert_int_equal(assert_fans_change_nothing(g) > 0, 1);
    geo_poly_free(g);

    /* the double cone: ring vertices at 125° steps (twice round in six) */
    geo_poly *p = geo_poly_new();
    const double top[3] = {0, 0, 0.3}, bottom[3] = {0, 0, -1};
    geo_poly_add_vertex(p, top);
    geo_poly_add_vertex(p, bottom);
    for (int i = 0; i < 6; i++) {
        double a = (i * 125.0 + (i == 5 ? -30 : 0)) * M_PI / 180;
        double x[3] = {cos(a) * (1 + 0.1 * i), sin(a) * (1 + 0.1 * i), 0};
        geo_poly_add_vertex(p, x);
    }
    for (uint32_t i = 0; i < 6; i++) {
        uint32_t a = 2 + i, b = 2 + (i + 1) % 6;
        uint32_t up[3] = {0, a, b}, down[3] = {1, b, a};
        geo_poly_add_facet(p, up, 3);
        geo_poly_add_facet(p, down, 3);
    }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    geo_topo *t = geo_topo_build(p, NULL);
    uint8_t fans[8];
    geo_selfint_simple_fans(p, t, fans);
    geo_topo_free(t);
    assert_int_equal(fans[0], 0);
    assert_int_equal(fans[1], 0);
    assert_fans_change_nothing(p);
    geo_selfint r;
    assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &r, NULL), 0);
    assert_true(r.count > 0);
    geo_selfint_clear(&r);
    geo_poly_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_edge_piercing_facet_counts),
        cmocka_unit_test(test_edge_passing_beside_facet_does_not_count),
        cmocka_unit_test(test_vertex_touching_interior_edge_or_vertex_counts),
        cmocka_unit_test(test_coplanar_overlap_and_containment_count),
        cmocka_unit_test(test_adjacent_fold_and_duplicates_count),
        cmocka_unit_test(test_shared_vertex_only_is_legal),
        cmocka_unit_test(test_shared_vertex_with_crossing_counts),
        cmocka_unit_test(test_shared_edge_at_any_angle_is_legal),
        cmocka_unit_test(test_nonconvex_facets),
        cmocka_unit_test(test_crossing_along_a_diagonal_counts),
        cmocka_unit_test(test_edge_in_plane_across_facet_counts),
        cmocka_unit_test(test_segment_meets_facet_three_ways),
        cmocka_unit_test(test_own_polygon_self_intersection),
        cmocka_unit_test(test_large_facet_sweep_matches_quadratic),
        cmocka_unit_test(test_large_facet_pairs),
        cmocka_unit_test(test_degenerate_facets_are_flagged_not_paired),
        cmocka_unit_test(test_nonplanar_neighbours_are_not_false_contacts),
        cmocka_unit_test(test_nearly_coplanar_facets_apart_do_not_touch),
        cmocka_unit_test(test_closed_models_are_clean),
        cmocka_unit_test(test_pushed_sphere_vertex_intersects),
        cmocka_unit_test(test_bvh_search_matches_brute_force),
        cmocka_unit_test(test_result_independent_of_thread_count),
        cmocka_unit_test(test_exact_symmetries_do_not_change_the_answer),
        cmocka_unit_test(test_cancel_stops_with_ecanceled),
        cmocka_unit_test(test_random_convex_clean_until_vertex_pushed_through),
        cmocka_unit_test(test_simple_fans_change_no_answer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
