/* test_predicates.c — the filtered predicates give the exact sign, also
 * where naive double arithmetic gets it wrong. Exact references come from
 * integer arithmetic on coordinates that are exact multiples of 2^-k. */
#include "testutil.h"

#include <math.h>

#include "ctx.h"
#include "plane.h"
#include "predicates.h"

__extension__ typedef __int128 i128;

static int sign128(i128 v) { return (v > 0) - (v < 0); }

/* Exact orient3d on integer coordinates (|x| < 2^30: products fit). */
static int orient3d_int(const int64_t a[3], const int64_t b[3],
                        const int64_t c[3], const int64_t d[3])
{
    i128 ab[3], ac[3], ad[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ad[k] = d[k] - a[k];
    }
    i128 nx = ab[1] * ac[2] - ab[2] * ac[1];
    i128 ny = ab[2] * ac[0] - ab[0] * ac[2];
    i128 nz = ab[0] * ac[1] - ab[1] * ac[0];
    return sign128(ad[0] * nx + ad[1] * ny + ad[2] * nz);
}

static void test_orient3d_simple_signs(void **state)
{
    (void)state;
    double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
    double up[3] = {0.2, 0.3, 1}, down[3] = {0.2, 0.3, -1},
           on[3] = {5, -7, 0};
    assert_int_equal(geo_orient3d(a, b, c, up), 1);
    assert_int_equal(geo_orient3d(a, b, c, down), -1);
    assert_int_equal(geo_orient3d(a, b, c, on), 0);
}

/* Points on the plane x+y+z = 1 scaled far from the origin with tiny
 * offsets: the naive determinant's rounding error dominates. */
static void test_orient3d_matches_exact_near_degenerate(void **state)
{
    (void)state;
    uint64_t rng = 12345;
    int zeros = 0;
    for (int trial = 0; trial < 20000; trial++) {
        int64_t P[4][3];
        const int64_t base = (int64_t)1 << 28;
        for (int i = 0; i < 4; i++) {
            int64_t x = (int64_t)(geo_rand_next(&rng) % 2001) - 1000;
            int64_t y = (int64_t)(geo_rand_next(&rng) % 2001) - 1000;
            P[i][0] = base + x;
            P[i][1] = base + y;
            P[i][2] = -(x + y) + (int64_t)(geo_rand_next(&rng) % 3) - 1;
        }
        double D[4][3];
        for (int i = 0; i < 4; i++)
            for (int k = 0; k < 3; k++)
                D[i][k] = (double)P[i][k] * 0x1.0p-20;
        int exact = orient3d_int(P[0], P[1], P[2], P[3]);
        assert_int_equal(geo_orient3d(D[0], D[1], D[2], D[3]), exact);
        if (exact == 0)
            zeros++;
    }
    /* the generator must produce exactly coplanar cases too */
    assert_true(zeros > 100);
}

/* The prepared plane gives geo_orient3d's sign: on the near-degenerate
 * sets above (exact integer reference), on the ulp-perturbed lifted
 * example, and on random points over magnitudes 2^-40 .. 2^40 and
 * far-apart scales within one query. */
