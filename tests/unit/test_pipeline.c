/* test_pipeline.c — the job pipeline parser accepts both op forms and
 * "correct", fills defaults, rejects unknown ops and parameters and bad
 * values with messages naming the place, and its canonical JSON parses
 * back to the same pipeline. */
#include "testutil.h"

#include <errno.h>
#include <string.h>

#include "pipeline.h"

static int parse(const char *text, proto_pipeline *p, geo_err *err)
{
    json_error_t je;
    json_t *v = json_loads(text, JSON_DECODE_ANY, &je);
    if (!v)
        fail_msg("test JSON: %s", je.text);
    int r = proto_pipeline_from_json(v, "pipeline", p, err);
    json_decref(v);
    return r;
}

static void expect_error(const char *text, const char *msg)
{
    proto_pipeline p = {0};
    geo_err err = {{0}};
    assert_int_equal(parse(text, &p, &err), -EINVAL);
    if (strcmp(err.msg, msg) != 0)
        fail_msg("expected '%s', got '%s'", msg, err.msg);
    assert_null(p.ops);
}

static void test_names_and_objects_parse_with_defaults(void **state)
{
    (void)state;
    proto_pipeline p;
    geo_err err = {{0}};
    assert_int_equal(parse("[\"inspect\", {\"op\":\"merge\","
                           "\"max_angle_deg\":0.5}, {\"op\":\"collapse\"}]",
                           &p, &err), 0);
    assert_int_equal(p.nops, 3);
    assert_int_equal(p.ops[0].kind, PROTO_OP_INSPECT);
    assert_int_equal(p.ops[1].kind, PROTO_OP_MERGE);
    assert_true(p.ops[1].u.merge.max_angle_deg == 0.5);
    /* 0: relative to the model's size (lib/correct/merge.h, lib/correct/clusters.h) */
    assert_true(p.ops[1].u.merge.max_deviation == 0);
    assert_int_equal(p.ops[1].u.merge.ngroups, 0);
    assert_true(p.ops[2].u.collapse.radius == 0);
    proto_pipeline_free(&p);
}

static void test_correct_is_the_post_scan_correction(void **state)
{
    (void)state;
    proto_pipeline p;
    assert_int_equal(parse("\"correct\"", &p, NULL), 0);
    assert_int_equal(p.nops, 3);
    proto_op_kind want[] = {PROTO_OP_INSPECT, PROTO_OP_CORRECT, PROTO_OP_INSPECT};
    for (int i = 0; i < 3; i++)
        assert_int_equal(p.ops[i].kind, want[i]);
    assert_true(p.ops[1].u.correct.max_angle_deg == 60);
    proto_pipeline_free(&p);
}

/* The names of the last release still parse, to the current op, and are
 * reported once each; the canonical JSON has the current names. */
static void test_deprecated_names_are_aliases(void **state)
{
    (void)state;
    static const struct {
        const char *old, *now;
    } names[] = {{"auto", "correct"}, {"merge_facets", "merge"},
                 {"fill_holes", "fill"}, {"move_vertex", "move"},
                 {"collapse_clusters", "collapse"},
                 {"inversion-stats", "inversion_stats"}};
    for (size_t i = 0; i < sizeof names / sizeof *names; i++)
        assert_string_equal(proto_op_canonical(names[i].old), names[i].now);
    assert_string_equal(proto_op_canonical("merge"), "merge");
    assert_null(proto_op_canonical("flatten"));
    proto_pipeline p;
    assert_int_equal(parse("[\"inspect\", \"merge_facets\", {\"op\":\"fill_holes\"}, "
                           "\"merge_facets\"]", &p, NULL), 0);
    assert_int_equal(p.ops[1].kind, PROTO_OP_MERGE);
    assert_int_equal(p.ops[2].kind, PROTO_OP_FILL);
    char msg[256];
    assert_int_equal(proto_pipeline_deprecations(&p, msg, sizeof msg), 2);
    assert_string_equal(msg, "op 'merge_facets' is deprecated: use 'merge'; "
                             "op 'fill_holes' is deprecated: use 'fill'");
    json_t *j = proto_pipeline_to_json(&p);
    char *text = json_dumps(j, JSON_COMPACT);
    assert_non_null(strstr(text, "{\"op\":\"merge\","));
    assert_null(strstr(text, "merge_facets"));
    free(text);
    json_decref(j);
    proto_pipeline_free(&p);
    assert_int_equal(parse("\"auto\"", &p, NULL), 0);
    assert_int_equal(p.ops[1].kind, PROTO_OP_CORRECT);
    assert_int_equal(proto_pipeline_deprecations(&p, msg, sizeof msg), 1);
    assert_string_equal(msg, "op 'auto' is deprecated: use 'correct'");
    proto_pipeline_free(&p);
    assert_int_equal(parse("\"correct\"", &p, NULL), 0);
    assert_int_equal(proto_pipeline_deprecations(&p, msg, sizeof msg), 0);
    assert_string_equal(msg, "");
    proto_pipeline_free(&p);
}

