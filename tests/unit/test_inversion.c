/* test_inversion.c — inversion statistics (Palachev 2012, §4.3.4): the Wilson
 * interval, identical results for any thread count, the paper's
 * conclusion on a sample scan (the probability falls with m and is 0 at
 * the smallest m), per-run detail, bad options and cancellation. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "inversion.h"
#include "parallel.h"
#include "tu_load.h"
#include "vec.h"

static void test_wilson_interval_known_values(void **state)
{
    (void)state;
    double lo, hi;
    geo_wilson95(0, 100, &lo, &hi);
    assert_true(lo == 0 && fabs(hi - 0.0370) < 1e-4);
    geo_wilson95(50, 100, &lo, &hi);
    assert_true(fabs(lo - 0.4038) < 1e-4 && fabs(hi - 0.5962) < 1e-4);
    geo_wilson95(100, 100, &lo, &hi);
    assert_true(fabs(lo - 0.9630) < 1e-4 && hi == 1);
    geo_wilson95(0, 0, &lo, &hi);
    assert_true(lo == 0 && hi == 1);
}

static void small_opts(geo_inversion_opts *o, uint32_t samples)
{
    geo_inversion_opts_default(o);
    o->samples = samples;
    o->keep_runs = true;
}

static void test_result_identical_for_any_thread_count(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(p);
    geo_inversion_opts o;
    small_opts(&o, 12);
    geo_ctx one = {.seed = 7};
    geo_inversion_stats a, b;
    assert_int_equal(geo_inversion_stats_run(p, &o, &one, &a, NULL), 0);
    par_pool *pool = par_pool_new(3);
    assert_non_null(pool);
    geo_ctx three = {.seed = 7, .parallel_for = par_for, .pf_user = pool};
    assert_int_equal(geo_inversion_stats_run(p, &o, &three, &b, NULL), 0);
    assert_int_equal(a.nrows, b.nrows);
    assert_int_equal(a.nruns, 12 * 10);
    assert_memory_equal(a.rows, b.rows, a.nrows * sizeof a.rows[0]);
    assert_memory_equal(a.runs, b.runs, a.nruns * sizeof a.runs[0]);
    /* another seed draws other vertices */
    geo_inversion_stats c;
    one.seed = 8;
    assert_int_equal(geo_inversion_stats_run(p, &o, &one, &c, NULL), 0);
    bool differ = false;
    for (uint32_t i = 0; i < c.nruns; i++)
        differ |= c.runs[i].vertex != a.runs[i].vertex;
    assert_true(differ);
    geo_inversion_stats_clear(&a);
    geo_inversion_stats_clear(&b);
    geo_inversion_stats_clear(&c);
    par_pool_free(pool);
    geo_poly_free(p);
}

static void test_runs_follow_the_sampling_plan(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(p);
    geo_inversion_opts o;
    small_opts(&o, 5);
    geo_ctx ctx = {.seed = 3};
    geo_inversion_stats s;
    assert_int_equal(geo_inversion_stats_run(p, &o, &ctx, &s, NULL), 0);
    for (uint32_t i = 0; i < s.nruns; i++) {
        const geo_inversion_run *r = &s.runs[i];
        const geo_inversion_run *first = &s.runs[r->sample * o.nmagnitudes];
        assert_int_equal(r->sample, i / o.nmagnitudes);
        assert_true(r->m == o.magnitudes[i % o.nmagnitudes]);
        /* one vertex and direction per sample, for every magnitude */
        assert_int_equal(r->vertex, first->vertex);
        assert_memory_equal(r->dir, first->dir, sizeof r->dir);
        assert_true(fabs(geo_vlen(r->dir) - 1) < 1e-12);
        /* δ is the distance to the nearest other vertex */
        double best = INFINITY;
        for (uint32_t v = 0; v < p->nverts; v++)
            if (v != r->vertex)
                best = fmin(best, geo_vdist(p->verts[v], p->verts[r->vertex]));
        assert_true(r->delta == best);
        assert_true(r->inverted == (!r->converged || r->nselfint != 0 ||
                                    r->ninverted != 0 || !(r->volume > 0)));
    }
    uint32_t total = 0;
    for (uint32_t k = 0; k < s.nrows; k++) {
        assert_int_equal(s.rows[k].runs, 5);
        total += s.rows[k].inverted;
    }
    uint32_t counted = 0;
    for (uint32_t i = 0; i < s.nruns; i++)
        counted += s.runs[i].inverted;
    assert_int_equal(total, counted);
    geo_inversion_stats_clear(&s);
    geo_poly_free(p);
}

