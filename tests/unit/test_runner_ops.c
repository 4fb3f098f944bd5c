/* test_runner_ops.c — the kernels wired into the runner's op table: cut
 * (lib/cut/cut.h), move_vertex (lib/replanar/replanar.h) and inversion_stats
 * (lib/replanar/inversion.h). Each replaces or keeps the model as it should,
 * reports in the stats, names its place on errors, and inversion_stats
 * gives the same report with and without a thread pool. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model_io.h"
#include "parallel.h"
#include "runner.h"
#include "tu_load.h"

static proto_pipeline parse(const char *text)
{
    json_t *v = json_loads(text, JSON_DECODE_ANY, NULL);
    assert_non_null(v);
    proto_pipeline p;
    geo_err err = {{0}};
    if (proto_pipeline_from_json(v, "pipeline", &p, &err) < 0)
        fail_msg("%s", err.msg);
    json_decref(v);
    return p;
}

/* Runs text on *m; returns the result code, stats in *ret_stats. */
static int run(const char *text, geo_poly **m, const geo_ctx *ctx,
               json_t **ret_stats, geo_err *err)
{
    proto_pipeline p = parse(text);
    json_t *summary = NULL;
    *ret_stats = NULL;
    int r = runner_run(&p, m, ctx, NULL, NULL, ret_stats, &summary, err);
    json_decref(summary);
    proto_pipeline_free(&p);
    return r;
}

static json_t *report(json_t *stats, size_t i)
{
    return json_object_get(json_array_get(json_object_get(stats, "ops"), i),
                           "report");
}

static double num(json_t *o, const char *key)
{
    json_t *v = json_object_get(o, key);
    assert_true(json_is_number(v));
    return json_number_value(v);
}

static void test_cut_keeps_the_lower_half_and_reports(void **state)
{
    (void)state;
    geo_poly *m = tu_box((double[]){0, 0, 0}, (double[]){2, 2, 2});
    json_t *stats;
    geo_err err = {{0}};
    int r = run("[\"inspect\", {\"op\":\"cut\",\"plane\":[0,0,2,-2]}, "
                "\"inspect\"]", &m, NULL, &stats, &err);
    if (r < 0)
        fail_msg("%s", err.msg);
    json_t *rep = report(stats, 1);
    assert_true(num(rep, "components") == 1);
    assert_true(num(rep, "new_facets") == 1);
    assert_true(num(rep, "split_facets") == 4);
    assert_true(num(rep, "volume_before") == 8);
    assert_true(fabs(num(rep, "volume_after") - 4) < 1e-12);
    assert_true(json_is_false(json_object_get(rep, "empty")));
    /* the plane is reported normalised */
    json_t *pl = json_object_get(rep, "plane");
    assert_true(json_number_value(json_array_get(pl, 2)) == 1);
    assert_true(json_number_value(json_array_get(pl, 3)) == -1);
    assert_int_equal(m->nfacets, 6);
    assert_true(fabs(geo_poly_volume(m) - 4) < 1e-12);
    /* the model changed, so the second inspect is "after" */
    json_t *after = json_object_get(stats, "after");
    assert_true(json_is_object(after));
    assert_true(json_is_true(json_object_get(after, "valid")));
    json_decref(stats);

    /* a plane above everything keeps the model; one below empties it */
    assert_int_equal(run("[{\"op\":\"cut\",\"plane\":[0,0,1,-10]}]", &m, NULL,
                         &stats, &err), 0);
    assert_true(json_is_true(json_object_get(report(stats, 0), "unchanged")));
    assert_int_equal(m->nfacets, 6);
    json_decref(stats);
    assert_int_equal(run("[{\"op\":\"cut\",\"plane\":[0,0,1,10]}]", &m, NULL,
                         &stats, &err), 0);
    assert_true(json_is_true(json_object_get(report(stats, 0), "empty")));
    assert_int_equal(m->nfacets, 0);
    json_decref(stats);
    geo_poly_free(m);
}

static void test_cut_of_an_open_model_fails_naming_the_op(void **state)
{
    (void)state;
    geo_poly *m = tu_box((double[]){0, 0, 0}, (double[]){1, 1, 1});
    m->nfacets--; /* drop the last facet: the box is open */
    json_t *stats;
    geo_err err = {{0}};
    assert_int_equal(run("[\"inspect\", {\"op\":\"cut\",\"plane\":[0,0,1,-0.5]}]",
                         &m, NULL, &stats, &err), -EINVAL);
    assert_null(stats);
    assert_non_null(strstr(err.msg, "pipeline[1] (cut): "));
    geo_poly_free(m);
}

