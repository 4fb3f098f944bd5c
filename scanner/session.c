/* session.c — the host side of the FSP/1 session state machine.
 *
 * Invariants:
 * - phase GREETING: only INFO is processed; rx_next is meaningless.
 *   Phase READY: rx_next is the device sequence number expected next.
 * - a sequence number d = seq - rx_next (16-bit, signed) is new when
 *   0 ≤ d ≤ WINDOW, old when -OLD_SPAN ≤ d < 0, and a jump otherwise;
 * - naks[] remembers every frame NAKed recently: pending while the device
 *   still owes it, kept after it arrived so that a frame failing its
 *   checks again and again is counted (and the scan dropped at max_naks);
 * - the scan's model buffer is allocated once its total is known; ivs[]
 *   is the sorted, disjoint, non-adjacent list of byte ranges received,
 *   and covered is their total length;
 * - every frame queued is also in hist[] (for device NAKs); RESULT and
 *   ABORT are in await[] until ACKed;
 * - ack_owed (defer_done_ack only) is set from a complete scan until
 *   scan_session_ack_done or a HELLO; last_done_valid only names a
 *   SCAN_DONE that was ACKed, so a re-sent one is ACKed again only then. */
#include "session.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "grow.h"
#include "crc32.h"

enum {
    WINDOW = 16,      /* largest gap NAKed frame by frame */
    OLD_SPAN = 1024,  /* how far back a frame still counts as a re-send */
    NAK_SLOTS = 32,
    HIST = 32,
    AWAIT = 16,
    MAX_TRIES = 3,    /* sends of a RESULT/ABORT, and NAKs of SCAN_DONE */
};

typedef struct qframe {
    struct qframe *next;
    size_t len;
    uint8_t bytes[];
} qframe;

typedef struct nak_slot {
    bool used, pending;
    uint16_t seq;
    int naks;
    uint64_t last_ms;
} nak_slot;

typedef struct hist_slot {
    bool used;
    uint16_t seq;
    size_t len;
    uint8_t *bytes;
} hist_slot;

typedef struct await_slot {
    bool used;
    uint16_t seq;
    int tries;
    uint64_t sent_ms;
} await_slot;

typedef struct interval {
    uint32_t lo, hi; /* [lo, hi) */
} interval;

typedef struct scan_state {
    bool active;
    uint8_t mode;
    uint32_t contours;
    bool total_known;
    uint32_t total;
    uint8_t *buf;
    interval *ivs;
    size_t nivs, civs;
    uint64_t covered;
    bool done_pending;
    uint16_t done_seq;
    proto_fsp_scan_done done;
    int done_naks;
    uint32_t prog_done, prog_total;
} scan_state;

struct scan_session {
    scan_session_cfg cfg;
    scan_session_events ev;
    scan_session_stats st;
    proto_fsp_decoder *dec;
    bool ready, started;
    uint16_t seq_out, rx_next;
    uint64_t next_info_ms, last_rx_ms;
    qframe *qhead, *qtail;
    nak_slot naks[NAK_SLOTS];
    hist_slot hist[HIST];
    size_t hist_pos;
    await_slot await[AWAIT];
    scan_state scan;
    bool last_done_valid;
    uint16_t last_done_seq;
    /* defer_done_ack: the SCAN_DONE of a complete scan not answered yet */
    bool ack_owed;
    uint16_t ack_seq;
    size_t ack_len;
};

void scan_session_cfg_default(scan_session_cfg *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    cfg->scan_timeout_ms = 30000;
    cfg->resend_ms = 5000;
    cfg->info_retry_ms = 2000;
    cfg->max_naks = 5;
    cfg->max_model = 64u << 20;
    strcpy(cfg->host_version, "0.1.0");
}

scan_session *scan_session_new(const scan_session_cfg *cfg,
                               const scan_session_events *ev)
{
    scan_session *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    if (cfg)
        s->cfg = *cfg;
    else
        scan_session_cfg_default(&s->cfg);
    if (ev)
        s->ev = *ev;
    s->dec = proto_fsp_decoder_new(0);
    if (!s->dec) {
        free(s);
        return NULL;
    }
    return s;
}

