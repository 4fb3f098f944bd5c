/* test_halfspace.c — the exact half-space intersection: right topology on
 * degenerate inputs (many planes through one point, planes through
 * vertices and edges, duplicates), clear failures for empty, flat and
 * unbounded regions, and volumes that agree with the simulator's
 * independent clipper. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "halfspace.h"
#include "stone_sim.h"
#include "topo.h"

/* Closed manifold, Euler characteristic 2, every vertex inside every
 * plane (to rounding) and on at least three facets. */
static void assert_valid_convex(const geo_poly *p)
{
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    assert_true(geo_topo_is_closed_manifold(t));
    geo_topo_free(t);
    uint32_t *deg = calloc(p->nverts, sizeof *deg);
    assert_non_null(deg);
    for (uint32_t c = 0; c < geo_poly_ncorners(p); c++)
        deg[p->fidx[c]]++;
    for (uint32_t v = 0; v < p->nverts; v++)
        assert_true(deg[v] >= 3);
    free(deg);
    uint32_t edges = geo_poly_ncorners(p) / 2;
    assert_int_equal((int64_t)p->nverts - edges + p->nfacets, 2);
    double tol = 1e-12 * (1.0 + geo_poly_size(p));
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (uint32_t v = 0; v < p->nverts; v++) {
            const double *q = p->planes[f], *x = p->verts[v];
            assert_true(q[0] * x[0] + q[1] * x[1] + q[2] * x[2] + q[3] <
                        tol);
        }
    assert_true(geo_poly_volume(p) > 0);
}

static geo_poly *must_intersect(const double *planes, uint32_t n,
                                uint32_t **ret_src)
{
    geo_poly *p = NULL;
    geo_err err = {{0}};
    int r = geo_halfspace_intersect(planes, n, -1, &p, ret_src, NULL, &err);
    if (r < 0)
        fail_msg("%s", err.msg);
    assert_valid_convex(p);
    return p;
}

static void test_cube_from_scaled_planes(void **state)
{
    (void)state;
    const double pl[] = {3, 0, 0, -3, -1, 0, 0, -1, 0, 2, 0, -2,
                         0, -5, 0, -5, 0, 0, 1, -1, 0, 0, -7, -7};
    uint32_t *src = NULL;
    geo_poly *p = must_intersect(pl, 6, &src);
    assert_int_equal(p->nverts, 8);
    assert_int_equal(p->nfacets, 6);
    for (uint32_t f = 0; f < 6; f++)
        assert_int_equal(src[f], f);
    assert_true(fabs(geo_poly_volume(p) - 8.0) < 1e-12);
    assert_true(fabs(p->planes[0][0] - 1.0) < 1e-15);
    free(src);
    geo_poly_free(p);
}

/* |x| + |y| + |z| ≤ 1: four planes through each vertex, one vertex each */
static void test_octahedron_merges_four_plane_vertices(void **state)
{
    (void)state;
    double pl[32];
    for (int i = 0; i < 8; i++) {
        pl[4 * i + 0] = (i & 1) ? 1 : -1;
        pl[4 * i + 1] = (i & 2) ? 1 : -1;
        pl[4 * i + 2] = (i & 4) ? 1 : -1;
        pl[4 * i + 3] = -1;
    }
    geo_poly *p = must_intersect(pl, 8, NULL);
    assert_int_equal(p->nverts, 6);
    assert_int_equal(p->nfacets, 8);
    assert_true(fabs(geo_poly_volume(p) - 4.0 / 3.0) < 1e-12);
    geo_poly_free(p);
}

/* A cube, a duplicate of its first plane, a plane touching it along an
 * edge and one through three of its vertices. */
static void test_touching_duplicate_and_vertex_planes(void **state)
{
    (void)state;
    const double pl[] = {1, 0, 0, -1, -1, 0, 0, -1, 0, 1, 0, -1,
                         0, -1, 0, -1, 0, 0, 1, -1, 0, 0, -1, -1,
                         4, 0, 0, -4,   /* duplicate of planes[0] */
                         1, 1, 0, -2,   /* touches the edge x = y = 1 */
                         1, 1, 1, -1};  /* through three corners */
    uint32_t *src = NULL;
    geo_poly *p = must_intersect(pl, 9, &src);
    assert_int_equal(p->nverts, 7);
    assert_int_equal(p->nfacets, 7);
    assert_int_equal(src[6], 8);
    assert_true(fabs(geo_poly_volume(p) - (8.0 - 4.0 / 3.0)) < 1e-12);
    free(src);
    geo_poly_free(p);
}

/* 96 planes through one apex and a base: a pyramid whose apex is one
 * vertex on 96 facets. */
