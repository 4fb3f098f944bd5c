/* http_ops.c — the operational routes: /livez, /readyz, /metrics,
 * /v1/version, /v1/openapi.json, and the synchronous POST /v1/inspect.
 *
 * /livez answers 200 while the process serves HTTP at all; /readyz
 * answers 200 only when start-up is complete, shutdown has not begun, the
 * store answers and the workers take jobs (503 otherwise, with the failing
 * checks listed), so a load balancer stops sending work to a node that is
 * starting, stopping or broken. */
#include "http.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "version.h"
#include "log.h"
#include "model_io.h"
#include "runner.h"

enum MHD_Result http_livez(http_req *r)
{
    return http_reply(r, 200, "text/plain; charset=utf-8", (char *)"ok\n", 3,
                      false, NULL);
}

enum MHD_Result http_readyz(http_req *r)
{
    http_env *env = r->env;
    json_t *failed = json_array();
    if (!atomic_load(&env->ready))
        json_array_append_new(failed, json_pack("{s:s,s:s}", "path", "startup",
                                                "message", "starting or "
                                                "stopping"));
    geo_err err;
    if (store_ping(env->s, &err) < 0)
        json_array_append_new(failed, json_pack("{s:s,s:s}", "path", "store",
                                                "message", err.msg));
    if (!env->pool || !job_pool_healthy(env->pool))
        json_array_append_new(failed, json_pack("{s:s,s:s}", "path",
                                                "workers", "message",
                                                "not taking jobs"));
    if (json_array_size(failed) == 0) {
        json_decref(failed);
        const char *h[] = {"Cache-Control", "no-store", NULL};
        return http_reply(r, 200, "text/plain; charset=utf-8",
                          (char *)"ready\n", 6, false, h);
    }
    const char *h[] = {"Retry-After", "1", "Cache-Control", "no-store", NULL};
    return http_problem(r, 503, "not-ready", "Service Unavailable", failed, h,
                        "not ready to take jobs");
}

enum MHD_Result http_metrics(http_req *r)
{
    http_env *env = r->env;
    metrics_gauges g = {0};
    g.store_ok = store_count(env->s, &g.counts, NULL) == 0;
    g.workers = env->workers;
    g.busy = env->pool ? job_pool_busy(env->pool) : 0;
    g.paused = env->pool ? job_pool_paused(env->pool) : 0;
    g.waiters = http_hub_count(r->srv->hub);
    g.queue_size = atomic_load(&env->queue_size);
    g.ready = atomic_load(&env->ready);
    g.node = store_node(env->s);
    scanners_get_metrics(env->sc, &g.scan);
    char *text;
    size_t len;
    if (metrics_render(env->m, &g, &text, &len) < 0)
        return http_problem(r, 500, "out-of-memory", "Internal Server Error",
                            NULL, NULL, "metrics could not be rendered");
    const char *h[] = {"Cache-Control", "no-store", NULL};
    return http_reply(r, 200, "text/plain; version=0.0.4; charset=utf-8", text,
                      len, true, h);
}

enum MHD_Result http_version(http_req *r)
{
    json_t *ops = json_array(), *fmts = json_array();
    for (int k = 0; k < PROTO_OP_COUNT; k++)
        json_array_append_new(ops,
                                  json_string(proto_op_name((proto_op_kind)k)));
    proto_format f;
    for (size_t i = 0; (f = proto_format_at(i)) != PROTO_FMT_UNKNOWN; i++)
        json_array_append_new(fmts, json_string(proto_format_name(f)));
    json_t *o = json_pack("{s:s, s:s, s:s, s:s, s:o, s:o}", "name", "facetd",
                          "version", FACET_VERSION, "api", "v1", "store",
                          r->env->s->ops->name, "ops", ops, "model_formats",
                          fmts);
    return http_reply_json(r, 200, o, NULL);
}

enum MHD_Result http_openapi(http_req *r)
{
    size_t len;
    const char *doc = http_openapi_doc(&len);
    char etag[40];
    snprintf(etag, sizeof etag, "\"%016llx\"",
             (unsigned long long)job_hash64(doc, len));
    const char *h[] = {"ETag", etag, NULL};
    if (http_not_modified(r, etag))
        return http_reply(r, 304, NULL, (char *)"", 0, false, h);
    return http_reply(r, 200, "application/json", (char *)doc, len, false, h);
}

enum MHD_Result http_post_inspect(http_req *r)
{
    json_error_t je;
    json_t *root = json_loadb(r->body ? r->body : "", r->len,
                              JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        json_t *errors = json_pack("[{s:s, s:s, s:i, s:i}]", "path", "",
                                   "message", je.text, "line",
                                   (json_int_t)je.line, "column",
                                   (json_int_t)je.column);
        return http_problem(r, 400, "malformed-json", "Bad Request", errors,
                            NULL, "line %d, column %d: %s", je.line,
                            je.column, je.text);
    }
    /* The body is the model itself, or {"model": ...} as for jobs. */
    const json_t *m = json_object_get(root, "model");
    if (!m)
        m = root;
    geo_err err = {{0}};
    proto_limits lim;
    proto_limits_default(&lim);
    geo_poly *p = proto_model_from_json(m, &lim, m == root ? NULL : "model",
                                        &err);
    json_decref(root);
    if (!p)
        return http_problem(r, 422, "invalid-model", "Unprocessable Content",
                            json_pack("[o]", http_error_entry(err.msg)), NULL,
                            "%s", err.msg);
    unsigned cap = atomic_load(&r->env->inspect_max_facets);
    if (p->nfacets > cap) {
        unsigned n = p->nfacets;
        geo_poly_free(p);
        return http_problem(r, 413, "model-too-large", "Content Too Large",
                            NULL, NULL, "%u facets; synchronous inspection "
                            "takes at most %u (submit a job instead)", n, cap);
    }
    proto_op op = {.kind = PROTO_OP_INSPECT};
    proto_pipeline pl = {1, &op};
    json_t *stats = NULL, *summary = NULL;
    int rc = runner_run(&pl, &p, NULL, NULL, NULL, &stats, &summary, &err);
    geo_poly_free(p);
    json_decref(summary);
    if (rc < 0)
        return http_problem(r, 500, "inspect-failed", "Internal Server Error",
                            NULL, NULL, "%s", err.msg);
    json_t *report = json_incref(json_object_get(stats, "before"));
    json_decref(stats);
    return http_reply_json(r, 200, report, NULL);
}
