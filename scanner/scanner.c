/* scanner.c — the registry of scanners, one thread per connection, and
 * the public API of scanner.h.
 *
 * A connection (scan_conn) is one attachment of one device: its thread
 * opens the transport, runs the session (session.h) and ends when the
 * device leaves or fails. A known scanner (scan_known) is a serial seen
 * in an INFO; it outlives its connections, so that its counters, its
 * last job and the RESULTs owed to it survive a re-plug.
 *
 * Session events are queued while the connection's smu is held and
 * delivered to the caller's callbacks after it is released, so callbacks
 * may call back into this API. RESULTs owed to a scanner form a queue in
 * the order of its scans; only its head may be sent, so RESULTs arrive in
 * scan order even when jobs end out of order. */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "intake.h"
#include "session.h"

enum {
    READ_MAX = PROTO_FSP_MAX_FRAME,
    MAX_WAIT_MS = 1000,       /* longest read: bounds shutdown latency */
    OPEN_TRIES = 5,
    OPEN_RETRY_MS = 300,
    PENDING_MAX = 64,         /* RESULTs owed to one scanner */
    KNOWN_MAX = 256,          /* scanners remembered (offline ones too) */
};

typedef enum ev_kind {
    EV_INFO,
    EV_STARTED,
    EV_PROGRESS,
    EV_COMPLETE,
    EV_DROPPED,
    EV_DEVICE_ERROR,
} ev_kind;

typedef struct conn_event {
    struct conn_event *next;
    ev_kind kind;
    proto_fsp_info info;
    uint32_t a, b;
    uint8_t *bytes;
    size_t len;
    uint8_t format;
    char text[160];
} conn_event;

struct scan_conn {
    scan_conn *next;
    scan_intake *in;
    scan_devaddr addr;
    pthread_t thread;
    atomic_bool leave, finished;
    pthread_mutex_t smu;
    scan_session *s;       /* NULL until open, and again after close */
    scan_transport *t;
    conn_event *ev_head, *ev_tail;
    scan_known *known;     /* set under in->mu once INFO arrived */
    char usb_serial[PROTO_FSP_TEXT_MAX + 1];
};

/* A RESULT owed for a scan. While naming, on_scan_complete is running and
 * the job id is not known yet; a RESULT that arrives meanwhile for a job
 * nobody owes is taken to be this one's (a job may end before the
 * callback that created it returns), and checked once the id is known.
 * A scanner has at most one entry naming, since its callbacks never run
 * concurrently. */
typedef struct pending_result {
    char job[PROTO_FSP_TEXT_MAX + 1];
    bool naming, ready;
    bool prior;             /* owed from before this intake started
                               (scan_owe_result): older than every scan
                               seen since, so queued ahead of them */
    proto_fsp_result r;
} pending_result;

struct scan_known {
    scan_known *next;
    scan_device_info info;  /* only serial until the first INFO */
    bool seen;              /* an INFO arrived since the intake started */
    scan_conn *conn;        /* the connection it is on, NULL when offline */
    scan_state state;
    uint32_t pdone, ptotal;
    char last_job[PROTO_FSP_TEXT_MAX + 1];
    uint64_t completed, dropped;
    int64_t last_seen_ms;
    pending_result pend[PENDING_MAX];
    size_t npend;
};

static uint64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

static int64_t real_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

const char *scan_state_name(scan_state st)
{
    switch (st) {
    case SCAN_STATE_IDLE: return "idle";
    case SCAN_STATE_SCANNING: return "scanning";
    case SCAN_STATE_OFFLINE: return "offline";
    }
    return "unknown";
}

void scan_options_default(scan_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->scan_timeout_ms = 30000;
    opt->resend_ms = 5000;
    opt->io_timeout_ms = 2000;
    opt->max_model = 64u << 20;
    strcpy(opt->host_version, "0.1.0");
}