static void test_move_vertex_places_it_and_logs_the_run(void **state)
{
    (void)state;
    geo_poly *m = tu_load_model("brilliant.truth.json");
    double start[3];
    memcpy(start, m->verts[100], sizeof start);
    json_t *stats;
    geo_err err = {{0}};
    int r = run("[\"inspect\", {\"op\":\"move\",\"vertex\":100,"
                "\"by\":[1e-6,-1e-6,5e-7]}, \"inspect\"]", &m, NULL, &stats,
                &err);
    if (r < 0)
        fail_msg("%s", err.msg);
    assert_true(m->verts[100][0] == start[0] + 1e-6);
    assert_true(m->verts[100][1] == start[1] + -1e-6);
    assert_true(m->verts[100][2] == start[2] + 5e-7);
    json_t *rep = report(stats, 1);
    assert_true(num(rep, "vertex") == 100);
    json_t *res = json_object_get(rep, "result");
    assert_true(json_is_true(json_object_get(res, "converged")));
    assert_true(json_is_true(json_object_get(res, "valid")));
    assert_string_equal(json_string_value(json_object_get(res, "schedule")),
                        "least-norm");
    json_t *log = json_object_get(rep, "log");
    assert_true(json_array_size(log) == num(res, "steps"));
    assert_true(json_array_size(log) > 0);
    json_t *after = json_object_get(stats, "after");
    assert_true(json_is_true(json_object_get(after, "valid")));
    json_decref(stats);
    geo_poly_free(m);
}

static void test_move_vertex_errors_name_the_op(void **state)
{
    (void)state;
    geo_poly *m = tu_load_model("brilliant.truth.json");
    json_t *stats;
    geo_err err = {{0}};
    assert_int_equal(run("[{\"op\":\"move\",\"vertex\":9999,"
                         "\"to\":[0,0,0]}]", &m, NULL, &stats, &err),
                     -EINVAL);
    assert_string_equal(err.msg, "pipeline[0] (move): vertex: 9999 "
                                 "out of range (238 vertices)");
    /* two steps cannot converge: the result is refused, not passed on */
    assert_int_equal(run("[\"inspect\", {\"op\":\"move\",\"vertex\":5,"
                         "\"by\":[0.01,0,0],\"max_steps\":2}]", &m, NULL,
                         &stats, &err), -EINVAL);
    assert_null(stats);
    assert_non_null(strstr(err.msg, "pipeline[1] (move): moving "
                                    "vertex 5 does not give a valid "
                                    "polyhedron (no convergence after 2 "
                                    "steps"));
    geo_poly_free(m);
}

static void test_inversion_stats_reads_only_and_ignores_threads(void **state)
{
    (void)state;
    const char *pl = "[{\"op\":\"inversion_stats\",\"samples\":4,"
                     "\"magnitudes\":[1,0.0001],\"seed\":7,"
                     "\"schedule\":\"scaled\"}, \"inspect\"]";
    proto_pipeline p = parse(pl);
    assert_false(runner_changes_model(&p));
    proto_pipeline_free(&p);
    char *dumps[2];
    par_pool *pool = par_pool_new(3);
    assert_non_null(pool);
    for (int t = 0; t < 2; t++) {
        geo_poly *m = tu_load_model("brilliant.truth.json");
        geo_ctx ctx = {.parallel_for = t ? par_for : NULL, .pf_user = pool,
                       .seed = 99};
        json_t *stats;
        geo_err err = {{0}};
        if (run(pl, &m, &ctx, &stats, &err) < 0)
            fail_msg("%s", err.msg);
        json_t *rep = report(stats, 0);
        assert_true(num(rep, "samples") == 4);
        assert_true(num(rep, "seed") == 7);
        json_t *table = json_object_get(rep, "table");
        assert_int_equal(json_array_size(table), 2);
        assert_true(num(json_array_get(table, 0), "runs") == 4);
        assert_true(num(json_array_get(table, 1), "m") == 0.0001);
        /* read-only: no "after" */
        assert_true(json_is_null(json_object_get(stats, "after")));
        dumps[t] = json_dumps(rep, JSON_COMPACT | JSON_SORT_KEYS);
        json_decref(stats);
        geo_poly_free(m);
    }
    assert_string_equal(dumps[0], dumps[1]);
    free(dumps[0]);
    free(dumps[1]);
    par_pool_free(pool);
}

static void test_changes_model_follows_the_ops(void **state)
{
    (void)state;
    static const struct {
        const char *pipeline;
        bool changes;
    } cases[] = {
        {"[\"inspect\"]", false},
        {"[\"inspect\", \"inversion_stats\"]", false},
        {"[\"inspect\", {\"op\":\"cut\",\"plane\":[0,0,1,0]}]", true},
        {"[{\"op\":\"move\",\"vertex\":0,\"to\":[0,0,0]}]", true},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        proto_pipeline p = parse(cases[i].pipeline);
        assert_int_equal(runner_changes_model(&p), cases[i].changes);
        proto_pipeline_free(&p);
    }
}

