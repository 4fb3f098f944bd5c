/* test_job_text.c — the job's JSON view written directly as text is byte
 * for byte jansson's compact dump of job_to_json, for every state, for
 * reals that need ".0", exponents and 17 digits, for strings with quotes,
 * backslashes, control characters and UTF-8, and for stored texts that
 * are not JSON (written as strings). */
#include "testutil.h"

#include <jansson.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"

static void check_same(const job_rec *r)
{
    json_t *o = job_to_json(r);
    assert_non_null(o);
    char *want = json_dumps(o, JSON_COMPACT);
    json_decref(o);
    size_t n = 0;
    char *got = job_to_text(r, &n);
    assert_non_null(want);
    assert_non_null(got);
    if (strcmp(want, got) != 0)
        print_error("want %s\ngot  %s\n", want, got);
    assert_string_equal(got, want);
    assert_int_equal(n, strlen(want));
    free(want);
    free(got);
}

static job_rec sample(void)
{
    job_rec r;
    memset(&r, 0, sizeof r);
    strcpy(r.id, "01M80MS1X4340QMBS39DJZ22FD");
    strcpy(r.source, "http");
    r.version = 1;
    return r;
}

static void test_every_state_and_time_matches_jansson(void **state)
{
    (void)state;
    for (int s = 0; s < JOB_NSTATES; s++) {
        job_rec r = sample();
        r.state = (job_state)s;
        r.priority = s % 2 ? JOB_PRIO_HIGH : JOB_PRIO_NORMAL;
        r.created_ms = 1795000000123;
        r.started_ms = s ? 1795000000456 : 0;
        r.finished_ms = s > 1 ? 1795000001789 : 0;
        r.cancel_requested = s == 4;
        r.attempts = s;
        r.version = 3 + s;
        check_same(&r);
    }
}

static void test_reals_match_jansson(void **state)
{
    (void)state;
    static const double values[] = {0, 1, 0.5, 0.1, 1e-5, 2.5e-7,
                                    0.123456789012345678, 1.0 / 3,
                                    0.99999999999999989, 5e-324};
    for (size_t i = 0; i < sizeof values / sizeof values[0]; i++) {
        job_rec r = sample();
        r.progress = values[i];
        check_same(&r);
    }
}

static void test_strings_match_jansson(void **state)
{
    (void)state;
    static const char *const labels[] = {
        "", "plain", "q\"uote", "back\\slash", "tab\tnew\nline\r",
        "ctl\x01\x1f\x7f", "slash/é 中文 😀", "\b\f",
    };
    for (size_t i = 0; i < sizeof labels / sizeof labels[0]; i++) {
        job_rec r = sample();
        strcpy(r.label, labels[i]);
        strcpy(r.source, "usb:SN\"1");
        /* a shared store names the node; the text must carry it the same */
        if (i % 2)
            snprintf(r.node, sizeof r.node, "%s", labels[i]);
        r.state = JOB_FAILED;
        r.error = strdup(labels[i]);
        check_same(&r);
        job_rec_clear(&r);
    }
}

static void test_stored_texts_are_embedded_or_quoted(void **state)
{
    (void)state;
    job_rec r = sample();
    r.state = JOB_SUCCEEDED;
    /* the store keeps what jansson's compact dump wrote (job_submit.c,
     * job_exec.c), so that is what is embedded */
    json_t *pl = json_pack("[{s:s, s:[f,f,f,f]}, {s:s}]", "op", "cut",
                           "plane", 0.0, 0.0, 1.0, -0.5, "op", "inspect");
    json_t *sum = json_pack("{s:b, s:f, s:s, s:[i,f,n,f]}", "valid", 1, "ms",
                            0.098230000730836764, "label", "\x1f\"é",
                            "n", 1, 2.5e-7, 1e300);
    r.pipeline = json_dumps(pl, JSON_COMPACT);
    r.summary = json_dumps(sum, JSON_COMPACT);
    json_decref(pl);
    json_decref(sum);
    check_same(&r);
    free(r.summary);
    r.summary = strdup("not json {");
    check_same(&r);
    free(r.summary);
    r.summary = strdup("{\"a\":1} {\"b\":2}");
    check_same(&r);
    job_rec_clear(&r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_state_and_time_matches_jansson),
        cmocka_unit_test(test_reals_match_jansson),
        cmocka_unit_test(test_strings_match_jansson),
        cmocka_unit_test(test_stored_texts_are_embedded_or_quoted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
