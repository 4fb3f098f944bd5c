/* test_ptree.c — the tree of balls over points: geo_ptree_reach gives,
 * bit for bit, what the evaluation of every (point, plane) pair gives
 * (planes tangent to a sphere, scaled, through one point; points inside
 * and out, in clusters, equal, not finite), and geo_ptree_above lists
 * every point above a plane's level, once, and few others. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "ptree.h"
#include "vec.h"

/* A random unit vector (rejection from the cube). */
static void rand_dir(uint64_t *rng, double n[3])
{
    double l;
    do {
        for (int c = 0; c < 3; c++)
            n[c] = 2 * geo_rand_unit(rng) - 1;
        l = geo_vdot(n, n);
    } while (l > 1 || l < 1e-6);
    for (int c = 0; c < 3; c++)
        n[c] /= sqrt(l);
}

/* Every pair evaluated: the value geo_ptree_reach must give. */
static double reach_brute(const double (*pl)[4], uint32_t np,
                          const double (*x)[3], uint32_t nx)
{
    double m = 0;
    for (uint32_t i = 0; i < nx; i++)
        for (uint32_t j = 0; j < np; j++) {
            double d = geo_plane_eval(pl[j], x[i]);
            if (d > m)
                m = d;
        }
    return m;
}

static double reach(const double (*pl)[4], uint32_t np,
                    const double (*x)[3], uint32_t nx)
{
    geo_ptree *t = NULL;
    double got = -1;
    assert_int_equal(geo_ptree_build(x, nx, &t), 0);
    assert_int_equal(geo_ptree_reach(t, x, pl, np, &got), 0);
    geo_ptree_free(t);
    return got;
}

static void test_reach_is_every_pair(void **state)
{
    (void)state;
    enum { NP = 700, NX = 300 };
    double(*pl)[4] = malloc(NP * sizeof *pl), (*x)[3] = malloc(NX * sizeof *x);
    assert_non_null(pl);
    assert_non_null(x);
    uint64_t rng = 41;
    int positive = 0;
    for (int round = 0; round < 40; round++) {
        uint32_t np = 1 + (uint32_t)(geo_rand_next(&rng) % NP);
        uint32_t nx = (uint32_t)(geo_rand_next(&rng) % NX);
        double s = round % 3 == 0 ? 3.0 : 1.0; /* not unit normals */
        double out = round % 4 == 1 ? 0.0 : 0.05; /* all inside or not */
        for (uint32_t j = 0; j < np; j++) {
            double n[3];
            rand_dir(&rng, n);
            for (int c = 0; c < 3; c++)
                pl[j][c] = s * n[c];
            pl[j][3] = -s * (1 + 0.01 * geo_rand_unit(&rng));
        }
        for (uint32_t i = 0; i < nx; i++) {
            double n[3];
            rand_dir(&rng, n);
            double r = out > 0 ? 1 - 0.1 * geo_rand_unit(&rng) +
                                     out * geo_rand_unit(&rng)
                               : 0.99 - 0.1 * geo_rand_unit(&rng);
            if (i > 0 && i % 7 < 3) /* a cluster around the last point */
                for (int c = 0; c < 3; c++)
                    x[i][c] = x[i - 1][c] + 1e-9 * geo_rand_unit(&rng);
            else if (i > 0 && i % 11 == 5) /* the same point again */
                memcpy(x[i], x[i - 1], sizeof x[i]);
            else
                for (int c = 0; c < 3; c++)
                    x[i][c] = r * n[c] + 5;
        }
        for (uint32_t j = 0; j < np; j++) /* about the centre (5, 5, 5) */
            pl[j][3] -= 5 * (pl[j][0] + pl[j][1] + pl[j][2]);
        if (round % 4 == 2 && nx > 0 && np > 10) /* a pencil through x[0] */
            for (uint32_t j = 0; j < 10; j++)
                pl[j][3] = -geo_vdot(pl[j], x[0]);
        double want = reach_brute((const double(*)[4])pl, np,
                                  (const double(*)[3])x, nx);
        double got = reach((const double(*)[4])pl, np, (const double(*)[3])x,
                           nx);
        assert_memory_equal(&want, &got, sizeof want);
        positive += want > 0;
        if (round % 4 == 1)
            assert_true(want == 0);
    }
    print_message("reach: %d of 40 sets reach outside\n", positive);
    assert_true(positive > 20);
    /* not finite: a NaN point and a NaN plane count for nothing, an
     * infinite point for what its planes give */
    double q[2][4] = {{1, 0, 0, -1}, {NAN, 0, 0, 0}};
    double y[3][3] = {{0.5, 0, 0}, {NAN, 0, 0}, {2, 0, 0}};
    assert_true(reach((const double(*)[4])q, 2, (const double(*)[3])y, 3) ==
                1.0);
    y[1][0] = INFINITY;
    assert_true(isinf(reach((const double(*)[4])q, 2, (const double(*)[3])y,
                            3)));
    assert_true(reach((const double(*)[4])q, 0, (const double(*)[3])y, 3) == 0);
    assert_true(reach((const double(*)[4])q, 2, (const double(*)[3])y, 0) == 0);
    free(pl), free(x);
}

