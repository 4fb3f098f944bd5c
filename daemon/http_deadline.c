/* http_deadline.c — the request-header deadline: every open connection
 * is listed from MHD's connection notification to its close, and a reaper
 * thread shuts down the socket of one whose request headers are not
 * complete HeaderTimeout after it connected (or after its previous
 * request ended). MHD's own timeout is an idle timeout, which a client
 * sending one byte a second never reaches.
 *
 * Invariant: a listed fd is still open — MHD notifies the close before it
 * closes the socket, and the entry leaves the list under conn_lock, the
 * lock the reaper holds while it calls shutdown(). */
#include "http.h"

#include <errno.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <time.h>

#include "log.h"

static http_conn *conn_of(struct MHD_Connection *c)
{
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
    return ci ? ci->socket_context : NULL;
}

void http_conn_notify(void *cls, struct MHD_Connection *c,
                      void **socket_context,
                      enum MHD_ConnectionNotificationCode toe)
{
    http_server *h = cls;
    if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
        const union MHD_ConnectionInfo *ci =
            MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
        http_conn *e = ci ? calloc(1, sizeof *e) : NULL;
        if (!e)
            return; /* untracked: only the idle timeout applies */
        e->fd = ci->connect_fd;
        e->since_ms = job_mono_ms();
        e->in_headers = true;
        pthread_mutex_lock(&h->conn_lock);
        e->next = h->conns;
        if (h->conns)
            h->conns->prev = e;
        h->conns = e;
        pthread_mutex_unlock(&h->conn_lock);
        *socket_context = e;
        return;
    }
    http_conn *e = *socket_context;
    if (!e)
        return;
    pthread_mutex_lock(&h->conn_lock);
    if (e->prev)
        e->prev->next = e->next;
    else
        h->conns = e->next;
    if (e->next)
        e->next->prev = e->prev;
    pthread_mutex_unlock(&h->conn_lock);
    *socket_context = NULL;
    free(e);
}

static void set_in_headers(http_server *h, struct MHD_Connection *c, bool v)
{
    http_conn *e = conn_of(c);
    if (!e)
        return;
    pthread_mutex_lock(&h->conn_lock);
    e->in_headers = v;
    e->since_ms = job_mono_ms();
    pthread_mutex_unlock(&h->conn_lock);
}

void http_conn_headers_done(http_server *h, struct MHD_Connection *c)
{
    set_in_headers(h, c, false);
}

void http_conn_request_done(http_server *h, struct MHD_Connection *c)
{
    set_in_headers(h, c, true);
}

static void *reaper(void *arg)
{
    http_server *h = arg;
    int64_t step = (int64_t)h->header_timeout_ms / 4;
    if (step < 50)
        step = 50;
    if (step > 500)
        step = 500;
    pthread_mutex_lock(&h->conn_lock);
    while (!h->reaper_stop) {
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        ts.tv_nsec += step * 1000000;
        ts.tv_sec += ts.tv_nsec / 1000000000;
        ts.tv_nsec %= 1000000000;
        pthread_cond_timedwait(&h->conn_tick, &h->conn_lock, &ts);
        int64_t now = job_mono_ms();
        unsigned cut = 0;
        for (http_conn *e = h->conns; e; e = e->next) {
            if (e->in_headers && !e->cut &&
                now - e->since_ms >= (int64_t)h->header_timeout_ms) {
                /* MHD sees end of stream and closes it, in its thread */
                shutdown(e->fd, SHUT_RDWR);
                e->cut = true;
                cut++;
            }
        }
        if (cut) {
            atomic_fetch_add(&h->header_cuts, cut);
            log_msg(LOG_DEBUG, NULL, "http: %u connection(s) closed: no "
                    "complete request headers within %.3g s", cut,
                    (double)h->header_timeout_ms / 1000);
        }
    }
    pthread_mutex_unlock(&h->conn_lock);
    return NULL;
}

int http_deadline_start(http_server *h, uint64_t timeout_ms)
{
    pthread_mutex_init(&h->conn_lock, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&h->conn_tick, &ca);
    pthread_condattr_destroy(&ca);
    h->header_timeout_ms = timeout_ms;
    if (!timeout_ms)
        return 0;
    if (pthread_create(&h->reaper, NULL, reaper, h) != 0)
        return -EAGAIN;
    h->reaper_started = true;
    return 0;
}

void http_deadline_stop(http_server *h)
{
    if (h->reaper_started) {
        pthread_mutex_lock(&h->conn_lock);
        h->reaper_stop = true;
        pthread_cond_signal(&h->conn_tick);
        pthread_mutex_unlock(&h->conn_lock);
        pthread_join(h->reaper, NULL);
        h->reaper_started = false;
    }
}

void http_deadline_fini(http_server *h)
{
    /* MHD has closed every connection (and notified) by now */
    pthread_cond_destroy(&h->conn_tick);
    pthread_mutex_destroy(&h->conn_lock);
}
