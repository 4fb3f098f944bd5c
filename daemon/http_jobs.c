/* http_jobs.c — the job routes: submit, read (with ?wait= long-polls),
 * list, cancel/delete, and the results (model in every format, stats).
 *
 * Status codes: 202 submitted (Location: /v1/jobs/{id}); 200 read; 304
 * when If-None-Match matches the ETag; 400 malformed JSON (with line and
 * column) or a bad query argument; 404 no such job; 409 no result (the
 * job has not succeeded); 422 a request that parses but is invalid (every
 * error listed with its place); 429 too many waiting clients; 503 queue
 * full (Retry-After). */
#include "http.h"

#include <ctype.h>
#include <stdarg.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "frep_json.h"
#include "job_submit.h"
#include "log.h"
#include "model_io.h"
#include "runner.h"

static enum MHD_Result store_failure(http_req *r, int code, const geo_err *e)
{
    if (code == -ENOENT)
        return http_problem(r, 404, "job-not-found", "Not Found", NULL, NULL,
                            "no job '%s'", r->id);
    if (code == -ENOTCONN) {
        const char *h[] = {"Retry-After", "2", NULL};
        return http_problem(r, 503, "store-unavailable",
                            "Service Unavailable", NULL, h, "%s", e->msg);
    }
    log_msg(LOG_ERR, r->id[0] ? r->id : NULL, "store: %s", e->msg);
    return http_problem(r, 500, "store-error", "Internal Server Error", NULL,
                        NULL, "the job store failed: %s", e->msg);
}

static enum MHD_Result reply_job(http_req *r, unsigned status, job_rec *j,
                                 const char *const *headers, json_t *extra)
{
    if (!extra) {
        size_t n;
        char *text = job_to_text(j, &n);
        char *nl = text ? realloc(text, n + 2) : NULL;
        if (!nl) {
            free(text);
            return http_problem(r, 500, "out-of-memory", "Out of memory",
                                NULL, NULL, "the response could not be built");
        }
        /* the trailing newline of http_reply_json */
        nl[n++] = '\n';
        nl[n] = '\0';
        return http_reply(r, status, "application/json", nl, n, true,
                          headers);
    }
    json_t *o = job_to_json(j);
    if (o && extra)
        json_object_update(o, extra);
    json_decref(extra);
    return http_reply_json(r, status, o, headers);
}

/* The body of POST /v1/jobs, read in one pass of the pull tokenizer: the
 * model goes straight into a geo_poly (no tree of its 10,000s of
 * numbers), every other member becomes a jansson value parsed from its
 * own text (already checked), in document order. */
typedef struct job_body {
    bool is_object;
    json_t *members;         /* every member but "model"; "model": true */
    geo_poly *model;         /* NULL: absent, or invalid (model_err) */
    geo_err model_err;
    proto_read_report rep;
} job_body;

/* 0, or -1 with j->error set (bad JSON, or out of memory). */
static int read_job_body(http_req *r, proto_jpull *j, job_body *b)
{
    const char *text = r->body ? r->body : "";
    proto_jpull_init(j, text, r->len);
    memset(b, 0, sizeof *b);
    proto_jtok t = proto_jpull_next(j);
    if (t == PROTO_JT_ERROR)
        return -1;
    if (t != PROTO_JT_OBJECT)
        return proto_jpull_skip(j) == PROTO_JT_ERROR ||
                       proto_jpull_next(j) == PROTO_JT_ERROR ? -1 : 0;
    b->is_object = true;
    b->members = json_object();
    if (!b->members)
        goto oom;
    while ((t = proto_jpull_next(j)) == PROTO_JT_KEY) {
        char key[64];
        bool is_model = strcmp(j->str, "model") == 0;
        json_t *v;
        char *long_key = NULL;
        if (j->str_len < sizeof key)
            memcpy(key, j->str, j->str_len + 1);
        else if (!(long_key = strdup(j->str)))
            goto oom;
        if (is_model) {
            bool syntax;
            b->model = proto_model_from_jpull(j, proto_jpull_next(j), NULL,
                                              "model", &b->rep, &syntax,
                                              &b->model_err);
            if (syntax)
                return -1;
            v = json_true();
        } else {
            proto_jpull_next(j);
            size_t start = j->tok_start;
            if (proto_jpull_skip(j) == PROTO_JT_ERROR) {
                free(long_key);
                return -1;
            }
            v = json_loadb(text + start, j->tok_end - start,
                           JSON_DECODE_ANY | JSON_REJECT_DUPLICATES, NULL);
        }
        int e = !v || json_object_set_new(b->members,
                                          long_key ? long_key : key, v) < 0;
        free(long_key);
        if (e)
            goto oom;
    }
    if (t == PROTO_JT_ERROR || proto_jpull_next(j) == PROTO_JT_ERROR)
        return -1;
    return 0;
oom:
    j->error.code = -ENOMEM;
    return -1;
}

