/* metrics.c — atomic counters and fixed-bucket histograms (metrics.h).
 * Invariant: a histogram's bucket counts are per bucket (not cumulative)
 * and made cumulative while rendering, so one observation is one atomic
 * add to one bucket plus the count and the sum (in microseconds). */
#include "metrics.h"

#include <errno.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const unsigned codes[] = {200, 201, 202, 204, 304, 400, 401, 403,
                                 404, 405, 406, 409, 410, 413, 415, 422,
                                 429, 500, 503};
enum { NCODES = sizeof codes / sizeof codes[0] + 1 }; /* + "other" */

static const double bounds[] = {0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025,
                                0.05,   0.1,   0.25,   0.5,   1,    2.5,
                                5,      10,    30,     60,    300,  1800};
enum { NB = sizeof bounds / sizeof bounds[0] + 1 }; /* + "+Inf" */

typedef struct hist {
    atomic_uint_fast64_t bucket[NB];
    atomic_uint_fast64_t count;
    atomic_uint_fast64_t sum_us;
} hist;

struct metrics {
    const char *const *routes;
    unsigned nroutes;                 /* + 1 "unmatched" slot */
    atomic_uint_fast64_t *requests;   /* [(nroutes+1) * NCODES] */
    hist *req_time;                   /* [nroutes+1] */
    atomic_uint_fast64_t bytes_in, bytes_out;
    atomic_uint_fast64_t jobs[JOB_NSTATES];
    atomic_uint_fast64_t queue_full;
    hist job_time;
    hist op_time[PROTO_OP_COUNT];
    atomic_uint_fast64_t scan_refused[METRICS_NREFUSALS];
    atomic_uint_fast64_t scan_results;
    hist scan_result_time;
};

metrics *metrics_new(const char *const *route_names, unsigned nroutes)
{
    metrics *m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    m->routes = route_names;
    m->nroutes = nroutes;
    m->requests = calloc((size_t)(nroutes + 1) * NCODES, sizeof *m->requests);
    m->req_time = calloc(nroutes + 1, sizeof *m->req_time);
    if (!m->requests || !m->req_time)
        return metrics_free(m);
    return m;
}

metrics *metrics_free(metrics *m)
{
    if (m) {
        free(m->requests);
        free(m->req_time);
        free(m);
    }
    return NULL;
}

static void observe(hist *h, double seconds)
{
    if (!(seconds >= 0))
        seconds = 0;
    unsigned b = 0;
    while (b < NB - 1 && seconds > bounds[b])
        b++;
    atomic_fetch_add_explicit(&h->bucket[b], 1, memory_order_relaxed);
    atomic_fetch_add_explicit(&h->count, 1, memory_order_relaxed);
    atomic_fetch_add_explicit(&h->sum_us, (uint64_t)(seconds * 1e6),
                              memory_order_relaxed);
}

void metrics_http(metrics *m, unsigned route, unsigned code,
                  uint64_t bytes_in, uint64_t bytes_out, double seconds)
{
    if (route > m->nroutes)
        route = m->nroutes;
    unsigned c = NCODES - 1;
    for (unsigned i = 0; i < NCODES - 1; i++)
        if (codes[i] == code)
            c = i;
    atomic_fetch_add_explicit(&m->requests[route * NCODES + c], 1,
                              memory_order_relaxed);
    atomic_fetch_add_explicit(&m->bytes_in, bytes_in, memory_order_relaxed);
    atomic_fetch_add_explicit(&m->bytes_out, bytes_out, memory_order_relaxed);
    observe(&m->req_time[route], seconds);
}

void metrics_job(metrics *m, job_state st, double seconds)
{
    if ((unsigned)st < JOB_NSTATES)
        atomic_fetch_add_explicit(&m->jobs[st], 1, memory_order_relaxed);
    observe(&m->job_time, seconds);
}

void metrics_op(metrics *m, proto_op_kind op, double seconds)
{
    if ((unsigned)op < PROTO_OP_COUNT)
        observe(&m->op_time[op], seconds);
}

void metrics_queue_full(metrics *m)
{
    atomic_fetch_add_explicit(&m->queue_full, 1, memory_order_relaxed);
}

