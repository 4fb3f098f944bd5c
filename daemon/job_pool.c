/* job_pool.c — worker threads, the monitor thread (time limits and cancel
 * requests made on other nodes) and the shutdown protocol (job_pool.h).
 *
 * Invariants: a slot's id/busy/deadline change only under pool->lock;
 * its cancel flag and reason are atomics, the reason set once per run
 * (first cause wins: canceled, timeout or shutdown), so the worker decides
 * the final state from a single value. */
#include "job_pool.h"

#include <errno.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "log.h"

enum reason { R_NONE = 0, R_CANCELED, R_TIMEOUT, R_SHUTDOWN };

typedef struct slot {
    job_pool *pool;
    pthread_t thread;
    bool started;
    /* under pool->lock */
    bool busy;
    char id[JOB_ID_LEN + 1];
    int64_t deadline;      /* monotonic ms */
    uint64_t limit_ms;     /* the limit the deadline came from */
    /* atomics */
    atomic_int cancel;
    atomic_int reason;
    /* worker thread only */
    int64_t last_report;   /* monotonic ms of the last stored progress */
} slot;

/* A primed input (job_pool_prime). */
typedef struct primed {
    char id[JOB_ID_LEN + 1];
    job_decoded d;
} primed;

struct job_pool {
    store *s;
    job_pool_config c;
    pthread_mutex_t lock;
    pthread_cond_t wake;   /* work may be available, or stopping */
    pthread_cond_t idle;   /* a worker finished a job */
    pthread_cond_t tick;   /* the monitor's sleep while jobs run */
    pthread_cond_t armed;  /* the monitor's sleep while none runs */
    bool stopping;
    bool paused;
    unsigned pending;      /* wake-ups not yet consumed */
    atomic_uint busy;      /* changed under lock; pool_parallel_for reads
                              it without */
    atomic_uint_fast64_t timeout_ms;
    slot *slots;
    unsigned nslots;
    /* workers whose outcome the store is refusing right now (disk full):
     * while non-zero the pool is not ready (job_pool_store_error) */
    atomic_uint store_failing;
    pthread_mutex_t err_lock;
    char store_err[sizeof(geo_err)]; /* under err_lock: the last refusal */
    pthread_t monitor;
    bool monitor_started;
    /* primed inputs, oldest first, under primed_lock */
    pthread_mutex_t primed_lock;
    primed primed[JOB_POOL_PRIMED_MAX];
    unsigned nprimed;
    size_t primed_bytes;
};

static void set_reason(slot *sl, int why)
{
    int none = R_NONE;
    atomic_compare_exchange_strong(&sl->reason, &none, why);
    atomic_store_explicit(&sl->cancel, 1, memory_order_release);
}

static void notify(job_pool *p, const char *id, bool progress_only)
{
    if (p->c.notify)
        p->c.notify(p->c.cb_user, id, progress_only);
}

static int on_progress(void *user, double fraction)
{
    slot *sl = user;
    job_pool *p = sl->pool;
    int64_t now = job_mono_ms();
    if (now - sl->last_report >= (int64_t)p->c.progress_every_ms) {
        sl->last_report = now;
        int cancel = 0;
        geo_err err;
        int r = store_progress(p->s, sl->id, fraction, &cancel, &err);
        if (r == 0) {
            if (cancel)
                set_reason(sl, R_CANCELED);
            notify(p, sl->id, true);
        } else if (r == -ESTALE) {
            /* another node runs it now: this run's result would be refused */
            log_msg(LOG_WARNING, sl->id, "%s; stopping this run", err.msg);
            set_reason(sl, R_CANCELED);
        } else {
            log_msg(LOG_WARNING, sl->id, "progress not recorded: %s", err.msg);
        }
    }
    return atomic_load_explicit(&sl->cancel, memory_order_acquire);
}

static void outcome_free(job_outcome *o)
{
    free(o->error);
    free(o->summary);
    free(o->model);
    free(o->stats);
    memset(o, 0, sizeof *o);
}