static void test_many_planes_through_one_point(void **state)
{
    (void)state;
    enum { N = 96 };
    double pl[4 * (N + 1)];
    for (int i = 0; i < N; i++) {
        double a = 2 * M_PI * i / N, s = sin(40.0 * M_PI / 180);
        pl[4 * i + 0] = cos(a) * s;
        pl[4 * i + 1] = sin(a) * s;
        pl[4 * i + 2] = -cos(40.0 * M_PI / 180);
        pl[4 * i + 3] = pl[4 * i + 2] * 1.0; /* through (0, 0, −1) */
    }
    pl[4 * N + 0] = 0, pl[4 * N + 1] = 0, pl[4 * N + 2] = 1,
    pl[4 * N + 3] = 0;
    geo_poly *p = must_intersect(pl, N + 1, NULL);
    assert_int_equal(p->nfacets, N + 1);
    assert_int_equal(p->nverts, N + 1);
    geo_poly_free(p);
}

static void expect_failure(const double *pl, uint32_t n,
                           enum geo_halfspace_status want, const char *word)
{
    geo_poly *p = NULL;
    geo_err err = {{0}};
    enum geo_halfspace_status st = GEO_HALFSPACE_OK;
    assert_int_equal(geo_halfspace_intersect(pl, n, -1, &p, NULL, &st, &err),
                     -EINVAL);
    assert_null(p);
    assert_int_equal(st, want);
    if (!strstr(err.msg, word))
        fail_msg("message \"%s\" lacks \"%s\"", err.msg, word);
}

static void test_empty_flat_unbounded_and_bad_planes(void **state)
{
    (void)state;
    const double cube[] = {1, 0, 0, -1, -1, 0, 0, -1, 0, 1, 0, -1,
                           0, -1, 0, -1, 0, 0, 1, -1, 0, 0, -1, -1};
    double empty[28], flat[28];
    memcpy(empty, cube, sizeof cube);
    memcpy(flat, cube, sizeof cube);
    const double away[4] = {-1, 0, 0, 2};  /* x ≥ 2 */
    const double wall[4] = {-1, 0, 0, 1};  /* x ≥ 1: only the face x = 1 */
    memcpy(empty + 24, away, sizeof away);
    memcpy(flat + 24, wall, sizeof wall);
    expect_failure(empty, 7, GEO_HALFSPACE_EMPTY, "bound nothing");
    expect_failure(flat, 7, GEO_HALFSPACE_EMPTY, "planes[6]");
    expect_failure(cube, 5, GEO_HALFSPACE_UNBOUNDED, "unbounded towards -z");
    expect_failure(cube, 0, GEO_HALFSPACE_UNBOUNDED, "unbounded");
    double zero[28];
    memcpy(zero, cube, sizeof cube);
    zero[24] = zero[25] = zero[26] = 0, zero[27] = -1;
    expect_failure(zero, 7, GEO_HALFSPACE_BAD_PLANE, "planes[6]: zero");
}

/* Random tangent planes of a sphere: the volume agrees with the
 * simulator's clipper to 1e-9 relative. */
static void test_random_planes_agree_with_independent_clipper(void **state)
{
    (void)state;
    uint64_t rng = 11;
    for (int round = 0; round < 5; round++) {
        uint32_t n = 20 + 60 * (uint32_t)round;
        double *pl = malloc(4 * (size_t)n * sizeof *pl);
        assert_non_null(pl);
        for (uint32_t i = 0; i < n; i++) {
            double z = 2 * geo_rand_unit(&rng) - 1;
            double a = 2 * M_PI * geo_rand_unit(&rng), r = sqrt(1 - z * z);
            pl[4 * i] = r * cos(a), pl[4 * i + 1] = r * sin(a);
            pl[4 * i + 2] = z, pl[4 * i + 3] = -(2 + geo_rand_unit(&rng));
        }
        geo_poly *p = must_intersect(pl, n, NULL);
        geo_poly *q = sim_halfspace_intersection(pl, n, 10.0);
        assert_non_null(q);
        double va = geo_poly_volume(p), vb = geo_poly_volume(q);
        if (fabs(va - vb) > 1e-9 * vb)
            fail_msg("n=%u volumes %.17g vs %.17g", n, va, vb);
        geo_poly_free(q);
        geo_poly_free(p);
        free(pl);
    }
}

/* The simulator's cut stones rebuilt from their own planes. */
static void test_stones_rebuilt_from_their_planes(void **state)
{
    (void)state;
    for (int cut = SIM_BRILLIANT; cut <= SIM_JUBILEE96; cut++) {
        geo_poly *s = sim_stone((enum sim_cut)cut, 3);
        assert_non_null(s);
        geo_poly *p = must_intersect(&s->planes[0][0], s->nfacets, NULL);
        double va = geo_poly_volume(p), vb = geo_poly_volume(s);
        if (fabs(va - vb) > 1e-9 * vb)
            fail_msg("cut %d volumes %.17g vs %.17g", cut, va, vb);
        geo_poly_free(p);
        geo_poly_free(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cube_from_scaled_planes),
        cmocka_unit_test(test_octahedron_merges_four_plane_vertices),
        cmocka_unit_test(test_touching_duplicate_and_vertex_planes),
        cmocka_unit_test(test_many_planes_through_one_point),
        cmocka_unit_test(test_empty_flat_unbounded_and_bad_planes),
        cmocka_unit_test(test_random_planes_agree_with_independent_clipper),
        cmocka_unit_test(test_stones_rebuilt_from_their_planes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