void metrics_scan_refused(metrics *m, metrics_refusal why)
{
    if (m && (unsigned)why < METRICS_NREFUSALS)
        atomic_fetch_add_explicit(&m->scan_refused[why], 1,
                                  memory_order_relaxed);
}

void metrics_scan_result(metrics *m, double seconds)
{
    if (!m)
        return;
    atomic_fetch_add_explicit(&m->scan_results, 1, memory_order_relaxed);
    if (seconds >= 0)
        observe(&m->scan_result_time, seconds);
}

/* A growing output buffer; on out-of-memory it stays failed. */
typedef struct out {
    char *buf;
    size_t len, cap;
    int failed;
} out;

__attribute__((format(printf, 2, 3)))
static void put(out *o, const char *fmt, ...)
{
    if (o->failed)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(o->buf + o->len, o->cap - o->len, fmt, ap);
        va_end(ap);
        if (n < 0) {
            o->failed = 1;
            return;
        }
        if ((size_t)n < o->cap - o->len) {
            o->len += (size_t)n;
            return;
        }
        size_t cap = o->cap * 2 + (size_t)n;
        char *b = realloc(o->buf, cap);
        if (!b) {
            o->failed = 1;
            return;
        }
        o->buf = b;
        o->cap = cap;
    }
}

static uint64_t ld(atomic_uint_fast64_t *a)
{
    return atomic_load_explicit(a, memory_order_relaxed);
}

static void put_hist(out *o, const char *name, const char *label,
                     const char *value, hist *h)
{
    uint64_t cum = 0;
    const char *sep = label ? "," : "";
    char lv[96] = "";
    if (label)
        snprintf(lv, sizeof lv, "%s=\"%s\"", label, value);
    for (unsigned b = 0; b < NB; b++) {
        cum += ld(&h->bucket[b]);
        if (b < NB - 1)
            put(o, "%s_bucket{%s%sle=\"%g\"} %llu\n", name, lv, sep,
                bounds[b], (unsigned long long)cum);
        else
            put(o, "%s_bucket{%s%sle=\"+Inf\"} %llu\n", name, lv, sep,
                (unsigned long long)cum);
    }
    put(o, "%s_sum%s%s%s %.6f\n", name, label ? "{" : "", lv,
        label ? "}" : "", (double)ld(&h->sum_us) / 1e6);
    put(o, "%s_count%s%s%s %llu\n", name, label ? "{" : "", lv,
        label ? "}" : "", (unsigned long long)ld(&h->count));
}

static void put_counter(out *o, const char *name, const char *help,
                        const char *label, const char *const *values,
                        const uint64_t *counts, size_t n)
{
    put(o, "# HELP %s %s\n# TYPE %s counter\n", name, help, name);
    for (size_t i = 0; i < n; i++) {
        if (label)
            put(o, "%s{%s=\"%s\"} %llu\n", name, label, values[i],
                (unsigned long long)counts[i]);
        else
            put(o, "%s %llu\n", name, (unsigned long long)counts[i]);
    }
}