/* Inputs above this size leave many freed pages in the worker's malloc
 * arena, which glibc keeps for reuse: a 1M-facet job left the RSS at
 * 1 GB. They go back to the system after such a job. */
enum { TRIM_ABOVE = 4 << 20 };

static void trim_after(size_t bytes)
{
#ifdef __GLIBC__
    if (bytes > TRIM_ABOVE)
        malloc_trim(0);
#else
    (void)bytes;
#endif
}

static int record_outcome(job_pool *p, const job_rec *job,
                          job_state final, const char *error,
                          const job_outcome *out, bool *ret_requeued,
                          geo_err *err);

static void decoded_release(job_decoded *d)
{
    if (d->data && d->free_fn)
        d->free_fn(d->data);
    d->data = NULL;
}

/* Drops primed entry i (under primed_lock), releasing its input. */
static void primed_drop(job_pool *p, unsigned i)
{
    p->primed_bytes -= p->primed[i].d.bytes;
    decoded_release(&p->primed[i].d);
    memmove(&p->primed[i], &p->primed[i + 1],
            (p->nprimed - i - 1) * sizeof *p->primed);
    p->nprimed--;
}

void job_pool_prime(job_pool *p, const char *id, job_decoded d)
{
    if (d.bytes > JOB_POOL_PRIMED_BYTES || strlen(id) > JOB_ID_LEN) {
        decoded_release(&d);
        return;
    }
    pthread_mutex_lock(&p->primed_lock);
    while (p->nprimed > 0 &&
           (p->nprimed == JOB_POOL_PRIMED_MAX ||
            p->primed_bytes + d.bytes > JOB_POOL_PRIMED_BYTES))
        primed_drop(p, 0);
    primed *e = &p->primed[p->nprimed++];
    snprintf(e->id, sizeof e->id, "%s", id);
    e->d = d;
    p->primed_bytes += d.bytes;
    pthread_mutex_unlock(&p->primed_lock);
}

/* Takes job id's primed input into *ret; false when there is none. */
static bool primed_take(job_pool *p, const char *id, job_decoded *ret)
{
    bool found = false;
    pthread_mutex_lock(&p->primed_lock);
    for (unsigned i = p->nprimed; i-- > 0;)
        if (strcmp(p->primed[i].id, id) == 0) {
            *ret = p->primed[i].d;
            p->primed[i].d.data = NULL; /* moved out, not released */
            primed_drop(p, i);
            found = true;
            break;
        }
    pthread_mutex_unlock(&p->primed_lock);
    return found;
}

void job_pool_unprime(job_pool *p, const char *id)
{
    job_decoded d;
    if (primed_take(p, id, &d))
        decoded_release(&d);
}

/* The kernels' parallel_for: the shared pool while this job is the only
 * one running, its own thread otherwise. With another job on the other
 * cores a job's loops gain nothing from the pool (it serves one loop at a
 * time, and its threads compete with the other job's worker) and pay the
 * hand-offs: on 2 cores, k400 inspect jobs from 32 clients cost 4.9-5.1 ms
 * of CPU each with the pool always, 4.5-4.7 ms with this rule. */
static void pool_parallel_for(void *user, size_t n,
                              void (*fn)(void *arg, size_t i), void *arg)
{
    job_pool *p = user;
    if (p->c.parallel_for &&
        atomic_load_explicit(&p->busy, memory_order_relaxed) <= 1) {
        p->c.parallel_for(p->c.pf_user, n, fn, arg);
        return;
    }
    for (size_t i = 0; i < n; i++)
        fn(arg, i);
}

