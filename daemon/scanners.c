/* scanners.c — scans in as jobs, RESULTs out (scanners.h).
 *
 * Invariants: owed holds one entry per job a RESULT is owed for, in the
 * order the jobs were made; an entry leaves it once its RESULT was handed
 * to the intake. Pipelines are read under plk (a reader per scan, the
 * writer on reload); owed, attached and the sender's state under mu;
 * pool under pool_mu, which on_scan_complete holds while it submits, so
 * the pool is never used after scanners_detach_pool returns. Lock order:
 * plk, then pool_mu; mu is never held while calling the store or the
 * intake. */
#include "scanners.h"

#include <errno.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "version.h"
#include "job_submit.h"
#include "log.h"
#include "model_io.h"
#include "pipeline.h"
#include "runner.h"

enum { SWEEP_MS = 1000, LIST_PAGE = 1000, ATTACHED_MAX = 256 };

#define SOURCE_PREFIX "usb:"

typedef struct owed {
    struct owed *next;
    char serial[PROTO_FSP_TEXT_MAX + 1];
    char job[JOB_ID_LEN + 1];
    int64_t t0_us;     /* monotonic µs of the scan's arrival; 0 when it
                          came before this start */
    bool check;        /* look it up in the store now */
} owed;

/* Which configured model a connected serial is (from its INFO), so a
 * scan picks its pipeline without asking the intake. */
typedef struct attached {
    struct attached *next;
    char serial[PROTO_FSP_TEXT_MAX + 1];
    scan_device_info info;
    int64_t scan_t0_us;  /* the first PROGRESS of the scan under way, 0
                            when none (for the intake's throughput) */
    uint32_t scan_contours; /* contours of the scan under way (its
                               PROGRESS total), 0 when unknown */
} attached;

/* One configured pipeline, as run and as shown. */
typedef struct plslot {
    bool set;
    proto_pipeline pl;
    json_t *json;      /* canonical form */
} plslot;

struct scanners {
    bool enabled;
    char why[768];
    scan_match list[SCAN_MATCH_MAX];
    char spec[SCAN_MATCH_MAX][CFG_SCANNER_LEN]; /* per-model pipeline, or "" */
    size_t nlist;

    pthread_rwlock_t plk;
    plslot model_pipe[SCAN_MATCH_MAX];
    plslot global;

    pthread_mutex_t pool_mu;
    job_pool *pool;

    store *s;
    metrics *m;
    scan_intake *in;

    pthread_mutex_t mu;
    pthread_cond_t cv;
    owed *owed_head, *owed_tail;
    attached *attached;
    size_t nattached;
    bool stop;
    pthread_t sender;
    bool sender_started;
};

static int64_t mono_us(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000 + ts.tv_nsec / 1000;
}

/* --- pipelines ----------------------------------------------------------- */

static void pipe_clear(plslot *p)
{
    if (p->set)
        proto_pipeline_free(&p->pl);
    json_decref(p->json);
    memset(p, 0, sizeof *p);
}

/* Loads spec into p and checks it against this build. */
static int pipe_load(plslot *p, const char *spec, geo_err *err)
{
    memset(p, 0, sizeof *p);
    json_t *pj = cfg_pipeline_json(spec, err);
    if (!pj)
        return -EINVAL;
    int r = proto_pipeline_from_json(pj, "pipeline", &p->pl, err);
    json_decref(pj);
    if (r < 0)
        return r;
    p->set = true;
    char dep[256];
    if (proto_pipeline_deprecations(&p->pl, dep, sizeof dep))
        log_msg(LOG_WARNING, NULL, "scanner pipeline %s: %s", spec, dep);
    r = runner_check_input(&p->pl, false, err);
    if (r == 0) {
        p->json = proto_pipeline_to_json(&p->pl);
        if (!p->json)
            r = geo_err_set(err, -ENOMEM, "out of memory");
    }
    if (r < 0)
        pipe_clear(p);
    return r;
}