static void put_scanners(out *o, metrics *m, const metrics_scanners *s)
{
    const scan_metrics *x = &s->intake;
    put(o, "# HELP facetd_scanner_intake_up 1 while the USB scanner intake "
           "runs.\n# TYPE facetd_scanner_intake_up gauge\n"
           "facetd_scanner_intake_up %d\n", s->enabled ? 1 : 0);
    put(o, "# HELP facetd_scanner_devices_connected Scanners connected and "
           "greeted.\n# TYPE facetd_scanner_devices_connected gauge\n"
           "facetd_scanner_devices_connected %llu\n",
        (unsigned long long)x->devices_connected);
    static const char *const dir_io[] = {"in", "out"};
    uint64_t frames[] = {x->frames_in, x->frames_out};
    put_counter(o, "facetd_scanner_frames_total", "FSP/1 frames received "
                "(valid) and sent.", "direction", dir_io, frames, 2);
    put_counter(o, "facetd_scanner_crc_errors_total", "Frames from scanners "
                "that failed their CRC.", NULL, NULL, &x->crc_errors, 1);
    put_counter(o, "facetd_scanner_bad_frames_total", "Frames from scanners "
                "with a bad magic, length or payload.", NULL, NULL,
                &x->bad_frames, 1);
    put_counter(o, "facetd_scanner_sequence_errors_total", "Gaps and jumps in "
                "scanners' sequence numbers.", NULL, NULL, &x->seq_errors, 1);
    static const char *const dir_nak[] = {"sent", "received"};
    uint64_t naks[] = {x->naks_sent, x->naks_received};
    put_counter(o, "facetd_scanner_naks_total", "NAKs sent to and received "
                "from scanners.", "direction", dir_nak, naks, 2);
    put_counter(o, "facetd_scanner_reassembly_failures_total", "HID reports "
                "dropped while reassembling frames.", NULL, NULL,
                &x->reassembly_failures, 1);
    static const char *const outcome[] = {"completed", "dropped"};
    uint64_t scans[] = {x->scans_completed, x->scans_dropped};
    put_counter(o, "facetd_scanner_scans_total", "Scans completed (kept as "
                "jobs) and dropped (faults, unplugging, refusals).",
                "outcome", outcome, scans, 2);
    put_counter(o, "facetd_scanner_model_bytes_total", "Model bytes of "
                "completed scans.", NULL, NULL, &x->model_bytes, 1);
    static const char *const reason[] = {"invalid_model", "store"};
    uint64_t refused[METRICS_NREFUSALS];
    for (int i = 0; i < METRICS_NREFUSALS; i++)
        refused[i] = ld(&m->scan_refused[i]);
    put_counter(o, "facetd_scanner_scans_refused_total", "Complete scans not "
                "kept, by reason (the scanner got ABORT).", "reason", reason,
                refused, METRICS_NREFUSALS);
    uint64_t results = ld(&m->scan_results);
    put_counter(o, "facetd_scanner_results_total", "RESULTs handed to the "
                "intake for scanners.", NULL, NULL, &results, 1);
    put(o, "# HELP facetd_scanner_result_latency_seconds Time from a scan's "
           "SCAN_DONE to its RESULT.\n# TYPE "
           "facetd_scanner_result_latency_seconds histogram\n");
    put_hist(o, "facetd_scanner_result_latency_seconds", NULL, NULL,
             &m->scan_result_time);
}

