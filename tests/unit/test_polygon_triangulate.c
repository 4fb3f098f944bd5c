/* test_polygon_triangulate.c — ear clipping of single polygons: the
 * triangles tile the polygon (every polygon edge used once in its own
 * direction, every diagonal twice in opposite directions, all triangles
 * turning like the polygon, areas adding up) for convex, star, comb, U,
 * collinear-corner, tilted, clockwise-seen and large polygons; degenerate
 * and self-intersecting input still yields n − 2 triangles. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "polygon_triangulate.h"
#include "vec.h"

enum { MAXN = 512 };

typedef struct polygon {
    uint32_t n;
    double v[MAXN][3];
    uint32_t idx[MAXN];
} polygon;

static void add2(polygon *pg, double x, double y)
{
    pg->v[pg->n][0] = x;
    pg->v[pg->n][1] = y;
    pg->v[pg->n][2] = 0;
    pg->idx[pg->n] = pg->n;
    pg->n++;
}

/* Rotates the polygon out of the xy plane (and shifts it), so that no
 * coordinate plane is parallel to it. */
static void tilt(polygon *pg)
{
    const double a = 0.7, b = 0.4;
    for (uint32_t i = 0; i < pg->n; i++) {
        double x = pg->v[i][0], y = pg->v[i][1], z = pg->v[i][2];
        double y1 = y * cos(a) - z * sin(a), z1 = y * sin(a) + z * cos(a);
        double x2 = x * cos(b) + z1 * sin(b), z2 = -x * sin(b) + z1 * cos(b);
        pg->v[i][0] = x2 + 3;
        pg->v[i][1] = y1 - 2;
        pg->v[i][2] = z2 + 1;
    }
}