static void scan_clear(scan_state *sc)
{
    free(sc->buf);
    free(sc->ivs);
    memset(sc, 0, sizeof *sc);
}

static void queue_clear(scan_session *s)
{
    while (s->qhead) {
        qframe *q = s->qhead;
        s->qhead = q->next;
        free(q);
    }
    s->qtail = NULL;
    for (size_t i = 0; i < HIST; i++) {
        free(s->hist[i].bytes);
        s->hist[i] = (hist_slot){0};
    }
    memset(s->await, 0, sizeof s->await);
}

scan_session *scan_session_free(scan_session *s)
{
    if (s) {
        queue_clear(s);
        scan_clear(&s->scan);
        proto_fsp_decoder_free(s->dec);
        free(s);
    }
    return NULL;
}

/* --- output ----------------------------------------------------------- */

static int enqueue_bytes(scan_session *s, const uint8_t *bytes, size_t len)
{
    qframe *q = malloc(sizeof *q + len);
    if (!q)
        return -ENOMEM;
    q->next = NULL;
    q->len = len;
    memcpy(q->bytes, bytes, len);
    if (s->qtail)
        s->qtail->next = q;
    else
        s->qhead = q;
    s->qtail = q;
    return 0;
}

/* Encodes and queues one frame with the next sequence number; await
 * says whether it must be ACKed (and is re-sent until then). */
static int emit(scan_session *s, uint8_t type, const void *payload,
                size_t len, bool await, uint64_t now)
{
    uint8_t small[64];
    size_t cap = len + PROTO_FSP_OVERHEAD, sz;
    uint8_t *buf = cap <= sizeof small ? small : malloc(cap);
    if (!buf)
        return -ENOMEM;
    uint16_t seq = s->seq_out;
    int r = proto_fsp_encode(type, seq, payload, len, buf, cap, &sz);
    if (r == 0)
        r = enqueue_bytes(s, buf, sz);
    if (r == 0) {
        s->seq_out++;
        hist_slot *h = &s->hist[s->hist_pos];
        s->hist_pos = (s->hist_pos + 1) % HIST;
        free(h->bytes);
        h->bytes = malloc(sz);
        h->used = h->bytes != NULL;
        if (h->used) {
            memcpy(h->bytes, buf, sz);
            h->seq = seq;
            h->len = sz;
        }
        if (await) {
            for (size_t i = 0; i < AWAIT; i++) {
                if (!s->await[i].used) {
                    s->await[i] = (await_slot){true, seq, 1, now};
                    break;
                }
            }
        }
    }
    if (buf != small)
        free(buf);
    return r;
}

static void send_seq(scan_session *s, uint8_t type, uint16_t seq, uint64_t now)
{
    uint8_t p[2];
    proto_fsp_build_seq(p, seq);
    if (emit(s, type, p, 2, false, now) == 0) {
        if (type == PROTO_FSP_ACK)
            s->st.acks_sent++;
        else
            s->st.naks_sent++;
    }
}

static int resend(scan_session *s, uint16_t seq)
{
    for (size_t i = 0; i < HIST; i++)
        if (s->hist[i].used && s->hist[i].seq == seq)
            return enqueue_bytes(s, s->hist[i].bytes, s->hist[i].len);
    return -ENOENT;
}

/* The next frame to send, malloc'd for the caller to free, or NULL when
 * none is queued. Counts it in frames_out. */
static uint8_t *scan_session_next_frame(scan_session *s, size_t *ret_len)
{
    qframe *q = s->qhead;
    if (!q)
        return NULL;
    uint8_t *out = malloc(q->len);
    if (!out)
        return NULL;
    memcpy(out, q->bytes, q->len);
    *ret_len = q->len;
    s->qhead = q->next;
    if (!s->qhead)
        s->qtail = NULL;
    free(q);
    s->st.frames_out++;
    return out;
}

int scan_session_flush(scan_session *s, scan_transport *t, int timeout_ms)
{
    size_t len;
    uint8_t *f;
    while ((f = scan_session_next_frame(s, &len)) != NULL) {
        int r = t->ops->write(t, f, len, timeout_ms);
        free(f);
        if (r < 0)
            return r;
    }
    return 0;
}

