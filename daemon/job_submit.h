/* job_submit.h — turning a validated request into a queued job: the one
 * path every source (HTTP, the scanner intake) takes into the
 * store, so the checks (operations available, queue bound, idempotency)
 * and the stored form are the same for all.
 *
 * A model input is stored as FMB1 (the scanner's binary model, proto/
 * model_io.h): a worker decodes it in microseconds instead of parsing JSON
 * again, and it keeps every double bit for bit. A copy of the parsed model
 * is also primed in the local pool (job_pool_prime), so that the worker
 * that runs the job here skips even that. A frep-object/1 input is
 * stored as its compact JSON text (jansson prints doubles exactly); the
 * executor tells the two apart by FMB1's magic "FMB1", which JSON text
 * cannot start with. The pipeline is stored in canonical JSON (every
 * parameter explicit), so a job's record says exactly what ran. */
#ifndef FACETD_JOB_SUBMIT_H
#define FACETD_JOB_SUBMIT_H

#include <stdbool.h>
#include <stdint.h>

#include <jansson.h>

#include "job.h"
#include "job_pool.h"
#include "pipeline.h"
#include "poly.h"
#include "store.h"

typedef struct job_request {
    const geo_poly *model;          /* the validated input (borrowed) */
    const json_t *frep;             /* or a validated frep-object/1
                                       (borrowed); exactly one is set */
    const proto_pipeline *pipeline; /* parsed pipeline (borrowed) */
    job_priority priority;
    const char *source;             /* "http", "usb:SERIAL" */
    const char *label;              /* may be NULL */
    const char *idem_key;           /* Idempotency-Key, may be NULL */
    uint64_t idem_hash;             /* hash of the request's bytes */
} job_request;

/* Queues rq. On 0, *ret is the job (new, or with *ret_replayed set the
 * one an earlier request with the same Idempotency-Key and the same bytes
 * created). Errors: -ENOTSUP an operation is not in this build (err names
 * it), -EAGAIN the queue holds queue_size jobs, -EEXIST the key was used
 * by a request with different bytes, -ENOMEM, -EIO. pool may be NULL (no
 * local workers to wake). Thread-safe. */
int job_submit(store *s, job_pool *pool, unsigned queue_size,
               const job_request *rq, job_rec *ret, bool *ret_replayed,
               geo_err *err);

#endif