int metrics_render(metrics *m, const metrics_gauges *g, char **ret,
                   size_t *ret_len)
{
    out o = {malloc(8192), 0, 8192, 0};
    if (!o.buf)
        return -ENOMEM;
    put(&o, "# HELP facetd_up 1 while facetd is ready to serve.\n"
            "# TYPE facetd_up gauge\nfacetd_up %d\n", g->ready ? 1 : 0);
    if (g->store_ok) {
        put(&o, "# HELP facetd_jobs Jobs in the store by state.\n"
                "# TYPE facetd_jobs gauge\n");
        for (int s = 0; s < JOB_NSTATES; s++)
            put(&o, "facetd_jobs{state=\"%s\"} %llu\n",
                job_state_name((job_state)s),
                (unsigned long long)g->counts.by_state[s]);
        put(&o, "# HELP facetd_queue_depth Jobs waiting for a worker.\n"
                "# TYPE facetd_queue_depth gauge\nfacetd_queue_depth %llu\n",
            (unsigned long long)g->counts.by_state[JOB_QUEUED]);
        put(&o, "# HELP facetd_store_bytes Bytes of the job store on disk.\n"
                "# TYPE facetd_store_bytes gauge\nfacetd_store_bytes %llu\n",
            (unsigned long long)g->counts.file_bytes);
        put(&o, "# HELP facetd_store_kept_bytes Bytes of inputs and results "
                "kept.\n# TYPE facetd_store_kept_bytes gauge\n"
                "facetd_store_kept_bytes %llu\n",
            (unsigned long long)g->counts.kept_bytes);
    }
    put(&o, "# HELP facetd_queue_capacity Queued jobs accepted before 503.\n"
            "# TYPE facetd_queue_capacity gauge\nfacetd_queue_capacity %u\n",
        g->queue_size);
    if (g->node)
        put(&o, "# HELP facetd_cluster_node This node of a cluster sharing "
                "one store (the job counts and queue depth are the "
                "cluster's; the counters and workers this node's).\n"
                "# TYPE facetd_cluster_node gauge\n"
                "facetd_cluster_node{node=\"%s\"} 1\n", g->node);
    put(&o, "# HELP facetd_workers Worker threads.\n# TYPE facetd_workers "
            "gauge\nfacetd_workers %u\n", g->workers);
    put(&o, "# HELP facetd_workers_paused 1 while workers take no new job "
            "(Paused=yes).\n# TYPE facetd_workers_paused gauge\n"
            "facetd_workers_paused %d\n", g->paused ? 1 : 0);
    put(&o, "# HELP facetd_workers_busy Workers running a job.\n"
            "# TYPE facetd_workers_busy gauge\nfacetd_workers_busy %u\n",
        g->busy);
    put(&o, "# HELP facetd_http_waiting_clients Clients suspended on ?wait= "
            "or an event stream.\n# TYPE facetd_http_waiting_clients gauge\n"
            "facetd_http_waiting_clients %u\n", g->waiters);
    put(&o, "# HELP facetd_jobs_finished_total Jobs that ended, by final "
            "state.\n# TYPE facetd_jobs_finished_total counter\n");
    for (int s = JOB_SUCCEEDED; s < JOB_NSTATES; s++)
        put(&o, "facetd_jobs_finished_total{state=\"%s\"} %llu\n",
            job_state_name((job_state)s), (unsigned long long)ld(&m->jobs[s]));
    put(&o, "# HELP facetd_jobs_rejected_total Submissions refused because "
            "the queue was full.\n# TYPE facetd_jobs_rejected_total counter\n"
            "facetd_jobs_rejected_total{reason=\"queue_full\"} %llu\n",
        (unsigned long long)ld(&m->queue_full));
    put(&o, "# HELP facetd_job_duration_seconds Run time of finished jobs.\n"
            "# TYPE facetd_job_duration_seconds histogram\n");
    put_hist(&o, "facetd_job_duration_seconds", NULL, NULL, &m->job_time);
    put(&o, "# HELP facetd_op_duration_seconds Run time of pipeline "
            "operations, by op.\n# TYPE facetd_op_duration_seconds "
            "histogram\n");
    for (int k = 0; k < PROTO_OP_COUNT; k++)
        if (ld(&m->op_time[k].count))
            put_hist(&o, "facetd_op_duration_seconds", "op",
                     proto_op_name((proto_op_kind)k), &m->op_time[k]);
    put(&o, "# HELP facetd_http_requests_total HTTP requests by route and "
            "status code.\n# TYPE facetd_http_requests_total counter\n");
    for (unsigned r = 0; r <= m->nroutes; r++) {
        const char *name = r < m->nroutes ? m->routes[r] : "unmatched";
        for (unsigned c = 0; c < NCODES; c++) {
            uint64_t n = ld(&m->requests[r * NCODES + c]);
            if (!n)
                continue;
            if (c < NCODES - 1)
                put(&o, "facetd_http_requests_total{route=\"%s\",code=\"%u\"}"
                        " %llu\n", name, codes[c], (unsigned long long)n);
            else
                put(&o, "facetd_http_requests_total{route=\"%s\",code="
                        "\"other\"} %llu\n", name, (unsigned long long)n);
        }
    }
    put(&o, "# HELP facetd_http_request_duration_seconds Time from request "
            "to response, by route.\n# TYPE "
            "facetd_http_request_duration_seconds histogram\n");
    for (unsigned r = 0; r <= m->nroutes; r++)
        if (ld(&m->req_time[r].count))
            put_hist(&o, "facetd_http_request_duration_seconds", "route",
                     r < m->nroutes ? m->routes[r] : "unmatched",
                     &m->req_time[r]);
    put(&o, "# HELP facetd_http_received_bytes_total Request body bytes "
            "received.\n# TYPE facetd_http_received_bytes_total counter\n"
            "facetd_http_received_bytes_total %llu\n",
        (unsigned long long)ld(&m->bytes_in));
    put(&o, "# HELP facetd_http_sent_bytes_total Response body bytes sent.\n"
            "# TYPE facetd_http_sent_bytes_total counter\n"
            "facetd_http_sent_bytes_total %llu\n",
        (unsigned long long)ld(&m->bytes_out));
    put_scanners(&o, m, &g->scan);
    if (o.failed) {
        free(o.buf);
        return -ENOMEM;
    }
    *ret = o.buf;
    *ret_len = o.len;
    return 0;
}
