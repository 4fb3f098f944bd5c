/* http_server.c — the libmicrohttpd daemon, the route table, request
 * bodies, authentication and per-request bookkeeping (http_server.h).
 *
 * Invariants: a request is routed (and answered 401/404/405/413/415) at
 * its first callback, before any body byte is read; a body never grows
 * beyond MaxBody (bytes past it are drained and dropped, then 413); the
 * handler runs only once the body is complete. */
#include "http.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "log.h"
#include "model_io.h"

typedef struct route {
    const char *name;
    unsigned methods;     /* HTTP_GET implies HEAD */
    http_handler get, post, del;
    bool open;            /* answered without a token */
    bool body_optional;   /* a POST without a body needs no Content-Type */
} route;

static const route routes[] = {
    /* the web viewer (http_web.c): open, it holds no job data */
    {"/", HTTP_GET, http_web_index, NULL, NULL, true, false},
    {"/ui/{file}", HTTP_GET, http_web_file, NULL, NULL, true, false},
    {"/livez", HTTP_GET, http_livez, NULL, NULL, true, false},
    {"/readyz", HTTP_GET, http_readyz, NULL, NULL, true, false},
    {"/metrics", HTTP_GET, http_metrics, NULL, NULL, false, false},
    {"/v1/version", HTTP_GET, http_version, NULL, NULL, false, false},
    {"/v1/openapi.json", HTTP_GET, http_openapi, NULL, NULL, false, false},
    {"/v1/scanners", HTTP_GET, http_scanners, NULL, NULL, false, false},
    {"/v1/scanners/{serial}/scan", HTTP_POST, NULL, http_scanner_scan, NULL,
     false, true},
    {"/v1/inspect", HTTP_POST, NULL, http_post_inspect, NULL, false, false},
    {"/v1/jobs", HTTP_GET | HTTP_POST, http_list_jobs, http_post_job, NULL,
     false, false},
    {"/v1/jobs/{id}", HTTP_GET | HTTP_DELETE, http_get_job, NULL,
     http_delete_job, false, false},
    {"/v1/jobs/{id}/model", HTTP_GET, http_get_model, NULL, NULL, false,
     false},
    {"/v1/jobs/{id}/stats", HTTP_GET, http_get_stats, NULL, NULL, false,
     false},
    {"/v1/jobs/{id}/events", HTTP_GET, http_job_events, NULL, NULL, false,
     false},
};
enum { NROUTES = sizeof routes / sizeof routes[0] };

const char *const http_route_names[NROUTES] = {
    "/", "/ui/{file}",
    "/livez", "/readyz", "/metrics", "/v1/version", "/v1/openapi.json",
    "/v1/scanners", "/v1/scanners/{serial}/scan", "/v1/inspect", "/v1/jobs",
    "/v1/jobs/{id}",
    "/v1/jobs/{id}/model", "/v1/jobs/{id}/stats", "/v1/jobs/{id}/events",
};
const unsigned http_nroutes = NROUTES;

void http_env_init(http_env *env)
{
    memset(env, 0, sizeof *env);
    pthread_mutex_init(&env->token_lock, NULL);
}

void http_env_set_token(http_env *env, const char *token)
{
    pthread_mutex_lock(&env->token_lock);
    snprintf(env->token, sizeof env->token, "%s", token ? token : "");
    pthread_mutex_unlock(&env->token_lock);
}

void http_env_fini(http_env *env)
{
    pthread_mutex_destroy(&env->token_lock);
}

static int64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

static http_method method_of(const char *m)
{
    static const struct { const char *name; http_method m; } map[] = {
        {"GET", HTTP_GET},       {"HEAD", HTTP_HEAD},
        {"POST", HTTP_POST},     {"DELETE", HTTP_DELETE},
        {"PUT", HTTP_PUT},       {"PATCH", HTTP_PATCH},
        {"OPTIONS", HTTP_OPTIONS},
    };
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (strcmp(m, map[i].name) == 0)
            return map[i].m;
    return HTTP_OTHER;
}

/* Matches url against a template with at most one "{id}", "{serial}" or
 * "{file}" segment, which goes to r->id, r->serial or r->file (cut to
 * fit: a cut value names nothing that exists). */