/* --- scans -------------------------------------------------------------- */

static void drop_scan(scan_session *s, const char *why, bool abort_device,
                      uint64_t now)
{
    if (!s->scan.active)
        return;
    scan_clear(&s->scan);
    s->st.scans_dropped++;
    memset(s->naks, 0, sizeof s->naks);
    if (s->ev.on_scan_dropped)
        s->ev.on_scan_dropped(s->ev.user, why);
    if (abort_device)
        emit(s, PROTO_FSP_ABORT, NULL, 0, true, now);
}

static void begin_scan(scan_session *s, uint8_t mode, uint32_t contours,
                       uint64_t now)
{
    if (s->scan.active)
        drop_scan(s, "superseded by a new scan", false, now);
    scan_clear(&s->scan);
    s->scan.active = true;
    s->scan.mode = mode;
    s->scan.contours = contours;
    s->st.scans_started++;
    if (s->ev.on_scan_started)
        s->ev.on_scan_started(s->ev.user, mode, contours);
}

/* Adds [lo, hi) to the received ranges, keeping them sorted and merged. */
static int add_interval(scan_state *sc, uint32_t lo, uint32_t hi)
{
    size_t i = 0;
    while (i < sc->nivs && sc->ivs[i].hi < lo)
        i++;
    size_t j = i;
    uint32_t nlo = lo, nhi = hi;
    while (j < sc->nivs && sc->ivs[j].lo <= hi) {
        if (sc->ivs[j].lo < nlo)
            nlo = sc->ivs[j].lo;
        if (sc->ivs[j].hi > nhi)
            nhi = sc->ivs[j].hi;
        j++;
    }
    /* ranges i .. j-1 merge into one */
    uint64_t before = 0;
    for (size_t k = i; k < j; k++)
        before += sc->ivs[k].hi - sc->ivs[k].lo;
    if (j == i) {
        if (geo_grow((void **)&sc->ivs, &sc->civs, sc->nivs + 1,
                     sizeof *sc->ivs) < 0)
            return -ENOMEM;
        memmove(sc->ivs + i + 1, sc->ivs + i, (sc->nivs - i) * sizeof *sc->ivs);
        sc->nivs++;
    } else {
        memmove(sc->ivs + i + 1, sc->ivs + j, (sc->nivs - j) * sizeof *sc->ivs);
        sc->nivs -= j - i - 1;
    }
    sc->ivs[i].lo = nlo;
    sc->ivs[i].hi = nhi;
    sc->covered += (uint64_t)(nhi - nlo) - before;
    return 0;
}

/* --- NAK bookkeeping ----------------------------------------------------- */

static nak_slot *nak_find(scan_session *s, uint16_t seq)
{
    for (size_t i = 0; i < NAK_SLOTS; i++)
        if (s->naks[i].used && s->naks[i].seq == seq)
            return &s->naks[i];
    return NULL;
}

static nak_slot *nak_slot_for(scan_session *s, uint16_t seq)
{
    nak_slot *n = nak_find(s, seq);
    if (n)
        return n;
    nak_slot *victim = NULL;
    for (size_t i = 0; i < NAK_SLOTS && !victim; i++)
        if (!s->naks[i].used)
            victim = &s->naks[i];
    for (size_t i = 0; i < NAK_SLOTS && !victim; i++)
        if (!s->naks[i].pending)
            victim = &s->naks[i];
    if (!victim) {
        victim = &s->naks[0];
        for (size_t i = 1; i < NAK_SLOTS; i++)
            if (s->naks[i].last_ms < victim->last_ms)
                victim = &s->naks[i];
    }
    *victim = (nak_slot){.used = true, .seq = seq};
    return victim;
}

/* Asks the device to send seq again. A frame NAKed max_naks times while
 * a scan is running ends that scan. */
