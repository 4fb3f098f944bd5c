/* http_wait.c — the waiter hub: suspended connections indexed by job id,
 * and one timer thread that resumes them at their deadlines.
 *
 * Invariants:
 * - A waiter is linked into a bucket exactly while its connection is
 *   suspended. Suspending happens under the hub lock after linking, and
 *   every resume happens under the same lock after unlinking, so
 *   MHD_resume_connection is never called on a connection that is not
 *   suspended (which libmicrohttpd leaves undefined).
 * - Lock order: hub lock, then libmicrohttpd's internal locks (taken by
 *   suspend/resume). libmicrohttpd never calls back into us while holding
 *   its own locks during normal operation; at shutdown the hub is closed
 *   (everyone resumed) before MHD_stop_daemon.
 * - The timer sleeps until the earliest deadline (re-checking at least
 *   every second, so a waiter added while it slept is never late).
 * - No lost wake-up: every notify bumps its bucket's seq under the lock,
 *   and a suspend whose seq (taken before the caller read the store) is
 *   out of date is refused, so a change that lands between the read and
 *   the suspend makes the caller read again instead of sleeping through
 *   it. */
#include "http.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { NBUCKETS = 256, TICK_MS = 1000 };

struct http_hub {
    pthread_mutex_t lock;
    pthread_cond_t cv;
    http_waiter *buckets[NBUCKETS];
    uint64_t seq[NBUCKETS];
    unsigned count;
    bool closed, stop;
    pthread_t timer;
    bool timer_started;
};

static unsigned bucket_of(const char *id)
{
    return (unsigned)(job_hash64(id, strlen(id)) % NBUCKETS);
}

static void link_waiter(http_hub *h, http_waiter *w)
{
    http_waiter **head = &h->buckets[bucket_of(w->id)];
    w->prev = NULL;
    w->next = *head;
    if (*head)
        (*head)->prev = w;
    *head = w;
    w->in_hub = true;
    h->count++;
}

/* Unlinks and resumes; hub lock held. */
static void release(http_hub *h, http_waiter *w)
{
    if (w->prev)
        w->prev->next = w->next;
    else
        h->buckets[bucket_of(w->id)] = w->next;
    if (w->next)
        w->next->prev = w->prev;
    w->next = w->prev = NULL;
    w->in_hub = false;
    h->count--;
    MHD_resume_connection(w->conn);
}

static void abs_time(int64_t mono_ms, struct timespec *ts)
{
    ts->tv_sec = (time_t)(mono_ms / 1000);
    ts->tv_nsec = (long)(mono_ms % 1000) * 1000000;
}

static void *timer_main(void *arg)
{
    http_hub *h = arg;
    pthread_mutex_lock(&h->lock);
    while (!h->stop) {
        int64_t now = job_mono_ms(), next = now + TICK_MS;
        for (unsigned b = 0; b < NBUCKETS; b++) {
            http_waiter *w = h->buckets[b];
            while (w) {
                http_waiter *nx = w->next;
                if (w->deadline <= now)
                    release(h, w);
                else if (w->deadline < next)
                    next = w->deadline;
                w = nx;
            }
        }
        struct timespec ts;
        abs_time(next, &ts);
        pthread_cond_timedwait(&h->cv, &h->lock, &ts);
    }
    pthread_mutex_unlock(&h->lock);
    return NULL;
}

http_hub *http_hub_new(void)
{
    http_hub *h = calloc(1, sizeof *h);
    if (!h)
        return NULL;
    pthread_mutex_init(&h->lock, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&h->cv, &ca);
    pthread_condattr_destroy(&ca);
    if (pthread_create(&h->timer, NULL, timer_main, h) != 0)
        return http_hub_free(h);
    h->timer_started = true;
    return h;
}

void http_hub_close(http_hub *h)
{
    pthread_mutex_lock(&h->lock);
    h->closed = true;
    for (unsigned b = 0; b < NBUCKETS; b++)
        while (h->buckets[b])
            release(h, h->buckets[b]);
    pthread_mutex_unlock(&h->lock);
}

http_hub *http_hub_free(http_hub *h)
{
    if (!h)
        return NULL;
    http_hub_close(h);
    pthread_mutex_lock(&h->lock);
    h->stop = true;
    pthread_cond_signal(&h->cv);
    pthread_mutex_unlock(&h->lock);
    if (h->timer_started)
        pthread_join(h->timer, NULL);
    pthread_cond_destroy(&h->cv);
    pthread_mutex_destroy(&h->lock);
    free(h);
    return NULL;
}

uint64_t http_hub_seq(http_hub *h, const char *id)
{
    pthread_mutex_lock(&h->lock);
    uint64_t s = h->seq[bucket_of(id)];
    pthread_mutex_unlock(&h->lock);
    return s;
}

int http_hub_suspend(http_hub *h, http_waiter *w, unsigned limit)
{
    pthread_mutex_lock(&h->lock);
    int r = 0;
    if (h->closed)
        r = -ESHUTDOWN;
    else if (h->seq[bucket_of(w->id)] != w->seq)
        r = -ESTALE;
    else if (h->count >= limit)
        r = -EAGAIN;
    if (r == 0) {
        link_waiter(h, w);
        MHD_suspend_connection(w->conn);
        /* The timer may be sleeping past this deadline. */
        pthread_cond_signal(&h->cv);
    }
    pthread_mutex_unlock(&h->lock);
    return r;
}

void http_hub_notify(http_hub *h, const char *id, bool progress_only)
{
    pthread_mutex_lock(&h->lock);
    h->seq[bucket_of(id)]++;
    http_waiter *w = h->buckets[bucket_of(id)];
    while (w) {
        http_waiter *nx = w->next;
        if (strcmp(w->id, id) == 0 && (w->progress || !progress_only))
            release(h, w);
        w = nx;
    }
    pthread_mutex_unlock(&h->lock);
}

unsigned http_hub_count(http_hub *h)
{
    pthread_mutex_lock(&h->lock);
    unsigned n = h->count;
    pthread_mutex_unlock(&h->lock);
    return n;
}
