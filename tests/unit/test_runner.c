/* test_runner.c — the pipeline runner: every op has its kernel in the
 * build, inspect runs and reports (stats "before",
 * summary counts and validity), progress rises monotonically to 1 across
 * the ops, and a set cancel flag stops the run with -ECANCELED. */
#include "testutil.h"

#include <errno.h>
#include <stdatomic.h>
#include <string.h>

#include "runner.h"

static proto_pipeline parse(const char *text)
{
    json_t *v = json_loads(text, JSON_DECODE_ANY, NULL);
    assert_non_null(v);
    proto_pipeline p;
    assert_int_equal(proto_pipeline_from_json(v, "pipeline", &p, NULL), 0);
    json_decref(v);
    return p;
}

typedef struct track {
    double last;
    int calls, decreased;
} track;

static int on_progress(void *user, double f)
{
    track *t = user;
    if (f < t->last || f < 0 || f > 1)
        t->decreased++;
    t->last = f;
    t->calls++;
    return 0;
}

static void test_inspect_reports_and_progress_rises(void **state)
{
    (void)state;
    proto_pipeline p = parse("[\"inspect\", \"inspect\"]");
    geo_poly *m = tu_notch_cube();
    track t = {0, 0, 0};
    geo_ctx ctx = {.progress = on_progress, .user = &t};
    json_t *stats, *summary;
    geo_err err = {{0}};
    int r = runner_run(&p, &m, &ctx, NULL, NULL, &stats, &summary, &err);
    if (r < 0)
        fail_msg("%s", err.msg);
    assert_int_equal(t.decreased, 0);
    assert_true(t.calls >= 3);
    assert_true(t.last == 1.0);
    json_t *ops = json_object_get(stats, "ops");
    assert_int_equal(json_array_size(ops), 2);
    assert_string_equal(json_string_value(json_object_get(
                            json_array_get(ops, 0), "op")), "inspect");
    json_t *before = json_object_get(stats, "before");
    assert_true(json_is_object(before));
    assert_int_equal(json_integer_value(json_object_get(before, "facets")),
                     m->nfacets);
    /* Inspect changes nothing, so there is no "after". */
    assert_true(json_is_null(json_object_get(stats, "after")));
    assert_int_equal(json_integer_value(json_object_get(summary,
                                                        "facets_before")),
                     m->nfacets);
    assert_true(json_is_true(json_object_get(summary, "valid")));
    assert_string_equal(json_string_value(json_object_get(summary,
                                                          "orientation")),
                        "outward");
    json_decref(stats);
    json_decref(summary);
    geo_poly_free(m);
    proto_pipeline_free(&p);
}

static void test_cancel_flag_stops_the_run(void **state)
{
    (void)state;
    proto_pipeline p = parse("[\"inspect\"]");
    geo_poly *m = tu_notch_cube();
    atomic_int cancel = 1;
    geo_ctx ctx = {.cancel = &cancel};
    json_t *stats = NULL, *summary = NULL;
    geo_err err = {{0}};
    assert_int_equal(runner_run(&p, &m, &ctx, NULL, NULL, &stats, &summary,
                                &err), -ECANCELED);
    assert_null(stats);
    assert_non_null(m);
    geo_poly_free(m);
    proto_pipeline_free(&p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_inspect_reports_and_progress_rises),
        cmocka_unit_test(test_cancel_flag_stops_the_run),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