/* Loads every pipeline of c into the new set (model[0 .. n), global). */
static int pipes_load(const cfg *c, const char spec[][CFG_SCANNER_LEN],
                      size_t n, plslot *model, plslot *global, geo_err *err)
{
    bool used_global = false;
    for (size_t i = 0; i < n; i++) {
        if (!spec[i][0]) {
            used_global = true;
            continue;
        }
        int r = pipe_load(&model[i], spec[i], err);
        if (r < 0) {
            char where[CFG_SCANNER_LEN + 32];
            snprintf(where, sizeof where, "[Scanners] Scanner=%s",
                     c->scanner[i]);
            geo_err_prefix(err, where);
            for (size_t j = 0; j < i; j++)
                pipe_clear(&model[j]);
            return r;
        }
    }
    if (!used_global)
        return 0;
    int r = pipe_load(global, c->scanner_pipeline, err);
    if (r < 0) {
        char where[CFG_PIPELINE_LEN + 32];
        snprintf(where, sizeof where, "[Scanners] Pipeline=%s",
                 c->scanner_pipeline);
        geo_err_prefix(err, where);
        for (size_t j = 0; j < n; j++)
            pipe_clear(&model[j]);
    }
    return r;
}

int scanners_new(const cfg *c, scanners **ret, geo_err *err)
{
    scanners *sc = calloc(1, sizeof *sc);
    if (!sc)
        return geo_err_set(err, -ENOMEM, "out of memory");
    pthread_rwlock_init(&sc->plk, NULL);
    pthread_mutex_init(&sc->pool_mu, NULL);
    pthread_mutex_init(&sc->mu, NULL);
    /* the sender's deadlines are CLOCK_MONOTONIC times: with the default
     * (realtime) clock every wait would end at once and the sender spin */
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&sc->cv, &ca);
    pthread_condattr_destroy(&ca);
    *ret = sc;
    if (!c->scanners) {
        snprintf(sc->why, sizeof sc->why, "[Scanners] Enabled=no");
        return 0;
    }
    for (unsigned i = 0; i < c->nscanner; i++) {
        char dev[64];
        const char *spec = cfg_scanner_split(c->scanner[i], dev, sizeof dev);
        int r = scan_match_parse(dev, &sc->list[i], err);
        if (r < 0) {
            *ret = scanners_free(sc);
            return r;
        }
        snprintf(sc->spec[i], sizeof sc->spec[i], "%s", spec);
    }
    sc->nlist = c->nscanner;
    int r = pipes_load(c, (const char (*)[CFG_SCANNER_LEN])sc->spec,
                       sc->nlist, sc->model_pipe, &sc->global, err);
    if (r < 0) {
        *ret = scanners_free(sc);
        return r;
    }
    sc->enabled = true;
    return 0;
}

bool scanners_enabled(scanners *sc, const char **why)
{
    if (why)
        *why = sc->why;
    return sc->enabled;
}

int scanners_reload(scanners *sc, const cfg *c, geo_err *err)
{
    if (!sc->enabled)
        return 0;
    plslot model[SCAN_MATCH_MAX], global;
    memset(model, 0, sizeof model);
    memset(&global, 0, sizeof global);
    int r = pipes_load(c, (const char (*)[CFG_SCANNER_LEN])sc->spec,
                       sc->nlist, model, &global, err);
    if (r < 0)
        return r;
    pthread_rwlock_wrlock(&sc->plk);
    for (size_t i = 0; i < sc->nlist; i++) {
        pipe_clear(&sc->model_pipe[i]);
        sc->model_pipe[i] = model[i];
    }
    pipe_clear(&sc->global);
    sc->global = global;
    pthread_rwlock_unlock(&sc->plk);
    return 0;
}

/* The pipeline for a scanner attached as vid:pid/kind (plk held), or
 * NULL for a device that is none of the configured models. */