static void notice(scan_intake *in, const char *serial, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void notice(scan_intake *in, const char *serial, const char *fmt, ...)
{
    if (!in->cb.on_notice)
        return;
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    in->cb.on_notice(in->cb.user, serial ? serial : "", msg);
}

/* --- session events (called with the connection's smu held) ------------ */

static conn_event *push_event(scan_conn *c, ev_kind kind)
{
    conn_event *e = calloc(1, sizeof *e);
    if (!e)
        return NULL;
    e->kind = kind;
    if (c->ev_tail)
        c->ev_tail->next = e;
    else
        c->ev_head = e;
    c->ev_tail = e;
    return e;
}

static void sev_info(void *u, const proto_fsp_info *info)
{
    conn_event *e = push_event(u, EV_INFO);
    if (e)
        e->info = *info;
}

static void sev_started(void *u, uint8_t mode, uint32_t contours)
{
    conn_event *e = push_event(u, EV_STARTED);
    if (e) {
        e->a = mode;
        e->b = contours;
    }
}

static void sev_progress(void *u, uint32_t done, uint32_t total)
{
    conn_event *e = push_event(u, EV_PROGRESS);
    if (e) {
        e->a = done;
        e->b = total;
    }
}

static void sev_complete(void *u, uint8_t *bytes, size_t len, uint8_t format)
{
    conn_event *e = push_event(u, EV_COMPLETE);
    if (!e) {
        free(bytes);
        return;
    }
    e->bytes = bytes;
    e->len = len;
    e->format = format;
}

static void sev_dropped(void *u, const char *why)
{
    conn_event *e = push_event(u, EV_DROPPED);
    if (e)
        snprintf(e->text, sizeof e->text, "%s", why);
}

static void sev_device_error(void *u, uint16_t code, const char *msg)
{
    conn_event *e = push_event(u, EV_DEVICE_ERROR);
    if (e) {
        e->a = code;
        snprintf(e->text, sizeof e->text, "%s", msg);
    }
}

/* --- known scanners (in->mu held) --------------------------------------- */

static scan_known *known_find(scan_intake *in, const char *serial)
{
    for (scan_known *k = in->known; k; k = k->next)
        if (strcmp(k->info.serial, serial) == 0)
            return k;
    return NULL;
}

/* A new, offline entry for serial, or NULL (out of memory, or KNOWN_MAX
 * scanners that are online or owed a RESULT). A device inventing serials
 * must not grow the list without end: past KNOWN_MAX an offline scanner
 * that is owed nothing goes. */
static scan_known *known_add(scan_intake *in, const char *serial)
{
    size_t n = 0;
    scan_known **victim = NULL;
    for (scan_known **pp = &in->known; *pp; pp = &(*pp)->next) {
        n++;
        if (!(*pp)->conn && (*pp)->npend == 0)
            victim = pp;
    }
    if (n >= KNOWN_MAX && victim) {
        scan_known *v = *victim;
        *victim = v->next;
        free(v);
        n--;
    }
    scan_known *k = n < KNOWN_MAX ? calloc(1, sizeof *k) : NULL;
    if (!k)
        return NULL;
    snprintf(k->info.serial, sizeof k->info.serial, "%s", serial);
    k->state = SCAN_STATE_OFFLINE;
    k->next = in->known;
    in->known = k;
    return k;
}

/* Sends the RESULTs at the head of k's queue that are ready, as long as
 * k is online and greeted. */
static void deliver_results(scan_intake *in, scan_known *k)
{
    while (k->npend > 0 && k->pend[0].ready && !k->pend[0].naming &&
           k->conn) {
        scan_conn *c = k->conn;
        int r = -ENODEV;
        pthread_mutex_lock(&c->smu);
        if (c->s && c->t && scan_session_ready(c->s)) {
            r = scan_session_send_result(c->s, &k->pend[0].r, mono_ms());
            if (r == 0)
                scan_session_flush(c->s, c->t, in->opt.io_timeout_ms);
        }
        pthread_mutex_unlock(&c->smu);
        /* -EINVAL cannot be retried (scan_send_result checked it first);
         * anything else is tried again when the scanner is next ready */
        if (r < 0 && r != -EINVAL)
            return;
        k->npend--;
        memmove(k->pend, k->pend + 1, k->npend * sizeof *k->pend);
    }
}

/* --- delivering events (no lock held) ------------------------------------ */

static void on_info_event(scan_conn *c, const proto_fsp_info *info)
{
    scan_intake *in = c->in;
    scan_device_info di;
    pthread_mutex_lock(&in->mu);
    scan_known *k = known_find(in, info->serial);
    if (k && k->conn && k->conn != c) {
        pthread_mutex_unlock(&in->mu);
        notice(in, info->serial,
               "%s: serial %s is already connected at %s; ignoring this one",
               c->addr.path, info->serial, k->info.path);
        atomic_store(&c->leave, true);
        return;
    }
    if (!k)
        k = known_add(in, info->serial);
    if (!k) {
        pthread_mutex_unlock(&in->mu);
        notice(in, info->serial, "%s: too many scanners; ignoring this one",
               c->addr.path);
        atomic_store(&c->leave, true);
        return;
    }
    if (c->known && c->known != k)
        c->known->conn = NULL;
    snprintf(k->info.serial, sizeof k->info.serial, "%s", info->serial);
    snprintf(k->info.vendor, sizeof k->info.vendor, "%s", info->vendor);
    snprintf(k->info.model, sizeof k->info.model, "%s", info->model);
    snprintf(k->info.firmware, sizeof k->info.firmware, "%s",
             info->firmware);
    k->info.contours = info->contours;
    k->info.vid = c->addr.vid;
    k->info.pid = c->addr.pid;
    k->info.kind = c->addr.kind;
    snprintf(k->info.path, sizeof k->info.path, "%s", c->addr.path);
    bool first = k->conn != c;
    k->conn = c;
    k->seen = true;
    c->known = k;
    if (first)
        k->state = SCAN_STATE_IDLE;
    k->last_seen_ms = real_ms();
    di = k->info;
    deliver_results(in, k);
    pthread_mutex_unlock(&in->mu);
    if (c->usb_serial[0] && strcmp(c->usb_serial, info->serial) != 0)
        notice(in, info->serial,
               "%s: USB serial \"%s\" differs from INFO serial \"%s\"",
               c->addr.path, c->usb_serial, info->serial);
    if (first && in->cb.on_device)
        in->cb.on_device(in->cb.user, &di);
}

static void deliver(scan_conn *c, conn_event *e)
{
    scan_intake *in = c->in;
    if (e->kind == EV_INFO) {
        on_info_event(c, &e->info);
        return;
    }
    char serial[PROTO_FSP_TEXT_MAX + 1] = "";
    pthread_mutex_lock(&in->mu);
    scan_known *k = c->known;
    if (k) {
        snprintf(serial, sizeof serial, "%s", k->info.serial);
        k->last_seen_ms = real_ms();
        switch (e->kind) {
        case EV_STARTED:
            k->state = SCAN_STATE_SCANNING;
            k->pdone = 0;
            k->ptotal = e->b;
            break;
        case EV_PROGRESS:
            k->pdone = e->a;
            k->ptotal = e->b;
            break;
        case EV_COMPLETE:
            k->state = SCAN_STATE_IDLE;
            k->pdone = k->ptotal = 0;
            break;
        case EV_DROPPED:
            k->state = SCAN_STATE_IDLE;
            k->pdone = k->ptotal = 0;
            k->dropped++;
            break;
        default:
            break;
        }
    }
    pthread_mutex_unlock(&in->mu);
    if (!k) {
        free(e->bytes);
        return;
    }
    switch (e->kind) {
    case EV_PROGRESS:
        if (in->cb.on_progress)
            in->cb.on_progress(in->cb.user, serial, e->a, e->b);
        break;
    case EV_COMPLETE: {
        char job[PROTO_FSP_TEXT_MAX + 1] = "";
        proto_format fmt = e->format == PROTO_FSP_MODEL_FMB1 ? PROTO_FMT_FMB1
                                                             : PROTO_FMT_JSON;
        char lost[PROTO_FSP_TEXT_MAX + 1] = "";
        char unknown[PROTO_FSP_TEXT_MAX + 1] = "";
        pthread_mutex_lock(&in->mu);
        if (k->npend == PENDING_MAX) {
            snprintf(lost, sizeof lost, "%s", k->pend[0].job);
            k->npend--;
            memmove(k->pend, k->pend + 1, k->npend * sizeof *k->pend);
        }
        memset(&k->pend[k->npend], 0, sizeof k->pend[0]);
        k->pend[k->npend++].naming = true;
        pthread_mutex_unlock(&in->mu);
        int r = in->cb.on_scan_complete
                    ? in->cb.on_scan_complete(in->cb.user, serial, e->bytes,
                                              e->len, fmt, job, sizeof job)
                    : -ENOTSUP;
        job[sizeof job - 1] = '\0';
        bool kept = r == 0 && job[0];
        /* the scan is ACKed only now that the caller has it (stored as a
         * job): a scan the device saw ACKed is never lost */
        pthread_mutex_lock(&c->smu);
        if (c->s && c->t &&
            scan_session_ack_done(c->s, kept, mono_ms()) == 0)
            scan_session_flush(c->s, c->t, in->opt.io_timeout_ms);
        pthread_mutex_unlock(&c->smu);
        pthread_mutex_lock(&in->mu);
        if (kept)
            k->completed++;
        else
            k->dropped++;
        size_t i = 0;
        while (i < k->npend && !k->pend[i].naming)
            i++;
        if (i < k->npend) {
            pending_result *p = &k->pend[i];
            if (kept) {
                snprintf(k->last_job, sizeof k->last_job, "%s", job);
                snprintf(p->job, sizeof p->job, "%s", job);
                p->naming = false;
                if (p->ready && strcmp(p->r.job, job) != 0) {
                    snprintf(unknown, sizeof unknown, "%s", p->r.job);
                    p->ready = false;
                }
            } else {
                k->npend--;
                memmove(p, p + 1, (k->npend - i) * sizeof *p);
            }
            deliver_results(in, k);
        }
        pthread_mutex_unlock(&in->mu);
        /* notices only without in->mu: on_notice may call back in */
        if (lost[0])
            notice(in, serial, "RESULT of job %s dropped: %d owed", lost,
                   PENDING_MAX);
        if (unknown[0])
            notice(in, serial, "RESULT of unknown job %s dropped", unknown);
        if (!kept)
            notice(in, serial, "scan refused by the host (%s): ABORT sent",
                   strerror(r < 0 ? -r : EINVAL));
        break;
    }
    case EV_DROPPED:
        notice(in, serial, "scan dropped: %s", e->text);
        break;
    case EV_DEVICE_ERROR:
        notice(in, serial, "ERROR %u from the device: %s", e->a, e->text);
        break;
    default:
        break;
    }
    free(e->bytes);
}

static void deliver_all(scan_conn *c)
{
    pthread_mutex_lock(&c->smu);
    conn_event *e = c->ev_head;
    c->ev_head = c->ev_tail = NULL;
    pthread_mutex_unlock(&c->smu);
    while (e) {
        conn_event *next = e->next;
        deliver(c, e);
        free(e);
        e = next;
    }
}

/* --- the connection thread ---------------------------------------------- */

static void add_stats(scan_metrics *m, const scan_session_stats *st,
                      const scan_transport *t)
{
    m->frames_in += st->frames_in;
    m->frames_out += st->frames_out;
    m->crc_errors += st->crc_errors;
    m->bad_frames += st->bad_magic + st->too_long + st->bad_frames;
    m->seq_errors += st->seq_errors;
    m->naks_sent += st->naks_sent;
    m->naks_received += st->naks_received;
    m->scans_completed += st->scans_completed;
    m->scans_dropped += st->scans_dropped;
    m->model_bytes += st->model_bytes;
    if (t)
        m->reassembly_failures += atomic_load(&t->reassembly_failures);
}

static bool sleep_unless_leaving(scan_conn *c, int ms)
{
    for (int i = 0; i < ms && !atomic_load(&c->leave); i += 50) {
        struct timespec ts = {0, 50 * 1000000L};
        nanosleep(&ts, NULL);
    }
    return !atomic_load(&c->leave);
}

static int conn_open(scan_conn *c)
{
    scan_intake *in = c->in;
    const scan_transport_ops *ops =
        c->addr.kind == SCAN_KIND_BULK ? &scan_libusb_ops : &scan_hidapi_ops;
    void *backend = c->addr.kind == SCAN_KIND_BULK ? in->usb : NULL;
    geo_err err = {""};
    int r = -EIO;
    for (int i = 0; i < OPEN_TRIES; i++) {
        scan_transport *t = NULL;
        r = ops->open(backend, &c->addr, &t, c->usb_serial,
                      sizeof c->usb_serial, &err);
        if (r == 0) {
            pthread_mutex_lock(&c->smu);
            c->t = t;
            pthread_mutex_unlock(&c->smu);
            return 0;
        }
        if (r == -ENODEV || !sleep_unless_leaving(c, OPEN_RETRY_MS))
            break;
    }
    notice(in, "", "%s", err.msg);
    return r;
}

static void *conn_main(void *arg)
{
    scan_conn *c = arg;
    scan_intake *in = c->in;
    uint8_t *buf = malloc(READ_MAX);
    scan_session_cfg cfg;
    scan_session_cfg_default(&cfg);
    cfg.defer_done_ack = true;
    cfg.scan_timeout_ms = in->opt.scan_timeout_ms;
    cfg.resend_ms = in->opt.resend_ms;
    cfg.max_model = in->opt.max_model;
    snprintf(cfg.host_version, sizeof cfg.host_version, "%s",
             in->opt.host_version);
    scan_session_events sev = {c,           sev_info,     sev_started,
                               sev_progress, sev_complete, sev_dropped,
                               sev_device_error};
    scan_session *s = buf ? scan_session_new(&cfg, &sev) : NULL;
    if (!s || conn_open(c) < 0) {
        scan_session_free(s);
        goto out;
    }
    pthread_mutex_lock(&c->smu);
    c->s = s;
    scan_session_hello(s, mono_ms());
    int w = scan_session_flush(s, c->t, in->opt.io_timeout_ms);
    pthread_mutex_unlock(&c->smu);
    while (!atomic_load(&c->leave) && w != -ENODEV) {
        pthread_mutex_lock(&c->smu);
        uint64_t deadline = scan_session_deadline(s);
        pthread_mutex_unlock(&c->smu);
        uint64_t now = mono_ms();
        int wait = deadline <= now ? 0
                   : deadline - now > MAX_WAIT_MS ? MAX_WAIT_MS
                                                  : (int)(deadline - now);
        ssize_t n = c->t->ops->read(c->t, buf, READ_MAX, wait);
        now = mono_ms();
        pthread_mutex_lock(&c->smu);
        if (n > 0)
            scan_session_input(s, buf, (size_t)n, now);
        scan_session_tick(s, now);
        w = scan_session_flush(s, c->t, in->opt.io_timeout_ms);
        pthread_mutex_unlock(&c->smu);
        deliver_all(c);
        if (n == -ENODEV || n == -EIO) {
            if (n == -EIO)
                notice(in, "", "%s: transfer failed", c->addr.path);
            break;
        }
    }

    pthread_mutex_lock(&in->mu);
    pthread_mutex_lock(&c->smu);
    bool partial = scan_session_scanning(s, NULL, NULL);
    scan_transport *t = c->t;
    add_stats(&in->retired, scan_session_get_stats(s), t);
    in->retired.scans_dropped += partial;
    c->s = NULL;
    c->t = NULL;
    pthread_mutex_unlock(&c->smu);
    /* from here on k may be forgotten (KNOWN_MAX) once in->mu is left */
    scan_known *k = c->known;
    c->known = NULL;
    char serial[PROTO_FSP_TEXT_MAX + 1] = "";
    if (k && k->conn == c) {
        snprintf(serial, sizeof serial, "%s", k->info.serial);
        k->conn = NULL;
        k->state = SCAN_STATE_OFFLINE;
        k->pdone = k->ptotal = 0;
        k->dropped += partial;
    }
    pthread_mutex_unlock(&in->mu);
    t->ops->close(t);
    scan_session_free(s);
    deliver_all(c);
    if (serial[0] && !atomic_load(&in->stop)) {
        if (partial)
            notice(in, serial,
                   "unplugged during a scan: partial scan dropped");
        if (in->cb.on_device_gone)
            in->cb.on_device_gone(in->cb.user, serial);
    }
out:
    free(buf);
    atomic_store(&c->finished, true);
    scan_intake_wake(in);
    return NULL;
}

/* --- connections (called by discovery.c) -------------------------------- */

static bool same_addr(const scan_devaddr *a, const scan_devaddr *b)
{
    if (a->kind != b->kind)
        return false;
    if (a->kind == SCAN_KIND_BULK)
        return a->bus == b->bus && a->address == b->address;
    return strcmp(a->path, b->path) == 0;
}

void scan_conn_arrive(scan_intake *in, const scan_devaddr *addr)
{
    /* hotplug events handled while scan_intake_stop waits for the
     * connections must not start new ones */
    if (atomic_load(&in->stop))
        return;
    pthread_mutex_lock(&in->mu);
    for (scan_conn *c = in->conns; c; c = c->next) {
        if (same_addr(&c->addr, addr) && !atomic_load(&c->leave)) {
            pthread_mutex_unlock(&in->mu);
            return;
        }
    }
    scan_conn *c = calloc(1, sizeof *c);
    if (!c) {
        pthread_mutex_unlock(&in->mu);
        return;
    }
    c->in = in;
    c->addr = *addr;
    pthread_mutex_init(&c->smu, NULL);
    if (pthread_create(&c->thread, NULL, conn_main, c) != 0) {
        pthread_mutex_destroy(&c->smu);
        free(c);
        pthread_mutex_unlock(&in->mu);
        notice(in, "", "%s: cannot start a thread", addr->path);
        return;
    }
    c->next = in->conns;
    in->conns = c;
    pthread_mutex_unlock(&in->mu);
}

static void conn_stop(scan_conn *c)
{
    atomic_store(&c->leave, true);
    pthread_mutex_lock(&c->smu);
    if (c->t)
        c->t->ops->cancel(c->t);
    pthread_mutex_unlock(&c->smu);
}

void scan_conn_leave(scan_intake *in, const scan_devaddr *addr)
{
    pthread_mutex_lock(&in->mu);
    for (scan_conn *c = in->conns; c; c = c->next)
        if (same_addr(&c->addr, addr))
            conn_stop(c);
    pthread_mutex_unlock(&in->mu);
}

static void conn_free(scan_conn *c)
{
    pthread_join(c->thread, NULL);
    pthread_mutex_destroy(&c->smu);
    free(c);
}

void scan_conn_reap(scan_intake *in)
{
    pthread_mutex_lock(&in->mu);
    scan_conn *done = NULL, **pp = &in->conns;
    while (*pp) {
        scan_conn *c = *pp;
        if (atomic_load(&c->finished)) {
            *pp = c->next;
            c->next = done;
            done = c;
        } else {
            pp = &c->next;
        }
    }
    pthread_mutex_unlock(&in->mu);
    while (done) {
        scan_conn *next = done->next;
        conn_free(done);
        done = next;
    }
}

/* --- public API ---------------------------------------------------------- */

scan_intake *scan_intake_stop(scan_intake *in)
{
    if (!in)
        return NULL;
    scan_discovery_stop_thread(in);
    pthread_mutex_lock(&in->mu);
    for (scan_conn *c = in->conns; c; c = c->next)
        conn_stop(c);
    scan_conn *list = in->conns;
    in->conns = NULL;
    pthread_mutex_unlock(&in->mu);
    /* the connections wait for libusb callbacks while they close, so
     * libusb events are handled here until every one of them has ended */
    for (scan_conn *c = list; c; c = c->next) {
        while (!atomic_load(&c->finished)) {
            if (in->usb) {
                struct timeval tv = {0, 20000};
                libusb_handle_events_timeout_completed(in->usb, &tv, NULL);
            } else {
                struct timespec ts = {0, 20 * 1000000L};
                nanosleep(&ts, NULL);
            }
        }
    }
    while (list) {
        scan_conn *next = list->next;
        conn_free(list);
        list = next;
    }
    scan_discovery_release(in);
    while (in->known) {
        scan_known *k = in->known;
        in->known = k->next;
        free(k);
    }
    pthread_mutex_destroy(&in->mu);
    free(in);
    return NULL;
}

scan_intake *scan_intake_start(const scan_match *list, size_t n,
                               const scan_callbacks *cb,
                               const scan_options *opt, geo_err *err)
{
    if (n == 0 || n > SCAN_MATCH_MAX) {
        geo_err_set(err, -EINVAL, "devices: %zu entries (1..%d)", n,
                    SCAN_MATCH_MAX);
        return NULL;
    }
    scan_intake *in = calloc(1, sizeof *in);
    if (!in) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    memcpy(in->list, list, n * sizeof *list);
    in->nlist = n;
    if (cb)
        in->cb = *cb;
    if (opt)
        in->opt = *opt;
    else
        scan_options_default(&in->opt);
    pthread_mutex_init(&in->mu, NULL);
    in->wake[0] = in->wake[1] = -1;
    if (scan_discovery_start(in, err) < 0)
        return scan_intake_stop(in);
    return in;
}

static void status_of(const scan_known *k, scan_device_status *st)
{
    memset(st, 0, sizeof *st);
    st->info = k->info;
    st->seen = k->seen;
    st->state = k->conn ? k->state : SCAN_STATE_OFFLINE;
    st->progress_done = k->pdone;
    st->progress_total = k->ptotal;
    snprintf(st->last_job, sizeof st->last_job, "%s", k->last_job);
    st->scans_completed = k->completed;
    st->scans_dropped = k->dropped;
    st->last_seen_ms = k->last_seen_ms;
}

static int by_serial(const void *a, const void *b)
{
    return strcmp(((const scan_device_status *)a)->info.serial,
                  ((const scan_device_status *)b)->info.serial);
}

int scan_list(scan_intake *in, scan_device_status **ret, size_t *ret_n)
{
    pthread_mutex_lock(&in->mu);
    size_t n = 0;
    for (scan_known *k = in->known; k; k = k->next)
        n++;
    scan_device_status *a = malloc((n ? n : 1) * sizeof *a);
    if (!a) {
        pthread_mutex_unlock(&in->mu);
        return -ENOMEM;
    }
    size_t i = 0;
    for (scan_known *k = in->known; k; k = k->next)
        status_of(k, &a[i++]);
    pthread_mutex_unlock(&in->mu);
    qsort(a, n, sizeof *a, by_serial);
    *ret = a;
    *ret_n = n;
    return 0;
}

int scan_get(scan_intake *in, const char *serial, scan_device_status *ret)
{
    pthread_mutex_lock(&in->mu);
    scan_known *k = known_find(in, serial);
    if (k)
        status_of(k, ret);
    pthread_mutex_unlock(&in->mu);
    return k ? 0 : -ENOENT;
}

int scan_request_start(scan_intake *in, const char *serial, uint8_t mode)
{
    pthread_mutex_lock(&in->mu);
    scan_known *k = known_find(in, serial);
    int r = !k ? -ENOENT : !k->conn ? -ENODEV : 0;
    if (r == 0) {
        scan_conn *c = k->conn;
        pthread_mutex_lock(&c->smu);
        if (!c->s || !c->t) {
            r = -ENODEV;
        } else {
            r = scan_session_start_scan(c->s, mode, mono_ms());
            if (r == 0 &&
                scan_session_flush(c->s, c->t, in->opt.io_timeout_ms) < 0)
                r = -EIO;
        }
        pthread_mutex_unlock(&c->smu);
    }
    pthread_mutex_unlock(&in->mu);
    return r;
}

int scan_send_result(scan_intake *in, const char *serial,
                     const proto_fsp_result *r)
{
    char *probe = proto_fsp_build_result(r);
    if (!probe)
        return -EINVAL;
    free(probe);
    pthread_mutex_lock(&in->mu);
    scan_known *k = known_find(in, serial);
    int rc = -ENOENT;
    for (size_t i = 0; k && i < k->npend && rc < 0; i++) {
        if (!k->pend[i].naming && !k->pend[i].ready &&
            strcmp(k->pend[i].job, r->job) == 0) {
            k->pend[i].r = *r;
            k->pend[i].ready = true;
            rc = 0;
        }
    }
    for (size_t i = 0; k && i < k->npend && rc < 0; i++) {
        if (k->pend[i].naming && !k->pend[i].ready) {
            k->pend[i].r = *r;
            k->pend[i].ready = true;
            rc = 0;
        }
    }
    if (rc == 0)
        deliver_results(in, k);
    pthread_mutex_unlock(&in->mu);
    return rc;
}

static bool valid_serial(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > PROTO_FSP_TEXT_MAX)
        return false;
    for (size_t i = 0; i < n; i++)
        if (!((s[i] >= 'a' && s[i] <= 'z') || (s[i] >= 'A' && s[i] <= 'Z') ||
              (s[i] >= '0' && s[i] <= '9') || strchr("._:-", s[i])))
            return false;
    return true;
}

