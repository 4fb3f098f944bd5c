/* facetd.c — the daemon's entry point: configuration, start-up in
 * dependency order (listener, store, workers, scanner intake, HTTP), the
 * main loop (signals, systemd notifications and watchdog, retention,
 * status), and the graceful shutdown (HTTP stops accepting, new scans
 * only go to the store, running jobs finish — their RESULTs still go to
 * the scanners — then HTTP, the intake and the store close).
 *
 * Signals are blocked in every thread and read from a signalfd by the main
 * thread only, so no handler runs in the middle of library code:
 *   SIGTERM, SIGINT  graceful shutdown: stop accepting, answer waiting
 *                    clients, let running jobs finish within
 *                    ShutdownTimeout, requeue the rest (they stay in the
 *                    store and run after the next start);
 *   SIGHUP           reload the configuration; keys that need a restart
 *                    are reported and keep their running values.
 * Exit status: 0 after a clean shutdown, 1 when start-up fails, 2 on a
 * configuration error. */
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include <systemd/sd-daemon.h>

#include "cfg.h"
#include "cfg_doc.h"
#include "version.h"
#include "http_listen.h"
#include "http_server.h"
#include "job_exec.h"
#include "job_pool.h"
#include "log.h"
#include "reserve.h"
#include "metrics.h"
#include "parallel.h"
#include "scanners.h"
#include "store.h"

/* What the pool's callbacks reach; hs is set once HTTP is up, sc before
 * the workers start. */
typedef struct app {
    _Atomic(http_server *) hs;
    _Atomic(job_pool *) pool;
    metrics *m;
    scanners *sc;
} app;

static void on_job_changed(void *user, const char *id, bool progress_only)
{
    app *a = user;
    http_server *hs = atomic_load(&a->hs);
    if (hs)
        http_server_job_changed(hs, id, progress_only);
}

/* A change anywhere in the cluster (a shared store's own thread): wakes
 * this node's workers, waiting clients and owed scanner RESULTs. */
static void on_store_event(void *user, store_event ev, const char *id,
                           const char *source)
{
    app *a = user;
    job_pool *pool = atomic_load(&a->pool);
    if (pool && (ev == STORE_EV_QUEUED || ev == STORE_EV_RESYNC))
        job_pool_wake(pool);
    if (!id)
        return;
    http_server *hs = atomic_load(&a->hs);
    if (hs)
        http_server_job_changed(hs, id, ev == STORE_EV_PROGRESS);
    if (ev == STORE_EV_ENDED || ev == STORE_EV_DELETED) {
        job_rec j = {.state = JOB_SUCCEEDED};
        snprintf(j.id, sizeof j.id, "%s", id);
        snprintf(j.source, sizeof j.source, "%s", source ? source : "");
        scanners_job_done(a->sc, &j);
    }
}

/* [Store] URL= names a PostgreSQL database shared by the cluster; else
 * the embedded SQLite store. The node is named HOST:PORT by default. */
static store *open_store(const cfg *c, const char *where, geo_err *err)
{
    if (!c->store_url[0])
        return store_sqlite_open(c->state_dir, err);
    char node[64];
    if (c->node_name[0]) {
        snprintf(node, sizeof node, "%s", c->node_name);
    } else {
        char host[48] = "localhost";
        gethostname(host, sizeof host - 1);
        const char *port = strrchr(where, ':');
        snprintf(node, sizeof node, "%s:%s", host, port ? port + 1 : "0");
    }
    store_pg_config pc = {
        .url = c->store_url,
        .password_file = c->store_password_file,
        .node = node,
        .lease_ms = c->job_lease_ms,
    };
    store *s = store_pg_open(&pc, err);
    if (s)
        log_msg(LOG_NOTICE, NULL, "cluster node %s on a shared PostgreSQL "
                "store (lease %.3g s)", node, (double)c->job_lease_ms / 1000);
    return s;
}