static plslot *pipe_for(scanners *sc, const scan_device_info *info)
{
    const scan_match *m =
        scan_match_find(sc->list, sc->nlist, info->vid, info->pid, info->kind);
    if (!m)
        return NULL;
    plslot *p = &sc->model_pipe[m - sc->list];
    return p->set ? p : &sc->global;
}

/* --- owed RESULTs -------------------------------------------------------- */

static void owe(scanners *sc, const char *serial, const char *job,
                int64_t t0_us)
{
    owed *o = calloc(1, sizeof *o);
    if (!o) {
        log_msg(LOG_ERR, job, "out of memory: the RESULT for scanner %s "
                "will not be sent", serial);
        return;
    }
    snprintf(o->serial, sizeof o->serial, "%s", serial);
    snprintf(o->job, sizeof o->job, "%s", job);
    o->t0_us = t0_us;
    o->check = true;
    pthread_mutex_lock(&sc->mu);
    if (sc->owed_tail)
        sc->owed_tail->next = o;
    else
        sc->owed_head = o;
    sc->owed_tail = o;
    pthread_cond_signal(&sc->cv);
    pthread_mutex_unlock(&sc->mu);
}

/* Unlinks the entry for job (mu held); the caller frees it. */
static owed *owed_take(scanners *sc, const char *job)
{
    owed *prev = NULL;
    for (owed *o = sc->owed_head; o; prev = o, o = o->next) {
        if (strcmp(o->job, job) != 0)
            continue;
        if (prev)
            prev->next = o->next;
        else
            sc->owed_head = o->next;
        if (sc->owed_tail == o)
            sc->owed_tail = prev;
        return o;
    }
    return NULL;
}

void scanners_job_done(scanners *sc, const job_rec *job)
{
    if (!sc || !sc->enabled ||
        strncmp(job->source, SOURCE_PREFIX, strlen(SOURCE_PREFIX)) != 0)
        return;
    pthread_mutex_lock(&sc->mu);
    for (owed *o = sc->owed_head; o; o = o->next) {
        if (strcmp(o->job, job->id) == 0) {
            o->check = true;
            pthread_cond_signal(&sc->cv);
            break;
        }
    }
    pthread_mutex_unlock(&sc->mu);
}

static int64_t summary_count(const json_t *sum, const char *key)
{
    const json_t *v = json_object_get(sum, key);
    return json_is_integer(v) && json_integer_value(v) >= 0
               ? (int64_t)json_integer_value(v)
               : -1;
}

/* Looks the job of o up; when it has ended (or is gone) hands its RESULT
 * to the intake. True when o is settled and can go. */
