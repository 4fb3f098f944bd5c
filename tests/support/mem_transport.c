/* mem_transport.c — the in-memory transport of the unit tests. */
#include "mem_transport.h"

#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

typedef struct mem_transport {
    scan_transport base;
    uint64_t *clock;
    size_t chunk;
    uint8_t *in;
    size_t in_len, in_pos, in_cap;
    proto_fsp_decoder *dec;
    mem_frame *out;
    size_t nout, cout;
    bool gone, canceled;
} mem_transport;

static int mem_write(scan_transport *t, const uint8_t *frame, size_t len,
                     int timeout_ms)
{
    (void)timeout_ms;
    mem_transport *m = (mem_transport *)t;
    if (m->gone)
        return -ENODEV;
    proto_fsp_event ev;
    do {
        size_t used = proto_fsp_decode(m->dec, frame, len, &ev);
        frame += used;
        len -= used;
        if (ev.kind != PROTO_FSP_EV_FRAME)
            continue;
        if (m->nout == m->cout) {
            m->cout = m->cout ? 2 * m->cout : 64;
            m->out = realloc(m->out, m->cout * sizeof *m->out);
        }
        mem_frame *f = &m->out[m->nout++];
        f->type = ev.frame.type;
        f->seq = ev.frame.seq;
        f->len = ev.frame.len;
        memcpy(f->payload, ev.frame.payload,
               ev.frame.len < sizeof f->payload ? ev.frame.len
                                                : sizeof f->payload);
    } while (len > 0 || ev.kind != PROTO_FSP_EV_NONE);
    return 0;
}

static ssize_t mem_read(scan_transport *t, uint8_t *buf, size_t cap,
                        int timeout_ms)
{
    mem_transport *m = (mem_transport *)t;
    if (m->gone)
        return -ENODEV;
    if (m->canceled)
        return -ECANCELED;
    size_t avail = m->in_len - m->in_pos;
    if (avail == 0) {
        if (timeout_ms > 0)
            *m->clock += (uint64_t)timeout_ms;
        return -ETIMEDOUT;
    }
    size_t n = avail < cap ? avail : cap;
    if (m->chunk && n > m->chunk)
        n = m->chunk;
    memcpy(buf, m->in + m->in_pos, n);
    m->in_pos += n;
    return (ssize_t)n;
}

static void mem_cancel(scan_transport *t)
{
    ((mem_transport *)t)->canceled = true;
}

static void mem_close(scan_transport *t)
{
    mem_transport *m = (mem_transport *)t;
    proto_fsp_decoder_free(m->dec);
    free(m->in);
    free(m->out);
    free(m);
}

static const scan_transport_ops mem_ops = {
    .name = "mem",
    .write = mem_write,
    .read = mem_read,
    .cancel = mem_cancel,
    .close = mem_close,
};

scan_transport *mem_transport_new(uint64_t *clock_ms, size_t chunk)
{
    mem_transport *m = calloc(1, sizeof *m);
    m->base.ops = &mem_ops;
    m->clock = clock_ms;
    m->chunk = chunk;
    m->dec = proto_fsp_decoder_new(0);
    return &m->base;
}

void mem_transport_push(scan_transport *t, const void *bytes, size_t n)
{
    mem_transport *m = (mem_transport *)t;
    if (m->in_pos == m->in_len)
        m->in_pos = m->in_len = 0;
    if (m->in_len + n > m->in_cap) {
        m->in_cap = (m->in_len + n) * 2;
        m->in = realloc(m->in, m->in_cap);
    }
    memcpy(m->in + m->in_len, bytes, n);
    m->in_len += n;
}

void mem_transport_push_frame(scan_transport *t, uint8_t type, uint16_t seq,
                              const void *payload, size_t len, int corrupt)
{
    size_t cap = len + PROTO_FSP_OVERHEAD, sz;
    uint8_t *buf = malloc(cap);
    proto_fsp_encode(type, seq, payload, len, buf, cap, &sz);
    if (corrupt)
        buf[sz - 1] ^= 0x10;
    mem_transport_push(t, buf, sz);
    free(buf);
}

size_t mem_transport_sent_count(const scan_transport *t)
{
    return ((const mem_transport *)t)->nout;
}

const mem_frame *mem_transport_sent(const scan_transport *t, size_t i)
{
    return &((const mem_transport *)t)->out[i];
}

size_t mem_transport_count(const scan_transport *t, uint8_t type,
                           size_t from)
{
    const mem_transport *m = (const mem_transport *)t;
    size_t c = 0;
    for (size_t i = from; i < m->nout; i++)
        c += m->out[i].type == type;
    return c;
}

const mem_frame *mem_transport_last(const scan_transport *t, uint8_t type)
{
    const mem_transport *m = (const mem_transport *)t;
    for (size_t i = m->nout; i > 0; i--)
        if (m->out[i - 1].type == type)
            return &m->out[i - 1];
    return NULL;
}

void mem_transport_unplug(scan_transport *t)
{
    ((mem_transport *)t)->gone = true;
}