int scan_owe_result(scan_intake *in, const char *serial, const char *job)
{
    if (!valid_serial(serial) || !job[0] || strlen(job) > PROTO_FSP_TEXT_MAX)
        return -EINVAL;
    pthread_mutex_lock(&in->mu);
    scan_known *k = known_find(in, serial);
    if (!k)
        k = known_add(in, serial);
    int rc = k ? 0 : -ENOSPC;
    size_t at = 0;
    for (size_t i = 0; k && i < k->npend && rc == 0; i++) {
        if (strcmp(k->pend[i].job, job) == 0)
            rc = 1;
        if (k->pend[i].prior)
            at = i + 1;
    }
    if (rc == 0 && k->npend == PENDING_MAX)
        rc = -ENOSPC;
    if (rc == 0) {
        memmove(k->pend + at + 1, k->pend + at,
                (k->npend - at) * sizeof *k->pend);
        memset(&k->pend[at], 0, sizeof k->pend[at]);
        snprintf(k->pend[at].job, sizeof k->pend[at].job, "%s", job);
        k->pend[at].prior = true;
        k->npend++;
    }
    pthread_mutex_unlock(&in->mu);
    return rc < 0 ? rc : 0;
}

void scan_get_metrics(scan_intake *in, scan_metrics *ret)
{
    pthread_mutex_lock(&in->mu);
    scan_metrics m = in->retired;
    for (scan_conn *c = in->conns; c; c = c->next) {
        pthread_mutex_lock(&c->smu);
        if (c->s) {
            add_stats(&m, scan_session_get_stats(c->s), c->t);
            m.devices_connected += c->known && c->known->conn == c &&
                                   scan_session_ready(c->s);
        }
        pthread_mutex_unlock(&c->smu);
    }
    pthread_mutex_unlock(&in->mu);
    *ret = m;
}