static bool try_send(scanners *sc, const owed *o)
{
    job_rec j;
    geo_err err = {{0}};
    int r = store_get(sc->s, o->job, &j, &err);
    proto_fsp_result res;
    memset(&res, 0, sizeof res);
    snprintf(res.job, sizeof res.job, "%s", o->job);
    snprintf(res.url, sizeof res.url, "/v1/jobs/%s", o->job);
    res.facets_before = res.facets_after = res.self_intersections = -1;
    if (r == -ENOENT) {
        /* deleted before it ended: the scanner's later RESULTs must not
         * wait for it forever */
        snprintf(res.state, sizeof res.state, "canceled");
    } else if (r < 0) {
        log_msg(LOG_WARNING, o->job, "RESULT for scanner %s delayed: %s",
                o->serial, err.msg);
        return false;
    } else if (!job_state_terminal(j.state)) {
        job_rec_clear(&j);
        return false;
    } else {
        snprintf(res.state, sizeof res.state, "%s", job_state_name(j.state));
        json_t *sum = j.summary ? json_loads(j.summary, 0, NULL) : NULL;
        res.facets_before = summary_count(sum, "facets_before");
        res.facets_after = summary_count(sum, "facets_after");
        res.self_intersections = summary_count(sum, "self_intersections");
        res.valid = json_is_true(json_object_get(sum, "valid"));
        json_decref(sum);
        job_rec_clear(&j);
    }
    r = scan_send_result(sc->in, o->serial, &res);
    int64_t t1 = mono_us();
    if (r == -ENOENT) {
        log_msg(LOG_WARNING, o->job, "scanner %s is owed no RESULT for this "
                "job (too many owed); none sent", o->serial);
        return true;
    }
    if (r < 0) {
        log_msg(LOG_ERR, o->job, "RESULT for scanner %s: %s", o->serial,
                strerror(-r));
        return true;
    }
    scan_device_status st;
    bool online = scan_get(sc->in, o->serial, &st) == 0 &&
                  st.state != SCAN_STATE_OFFLINE;
    if (o->t0_us && online) {
        double secs = (double)(t1 - o->t0_us) / 1e6;
        metrics_scan_result(sc->m, secs);
        log_msg(LOG_INFO, o->job, "RESULT (%s) to scanner %s %.1f ms after "
                "its SCAN_DONE", res.state, o->serial, secs * 1e3);
    } else {
        metrics_scan_result(sc->m, -1);
        log_msg(LOG_INFO, o->job, "RESULT (%s) for scanner %s %s", res.state,
                o->serial, online ? "sent" : "queued until it is back");
    }
    return true;
}

static void *sender_main(void *arg)
{
    scanners *sc = arg;
    int64_t next_sweep = 0;
    pthread_mutex_lock(&sc->mu);
    while (!sc->stop) {
        int64_t now = job_mono_ms();
        if (now >= next_sweep) {
            for (owed *o = sc->owed_head; o; o = o->next)
                o->check = true;
            next_sweep = now + SWEEP_MS;
        }
        owed *o = sc->owed_head;
        while (o && !o->check)
            o = o->next;
        if (!o) {
            struct timespec ts;
            clock_gettime(CLOCK_MONOTONIC, &ts);
            int64_t wait = next_sweep - now;
            ts.tv_sec += wait / 1000;
            ts.tv_nsec += (wait % 1000) * 1000000;
            if (ts.tv_nsec >= 1000000000) {
                ts.tv_sec++;
                ts.tv_nsec -= 1000000000;
            }
            pthread_cond_timedwait(&sc->cv, &sc->mu, &ts);
            continue;
        }
        o->check = false;
        owed copy = *o;
        pthread_mutex_unlock(&sc->mu);
        bool settled = try_send(sc, &copy);
        pthread_mutex_lock(&sc->mu);
        if (settled)
            free(owed_take(sc, copy.job));
    }
    pthread_mutex_unlock(&sc->mu);
    return NULL;
}

/* --- intake callbacks ---------------------------------------------------- */

static void on_device(void *user, const scan_device_info *d)
{
    scanners *sc = user;
    pthread_mutex_lock(&sc->mu);
    attached *a = sc->attached, *prev = NULL;
    while (a && strcmp(a->serial, d->serial) != 0) {
        prev = a;
        a = a->next;
    }
    if (a) {
        if (prev) {
            prev->next = a->next;
            a->next = sc->attached;
            sc->attached = a;
        }
    } else if (sc->nattached == ATTACHED_MAX) {
        /* the least recently attached serial makes room */
        attached **pp = &sc->attached;
        while ((*pp)->next)
            pp = &(*pp)->next;
        a = *pp;
        *pp = NULL;
        a->next = sc->attached;
        sc->attached = a;
    } else if ((a = calloc(1, sizeof *a)) != NULL) {
        a->next = sc->attached;
        sc->attached = a;
        sc->nattached++;
    }
    if (a) {
        snprintf(a->serial, sizeof a->serial, "%s", d->serial);
        a->info = *d;
        a->scan_t0_us = 0;
    }
    pthread_mutex_unlock(&sc->mu);
    log_msg(LOG_NOTICE, NULL, "scanner %s connected: %s %s, firmware %s, "
            "%u contours, %04x:%04x over %s at %s", d->serial, d->vendor,
            d->model, d->firmware, d->contours, d->vid, d->pid,
            scan_kind_name(d->kind), d->path);
}