static void nak(scan_session *s, uint16_t seq, uint64_t now)
{
    nak_slot *n = nak_slot_for(s, seq);
    if (n->naks >= s->cfg.max_naks) {
        n->used = false;
        drop_scan(s, "a frame failed its checks too often", true, now);
        return;
    }
    n->naks++;
    n->pending = true;
    n->last_ms = now;
    send_seq(s, PROTO_FSP_NAK, seq, now);
}

static void bad_frame(scan_session *s, const proto_fsp_frame *f, uint64_t now)
{
    s->st.bad_frames++;
    nak(s, f->seq, now);
}

/* --- frames ------------------------------------------------------------- */

static void finish_if_complete(scan_session *s, uint64_t now)
{
    scan_state *sc = &s->scan;
    if (!sc->done_pending || !sc->total_known || sc->covered != sc->total)
        return;
    uint16_t seq = sc->done_seq;
    sc->done_pending = false;
    if (proto_crc32(sc->buf, sc->total) != sc->done.crc) {
        sc->done_naks++;
        s->st.bad_frames++;
        if (sc->done_naks >= MAX_TRIES) {
            /* the third NAK: the device drops the scan and says ERROR 3 */
            send_seq(s, PROTO_FSP_NAK, seq, now);
            drop_scan(s, "the model's CRC-32 does not match SCAN_DONE",
                      false, now);
            return;
        }
        nak_slot *n = nak_slot_for(s, seq);
        n->pending = true;
        n->last_ms = now;
        send_seq(s, PROTO_FSP_NAK, seq, now);
        return;
    }
    uint8_t *bytes = sc->buf;
    size_t len = sc->total;
    uint8_t format = sc->done.format;
    sc->buf = NULL;
    scan_clear(sc);
    memset(s->naks, 0, sizeof s->naks);
    if (s->cfg.defer_done_ack) {
        s->ack_owed = true;
        s->ack_seq = seq;
        s->ack_len = len;
    } else {
        send_seq(s, PROTO_FSP_ACK, seq, now);
        s->st.scans_completed++;
        s->st.model_bytes += len;
        s->last_done_valid = true;
        s->last_done_seq = seq;
    }
    if (s->ev.on_scan_complete)
        s->ev.on_scan_complete(s->ev.user, bytes, len, format);
    else
        free(bytes);
}

static void on_model(scan_session *s, const proto_fsp_frame *f, uint64_t now)
{
    proto_fsp_model_chunk c;
    if (proto_fsp_parse_model(f, &c, NULL) < 0) {
        bad_frame(s, f, now);
        return;
    }
    scan_state *sc = &s->scan;
    if (!sc->active)
        begin_scan(s, 255, 0, now);
    if (!sc->total_known) {
        if (c.total > s->cfg.max_model) {
            s->st.bad_frames++;
            drop_scan(s, "the model is larger than the configured limit",
                      true, now);
            return;
        }
        sc->buf = malloc(c.total ? c.total : 1);
        if (!sc->buf) {
            drop_scan(s, "out of memory", true, now);
            return;
        }
        sc->total = c.total;
        sc->total_known = true;
    }
    if (c.total != sc->total) {
        bad_frame(s, f, now);
        return;
    }
    memcpy(sc->buf + c.offset, c.bytes, c.len);
    if (add_interval(sc, c.offset, c.offset + c.len) < 0) {
        drop_scan(s, "out of memory", true, now);
        return;
    }
    send_seq(s, PROTO_FSP_ACK, f->seq, now);
    finish_if_complete(s, now);
}

static void on_scan_done(scan_session *s, const proto_fsp_frame *f,
                         uint64_t now)
{
    proto_fsp_scan_done d;
    if (proto_fsp_parse_scan_done(f, &d, NULL) < 0) {
        bad_frame(s, f, now);
        return;
    }
    scan_state *sc = &s->scan;
    if (!sc->active || (sc->total_known && d.total != sc->total)) {
        /* nothing (or something else) was received: the model cannot be
         * checked, which is a mismatch for the device */
        bad_frame(s, f, now);
        return;
    }
    sc->done_pending = true;
    sc->done_seq = f->seq;
    sc->done = d;
    /* incomplete: wait for the missing chunks (NAKed, or re-sent by the
     * device after its own timeout) */
    finish_if_complete(s, now);
}

