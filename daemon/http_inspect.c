/* http_inspect.c — POST /v1/inspect: the synchronous inspection of a
 * small model, run by inspector threads of its own rather than on the
 * HTTP threads, under a time limit (InspectTimeout).
 *
 * The body is first scanned token by token without building anything:
 * its top-level members (the model itself, or {"model": ...}; any other
 * member is refused as for jobs) and the number of facets, so a model
 * over InspectMaxFacets is refused 413 after one pass of the tokenizer,
 * at no cost in memory. Then the model is read in place, the connection
 * suspended and the task queued; an inspector thread runs it with the
 * deadline in its geo_ctx and resumes the connection, whose handler is
 * called again and answers. A full queue is 503. */
#include "http.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "log.h"
#include "model_io.h"
#include "runner.h"

enum { INSPECT_THREADS = 2, INSPECT_QUEUE = 32 };

struct inspect_task {
    struct MHD_Connection *conn;
    geo_poly *model;
    int64_t deadline_ns;
    atomic_int cancel;       /* shutdown */
    /* set by the inspector, read after the resume */
    int rc;
    bool timed_out;
    geo_err err;
    json_t *report;
    struct inspect_task *next;
};

struct http_inspector {
    pthread_mutex_t lock;
    pthread_cond_t wake;
    inspect_task *head, *tail;   /* queued */
    unsigned queued;
    bool stopping;
    inspect_task *running[INSPECT_THREADS];
    pthread_t threads[INSPECT_THREADS];
    unsigned nthreads;
};

static void run_task(inspect_task *t)
{
    proto_op op = {.kind = PROTO_OP_INSPECT};
    proto_pipeline pl = {1, &op};
    geo_ctx ctx = {.cancel = &t->cancel, .deadline_ns = t->deadline_ns};
    json_t *stats = NULL, *summary = NULL;
    t->rc = runner_run(&pl, &t->model, &ctx, NULL, NULL, &stats, &summary,
                       &t->err);
    t->timed_out = t->rc == -ECANCELED &&
                   !atomic_load(&t->cancel) && geo_ctx_now_ns() >= t->deadline_ns;
    json_decref(summary);
    if (t->rc == 0)
        t->report = json_incref(json_object_get(stats, "before"));
    json_decref(stats);
    geo_poly_free(t->model);
    t->model = NULL;
}

static void *inspector(void *arg)
{
    http_inspector *q = arg;
    pthread_mutex_lock(&q->lock);
    unsigned me = 0;
    while (me < q->nthreads && !pthread_equal(q->threads[me], pthread_self()))
        me++;
    for (;;) {
        while (!q->head && !q->stopping)
            pthread_cond_wait(&q->wake, &q->lock);
        inspect_task *t = q->head;
        if (!t)
            break; /* stopping with an empty queue */
        q->head = t->next;
        if (!q->head)
            q->tail = NULL;
        q->queued--;
        if (q->stopping)
            atomic_store(&t->cancel, 1);
        if (me < INSPECT_THREADS)
            q->running[me] = t;
        pthread_mutex_unlock(&q->lock);
        run_task(t);
        pthread_mutex_lock(&q->lock);
        if (me < INSPECT_THREADS)
            q->running[me] = NULL;
        /* the handler suspended the connection before queuing t */
        MHD_resume_connection(t->conn);
    }
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

http_inspector *http_inspector_start(void)
{
    http_inspector *q = calloc(1, sizeof *q);
    if (!q)
        return NULL;
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->wake, NULL);
    pthread_mutex_lock(&q->lock);
    for (unsigned i = 0; i < INSPECT_THREADS; i++) {
        if (pthread_create(&q->threads[i], NULL, inspector, q) != 0)
            break;
        q->nthreads++;
    }
    pthread_mutex_unlock(&q->lock);
    if (!q->nthreads) {
        pthread_cond_destroy(&q->wake);
        pthread_mutex_destroy(&q->lock);
        free(q);
        return NULL;
    }
    return q;
}

void http_inspector_cancel_all(http_inspector *q)
{
    if (!q)
        return;
    pthread_mutex_lock(&q->lock);
    q->stopping = true;
    for (inspect_task *t = q->head; t; t = t->next)
        atomic_store(&t->cancel, 1);
    for (unsigned i = 0; i < INSPECT_THREADS; i++)
        if (q->running[i])
            atomic_store(&q->running[i]->cancel, 1);
    pthread_cond_broadcast(&q->wake);
    pthread_mutex_unlock(&q->lock);
}

