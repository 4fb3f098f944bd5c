/* job_submit.c — validated request → stored, queued job (job_submit.h). */
#include "job_submit.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "model_io.h"
#include "runner.h"

static void poly_free(void *data)
{
    geo_poly_free(data);
}

/* Hands a copy of the model just stored to the pool, for the worker that
 * runs it (job_pool_prime): a copy of the arrays costs a fraction of
 * reading the FMB1 back and checking its planes. Out of memory it is
 * simply not primed. */
static void prime(job_pool *pool, const char *id, const geo_poly *model)
{
    size_t bytes =
        sizeof *model + (size_t)model->nverts * sizeof *model->verts +
        ((size_t)model->nfacets + 1) * sizeof *model->fstart +
        (size_t)geo_poly_ncorners(model) * sizeof *model->fidx +
        (size_t)model->nfacets * sizeof *model->planes;
    if (bytes > JOB_POOL_PRIMED_BYTES)
        return; /* the pool would not keep it: no copy of a large model */
    geo_poly *copy = geo_poly_copy(model);
    if (copy)
        job_pool_prime(pool, id, (job_decoded){copy, bytes, poly_free});
}

int job_submit(store *s, job_pool *pool, unsigned queue_size,
               const job_request *rq, job_rec *ret, bool *ret_replayed,
               geo_err *err)
{
    int r = runner_check_input(rq->pipeline, rq->frep != NULL, err);
    if (r < 0)
        return r;
    json_t *pj = proto_pipeline_to_json(rq->pipeline);
    char *pipeline = pj ? json_dumps(pj, JSON_COMPACT) : NULL;
    json_decref(pj);
    char *input = NULL;
    size_t input_len = 0;
    if (!pipeline) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    if (rq->frep) {
        input = json_dumps(rq->frep, JSON_COMPACT | JSON_REAL_PRECISION(17));
        if (!input) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto out;
        }
        input_len = strlen(input);
    } else {
        r = proto_model_write_mem(rq->model, PROTO_FMT_FMB1, &input,
                                  &input_len, err);
        if (r < 0)
            goto out;
    }
    char id[JOB_ID_LEN + 1];
    int64_t now = job_now_ms();
    job_id_new(id, now);
    store_new_job j = {
        .id = id,
        .priority = rq->priority,
        .source = rq->source,
        .label = rq->label,
        .pipeline = pipeline,
        .input = input,
        .input_len = input_len,
        .idem_key = rq->idem_key,
        .idem_hash = rq->idem_hash,
        .created_ms = now,
    };
    /* primed before the job is visible to the workers, which may claim
     * it the moment it is stored; withdrawn if it is not stored */
    if (pool && rq->model)
        prime(pool, id, rq->model);
    job_rec old;
    r = store_put(s, &j, queue_size, &old, err);
    if (r < 0 && pool && rq->model)
        job_pool_unprime(pool, id);
    if (r == -EEXIST) {
        if (old.idem_hash != rq->idem_hash) {
            r = geo_err_set(err, -EEXIST, "Idempotency-Key '%s' was used "
                            "for a different request (job %s)", rq->idem_key,
                            old.id);
            job_rec_clear(&old);
            goto out;
        }
        *ret = old;
        *ret_replayed = true;
        r = 0;
        goto out;
    }
    if (r < 0)
        goto out;
    r = store_get(s, id, ret, err);
    if (r == 0) {
        *ret_replayed = false;
        if (pool)
            job_pool_wake(pool);
    }
out:
    free(pipeline);
    free(input);
    return r;
}