static void test_orient3d_plane_matches_orient3d(void **state)
{
    (void)state;
    uint64_t rng = 777;
    int zeros = 0;
    for (int trial = 0; trial < 20000; trial++) {
        int64_t P[6][3];
        const int64_t base = (int64_t)1 << 28;
        for (int i = 0; i < 6; i++) {
            int64_t x = (int64_t)(geo_rand_next(&rng) % 2001) - 1000;
            int64_t y = (int64_t)(geo_rand_next(&rng) % 2001) - 1000;
            P[i][0] = base + x;
            P[i][1] = base + y;
            P[i][2] = -(x + y) + (int64_t)(geo_rand_next(&rng) % 3) - 1;
        }
        double D[6][3];
        for (int i = 0; i < 6; i++)
            for (int k = 0; k < 3; k++)
                D[i][k] = (double)P[i][k] * 0x1.0p-20;
        geo_orient3d_plane pl;
        geo_orient3d_plane_init(&pl, D[0], D[1], D[2]);
        for (int q = 3; q < 6; q++) {
            int exact = orient3d_int(P[0], P[1], P[2], P[q]);
            assert_int_equal(geo_orient3d_plane_sign(&pl, D[q]), exact);
            zeros += exact == 0;
        }
    }
    assert_true(zeros > 100);

    double b[3] = {12, 12, 0}, c[3] = {24, 24, 0}, e[3] = {24, 24, 1};
    geo_orient3d_plane pl;
    geo_orient3d_plane_init(&pl, b, c, e);
    for (int i = 0; i < 128; i++)
        for (int j = 0; j < 128; j++) {
            double a[3] = {0.5 + i * 0x1.0p-53, 0.5 + j * 0x1.0p-53, 0};
            int exact = (a[0] > a[1]) - (a[0] < a[1]);
            assert_int_equal(geo_orient3d_plane_sign(&pl, a), exact);
        }

    for (int trial = 0; trial < 20000; trial++) {
        double Q[5][3];
        for (int i = 0; i < 5; i++) {
            double scale = ldexp(1.0, (int)(geo_rand_next(&rng) % 81) - 40);
            for (int k = 0; k < 3; k++)
                Q[i][k] = (2 * geo_rand_unit(&rng) - 1) * scale;
        }
        /* a query on the line through two of the points, rounded: nearly
         * coplanar */
        for (int k = 0; k < 3; k++)
            Q[4][k] = Q[0][k] + (Q[1][k] - Q[0][k]) * 0.375;
        geo_orient3d_plane_init(&pl, Q[0], Q[1], Q[2]);
        for (int q = 3; q < 5; q++)
            assert_int_equal(geo_orient3d_plane_sign(&pl, Q[q]),
                             geo_orient3d(Q[0], Q[1], Q[2], Q[q]));
    }
}

/* Shewchuk's classic example: points near the line y = x, where naive
 * orient2d returns wrong and inconsistent signs. */
static void test_orient2d_beats_naive(void **state)
{
    (void)state;
    double b[2] = {12, 12}, c[2] = {24, 24};
    int naive_wrong = 0;
    for (int i = 0; i < 256; i++)
        for (int j = 0; j < 256; j++) {
            double a[2] = {0.5 + i * 0x1.0p-53, 0.5 + j * 0x1.0p-53};
            /* exact: (b−a)×(c−a) = 12·(ay − ax), since b and c lie on
             * the line y = x */
            int exact = (a[1] > a[0]) - (a[1] < a[0]);
            int got = geo_orient2d(a, b, c);
            assert_int_equal(got, exact);
            double naive = (b[0] - a[0]) * (c[1] - a[1]) -
                           (b[1] - a[1]) * (c[0] - a[0]);
            int ns = (naive > 0) - (naive < 0);
            if (ns != exact)
                naive_wrong++;
        }
    /* the test is meaningful only if naive arithmetic does fail here */
    assert_true(naive_wrong > 1000);
}

static void test_orient3d_beats_naive(void **state)
{
    (void)state;
    /* The 2D example lifted: plane z = 0 through three points, the query
     * point perturbed by one ulp around the plane x = y containing b, c. */
    double b[3] = {12, 12, 0}, c[3] = {24, 24, 0}, e[3] = {24, 24, 1};
    int naive_wrong = 0;
    for (int i = 0; i < 128; i++)
        for (int j = 0; j < 128; j++) {
            double a[3] = {0.5 + i * 0x1.0p-53, 0.5 + j * 0x1.0p-53, 0};
            int got = geo_orient3d(b, c, e, a);
            /* normal (c−b)×(e−b) = (12,12,0)×(12,12,1) = (12,−12,0):
             * the positive side is x > y */
            int exact = (a[0] > a[1]) - (a[0] < a[1]);
            assert_int_equal(got, exact);
            double u[3], v[3], w[3];
            for (int k = 0; k < 3; k++) {
                u[k] = c[k] - b[k];
                v[k] = e[k] - b[k];
                w[k] = a[k] - b[k];
            }
            double naive = w[0] * (u[1] * v[2] - u[2] * v[1]) +
                           w[1] * (u[2] * v[0] - u[0] * v[2]) +
                           w[2] * (u[0] * v[1] - u[1] * v[0]);
            if (((naive > 0) - (naive < 0)) != exact)
                naive_wrong++;
        }
    assert_true(naive_wrong > 0);
}