/* report reads the stone: the truth brilliant's proportions in the op's
 * report, the model untouched; a model without a table (the notch cube)
 * is reported as such without failing the run; with an axis it is
 * measured along it. */
static void test_report_gives_the_proportions(void **state)
{
    (void)state;
    geo_poly *m = tu_load_model("brilliant.truth.json");
    uint32_t nf = m->nfacets;
    json_t *stats;
    geo_err err = {{0}};
    assert_int_equal(run("[{\"op\":\"report\",\"gear\":64}]", &m, NULL,
                         &stats, &err), 0);
    json_t *r = report(stats, 0);
    assert_true(json_is_true(json_object_get(r, "table")));
    double t = num(r, "table_percent");
    assert_true(t > 40 && t < 75);
    double c = num(r, "crown_angle_deg"), pv = num(r, "pavilion_angle_deg");
    assert_true(c > 20 && c < 45 && pv > 35 && pv < 48);
    assert_int_equal(json_array_size(json_object_get(r, "facets")), nf);
    assert_int_equal(m->nfacets, nf);
    json_decref(stats);
    geo_poly_free(m);

    /* a tetrahedron standing on a face: no facet faces up */
    static const char tetra[] =
        "{\"format\":\"facet-model/1\",\"vertices\":[[1,0,0],"
        "[-0.5,0.8660254037844386,0],[-0.5,-0.8660254037844386,0],"
        "[0,0,1.4142135623730951]],\"facets\":[{\"vertices\":[0,2,1]},"
        "{\"vertices\":[0,1,3]},{\"vertices\":[1,2,3]},"
        "{\"vertices\":[2,0,3]}]}";
    m = proto_model_read_mem(tetra, sizeof tetra - 1, PROTO_FMT_JSON, NULL,
                             &err);
    assert_non_null(m);
    assert_int_equal(run("[\"report\"]", &m, NULL, &stats, &err), 0);
    r = report(stats, 0);
    assert_true(json_is_false(json_object_get(r, "table")));
    assert_non_null(strstr(json_string_value(json_object_get(r, "reason")),
                           "table"));
    json_decref(stats);
    assert_int_equal(run("[{\"op\":\"report\",\"axis\":[0,0,1]}]", &m,
                         NULL, &stats, &err), 0);
    assert_non_null(json_object_get(report(stats, 0), "facets"));
    json_decref(stats);
    geo_poly_free(m);
}

/* report with scan measures the result against the model as submitted:
 * after a correction of the k400 scan every facet of the result has a
 * deviation of a few µm (the scan's noise and slivers); without scan the
 * facets carry none. */
static void test_report_scan_measures_against_the_input(void **state)
{
    (void)state;
    geo_poly *m = tu_load_model("brilliant.scan-k400.json");
    json_t *stats;
    geo_err err = {{0}};
    if (run("[\"correct\", {\"op\":\"report\",\"scan\":true}, \"report\"]",
            &m, NULL, &stats, &err) != 0)
        fail_msg("%s", err.msg);
    json_t *fs = json_object_get(report(stats, 1), "facets");
    assert_int_equal(json_array_size(fs), m->nfacets);
    double worst = 0;
    size_t measured = 0, i;
    json_t *f;
    json_array_foreach(fs, i, f) {
        json_t *d = json_object_get(f, "scan_deviation_um");
        assert_non_null(d);
        if (json_is_null(d))
            continue;
        measured++;
        double mx = num(d, "max"), rms = num(d, "rms");
        assert_true(rms >= 0 && rms <= mx);
        worst = mx > worst ? mx : worst;
    }
    /* the raw scan lies within a few µm of its correction */
    assert_true(measured > m->nfacets / 2);
    assert_true(worst > 0.1 && worst < 20);
    json_t *plain = json_array_get(json_object_get(report(stats, 2), "facets"), 0);
    assert_null(json_object_get(plain, "scan_deviation_um"));
    json_decref(stats);
    geo_poly_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cut_keeps_the_lower_half_and_reports),
        cmocka_unit_test(test_cut_of_an_open_model_fails_naming_the_op),
        cmocka_unit_test(test_move_vertex_places_it_and_logs_the_run),
        cmocka_unit_test(test_move_vertex_errors_name_the_op),
        cmocka_unit_test(test_inversion_stats_reads_only_and_ignores_threads),
        cmocka_unit_test(test_changes_model_follows_the_ops),
        cmocka_unit_test(test_report_gives_the_proportions),
        cmocka_unit_test(test_report_scan_measures_against_the_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