static void on_job_done(void *user, const job_rec *job, job_state st,
                        double seconds)
{
    app *a = user;
    metrics_job(a->m, st, seconds);
    scanners_job_done(a->sc, job);
}

/* Opens the store and queues again the jobs the last stop interrupted.
 * On a disk that filled up meanwhile both need a little room: the
 * reserve (reserve.h) is given up for it, and made again next time. */
static store *open_store_reserved(const cfg *c, const char *where,
                                  unsigned *requeued, geo_err *err)
{
    for (int attempt = 0; attempt < 2; attempt++) {
        store *s = open_store(c, where, err);
        if (s && store_recover(s, requeued, err) == 0) {
            if (!c->store_url[0] &&
                reserve_keep(c->state_dir, RESERVE_BYTES) < 0)
                log_msg(LOG_WARNING, NULL, "no room for the %u MiB disk "
                        "reserve in %s", RESERVE_BYTES >> 20, c->state_dir);
            return s;
        }
        store_close(s);
        if (attempt > 0 || c->store_url[0] || !reserve_release(c->state_dir))
            break;
        log_msg(LOG_WARNING, NULL, "%s; gave up the %u MiB disk reserve to "
                "start", err->msg, RESERVE_BYTES >> 20);
    }
    return NULL;
}

static unsigned cpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (unsigned)n : 1;
}

/* The reloadable values the HTTP threads read. */
static void apply_http_settings(http_env *env, const cfg *c)
{
    atomic_store(&env->max_body, c->max_body);
    atomic_store(&env->max_wait_ms, c->max_wait_ms);
    atomic_store(&env->keepalive_ms, c->keepalive_ms);
    atomic_store(&env->max_waiters, c->max_waiters);
    atomic_store(&env->queue_size, c->queue_size);
    atomic_store(&env->inspect_max_facets, c->inspect_max_facets);
    atomic_store(&env->max_query_args, c->max_query_args);
    atomic_store(&env->inspect_timeout_ms, c->inspect_timeout_ms);
    http_env_set_token(env, c->api_token);
}

static int check_auth(const cfg *c, bool loopback, const char *where)
{
    if (loopback || c->api_token[0] || c->allow_unauthenticated)
        return 0;
    log_msg(LOG_ERR, NULL, "listening on %s (not loopback) requires an API "
            "token: set ApiToken= or ApiTokenFile= in [Server], or "
            "AllowUnauthenticated=yes to serve without one", where);
    return -EACCES;
}

static void retention(store *s, const cfg *c);

static void reload(cfg *cur, int argc, char **argv, http_env *env,
                   store *s, job_pool *pool, scanners *sc, bool loopback,
                   const char *where)
{
    sd_notify(0, "RELOADING=1\nSTATUS=reloading the configuration");
    cfg next;
    geo_err err;
    if (cfg_load(&next, argc, argv, &err) < 0) {
        log_msg(LOG_ERR, NULL, "reload failed, configuration unchanged: %s",
                err.msg);
    } else if (check_auth(&next, loopback, where) < 0) {
        log_msg(LOG_ERR, NULL, "reload refused, configuration unchanged");
    } else {
        char keys[512];
        if (cfg_restart_only_changes(cur, &next, keys, sizeof keys) > 0)
            log_msg(LOG_WARNING, NULL, "reload: %s changed; a restart is "
                    "needed to apply %s", keys, "them (running values kept)");
        /* Restart-only keys keep their running values. */
        snprintf(next.listen, sizeof next.listen, "%s", cur->listen);
        snprintf(next.state_dir, sizeof next.state_dir, "%s", cur->state_dir);
        snprintf(next.store_url, sizeof next.store_url, "%s", cur->store_url);
        snprintf(next.store_password_file, sizeof next.store_password_file,
                 "%s", cur->store_password_file);
        snprintf(next.node_name, sizeof next.node_name, "%s", cur->node_name);
        next.job_lease_ms = cur->job_lease_ms;
        next.http_threads = cur->http_threads;
        next.max_connections = cur->max_connections;
        next.connection_timeout_ms = cur->connection_timeout_ms;
        next.connection_memory = cur->connection_memory;
        next.header_timeout_ms = cur->header_timeout_ms;
        next.per_client_connections = cur->per_client_connections;
        next.workers = cur->workers;
        next.scanners = cur->scanners;
        memcpy(next.scanner, cur->scanner, sizeof next.scanner);
        next.nscanner = cur->nscanner;
        next.scanner_set = cur->scanner_set;
        if (scanners_reload(sc, &next, &err) < 0) {
            log_msg(LOG_ERR, NULL, "reload: %s; scanner pipelines unchanged",
                    err.msg);
            snprintf(next.scanner_pipeline, sizeof next.scanner_pipeline,
                     "%s", cur->scanner_pipeline);
            next.scanner_pipeline_set = cur->scanner_pipeline_set;
        }
        *cur = next;
        log_set_level(cur->log_level);
        apply_http_settings(env, cur);
        job_pool_set_timeout(pool, cur->job_timeout_ms);
        /* logged before the workers resume: the log shows the reload
         * before any job it lets start */
        log_msg(LOG_NOTICE, NULL, "configuration reloaded");
        job_pool_set_paused(pool, cur->paused);
        retention(s, cur);
    }
    sd_notify(0, "READY=1");
}

