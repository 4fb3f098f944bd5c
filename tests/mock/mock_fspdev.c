/* mock_fspdev.c — the device side of FSP/1 for the mocked scanner.
 *
 * Invariants: hist[] holds the recent frames sent since the last HELLO,
 * each with the bytes as they should be (a corrupted emission is only in
 * the output queue), so a NAK or a timeout re-sends a clean copy;
 * inflight counts MODEL frames sent and not yet ACKed (≤ 4); SCAN_DONE
 * goes out once every MODEL frame of the scan was ACKed. */
#include "mock_fspdev.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "crc32.h"

enum { HIST = 64, RESEND_MS = 5000, MAX_DONE_NAKS = 3 };

typedef struct outq {
    struct outq *next;
    size_t len;
    uint8_t bytes[];
} outq;

typedef struct sent {
    bool used, await;
    uint8_t type;
    uint16_t seq;
    uint8_t *bytes;
    size_t len;
    uint64_t sent_ms;
} sent;

struct mock_fspdev {
    proto_fsp_info info;
    void (*on_event)(void *user, const char *line);
    void *user;
    proto_fsp_decoder *dec;
    uint16_t seq_out;
    outq *qhead, *qtail;
    sent hist[HIST];
    size_t hist_pos;
    uint8_t *model;
    size_t model_len;
    uint8_t format;
    /* one MODEL payload being built: per device, as two devices stream
     * at once from different threads */
    uint8_t chunk[8 + PROTO_FSP_MODEL_CHUNK_MAX];
    bool scanning, done_sent;
    uint8_t mode;
    size_t next_off;
    unsigned model_sent;
    int inflight, done_naks;
    unsigned corrupt_k, unplug_n, stall_n;
    size_t stall_release; /* frames still sent after a stall began */
    bool corrupt_done, stall, wants_unplug;
    mock_fspdev_record rec;
    char last_result[1024];
};

