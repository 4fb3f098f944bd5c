/* parallel.h — a fixed pool of worker threads behind the kernels'
 * geo_parallel_for_fn (lib/core/ctx.h): kernels never create threads, the CLI
 * and the daemon hand them this loop.
 *
 * par_for(pool, n, fn, arg) runs fn(arg, i) for every i in [0, n) on the
 * pool's threads plus the calling thread and returns when all are done.
 * Indices are handed out dynamically (an atomic counter), so results must
 * not depend on which thread ran which index. One par_for at a time uses
 * the pool's threads: a call made while another thread's loop runs there
 * runs all its indices in the calling thread (so nested calls and
 * concurrent callers never wait for each other). */
#ifndef FACET_PARALLEL_H
#define FACET_PARALLEL_H

#include <stddef.h>

typedef struct par_pool par_pool;

/* A pool using nthreads threads in total (the caller counts as one;
 * nthreads ≤ 1 means run inline). nthreads 0 means the number of online
 * CPUs. Returns NULL on failure (errno set). */
par_pool *par_pool_new(int nthreads);

/* Stops the threads and frees the pool; accepts NULL; returns NULL. */
par_pool *par_pool_free(par_pool *pool);

/* The geo_parallel_for_fn: pool_user is a par_pool * (NULL runs inline). */
void par_for(void *pool_user, size_t n, void (*fn)(void *arg, size_t i),
             void *arg);

/* Threads the pool runs with (≥ 1). */
int par_pool_threads(const par_pool *pool);

#endif