static void test_probability_falls_with_magnitude_on_a_scan(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(p);
    geo_inversion_opts o;
    geo_inversion_opts_default(&o);
    o.samples = 40;
    o.nmagnitudes = 3;
    o.magnitudes[0] = 1;
    o.magnitudes[1] = 0.01;
    o.magnitudes[2] = 0.00005;
    geo_ctx ctx = {.seed = 1};
    geo_inversion_stats s;
    assert_int_equal(geo_inversion_stats_run(p, &o, &ctx, &s, NULL), 0);
    assert_true(s.rows[0].p > 0.5);
    assert_true(s.rows[0].p > s.rows[1].p);
    assert_true(s.rows[1].p >= s.rows[2].p);
    assert_int_equal(s.rows[2].inverted, 0);
    assert_true(s.rows[0].lo <= s.rows[0].p && s.rows[0].p <= s.rows[0].hi);
    geo_inversion_stats_clear(&s);
    geo_poly_free(p);
}

static void test_first_selfint_step_recorded_on_request(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.scan-k100.json");
    assert_non_null(p);
    geo_inversion_opts o;
    small_opts(&o, 4);
    o.nmagnitudes = 1; /* m = 1: most runs self-intersect */
    o.first_selfint = true;
    geo_ctx ctx = {.seed = 1};
    geo_inversion_stats s;
    assert_int_equal(geo_inversion_stats_run(p, &o, &ctx, &s, NULL), 0);
    uint32_t seen = 0;
    for (uint32_t i = 0; i < s.nruns; i++) {
        const geo_inversion_run *r = &s.runs[i];
        if (r->nselfint > 0) {
            assert_true(r->first_selfint_step >= 0);
            assert_true(r->first_selfint_step < r->steps);
            seen++;
        } else {
            assert_true(r->first_selfint_step == -1);
        }
    }
    assert_true(seen > 0);
    geo_inversion_stats_clear(&s);
    geo_poly_free(p);
}

static int cancel_now(void *user, double fraction)
{
    (void)user;
    return fraction >= 0;
}

static void test_bad_options_and_cancel(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("brilliant.truth.json");
    assert_non_null(p);
    geo_inversion_opts o;
    geo_inversion_opts_default(&o);
    geo_inversion_stats s;
    geo_err err = {{0}};
    o.magnitudes[3] = -0.5;
    assert_int_equal(geo_inversion_stats_run(p, &o, NULL, &s, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "magnitudes[3]"));
    geo_inversion_opts_default(&o);
    o.samples = 0;
    assert_int_equal(geo_inversion_stats_run(p, &o, NULL, &s, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "samples"));
    geo_inversion_opts_default(&o);
    o.samples = 3;
    geo_ctx ctx = {.progress = cancel_now};
    assert_int_equal(geo_inversion_stats_run(p, &o, &ctx, &s, &err),
                     -ECANCELED);
    assert_null(s.rows);
    assert_null(s.runs);
    geo_poly_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wilson_interval_known_values),
        cmocka_unit_test(test_result_identical_for_any_thread_count),
        cmocka_unit_test(test_runs_follow_the_sampling_plan),
        cmocka_unit_test(test_probability_falls_with_magnitude_on_a_scan),
        cmocka_unit_test(test_first_selfint_step_recorded_on_request),
        cmocka_unit_test(test_bad_options_and_cancel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