static void retention(store *s, const cfg *c)
{
    unsigned n = 0;
    geo_err err;
    int64_t cutoff = job_now_ms() - (int64_t)c->retention_age_ms;
    if (store_retention(s, cutoff, c->retention_bytes, &n, &err) < 0)
        log_msg(LOG_ERR, NULL, "retention: %s", err.msg);
    else if (n)
        log_msg(LOG_INFO, NULL, "retention deleted %u finished job(s)", n);
}

static void status(store *s, job_pool *pool)
{
    store_counts n;
    if (store_count(s, &n, NULL) == 0)
        sd_notifyf(0, "STATUS=%llu queued, %u running, %llu succeeded, "
                   "%llu failed",
                   (unsigned long long)n.by_state[JOB_QUEUED],
                   job_pool_busy(pool),
                   (unsigned long long)n.by_state[JOB_SUCCEEDED],
                   (unsigned long long)n.by_state[JOB_FAILED]);
}

int main(int argc, char **argv)
{
    if (cfg_wants_help(argc - 1, argv + 1)) {
        cfg_print_help(stdout, "facetd");
        return 0;
    }
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--version") == 0) {
            printf("facetd %s\n", FACET_VERSION);
            return 0;
        }
        /* hidden: the build writes facetd.conf(5) and the example file
         * from the key table with these (cfg_doc.h) */
        if (strcmp(argv[i], "--dump-config-man") == 0) {
            cfg_doc_man(stdout);
            return fflush(stdout) == 0 ? 0 : 1;
        }
        if (strcmp(argv[i], "--dump-config-example") == 0) {
            cfg_doc_example(stdout);
            return fflush(stdout) == 0 ? 0 : 1;
        }
    }
    cfg c;
    geo_err err = {{0}};
    if (cfg_load(&c, argc - 1, argv + 1, &err) < 0) {
        fprintf(stderr, "facetd: %s\n", err.msg);
        return 2;
    }
    log_set_level(c.log_level);

    /* Every thread inherits this mask; only the signalfd sees them. */
    sigset_t mask;
    sigemptyset(&mask);
    sigaddset(&mask, SIGTERM);
    sigaddset(&mask, SIGINT);
    sigaddset(&mask, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &mask, NULL);
    signal(SIGPIPE, SIG_IGN);
    int sfd = signalfd(-1, &mask, SFD_CLOEXEC);
    if (sfd < 0) {
        log_msg(LOG_ERR, NULL, "signalfd: %s", strerror(errno));
        return 1;
    }
    sd_notify(0, "STATUS=starting");

    int rc = 1, lfd = -1;
    store *s = NULL;
    metrics *m = NULL;
    par_pool *par = NULL;
    job_pool *pool = NULL;
    http_server *hs = NULL;
    scanners *sc = NULL;
    http_env env;
    http_env_init(&env);
    app a = {NULL, NULL, NULL, NULL};

    /* A scanner pipeline this build cannot run is a configuration error:
     * scans would be taken only to be refused. */
    if (scanners_new(&c, &sc, &err) < 0) {
        log_msg(LOG_ERR, NULL, "%s", err.msg);
        rc = 2;
        goto out;
    }
    const char *why;
    if (!scanners_enabled(sc, &why) && c.scanners)
        log_msg(LOG_WARNING, NULL, "scanner intake off: %s", why);
    a.sc = sc;

    int nfds = sd_listen_fds(1);
    if (nfds > 1) {
        log_msg(LOG_ERR, NULL, "socket activation passed %d sockets; facetd "
                "takes one", nfds);
        goto out;
    }
    if (nfds == 1) {
        lfd = SD_LISTEN_FDS_START;
        if (sd_is_socket(lfd, AF_UNSPEC, SOCK_STREAM, 1) <= 0) {
            log_msg(LOG_ERR, NULL, "the socket systemd passed is not a "
                    "listening stream socket");
            goto out;
        }
    } else {
        /* Refuse an unauthenticated public address before binding it. */
        bool lo;
        if (http_listen_check(c.listen, &lo, &err) < 0) {
            log_msg(LOG_ERR, NULL, "%s", err.msg);
            rc = 2;
            goto out;
        }
        if (check_auth(&c, lo, c.listen) < 0) {
            rc = 2;
            goto out;
        }
        if (http_listen_open(c.listen, 1024, &lfd, &err) < 0) {
            log_msg(LOG_ERR, NULL, "%s", err.msg);
            goto out;
        }
    }
    char where[128];
    bool loopback;
    if (http_listen_describe(lfd, where, sizeof where, &loopback, &err) < 0) {
        log_msg(LOG_ERR, NULL, "%s", err.msg);
        goto out;
    }
    if (check_auth(&c, loopback, where) < 0) {
        rc = 2;
        goto out;
    }
    unsigned requeued = 0;
    s = open_store_reserved(&c, where, &requeued, &err);
    if (!s) {
        log_msg(LOG_ERR, NULL, "%s", err.msg);
        goto out;
    }
    if (requeued)
        log_msg(LOG_NOTICE, NULL, "%u job(s) interrupted by the last stop "
                "queued again", requeued);
    retention(s, &c);
    m = metrics_new(http_route_names, http_nroutes);
    par = par_pool_new(0);
    if (!m || !par) {
        log_msg(LOG_ERR, NULL, "out of memory");
        goto out;
    }
    a.m = m;
    unsigned workers = c.workers ? c.workers : cpus();
    job_pool_config pc = {
        .workers = workers,
        .job_timeout_ms = c.job_timeout_ms,
        .progress_every_ms = 100,
        .parallel_for = par_for,
        .pf_user = par,
        .paused = c.paused,
        .exec = job_exec,
        .exec_user = m,
        .notify = on_job_changed,
        .done = on_job_done,
        .cb_user = &a,
    };
    pool = job_pool_start(s, &pc, &err);
    if (!pool) {
        log_msg(LOG_ERR, NULL, "%s", err.msg);
        goto out;
    }
    atomic_store(&a.pool, pool);
    store_set_events(s, &(store_events){on_store_event, &a});
    if (scanners_start(sc, s, pool, m, &err) < 0) {
        log_msg(LOG_ERR, NULL, "%s", err.msg);
        goto out;
    }
    env.s = s;
    env.pool = pool;
    env.sc = sc;
    env.m = m;
    env.workers = workers;
    apply_http_settings(&env, &c);
    unsigned threads = c.http_threads ? c.http_threads : cpus();
    http_config hc = {
        .listen_fd = lfd,
        .threads = threads,
        .max_connections = c.max_connections,
        .timeout_s = (unsigned)((c.connection_timeout_ms + 999) / 1000),
        .connection_memory = (size_t)c.connection_memory,
        .header_timeout_ms = c.header_timeout_ms,
        .per_client_connections = c.per_client_connections,
    };
    hs = http_server_start(&env, &hc, &err);
    if (!hs) {
        log_msg(LOG_ERR, NULL, "%s", err.msg);
        goto out;
    }
    atomic_store(&a.hs, hs);
    atomic_store(&env.ready, 1);
    log_msg(LOG_NOTICE, NULL, "facetd %s listening on http://%s (store %s, "
            "%u workers%s, %u HTTP threads%s)", FACET_VERSION, where,
            c.store_url[0] ? "PostgreSQL" : c.state_dir, workers,
            c.paused ? " paused" : "", threads, env.token[0] ? ", API token required" : "");
    sd_notifyf(0, "READY=1\nSTATUS=listening on %s", where);

    uint64_t wd_usec = 0;
    bool watchdog = sd_watchdog_enabled(0, &wd_usec) > 0 && wd_usec > 0;
    int tick_ms = watchdog && wd_usec / 2000 < 1000 ? (int)(wd_usec / 2000)
                                                    : 1000;
    int64_t next_retention = job_mono_ms() + 60000, next_status = 0;
    for (;;) {
        struct pollfd pfd = {sfd, POLLIN, 0};
        int pr = poll(&pfd, 1, tick_ms);
        if (pr < 0 && errno != EINTR) {
            log_msg(LOG_ERR, NULL, "poll: %s", strerror(errno));
            break;
        }
        if (pr > 0) {
            struct signalfd_siginfo si;
            if (read(sfd, &si, sizeof si) == (ssize_t)sizeof si) {
                if (si.ssi_signo == SIGHUP) {
                    reload(&c, argc - 1, argv + 1, &env, s, pool, sc,
                           loopback, where);
                    continue;
                }
                log_msg(LOG_NOTICE, NULL, "%s: shutting down",
                        strsignal((int)si.ssi_signo));
                break;
            }
        }
        int64_t now = job_mono_ms();
        if (watchdog && store_ping(s, NULL) == 0 && job_pool_healthy(pool))
            sd_notify(0, "WATCHDOG=1");
        if (now >= next_retention) {
            retention(s, &c);
            next_retention = now + 60000;
        }
        if (now >= next_status) {
            status(s, pool);
            next_status = now + 5000;
        }
    }
    rc = 0;
    atomic_store(&env.ready, 0);
    sd_notifyf(0, "STOPPING=1\nSTATUS=stopping: waiting up to %.3g s for "
               "running jobs", (double)c.shutdown_timeout_ms / 1000);
    http_server_quiesce(hs);
out:
    /* no more cluster events: what they reach is going away */
    if (s)
        store_set_events(s, &(store_events){NULL, NULL});
    atomic_store(&a.pool, NULL);
    /* scans still arriving are stored for the next start */
    scanners_detach_pool(sc);
    if (pool) {
        /* The grace period may be longer than systemd's stop timeout. */
        if (rc == 0)
            sd_notifyf(0, "EXTEND_TIMEOUT_USEC=%llu",
                       (unsigned long long)(c.shutdown_timeout_ms + 10000) *
                           1000);
        pool = job_pool_stop(pool, rc == 0 ? c.shutdown_timeout_ms : 0);
    }
    atomic_store(&a.hs, NULL);
    hs = http_server_stop(hs);
    sc = scanners_free(sc);
    if (lfd >= 0)
        close(lfd);
    s = store_close(s);
    m = metrics_free(m);
    par = par_pool_free(par);
    http_env_fini(&env);
    close(sfd);
    log_msg(rc ? LOG_ERR : LOG_NOTICE, NULL, rc ? "start-up failed" : "stopped");
    return rc;
}