static void job_body_clear(job_body *b, proto_jpull *j)
{
    json_decref(b->members);
    geo_poly_free(b->model);
    proto_jpull_clear(j);
}

static void add_error(json_t *errors, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void add_error(json_t *errors, const char *path, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    json_array_append_new(errors,
                          json_pack("{s:s, s:s}", "path", path, "message", msg));
}

/* "path: message" from a geo_err into errors. */
static void add_geo_error(json_t *errors, const geo_err *e)
{
    json_t *entry = http_error_entry(e->msg);
    if (entry)
        json_array_append_new(errors, entry);
}

/* What the store cannot hold, and op arguments that name a vertex or
 * facet the model lacks, are the client's error: named at submission
 * rather than a 500 or a failed job later. pl may be NULL (not parsed). */
static void check_model(json_t *errors, const geo_poly *poly,
                        const proto_pipeline *pl, const char *where)
{
    geo_err err = {{0}};
    if (proto_fmb1_check(poly, &err) < 0) {
        char msg[600];
        snprintf(msg, sizeof msg, "%s.%s", where, err.msg);
        json_array_append_new(errors, http_error_entry(msg));
    }
    if (pl && runner_check_model(pl, poly, &err) < 0)
        add_geo_error(errors, &err);
}

static bool valid_idem_key(const char *k)
{
    size_t n = strlen(k);
    if (n == 0 || n > 255)
        return false;
    for (size_t i = 0; i < n; i++)
        if (!isgraph((unsigned char)k[i]))
            return false;
    return true;
}

/* The two meshes of a stitch job as one model of two pieces (mesh 1's
 * vertices and facets first), which the stitch operation splits again;
 * NULL with the errors added. */
static geo_poly *meshes_union(const json_t *meshes, proto_read_report *rep,
                              json_t *errors)
{
    geo_poly *m[2] = {NULL, NULL}, *u = NULL;
    geo_err err = {{0}};
    for (size_t k = 0; k < 2; k++) {
        char where[32];
        snprintf(where, sizeof where, "meshes[%zu]", k);
        m[k] = proto_model_from_json_ex(json_array_get(meshes, k), NULL, where,
                                        rep, &err);
        if (!m[k])
            add_geo_error(errors, &err);
    }
    if (m[0] && m[1]) {
        u = geo_poly_copy(m[0]);
        uint32_t off = m[0]->nverts;
        bool ok = u && geo_poly_reserve(u, (size_t)off + m[1]->nverts,
                                        (size_t)u->nfacets + m[1]->nfacets,
                                        (size_t)geo_poly_ncorners(u) +
                                            geo_poly_ncorners(m[1])) == 0;
        for (uint32_t v = 0; ok && v < m[1]->nverts; v++)
            geo_poly_add_vertex(u, m[1]->verts[v]);
        for (uint32_t f = 0; ok && f < m[1]->nfacets; f++) {
            int64_t nf = geo_poly_add_facet(u, geo_poly_facet(m[1], f),
                                            geo_poly_facet_size(m[1], f));
            uint32_t *fv = u->fidx + u->fstart[nf];
            for (uint32_t i = 0; i < geo_poly_facet_size(m[1], f); i++)
                fv[i] += off;
            memcpy(u->planes[nf], m[1]->planes[f], sizeof u->planes[0]);
        }
        if (!ok) {
            u = geo_poly_free(u);
            add_error(errors, "meshes", "out of memory");
        }
    }
    geo_poly_free(m[0]);
    geo_poly_free(m[1]);
    return u;
}

/* Queues a validated job and answers 202 (or the queue's refusal): the
 * one tail of both forms of POST /v1/jobs. poly, frep and pl stay the
 * caller's. */
static enum MHD_Result submit_and_reply(http_req *r, const geo_poly *poly,
                                        const json_t *frep,
                                        const proto_pipeline *pl,
                                        job_priority prio, const char *label,
                                        const char *idem, uint64_t idem_hash,
                                        const proto_read_report *rep)
{
    http_env *env = r->env;
    enum MHD_Result res;
    geo_err err = {{0}};
    job_request rq = {
        .model = poly, .frep = frep, .pipeline = pl, .priority = prio,
        .source = "http", .label = label, .idem_key = idem,
        /* only a keyed request is ever compared: no other hashes 464 KB */
        .idem_hash = idem_hash,
    };
    job_rec job;
    bool replayed = false;
    int rc = job_submit(env->s, env->pool, atomic_load(&env->queue_size), &rq,
                        &job, &replayed, &err);
    if (rc == -EAGAIN) {
        metrics_queue_full(env->m);
        const char *h[] = {"Retry-After", "1", NULL};
        res = http_problem(r, 503, "queue-full", "Service Unavailable", NULL,
                           h, "%s; retry later", err.msg);
    } else if (rc == -ENOTCONN) {
        /* nothing accepted: the client retries (with its key, safely) */
        const char *h[] = {"Retry-After", "2", NULL};
        res = http_problem(r, 503, "store-unavailable", "Service Unavailable",
                           NULL, h, "%s; retry later", err.msg);
    } else if (rc == -EEXIST) {
        res = http_problem(r, 422, "idempotency-key-reused",
                           "Unprocessable Content", NULL, NULL, "%s", err.msg);
    } else if (rc == -ENOSPC) {
        log_msg(LOG_ERR, NULL, "submit: %s", err.msg);
        const char *h[] = {"Retry-After", "5", NULL};
        res = http_problem(r, 503, "store-full", "Service Unavailable", NULL,
                           h, "the job store cannot take the job now (%s); "
                           "retry later", err.msg);
    } else if (rc == -ERANGE || rc == -EINVAL) {
        /* a limit of the stored form the checks above did not foresee */
        res = http_problem(r, 422, "invalid-job", "Unprocessable Content",
                           json_pack("[o]", http_error_entry(err.msg)), NULL,
                           "%s", err.msg);
    } else if (rc < 0) {
        log_msg(LOG_ERR, NULL, "submit: %s", err.msg);
        res = http_problem(r, 500, "submit-failed", "Internal Server Error",
                           NULL, NULL, "%s", err.msg);
    } else {
        memcpy(r->id, job.id, sizeof r->id);
        char loc[64];
        snprintf(loc, sizeof loc, "/v1/jobs/%s", job.id);
        const char *h[] = {"Location", loc,
                           replayed ? "Idempotent-Replayed" : NULL, "true",
                           NULL};
        json_t *extra = NULL;
        char dep[256];
        bool deprecated = proto_pipeline_deprecations(pl, dep, sizeof dep);
        if (rep->plane_mismatches || deprecated) {
            json_t *w = json_array();
            if (rep->plane_mismatches)
                json_array_append_new(w, json_string(rep->first));
            if (deprecated)
                json_array_append_new(w, json_string(dep));
            extra = json_pack("{s:o}", "warnings", w);
        }
        if (deprecated && !replayed)
            log_msg(LOG_WARNING, job.id, "%s", dep);
        if (!replayed && poly)
            log_msg(LOG_INFO, job.id, "queued (%u vertices, %u facets, "
                    "%zu ops, priority %s)", poly->nverts, poly->nfacets,
                    pl->nops, prio == JOB_PRIO_HIGH ? "high" : "normal");
        else if (!replayed)
            log_msg(LOG_INFO, job.id, "queued (frep-object, %zu ops, "
                    "priority %s)", pl->nops,
                    prio == JOB_PRIO_HIGH ? "high" : "normal");
        res = reply_job(r, 202, &job, h, extra);
        job_rec_clear(&job);
    }
    return res;
}

/* The 422 of a request with errors (stolen): the first in the detail. */
static enum MHD_Result invalid_job(http_req *r, json_t *errors)
{
    const json_t *first = json_array_get(errors, 0);
    const char *path = json_string_value(json_object_get(first, "path"));
    const char *msg = json_string_value(json_object_get(first, "message"));
    size_t n = json_array_size(errors);
    char detail[768];
    snprintf(detail, sizeof detail, "%s%s%s%s", path && *path ? path : "",
             path && *path ? ": " : "", msg ? msg : "invalid",
             n > 1 ? " (and more, see errors)" : "");
    return http_problem(r, 422, "invalid-job", "Unprocessable Content",
                        errors, NULL, "%s", detail);
}

/* ---- POST /v1/jobs?format=NAME: the model file itself as the body ----
 * For curl users and the viewer's drop zone: the model in any format
 * facetd reads, the job's other members as query parameters (pipeline,
 * priority, label), checked and answered exactly as the JSON form's. */

/* The query's pipeline: a JSON value ('["inspect"]', '"correct"'), or op
 * names separated by commas ("merge,inspect"). NULL when it is neither
 * (the caller says why). */
static json_t *pipeline_query(const char *q)
{
    while (*q == ' ')
        q++;
    if (*q == '[' || *q == '{' || *q == '"')
        return json_loads(q, JSON_DECODE_ANY | JSON_REJECT_DUPLICATES, NULL);
    json_t *a = json_array();
    const char *p = q;
    while (a) {
        size_t n = strcspn(p, ",");
        if (n == 0 || json_array_append_new(a, json_stringn(p, n)) < 0) {
            json_decref(a);
            return NULL;
        }
        if (!p[n])
            break;
        p += n + 1;
    }
    return a;
}

typedef struct query_check {
    json_t *errors;
} query_check;

static enum MHD_Result unknown_arg(void *cls, enum MHD_ValueKind kind,
                                   const char *key, const char *value)
{
    query_check *qc = cls;
    static const char *const known[] = {"format", "pipeline", "priority",
                                        "label"};
    for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
        if (strcmp(key, known[i]) == 0)
            return MHD_YES;
    add_error(qc->errors, key, "unknown parameter (expected format, "
              "pipeline, priority, label)");
    return MHD_YES;
}

/* True when a file of format fmt may come as ct: the format's own media
 * type, application/octet-stream, or (no header) nothing said. */
bool http_model_content_type_ok(const char *fmt_name, const char *ct)
{
    proto_format fmt = proto_format_from_name(fmt_name);
    if (!ct || fmt == PROTO_FMT_UNKNOWN)
        return true; /* the handler answers a bad format by name */
    while (*ct == ' ')
        ct++;
    size_t n = strcspn(ct, "; ");
    const char *mime = proto_format_mime(fmt);
    return (n == strlen(mime) && strncasecmp(ct, mime, n) == 0) ||
           (n == 24 && strncasecmp(ct, "application/octet-stream", 24) == 0);
}

static enum MHD_Result post_job_file(http_req *r, const char *fmt_name)
{
    proto_format fmt = proto_format_from_name(fmt_name);
    if (fmt == PROTO_FMT_UNKNOWN || fmt == PROTO_FMT_ASE)
        return http_problem(r, 400, "bad-argument", "Bad Request", NULL, NULL,
                            "format: expected json, poly, obj, stl, ply, "
                            "fmb1 or off (a format facetd reads)");
    const char *idem = http_header(r, "Idempotency-Key");
    if (idem && !valid_idem_key(idem))
        return http_problem(r, 400, "bad-idempotency-key", "Bad Request",
                            NULL, NULL, "Idempotency-Key must be 1 to 255 "
                            "visible ASCII characters");
    query_check qc = {json_array()};
    MHD_get_connection_values(r->conn, MHD_GET_ARGUMENT_KIND, unknown_arg,
                              &qc);
    json_t *errors = qc.errors;
    geo_err err = {{0}};
    proto_pipeline pl = {0};
    bool have_pipeline = false;
    const char *pq = http_arg(r, "pipeline");
    json_t *pv = pq ? pipeline_query(pq) : json_string("correct");
    if (!pv)
        add_error(errors, "pipeline", "expected op names separated by commas "
                  "or a JSON pipeline");
    else if (proto_pipeline_from_json(pv, "pipeline", &pl, &err) < 0)
        add_geo_error(errors, &err);
    else if (runner_check_input(&pl, false, &err) < 0)
        add_geo_error(errors, &err);
    else
        have_pipeline = true;
    json_decref(pv);
    if (have_pipeline && pl.nops > 0 && pl.ops[0].kind == PROTO_OP_STITCH)
        add_error(errors, "pipeline", "stitch joins two meshes: post them "
                  "as 'meshes' in the JSON form");
    job_priority prio = JOB_PRIO_NORMAL;
    const char *pr = http_arg(r, "priority");
    if (pr && strcmp(pr, "high") == 0)
        prio = JOB_PRIO_HIGH;
    else if (pr && strcmp(pr, "normal") != 0)
        add_error(errors, "priority", "expected \"normal\" or \"high\"");
    const char *label = http_arg(r, "label");
    if (label && strlen(label) >= JOB_LABEL_MAX)
        add_error(errors, "label", "longer than %d bytes", JOB_LABEL_MAX - 1);
    proto_read_report rep = {0};
    geo_poly *poly = NULL;
    if (r->len == 0) {
        add_error(errors, "model", "required: the model file as the body");
    } else {
        poly = proto_model_read_mem_ex(r->body, r->len, fmt, NULL, &rep,
                                       &err);
        if (!poly) {
            geo_err_prefix(&err, "model");
            add_geo_error(errors, &err);
        } else {
            check_model(errors, poly, have_pipeline ? &pl : NULL, "model");
        }
    }
    enum MHD_Result res;
    if (json_array_size(errors) > 0) {
        res = invalid_job(r, errors);
    } else {
        json_decref(errors);
        /* the same bytes under another pipeline are another request */
        uint64_t h = 0;
        if (idem) {
            h = job_hash64(r->body, r->len);
            const char *parts[] = {fmt_name, pq, pr, label};
            for (size_t i = 0; i < 4; i++)
                h = h * 1099511628211ull ^
                    (parts[i] ? job_hash64(parts[i], strlen(parts[i])) : i);
        }
        res = submit_and_reply(r, poly, NULL, &pl, prio, label, idem, h,
                               &rep);
    }
    geo_poly_free(poly);
    if (have_pipeline || pl.ops)
        proto_pipeline_free(&pl);
    return res;
}

enum MHD_Result http_post_job(http_req *r)
{
    const char *fmt_name = http_arg(r, "format");
    if (fmt_name)
        return post_job_file(r, fmt_name);
    const char *idem = http_header(r, "Idempotency-Key");
    if (idem && !valid_idem_key(idem))
        return http_problem(r, 400, "bad-idempotency-key", "Bad Request",
                            NULL, NULL, "Idempotency-Key must be 1 to 255 "
                            "visible ASCII characters");
    proto_jpull j;
    job_body jb;
    if (read_job_body(r, &j, &jb) < 0) {
        enum MHD_Result res = http_malformed_json(r, &j.error);
        job_body_clear(&jb, &j);
        return res;
    }
    if (!jb.is_object) {
        job_body_clear(&jb, &j);
        return http_problem(r, 422, "invalid-job", "Unprocessable Content",
                            NULL, NULL, "the body must be a JSON object");
    }
    json_t *root = jb.members;
    json_t *errors = json_array();
    static const char *const known[] = {"model", "frep", "meshes", "pipeline",
                                        "priority", "label"};
    const char *key;
    json_t *val;
    json_object_foreach(root, key, val) {
        bool ok = false;
        for (size_t i = 0; i < sizeof known / sizeof known[0]; i++)
            ok |= strcmp(key, known[i]) == 0;
        if (!ok)
            add_error(errors, key, "unknown member (expected model, "
                      "frep, pipeline, priority, label)");
    }
    const json_t *model = json_object_get(root, "model");
    const json_t *frep = json_object_get(root, "frep");
    int inputs = !!model + !!frep + !!json_object_get(root, "meshes");
    if (inputs == 0)
        add_error(errors, "model", "required: the facet-model/1 to process "
                  "(or a frep-object/1 as 'frep')");
    else if (inputs > 1)
        add_error(errors, "", "give exactly one of model, frep, meshes");
    const json_t *meshes = json_object_get(root, "meshes");
    if (meshes && json_array_size(meshes) != 2)
        add_error(errors, "meshes", "expected an array of two facet-model/1 "
                  "objects (the open meshes to stitch)");
    proto_pipeline pl = {0};
    json_t *pv = json_object_get(root, "pipeline");
    /* without a pipeline: the post-scan correction of a model, the
     * triangulation (at its defaults) of a frep; two meshes are stitched
     * first, then inspected */
    json_t *pdefault = pv       ? NULL
                       : frep   ? json_pack("[s]", "triangulate")
                       : meshes ? json_pack("[s, s]", "stitch", "inspect")
                                : json_string("correct");
    geo_err err = {{0}};
    bool have_pipeline = false;
    if (proto_pipeline_from_json(pv ? pv : pdefault, "pipeline", &pl, &err) < 0)
        add_geo_error(errors, &err);
    else if (inputs == 1 && runner_check_input(&pl, frep != NULL, &err) < 0)
        add_geo_error(errors, &err);
    else
        have_pipeline = true;
    if (have_pipeline && meshes &&
        (pl.nops == 0 || pl.ops[0].kind != PROTO_OP_STITCH))
        add_error(errors, "pipeline", "a job with meshes must start with "
                  "stitch (it joins the two meshes into one model)");
    json_decref(pdefault);
    if (frep) {
        /* validated here, stored as JSON (job_submit.h) */
        geo_frep *f = proto_frep_from_json(frep, NULL, "frep", &err);
        if (!f)
            add_geo_error(errors, &err);
        geo_frep_free(f);
    }
    job_priority prio = JOB_PRIO_NORMAL;
    const json_t *pr = json_object_get(root, "priority");
    if (pr) {
        const char *s = json_string_value(pr);
        if (s && strcmp(s, "high") == 0)
            prio = JOB_PRIO_HIGH;
        else if (!s || strcmp(s, "normal") != 0)
            add_error(errors, "priority", "expected \"normal\" or \"high\"");
    }
    const char *label = NULL;
    const json_t *lb = json_object_get(root, "label");
    if (lb) {
        label = json_string_value(lb);
        if (!label)
            add_error(errors, "label", "expected a string");
        else if (strlen(label) >= JOB_LABEL_MAX)
            add_error(errors, "label", "longer than %d bytes",
                      JOB_LABEL_MAX - 1);
    }
    /* the model read in place (now owned here), or the union of meshes */
    geo_poly *poly = jb.model;
    proto_read_report rep = jb.rep;
    jb.model = NULL;
    if (model && !poly)
        add_geo_error(errors, &jb.model_err);
    else if (meshes && json_array_size(meshes) == 2)
        poly = meshes_union(meshes, &rep, errors);
    if (poly)
        check_model(errors, poly, have_pipeline ? &pl : NULL,
                    meshes ? "meshes" : "model");
    enum MHD_Result res;
    if (json_array_size(errors) > 0) {
        res = invalid_job(r, errors);
        errors = NULL;
        goto out;
    }
    res = submit_and_reply(r, poly, frep, &pl, prio, label, idem,
                           idem ? job_hash64(r->body ? r->body : "", r->len)
                                : 0,
                           &rep);
out:
    json_decref(errors);
    geo_poly_free(poly);
    if (have_pipeline || pl.ops)
        proto_pipeline_free(&pl);
    job_body_clear(&jb, &j);
    return res;
}

/* Parses ?wait= (seconds, fractions allowed) into ms; -1 when invalid. */
static int64_t wait_arg(http_req *r)
{
    const char *w = http_arg(r, "wait");
    if (!w)
        return 0;
    char *end;
    double s = strtod(w, &end);
    if (end == w || *end || !isfinite(s) || s < 0)
        return -1;
    uint64_t cap = atomic_load(&r->env->max_wait_ms);
    double ms = s * 1000.0;
    return ms > (double)cap ? (int64_t)cap : (int64_t)ms;
}

enum MHD_Result http_get_job(http_req *r)
{
    if (!r->waiting) {
        int64_t wait = wait_arg(r);
        if (wait < 0)
            return http_problem(r, 400, "bad-argument", "Bad Request", NULL,
                                NULL, "wait: expected a number of seconds "
                                "≥ 0");
        r->w.deadline = job_mono_ms() + wait;
    }
    job_rec j;
    geo_err err;
    int rc;
again:
    r->w.seq = http_hub_seq(r->srv->hub, r->id);
    rc = store_get(r->env->s, r->id, &j, &err);
    if (rc < 0)
        return store_failure(r, rc, &err);
    if (!job_state_terminal(j.state) && job_mono_ms() < r->w.deadline) {
        r->w.conn = r->conn;
        memcpy(r->w.id, j.id, sizeof r->w.id);
        r->w.progress = false;
        bool first = !r->waiting;
        r->waiting = true;
        rc = http_hub_suspend(r->srv->hub, &r->w,
                              atomic_load(&r->env->max_waiters));
        if (rc == 0) {
            job_rec_clear(&j);
            return MHD_YES;
        }
        if (rc == -ESTALE) {
            r->waiting = !first;
            job_rec_clear(&j);
            goto again;
        }
        if (rc == -EAGAIN && first) {
            job_rec_clear(&j);
            const char *h[] = {"Retry-After", "1", NULL};
            return http_problem(r, 429, "too-many-waiters",
                                "Too Many Requests", NULL, h,
                                "too many clients are waiting; poll without "
                                "wait= or retry later");
        }
    }
    char etag[40];
    snprintf(etag, sizeof etag, "W/\"v%lld\"", (long long)j.version);
    const char *h[] = {"ETag", etag, "Cache-Control", "no-cache", NULL};
    enum MHD_Result res;
    if (http_not_modified(r, etag))
        res = http_reply(r, 304, NULL, (char *)"", 0, false, h);
    else
        res = reply_job(r, 200, &j, h, NULL);
    job_rec_clear(&j);
    return res;
}

enum MHD_Result http_delete_job(http_req *r)
{
    http_env *env = r->env;
    job_rec j;
    geo_err err;
    int rc = store_cancel(env->s, r->id, &j, &err);
    if (rc == -EBUSY) {
        /* Already finished: DELETE removes the job and its results. */
        job_rec_clear(&j);
        rc = store_remove(env->s, r->id, &err);
        if (rc == -EBUSY) /* it was requeued meanwhile: cancel again */
            return http_delete_job(r);
        if (rc < 0)
            return store_failure(r, rc, &err);
        log_msg(LOG_INFO, r->id, "deleted");
        http_server_job_changed(r->srv, r->id, false);
        return http_reply(r, 204, NULL, (char *)"", 0, false, NULL);
    }
    if (rc < 0)
        return store_failure(r, rc, &err);
    enum MHD_Result res;
    if (j.state == JOB_RUNNING) {
        if (env->pool)
            job_pool_cancel(env->pool, j.id);
        log_msg(LOG_INFO, j.id, "cancel requested");
        res = reply_job(r, 202, &j, NULL, NULL);
    } else {
        log_msg(LOG_INFO, j.id, "canceled before it started");
        res = reply_job(r, 200, &j, NULL, NULL);
    }
    http_server_job_changed(r->srv, r->id, false);
    job_rec_clear(&j);
    return res;
}

static bool valid_source(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= JOB_SOURCE_MAX)
        return false;
    for (size_t i = 0; i < n; i++)
        if (!isalnum((unsigned char)s[i]) && !strchr(":._-", s[i]))
            return false;
    return true;
}