/* Points on a sphere (some repeated, some not finite): for random planes
 * and levels every point above the level is listed, none twice, and a
 * tangent plane lists few of the 5,000. */
static void test_above_lists_every_point_above(void **state)
{
    (void)state;
    enum { N = 5000 };
    double(*x)[3] = malloc(N * sizeof *x);
    uint32_t *out = malloc(N * sizeof *out), *seen = calloc(N, sizeof *seen);
    assert_non_null(x);
    assert_non_null(out);
    assert_non_null(seen);
    uint64_t rng = 7;
    for (uint32_t i = 0; i < N; i++) {
        rand_dir(&rng, x[i]);
        geo_vscale(x[i], 3, x[i]);
        if (i % 97 == 3)
            memcpy(x[i], x[i - 1], sizeof x[i]);
    }
    x[10][1] = NAN, x[20][2] = -INFINITY;
    geo_ptree *t = NULL;
    assert_int_equal(geo_ptree_build((const double(*)[3])x, N, &t), 0);
    uint32_t tangent_max = 0;
    for (uint32_t round = 1; round <= 200; round++) {
        double pl[4];
        rand_dir(&rng, pl);
        double s = round % 5 == 0 ? 0.25 : 1.0;
        geo_vscale(pl, s, pl);
        pl[3] = -s * 3 * geo_rand_unit(&rng);
        double level = round % 2 ? 0 : s * (geo_rand_unit(&rng) - 0.5);
        uint32_t n = geo_ptree_above(t, pl, level, out);
        for (uint32_t i = 0; i < n; i++) {
            assert_true(out[i] < N);
            assert_int_not_equal(seen[out[i]], round); /* once */
            seen[out[i]] = round;
        }
        uint32_t above = 0;
        for (uint32_t i = 0; i < N; i++)
            if (geo_plane_eval(pl, x[i]) > level) {
                above++;
                assert_int_equal(seen[i], round);
            }
        assert_int_equal(seen[10], round); /* not finite: always */
        assert_int_equal(seen[20], round);
        assert_true(n >= above);
        /* tangent: offset −3·s, level 0 */
        pl[3] = -3 * s;
        n = geo_ptree_above(t, pl, 0, out);
        tangent_max = n > tangent_max ? n : tangent_max;
    }
    print_message("above: a tangent plane lists at most %u of %u points\n",
                  tangent_max, N);
    assert_true(tangent_max < N / 20);
    geo_ptree_free(t);
    /* no points; all points equal (one leaf of them all) */
    assert_int_equal(geo_ptree_build((const double(*)[3])x, 0, &t), 0);
    double pl[4] = {1, 0, 0, 0};
    assert_int_equal(geo_ptree_above(t, pl, -1, out), 0);
    geo_ptree_free(t);
    for (uint32_t i = 0; i < 100; i++)
        x[i][0] = x[i][1] = x[i][2] = 1;
    assert_int_equal(geo_ptree_build((const double(*)[3])x, 100, &t), 0);
    assert_int_equal(geo_ptree_above(t, pl, 0.5, out), 100);
    assert_int_equal(geo_ptree_above(t, pl, 1.5, out), 0);
    assert_null(geo_ptree_free(t));
    free(x), free(out), free(seen);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reach_is_every_pair),
        cmocka_unit_test(test_above_lists_every_point_above),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