static bool match(const char *tmpl, const char *url, http_req *r)
{
    const char *brace = strchr(tmpl, '{'), *close;
    if (!brace || !(close = strchr(brace, '}')))
        return strcmp(tmpl, url) == 0;
    size_t pre = (size_t)(brace - tmpl);
    if (strncmp(tmpl, url, pre) != 0)
        return false;
    const char *seg = url + pre, *slash = strchr(seg, '/');
    size_t n = slash ? (size_t)(slash - seg) : strlen(seg);
    if (n == 0 || strcmp(slash ? slash : "", close + 1) != 0)
        return false;
    char *dst = r->id;
    size_t cap = sizeof r->id;
    if (strncmp(brace, "{serial}", 8) == 0) {
        dst = r->serial;
        cap = sizeof r->serial;
    } else if (strncmp(brace, "{file}", 6) == 0) {
        dst = r->file;
        cap = sizeof r->file;
    }
    if (n >= cap)
        n = cap - 1;
    memcpy(dst, seg, n);
    dst[n] = '\0';
    return true;
}

static void allow_list(unsigned methods, char *buf, size_t size)
{
    snprintf(buf, size, "%s%s%s%sOPTIONS",
             methods & HTTP_GET ? "GET, HEAD, " : "",
             methods & HTTP_POST ? "POST, " : "",
             methods & HTTP_DELETE ? "DELETE, " : "", "");
}

/* Constant-time in the secret's content: every byte of the presented
 * token is compared, whether or not an earlier one differed. */
static bool token_ok(http_env *env, const char *auth)
{
    pthread_mutex_lock(&env->token_lock);
    bool ok = true;
    if (env->token[0]) {
        const char *given = "";
        if (auth && strncasecmp(auth, "Bearer ", 7) == 0)
            given = auth + 7;
        size_t gl = strlen(given), tl = strlen(env->token);
        unsigned char diff = gl != tl;
        for (size_t i = 0; i < gl; i++)
            diff |= (unsigned char)(given[i] ^ env->token[i % tl]);
        ok = diff == 0;
    }
    pthread_mutex_unlock(&env->token_lock);
    return ok;
}

static bool json_content_type(const char *ct)
{
    if (!ct)
        return false;
    while (*ct == ' ')
        ct++;
    size_t n = strcspn(ct, "; ");
    return (n == 16 && strncasecmp(ct, "application/json", 16) == 0) ||
           (n > 17 && strncasecmp(ct, "application/", 12) == 0 &&
            strncasecmp(ct + n - 5, "+json", 5) == 0);
}

/* First callback: route, method, authentication, body preconditions.
 * Returns MHD_YES with no response queued when the request proceeds. */
static enum MHD_Result admit(http_req *r, const char *url, bool *answered)
{
    *answered = true;
    const route *rt = NULL;
    for (int i = 0; i < NROUTES; i++) {
        if (match(routes[i].name, url, r)) {
            rt = &routes[i];
            r->route = i;
            break;
        }
    }
    if (!rt)
        return http_problem(r, 404, "not-found", "Not Found", NULL, NULL,
                            "no resource at %.200s", url);
    char allow[64];
    allow_list(rt->methods, allow, sizeof allow);
    const char *allow_hdr[] = {"Allow", allow, NULL};
    if (r->method == HTTP_OPTIONS)
        return http_reply(r, 204, NULL, (char *)"", 0, false, allow_hdr);
    unsigned m = r->method == HTTP_HEAD ? HTTP_GET : r->method;
    if (!(rt->methods & m))
        return http_problem(r, 405, "method-not-allowed",
                            "Method Not Allowed", NULL, allow_hdr,
                            "%s takes %s", rt->name, allow);
    if (!rt->open && !token_ok(r->env, http_header(r, "Authorization"))) {
        const char *h[] = {"WWW-Authenticate", "Bearer realm=\"facetd\"",
                           NULL};
        return http_problem(r, 401, "unauthorized", "Unauthorized", NULL, h,
                            "this server requires an API token "
                            "(Authorization: Bearer TOKEN)");
    }
    if (m == HTTP_POST && (r->has_body || !rt->body_optional)) {
        const char *ct = http_header(r, MHD_HTTP_HEADER_CONTENT_TYPE);
        /* POST /v1/jobs?format=stl takes the model file itself */
        const char *fmt = rt->post == http_post_job ? http_arg(r, "format")
                                                    : NULL;
        if (fmt && !http_model_content_type_ok(fmt, ct)) {
            const char *h[] = {"Accept-Post", "application/octet-stream",
                               NULL};
            return http_problem(r, 415, "unsupported-media-type",
                                "Unsupported Media Type", NULL, h,
                                "a format=%.32s body must be %s or "
                                "application/octet-stream", fmt,
                                proto_format_mime(
                                    proto_format_from_name(fmt)));
        }
        if (!fmt && !json_content_type(ct)) {
            const char *h[] = {"Accept-Post", "application/json", NULL};
            return http_problem(r, 415, "unsupported-media-type",
                                "Unsupported Media Type", NULL, h,
                                "the body must be application/json");
        }
        const char *cl = http_header(r, MHD_HTTP_HEADER_CONTENT_LENGTH);
        uint64_t max = atomic_load(&r->env->max_body);
        if (cl && strtoull(cl, NULL, 10) > max)
            return http_problem(r, 413, "body-too-large", "Content Too Large",
                                NULL, NULL, "the body has %s bytes; the "
                                "limit is %llu", cl, (unsigned long long)max);
    }
    *answered = false;
    return MHD_YES;
}