static void on_error_frame(scan_session *s, const proto_fsp_frame *f,
                           uint64_t now)
{
    uint16_t code;
    char msg[128];
    if (proto_fsp_parse_error(f, &code, msg, sizeof msg, NULL) < 0) {
        s->st.bad_frames++;
        return;
    }
    if (code == PROTO_FSP_ERR_SCAN_DROPPED)
        drop_scan(s, "the device dropped the scan", false, now);
    if (s->ev.on_device_error)
        s->ev.on_device_error(s->ev.user, code, msg);
}

static void on_info(scan_session *s, const proto_fsp_frame *f)
{
    proto_fsp_info info;
    if (proto_fsp_parse_info(f, &info, NULL) < 0) {
        s->st.bad_frames++;
        return;
    }
    s->ready = true;
    if (s->ev.on_info)
        s->ev.on_info(s->ev.user, &info);
}

static void dispatch(scan_session *s, const proto_fsp_frame *f, uint64_t now)
{
    switch (f->type) {
    case PROTO_FSP_INFO:
        on_info(s, f);
        break;
    case PROTO_FSP_SCAN_STARTED: {
        proto_fsp_scan_started ss;
        if (proto_fsp_parse_scan_started(f, &ss, NULL) < 0)
            bad_frame(s, f, now);
        else
            begin_scan(s, ss.mode, ss.contours, now);
        break;
    }
    case PROTO_FSP_PROGRESS: {
        proto_fsp_progress p;
        if (proto_fsp_parse_progress(f, &p, NULL) < 0) {
            bad_frame(s, f, now);
        } else {
            if (s->scan.active) {
                s->scan.prog_done = p.done;
                s->scan.prog_total = p.total;
            }
            if (s->ev.on_progress)
                s->ev.on_progress(s->ev.user, p.done, p.total);
        }
        break;
    }
    case PROTO_FSP_MODEL:
        on_model(s, f, now);
        break;
    case PROTO_FSP_SCAN_DONE:
        on_scan_done(s, f, now);
        break;
    case PROTO_FSP_ERROR:
        on_error_frame(s, f, now);
        break;
    case PROTO_FSP_ACK: {
        uint16_t seq;
        if (proto_fsp_parse_seq(f, &seq, NULL) < 0) {
            s->st.bad_frames++;
            break;
        }
        for (size_t i = 0; i < AWAIT; i++)
            if (s->await[i].used && s->await[i].seq == seq)
                s->await[i].used = false;
        break;
    }
    case PROTO_FSP_NAK: {
        uint16_t seq;
        if (proto_fsp_parse_seq(f, &seq, NULL) < 0) {
            s->st.bad_frames++;
            break;
        }
        s->st.naks_received++;
        resend(s, seq);
        break;
    }
    default:
        /* host-only and unknown types */
        s->st.bad_frames++;
        break;
    }
}

/* A frame with a sequence number already passed: a re-send we asked for,
 * or a duplicate whose ACK the device did not get. */
static void old_frame(scan_session *s, const proto_fsp_frame *f, uint64_t now)
{
    nak_slot *n = nak_find(s, f->seq);
    if (n && n->pending) {
        n->pending = false;
        dispatch(s, f, now);
        return;
    }
    if (f->type == PROTO_FSP_MODEL && s->scan.active) {
        send_seq(s, PROTO_FSP_ACK, f->seq, now);
    } else if (f->type == PROTO_FSP_SCAN_DONE && s->last_done_valid &&
               s->last_done_seq == f->seq && !s->scan.active) {
        send_seq(s, PROTO_FSP_ACK, f->seq, now);
    } else if (f->type == PROTO_FSP_SCAN_DONE && s->scan.active &&
               !s->scan.done_pending) {
        /* SCAN_DONE re-sent by the device's own timer */
        dispatch(s, f, now);
    }
}

