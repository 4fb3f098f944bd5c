/* runner.c — the op table and the pipeline loop (runner.h).
 * Invariant: an entry exists in ops[] only for a kernel that is part of
 * this build; everything else about an op (its name, its parameters)
 * lives in proto/pipeline.c. */
#include "runner.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "stats.h"
#include "stats_json.h"

/* Runs one operation on *model (may replace it, freeing the old one).
 * Adds its report to *ret_report (a new object it creates) and summary
 * fields to summary. 0 or a negative errno with err set. */
typedef int (*op_fn)(const proto_op *op, geo_poly **model, const geo_ctx *ctx,
                     json_t **ret_report, json_t *summary, geo_err *err);

typedef struct op_entry {
    op_fn run;
    bool changes_model; /* false for read-only ops such as inspect */
} op_entry;

/* inspect (lib/stats.h): every statistic of the model, unchanged. */
static int run_inspect(const proto_op *op, geo_poly **model,
                       const geo_ctx *ctx, json_t **ret_report,
                       json_t *summary, geo_err *err)
{
    (void)op;
    geo_stats st;
    int r = geo_inspect(*model, NULL, ctx, &st, err);
    if (r < 0)
        return r;
    json_t *rep = proto_stats_to_json(&st);
    int e = !rep;
    e |= json_object_set_new(summary, "valid", json_boolean(st.valid));
    e |= json_object_set_new(summary, "closed", json_boolean(st.closed));
    e |= json_object_set_new(summary, "orientation",
                             json_string(geo_orientation_name(st.orientation)));
    e |= json_object_set_new(summary, "self_intersections",
                             json_integer((json_int_t)st.selfint.count));
    geo_stats_clear(&st);
    if (e) {
        json_decref(rep);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    *ret_report = rep;
    return 0;
}

static const op_entry ops[PROTO_OP_COUNT] = {
    [PROTO_OP_INSPECT] = {run_inspect, false},
};

bool runner_op_available(proto_op_kind op)
{
    return (unsigned)op < PROTO_OP_COUNT && ops[op].run != NULL;
}

bool runner_changes_model(const proto_pipeline *p)
{
    for (size_t i = 0; i < p->nops; i++)
        if (!runner_op_available(p->ops[i].kind) ||
            ops[p->ops[i].kind].changes_model)
            return true;
    return false;
}

int runner_check(const proto_pipeline *p, geo_err *err)
{
    for (size_t i = 0; i < p->nops; i++)
        if (!runner_op_available(p->ops[i].kind))
            return geo_err_set(err, -ENOTSUP,
                               "pipeline[%zu]: op '%s' is not available in "
                               "this build", i, proto_op_name(p->ops[i].kind));
    return 0;
}

/* Maps an operation's progress into its share of the whole run. */
typedef struct sub_progress {
    const geo_ctx *outer;
    double base, span;
} sub_progress;

static int sub_report(void *user, double fraction)
{
    sub_progress *s = user;
    if (fraction < 0)
        fraction = 0;
    if (fraction > 1)
        fraction = 1;
    return geo_ctx_progress(s->outer, s->base + s->span * fraction) < 0;
}

static double mono_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static int add_counts(json_t *summary, const char *suffix, const geo_poly *p)
{
    char k1[32], k2[32];
    snprintf(k1, sizeof k1, "vertices_%s", suffix);
    snprintf(k2, sizeof k2, "facets_%s", suffix);
    return json_object_set_new(summary, k1, json_integer(p->nverts)) |
           json_object_set_new(summary, k2, json_integer(p->nfacets));
}

int runner_run(const proto_pipeline *p, geo_poly **model, const geo_ctx *ctx,
               runner_op_timer timer, void *timer_user, json_t **ret_stats,
               json_t **ret_summary, geo_err *err)
{
    int r = runner_check(p, err);
    if (r < 0)
        return r;
    json_t *stats = json_object(), *list = json_array(),
           *summary = json_object();
    json_t *before = NULL, *after = NULL;
    bool changed = false;
    double t_start = mono_seconds();
    if (!stats || !list || !summary || add_counts(summary, "before", *model)) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    for (size_t i = 0; i < p->nops; i++) {
        const proto_op *op = &p->ops[i];
        sub_progress sp = {ctx, (double)i / (double)p->nops,
                           1.0 / (double)p->nops};
        geo_ctx sub = {0};
        if (ctx)
            sub = *ctx;
        sub.progress = sub_report;
        sub.user = &sp;
        if (geo_ctx_progress(ctx, sp.base) < 0) {
            r = geo_err_set(err, -ECANCELED, "canceled");
            goto fail;
        }
        json_t *report = NULL;
        double t0 = mono_seconds();
        r = ops[op->kind].run(op, model, &sub, &report, summary, err);
        double secs = mono_seconds() - t0;
        if (timer)
            timer(timer_user, op->kind, secs);
        if (r < 0) {
            json_decref(report);
            char where[64];
            snprintf(where, sizeof where, "pipeline[%zu] (%s)", i,
                     proto_op_name(op->kind));
            geo_err_prefix(err, where);
            goto fail;
        }
        changed |= ops[op->kind].changes_model;
        if (op->kind == PROTO_OP_INSPECT && report) {
            if (!before)
                before = json_incref(report);
            else if (changed) {
                json_decref(after);
                after = json_incref(report);
            }
        }
        json_t *entry = json_pack("{s:s, s:f, s:o}", "op",
                                  proto_op_name(op->kind), "ms", secs * 1e3,
                                  "report", report ? report : json_null());
        if (!entry || json_array_append_new(list, entry) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto fail;
        }
    }
    if (geo_ctx_progress(ctx, 1.0) < 0) {
        r = geo_err_set(err, -ECANCELED, "canceled");
        goto fail;
    }
    /* json_object_set_new consumes its value even when it fails. */
    int e = json_object_set_new(stats, "ops", list);
    e |= json_object_set_new(stats, "before", before ? before : json_null());
    e |= json_object_set_new(stats, "after", after ? after : json_null());
    list = before = after = NULL;
    e |= add_counts(summary, "after", *model);
    e |= json_object_set_new(summary, "ms",
                             json_real((mono_seconds() - t_start) * 1e3));
    if (e) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    *ret_stats = stats;
    *ret_summary = summary;
    return 0;
fail:
    json_decref(stats);
    json_decref(list);
    json_decref(summary);
    json_decref(before);
    json_decref(after);
    return r;
}
