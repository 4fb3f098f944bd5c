/* test_metrics.c — the Prometheus rendering: counters by route and code,
 * histograms with cumulative buckets ending at +Inf equal to the count,
 * per-op histograms only for ops that ran, the gauges given at scrape
 * time, and the scanner intake's counters. */
#include "testutil.h"

#include <stdlib.h>
#include <string.h>

#include "metrics.h"

static const char *const routes[] = {"/a", "/b/{id}"};

static char *render(metrics *m, const metrics_gauges *g)
{
    char *text;
    size_t len;
    assert_int_equal(metrics_render(m, g, &text, &len), 0);
    assert_int_equal(strlen(text), len);
    return text;
}

static void expect_line(const char *text, const char *line)
{
    const char *p = text;
    size_t n = strlen(line);
    while ((p = strstr(p, line))) {
        if ((p == text || p[-1] == '\n') && (p[n] == '\n'))
            return;
        p += n;
    }
    fail_msg("no line '%s' in:\n%s", line, text);
}

static void test_counters_by_route_and_code(void **state)
{
    (void)state;
    metrics *m = metrics_new(routes, 2);
    metrics_http(m, 0, 200, 10, 100, 0.001);
    metrics_http(m, 0, 200, 10, 100, 0.001);
    metrics_http(m, 1, 404, 0, 50, 0.002);
    metrics_http(m, 7, 418, 0, 5, 0.002); /* unmatched route, other code */
    metrics_gauges g = {0};
    char *t = render(m, &g);
    expect_line(t, "facetd_http_requests_total{route=\"/a\",code=\"200\"} 2");
    expect_line(t, "facetd_http_requests_total{route=\"/b/{id}\",code=\"404\"} 1");
    expect_line(t, "facetd_http_requests_total{route=\"unmatched\",code=\"other\"} 1");
    expect_line(t, "facetd_http_received_bytes_total 20");
    expect_line(t, "facetd_http_sent_bytes_total 255");
    assert_null(strstr(t, "code=\"500\""));
    free(t);
    metrics_free(m);
}

static void test_histograms_are_cumulative(void **state)
{
    (void)state;
    metrics *m = metrics_new(routes, 2);
    metrics_op(m, PROTO_OP_INSPECT, 0.003);
    metrics_op(m, PROTO_OP_INSPECT, 0.2);
    metrics_op(m, PROTO_OP_INSPECT, 5000);
    metrics_job(m, JOB_SUCCEEDED, 0.2);
    metrics_job(m, JOB_FAILED, 1.5);
    metrics_gauges g = {0};
    char *t = render(m, &g);
    expect_line(t, "facetd_op_duration_seconds_bucket{op=\"inspect\",le=\"0.0025\"} 0");
    expect_line(t, "facetd_op_duration_seconds_bucket{op=\"inspect\",le=\"0.005\"} 1");
    expect_line(t, "facetd_op_duration_seconds_bucket{op=\"inspect\",le=\"0.25\"} 2");
    expect_line(t, "facetd_op_duration_seconds_bucket{op=\"inspect\",le=\"1800\"} 2");
    expect_line(t, "facetd_op_duration_seconds_bucket{op=\"inspect\",le=\"+Inf\"} 3");
    expect_line(t, "facetd_op_duration_seconds_count{op=\"inspect\"} 3");
    assert_null(strstr(t, "op=\"cut\""));
    expect_line(t, "facetd_jobs_finished_total{state=\"succeeded\"} 1");
    expect_line(t, "facetd_jobs_finished_total{state=\"failed\"} 1");
    expect_line(t, "facetd_job_duration_seconds_bucket{le=\"+Inf\"} 2");
    expect_line(t, "facetd_job_duration_seconds_sum 1.700000");
    free(t);
    metrics_free(m);
}

static void test_gauges_come_from_the_snapshot(void **state)
{
    (void)state;
    metrics *m = metrics_new(routes, 2);
    metrics_gauges g = {.store_ok = 1, .workers = 4, .busy = 3, .waiters = 9,
                        .queue_size = 100, .ready = 1, .paused = 1};
    g.counts.by_state[JOB_QUEUED] = 12;
    g.counts.file_bytes = 4096;
    metrics_queue_full(m);
    char *t = render(m, &g);
    expect_line(t, "facetd_up 1");
    expect_line(t, "facetd_jobs{state=\"queued\"} 12");
    expect_line(t, "facetd_queue_depth 12");
    expect_line(t, "facetd_store_bytes 4096");
    expect_line(t, "facetd_workers_busy 3");
    expect_line(t, "facetd_workers_paused 1");
    expect_line(t, "facetd_http_waiting_clients 9");
    expect_line(t, "facetd_jobs_rejected_total{reason=\"queue_full\"} 1");
    free(t);
    /* Without store counts the store gauges are left out, not zero. */
    g.store_ok = 0;
    t = render(m, &g);
    assert_null(strstr(t, "facetd_queue_depth"));
    free(t);
    metrics_free(m);
}

static void test_scanner_counters_and_result_latency(void **state)
{
    (void)state;
    metrics *m = metrics_new(routes, 2);
    metrics_gauges g = {0};
    g.scan.enabled = 1;
    g.scan.intake = (scan_metrics){.frames_in = 40, .frames_out = 31,
                                   .crc_errors = 2, .bad_frames = 1,
                                   .seq_errors = 3, .naks_sent = 5,
                                   .naks_received = 1,
                                   .reassembly_failures = 4,
                                   .devices_connected = 2,
                                   .scans_completed = 7, .scans_dropped = 3,
                                   .model_bytes = 123456};
    metrics_scan_refused(m, METRICS_REFUSED_INVALID);
    metrics_scan_result(m, 0.04);
    metrics_scan_result(m, -1); /* not measured: counted, not observed */
    char *t = render(m, &g);
    expect_line(t, "facetd_scanner_intake_up 1");
    expect_line(t, "facetd_scanner_devices_connected 2");
    expect_line(t, "facetd_scanner_frames_total{direction=\"in\"} 40");
    expect_line(t, "facetd_scanner_frames_total{direction=\"out\"} 31");
    expect_line(t, "facetd_scanner_crc_errors_total 2");
    expect_line(t, "facetd_scanner_bad_frames_total 1");
    expect_line(t, "facetd_scanner_sequence_errors_total 3");
    expect_line(t, "facetd_scanner_naks_total{direction=\"sent\"} 5");
    expect_line(t, "facetd_scanner_naks_total{direction=\"received\"} 1");
    expect_line(t, "facetd_scanner_reassembly_failures_total 4");
    expect_line(t, "facetd_scanner_scans_total{outcome=\"completed\"} 7");
    expect_line(t, "facetd_scanner_scans_total{outcome=\"dropped\"} 3");
    expect_line(t, "facetd_scanner_model_bytes_total 123456");
    expect_line(t, "facetd_scanner_scans_refused_total{reason=\"invalid_model\"} 1");
    expect_line(t, "facetd_scanner_scans_refused_total{reason=\"store\"} 0");
    expect_line(t, "facetd_scanner_results_total 2");
    expect_line(t, "facetd_scanner_result_latency_seconds_bucket{le=\"0.025\"} 0");
    expect_line(t, "facetd_scanner_result_latency_seconds_bucket{le=\"0.05\"} 1");
    expect_line(t, "facetd_scanner_result_latency_seconds_count 1");
    free(t);
    metrics_free(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_counters_by_route_and_code),
        cmocka_unit_test(test_histograms_are_cumulative),
        cmocka_unit_test(test_gauges_come_from_the_snapshot),
        cmocka_unit_test(test_scanner_counters_and_result_latency),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