static void test_plane_sign_exact(void **state)
{
    (void)state;
    /* plane 0.1·x − 0.1·y + 0 = 0 with doubles 0.1: the product rounding
     * must not decide the sign */
    double plane[4] = {0.1, -0.1, 0, 0};
    double p[3] = {3.0, 3.0, 7};
    assert_int_equal(geo_plane_sign(plane, p), 0);
    double q[3] = {nextafter(3.0, 4.0), 3.0, 7};
    assert_int_equal(geo_plane_sign(plane, q), 1);
    double r[3] = {3.0, nextafter(3.0, 4.0), 7};
    assert_int_equal(geo_plane_sign(plane, r), -1);
    /* d that cancels a product exactly only in exact arithmetic */
    double pl2[4] = {0.1, 0, 0, -0.1 * 3.0};
    double s[3] = {3.0, 0, 0};
    /* 0.1·3.0 exact ≠ fl(0.1·3.0): sign decided by the rounding residue */
    double hi = 0.1 * 3.0;
    double lo = fma(0.1, 3.0, -hi);
    int expect = (lo > 0) - (lo < 0);
    assert_int_equal(geo_plane_sign(pl2, s), expect);
}

static void test_orient2d_proj_axes(void **state)
{
    (void)state;
    double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {0, 1, 0};
    assert_int_equal(geo_orient2d_proj(a, b, c, 2), 1);
    double a2[3] = {0, 0, 0}, b2[3] = {0, 1, 0}, c2[3] = {0, 0, 1};
    assert_int_equal(geo_orient2d_proj(a2, b2, c2, 0), 1);
    double a3[3] = {0, 0, 0}, b3[3] = {0, 0, 1}, c3[3] = {1, 0, 0};
    assert_int_equal(geo_orient2d_proj(a3, b3, c3, 1), 1);
}

/* The projected orientation (its own filter, then the exact path) gives
 * the integer-exact sign on near-collinear points far from the origin,
 * for each dropped axis; the normal form N·(p − p0) likewise. */
static void test_orient2d_proj_and_normal_sign_exact(void **state)
{
    (void)state;
    uint64_t rng = 31;
    for (int t = 0; t < 20000; t++) {
        int64_t P[3][3];
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                P[i][k] = ((int64_t)1 << 40) +
                          (int64_t)(geo_rand_next(&rng) % 5) * (i + 1) +
                          (int64_t)(geo_rand_next(&rng) % 3);
        double D[3][3];
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                D[i][k] = (double)P[i][k] * 0x1p-30;
        for (int drop = 0; drop < 3; drop++) {
            int u = (drop + 1) % 3, v = (drop + 2) % 3;
            i128 det = (i128)(P[1][u] - P[0][u]) * (P[2][v] - P[0][v]) -
                       (i128)(P[1][v] - P[0][v]) * (P[2][u] - P[0][u]);
            assert_int_equal(geo_orient2d_proj(D[0], D[1], D[2], drop),
                             sign128(det));
        }
        int64_t N[3] = {(int64_t)(geo_rand_next(&rng) % 7) - 3,
                        (int64_t)(geo_rand_next(&rng) % 7) - 3,
                        (int64_t)(geo_rand_next(&rng) % 7) - 3};
        double n[3] = {(double)N[0], (double)N[1], (double)N[2]};
        i128 dot = 0;
        for (int k = 0; k < 3; k++)
            dot += (i128)N[k] * (P[2][k] - P[0][k]);
        assert_int_equal(geo_normal_sign(D[0], n, D[2]), sign128(dot));
    }
}

