/* test_select.c — geo_select_kth gives the value a sort puts at k: every
 * k of short arrays, random k of long ones, with many equal values,
 * sorted, reversed, all equal and organ-pipe orders, and zeros, negative
 * values and infinities among them; geo_select_axis splits point
 * indices as a sort by a coordinate would, over the same orders. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "select.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void fill(double *a, uint32_t n, int kind, uint64_t *rng)
{
    for (uint32_t i = 0; i < n; i++) {
        switch (kind) {
        case 0: a[i] = geo_rand_unit(rng); break;
        case 1: a[i] = (double)(geo_rand_next(rng) % 5); break;
        case 2: a[i] = i; break;
        case 3: a[i] = n - i; break;
        case 4: a[i] = 7; break;
        case 5: a[i] = i < n / 2 ? i : n - i; break;
        default:
            a[i] = i % 3 == 0 ? 0.0 : i % 3 == 1 ? INFINITY : -1.5 * i;
        }
    }
}

static void check(const double *a, uint32_t n, uint32_t k)
{
    double *s = malloc((n + 1) * sizeof *s), *w = malloc((n + 1) * sizeof *w);
    assert_non_null(s);
    assert_non_null(w);
    memcpy(s, a, n * sizeof *s);
    memcpy(w, a, n * sizeof *w);
    qsort(s, n, sizeof *s, cmp_double);
    double v = geo_select_kth(w, n, k);
    assert_true(v == s[k]);
    /* a permutation of the input */
    qsort(w, n, sizeof *w, cmp_double);
    assert_memory_equal(w, s, n * sizeof *s);
    free(s), free(w);
}

static void test_kth_is_what_a_sort_gives(void **state)
{
    (void)state;
    uint64_t rng = 17;
    double *a = malloc(100001 * sizeof *a);
    assert_non_null(a);
    for (int kind = 0; kind < 7; kind++) {
        for (uint32_t n = 1; n <= 70; n++) {
            fill(a, n, kind, &rng);
            for (uint32_t k = 0; k < n; k++)
                check(a, n, k);
        }
        static const uint32_t big[] = {1000, 4097, 100000};
        for (size_t b = 0; b < sizeof big / sizeof big[0]; b++)
            for (int t = 0; t < 4; t++) {
                fill(a, big[b], kind, &rng);
                uint32_t k = t == 0 ? 0 : t == 1 ? big[b] - 1
                                      : (uint32_t)(geo_rand_next(&rng) % big[b]);
                check(a, big[b], k);
            }
    }
    free(a);
}

/* geo_select_axis: idx[k] carries the key a sort puts at k, the keys
 * before it are not larger and those after not smaller, and idx stays a
 * permutation; for every fill order (equal keys, sorted, organ pipe). */
static void test_axis_split_is_a_partition(void **state)
{
    (void)state;
    enum { N = 3000 };
    double(*pts)[3] = malloc(N * sizeof *pts), *key = malloc(N * sizeof *key);
    uint32_t *idx = malloc(N * sizeof *idx), *seen = calloc(N, sizeof *seen);
    assert_non_null(pts);
    assert_non_null(key);
    assert_non_null(idx);
    assert_non_null(seen);
    uint64_t rng = 5;
    for (int kind = 0; kind < 7; kind++)
        for (int round = 0; round < 20; round++) {
            uint32_t n = 1 + (uint32_t)(geo_rand_next(&rng) % N);
            int axis = round % 3;
            fill(key, n, kind, &rng);
            for (uint32_t i = 0; i < n; i++) {
                pts[i][0] = pts[i][1] = pts[i][2] = -1;
                pts[i][axis] = key[i];
                idx[i] = i;
            }
            uint32_t lo = (uint32_t)(geo_rand_next(&rng) % n);
            uint32_t hi = lo + 1 + (uint32_t)(geo_rand_next(&rng) % (n - lo));
            uint32_t k = lo + (uint32_t)(geo_rand_next(&rng) % (hi - lo));
            for (uint32_t i = 0; i < hi - lo; i++)
                key[i] = pts[lo + i][axis];
            qsort(key, hi - lo, sizeof *key, cmp_double);
            geo_select_axis((const double(*)[3])pts, idx, lo, hi, k, axis);
            double kv = pts[idx[k]][axis];
            assert_true(kv == key[k - lo]);
            uint32_t tag = (uint32_t)(kind * 20 + round + 1);
            for (uint32_t i = 0; i < n; i++) {
                assert_true(idx[i] < n);
                assert_int_not_equal(seen[idx[i]], tag);
                seen[idx[i]] = tag;
                if (i < lo || i >= hi)
                    assert_int_equal(idx[i], i);
                else if (i < k)
                    assert_true(pts[idx[i]][axis] <= kv);
                else
                    assert_true(pts[idx[i]][axis] >= kv);
            }
        }
    free(pts), free(key), free(idx), free(seen);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kth_is_what_a_sort_gives),
        cmocka_unit_test(test_axis_split_is_a_partition),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