static void test_errors_name_the_place(void **state)
{
    (void)state;
    expect_error("[{\"op\":\"report\",\"gear\":0}]",
                 "pipeline[0].gear: 0 out of range [1, 100000]");
    expect_error("[{\"op\":\"report\",\"axis\":[0,0,0]}]",
                 "pipeline[0].axis: must be a non-zero vector");
    expect_error("[{\"op\":\"report\",\"scan\":1}]",
                 "pipeline[0].scan: expected true or false");
    expect_error("[{\"op\":\"report\",\"deviation\":true}]",
                 "pipeline[0].deviation: unknown parameter of report");
    expect_error("[\"inspect\", \"inspect\", {\"op\":\"merge\","
                 "\"max_angle_deg\":\"1\"}]",
                 "pipeline[2].max_angle_deg: expected a number");
    expect_error("[\"flatten\"]", "pipeline[0]: unknown operation 'flatten'");
    /* a bare name still needs what the op requires (found by fuzzing:
     * ["cut"] was accepted with a zero plane its canonical form refused) */
    expect_error("[\"cut\"]", "pipeline[0].plane: required");
    expect_error("[\"inspect\", \"move\"]", "pipeline[1].vertex: required");
    expect_error("[\"compare\"]", "pipeline[0].reference: required (the "
                 "facet-model/1 to compare the job's model with)");
    expect_error("[{\"op\":\"cut\",\"plane\":[0,0,1,0],\"keep\":1}]",
                 "pipeline[0].keep: unknown parameter of cut");
    expect_error("[{\"op\":\"cut\"}]", "pipeline[0].plane: required");
    expect_error("[{\"op\":\"cut\",\"plane\":[0,0,0,1]}]",
                 "pipeline[0].plane: normal (a, b, c) must be non-zero "
                 "with a finite length");
    expect_error("[{\"op\":\"cut\",\"plane\":[0,0,1]}]",
                 "pipeline[0].plane: expected an array of 4 numbers");
    expect_error("[{\"op\":\"move\",\"vertex\":3,\"to\":[0,0,0],"
                 "\"by\":[1,0,0]}]",
                 "pipeline[0]: exactly one of \"to\" and \"by\" is required");
    expect_error("[{\"op\":\"move\",\"vertex\":-1,\"to\":[0,0,0]}]",
                 "pipeline[0].vertex: -1 out of range [0, 4294967294]");
    expect_error("[{\"op\":\"move\",\"vertex\":1,\"to\":[0,0,0],"
                 "\"schedule\":\"fast\"}]",
                 "pipeline[0].schedule: expected one of \"local-exp\", "
                 "\"scaled\", \"global-exp\", \"least-norm\"");
    expect_error("[{\"op\":\"merge\",\"groups\":[[1]]}]",
                 "pipeline[0].groups[0]: expected an array of at least 2 "
                 "facet indices");
    expect_error("[{\"op\":\"merge\",\"max_angle_deg\":0}]",
                 "pipeline[0].max_angle_deg: 0 out of range (0, 90]");
    expect_error("[{\"op\":\"inversion_stats\",\"magnitudes\":[1,0]}]",
                 "pipeline[0].magnitudes[1]: expected a positive number");
    expect_error("[{\"op\":\"triangulate\",\"quad_levels\":12}]",
                 "pipeline[0].quad_levels: 12 out of range [1, 11]");
    expect_error("[{\"op\":\"triangulate\",\"fair\":true}]",
                 "pipeline[0].fair: expected one of \"none\", \"uniform\", "
                 "\"length\"");
    expect_error("[{\"op\":\"fill\",\"refine\":\"yes\"}]",
                 "pipeline[0].refine: expected true or false");
    expect_error("[{\"radius\":1}]",
                 "pipeline[0].op: required (the operation's name)");
    expect_error("[]", "pipeline: expected at least one operation");
    expect_error("\"manual\"",
                 "pipeline: expected an array of operations or \"correct\"");
    expect_error("[42]", "pipeline[0]: expected an operation name or object");
}