/* The prepared 2D line gives geo_orient2d_proj's sign (integer reference)
 * for each dropped axis, on points a few units apart far from the
 * origin, where cancellation is at its worst, and on random points over
 * magnitudes 2^-40 .. 2^40. */
static void test_orient2d_line_matches_orient2d_proj(void **state)
{
    (void)state;
    uint64_t rng = 57;
    int zeros = 0;
    for (int t = 0; t < 20000; t++) {
        int64_t P[5][3];
        for (int i = 0; i < 5; i++)
            for (int k = 0; k < 3; k++)
                P[i][k] = ((int64_t)1 << 40) +
                          (int64_t)(geo_rand_next(&rng) % 5) * (i + 1) +
                          (int64_t)(geo_rand_next(&rng) % 3);
        double D[5][3];
        for (int i = 0; i < 5; i++)
            for (int k = 0; k < 3; k++)
                D[i][k] = (double)P[i][k] * 0x1p-30;
        for (int drop = 0; drop < 3; drop++) {
            geo_orient2d_line l;
            geo_orient2d_line_init(&l, D[0], D[1], drop);
            int u = (drop + 1) % 3, v = (drop + 2) % 3;
            for (int q = 2; q < 5; q++) {
                i128 det =
                    (i128)(P[1][u] - P[0][u]) * (P[q][v] - P[0][v]) -
                    (i128)(P[1][v] - P[0][v]) * (P[q][u] - P[0][u]);
                assert_int_equal(geo_orient2d_line_sign(&l, D[q]),
                                 sign128(det));
                zeros += det == 0;
            }
        }
    }
    assert_true(zeros > 100);
    for (int t = 0; t < 20000; t++) {
        double Q[4][3];
        for (int i = 0; i < 3; i++) {
            double scale = ldexp(1.0, (int)(geo_rand_next(&rng) % 81) - 40);
            for (int k = 0; k < 3; k++)
                Q[i][k] = (2 * geo_rand_unit(&rng) - 1) * scale;
        }
        for (int k = 0; k < 3; k++) /* on the line, rounded */
            Q[3][k] = Q[0][k] + (Q[1][k] - Q[0][k]) * 0.625;
        for (int drop = 0; drop < 3; drop++) {
            geo_orient2d_line l;
            geo_orient2d_line_init(&l, Q[0], Q[1], drop);
            for (int q = 2; q < 4; q++)
                assert_int_equal(geo_orient2d_line_sign(&l, Q[q]),
                                 geo_orient2d_proj(Q[0], Q[1], Q[q], drop));
        }
    }
}

/* geo_plane_meet_sign on integer planes through an integer point P: the
 * side of P of a fourth plane q, which is exactly q(P) = δ. Normals and P
 * near 2^25 (products stay below 2^53) make the 4 × 4 determinant cancel far below the doubles'
 * resolution, so the exact path decides. Orders of the three planes and
 * their scaling by powers of two never change the answer. */