static attached *attached_find(scanners *sc, const char *serial)
{
    for (attached *a = sc->attached; a; a = a->next)
        if (strcmp(a->serial, serial) == 0)
            return a;
    return NULL;
}

static void on_progress(void *user, const char *serial, uint32_t done,
                        uint32_t total)
{
    scanners *sc = user;
    pthread_mutex_lock(&sc->mu);
    attached *a = attached_find(sc, serial);
    if (a && (done == 0 || !a->scan_t0_us))
        a->scan_t0_us = mono_us();
    if (a)
        a->scan_contours = total;
    pthread_mutex_unlock(&sc->mu);
}

static void on_device_gone(void *user, const char *serial)
{
    (void)user;
    log_msg(LOG_NOTICE, NULL, "scanner %s disconnected", serial);
}

static void on_notice(void *user, const char *serial, const char *msg)
{
    (void)user;
    if (serial[0])
        log_msg(LOG_WARNING, NULL, "scanner %s: %s", serial, msg);
    else
        log_msg(LOG_WARNING, NULL, "scanner intake: %s", msg);
}

static int on_scan_complete(void *user, const char *serial,
                            const uint8_t *bytes, size_t len, proto_format fmt,
                            char *ret_job, size_t job_cap)
{
    scanners *sc = user;
    int64_t t0 = mono_us();
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem(bytes, len, fmt, NULL, &err);
    if (!p) {
        metrics_scan_refused(sc->m, METRICS_REFUSED_INVALID);
        log_msg(LOG_WARNING, NULL, "scan from %s refused (%zu bytes of %s): "
                "%s", serial, len, proto_format_name(fmt), err.msg);
        return -EINVAL;
    }
    scan_device_info info;
    memset(&info, 0, sizeof info);
    int64_t began = 0;
    uint32_t contours = 0;
    pthread_mutex_lock(&sc->mu);
    attached *a = attached_find(sc, serial);
    if (a) {
        info = a->info;
        began = a->scan_t0_us;
        contours = a->scan_contours ? a->scan_contours : a->info.contours;
        a->scan_t0_us = 0;
        a->scan_contours = 0;
    }
    pthread_mutex_unlock(&sc->mu);
    int64_t t_parsed = mono_us();
    char source[JOB_SOURCE_MAX];
    snprintf(source, sizeof source, SOURCE_PREFIX "%s", serial);
    job_rec job;
    bool replayed = false;
    int r;
    pthread_rwlock_rdlock(&sc->plk);
    plslot *pp = pipe_for(sc, &info);
    if (!pp) {
        r = geo_err_set(&err, -ENODEV, "not a configured scanner model");
    } else {
        /* the correction reads the view step off the scan; the scanner
         * knows it exactly (the scan's contours, else INFO's), so its
         * jobs carry it */
        proto_pipeline pl = {0};
        r = proto_pipeline_copy(&pp->pl, &pl);
        if (r < 0) {
            geo_err_set(&err, r, "out of memory");
        } else {
            proto_pipeline_set_views(&pl, contours);
            job_request rq = {
                .model = p,
                .pipeline = &pl,
                .priority = JOB_PRIO_HIGH,
                .source = source,
            };
            pthread_mutex_lock(&sc->pool_mu);
            r = job_submit(sc->s, sc->pool, UINT_MAX, &rq, &job, &replayed,
                           &err);
            pthread_mutex_unlock(&sc->pool_mu);
            proto_pipeline_free(&pl);
        }
    }
    pthread_rwlock_unlock(&sc->plk);
    unsigned nv = p->nverts, nf = p->nfacets;
    geo_poly_free(p);
    if (r < 0) {
        metrics_scan_refused(sc->m, METRICS_REFUSED_STORE);
        log_msg(LOG_ERR, NULL, "scan from %s refused: %s", serial, err.msg);
        return r;
    }
    snprintf(ret_job, job_cap, "%s", job.id);
    char rate[96] = "";
    if (began && t0 > began)
        snprintf(rate, sizeof rate, "received in %.1f ms (%.2f MB/s), ",
                 (double)(t0 - began) / 1e3,
                 (double)len / (double)(t0 - began));
    log_msg(LOG_INFO, job.id, "queued from scanner %s (%zu bytes of %s, %u "
            "vertices, %u facets; %sparsed in %.1f ms, stored in %.1f ms)",
            serial, len, proto_format_name(fmt), nv, nf, rate,
            (double)(t_parsed - t0) / 1e3,
            (double)(mono_us() - t_parsed) / 1e3);
    owe(sc, serial, job.id, t0);
    job_rec_clear(&job);
    return 0;
}