typedef struct framing {
    unsigned content_lengths;
    bool lengths_differ;
    const char *first_length;
} framing;

static enum MHD_Result count_lengths(void *cls, enum MHD_ValueKind kind,
                                     const char *key, const char *value)
{
    (void)kind;
    framing *f = cls;
    if (strcasecmp(key, MHD_HTTP_HEADER_CONTENT_LENGTH) != 0)
        return MHD_YES;
    if (f->content_lengths++ == 0)
        f->first_length = value ? value : "";
    else if (strcmp(f->first_length, value ? value : "") != 0)
        f->lengths_differ = true;
    return MHD_YES;
}

/* Framing a request cannot be read by (RFC 9112 §6.3) and query strings
 * no route needs: answered 400 at once, and the connection closed, rather
 * than guessing where the body ends and waiting for bytes that never
 * come. */
static enum MHD_Result framing_problem(http_req *r, bool *answered)
{
    static const char *const close_hdr[] = {"Connection", "close", NULL};
    *answered = true;
    framing f = {0};
    MHD_get_connection_values(r->conn, MHD_HEADER_KIND, count_lengths, &f);
    const char *te = http_header(r, MHD_HTTP_HEADER_TRANSFER_ENCODING);
    if (f.lengths_differ)
        return http_problem(r, 400, "bad-framing", "Bad Request", NULL,
                            close_hdr, "Content-Length is given %u times "
                            "with different values", f.content_lengths);
    if (te && strcasecmp(te, "chunked") != 0)
        return http_problem(r, 400, "bad-framing", "Bad Request", NULL,
                            close_hdr, "Transfer-Encoding '%.100s': only "
                            "chunked is understood", te);
    if (te && f.content_lengths)
        return http_problem(r, 400, "bad-framing", "Bad Request", NULL,
                            close_hdr, "both Transfer-Encoding and "
                            "Content-Length: the body's end is ambiguous");
    int nargs = MHD_get_connection_values(r->conn, MHD_GET_ARGUMENT_KIND,
                                          NULL, NULL);
    unsigned max_args = atomic_load(&r->env->max_query_args);
    if (r->query_args > max_args || (nargs > 0 && (unsigned)nargs > max_args))
        return http_problem(r, 400, "bad-request", "Bad Request", NULL,
                            close_hdr, "%u query arguments; the limit is %u",
                            r->query_args > (unsigned)nargs ? r->query_args
                                                            : (unsigned)nargs,
                            max_args);
    *answered = false;
    return MHD_YES;
}

static void append_body(http_req *r, const char *data, size_t n)
{
    r->bytes_in += n;
    if (r->too_large)
        return;
    uint64_t max = atomic_load(&r->env->max_body);
    if ((uint64_t)r->len + n > max) {
        r->too_large = true;
        free(r->body);
        r->body = NULL;
        r->len = r->cap = 0;
        return;
    }
    if (r->len + n + 1 > r->cap) {
        /* the announced length at once (checked against MaxBody when the
         * request was admitted): no copying as the buffer grows */
        size_t cap = r->cap                        ? r->cap
                     : r->content_length + 1 > 16384 ? r->content_length + 1
                                                      : 16384;
        while (cap < r->len + n + 1)
            cap *= 2;
        if (cap > max + 1)
            cap = (size_t)max + 1;
        char *b = realloc(r->body, cap);
        if (!b) {
            /* Treated as too large: the client learns the body was
             * refused rather than the server failing silently. */
            r->too_large = true;
            free(r->body);
            r->body = NULL;
            r->len = r->cap = 0;
            return;
        }
        r->body = b;
        r->cap = cap;
    }
    memcpy(r->body + r->len, data, n);
    r->len += n;
    r->body[r->len] = '\0';
}

