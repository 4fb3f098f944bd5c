/* job.h — a job as the daemon sees it: its states, its record (what the
 * store keeps about it besides the blobs), its id and its JSON view.
 *
 * States and their transitions (the only ones the store performs):
 *   queued → running → succeeded | failed | canceled
 *   queued → canceled          (DELETE before a worker took it)
 *   running → queued           (shutdown interrupted it, or a restart
 *                               found it running: it runs again)
 * A job's version counts its changes (state, progress, cancel request);
 * it starts at 1 and only grows, so it orders the events of one job.
 *
 * Ids are 26-character ULIDs (Crockford base32 of a 48-bit millisecond
 * time and 80 random bits): unique across nodes sharing a store, and
 * sortable by creation time.
 *
 * Ownership: a job_rec owns its malloc'd strings; job_rec_clear frees them.
 * Nothing here is shared between threads. */
#ifndef FACETD_JOB_H
#define FACETD_JOB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

typedef enum job_state {
    JOB_QUEUED = 0,
    JOB_RUNNING = 1,
    JOB_SUCCEEDED = 2,
    JOB_FAILED = 3,
    JOB_CANCELED = 4,
} job_state;
enum { JOB_NSTATES = 5 };

typedef enum job_priority { JOB_PRIO_NORMAL = 0, JOB_PRIO_HIGH = 1 } job_priority;

#define JOB_ID_LEN 26
#define JOB_SOURCE_MAX 72  /* bytes of source, NUL included ("usb:" and
                              a serial of up to 63) */
#define JOB_LABEL_MAX 256  /* bytes of label, NUL included */
#define JOB_NODE_MAX 64    /* bytes of node, NUL included */

typedef struct job_rec {
    char id[JOB_ID_LEN + 1];
    job_state state;
    job_priority priority;
    char source[JOB_SOURCE_MAX]; /* "http" or "usb:SERIAL" */
    char label[JOB_LABEL_MAX];   /* caller's label, may be empty */
    char *pipeline;    /* JSON text of the pipeline as submitted (owned) */
    char *error;       /* why it failed/was canceled, or NULL (owned) */
    char *summary;     /* JSON text of the result summary, or NULL (owned) */
    double progress;   /* 0..1 */
    int64_t created_ms, started_ms, finished_ms; /* Unix ms; 0 = not yet */
    int64_t version;   /* ≥ 1, grows with every change */
    bool cancel_requested;
    int attempts;      /* times a worker took it */
    uint64_t input_bytes, result_bytes; /* sizes of the kept blobs */
    uint64_t result_hash; /* names the result for ETags: job_digest64 of the
                             result model, or of the id when the result is
                             the input (FNV-1a 64 of the model for jobs
                             finished by older versions), 0 if none */
    uint64_t idem_hash;   /* hash of the request that created it */
    char node[JOB_NODE_MAX]; /* the node that runs or ran it, "" when the
                                store is not shared (not in the JSON then) */
} job_rec;

/* Frees the owned strings and zeroes r; accepts NULL. */
void job_rec_clear(job_rec *r);

/* "queued", "running", …; NULL for an invalid value. */
const char *job_state_name(job_state s);
/* The state named s, or -1. */
int job_state_from_name(const char *s);
/* Succeeded, failed or canceled: no further change. */
bool job_state_terminal(job_state s);

/* Writes a new id (JOB_ID_LEN chars + NUL) for time now_ms. Thread-safe
 * (randomness from getrandom, falling back to a seeded generator). */
void job_id_new(char ret[JOB_ID_LEN + 1], int64_t now_ms);
/* True when s has the form of an id (26 Crockford base32 characters). */
bool job_id_valid(const char *s);

/* Unix time in milliseconds (CLOCK_REALTIME). */
int64_t job_now_ms(void);
/* Monotonic milliseconds, for durations and deadlines. */
int64_t job_mono_ms(void);
/* RFC 3339 UTC with milliseconds ("2024-05-01T12:00:00.123Z") into buf
 * (≥ 25 bytes). */
void job_time_format(int64_t ms, char *buf, size_t size);

/* The job's public JSON view (id, state, progress, priority, source,
 * label, node when set, pipeline, created/started/finished, error,
 * summary, links), or
 * NULL on out-of-memory. The caller owns the result. */
json_t *job_to_json(const job_rec *r);

/* The same view as compact JSON text, byte for byte what
 * json_dumps(job_to_json(r), JSON_COMPACT) gives, written directly
 * (daemon/job_text.c); the length in *ret_len (may be NULL). A malloc'd
 * NUL-terminated string for the caller, or NULL on out-of-memory. */
char *job_to_text(const job_rec *r, size_t *ret_len);

/* FNV-1a 64-bit hash of n bytes (idempotency checks; stored, so it never
 * changes). */
uint64_t job_hash64(const void *data, size_t n);

/* A 64-bit digest of n bytes taken 8 at a time (several times faster than
 * job_hash64), for the ETags of results. */
uint64_t job_digest64(const void *data, size_t n);

#endif