enum MHD_Result http_list_jobs(http_req *r)
{
    store_filter f = {.state = -1, .limit = 100};
    const char *st = http_arg(r, "status"), *src = http_arg(r, "source"),
               *lim = http_arg(r, "limit"), *after = http_arg(r, "after");
    if (st && (f.state = job_state_from_name(st)) < 0)
        return http_problem(r, 400, "bad-argument", "Bad Request", NULL, NULL,
                            "status: expected queued, running, succeeded, "
                            "failed or canceled");
    if (src && !valid_source(src))
        return http_problem(r, 400, "bad-argument", "Bad Request", NULL, NULL,
                            "source: expected letters, digits and :._-");
    f.source = src;
    if (lim) {
        char *end;
        long v = strtol(lim, &end, 10);
        if (end == lim || *end || v < 1 || v > 1000)
            return http_problem(r, 400, "bad-argument", "Bad Request", NULL,
                                NULL, "limit: expected 1 to 1000");
        f.limit = (unsigned)v;
    }
    if (after && !job_id_valid(after))
        return http_problem(r, 400, "bad-argument", "Bad Request", NULL, NULL,
                            "after: expected a job id");
    f.after = after;
    job_rec *v;
    size_t n;
    geo_err err;
    int rc = store_list(r->env->s, &f, &v, &n, &err);
    if (rc < 0)
        return store_failure(r, rc, &err);
    json_t *arr = json_array();
    for (size_t i = 0; i < n; i++) {
        json_array_append_new(arr, job_to_json(&v[i]));
    }
    json_t *next = json_null();
    if (n == f.limit) {
        char url[256];
        snprintf(url, sizeof url, "/v1/jobs?limit=%u&after=%s%s%s%s%s",
                 f.limit, v[n - 1].id, st ? "&status=" : "", st ? st : "",
                 src ? "&source=" : "", src ? src : "");
        json_decref(next);
        next = json_string(url);
    }
    for (size_t i = 0; i < n; i++)
        job_rec_clear(&v[i]);
    free(v);
    json_t *o = json_object();
    json_object_set_new(o, "jobs", arr);
    json_object_set_new(o, "next", next);
    return http_reply_json(r, 200, o, NULL);
}