/* Called with the request line, before MHD parses the query: a query of
 * more arguments than any route takes is emptied here (and refused at the
 * first callback), because MHD 0.9.75 parsing one that overflows the
 * connection's memory queues a 431 it never sends and holds the
 * connection. The request state is born here (MHD hands the returned
 * pointer to every later callback). */
static void *uri_log(void *cls, const char *uri, struct MHD_Connection *conn)
{
    http_server *srv = cls;
    http_req *r = calloc(1, sizeof *r);
    if (!r)
        return NULL;
    atomic_fetch_add(&srv->active, 1);
    r->srv = srv;
    r->env = srv->env;
    r->conn = conn;
    r->route = -1;
    char *q = strchr(uri, '?');
    if (q) {
        unsigned n = 0;
        for (const char *c = q + 1; *c; c++)
            n += *c != '&' && (c == q + 1 || c[-1] == '&');
        r->query_args = n;
        /* the buffer is MHD's own, writable copy of the request line */
        if (n > atomic_load(&srv->env->max_query_args))
            q[1] = '\0';
    }
    return r;
}

static enum MHD_Result on_request(void *cls, struct MHD_Connection *conn,
                                  const char *url, const char *method,
                                  const char *version, const char *upload,
                                  size_t *upload_size, void **con_cls)
{
    http_server *srv = cls;
    http_req *r = *con_cls;
    if (!r)
        return MHD_NO; /* uri_log could not allocate it */
    if (!r->started) {
        r->started = true;
        r->conn = conn;
        r->t0_us = mono_us();
        r->method = method_of(method);
        http_conn_headers_done(srv, conn);
        bool answered;
        enum MHD_Result res = framing_problem(r, &answered);
        if (answered)
            return res;
        /* A request with a body is judged before its body is read (a
         * refusal then closes the connection instead of reading it); one
         * without is answered at the next callback, which keeps the
         * connection alive. */
        const char *cl = http_header(r, MHD_HTTP_HEADER_CONTENT_LENGTH);
        const char *te = http_header(r, MHD_HTTP_HEADER_TRANSFER_ENCODING);
        r->has_body = te || (cl && strcmp(cl, "0") != 0);
        if (cl && !te) {
            uint64_t v = strtoull(cl, NULL, 10);
            if (v <= atomic_load(&r->env->max_body))
                r->content_length = v;
        }
        if (!r->has_body)
            return MHD_YES;
        res = admit(r, url, &answered);
        if (answered || res != MHD_YES)
            return res;
        r->admitted = true;
        return MHD_YES;
    }
    if (*upload_size) {
        append_body(r, upload, *upload_size);
        *upload_size = 0;
        return MHD_YES;
    }
    if (!r->admitted) {
        bool answered;
        enum MHD_Result res = admit(r, url, &answered);
        if (answered || res != MHD_YES)
            return res;
        r->admitted = true;
    }
    if (r->too_large)
        return http_problem(r, 413, "body-too-large", "Content Too Large",
                            NULL, NULL, "the body is larger than %llu bytes",
                            (unsigned long long)atomic_load(&r->env->max_body));
    const route *rt = &routes[r->route];
    http_handler h = r->method == HTTP_POST     ? rt->post
                     : r->method == HTTP_DELETE ? rt->del
                                                : rt->get;
    return h(r);
}

static void on_completed(void *cls, struct MHD_Connection *conn,
                         void **con_cls, enum MHD_RequestTerminationCode toe)
{
    (void)toe;
    http_server *srv = cls;
    http_req *r = *con_cls;
    if (!r)
        return;
    double secs = (double)(mono_us() - r->t0_us) / 1e6;
    if (r->status) {
        metrics_http(srv->env->m, r->route < 0 ? NROUTES : (unsigned)r->route,
                     r->status, r->bytes_in, r->bytes_out, secs);
        log_msg(LOG_DEBUG, r->id[0] ? r->id : NULL, "%s %s %u %.3f ms",
                r->route < 0 ? "-" : routes[r->route].name,
                r->method == HTTP_POST ? "POST" : r->method == HTTP_DELETE
                ? "DELETE" : "GET", r->status, secs * 1e3);
    }
    free(r->body);
    free(r);
    *con_cls = NULL;
    http_conn_request_done(srv, conn);
    atomic_fetch_sub(&srv->active, 1);
}