http_inspector *http_inspector_stop(http_inspector *q)
{
    if (!q)
        return NULL;
    http_inspector_cancel_all(q);
    for (unsigned i = 0; i < q->nthreads; i++)
        pthread_join(q->threads[i], NULL);
    pthread_cond_destroy(&q->wake);
    pthread_mutex_destroy(&q->lock);
    free(q);
    return NULL;
}

/* 0, -EAGAIN (queue full) or -ESHUTDOWN. */
static int enqueue(http_inspector *q, inspect_task *t)
{
    pthread_mutex_lock(&q->lock);
    int r = q->stopping ? -ESHUTDOWN : q->queued >= INSPECT_QUEUE ? -EAGAIN
                                                                 : 0;
    if (r == 0) {
        /* suspended under the lock: no inspector can resume it first */
        MHD_suspend_connection(t->conn);
        if (q->tail)
            q->tail->next = t;
        else
            q->head = t;
        q->tail = t;
        q->queued++;
        pthread_cond_signal(&q->wake);
    }
    pthread_mutex_unlock(&q->lock);
    return r;
}

typedef struct scan {
    bool wrapped;            /* {"model": ...} */
    bool is_object;
    uint64_t facets;         /* counted up to cap + 1 */
    char unknown[64];        /* the first member besides "model" */
} scan;

/* Counts the elements of the "facets" array of the object whose first
 * token was just read, stopping past cap. -1 on bad JSON (j->error). */
static int count_facets(proto_jpull *j, uint64_t cap, scan *s)
{
    proto_jtok t;
    while ((t = proto_jpull_next(j)) == PROTO_JT_KEY) {
        if (strcmp(j->str, "facets") != 0) {
            if (proto_jpull_skip(j) == PROTO_JT_ERROR)
                return -1;
            continue;
        }
        t = proto_jpull_next(j);
        if (t != PROTO_JT_ARRAY) {
            if (proto_jpull_skip(j) == PROTO_JT_ERROR)
                return -1;
            continue;
        }
        while ((t = proto_jpull_next(j)) != PROTO_JT_ARRAY_END) {
            if (t == PROTO_JT_ERROR || proto_jpull_skip(j) == PROTO_JT_ERROR)
                return -1;
            if (++s->facets > cap)
                return 0; /* enough to refuse */
        }
    }
    return t == PROTO_JT_ERROR ? -1 : 0;
}

/* The shape of the body and its facet count, in one token pass. 0, or -1
 * with j->error set; the tokenizer is cleared either way. */
static int scan_body(const char *text, size_t len, uint64_t cap, scan *s,
                     proto_jerror *je)
{
    proto_jpull j;
    proto_jpull_init(&j, text, len);
    memset(s, 0, sizeof *s);
    int r = 0;
    proto_jtok t = proto_jpull_next(&j);
    if (t == PROTO_JT_OBJECT) {
        s->is_object = true;
        /* first pass over the members: which form is it */
        proto_jpull k;
        proto_jpull_init(&k, text, len);
        proto_jpull_next(&k);
        while (proto_jpull_next(&k) == PROTO_JT_KEY) {
            if (strcmp(k.str, "model") == 0)
                s->wrapped = true;
            else if (!s->unknown[0])
                snprintf(s->unknown, sizeof s->unknown, "%s", k.str);
            if (proto_jpull_skip(&k) == PROTO_JT_ERROR)
                break;
        }
        proto_jpull_clear(&k);
        if (!s->wrapped) {
            r = count_facets(&j, cap, s);
        } else {
            while ((t = proto_jpull_next(&j)) == PROTO_JT_KEY) {
                bool model = strcmp(j.str, "model") == 0;
                t = proto_jpull_next(&j);
                if (model && t == PROTO_JT_OBJECT) {
                    r = count_facets(&j, cap, s);
                    break;
                }
                if (t == PROTO_JT_ERROR ||
                    proto_jpull_skip(&j) == PROTO_JT_ERROR) {
                    r = -1;
                    break;
                }
            }
        }
    } else if (t == PROTO_JT_ERROR) {
        r = -1;
    }
    if (r < 0)
        *je = j.error;
    proto_jpull_clear(&j);
    return r;
}