static void newell(const polygon *pg, double ret[3])
{
    ret[0] = ret[1] = ret[2] = 0;
    for (uint32_t i = 0; i < pg->n; i++) {
        const double *a = pg->v[pg->idx[i]], *b = pg->v[pg->idx[(i + 1) % pg->n]];
        ret[0] += (a[1] - b[1]) * (a[2] + b[2]);
        ret[1] += (a[2] - b[2]) * (a[0] + b[0]);
        ret[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
}

static void tri_area_vector(const polygon *pg, const uint32_t t[3],
                            double ret[3])
{
    const double *a = pg->v[pg->idx[t[0]]], *b = pg->v[pg->idx[t[1]]],
                 *c = pg->v[pg->idx[t[2]]];
    double u[3], w[3];
    geo_vsub(b, a, u);
    geo_vsub(c, a, w);
    geo_vcross(u, w, ret);
}

/* Triangulates and checks that the triangles tile the polygon. */
static void check_tiling(const polygon *pg)
{
    uint32_t (*t)[3] = malloc((pg->n - 2) * sizeof *t);
    assert_non_null(t);
    assert_int_equal(
        geo_polygon_triangulate(&pg->v[0][0], pg->idx, pg->n, t), 0);
    double nrm[3];
    newell(pg, nrm);
    double area = 0.5 * geo_vlen(nrm), sum = 0;
    geo_vnormalize(nrm);
    /* edge use count: +1 for i→j, stored at [i][j] */
    static int8_t use[MAXN][MAXN];
    memset(use, 0, sizeof use);
    for (uint32_t k = 0; k + 2 < pg->n; k++) {
        for (int e = 0; e < 3; e++) {
            uint32_t i = t[k][e], j = t[k][(e + 1) % 3];
            assert_true(i < pg->n && j < pg->n && i != j);
            use[i][j]++;
        }
        double av[3];
        tri_area_vector(pg, t[k], av);
        double s = geo_vdot(av, nrm);
        if (s <= 0)
            fail_msg("triangle %u (%u %u %u) does not turn like the polygon",
                     k, t[k][0], t[k][1], t[k][2]);
        sum += 0.5 * s;
    }
    for (uint32_t i = 0; i < pg->n; i++)
        for (uint32_t j = 0; j < pg->n; j++) {
            int boundary = j == (i + 1) % pg->n;
            if (boundary)
                assert_int_equal(use[i][j], 1);
            else if (j != (i + pg->n - 1) % pg->n)
                assert_int_equal(use[i][j], use[j][i]);
            else
                assert_int_equal(use[i][j], 0);
            assert_true(use[i][j] <= 1);
        }
    assert_true(fabs(sum - area) <= 1e-12 * (1 + area));
    free(t);
}

static void test_convex_polygon_is_fanned(void **state)
{
    (void)state;
    polygon pg = {0};
    for (int i = 0; i < 6; i++)
        add2(&pg, cos(i * M_PI / 3), sin(i * M_PI / 3));
    uint32_t t[4][3];
    assert_int_equal(geo_polygon_triangulate(&pg.v[0][0], pg.idx, pg.n, t), 0);
    for (uint32_t k = 0; k < 4; k++) {
        assert_int_equal(t[k][0], 0);
        assert_int_equal(t[k][1], k + 1);
        assert_int_equal(t[k][2], k + 2);
    }
    check_tiling(&pg);
    tilt(&pg);
    check_tiling(&pg);
}

static void test_triangle_is_itself(void **state)
{
    (void)state;
    polygon pg = {0};
    add2(&pg, 0, 0);
    add2(&pg, 1, 0);
    add2(&pg, 0, 1);
    uint32_t t[1][3];
    assert_int_equal(geo_polygon_triangulate(&pg.v[0][0], pg.idx, 3, t), 0);
    assert_int_equal(t[0][0], 0);
    assert_int_equal(t[0][1], 1);
    assert_int_equal(t[0][2], 2);
    assert_int_equal(geo_polygon_triangulate(&pg.v[0][0], pg.idx, 2, t), -EINVAL);
}

static void star(polygon *pg, int points, double r_in, double r_out)
{
    pg->n = 0;
    for (int i = 0; i < 2 * points; i++) {
        double r = i % 2 ? r_in : r_out, a = i * M_PI / points;
        add2(pg, r * cos(a), r * sin(a));
    }
}

static void test_star_is_tiled(void **state)
{
    (void)state;
    polygon pg = {0};
    star(&pg, 5, 0.4, 1);
    check_tiling(&pg);
    tilt(&pg);
    check_tiling(&pg);
}

static void test_comb_is_tiled(void **state)
{
    (void)state;
    polygon pg = {0};
    /* a spine along the bottom and 6 teeth pointing up */
    add2(&pg, 0, 0);
    add2(&pg, 13, 0);
    for (int k = 6; k >= 0; k--) {
        double x = 2 * k;
        add2(&pg, x + 1, 5);
        add2(&pg, x, 5);
        if (k)
            add2(&pg, x - 0.5, 1);
    }
    /* the last point added is (0, 5): the polygon closes down to (0, 0) */
    check_tiling(&pg);
    tilt(&pg);
    check_tiling(&pg);
}

static void test_u_shape_is_tiled(void **state)
{
    (void)state;
    polygon pg = {0};
    const double u[8][2] = {{0, 0}, {3, 0}, {3, 3}, {2, 3},
                            {2, 1}, {1, 1}, {1, 3}, {0, 3}};
    for (int i = 0; i < 8; i++)
        add2(&pg, u[i][0], u[i][1]);
    check_tiling(&pg);
    /* every start corner: the clipping order depends on it */
    for (uint32_t s = 1; s < pg.n; s++) {
        polygon r = {0};
        for (uint32_t i = 0; i < pg.n; i++)
            add2(&r, u[(i + s) % 8][0], u[(i + s) % 8][1]);
        check_tiling(&r);
    }
}

static void test_collinear_corners_make_no_flat_triangles(void **state)
{
    (void)state;
    polygon pg = {0};
    /* a square with extra corners on every side, one side with three */
    const double sq[12][2] = {{0, 0}, {1, 0}, {2, 0}, {2, 1}, {2, 2},
                              {1.5, 2}, {1, 2}, {0.5, 2}, {0, 2}, {0, 1.5},
                              {0, 1}, {0, 0.5}};
    for (int i = 0; i < 12; i++)
        add2(&pg, sq[i][0], sq[i][1]);
    check_tiling(&pg);
    tilt(&pg);
    check_tiling(&pg);
    /* a non-convex one: an L with collinear corners along both arms */
    polygon l = {0};
    const double lp[8][2] = {{0, 0}, {1, 0}, {2, 0}, {2, 1},
                             {1, 1}, {1, 2}, {0, 2}, {0, 1}};
    for (int i = 0; i < 8; i++)
        add2(&l, lp[i][0], lp[i][1]);
    check_tiling(&l);
}

static void test_clockwise_seen_polygon_keeps_its_direction(void **state)
{
    (void)state;
    polygon pg = {0};
    star(&pg, 6, 0.5, 1);
    /* reverse: the normal now points to −z */
    for (uint32_t i = 0; i < pg.n; i++)
        pg.idx[i] = pg.n - 1 - i;
    check_tiling(&pg);
}

static void test_nearly_planar_polygon_is_tiled(void **state)
{
    (void)state;
    polygon pg = {0};
    star(&pg, 7, 0.3, 1);
    for (uint32_t i = 0; i < pg.n; i++)
        pg.v[i][2] = 1e-9 * ((i * 7919) % 13);
    tilt(&pg);
    check_tiling(&pg);
}

static void test_large_polygon_uses_heap_path(void **state)
{
    (void)state;
    polygon pg = {0};
    star(&pg, 100, 0.8, 1);
    check_tiling(&pg);
}

static void test_degenerate_input_still_gives_n_minus_2(void **state)
{
    (void)state;
    polygon pg = {0};
    for (int i = 0; i < 5; i++)
        add2(&pg, i, 2 * i); /* all collinear: zero Newell normal */
    uint32_t t[3][3];
    assert_int_equal(geo_polygon_triangulate(&pg.v[0][0], pg.idx, 5, t), 0);
    for (int k = 0; k < 3; k++)
        for (int e = 0; e < 3; e++)
            assert_true(t[k][e] < 5);
    /* a bow tie (self-intersecting) and a polygon visiting a point twice */
    polygon bt = {0};
    const double b[6][2] = {{0, 0}, {2, 2}, {2, 0}, {0, 2}, {1, 3}, {-1, 1}};
    for (int i = 0; i < 6; i++)
        add2(&bt, b[i][0], b[i][1]);
    uint32_t t2[4][3];
    assert_int_equal(geo_polygon_triangulate(&bt.v[0][0], bt.idx, 6, t2), 0);
    uint32_t seen = 0;
    for (int k = 0; k < 4; k++)
        for (int e = 0; e < 3; e++) {
            assert_true(t2[k][e] < 6);
            seen |= 1u << t2[k][e];
        }
    assert_int_equal(seen, 0x3f);
    polygon tw = {0};
    const double w[6][2] = {{0, 0}, {2, 0}, {1, 1}, {2, 2}, {0, 2}, {1, 1}};
    for (int i = 0; i < 6; i++)
        add2(&tw, w[i][0], w[i][1]);
    assert_int_equal(geo_polygon_triangulate(&tw.v[0][0], tw.idx, 6, t2), 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_convex_polygon_is_fanned),
        cmocka_unit_test(test_triangle_is_itself),
        cmocka_unit_test(test_star_is_tiled),
        cmocka_unit_test(test_comb_is_tiled),
        cmocka_unit_test(test_u_shape_is_tiled),
        cmocka_unit_test(test_collinear_corners_make_no_flat_triangles),
        cmocka_unit_test(test_clockwise_seen_polygon_keeps_its_direction),
        cmocka_unit_test(test_nearly_planar_polygon_is_tiled),
        cmocka_unit_test(test_large_polygon_uses_heap_path),
        cmocka_unit_test(test_degenerate_input_still_gives_n_minus_2),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
