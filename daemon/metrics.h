/* metrics.h — facetd's counters and histograms, rendered in the
 * Prometheus text exposition format (version 0.0.4) for GET /metrics.
 *
 * What is counted where: HTTP requests by route and status code, request
 * durations by route and body bytes in/out (http_server.c); finished jobs
 * by final state, job durations and per-operation durations by op
 * (job_exec.c / the pool's done callback). Gauges that live elsewhere
 * (jobs by state and store size from the store, busy workers, waiting
 * clients) are passed to metrics_render as a snapshot, so nothing here
 * assumes the store is in-process.
 *
 * Every update is a relaxed atomic add: safe from any thread, no locks.
 * Routes are indices into the name table given to metrics_new; codes
 * outside the tracked set are counted as "other". */
#ifndef FACETD_METRICS_H
#define FACETD_METRICS_H

#include <stddef.h>
#include <stdint.h>

#include "job.h"
#include "pipeline.h"
#include "scanner.h"
#include "store.h"

typedef struct metrics metrics;

/* nroutes route names (e.g. "/v1/jobs/{id}"), borrowed for the life of
 * the metrics object. NULL on out-of-memory. */
metrics *metrics_new(const char *const *route_names, unsigned nroutes);
/* Accepts NULL; returns NULL. */
metrics *metrics_free(metrics *m);

/* One HTTP request: route index (or ≥ nroutes for "unmatched"), status
 * code, body bytes received and sent, and its duration in seconds. */
void metrics_http(metrics *m, unsigned route, unsigned code,
                  uint64_t bytes_in, uint64_t bytes_out, double seconds);

/* A job ended in state st after seconds of running. */
void metrics_job(metrics *m, job_state st, double seconds);

/* One pipeline operation ran for seconds. */
void metrics_op(metrics *m, proto_op_kind op, double seconds);

/* A submission was refused because the queue was full. */
void metrics_queue_full(metrics *m);

/* Why a complete scan was not kept (its device got ABORT). */
typedef enum metrics_refusal {
    METRICS_REFUSED_INVALID = 0, /* the model bytes do not parse */
    METRICS_REFUSED_STORE,       /* the job could not be stored */
    METRICS_NREFUSALS
} metrics_refusal;

void metrics_scan_refused(metrics *m, metrics_refusal why);

/* A RESULT went to a scanner seconds after the SCAN_DONE it answers
 * (negative: not measured, the scan came before this start or the
 * scanner is offline). */
void metrics_scan_result(metrics *m, double seconds);

/* The scanner intake's counters, read at scrape time. */
typedef struct metrics_scanners {
    int enabled;             /* the intake runs */
    scan_metrics intake;
} metrics_scanners;

/* Values read at scrape time. */
typedef struct metrics_gauges {
    int store_ok;            /* counts valid */
    store_counts counts;
    unsigned workers, busy;  /* worker pool */
    int paused;              /* workers take no new job */
    unsigned waiters;        /* suspended ?wait= / event-stream clients */
    unsigned queue_size;     /* configured bound */
    int ready;
    metrics_scanners scan;
    const char *node;        /* cluster node name, NULL when not shared */
} metrics_gauges;

/* Renders every metric into a malloc'd, NUL-terminated buffer (*ret, its
 * length in *ret_len). 0 or -ENOMEM. */
int metrics_render(metrics *m, const metrics_gauges *g, char **ret,
                   size_t *ret_len);

#endif