static void test_plane_meet_sign_exact(void **state)
{
    (void)state;
    uint64_t rng = 99;
    int exact_needed = 0;
    for (int round = 0; round < 2000; round++) {
        double big = round % 2 ? 0x1p25 : 3;
        double P[3], pl[4][4];
        for (int k = 0; k < 3; k++)
            P[k] = floor((geo_rand_unit(&rng) - 0.5) * 2 * big);
        for (int i = 0; i < 4; i++) {
            for (int k = 0; k < 3; k++)
                pl[i][k] = floor((geo_rand_unit(&rng) - 0.5) * 2 * big);
            pl[i][3] = -(pl[i][0] * P[0] + pl[i][1] * P[1] + pl[i][2] * P[2]);
        }
        /* integers below 2^53 throughout: every plane passes through P */
        double delta = (double)(int)(geo_rand_next(&rng) % 3) - 1;
        pl[3][3] += delta;
        static const double zero[3] = {0, 0, 0};
        if (geo_orient3d(zero, pl[0], pl[1], pl[2]) == 0)
            continue;
        int want = (delta > 0) - (delta < 0);
        assert_int_equal(geo_plane_meet_sign(pl[0], pl[1], pl[2], pl[3]),
                         want);
        geo_meet m;
        geo_meet_prepare(pl[0], pl[1], pl[2], &m);
        assert_int_equal(geo_meet_side(&m, pl[3]), want);
        assert_int_equal(geo_plane_meet_sign(pl[2], pl[0], pl[1], pl[3]),
                         want);
        assert_int_equal(geo_plane_meet_sign(pl[1], pl[0], pl[2], pl[3]),
                         want);
        double half[4], neg[4];
        for (int k = 0; k < 4; k++)
            half[k] = pl[0][k] * 0.5, neg[k] = -pl[3][k];
        assert_int_equal(geo_plane_meet_sign(half, pl[1], pl[2], pl[3]),
                         want);
        assert_int_equal(geo_plane_meet_sign(pl[0], pl[1], pl[2], neg),
                         -want);
        exact_needed += big > 1e6 && delta != 0;
    }
    assert_true(exact_needed > 100);
    /* parallel normals meet in no point */
    const double a[4] = {1, 0, 0, 0}, b[4] = {2, 0, 0, -1}, c[4] = {0, 1, 0, 0};
    const double q[4] = {0, 0, 1, 5};
    assert_int_equal(geo_plane_meet_sign(a, b, c, q), 0);
}

/* geo_meet_side answers as geo_plane_meet_sign does: on random planes
 * of unit-ish normals and millimetre offsets, with a fourth plane far
 * from the meet, through it as nearly as doubles allow (its offset from
 * the rounded meet point: the sign is then a matter of the last bits),
 * and through it exactly (a sum of two of the three planes). */
static void test_meet_side_matches_plane_meet_sign(void **state)
{
    (void)state;
    uint64_t rng = 5;
    static const double zero[3] = {0, 0, 0};
    int near_zero = 0;
    for (int round = 0; round < 100000; round++) {
        double pl[3][4], q[4];
        for (int i = 0; i < 3; i++) {
            for (int k = 0; k < 4; k++)
                pl[i][k] = (geo_rand_unit(&rng) - 0.5) * (k == 3 ? 20 : 2);
        }
        if (geo_orient3d(zero, pl[0], pl[1], pl[2]) == 0)
            continue;
        geo_meet m;
        geo_meet_prepare(pl[0], pl[1], pl[2], &m);
        for (int k = 0; k < 3; k++)
            q[k] = geo_rand_unit(&rng) - 0.5;
        int kind = round % 3;
        if (kind == 0) {
            q[3] = (geo_rand_unit(&rng) - 0.5) * 20;
        } else if (kind == 1) {
            double x[3];
            if (!geo_plane_intersect3(pl[0], pl[1], pl[2], x))
                continue;
            q[3] = -(q[0] * x[0] + q[1] * x[1] + q[2] * x[2]);
        } else {
            for (int k = 0; k < 4; k++)
                q[k] = pl[0][k] + pl[2][k];
        }
        int want = geo_plane_meet_sign(pl[0], pl[1], pl[2], q);
        assert_int_equal(geo_meet_side(&m, q), want);
        near_zero += kind > 0 && want == 0;
    }
    assert_true(near_zero > 1000); /* the exact zeros were reached */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_orient3d_simple_signs),
        cmocka_unit_test(test_orient3d_matches_exact_near_degenerate),
        cmocka_unit_test(test_orient3d_plane_matches_orient3d),
        cmocka_unit_test(test_orient2d_beats_naive),
        cmocka_unit_test(test_orient3d_beats_naive),
        cmocka_unit_test(test_plane_sign_exact),
        cmocka_unit_test(test_orient2d_proj_axes),
        cmocka_unit_test(test_orient2d_proj_and_normal_sign_exact),
        cmocka_unit_test(test_orient2d_line_matches_orient2d_proj),
        cmocka_unit_test(test_plane_meet_sign_exact),
        cmocka_unit_test(test_meet_side_matches_plane_meet_sign),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
