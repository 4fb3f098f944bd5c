/* http.h — what the files of the HTTP server share (not used outside
 * http_*.c): the per-request state, the waiter hub that suspends and
 * resumes connections, the reply helpers and the route handlers.
 *
 * Request lifetime: http_server.c allocates an http_req at a request's
 * first callback, feeds it the body, and calls the route's handler once
 * the body is complete — and again each time a suspended request is
 * resumed. The handler queues exactly one response (through the helpers
 * below) or suspends. MHD's completion callback records metrics and frees
 * the http_req. */
#ifndef FACETD_HTTP_H
#define FACETD_HTTP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <jansson.h>
#include <microhttpd.h>

#include "http_server.h"
#include "job.h"
#include "json_pull.h"

/* ---- waiter hub (http_wait.c) ----
 * A waiter is a suspended connection waiting for a job to change, for a
 * deadline, or for shutdown. Invariant: a waiter is in the hub exactly
 * while its connection is suspended, and only the hub resumes it (under
 * its lock, so a resume never precedes the suspend). */
typedef struct http_waiter {
    struct MHD_Connection *conn;
    char id[JOB_ID_LEN + 1];
    int64_t deadline;        /* monotonic ms */
    bool progress;           /* progress-only changes wake it too */
    uint64_t seq;            /* http_hub_seq(id) before the store was read */
    bool in_hub;             /* under the hub lock */
    struct http_waiter *next, *prev;
} http_waiter;

typedef struct http_hub http_hub;

http_hub *http_hub_new(void);
/* Resumes everyone and stops the timer; accepts NULL; returns NULL. */
http_hub *http_hub_free(http_hub *h);
/* The change count of id's bucket. A caller takes it into w->seq before
 * reading the job from the store, so that a change notified between that
 * read and the suspend is not lost (http_hub_suspend then says -ESTALE). */
uint64_t http_hub_seq(http_hub *h, const char *id);
/* Suspends w->conn until w->id changes, w->deadline passes or the hub
 * closes. Must be called from the connection's access handler or content
 * reader. 0 when suspended; -ESTALE when a job of w->id's bucket changed
 * since w->seq was taken (read the store again); -EAGAIN when limit
 * waiters are already suspended; -ESHUTDOWN when the hub is closed
 * (answer now). */
int http_hub_suspend(http_hub *h, http_waiter *w, unsigned limit);
void http_hub_notify(http_hub *h, const char *id, bool progress_only);
/* Resumes everyone; later suspends fail with -ESHUTDOWN. */
void http_hub_close(http_hub *h);
unsigned http_hub_count(http_hub *h);

/* ---- the inspector threads of POST /v1/inspect (http_inspect.c) ---- */
typedef struct inspect_task inspect_task;
typedef struct http_inspector http_inspector;
/* NULL when no thread could start. */
http_inspector *http_inspector_start(void);
/* Cancels queued and running inspections (their requests answer 503);
 * later ones are refused. */
void http_inspector_cancel_all(http_inspector *q);
/* Cancels, joins (every connection resumed); accepts NULL; returns NULL. */
http_inspector *http_inspector_stop(http_inspector *q);
/* Frees a task whose request ended without its answer. */
void http_inspect_task_free(inspect_task *t);

/* ---- request state ---- */
typedef enum http_method {
    HTTP_GET = 1, HTTP_HEAD = 2, HTTP_POST = 4, HTTP_DELETE = 8,
    HTTP_PUT = 16, HTTP_PATCH = 32, HTTP_OPTIONS = 64, HTTP_OTHER = 128,
} http_method;

typedef struct http_req {
    struct http_server *srv;
    http_env *env;
    struct MHD_Connection *conn;
    http_method method;
    int route;               /* index into the route table, -1 unmatched */
    char id[JOB_ID_LEN + 1]; /* {id} of the path, if any */
    char serial[64];         /* {serial} of the path, if any */
    char file[64];           /* {file} of the path, if any */
    int64_t t0_us;           /* monotonic start */
    unsigned status;         /* of the queued response */
    uint64_t bytes_in, bytes_out;
    bool has_body;           /* Content-Length > 0 or chunked */
    uint64_t content_length; /* as announced; 0 when unknown */
    bool admitted;           /* routed, authorised, preconditions met */
    bool started;            /* the first access callback happened */
    unsigned query_args;     /* counted in the raw request line */
    /* body */
    char *body;
    size_t len, cap;
    bool too_large;
    /* waiting */
    http_waiter w;
    bool waiting;            /* a wait was started (the handler resumes) */
    inspect_task *inspect;   /* queued or done inspection (http_inspect.c) */
    int64_t seen_version;
} http_req;

/* A TCP connection, from MHD's connection notification to its close:
 * what the header deadline needs (http_server.c). */
typedef struct http_conn {
    int fd;
    int64_t since_ms;        /* connect, or the end of the last request */
    bool in_headers;         /* no request's headers complete since then */
    bool cut;                /* shut down by the deadline */
    struct http_conn *next, *prev;
} http_conn;

