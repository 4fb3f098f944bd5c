/* http_events.c — GET /v1/jobs/{id}/events: a Server-Sent Events stream
 * of one job's changes.
 *
 * Each event is a snapshot of the job: "id:" is the job's version, so a
 * client reconnecting with Last-Event-ID gets the current snapshot at
 * once if anything changed since, and nothing it has seen. "event:" is
 * "state" when the state differs from the previous event's, else
 * "progress"; "data:" is the job's JSON on one line. The stream ends after
 * the event of a final state (or "event: gone" if the job was deleted).
 * Between events the connection is suspended in the waiter hub (no thread
 * blocked); a ": keep-alive" comment goes out every KeepAlive so proxies
 * and clients see the stream alive and a vanished client is noticed.
 * Successive progress changes coalesce into the latest snapshot. */
#include "http.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "log.h"

typedef struct sse {
    http_server *srv;
    http_env *env;
    char id[JOB_ID_LEN + 1];
    int64_t last_version;   /* of the last event sent */
    int last_state;         /* -1 before the first event */
    int64_t next_keepalive; /* monotonic ms */
    bool done;              /* the final event is out */
    char *pending;          /* formatted bytes not yet handed to MHD */
    size_t plen, poff;
    http_waiter w;
} sse;

static ssize_t drain(sse *s, char *buf, size_t max)
{
    size_t n = s->plen - s->poff;
    if (n > max)
        n = max;
    memcpy(buf, s->pending + s->poff, n);
    s->poff += n;
    if (s->poff == s->plen) {
        free(s->pending);
        s->pending = NULL;
        s->plen = s->poff = 0;
    }
    return (ssize_t)n;
}

static int set_pending(sse *s, char *text)
{
    if (!text)
        return -ENOMEM;
    free(s->pending);
    s->pending = text;
    s->plen = strlen(text);
    s->poff = 0;
    return 0;
}

static int event_for(sse *s, const job_rec *j)
{
    char *data = job_to_text(j, NULL);
    if (!data)
        return -ENOMEM;
    const char *kind = (int)j->state != s->last_state ? "state" : "progress";
    char *text = NULL;
    if (asprintf(&text, "id: %lld\nevent: %s\ndata: %s\n\n",
                 (long long)j->version, kind, data) < 0)
        text = NULL;
    free(data);
    s->last_version = j->version;
    s->last_state = (int)j->state;
    if (job_state_terminal(j->state))
        s->done = true;
    return set_pending(s, text);
}

static ssize_t sse_read(void *cls, uint64_t pos, char *buf, size_t max)
{
    sse *s = cls;
    (void)pos;
    if (s->pending)
        return drain(s, buf, max);
    if (s->done)
        return MHD_CONTENT_READER_END_OF_STREAM;
    job_rec j;
    geo_err err;
    int rc;
again:
    s->w.seq = http_hub_seq(s->srv->hub, s->id);
    rc = store_get(s->env->s, s->id, &j, &err);
    if (rc == -ENOENT) {
        s->done = true;
        if (set_pending(s, strdup("event: gone\ndata: {}\n\n")) < 0)
            return MHD_CONTENT_READER_END_WITH_ERROR;
        return drain(s, buf, max);
    }
    if (rc < 0) {
        log_msg(LOG_ERR, s->id, "event stream: %s", err.msg);
        return MHD_CONTENT_READER_END_WITH_ERROR;
    }
    if (j.version > s->last_version) {
        rc = event_for(s, &j);
        job_rec_clear(&j);
        if (rc < 0)
            return MHD_CONTENT_READER_END_WITH_ERROR;
        return drain(s, buf, max);
    }
    bool ended = job_state_terminal(j.state);
    job_rec_clear(&j);
    if (ended) /* the client saw the final event on an earlier stream */
        return MHD_CONTENT_READER_END_OF_STREAM;
    int64_t now = job_mono_ms();
    if (now >= s->next_keepalive) {
        s->next_keepalive = now + (int64_t)atomic_load(&s->env->keepalive_ms);
        static const char ka[] = ": keep-alive\n\n";
        if (max < sizeof ka - 1)
            return 0;
        memcpy(buf, ka, sizeof ka - 1);
        return (ssize_t)(sizeof ka - 1);
    }
    s->w.deadline = s->next_keepalive;
    rc = http_hub_suspend(s->srv->hub, &s->w,
                          atomic_load(&s->env->max_waiters));
    if (rc == 0)
        return 0;
    if (rc == -ESTALE)
        goto again;
    /* Shutting down, or out of waiter slots: end the stream; the client
     * reconnects with Last-Event-ID and loses nothing. */
    return MHD_CONTENT_READER_END_OF_STREAM;
}

static void sse_free(void *cls)
{
    sse *s = cls;
    free(s->pending);
    free(s);
}

enum MHD_Result http_job_events(http_req *r)
{
    job_rec j;
    geo_err err;
    int rc = store_get(r->env->s, r->id, &j, &err);
    if (rc == -ENOENT)
        return http_problem(r, 404, "job-not-found", "Not Found", NULL, NULL,
                            "no job '%s'", r->id);
    if (rc < 0)
        return http_problem(r, 500, "store-error", "Internal Server Error",
                            NULL, NULL, "%s", err.msg);
    job_rec_clear(&j);
    if (http_hub_count(r->srv->hub) >= atomic_load(&r->env->max_waiters)) {
        const char *h[] = {"Retry-After", "1", NULL};
        return http_problem(r, 429, "too-many-waiters", "Too Many Requests",
                            NULL, h, "too many clients are waiting; retry "
                            "later");
    }
    sse *s = calloc(1, sizeof *s);
    if (!s)
        return MHD_NO;
    s->srv = r->srv;
    s->env = r->env;
    memcpy(s->id, r->id, sizeof s->id);
    s->last_state = -1;
    const char *last = http_header(r, "Last-Event-ID");
    if (last)
        s->last_version = strtoll(last, NULL, 10);
    if (s->last_version < 0)
        s->last_version = 0;
    s->next_keepalive = job_mono_ms() +
                        (int64_t)atomic_load(&r->env->keepalive_ms);
    s->w.conn = r->conn;
    memcpy(s->w.id, s->id, sizeof s->w.id);
    s->w.progress = true;
    struct MHD_Response *resp = MHD_create_response_from_callback(
        MHD_SIZE_UNKNOWN, 4096, sse_read, s, sse_free);
    if (!resp) {
        free(s);
        return MHD_NO;
    }
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE,
                            "text/event-stream");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL, "no-cache");
    MHD_add_response_header(resp, "X-Accel-Buffering", "no");
    r->status = 200;
    enum MHD_Result res = MHD_queue_response(r->conn, 200, resp);
    MHD_destroy_response(resp);
    return res;
}