static void on_frame(scan_session *s, const proto_fsp_frame *f, uint64_t now)
{
    s->st.frames_in++;
    s->last_rx_ms = now;
    if (!s->ready) {
        if (f->type == PROTO_FSP_INFO)
            on_info(s, f);
        else
            s->st.ignored++;
        /* numbering starts with the INFO that answers HELLO */
        s->rx_next = (uint16_t)(f->seq + 1);
        return;
    }
    int16_t d = (int16_t)(uint16_t)(f->seq - s->rx_next);
    if (d > WINDOW || d < -OLD_SPAN) {
        /* the device's numbering no longer relates to ours */
        s->st.seq_errors++;
        s->st.restarts++;
        scan_session_hello(s, now);
        return;
    }
    if (d < 0) {
        old_frame(s, f, now);
        return;
    }
    if (d > 0) {
        s->st.seq_errors++;
        for (uint16_t q = s->rx_next; q != f->seq; q++)
            nak(s, q, now);
    }
    s->rx_next = (uint16_t)(f->seq + 1);
    nak_slot *n = nak_find(s, f->seq);
    if (n)
        n->pending = false;
    dispatch(s, f, now);
}

static void on_crc_error(scan_session *s, const proto_fsp_frame *claimed,
                         uint64_t now)
{
    s->st.crc_errors++;
    if (!s->ready)
        return;
    /* the header may be what was corrupted: trust its sequence number only
     * when it is one the device can be sending now */
    int16_t d = (int16_t)(uint16_t)(claimed->seq - s->rx_next);
    if (d >= 0 && d <= WINDOW) {
        s->st.seq_errors += d > 0;
        for (uint16_t q = s->rx_next; q != (uint16_t)(claimed->seq + 1); q++)
            nak(s, q, now);
        s->rx_next = (uint16_t)(claimed->seq + 1);
    } else if (d < 0) {
        nak_slot *n = nak_find(s, claimed->seq);
        if (n && n->pending)
            nak(s, claimed->seq, now);
    }
}

void scan_session_input(scan_session *s, const uint8_t *data, size_t len,
                        uint64_t now_ms)
{
    proto_fsp_event ev;
    do {
        size_t used = proto_fsp_decode(s->dec, data, len, &ev);
        data += used;
        len -= used;
        switch (ev.kind) {
        case PROTO_FSP_EV_FRAME:
            on_frame(s, &ev.frame, now_ms);
            break;
        case PROTO_FSP_EV_BAD_CRC:
            on_crc_error(s, &ev.frame, now_ms);
            break;
        case PROTO_FSP_EV_BAD_MAGIC:
            s->st.bad_magic++;
            break;
        case PROTO_FSP_EV_TOO_LONG:
            s->st.too_long++;
            break;
        case PROTO_FSP_EV_NONE:
            break;
        }
    } while (len > 0 || ev.kind != PROTO_FSP_EV_NONE);
}

/* --- requests and time ---------------------------------------------------- */

int scan_session_hello(scan_session *s, uint64_t now_ms)
{
    if (s->started)
        drop_scan(s, "the session restarted (HELLO)", false, now_ms);
    scan_clear(&s->scan);
    queue_clear(s);
    memset(s->naks, 0, sizeof s->naks);
    proto_fsp_decoder_reset(s->dec);
    s->started = true;
    s->ready = false;
    s->last_done_valid = false;
    s->ack_owed = false;
    s->seq_out = 0;
    s->last_rx_ms = now_ms;
    s->next_info_ms = now_ms + (uint64_t)s->cfg.info_retry_ms;
    proto_fsp_hello h;
    snprintf(h.host, sizeof h.host, "facetd");
    snprintf(h.version, sizeof h.version, "%s", s->cfg.host_version);
    char *json = proto_fsp_build_hello(&h);
    if (!json)
        return -ENOMEM;
    int r = emit(s, PROTO_FSP_HELLO, json, strlen(json), false, now_ms);
    free(json);
    return r;
}

