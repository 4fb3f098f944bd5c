/* store.h — the job store: the one place jobs, their inputs and their
 * results live. A small interface (put, claim, progress, finish, cancel,
 * get, list, delete, recover, retention) with backends behind a table of
 * functions, as Redis puts ae_epoll.c behind ae.c: store_sqlite.c is the
 * embedded default; a PostgreSQL backend can later let several facetd
 * nodes share one queue. So nothing above this interface may assume the
 * store is in-process or that one node sees every job: workers learn of
 * cancel requests from store_progress, and waiters re-read the store.
 *
 * Durability contract: when store_put returns 0 the job is committed (it
 * survives a crash of the process, and with the SQLite backend a power
 * loss too). State changes after that survive a process crash; a job found
 * running after a crash is queued again by store_recover (at-least-once).
 *
 * Errors: every function returns 0 or a negative errno: -ENOENT (no such
 * job / nothing queued), -EEXIST (idempotency key already used), -EAGAIN
 * (queue full), -EBUSY (transition not allowed from the job's state),
 * -ENOMEM, -EIO (backend failure, err says what), -ENOTCONN (a shared
 * store is unreachable right now: nothing was changed that the caller
 * can rely on; retry later), -ESTALE (store_progress: this node's claim
 * on the job was lost, another node runs it). Out-parameters are
 * written only on success (and on -EEXIST for store_put).
 *
 * Thread safety: every function may be called from any thread
 * concurrently; the backend serialises what it must. */
#ifndef FACETD_STORE_H
#define FACETD_STORE_H

#include <stddef.h>
#include <stdint.h>

#include "ctx.h"
#include "job.h"

typedef struct store store;

/* What the caller gives for a new job; every pointer is borrowed. */
typedef struct store_new_job {
    const char *id;            /* from job_id_new */
    job_priority priority;
    const char *source;        /* < JOB_SOURCE_MAX bytes */
    const char *label;         /* < JOB_LABEL_MAX bytes, may be NULL */
    const char *pipeline;      /* JSON text */
    const void *input;         /* the input model bytes */
    size_t input_len;
    const char *idem_key;      /* Idempotency-Key, or NULL */
    uint64_t idem_hash;        /* hash of the request it came with */
    int64_t created_ms;
} store_new_job;

typedef enum store_blob {
    STORE_BLOB_INPUT = 0,  /* the submitted model (FMB1) */
    STORE_BLOB_MODEL = 1,  /* the result model (FMB1); the input when the
                              pipeline left the model unchanged */
    STORE_BLOB_STATS = 2,  /* the statistics JSON */
} store_blob;

typedef struct store_filter {
    int state;              /* a job_state, or -1 for any */
    const char *source;     /* exact source, or NULL for any */
    const char *after;      /* list jobs older than this id, or NULL */
    unsigned limit;         /* at most this many (1..1000) */
} store_filter;

typedef struct store_counts {
    uint64_t by_state[JOB_NSTATES]; /* jobs in each state */
    uint64_t kept_bytes;    /* input + result + stats bytes of all jobs */
    uint64_t file_bytes;    /* the backend's size on disk, 0 if unknown */
} store_counts;

struct store_events;

/* The backend's functions; see the wrappers below for each contract. */
typedef struct store_ops {
    const char *name;
    int (*put)(store *s, const store_new_job *j, unsigned max_queued,
               job_rec *ret_existing, geo_err *err);
    int (*claim)(store *s, job_rec *ret, geo_err *err);
    int (*progress)(store *s, const char *id, double progress,
                    int *ret_cancel, geo_err *err);
    int (*finish)(store *s, const char *id, job_state state,
                  const char *error, const char *summary, const void *model,
                  size_t model_len, const void *stats, size_t stats_len,
                  geo_err *err);
    int (*requeue)(store *s, const char *id, geo_err *err);
    int (*cancel)(store *s, const char *id, job_rec *ret, geo_err *err);
    int (*remove)(store *s, const char *id, geo_err *err);
    int (*get)(store *s, const char *id, job_rec *ret, geo_err *err);
    int (*get_blob)(store *s, const char *id, store_blob which, void **ret,
                    size_t *ret_len, geo_err *err);
    int (*list)(store *s, const store_filter *f, job_rec **ret,
                size_t *ret_n, geo_err *err);
    int (*recover)(store *s, unsigned *ret_n, geo_err *err);
    int (*retention)(store *s, int64_t older_than_ms, uint64_t max_bytes,
                     unsigned *ret_deleted, geo_err *err);
    int (*counts)(store *s, store_counts *ret, geo_err *err);
    int (*ping)(store *s, geo_err *err);
    void (*close)(store *s);
    /* Optional (NULL: the store sees only this process's changes). */
    void (*set_events)(store *s, const struct store_events *ev);
    const char *(*node)(store *s);
} store_ops;

/* Every backend's handle starts with this. */
struct store {
    const store_ops *ops;
};

/* What a shared store tells about changes made anywhere in the cluster
 * (also this node's own; a duplicate wake-up only costs a re-read). */
typedef enum store_event {
    STORE_EV_QUEUED = 0,   /* a job became queued: a worker may claim it */
    STORE_EV_CHANGED = 1,  /* state or cancel request changed */
    STORE_EV_PROGRESS = 2, /* only the progress moved */
    STORE_EV_ENDED = 3,    /* reached a terminal state */
    STORE_EV_DELETED = 4,
    STORE_EV_RESYNC = 5,   /* events may have been missed (the store was
                              unreachable): id and source are NULL */
} store_event;

