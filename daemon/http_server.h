/* http_server.h — facetd's HTTP server (libmicrohttpd): the Job API
 * routes (formats.md "Job API"), health and metrics endpoints.
 *
 * Model: a fixed pool of HTTP threads, each with its own epoll set, all
 * accepting on one listening socket. A request that has to wait — a
 * ?wait= long-poll or an event stream between events — suspends its
 * connection (MHD_suspend_connection) and costs no thread; the worker
 * pool's change notifications, a deadline timer or shutdown resume it.
 * Request bodies are read incrementally into a buffer capped by MaxBody
 * (413 beyond). Every error is an RFC 9457 problem+json document.
 *
 * The server reads jobs only through the store interface and cancels
 * through the store first, so it works the same when the store is shared
 * by several nodes. Waiting clients are woken by http_server_job_changed:
 * the local worker pool calls it, and a shared store backend must feed
 * it the other nodes' changes too (PostgreSQL: LISTEN/NOTIFY); without a
 * notification a waiter still answers at its deadline.
 *
 * Thread safety: http_server_job_changed and http_server_waiters may be
 * called from any thread; start, quiesce and stop from the main thread. */
#ifndef FACETD_HTTP_SERVER_H
#define FACETD_HTTP_SERVER_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "job_pool.h"
#include "metrics.h"
#include "scanners.h"
#include "store.h"

/* What the routes use; owned by the caller, outlives the server. The
 * atomics and the token may change at any time (SIGHUP reload). */
typedef struct http_env {
    store *s;
    job_pool *pool;                 /* local workers, may be NULL */
    scanners *sc;                   /* the scanner intake, may be NULL */
    metrics *m;
    unsigned workers;               /* for /metrics */
    atomic_uint_fast64_t max_body;  /* bytes */
    atomic_uint_fast64_t max_wait_ms;
    atomic_uint_fast64_t keepalive_ms;
    atomic_uint max_waiters;
    atomic_uint queue_size;
    atomic_uint inspect_max_facets;
    atomic_uint max_query_args;
    atomic_int ready;               /* 1 between start-up and shutdown */
    pthread_mutex_t token_lock;     /* guards token */
    char token[256];                /* "" = no authentication */
} http_env;

typedef struct http_config {
    int listen_fd;                  /* listening socket (borrowed) */
    unsigned threads;               /* ≥ 1 */
    unsigned max_connections;
    unsigned timeout_s;             /* idle connection timeout */
    size_t connection_memory;       /* bytes per connection */
    uint64_t header_timeout_ms;     /* connect to complete headers */
    unsigned per_client_connections; /* 0 = no limit */
} http_config;

typedef struct http_server http_server;

/* The route templates, in the order metrics count them. */
extern const char *const http_route_names[];
extern const unsigned http_nroutes;

/* Initialises env's locks and atomics (values zero, token empty). */
void http_env_init(http_env *env);
void http_env_set_token(http_env *env, const char *token);
void http_env_fini(http_env *env);

/* Starts serving on c->listen_fd. NULL with err on failure. */
http_server *http_server_start(http_env *env, const http_config *c,
                               geo_err *err);

/* The job changed (state, or progress only): wakes its waiting clients.
 * A job_notify_fn for the worker pool (user = the server). */
void http_server_job_changed(void *server, const char *id, bool progress_only);


/* Stops accepting connections and answers every waiting client now with
 * what it has (long-polls get the current state, event streams end).
 * Requests on open connections are still served. */
void http_server_quiesce(http_server *h);

/* Stops the server (quiescing first if needed), after the requests in
 * progress have answered (at most 5 s). Accepts NULL; returns NULL. */
http_server *http_server_stop(http_server *h);

#endif
