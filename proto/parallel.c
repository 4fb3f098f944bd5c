/* parallel.c — the thread pool behind par_for: workers sleep on a
 * condition variable, take indices from an atomic counter while a loop is
 * active, and the last one to finish wakes the caller. One loop uses the
 * pool at a time; a concurrent caller runs its loop itself. */
#include "parallel.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <unistd.h>

struct par_pool {
    int nthreads;           /* total, caller included */
    pthread_t *threads;     /* nthreads - 1 workers */
    pthread_mutex_t lock;   /* guards the fields below */
    pthread_cond_t wake;    /* a new loop or shutdown */
    pthread_cond_t done;    /* all workers left the current loop */
    pthread_mutex_t serial; /* one par_for at a time */
    unsigned long generation;
    bool quit;
    int busy;               /* workers inside the current loop */
    /* the current loop */
    size_t n;
    void (*fn)(void *, size_t);
    void *arg;
    atomic_size_t next;
};

static void run_indices(par_pool *p)
{
    for (;;) {
        size_t i = atomic_fetch_add(&p->next, 1);
        if (i >= p->n)
            return;
        p->fn(p->arg, i);
    }
}

static void *worker(void *user)
{
    par_pool *p = user;
    unsigned long seen = 0;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        while (!p->quit && p->generation == seen)
            pthread_cond_wait(&p->wake, &p->lock);
        if (p->quit)
            break;
        seen = p->generation;
        p->busy++;
        pthread_mutex_unlock(&p->lock);
        run_indices(p);
        pthread_mutex_lock(&p->lock);
        if (--p->busy == 0)
            pthread_cond_signal(&p->done);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

par_pool *par_pool_new(int nthreads)
{
    if (nthreads <= 0) {
        long c = sysconf(_SC_NPROCESSORS_ONLN);
        nthreads = c > 0 ? (int)c : 1;
    }
    par_pool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    p->nthreads = 1;
    pthread_mutex_init(&p->lock, NULL);
    pthread_mutex_init(&p->serial, NULL);
    pthread_cond_init(&p->wake, NULL);
    pthread_cond_init(&p->done, NULL);
    atomic_init(&p->next, 0);
    if (nthreads > 1) {
        p->threads = calloc((size_t)nthreads - 1, sizeof *p->threads);
        if (!p->threads)
            return par_pool_free(p);
        for (int i = 0; i < nthreads - 1; i++) {
            int r = pthread_create(&p->threads[i], NULL, worker, p);
            if (r != 0) {
                errno = r;
                return par_pool_free(p);
            }
            p->nthreads++;
        }
    }
    return p;
}

par_pool *par_pool_free(par_pool *p)
{
    if (!p)
        return NULL;
    pthread_mutex_lock(&p->lock);
    p->quit = true;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
    for (int i = 0; i < p->nthreads - 1; i++)
        pthread_join(p->threads[i], NULL);
    free(p->threads);
    pthread_mutex_destroy(&p->lock);
    pthread_mutex_destroy(&p->serial);
    pthread_cond_destroy(&p->wake);
    pthread_cond_destroy(&p->done);
    free(p);
    return NULL;
}

int par_pool_threads(const par_pool *p)
{
    return p ? p->nthreads : 1;
}

void par_for(void *pool_user, size_t n, void (*fn)(void *arg, size_t i),
             void *arg)
{
    par_pool *p = pool_user;
    /* A loop that finds the pool busy with another caller's loop runs in
     * the calling thread: the pool's threads are working for that caller,
     * so waiting would leave this thread idle (facetd's job workers share
     * one pool). */
    if (!p || p->nthreads <= 1 || n <= 1 ||
        pthread_mutex_trylock(&p->serial) != 0) {
        for (size_t i = 0; i < n; i++)
            fn(arg, i);
        return;
    }
    pthread_mutex_lock(&p->lock);
    /* a worker that woke late for the previous loop may still be reading
     * its fields: let it leave before they change */
    while (p->busy > 0)
        pthread_cond_wait(&p->done, &p->lock);
    p->n = n;
    p->fn = fn;
    p->arg = arg;
    atomic_store(&p->next, 0);
    p->generation++;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);

    run_indices(p);

    pthread_mutex_lock(&p->lock);
    /* workers that never woke for this generation will find no index left;
     * wait only for those inside the loop */
    while (p->busy > 0)
        pthread_cond_wait(&p->done, &p->lock);
    pthread_mutex_unlock(&p->lock);
    pthread_mutex_unlock(&p->serial);
}