struct http_server {
    struct MHD_Daemon *d;
    http_env *env;
    http_hub *hub;
    http_inspector *inspector;
    bool quiesced;
    atomic_int active;       /* requests begun and not completed */
    /* the header deadline: every open connection, a reaper thread */
    pthread_mutex_t conn_lock;
    pthread_cond_t conn_tick;
    http_conn *conns;        /* under conn_lock */
    uint64_t header_timeout_ms;
    bool reaper_started, reaper_stop;
    pthread_t reaper;
    atomic_uint_fast64_t header_cuts;
};

/* ---- the header deadline (http_deadline.c) ---- */
void http_conn_notify(void *cls, struct MHD_Connection *c,
                      void **socket_context,
                      enum MHD_ConnectionNotificationCode toe);
/* A request's headers are complete / a request ended (the next one's
 * headers are awaited). */
void http_conn_headers_done(http_server *h, struct MHD_Connection *c);
void http_conn_request_done(http_server *h, struct MHD_Connection *c);
/* Before MHD starts (locks; the reaper when timeout_ms > 0); -EAGAIN. */
int http_deadline_start(http_server *h, uint64_t timeout_ms);
/* Stops the reaper (before MHD stops); fini after MHD stopped. */
void http_deadline_stop(http_server *h);
void http_deadline_fini(http_server *h);

/* ---- replies (http_reply.c); each returns MHD's result ----
 * headers: NULL or a NULL-terminated list of name, value pairs (copied).
 * http_reply takes buf (malloc'd, freed by MHD) when take_buf, else buf
 * must be static storage. */
enum MHD_Result http_reply(http_req *r, unsigned status, const char *ctype,
                           char *buf, size_t len, bool take_buf,
                           const char *const *headers);
/* body is stolen (decref'd). */
enum MHD_Result http_reply_json(http_req *r, unsigned status, json_t *body,
                                const char *const *headers);
/* An RFC 9457 problem: type "urn:facetd:problem:SLUG", title, detail,
 * and errors (stolen, may be NULL) as [{"path","message"}, ...]. */
enum MHD_Result http_problem(http_req *r, unsigned status, const char *slug,
                             const char *title, json_t *errors,
                             const char *const *headers, const char *fmt, ...)
    __attribute__((format(printf, 7, 8)));
/* The answer to a body that is not JSON: 400 malformed-json naming line
 * and column, or 500 when reading it ran out of memory. */
enum MHD_Result http_malformed_json(http_req *r, const proto_jerror *je);
/* Copies src into dst (size bytes, NUL-terminated), every byte that is
 * not part of well-formed UTF-8 written as the four characters \\xHH, so
 * the result always serialises as a JSON string. */
void http_utf8_scrub(char *dst, size_t size, const char *src);
/* One {"path", "message"} entry split from a geo_err message of the form
 * "a.b[3].c: what" (path "" when the message names no place). */
json_t *http_error_entry(const char *msg);
/* 304 when If-None-Match matches etag ("\"...\"" or W/"..."). */
bool http_not_modified(http_req *r, const char *etag);
/* Query parameter or header; NULL when absent. */
const char *http_arg(http_req *r, const char *name);
const char *http_header(http_req *r, const char *name);

/* ---- handlers (http_jobs.c, http_events.c, http_ops.c,
 * http_scanners.c) ---- */
typedef enum MHD_Result (*http_handler)(http_req *r);
enum MHD_Result http_post_job(http_req *r);
enum MHD_Result http_get_job(http_req *r);
enum MHD_Result http_delete_job(http_req *r);
enum MHD_Result http_list_jobs(http_req *r);
enum MHD_Result http_get_model(http_req *r);
enum MHD_Result http_get_stats(http_req *r);
enum MHD_Result http_job_events(http_req *r);
enum MHD_Result http_post_inspect(http_req *r);
enum MHD_Result http_livez(http_req *r);
enum MHD_Result http_readyz(http_req *r);
enum MHD_Result http_metrics(http_req *r);
enum MHD_Result http_version(http_req *r);
enum MHD_Result http_openapi(http_req *r);
enum MHD_Result http_scanners(http_req *r);
enum MHD_Result http_scanner_scan(http_req *r);
enum MHD_Result http_web_index(http_req *r);
enum MHD_Result http_web_file(http_req *r);

/* True when a POST /v1/jobs?format=fmt_name body may come with
 * Content-Type ct (http_jobs.c). */
bool http_model_content_type_ok(const char *fmt_name, const char *ct);

/* The viewer's embedded files (http_web.c): their total size in bytes. */
size_t http_web_total_bytes(void);

/* The embedded OpenAPI document (http_openapi.c): NUL-terminated, its
 * length in *ret_len; static storage. */
const char *http_openapi_doc(size_t *ret_len);

#endif