/* Reads the job and answers 404/409 unless it succeeded; 0 to go on. */
static int need_result(http_req *r, job_rec *j, enum MHD_Result *res)
{
    geo_err err;
    int rc = store_get(r->env->s, r->id, j, &err);
    if (rc < 0) {
        *res = store_failure(r, rc, &err);
        return -1;
    }
    if (j->state != JOB_SUCCEEDED) {
        *res = http_problem(r, 409, "no-result", "Conflict", NULL, NULL,
                            "job %s is %s; results exist once it has "
                            "succeeded", j->id, job_state_name(j->state));
        job_rec_clear(j);
        return -1;
    }
    return 0;
}

enum MHD_Result http_get_model(http_req *r)
{
    const char *name = http_arg(r, "format");
    proto_format fmt = name ? proto_format_from_name(name) : PROTO_FMT_JSON;
    if (fmt == PROTO_FMT_UNKNOWN) {
        char list[256];
        proto_format_list(list, sizeof list);
        return http_problem(r, 400, "bad-argument", "Bad Request", NULL, NULL,
                            "format: expected %s", list);
    }
    /* which=input: the model as submitted (the viewer's before/after),
     * there from submission on; the result only once the job succeeded */
    const char *which = http_arg(r, "which");
    bool input = which && strcmp(which, "input") == 0;
    if (which && !input && strcmp(which, "result") != 0)
        return http_problem(r, 400, "bad-argument", "Bad Request", NULL, NULL,
                            "which: expected result or input");
    job_rec j;
    enum MHD_Result res;
    if (input) {
        geo_err gerr;
        int grc = store_get(r->env->s, r->id, &j, &gerr);
        if (grc < 0)
            return store_failure(r, grc, &gerr);
    } else if (need_result(r, &j, &res) < 0) {
        return res;
    }
    char etag[64], disp[96];
    /* an input never changes: the job's id names it */
    snprintf(etag, sizeof etag, "\"%016llx-%s%s\"",
             input ? (unsigned long long)job_hash64(j.id, strlen(j.id))
                   : (unsigned long long)j.result_hash,
             input ? "input-" : "", proto_format_name(fmt));
    const char *ext = fmt == PROTO_FMT_STL_ASCII   ? "stl"
                      : fmt == PROTO_FMT_PLY_ASCII ? "ply"
                      : fmt == PROTO_FMT_FMB1      ? "fmb"
                                                   : proto_format_name(fmt);
    snprintf(disp, sizeof disp, "inline; filename=\"%s%s.%s\"", j.id,
             input ? "-input" : "", ext);
    job_rec_clear(&j);
    const char *h[] = {"ETag", etag, "Cache-Control", "private, max-age=3600",
                       "Content-Disposition", disp, NULL};
    if (http_not_modified(r, etag))
        return http_reply(r, 304, NULL, (char *)"", 0, false, h);
    void *blob;
    size_t len;
    geo_err err;
    int rc = store_get_blob(r->env->s, r->id,
                            input ? STORE_BLOB_INPUT : STORE_BLOB_MODEL,
                            &blob, &len, &err);
    if (rc < 0)
        return store_failure(r, rc, &err);
    if (input && (len < 4 || memcmp(blob, "FMB1", 4) != 0)) {
        /* a frep-object/1 input is stored as its JSON (job_submit.h) */
        free(blob);
        return http_problem(r, 409, "no-input-model", "Conflict", NULL, NULL,
                            "job %s was given a frep-object, not a model",
                            r->id);
    }
    if (fmt == PROTO_FMT_FMB1)
        return http_reply(r, 200, proto_format_mime(fmt), blob, len, true, h);
    geo_poly *p = proto_model_read_mem(blob, len, PROTO_FMT_FMB1, NULL, &err);
    free(blob);
    if (!p) {
        log_msg(LOG_ERR, r->id, "stored result unreadable: %s", err.msg);
        return http_problem(r, 500, "store-error", "Internal Server Error",
                            NULL, NULL, "stored result: %s", err.msg);
    }
    char *out;
    size_t olen;
    rc = proto_model_write_mem(p, fmt, &out, &olen, &err);
    geo_poly_free(p);
    if (rc < 0)
        return http_problem(r, 500, "write-failed", "Internal Server Error",
                            NULL, NULL, "%s", err.msg);
    return http_reply(r, 200, proto_format_mime(fmt), out, olen, true, h);
}

enum MHD_Result http_get_stats(http_req *r)
{
    job_rec j;
    enum MHD_Result res;
    if (need_result(r, &j, &res) < 0)
        return res;
    char etag[64];
    snprintf(etag, sizeof etag, "\"%016llx-stats\"",
             (unsigned long long)j.result_hash);
    job_rec_clear(&j);
    const char *h[] = {"ETag", etag, "Cache-Control", "private, max-age=3600",
                       NULL};
    if (http_not_modified(r, etag))
        return http_reply(r, 304, NULL, (char *)"", 0, false, h);
    void *blob;
    size_t len;
    geo_err err;
    int rc = store_get_blob(r->env->s, r->id, STORE_BLOB_STATS, &blob, &len,
                            &err);
    if (rc < 0)
        return store_failure(r, rc, &err);
    return http_reply(r, 200, "application/json", blob, len, true, h);
}
