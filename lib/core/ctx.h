/* ctx.h — what every kernel takes besides its geometry: error reporting,
 * progress, cancellation, a seed and a caller-provided parallel loop.
 *
 * Contract for all of lib/: actions return 0 or a negative errno-style code
 * (-EINVAL bad input, -ENOMEM out of memory, -ECANCELED canceled, -ERANGE a
 * configured limit was exceeded) and, when the caller passed a geo_err,
 * a message that names the place ("facets[12]: ..."). lib/ never logs,
 * never exits and starts no threads of its own. */
#ifndef GEO_CTX_H
#define GEO_CTX_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* A message for a human; msg is always NUL-terminated. */
typedef struct geo_err {
    char msg[512];
} geo_err;

/* Formats into err->msg (printf-style). err may be NULL: then nothing
 * happens. Returns code, so `return geo_err_set(err, -EINVAL, ...)` reads
 * naturally. */
int geo_err_set(geo_err *err, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Prefixes err->msg with "prefix: " (for nesting places, e.g. "model: ").
 * err may be NULL. */
void geo_err_prefix(geo_err *err, const char *prefix);

/* Runs fn(arg, i) for every i in [0, n), possibly concurrently. A caller
 * (CLI, daemon) provides it; kernels never create threads. fn must be
 * safe to run concurrently for distinct i. */
typedef void (*geo_parallel_for_fn)(void *pf_user, size_t n,
                                    void (*fn)(void *arg, size_t i), void *arg);

/* The optional context of a kernel run. Every field may be zero/NULL. */
typedef struct geo_ctx {
    /* Called with fraction in [0,1] at a kernel's convenience; a non-zero
     * return asks the kernel to stop (it then returns -ECANCELED). */
    int (*progress)(void *user, double fraction);
    void *user;
    /* Set to non-zero by another thread to cancel; read with acquire. */
    const atomic_int *cancel;
    /* CLOCK_MONOTONIC time (ns) after which the run counts as canceled;
     * 0 = none. Lets a kernel stop at a time limit by itself, without a
     * thread to raise the flag (geo_ctx_now_ns gives the clock). */
    int64_t deadline_ns;
    /* Seed for kernels that draw random numbers (deterministic per seed). */
    uint64_t seed;
    /* Parallel loop, NULL means run sequentially. */
    geo_parallel_for_fn parallel_for;
    void *pf_user;
} geo_ctx;

/* True when the caller asked to stop (cancel flag set) or the deadline
 * passed. ctx may be NULL. Cheap (an atomic load, a vDSO clock read with
 * a deadline): a long loop calls it every few thousand iterations
 * (GEO_CTX_CHECK_EVERY), so that cancellation lands within milliseconds. */
bool geo_ctx_canceled(const geo_ctx *ctx);

/* Iterations between two geo_ctx_canceled checks in a kernel's loop:
 * `if ((i & GEO_CTX_CHECK_MASK) == 0 && geo_ctx_canceled(ctx))`. */
#define GEO_CTX_CHECK_MASK 1023u

/* CLOCK_MONOTONIC in nanoseconds (the clock of deadline_ns). */
int64_t geo_ctx_now_ns(void);

/* Reports progress; returns -ECANCELED when the run should stop, else 0.
 * ctx may be NULL. */
int geo_ctx_progress(const geo_ctx *ctx, double fraction);

/* Runs fn over [0,n) with ctx->parallel_for, or sequentially without one. */
void geo_ctx_parallel_for(const geo_ctx *ctx, size_t n,
                          void (*fn)(void *arg, size_t i), void *arg);

/* splitmix64: a small, well-mixed deterministic generator for kernels.
 * *state advances; returns the next 64 random bits. */
uint64_t geo_rand_next(uint64_t *state);
/* Uniform double in [0, 1). */
double geo_rand_unit(uint64_t *state);

#endif