static void test_cut_plane_is_normalised(void **state)
{
    (void)state;
    proto_pipeline p;
    assert_int_equal(parse("[{\"op\":\"cut\",\"plane\":[0,0,2,-1]}]", &p, NULL), 0);
    assert_true(p.ops[0].u.cut.plane[2] == 1.0);
    assert_true(p.ops[0].u.cut.plane[3] == -0.5);
    proto_pipeline_free(&p);
}

/* Normalising [1,0,1,-0.5] rounds, and normalising the result again
 * rounded once more: the plane a worker read back from the stored
 * canonical JSON was not the one validated. */
static void test_cut_plane_survives_the_round_trip(void **state)
{
    (void)state;
    proto_pipeline p, q;
    assert_int_equal(parse("[{\"op\":\"cut\",\"plane\":[1,0,1,-0.5]}]", &p, NULL), 0);
    json_t *canon = proto_pipeline_to_json(&p);
    geo_err err = {{0}};
    assert_int_equal(proto_pipeline_from_json(canon, "pipeline", &q, &err), 0);
    assert_memory_equal(q.ops[0].u.cut.plane, p.ops[0].u.cut.plane,
                        sizeof p.ops[0].u.cut.plane);
    json_decref(canon);
    proto_pipeline_free(&q);
    proto_pipeline_free(&p);
}

static void test_canonical_json_round_trips(void **state)
{
    (void)state;
    const char *text =
        "[\"inspect\", {\"op\":\"merge\",\"groups\":[[1,2],[5,6,7]]},"
        "{\"op\":\"move\",\"vertex\":4,\"by\":[0.1,0,0],"
        "\"schedule\":\"scaled\",\"max_steps\":50},"
        "{\"op\":\"inversion_stats\",\"samples\":10,\"magnitudes\":[1,0.1],"
        "\"seed\":7}, {\"op\":\"triangulate\",\"fair\":\"none\","
        "\"fill\":\"edges\"},"
        "{\"op\":\"fill\",\"weight\":\"length\"}, \"stitch\","
        "{\"op\":\"cut\",\"plane\":[1,0,0,0.25]},"
        "{\"op\":\"collapse\",\"radius\":0.01}]";
    proto_pipeline a, b;
    assert_int_equal(parse(text, &a, NULL), 0);
    json_t *j = proto_pipeline_to_json(&a);
    assert_non_null(j);
    char *canon = json_dumps(j, JSON_COMPACT);
    assert_int_equal(proto_pipeline_from_json(j, "pipeline", &b, NULL), 0);
    json_t *j2 = proto_pipeline_to_json(&b);
    char *canon2 = json_dumps(j2, JSON_COMPACT);
    assert_string_equal(canon, canon2);
    assert_int_equal(b.ops[1].u.merge.ngroups, 2);
    assert_int_equal(b.ops[1].u.merge.gfacets[4], 7);
    assert_true(b.ops[2].u.move.relative);
    assert_int_equal(b.ops[2].u.move.schedule, PROTO_SCHED_SCALED);
    assert_int_equal(b.ops[3].u.inversion.nmagnitudes, 2);
    assert_int_equal(b.ops[3].u.inversion.seed, 7);
    assert_int_equal(b.ops[4].u.triangulate.fair, PROTO_FAIR_NONE);
    assert_true(b.ops[4].u.triangulate.fill_edges);
    assert_true(b.ops[4].u.triangulate.sharpen);
    assert_int_equal(b.ops[4].u.triangulate.quad_levels, 9);
    assert_true(b.ops[5].u.fill.weight_length);
    free(canon);
    free(canon2);
    json_decref(j);
    json_decref(j2);
    proto_pipeline_free(&a);
    proto_pipeline_free(&b);
}

/* compare carries its reference model: read with its place in errors,
 * refused without a table unless an axis is given, and written back in
 * the canonical JSON so that the stored pipeline runs the same. */
