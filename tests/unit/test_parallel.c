/* test_parallel.c — par_for runs every index exactly once, for any pool
 * size and for many loops in a row on the same pool. */
#include "testutil.h"

#include <stdatomic.h>
#include <stdlib.h>

#include "parallel.h"

typedef struct counts {
    atomic_int *hit;
} counts;

static void mark(void *arg, size_t i)
{
    counts *c = arg;
    atomic_fetch_add(&c->hit[i], 1);
}

static void test_every_index_runs_once(void **state)
{
    (void)state;
    for (int threads = 1; threads <= 4; threads++) {
        par_pool *p = par_pool_new(threads);
        assert_non_null(p);
        assert_int_equal(par_pool_threads(p), threads);
        for (int loop = 0; loop < 200; loop++) {
            size_t n = (size_t)(loop * 37 % 500);
            counts c = {calloc(n + 1, sizeof(atomic_int))};
            par_for(p, n, mark, &c);
            for (size_t i = 0; i < n; i++)
                assert_int_equal(atomic_load(&c.hit[i]), 1);
            free(c.hit);
        }
        par_pool_free(p);
    }
}

static void test_null_pool_runs_inline(void **state)
{
    (void)state;
    counts c = {calloc(10, sizeof(atomic_int))};
    par_for(NULL, 10, mark, &c);
    for (size_t i = 0; i < 10; i++)
        assert_int_equal(atomic_load(&c.hit[i]), 1);
    free(c.hit);
    assert_null(par_pool_free(NULL));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_index_runs_once),
        cmocka_unit_test(test_null_pool_runs_inline),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