/* --- start and stop ------------------------------------------------------ */

/* The store's unfinished usb: jobs, oldest first, into *ret. */
static int unfinished_scan_jobs(store *s, job_rec **ret, size_t *ret_n,
                                geo_err *err)
{
    job_rec *all = NULL;
    size_t n = 0;
    int r = 0;
    static const job_state states[] = {JOB_QUEUED, JOB_RUNNING};
    for (size_t k = 0; k < 2 && r == 0; k++) {
        char after[JOB_ID_LEN + 1] = "";
        for (;;) {
            store_filter f = {.state = (int)states[k],
                              .after = after[0] ? after : NULL,
                              .limit = LIST_PAGE};
            job_rec *v;
            size_t m;
            r = store_list(s, &f, &v, &m, err);
            if (r < 0)
                break;
            job_rec *grown = m ? realloc(all, (n + m) * sizeof *all) : all;
            if (m && !grown) {
                for (size_t i = 0; i < m; i++)
                    job_rec_clear(&v[i]);
                free(v);
                r = geo_err_set(err, -ENOMEM, "out of memory");
                break;
            }
            all = grown;
            for (size_t i = 0; i < m; i++) {
                if (strncmp(v[i].source, SOURCE_PREFIX,
                            strlen(SOURCE_PREFIX)) == 0)
                    all[n++] = v[i];
                else
                    job_rec_clear(&v[i]);
            }
            if (m)
                memcpy(after, v[m - 1].id, sizeof after);
            free(v);
            if (m < LIST_PAGE)
                break;
        }
    }
    if (r < 0) {
        for (size_t i = 0; i < n; i++)
            job_rec_clear(&all[i]);
        free(all);
        return r;
    }
    /* ids are ULIDs: their order is the order the scans arrived in */
    for (size_t i = 1; i < n; i++)
        for (size_t j = i; j > 0 && strcmp(all[j - 1].id, all[j].id) > 0;
             j--) {
            job_rec t = all[j];
            all[j] = all[j - 1];
            all[j - 1] = t;
        }
    *ret = all;
    *ret_n = n;
    return 0;
}