static void test_compare_carries_its_reference(void **state)
{
    (void)state;
    static const char tetra[] =
        "{\"format\":\"facet-model/1\",\"vertices\":[[1,0,0],"
        "[-0.5,0.8660254037844386,0],[-0.5,-0.8660254037844386,0],"
        "[0,0,1.4142135623730951]],\"facets\":[{\"vertices\":[0,2,1]},"
        "{\"vertices\":[0,1,3]},{\"vertices\":[1,2,3]},"
        "{\"vertices\":[2,0,3]}]}";
    char text[1024];
    snprintf(text, sizeof text, "[{\"op\":\"compare\",\"axis\":[0,0,-1],"
             "\"reference\":%s}]", tetra);
    proto_pipeline a, b;
    geo_err err = {{0}};
    assert_int_equal(parse(text, &a, &err), 0);
    assert_int_equal(a.ops[0].kind, PROTO_OP_COMPARE);
    assert_int_equal(a.ops[0].u.compare.reference->nfacets, 4);
    json_t *j = proto_pipeline_to_json(&a);
    char *canon = json_dumps(j, JSON_COMPACT);
    assert_int_equal(proto_pipeline_from_json(j, "pipeline", &b, &err), 0);
    json_t *j2 = proto_pipeline_to_json(&b);
    char *canon2 = json_dumps(j2, JSON_COMPACT);
    assert_string_equal(canon, canon2);
    assert_memory_equal(b.ops[0].u.compare.reference->verts,
                        a.ops[0].u.compare.reference->verts,
                        4 * sizeof(double[3]));
    free(canon);
    free(canon2);
    json_decref(j);
    json_decref(j2);
    proto_pipeline_free(&a);
    proto_pipeline_free(&b);

    snprintf(text, sizeof text, "[\"inspect\", {\"op\":\"compare\","
             "\"reference\":%s}]", tetra);
    assert_int_equal(parse(text, &a, &err), -EINVAL);
    if (strncmp(err.msg, "pipeline[1].reference: no table", 31) != 0)
        fail_msg("got '%s'", err.msg);
    expect_error("[{\"op\":\"compare\"}]",
                 "pipeline[0].reference: required (the facet-model/1 to "
                 "compare the job's model with)");
    expect_error("[{\"op\":\"compare\",\"reference\":{\"format\":"
                 "\"facet-model/1\",\"vertices\":[[0,0,0],[1,0,0],[0,1,0]],"
                 "\"facets\":[{\"vertices\":[0,1,5]}]}}]",
                 "pipeline[0].reference.facets[0].vertices[2]: index 5 out "
                 "of range (3 vertices)");
}

/* A scanner job's pipeline carries the scan's contour count to every op
 * that would otherwise read the view step off the model; an explicit
 * "views" stays as given, and the copy leaves the original untouched. */
static void test_views_are_set_on_a_copy_for_scanner_jobs(void **state)
{
    (void)state;
    proto_pipeline p, q;
    geo_err err = {{0}};
    assert_int_equal(parse("[\"inspect\", \"correct\", {\"op\":\"merge\","
                           "\"views\":250}, \"merge\"]", &p, &err), 0);
    assert_int_equal(p.ops[1].u.correct.views, 0);
    assert_int_equal(p.ops[2].u.merge.views, 250);
    assert_int_equal(proto_pipeline_copy(&p, &q), 0);
    proto_pipeline_set_views(&q, 400);
    assert_int_equal(q.ops[1].u.correct.views, 400);
    assert_int_equal(q.ops[2].u.merge.views, 250);
    assert_int_equal(q.ops[3].u.merge.views, 400);
    assert_int_equal(p.ops[1].u.correct.views, 0);
    assert_int_equal(p.ops[3].u.merge.views, 0);
    proto_pipeline_free(&q);
    proto_pipeline_free(&p);
    expect_error("[{\"op\":\"correct\",\"views\":-1}]",
                 "pipeline[0].views: -1 out of range [0, 100000]");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names_and_objects_parse_with_defaults),
        cmocka_unit_test(test_correct_is_the_post_scan_correction),
        cmocka_unit_test(test_deprecated_names_are_aliases),
        cmocka_unit_test(test_errors_name_the_place),
        cmocka_unit_test(test_cut_plane_is_normalised),
        cmocka_unit_test(test_cut_plane_survives_the_round_trip),
        cmocka_unit_test(test_canonical_json_round_trips),
        cmocka_unit_test(test_compare_carries_its_reference),
        cmocka_unit_test(test_views_are_set_on_a_copy_for_scanner_jobs),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
