/* job_exec.h — the executor the worker pool runs for every job: decodes
 * the stored input (FMB1) unless its submitter primed the model, parses the stored pipeline, runs it through the
 * runner, and encodes the outcome (result model as FMB1, statistics and
 * summary as JSON). It is the glue between job_pool (threads, store) and
 * runner (kernels); it does no geometry itself. */
#ifndef FACETD_JOB_EXEC_H
#define FACETD_JOB_EXEC_H

#include "job_pool.h"
#include "metrics.h"

/* A job_exec_fn (job_pool.h); user is a metrics * (per-operation
 * durations are recorded there) or NULL. A primed input (decoded) is a
 * geo_poly *, taken over. */
int job_exec(void *user, const job_rec *job, const void *input,
             size_t input_len, job_decoded *decoded, const geo_ctx *ctx,
             job_outcome *ret);

#endif
