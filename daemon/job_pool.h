/* job_pool.h — the worker pool: N threads that claim jobs from the store
 * (high priority first, then oldest — the store's order), run them through
 * an executor with a geo_ctx carrying progress and an atomic cancel flag,
 * and record the outcome in the store.
 *
 * The queue itself is the store (durable, bounded by store_put's
 * max_queued); the pool only wakes workers when job_pool_wake says a job
 * arrived, and re-polls the store every second in case another node or
 * a missed wake-up queued one.
 *
 * Cancellation reaches a running job three ways: job_pool_cancel (a DELETE
 * on this node), the store's cancel_requested flag (seen on every progress
 * report and by a once-a-second check, for a DELETE on another node), and
 * the per-job time limit (checked every 100 ms). Each sets the job's
 * atomic flag; kernels stop at their next geo_ctx check.
 *
 * Shutdown (job_pool_stop): workers stop claiming; running jobs get a
 * grace period to finish, then are canceled and put back in the queue
 * (not marked canceled), so a restart runs them again.
 *
 * Thread safety: every function may be called from any thread, except
 * job_pool_stop, which must be called once, after which the pool is gone. */
#ifndef FACETD_JOB_POOL_H
#define FACETD_JOB_POOL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctx.h"
#include "job.h"
#include "store.h"

/* What an executor produces; every pointer is malloc'd and handed to the
 * pool, which frees it. All may be NULL. */
typedef struct job_outcome {
    char *error;     /* for a failure: what went wrong, naming the place */
    char *summary;   /* JSON text of the job summary */
    void *model;     /* result model bytes (FMB1); NULL on success means
                        the result is the input unchanged (store_finish) */
    size_t model_len;
    void *stats;     /* statistics JSON bytes */
    size_t stats_len;
} job_outcome;

/* A job's input already decoded by whoever stored it (job_submit: the
 * model it has just parsed and stored), handed to the pool so that the
 * worker that runs the job soon after neither reads it back from the
 * store nor decodes it again. data is released with free_fn; bytes is
 * what it holds in memory. */
typedef struct job_decoded {
    void *data;
    size_t bytes;
    void (*free_fn)(void *data);
} job_decoded;

/* Runs one job: job is the claimed record, input its input blob; ctx has
 * progress and cancel wired (and the pool's parallel_for while no other
 * job runs). decoded is NULL, or the input as it was primed
 * (job_pool_prime; input is then NULL): the executor may take
 * decoded->data (setting it NULL), else the pool releases it after the
 * call. Returns 0 on success (outcome
 * filled), -ECANCELED when ctx asked it to stop, any other negative
 * errno on failure (outcome->error says why). Called on a worker thread;
 * must be thread-safe. */
typedef int (*job_exec_fn)(void *user, const job_rec *job, const void *input,
                           size_t input_len, job_decoded *decoded,
                           const geo_ctx *ctx, job_outcome *ret);

/* Told after every change the pool makes to a job in the store (claimed,
 * progress, finished, requeued); used to wake waiting clients.
 * progress_only is true when only the progress moved. Called on a worker
 * thread; must be quick and thread-safe. */
typedef void (*job_notify_fn)(void *user, const char *id, bool progress_only);

/* Told when a job ends: its final state and run time in seconds. */
typedef void (*job_done_fn)(void *user, const job_rec *job, job_state state,
                            double seconds);

typedef struct job_pool_config {
    unsigned workers;           /* ≥ 1 */
    uint64_t job_timeout_ms;    /* ≥ 1 */
    uint64_t progress_every_ms; /* store progress at most this often */
    geo_parallel_for_fn parallel_for; /* handed to kernels, may be NULL */
    void *pf_user;
    job_exec_fn exec;
    void *exec_user;
    bool paused;                /* start paused (job_pool_set_paused) */
    job_notify_fn notify;       /* may be NULL */
    job_done_fn done;           /* may be NULL */
    void *cb_user;              /* for notify and done */
} job_pool_config;

typedef struct job_pool job_pool;

/* Starts the workers. NULL with err on failure (no threads left). */
job_pool *job_pool_start(store *s, const job_pool_config *c, geo_err *err);

/* A job was queued: wakes one idle worker. */
void job_pool_wake(job_pool *p);

/* Sets the cancel flag of job id if it runs on this pool. Returns 1 if it
 * did, 0 if the job does not run here. */
int job_pool_cancel(job_pool *p, const char *id);

/* Paused workers take no new job (running ones finish); submissions
 * still queue. Unpausing wakes them. */
void job_pool_set_paused(job_pool *p, bool paused);

/* True while paused. */
bool job_pool_paused(job_pool *p);

/* Changes the time limit for jobs claimed from now on (reload). */
void job_pool_set_timeout(job_pool *p, uint64_t job_timeout_ms);

/* What the pool keeps of primed inputs at most, together and in count:
 * beyond it the oldest go, and their jobs' workers read the store, as for
 * a job queued before the start or stored by another node. */
#define JOB_POOL_PRIMED_BYTES ((size_t)64 << 20)
#define JOB_POOL_PRIMED_MAX 1024

/* Keeps d, the decoded input of job id just stored, for the job's run on
 * this node; the pool owns d from here (released at once when it alone
 * exceeds the budget). An entry no run takes — the job canceled while
 * queued, or run by another node — stays until the budget pushes it out
 * or the pool stops. */
void job_pool_prime(job_pool *p, const char *id, job_decoded d);

/* Releases job id's primed input, if the pool holds one (the job was not
 * stored after all). */
void job_pool_unprime(job_pool *p, const char *id);

/* Workers running a job right now. */
unsigned job_pool_busy(job_pool *p);

/* True while the workers take jobs (not stopping), for /readyz. */
int job_pool_healthy(job_pool *p);

/* True while a worker's outcome is being refused by the store (and
 * retried): buf gets the store's last message. */
bool job_pool_store_error(job_pool *p, char *buf, size_t size);

/* Stops claiming, waits up to grace_ms for running jobs, cancels and
 * requeues the rest, joins the threads and frees the pool. Accepts NULL;
 * returns NULL. */
job_pool *job_pool_stop(job_pool *p, uint64_t grace_ms);

#endif