int scanners_start(scanners *sc, store *s, job_pool *pool, metrics *m,
                   geo_err *err)
{
    if (!sc->enabled)
        return 0;
    sc->s = s;
    sc->pool = pool;
    sc->m = m;
    job_rec *prior = NULL;
    size_t nprior = 0;
    int r = unfinished_scan_jobs(s, &prior, &nprior, err);
    if (r < 0)
        return r;
    scan_callbacks cb = {
        .user = sc,
        .on_device = on_device,
        .on_device_gone = on_device_gone,
        .on_scan_complete = on_scan_complete,
        .on_progress = on_progress,
        .on_notice = on_notice,
    };
    scan_options opt;
    scan_options_default(&opt);
    snprintf(opt.host_version, sizeof opt.host_version, "%s", FACET_VERSION);
    geo_err ierr = {{0}};
    sc->in = scan_intake_start(sc->list, sc->nlist, &cb, &opt, &ierr);
    if (!sc->in) {
        r = geo_err_set(err, -EIO, "scanner intake: %s (start with "
                        "--no-scanners to serve without scanners)",
                        ierr.msg);
        goto out;
    }
    for (size_t i = 0; i < nprior; i++) {
        const char *serial = prior[i].source + strlen(SOURCE_PREFIX);
        if (scan_owe_result(sc->in, serial, prior[i].id) == 0)
            owe(sc, serial, prior[i].id, 0);
        else
            log_msg(LOG_WARNING, prior[i].id, "no RESULT will go to "
                    "scanner %s for this job", serial);
    }
    if (nprior)
        log_msg(LOG_NOTICE, NULL, "%zu scanner job(s) from before this start "
                "will send their RESULT when they end", nprior);
    if (pthread_create(&sc->sender, NULL, sender_main, sc) != 0) {
        r = geo_err_set(err, -EAGAIN, "cannot start the RESULT thread");
        goto out;
    }
    sc->sender_started = true;
    char devs[SCAN_MATCH_MAX * 24] = "";
    for (size_t i = 0; i < sc->nlist; i++)
        snprintf(devs + strlen(devs), sizeof devs - strlen(devs), "%s%04x:%04x"
                 ":%s", i ? ", " : "", sc->list[i].vid, sc->list[i].pid,
                 scan_kind_name(sc->list[i].kind));
    log_msg(LOG_NOTICE, NULL, "scanner intake watching %s", devs);
out:
    for (size_t i = 0; i < nprior; i++)
        job_rec_clear(&prior[i]);
    free(prior);
    return r;
}

void scanners_detach_pool(scanners *sc)
{
    if (!sc)
        return;
    pthread_mutex_lock(&sc->pool_mu);
    sc->pool = NULL;
    pthread_mutex_unlock(&sc->pool_mu);
}

scanners *scanners_free(scanners *sc)
{
    if (!sc)
        return NULL;
    if (sc->sender_started) {
        pthread_mutex_lock(&sc->mu);
        sc->stop = true;
        pthread_cond_signal(&sc->cv);
        pthread_mutex_unlock(&sc->mu);
        pthread_join(sc->sender, NULL);
    }
    sc->in = scan_intake_stop(sc->in);
    while (sc->owed_head) {
        owed *o = sc->owed_head;
        sc->owed_head = o->next;
        free(o);
    }
    while (sc->attached) {
        attached *a = sc->attached;
        sc->attached = a->next;
        free(a);
    }
    for (size_t i = 0; i < SCAN_MATCH_MAX; i++)
        pipe_clear(&sc->model_pipe[i]);
    pipe_clear(&sc->global);
    pthread_cond_destroy(&sc->cv);
    pthread_mutex_destroy(&sc->mu);
    pthread_mutex_destroy(&sc->pool_mu);
    pthread_rwlock_destroy(&sc->plk);
    free(sc);
    return NULL;
}

/* --- status -------------------------------------------------------------- */

static json_t *text_or_null(bool seen, const char *s)
{
    return seen ? json_string(s) : json_null();
}