static void event(mock_fspdev *d, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void event(mock_fspdev *d, const char *fmt, ...)
{
    if (!d->on_event)
        return;
    char line[1200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    d->on_event(d->user, line);
}

mock_fspdev *mock_fspdev_new(const proto_fsp_info *info,
                             void (*on_event)(void *user, const char *line),
                             void *user)
{
    mock_fspdev *d = calloc(1, sizeof *d);
    if (!d)
        return NULL;
    d->info = *info;
    d->on_event = on_event;
    d->user = user;
    d->dec = proto_fsp_decoder_new(0);
    if (!d->dec) {
        free(d);
        return NULL;
    }
    return d;
}

static void clear_output(mock_fspdev *d)
{
    while (d->qhead) {
        outq *q = d->qhead;
        d->qhead = q->next;
        free(q);
    }
    d->qtail = NULL;
    for (size_t i = 0; i < HIST; i++) {
        free(d->hist[i].bytes);
        d->hist[i] = (sent){0};
    }
}

mock_fspdev *mock_fspdev_free(mock_fspdev *d)
{
    if (d) {
        clear_output(d);
        proto_fsp_decoder_free(d->dec);
        free(d->model);
        free(d);
    }
    return NULL;
}

static void enqueue(mock_fspdev *d, const uint8_t *bytes, size_t len,
                    bool corrupt)
{
    outq *q = malloc(sizeof *q + len);
    if (!q)
        return;
    q->next = NULL;
    q->len = len;
    memcpy(q->bytes, bytes, len);
    if (corrupt)
        q->bytes[len - 1] ^= 0x5a;
    if (d->qtail)
        d->qtail->next = q;
    else
        d->qhead = q;
    d->qtail = q;
}

/* Sends one frame with the next sequence number; await: it must be ACKed
 * (re-sent every 5 s until then). */
static void emit(mock_fspdev *d, uint8_t type, const void *payload,
                 size_t len, bool await, bool corrupt, uint64_t now)
{
    size_t cap = len + PROTO_FSP_OVERHEAD, sz;
    uint8_t *buf = malloc(cap);
    if (!buf)
        return;
    proto_fsp_encode(type, d->seq_out, payload, len, buf, cap, &sz);
    enqueue(d, buf, sz, corrupt);
    sent *h = &d->hist[d->hist_pos];
    d->hist_pos = (d->hist_pos + 1) % HIST;
    free(h->bytes);
    *h = (sent){true, await, type, d->seq_out, buf, sz, now};
    d->seq_out++;
}

static sent *find_sent(mock_fspdev *d, uint16_t seq)
{
    for (size_t i = 0; i < HIST; i++)
        if (d->hist[i].used && d->hist[i].seq == seq)
            return &d->hist[i];
    return NULL;
}

static void send_seq(mock_fspdev *d, uint8_t type, uint16_t seq, uint64_t now)
{
    uint8_t p[2];
    proto_fsp_build_seq(p, seq);
    emit(d, type, p, 2, false, false, now);
}

static void send_error(mock_fspdev *d, uint16_t code, const char *msg,
                       uint64_t now)
{
    uint8_t p[128];
    emit(d, PROTO_FSP_ERROR, p, proto_fsp_build_error(p, sizeof p, code, msg),
         false, false, now);
}

static void send_info(mock_fspdev *d, uint64_t now)
{
    char *json = proto_fsp_build_info(&d->info);
    if (json) {
        emit(d, PROTO_FSP_INFO, json, strlen(json), false, false, now);
        free(json);
    }
}

static void end_scan(mock_fspdev *d)
{
    d->scanning = false;
    d->corrupt_k = 0;
    d->corrupt_done = false;
    d->unplug_n = 0;
    d->stall_n = 0;
    for (size_t i = 0; i < HIST; i++)
        d->hist[i].await = false;
}

static void progress(mock_fspdev *d, uint64_t now)
{
    proto_fsp_progress p = {0, d->info.contours};
    if (d->model_len)
        p.done = (uint32_t)((uint64_t)d->info.contours * d->next_off /
                            d->model_len);
    uint8_t b[8];
    emit(d, PROTO_FSP_PROGRESS, b, proto_fsp_build_progress(b, &p), false,
         false, now);
}

/* Sends MODEL chunks while the window allows, then SCAN_DONE. */
static void stream(mock_fspdev *d, uint64_t now)
{
    uint8_t *p = d->chunk;
    while (d->scanning && !d->wants_unplug &&
           d->inflight < PROTO_FSP_MODEL_WINDOW &&
           d->next_off < d->model_len) {
        size_t n = d->model_len - d->next_off;
        if (n > PROTO_FSP_MODEL_CHUNK_MAX)
            n = PROTO_FSP_MODEL_CHUNK_MAX;
        size_t pl = proto_fsp_build_model(p, (uint32_t)d->model_len,
                                          (uint32_t)d->next_off,
                                          d->model + d->next_off,
                                          (uint32_t)n);
        d->model_sent++;
        d->rec.model_frames++;
        emit(d, PROTO_FSP_MODEL, p, pl, true, d->model_sent == d->corrupt_k,
             now);
        d->next_off += n;
        d->inflight++;
        if (d->model_sent % 4 == 0)
            progress(d, now);
        if (d->stall_n && d->model_sent >= d->stall_n) {
            /* what is queued still goes out; then silence */
            d->stall = true;
            d->stall_n = 0;
            d->stall_release = 0;
            for (outq *q = d->qhead; q; q = q->next)
                d->stall_release++;
            event(d, "stalled %u", d->model_sent);
            break;
        }
        if (d->unplug_n && d->model_sent >= d->unplug_n) {
            d->wants_unplug = true;
            event(d, "wants-unplug %u", d->model_sent);
        }
    }
    if (d->scanning && !d->done_sent && d->next_off == d->model_len &&
        d->inflight == 0) {
        progress(d, now);
        proto_fsp_scan_done sd = {(uint32_t)d->model_len,
                                  proto_crc32(d->model, d->model_len),
                                  d->format};
        if (d->corrupt_done)
            sd.crc ^= 0xffffffffu;
        uint8_t b[9];
        emit(d, PROTO_FSP_SCAN_DONE, b, proto_fsp_build_scan_done(b, &sd),
             true, false, now);
        d->done_sent = true;
    }
}

static void start(mock_fspdev *d, uint8_t mode, uint64_t now)
{
    d->scanning = true;
    d->done_sent = false;
    d->mode = mode;
    d->next_off = 0;
    d->model_sent = 0;
    d->inflight = 0;
    d->done_naks = 0;
    d->wants_unplug = false;
    d->rec.scans_started++;
    proto_fsp_scan_started ss = {mode, d->info.contours};
    uint8_t b[5];
    emit(d, PROTO_FSP_SCAN_STARTED, b, proto_fsp_build_scan_started(b, &ss),
         false, false, now);
    event(d, "scan-started %zu", d->model_len);
    progress(d, now);
    stream(d, now);
}

int mock_fspdev_set_model(mock_fspdev *d, const uint8_t *bytes, size_t len,
                          uint8_t format)
{
    if (d->scanning)
        return -EBUSY;
    uint8_t *m = malloc(len ? len : 1);
    if (!m)
        return -ENOMEM;
    memcpy(m, bytes, len);
    free(d->model);
    d->model = m;
    d->model_len = len;
    d->format = format;
    return 0;
}

int mock_fspdev_scan(mock_fspdev *d, uint64_t now_ms)
{
    if (d->scanning)
        return -EBUSY;
    if (!d->model || d->model_len == 0)
        return -ENOENT;
    start(d, PROTO_FSP_MODE_ACCURACY, now_ms);
    return 0;
}

void mock_fspdev_corrupt_model(mock_fspdev *d, unsigned k)
{
    d->corrupt_k = k;
}

void mock_fspdev_corrupt_done(mock_fspdev *d, bool on)
{
    d->corrupt_done = on;
}

void mock_fspdev_unplug_after(mock_fspdev *d, unsigned n)
{
    d->unplug_n = n;
}

void mock_fspdev_stall(mock_fspdev *d, bool on)
{
    d->stall = on;
    d->stall_release = 0;
}

void mock_fspdev_stall_after(mock_fspdev *d, unsigned n)
{
    d->stall_n = n;
}

bool mock_fspdev_wants_unplug(const mock_fspdev *d)
{
    return d->wants_unplug;
}

static void on_ack(mock_fspdev *d, uint16_t seq, uint64_t now)
{
    sent *s = find_sent(d, seq);
    if (!s || !s->await)
        return;
    s->await = false;
    if (s->type == PROTO_FSP_MODEL) {
        d->inflight--;
        stream(d, now);
    } else if (s->type == PROTO_FSP_SCAN_DONE && d->scanning) {
        d->rec.scans_done++;
        end_scan(d);
        event(d, "done-acked");
    }
}

static void on_nak(mock_fspdev *d, uint16_t seq, uint64_t now)
{
    event(d, "nak %u", seq);
    sent *s = find_sent(d, seq);
    if (!s)
        return;
    if (s->type == PROTO_FSP_SCAN_DONE && d->scanning) {
        if (++d->done_naks >= MAX_DONE_NAKS) {
            d->rec.scans_dropped++;
            end_scan(d);
            event(d, "dropped");
            send_error(d, PROTO_FSP_ERR_SCAN_DROPPED, "scan dropped", now);
            return;
        }
    }
    d->rec.resends++;
    enqueue(d, s->bytes, s->len, false);
    s->sent_ms = now;
}

static void on_host_frame(mock_fspdev *d, const proto_fsp_frame *f,
                          uint64_t now)
{
    uint16_t seq;
    switch (f->type) {
    case PROTO_FSP_HELLO:
        d->rec.hellos++;
        if (d->scanning) {
            d->rec.scans_abandoned++;
            end_scan(d);
            event(d, "abandoned");
        }
        clear_output(d);
        d->seq_out = 0;
        event(d, "hello");
        send_info(d, now);
        break;
    case PROTO_FSP_GET_INFO:
        d->rec.get_infos++;
        send_info(d, now);
        break;
    case PROTO_FSP_START_SCAN: {
        uint8_t mode;
        d->rec.start_scans++;
        if (proto_fsp_parse_start_scan(f, &mode, NULL) < 0)
            send_error(d, PROTO_FSP_ERR_BAD_REQUEST, "bad START_SCAN", now);
        else if (d->scanning)
            send_error(d, PROTO_FSP_ERR_BUSY, "busy", now);
        else if (!d->model || d->model_len == 0)
            send_error(d, PROTO_FSP_ERR_BAD_REQUEST, "no model loaded", now);
        else
            start(d, mode, now);
        break;
    }
    case PROTO_FSP_ACK:
        if (proto_fsp_parse_seq(f, &seq, NULL) == 0) {
            d->rec.acks++;
            on_ack(d, seq, now);
        }
        break;
    case PROTO_FSP_NAK:
        if (proto_fsp_parse_seq(f, &seq, NULL) == 0) {
            d->rec.naks++;
            on_nak(d, seq, now);
        }
        break;
    case PROTO_FSP_ABORT:
        d->rec.aborts++;
        send_seq(d, PROTO_FSP_ACK, f->seq, now);
        if (d->scanning) {
            d->rec.scans_dropped++;
            end_scan(d);
            event(d, "aborted");
        }
        break;
    case PROTO_FSP_RESULT: {
        proto_fsp_result r;
        if (proto_fsp_parse_result(f, &r, NULL) < 0) {
            send_error(d, PROTO_FSP_ERR_BAD_REQUEST, "bad RESULT", now);
            break;
        }
        d->rec.results++;
        size_t n = f->len < sizeof d->last_result - 1
                       ? f->len
                       : sizeof d->last_result - 1;
        memcpy(d->last_result, f->payload, n);
        d->last_result[n] = '\0';
        send_seq(d, PROTO_FSP_ACK, f->seq, now);
        event(d, "result %s", d->last_result);
        break;
    }
    default:
        send_error(d, PROTO_FSP_ERR_BAD_FRAME, "unexpected frame type", now);
        break;
    }
}

void mock_fspdev_input(mock_fspdev *d, const uint8_t *data, size_t len,
                       uint64_t now_ms)
{
    if (d->stall)
        return;
    proto_fsp_event ev;
    do {
        size_t used = proto_fsp_decode(d->dec, data, len, &ev);
        data += used;
        len -= used;
        if (ev.kind == PROTO_FSP_EV_FRAME)
            on_host_frame(d, &ev.frame, now_ms);
        else if (ev.kind == PROTO_FSP_EV_BAD_CRC)
            d->rec.crc_errors++;
    } while (len > 0 || ev.kind != PROTO_FSP_EV_NONE);
}

void mock_fspdev_tick(mock_fspdev *d, uint64_t now_ms)
{
    if (d->stall)
        return;
    for (size_t i = 0; i < HIST; i++) {
        sent *s = &d->hist[i];
        if (s->used && s->await && now_ms - s->sent_ms >= RESEND_MS) {
            d->rec.resends++;
            enqueue(d, s->bytes, s->len, false);
            s->sent_ms = now_ms;
        }
    }
}

uint64_t mock_fspdev_deadline(const mock_fspdev *d)
{
    uint64_t t = UINT64_MAX;
    for (size_t i = 0; i < HIST; i++)
        if (d->hist[i].used && d->hist[i].await &&
            d->hist[i].sent_ms + RESEND_MS < t)
            t = d->hist[i].sent_ms + RESEND_MS;
    return t;
}

uint8_t *mock_fspdev_next_frame(mock_fspdev *d, size_t *ret_len)
{
    outq *q = d->qhead;
    if (!q || (d->stall && d->stall_release == 0))
        return NULL;
    if (d->stall)
        d->stall_release--;
    uint8_t *out = malloc(q->len);
    if (!out)
        return NULL;
    memcpy(out, q->bytes, q->len);
    *ret_len = q->len;
    d->qhead = q->next;
    if (!d->qhead)
        d->qtail = NULL;
    free(q);
    return out;
}

const mock_fspdev_record *mock_fspdev_get_record(const mock_fspdev *d)
{
    return &d->rec;
}

char *mock_fspdev_status_json(const mock_fspdev *d)
{
    const mock_fspdev_record *r = &d->rec;
    json_t *res = NULL;
    if (d->last_result[0])
        res = json_loads(d->last_result, 0, NULL);
    json_t *o = json_pack(
        "{s:s, s:b, s:b, s:I, s:I, s:{s:I, s:I, s:I, s:I, s:I, s:I, s:I, "
        "s:I, s:I, s:I, s:I, s:I, s:I, s:I}, s:o}",
        "serial", d->info.serial, "scanning", d->scanning, "stalled",
        d->stall, "sent", (json_int_t)d->next_off, "total",
        (json_int_t)d->model_len, "record", "hellos", (json_int_t)r->hellos,
        "get_infos", (json_int_t)r->get_infos, "start_scans",
        (json_int_t)r->start_scans, "acks", (json_int_t)r->acks, "naks",
        (json_int_t)r->naks, "aborts", (json_int_t)r->aborts, "results",
        (json_int_t)r->results, "crc_errors", (json_int_t)r->crc_errors,
        "scans_started", (json_int_t)r->scans_started, "scans_done",
        (json_int_t)r->scans_done, "scans_dropped",
        (json_int_t)r->scans_dropped, "scans_abandoned",
        (json_int_t)r->scans_abandoned, "model_frames",
        (json_int_t)r->model_frames, "resends", (json_int_t)r->resends,
        "last_result", res ? res : json_null());
    if (!o)
        return NULL;
    char *s = json_dumps(o, JSON_COMPACT);
    json_decref(o);
    return s;
}