static void run_job(slot *sl, job_rec *job)
{
    job_pool *p = sl->pool;
    int64_t t0 = job_mono_ms();
    uint64_t limit = atomic_load(&p->timeout_ms);
    pthread_mutex_lock(&p->lock);
    memcpy(sl->id, job->id, sizeof sl->id);
    sl->busy = true;
    sl->deadline = t0 + (int64_t)limit;
    sl->limit_ms = limit;
    atomic_store(&sl->cancel, 0);
    atomic_store(&sl->reason, R_NONE);
    if (++p->busy == 1)
        pthread_cond_signal(&p->armed);
    pthread_mutex_unlock(&p->lock);
    sl->last_report = t0;
    log_msg(LOG_INFO, job->id, "started (attempt %d, source %s)",
            job->attempts, job->source);
    notify(p, job->id, false);

    job_outcome out;
    memset(&out, 0, sizeof out);
    void *input = NULL;
    size_t input_len = 0;
    geo_err err = {{0}};
    /* the input as its submitter decoded it, else the stored bytes */
    job_decoded dec;
    bool was_primed = primed_take(p, job->id, &dec);
    int r = was_primed ? 0
                   : store_get_blob(p->s, job->id, STORE_BLOB_INPUT, &input,
                                    &input_len, &err);
    if (r == 0) {
        geo_ctx ctx = {
            .progress = on_progress,
            .user = sl,
            .cancel = &sl->cancel,
            /* the kernels stop at the time limit by themselves, without
             * waiting for the monitor's next tick (t0 is whole ms: the
             * extra one keeps the run at least the limit long) */
            .deadline_ns = (t0 + 1 + (int64_t)limit) * 1000000,
            .seed = 1,
            .parallel_for = pool_parallel_for,
            .pf_user = p,
        };
        r = p->c.exec(p->c.exec_user, job, input, input_len,
                      was_primed ? &dec : NULL, &ctx, &out);
        if (was_primed) {
            input_len = dec.bytes; /* for the trim below */
            decoded_release(&dec);
        }
        free(input);
    } else {
        out.error = strdup(err.msg);
    }
    double secs = (double)(job_mono_ms() - t0) / 1000.0;
    if (r == -ECANCELED && job_mono_ms() >= t0 + (int64_t)limit) {
        int none = R_NONE;
        atomic_compare_exchange_strong(&sl->reason, &none, R_TIMEOUT);
    }
    int why = atomic_load(&sl->reason);
    job_state final;
    const char *error = out.error;
    char msg[128];
    if (r == 0) {
        final = JOB_SUCCEEDED;
        error = NULL;
    } else if (r == -ECANCELED && why == R_SHUTDOWN) {
        final = JOB_QUEUED;
    } else if (r == -ECANCELED && why == R_TIMEOUT) {
        final = JOB_FAILED;
        snprintf(msg, sizeof msg, "time limit of %.3g s exceeded",
                 (double)sl->limit_ms / 1000.0);
        error = msg;
    } else if (r == -ECANCELED) {
        final = JOB_CANCELED;
        error = "canceled while running";
    } else {
        final = JOB_FAILED;
        if (!error)
            error = r == -ENOMEM ? "out of memory" : "failed";
    }
    bool requeued = false;
    r = record_outcome(p, job, final, error, &out, &requeued, &err);
    if (r == 0 && requeued) {
        log_msg(LOG_NOTICE, job->id, "the store refused the outcome; queued "
                "again for a later attempt");
        final = JOB_QUEUED;
    } else if (final == JOB_QUEUED) {
        if (r == 0)
            log_msg(LOG_NOTICE, job->id, "interrupted by shutdown after "
                    "%.3f s; queued again", secs);
    } else {
        if (r == 0) {
            if (final == JOB_FAILED)
                log_msg(LOG_WARNING, job->id, "failed after %.3f s: %s", secs,
                        error);
            else
                log_msg(LOG_INFO, job->id, "%s in %.3f s",
                        job_state_name(final), secs);
        }
    }
    if (r < 0)
        log_msg(LOG_ERR, job->id, "outcome not recorded: %s", err.msg);
    else if (final != JOB_QUEUED && p->c.done)
        p->c.done(p->c.cb_user, job, final, secs);
    size_t moved = input_len + out.model_len;
    outcome_free(&out);
    trim_after(moved);
    pthread_mutex_lock(&p->lock);
    sl->busy = false;
    p->busy--;
    pthread_cond_broadcast(&p->idle);
    pthread_mutex_unlock(&p->lock);
    notify(p, job->id, false);
}