void scan_session_tick(scan_session *s, uint64_t now_ms)
{
    if (!s->started)
        return;
    if (!s->ready) {
        if (now_ms >= s->next_info_ms) {
            emit(s, PROTO_FSP_GET_INFO, NULL, 0, false, now_ms);
            s->next_info_ms = now_ms + (uint64_t)s->cfg.info_retry_ms;
        }
        return;
    }
    if (s->scan.active &&
        now_ms - s->last_rx_ms >= (uint64_t)s->cfg.scan_timeout_ms)
        drop_scan(s, "no frame from the device for too long", true, now_ms);
    for (size_t i = 0; i < NAK_SLOTS; i++) {
        nak_slot *n = &s->naks[i];
        if (n->used && n->pending &&
            now_ms - n->last_ms >= (uint64_t)s->cfg.resend_ms) {
            if (s->scan.active) {
                nak(s, n->seq, now_ms);
            } else {
                /* only scans need what went missing */
                n->used = false;
            }
        }
    }
    for (size_t i = 0; i < AWAIT; i++) {
        await_slot *a = &s->await[i];
        if (!a->used || now_ms - a->sent_ms < (uint64_t)s->cfg.resend_ms)
            continue;
        if (a->tries >= MAX_TRIES || resend(s, a->seq) < 0) {
            a->used = false;
        } else {
            a->tries++;
            a->sent_ms = now_ms;
        }
    }
}

static uint64_t earlier(uint64_t a, uint64_t b)
{
    return a < b ? a : b;
}

uint64_t scan_session_deadline(const scan_session *s)
{
    uint64_t t = UINT64_MAX;
    if (!s->started)
        return t;
    if (!s->ready)
        return s->next_info_ms;
    if (s->scan.active)
        t = earlier(t, s->last_rx_ms + (uint64_t)s->cfg.scan_timeout_ms);
    for (size_t i = 0; i < NAK_SLOTS; i++)
        if (s->naks[i].used && s->naks[i].pending)
            t = earlier(t, s->naks[i].last_ms + (uint64_t)s->cfg.resend_ms);
    for (size_t i = 0; i < AWAIT; i++)
        if (s->await[i].used)
            t = earlier(t, s->await[i].sent_ms + (uint64_t)s->cfg.resend_ms);
    return t;
}

int scan_session_start_scan(scan_session *s, uint8_t mode, uint64_t now_ms)
{
    if (mode > PROTO_FSP_MODE_HI_ACCURACY)
        return -EINVAL;
    if (!s->ready)
        return -EAGAIN;
    if (s->scan.active)
        return -EBUSY;
    uint8_t p[1];
    proto_fsp_build_start_scan(p, mode);
    return emit(s, PROTO_FSP_START_SCAN, p, 1, false, now_ms);
}

int scan_session_send_result(scan_session *s, const proto_fsp_result *r,
                             uint64_t now_ms)
{
    if (!s->ready)
        return -EAGAIN;
    char *json = proto_fsp_build_result(r);
    if (!json)
        return -EINVAL;
    int rc = emit(s, PROTO_FSP_RESULT, json, strlen(json), true, now_ms);
    free(json);
    return rc;
}

int scan_session_ack_done(scan_session *s, bool kept, uint64_t now_ms)
{
    if (!s->ack_owed)
        return -ENOENT;
    s->ack_owed = false;
    if (!kept) {
        s->st.scans_dropped++;
        return emit(s, PROTO_FSP_ABORT, NULL, 0, true, now_ms);
    }
    send_seq(s, PROTO_FSP_ACK, s->ack_seq, now_ms);
    s->st.scans_completed++;
    s->st.model_bytes += s->ack_len;
    s->last_done_valid = true;
    s->last_done_seq = s->ack_seq;
    return 0;
}

int scan_session_abort(scan_session *s, uint64_t now_ms)
{
    if (!s->ready)
        return -EAGAIN;
    if (s->scan.active)
        drop_scan(s, "aborted by the host", false, now_ms);
    return emit(s, PROTO_FSP_ABORT, NULL, 0, true, now_ms);
}

bool scan_session_ready(const scan_session *s)
{
    return s->ready;
}

bool scan_session_scanning(const scan_session *s, uint32_t *ret_done,
                           uint32_t *ret_total)
{
    if (ret_done)
        *ret_done = s->scan.prog_done;
    if (ret_total)
        *ret_total = s->scan.prog_total;
    return s->scan.active;
}

const scan_session_stats *scan_session_get_stats(const scan_session *s)
{
    return &s->st;
}