/* Reads the model (the body, or its "model" member) in place. */
static geo_poly *read_model(http_req *r, const scan *s, unsigned cap,
                            bool *syntax, proto_jerror *je, geo_err *err)
{
    proto_jpull j;
    proto_jpull_init(&j, r->body ? r->body : "", r->len);
    proto_limits lim;
    proto_limits_default(&lim);
    lim.max_facets = cap;
    if ((uint64_t)cap * 4 + 64 < lim.max_vertices)
        lim.max_vertices = cap * 4 + 64;
    geo_poly *p = NULL;
    *syntax = false;
    proto_jtok t = proto_jpull_next(&j);
    if (!s->wrapped) {
        p = proto_model_from_jpull(&j, t, &lim, NULL, NULL, syntax, err);
    } else {
        while ((t = proto_jpull_next(&j)) == PROTO_JT_KEY) {
            if (strcmp(j.str, "model") == 0) {
                p = proto_model_from_jpull(&j, proto_jpull_next(&j), &lim,
                                           "model", NULL, syntax, err);
                break;
            }
            if (proto_jpull_skip(&j) == PROTO_JT_ERROR) {
                *syntax = true;
                break;
            }
        }
    }
    if (*syntax)
        *je = j.error;
    proto_jpull_clear(&j);
    return p;
}

void http_inspect_task_free(inspect_task *t)
{
    if (!t)
        return;
    json_decref(t->report);
    geo_poly_free(t->model);
    free(t);
}

static enum MHD_Result answer(http_req *r)
{
    inspect_task *t = r->inspect;
    r->inspect = NULL;
    enum MHD_Result res;
    if (t->rc == 0) {
        res = http_reply_json(r, 200, t->report, NULL);
        t->report = NULL;
    } else if (t->timed_out) {
        res = http_problem(r, 503, "inspect-timeout", "Service Unavailable",
                           NULL, NULL, "the inspection took longer than "
                           "InspectTimeout (%.3g s); submit a job instead",
                           (double)atomic_load(&r->env->inspect_timeout_ms) /
                               1000);
    } else if (t->rc == -ECANCELED) {
        const char *h[] = {"Retry-After", "1", NULL};
        res = http_problem(r, 503, "shutting-down", "Service Unavailable",
                           NULL, h, "the server is stopping");
    } else {
        res = http_problem(r, t->rc == -ENOMEM ? 500 : 422,
                           t->rc == -ENOMEM ? "out-of-memory" : "invalid-model",
                           t->rc == -ENOMEM ? "Internal Server Error"
                                            : "Unprocessable Content",
                           NULL, NULL, "%s", t->err.msg);
    }
    http_inspect_task_free(t);
    return res;
}

enum MHD_Result http_post_inspect(http_req *r)
{
    if (r->inspect)
        return answer(r); /* resumed: the inspector is done */
    unsigned cap = atomic_load(&r->env->inspect_max_facets);
    scan s;
    proto_jerror je;
    if (scan_body(r->body ? r->body : "", r->len, cap, &s, &je) < 0)
        return http_malformed_json(r, &je);
    if (s.wrapped && s.unknown[0])
        return http_problem(r, 422, "invalid-model", "Unprocessable Content",
                            json_pack("[{s:s, s:s}]", "path", s.unknown,
                                      "message", "unknown member (expected "
                                      "model)"), NULL,
                            "%s: unknown member (expected model)", s.unknown);
    if (s.facets > cap)
        return http_problem(r, 413, "model-too-large", "Content Too Large",
                            NULL, NULL, "more than %u facets; synchronous "
                            "inspection takes at most %u (submit a job "
                            "instead)", cap, cap);
    bool syntax;
    geo_err err = {{0}};
    geo_poly *p = read_model(r, &s, cap, &syntax, &je, &err);
    if (!p && syntax)
        return http_malformed_json(r, &je);
    if (!p)
        return http_problem(r, 422, "invalid-model", "Unprocessable Content",
                            json_pack("[o]", http_error_entry(err.msg)), NULL,
                            "%s", err.msg);
    inspect_task *t = calloc(1, sizeof *t);
    if (!t) {
        geo_poly_free(p);
        return http_problem(r, 500, "out-of-memory", "Internal Server Error",
                            NULL, NULL, "out of memory");
    }
    t->conn = r->conn;
    t->model = p;
    t->deadline_ns = geo_ctx_now_ns() +
                     (int64_t)atomic_load(&r->env->inspect_timeout_ms) *
                         1000000;
    atomic_init(&t->cancel, 0);
    r->inspect = t;
    int q = enqueue(r->srv->inspector, t);
    if (q == 0)
        return MHD_YES;
    r->inspect = NULL;
    geo_poly_free(p);
    free(t);
    const char *h[] = {"Retry-After", "1", NULL};
    return http_problem(r, 503, q == -EAGAIN ? "busy" : "shutting-down",
                        "Service Unavailable", NULL, h, q == -EAGAIN
                        ? "%u inspections are waiting; retry later"
                        : "the server is stopping%.0u", INSPECT_QUEUE);
}