static void timed_wait(pthread_cond_t *cv, pthread_mutex_t *m, int64_t ms);

/* Records the outcome, retrying with back-off while the store cannot
 * write (a full disk, a database away): first the whole outcome, then —
 * a smaller write — the job queued again for a later attempt,
 * alternately, until one lands or the pool stops (then the job stays
 * running in the store, which start-up queues again). Never leaves a job
 * running with no worker behind it while the process lives. */
static int record_outcome(job_pool *p, const job_rec *job,
                          job_state final, const char *error,
                          const job_outcome *out, bool *ret_requeued,
                          geo_err *err)
{
    int64_t wait_ms = 100;
    bool failing = false;
    *ret_requeued = false;
    for (unsigned attempt = 0;; attempt++) {
        int r;
        bool requeue = final == JOB_QUEUED || attempt % 2 == 1;
        if (requeue)
            r = store_requeue(p->s, job->id, err);
        else
            r = store_finish(p->s, job->id, final, error, out->summary,
                             final == JOB_SUCCEEDED ? out->model : NULL,
                             out->model_len,
                             final == JOB_SUCCEEDED ? out->stats : NULL,
                             out->stats_len, err);
        /* refused for good (the job is no longer this node's: -EBUSY,
         * -ESTALE, -ENOENT) is an answer, not a store that cannot write */
        bool transient = r == -ENOSPC || r == -EIO || r == -EAGAIN ||
                         r == -ENOMEM;
        if (r == 0 || !transient) {
            *ret_requeued = r == 0 && requeue && final != JOB_QUEUED;
            if (failing)
                atomic_fetch_sub(&p->store_failing, 1);
            return r;
        }
        if (!failing) {
            failing = true;
            atomic_fetch_add(&p->store_failing, 1);
        }
        pthread_mutex_lock(&p->err_lock);
        snprintf(p->store_err, sizeof p->store_err, "%s", err->msg);
        pthread_mutex_unlock(&p->err_lock);
        log_msg(attempt ? LOG_DEBUG : LOG_ERR, job->id, "outcome not "
                "recorded (%s), retrying in %lld ms: %s",
                requeue ? "queue again" : job_state_name(final),
                (long long)wait_ms, err->msg);
        pthread_mutex_lock(&p->lock);
        bool stop = p->stopping;
        if (!stop)
            timed_wait(&p->tick, &p->lock, wait_ms);
        stop = p->stopping;
        pthread_mutex_unlock(&p->lock);
        if (stop) {
            atomic_fetch_sub(&p->store_failing, 1);
            return r;
        }
        if (wait_ms < 5000)
            wait_ms *= 2;
    }
}

static void timed_wait(pthread_cond_t *cv, pthread_mutex_t *m, int64_t ms)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    ts.tv_sec += ms / 1000;
    ts.tv_nsec += (ms % 1000) * 1000000;
    if (ts.tv_nsec >= 1000000000) {
        ts.tv_sec++;
        ts.tv_nsec -= 1000000000;
    }
    pthread_cond_timedwait(cv, m, &ts);
}

static void *worker(void *arg)
{
    slot *sl = arg;
    job_pool *p = sl->pool;
    for (;;) {
        pthread_mutex_lock(&p->lock);
        while (p->paused && !p->stopping)
            pthread_cond_wait(&p->wake, &p->lock);
        bool stop = p->stopping;
        pthread_mutex_unlock(&p->lock);
        if (stop)
            break;
        job_rec job;
        geo_err err;
        int r = store_claim(p->s, &job, &err);
        if (r == 0) {
            run_job(sl, &job);
            job_rec_clear(&job);
            continue;
        }
        if (r != -ENOENT)
            log_msg(LOG_ERR, NULL, "claiming a job failed: %s", err.msg);
        pthread_mutex_lock(&p->lock);
        if (!p->stopping && p->pending == 0)
            timed_wait(&p->wake, &p->lock, r == -ENOENT ? 1000 : 2000);
        if (p->pending)
            p->pending--;
        pthread_mutex_unlock(&p->lock);
    }
    return NULL;
}

