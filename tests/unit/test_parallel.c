/* test_parallel.c — par_for runs every index exactly once, for any pool
 * size, for many loops in a row on the same pool, for loops started from
 * several threads at once and for loops nested inside a loop. */
#include "testutil.h"

#include <pthread.h>
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

typedef struct nest {
    par_pool *pool;
    atomic_int *hit; /* 50 × 40 inner indices */
} nest;

static void inner(void *arg, size_t i)
{
    atomic_int *row = arg;
    atomic_fetch_add(&row[i], 1);
}

static void outer(void *arg, size_t i)
{
    nest *n = arg;
    par_for(n->pool, 40, inner, n->hit + i * 40);
}

static void *caller(void *arg)
{
    nest *n = arg;
    for (int loop = 0; loop < 50; loop++)
        par_for(n->pool, 50, outer, n);
    return NULL;
}

static void test_concurrent_and_nested_loops_run_every_index(void **state)
{
    (void)state;
    par_pool *p = par_pool_new(3);
    assert_non_null(p);
    enum { CALLERS = 4 };
    nest ns[CALLERS];
    pthread_t th[CALLERS];
    for (int c = 0; c < CALLERS; c++) {
        ns[c] = (nest){p, calloc(50 * 40, sizeof(atomic_int))};
        assert_int_equal(pthread_create(&th[c], NULL, caller, &ns[c]), 0);
    }
    for (int c = 0; c < CALLERS; c++) {
        pthread_join(th[c], NULL);
        for (int i = 0; i < 50 * 40; i++)
            assert_int_equal(atomic_load(&ns[c].hit[i]), 50);
        free(ns[c].hit);
    }
    par_pool_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_index_runs_once),
        cmocka_unit_test(test_null_pool_runs_inline),
        cmocka_unit_test(test_concurrent_and_nested_loops_run_every_index),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