static void mhd_log(void *cls, const char *fmt, va_list ap)
{
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, ap);
    size_t n = strlen(msg);
    while (n && (msg[n - 1] == '\n' || msg[n - 1] == '\r'))
        msg[--n] = '\0';
    log_msg(LOG_WARNING, NULL, "http: %s", msg);
}

http_server *http_server_start(http_env *env, const http_config *c,
                               geo_err *err)
{
    http_server *h = calloc(1, sizeof *h);
    if (!h) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    h->env = env;
    h->hub = http_hub_new();
    if (!h->hub) {
        free(h);
        geo_err_set(err, -ENOMEM, "cannot start the waiter timer");
        return NULL;
    }
    unsigned flags = MHD_USE_EPOLL_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME |
                     MHD_USE_ERROR_LOG;
    if (http_deadline_start(h, c->header_timeout_ms) < 0) {
        geo_err_set(err, -EAGAIN, "cannot start the header deadline thread");
        http_deadline_fini(h);
        http_hub_free(h->hub);
        free(h);
        return NULL;
    }
    struct MHD_OptionItem opts[12];
    int n = 0;
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_EXTERNAL_LOGGER,
                                        (intptr_t)mhd_log, NULL};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_LISTEN_SOCKET,
                                        c->listen_fd, NULL};
    if (c->threads > 1)
        opts[n++] = (struct MHD_OptionItem){MHD_OPTION_THREAD_POOL_SIZE,
                                            c->threads, NULL};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_CONNECTION_LIMIT,
                                        c->max_connections, NULL};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_CONNECTION_MEMORY_LIMIT,
                                        (intptr_t)c->connection_memory, NULL};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_CONNECTION_TIMEOUT,
                                        c->timeout_s, NULL};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_NOTIFY_COMPLETED,
                                        (intptr_t)on_completed, h};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_URI_LOG_CALLBACK,
                                        (intptr_t)uri_log, h};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_NOTIFY_CONNECTION,
                                        (intptr_t)http_conn_notify, h};
    if (c->per_client_connections)
        opts[n++] = (struct MHD_OptionItem){MHD_OPTION_PER_IP_CONNECTION_LIMIT,
                                            c->per_client_connections, NULL};
    opts[n++] = (struct MHD_OptionItem){MHD_OPTION_END, 0, NULL};
    h->d = MHD_start_daemon(flags, 0, NULL, NULL, on_request, h,
                            MHD_OPTION_ARRAY, opts, MHD_OPTION_END);
    if (!h->d) {
        geo_err_set(err, -EIO, "cannot start the HTTP server (see the "
                    "messages above)");
        http_deadline_stop(h);
        http_deadline_fini(h);
        http_hub_free(h->hub);
        free(h);
        return NULL;
    }
    return h;
}

void http_server_job_changed(void *server, const char *id, bool progress_only)
{
    http_server *h = server;
    http_hub_notify(h->hub, id, progress_only);
}

void http_server_quiesce(http_server *h)
{
    if (h->quiesced)
        return;
    h->quiesced = true;
    /* The socket is the caller's: quiescing only stops accepting on it. */
    MHD_quiesce_daemon(h->d);
    http_hub_close(h->hub);
}

http_server *http_server_stop(http_server *h)
{
    if (!h)
        return NULL;
    http_server_quiesce(h);
    /* Requests woken by the quiesce still have to send their answers:
     * MHD_stop_daemon would cut them off. */
    int64_t end = job_mono_ms() + 5000;
    while (atomic_load(&h->active) > 0 && job_mono_ms() < end) {
        struct timespec ts = {0, 10 * 1000 * 1000};
        nanosleep(&ts, NULL);
    }
    http_deadline_stop(h);
    MHD_stop_daemon(h->d);
    http_deadline_fini(h);
    http_hub_free(h->hub);
    free(h);
    return NULL;
}