/* Every 100 ms while a job runs: time limits; every second: cancel flags
 * in the store. With no job running it sleeps until one starts, so an
 * idle daemon does not wake ten times a second. */
static void *monitor(void *arg)
{
    job_pool *p = arg;
    int tick = 0;
    pthread_mutex_lock(&p->lock);
    while (!p->stopping || p->busy) {
        if (!p->busy && !p->stopping) {
            pthread_cond_wait(&p->armed, &p->lock);
            continue;
        }
        timed_wait(&p->tick, &p->lock, 100);
        int64_t now = job_mono_ms();
        bool poll_store = ++tick % 10 == 0;
        char ids[64][JOB_ID_LEN + 1];
        slot *which[64];
        unsigned n = 0;
        for (unsigned i = 0; i < p->nslots; i++) {
            slot *sl = &p->slots[i];
            if (!sl->busy)
                continue;
            if (now >= sl->deadline)
                set_reason(sl, R_TIMEOUT);
            else if (poll_store && n < 64) {
                memcpy(ids[n], sl->id, sizeof ids[n]);
                which[n++] = sl;
            }
        }
        if (!n)
            continue;
        pthread_mutex_unlock(&p->lock);
        bool flagged[64] = {false};
        for (unsigned i = 0; i < n; i++) {
            job_rec r;
            if (store_get(p->s, ids[i], &r, NULL) == 0) {
                flagged[i] = r.cancel_requested;
                job_rec_clear(&r);
            }
        }
        pthread_mutex_lock(&p->lock);
        for (unsigned i = 0; i < n; i++)
            if (flagged[i] && which[i]->busy &&
                strcmp(which[i]->id, ids[i]) == 0)
                set_reason(which[i], R_CANCELED);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

job_pool *job_pool_start(store *s, const job_pool_config *c, geo_err *err)
{
    if (!c->workers || !c->exec || !c->job_timeout_ms) {
        geo_err_set(err, -EINVAL, "job pool: invalid configuration");
        return NULL;
    }
    job_pool *p = calloc(1, sizeof *p);
    slot *slots = calloc(c->workers, sizeof *slots);
    if (!p || !slots) {
        free(p);
        free(slots);
        geo_err_set(err, -ENOMEM, "job pool: out of memory");
        return NULL;
    }
    p->s = s;
    p->c = *c;
    p->paused = c->paused;
    p->slots = slots;
    p->nslots = c->workers;
    atomic_init(&p->timeout_ms, c->job_timeout_ms);
    pthread_mutex_init(&p->lock, NULL);
    pthread_mutex_init(&p->err_lock, NULL);
    pthread_mutex_init(&p->primed_lock, NULL);
    atomic_init(&p->store_failing, 0);
    atomic_init(&p->busy, 0);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&p->wake, &ca);
    pthread_cond_init(&p->idle, &ca);
    pthread_cond_init(&p->tick, &ca);
    pthread_cond_init(&p->armed, &ca);
    pthread_condattr_destroy(&ca);
    for (unsigned i = 0; i < p->nslots; i++) {
        slot *sl = &p->slots[i];
        sl->pool = p;
        atomic_init(&sl->cancel, 0);
        atomic_init(&sl->reason, R_NONE);
        if (pthread_create(&sl->thread, NULL, worker, sl) != 0) {
            geo_err_set(err, -EAGAIN, "job pool: cannot start worker %u", i);
            job_pool_stop(p, 0);
            return NULL;
        }
        sl->started = true;
    }
    if (pthread_create(&p->monitor, NULL, monitor, p) != 0) {
        geo_err_set(err, -EAGAIN, "job pool: cannot start the monitor");
        job_pool_stop(p, 0);
        return NULL;
    }
    p->monitor_started = true;
    return p;
}

void job_pool_wake(job_pool *p)
{
    pthread_mutex_lock(&p->lock);
    if (p->pending < p->nslots)
        p->pending++;
    pthread_cond_signal(&p->wake);
    pthread_mutex_unlock(&p->lock);
}

int job_pool_cancel(job_pool *p, const char *id)
{
    int found = 0;
    pthread_mutex_lock(&p->lock);
    for (unsigned i = 0; i < p->nslots; i++) {
        slot *sl = &p->slots[i];
        if (sl->busy && strcmp(sl->id, id) == 0) {
            set_reason(sl, R_CANCELED);
            found = 1;
        }
    }
    pthread_mutex_unlock(&p->lock);
    return found;
}

void job_pool_set_paused(job_pool *p, bool paused)
{
    pthread_mutex_lock(&p->lock);
    p->paused = paused;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
}

bool job_pool_paused(job_pool *p)
{
    pthread_mutex_lock(&p->lock);
    bool v = p->paused;
    pthread_mutex_unlock(&p->lock);
    return v;
}

void job_pool_set_timeout(job_pool *p, uint64_t job_timeout_ms)
{
    if (job_timeout_ms)
        atomic_store(&p->timeout_ms, job_timeout_ms);
}

unsigned job_pool_busy(job_pool *p)
{
    pthread_mutex_lock(&p->lock);
    unsigned n = p->busy;
    pthread_mutex_unlock(&p->lock);
    return n;
}

bool job_pool_store_error(job_pool *p, char *buf, size_t size)
{
    if (atomic_load(&p->store_failing) == 0)
        return false;
    pthread_mutex_lock(&p->err_lock);
    snprintf(buf, size, "%s", p->store_err);
    pthread_mutex_unlock(&p->err_lock);
    return true;
}

int job_pool_healthy(job_pool *p)
{
    pthread_mutex_lock(&p->lock);
    int ok = !p->stopping;
    pthread_mutex_unlock(&p->lock);
    return ok;
}

job_pool *job_pool_stop(job_pool *p, uint64_t grace_ms)
{
    if (!p)
        return NULL;
    pthread_mutex_lock(&p->lock);
    p->stopping = true;
    pthread_cond_broadcast(&p->wake);
    int64_t end = job_mono_ms() + (int64_t)grace_ms;
    while (p->busy && job_mono_ms() < end)
        timed_wait(&p->idle, &p->lock, end - job_mono_ms());
    if (p->busy)
        log_msg(LOG_NOTICE, NULL, "%u running job(s) did not finish within "
                "%.3g s; interrupting them", p->busy, (double)grace_ms / 1000);
    for (unsigned i = 0; i < p->nslots; i++)
        if (p->slots[i].busy)
            set_reason(&p->slots[i], R_SHUTDOWN);
    pthread_cond_broadcast(&p->tick);
    pthread_mutex_unlock(&p->lock);
    for (unsigned i = 0; i < p->nslots; i++)
        if (p->slots[i].started)
            pthread_join(p->slots[i].thread, NULL);
    if (p->monitor_started) {
        pthread_mutex_lock(&p->lock);
        pthread_cond_broadcast(&p->tick);
        pthread_cond_broadcast(&p->armed);
        pthread_mutex_unlock(&p->lock);
        pthread_join(p->monitor, NULL);
    }
    pthread_cond_destroy(&p->wake);
    pthread_cond_destroy(&p->idle);
    pthread_cond_destroy(&p->tick);
    pthread_cond_destroy(&p->armed);
    pthread_mutex_destroy(&p->lock);
    pthread_mutex_destroy(&p->err_lock);
    while (p->nprimed > 0)
        primed_drop(p, p->nprimed - 1);
    pthread_mutex_destroy(&p->primed_lock);
    free(p->slots);
    free(p);
    return NULL;
}