static json_t *status_to_json(scanners *sc, const scan_device_status *st)
{
    const scan_device_info *d = &st->info;
    char usb_id[16], seen_at[32], url[80];
    snprintf(usb_id, sizeof usb_id, "%04x:%04x", d->vid, d->pid);
    job_time_format(st->last_seen_ms, seen_at, sizeof seen_at);
    snprintf(url, sizeof url, "/v1/jobs/%s", st->last_job);
    json_t *o = json_object();
    if (!o)
        return NULL;
    int e = 0;
    e |= json_object_set_new(o, "serial", json_string(d->serial));
    e |= json_object_set_new(o, "vendor", text_or_null(st->seen, d->vendor));
    e |= json_object_set_new(o, "model", text_or_null(st->seen, d->model));
    e |= json_object_set_new(o, "firmware",
                             text_or_null(st->seen, d->firmware));
    e |= json_object_set_new(o, "contours", st->seen
                                                ? json_integer(d->contours)
                                                : json_null());
    e |= json_object_set_new(o, "usb_id", text_or_null(st->seen, usb_id));
    e |= json_object_set_new(o, "transport",
                             text_or_null(st->seen, scan_kind_name(d->kind)));
    e |= json_object_set_new(o, "path", text_or_null(st->seen, d->path));
    e |= json_object_set_new(o, "state",
                             json_string(scan_state_name(st->state)));
    double frac = st->progress_total
                      ? (double)st->progress_done / st->progress_total
                      : 0.0;
    e |= json_object_set_new(o, "progress", json_real(frac > 1 ? 1 : frac));
    e |= json_object_set_new(o, "contours_done",
                             json_integer(st->progress_done));
    e |= json_object_set_new(o, "contours_total",
                             json_integer(st->progress_total));
    e |= json_object_set_new(o, "last_job", st->last_job[0]
                                                ? json_string(st->last_job)
                                                : json_null());
    e |= json_object_set_new(o, "last_job_url", st->last_job[0]
                                                    ? json_string(url)
                                                    : json_null());
    e |= json_object_set_new(o, "scans_completed",
                             json_integer((json_int_t)st->scans_completed));
    e |= json_object_set_new(o, "scans_dropped",
                             json_integer((json_int_t)st->scans_dropped));
    e |= json_object_set_new(o, "last_seen", st->last_seen_ms
                                                 ? json_string(seen_at)
                                                 : json_null());
    json_t *pj = json_null();
    if (st->seen) {
        pthread_rwlock_rdlock(&sc->plk);
        plslot *cur = pipe_for(sc, d);
        if (cur && cur->json)
            pj = json_deep_copy(cur->json);
        pthread_rwlock_unlock(&sc->plk);
    }
    e |= json_object_set_new(o, "pipeline", pj ? pj : json_null());
    if (e) {
        json_decref(o);
        return NULL;
    }
    return o;
}

json_t *scanners_list_json(scanners *sc)
{
    json_t *arr = json_array();
    json_t *o = json_pack("{s:b}", "enabled", sc->enabled);
    if (!arr || !o)
        goto fail;
    if (!sc->enabled && json_object_set_new(o, "disabled_reason",
                                            json_string(sc->why)) < 0)
        goto fail;
    if (sc->in) {
        scan_device_status *st;
        size_t n;
        if (scan_list(sc->in, &st, &n) < 0)
            goto fail;
        for (size_t i = 0; i < n; i++) {
            json_t *one = status_to_json(sc, &st[i]);
            if (!one || json_array_append_new(arr, one) < 0) {
                free(st);
                goto fail;
            }
        }
        free(st);
    }
    if (json_object_set_new(o, "scanners", arr) < 0) {
        arr = NULL;
        goto fail;
    }
    return o;
fail:
    json_decref(arr);
    json_decref(o);
    return NULL;
}

int scanners_status_json(scanners *sc, const char *serial, json_t **ret)
{
    scan_device_status st;
    if (!sc->in || scan_get(sc->in, serial, &st) < 0)
        return -ENOENT;
    *ret = status_to_json(sc, &st);
    return *ret ? 0 : -ENOMEM;
}

int scanners_request_scan(scanners *sc, const char *serial, uint8_t mode)
{
    if (!sc->in)
        return -ENOENT;
    return scan_request_start(sc->in, serial, mode);
}

void scanners_get_metrics(scanners *sc, metrics_scanners *ret)
{
    memset(ret, 0, sizeof *ret);
    ret->enabled = sc && sc->in;
    if (ret->enabled)
        scan_get_metrics(sc->in, &ret->intake);
}