/* Called on the store's own thread; must be quick and thread-safe. */
typedef struct store_events {
    void (*fn)(void *user, store_event ev, const char *id,
               const char *source);
    void *user;
} store_events;

/* Opens (creating or migrating) the SQLite store in dir/facetd.db.
 * Returns NULL with err set on failure. Close with store_close. */
store *store_sqlite_open(const char *dir, geo_err *err);

/* The PostgreSQL store shared by every node that names the same
 * database (store_pg.c). */
typedef struct store_pg_config {
    const char *url;           /* libpq URI or conninfo */
    const char *password_file; /* libpq passfile, or NULL/"" for libpq's
                                  own default (PGPASSFILE, ~/.pgpass) */
    const char *node;          /* this node's name (job_rec.node) */
    uint64_t lease_ms;         /* claim lease, renewed while running */
} store_pg_config;

/* Connects, creates or migrates the schema (serialised across nodes by
 * an advisory lock) and starts the thread that renews this node's leases,
 * re-queues jobs whose lease expired, and listens for the cluster's job
 * changes. NULL with err on failure. */
store *store_pg_open(const store_pg_config *c, geo_err *err);

/* Routes the cluster's job changes to ev (copied); a no-op for a store
 * that only sees this process. */
void store_set_events(store *s, const store_events *ev);

/* This node's name in a shared store's cluster, or NULL for a store that
 * only this process uses. */
const char *store_node(store *s);

/* Adds a queued job. 0 when committed. -EAGAIN when max_queued jobs are
 * already queued (nothing written). -EEXIST when j->idem_key was used
 * before: *ret_existing (if not NULL) receives that job, whose stored
 * request hash the caller compares with its own; nothing written. */
int store_put(store *s, const store_new_job *j, unsigned max_queued,
              job_rec *ret_existing, geo_err *err);

/* Takes the next queued job (high priority first, then oldest) and marks
 * it running (started_ms, attempts+1; a shared store also sets node and
 * leases the job to this node until store_finish or store_requeue). -ENOENT when none is queued. The
 * caller owns *ret (job_rec_clear). */
int store_claim(store *s, job_rec *ret, geo_err *err);

/* Records the progress (0..1) of a running job; *ret_cancel (may be NULL)
 * becomes 1 when a cancel was requested. -ENOENT for a missing job,
 * -EBUSY if it is not running. */
int store_progress(store *s, const char *id, double progress,
                   int *ret_cancel, geo_err *err);

/* Ends a running job in a terminal state with an optional error text,
 * summary JSON and result blobs (copied; NULL/0 for none). A succeeded job
 * without a model blob has the input as its result (a pipeline that only
 * inspects): no second copy is kept, store_get_blob(STORE_BLOB_MODEL)
 * gives the input, and result_hash is the digest of the job's id (it
 * only has to name the result, which never changes). -EBUSY when the job
 * is not running. */
int store_finish(store *s, const char *id, job_state state,
                 const char *error, const char *summary, const void *model,
                 size_t model_len, const void *stats, size_t stats_len,
                 geo_err *err);

/* Puts a running job back in the queue (its run was interrupted, not
 * failed). -EBUSY when not running. */
int store_requeue(store *s, const char *id, geo_err *err);

/* Cancels: a queued job becomes canceled at once, a running one gets
 * cancel_requested (its worker stops at the next check). *ret receives
 * the job after the change (may be NULL). -EBUSY for a job already in a
 * terminal state (nothing changed; *ret still receives it). */
int store_cancel(store *s, const char *id, job_rec *ret, geo_err *err);

/* Deletes a job in a terminal state with its blobs. -EBUSY otherwise. */
int store_remove(store *s, const char *id, geo_err *err);

/* Reads a job's record. The caller owns *ret. */
int store_get(store *s, const char *id, job_rec *ret, geo_err *err);

/* Reads one blob of a job into a malloc'd buffer (*ret, NUL-terminated
 * beyond *ret_len for convenience). -ENOENT when the job or that blob does
 * not exist. */
int store_get_blob(store *s, const char *id, store_blob which, void **ret,
                   size_t *ret_len, geo_err *err);

/* Lists jobs newest first. *ret is a malloc'd array of *ret_n records:
 * free each with job_rec_clear, then the array. */
int store_list(store *s, const store_filter *f, job_rec **ret, size_t *ret_n,
               geo_err *err);

/* At start-up: every running job goes back to queued (its previous run
 * died with the process). A shared store re-queues only the jobs of this
 * node and those whose lease expired. *ret_n (may be NULL) receives how
 * many. */
int store_recover(store *s, unsigned *ret_n, geo_err *err);

/* Deletes terminal jobs finished before older_than_ms, then more terminal
 * jobs, oldest first, while all jobs together keep more than max_bytes.
 * Queued and running jobs are never deleted. A shared store runs it once
 * for the cluster: a call soon after another node's does nothing. */
int store_retention(store *s, int64_t older_than_ms, uint64_t max_bytes,
                    unsigned *ret_deleted, geo_err *err);

/* Job counts by state and sizes. */
int store_count(store *s, store_counts *ret, geo_err *err);

/* Cheap check that the store answers (for /readyz and the watchdog). */
int store_ping(store *s, geo_err *err);

/* Closes the store; every other call must have returned. Accepts NULL;
 * returns NULL. */
store *store_close(store *s);

#endif
