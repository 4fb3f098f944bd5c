/* http_ops.c — the operational routes: /livez, /readyz, /metrics,
 * /v1/version and /v1/openapi.json (POST /v1/inspect: http_inspect.c).
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
    char why[sizeof(geo_err)];
    if (env->pool && job_pool_store_error(env->pool, why, sizeof why))
        json_array_append_new(failed, json_pack("{s:s,s:s}", "path",
                                                "store", "message", why));
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
