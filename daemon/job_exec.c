/* job_exec.c — one job: stored bytes in, stored bytes out (job_exec.h).
 * The stored input is an FMB1 model or a frep-object/1 JSON text
 * (job_submit.h). Every failure leaves a message naming its place in
 * ret->error. */
#include "job_exec.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "frep_json.h"
#include "json_text.h"
#include "model_io.h"
#include "runner.h"

static void op_timer(void *user, proto_op_kind op, double seconds)
{
    if (user)
        metrics_op(user, op, seconds);
}

static int fail(job_outcome *ret, int r, const geo_err *err)
{
    ret->error = strdup(err->msg[0] ? err->msg : "failed");
    return r;
}

int job_exec(void *user, const job_rec *job, const void *input,
             size_t input_len, job_decoded *decoded, const geo_ctx *ctx,
             job_outcome *ret)
{
    geo_err err = {{0}};
    json_error_t je;
    json_t *pj = json_loads(job->pipeline ? job->pipeline : "", 0, &je);
    if (!pj) {
        geo_err_set(&err, -EINVAL, "stored pipeline: %s", je.text);
        return fail(ret, -EINVAL, &err);
    }
    proto_pipeline pl;
    int r = proto_pipeline_from_json(pj, "pipeline", &pl, &err);
    json_decref(pj);
    if (r < 0)
        return fail(ret, r, &err);
    geo_poly *model = NULL;
    json_t *stats = NULL, *summary = NULL;
    /* a read-only pipeline's result is its (FMB1) input: the store keeps
     * one copy (store_finish without a model). A primed input is the
     * model job_submit stored as FMB1, bit for bit what reading it back
     * gives (FMB1 keeps every double, a unit plane is kept as it is). */
    bool fmb1 = decoded || (input_len >= 4 && memcmp(input, "FMB1", 4) == 0);
    bool changes = !fmb1 || runner_changes_model(&pl);
    if (decoded) {
        model = decoded->data;
        decoded->data = NULL;
    } else if (fmb1) {
        model = proto_model_read_mem(input, input_len, PROTO_FMT_FMB1, NULL,
                                     &err);
    }
    if (fmb1) {
        if (!model) {
            geo_err_prefix(&err, "stored input");
            proto_pipeline_free(&pl);
            return fail(ret, -EINVAL, &err);
        }
        r = runner_run(&pl, &model, ctx, op_timer, user, &stats, &summary,
                       &err);
    } else {
        /* a frep-object/1, stored as JSON text (job_submit.h) */
        geo_frep *f = proto_frep_read_mem(input, input_len, NULL, &err);
        if (!f) {
            geo_err_prefix(&err, "stored input");
            proto_pipeline_free(&pl);
            return fail(ret, -EINVAL, &err);
        }
        r = runner_run_frep(&pl, f, &model, ctx, op_timer, user, &stats,
                            &summary, &err);
        geo_frep_free(f);
    }
    proto_pipeline_free(&pl);
    if (r == 0) {
        char *buf = NULL;
        size_t len = 0;
        if (changes)
            r = proto_model_write_mem(model, PROTO_FMT_FMB1, &buf, &len, &err);
        if (r == 0) {
            ret->model = buf;
            ret->model_len = len;
            /* the same text, its reals without snprintf */
            ret->stats = proto_json_dumps(stats, JSON_COMPACT);
            ret->stats_len = ret->stats ? strlen(ret->stats) : 0;
            ret->summary = json_dumps(summary, JSON_COMPACT);
            if (!ret->stats || !ret->summary)
                r = geo_err_set(&err, -ENOMEM, "out of memory");
        }
    }
    json_decref(stats);
    json_decref(summary);
    geo_poly_free(model);
    return r < 0 ? fail(ret, r, &err) : 0;
}
