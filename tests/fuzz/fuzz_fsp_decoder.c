/* fuzz_fsp_decoder.c — libFuzzer target for the FSP/1 decoder and payload
 * parsers. Any input must decode without a crash, a leak or a hang, the
 * decoder must make progress on every call, and every frame it accepts
 * must re-encode to the very bytes it came from.
 *
 * The first input byte picks a mode: even — the rest is a raw byte
 * stream, cut into pieces whose sizes come from the byte itself; odd —
 * the rest is a frame type and a payload which are wrapped into a valid
 * frame first, so that the payload parsers see inputs that passed the
 * CRC (a fuzzer rarely forges a CRC by itself). */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fsp.h"

static void check(int cond)
{
    if (!cond)
        abort();
}

static void parse_payload(const proto_fsp_frame *f)
{
    geo_err err;
    uint16_t seq, code;
    uint8_t mode;
    char msg[32];
    proto_fsp_scan_started ss;
    proto_fsp_progress pg;
    proto_fsp_model_chunk mc;
    proto_fsp_scan_done sd;
    proto_fsp_hello h;
    proto_fsp_info in;
    proto_fsp_result r;
    switch (f->type) {
    case PROTO_FSP_ACK:
    case PROTO_FSP_NAK:
        proto_fsp_parse_seq(f, &seq, &err);
        break;
    case PROTO_FSP_START_SCAN:
        proto_fsp_parse_start_scan(f, &mode, &err);
        break;
    case PROTO_FSP_SCAN_STARTED:
        proto_fsp_parse_scan_started(f, &ss, &err);
        break;
    case PROTO_FSP_PROGRESS:
        if (proto_fsp_parse_progress(f, &pg, &err) == 0)
            check(pg.done <= pg.total);
        break;
    case PROTO_FSP_MODEL:
        if (proto_fsp_parse_model(f, &mc, &err) == 0)
            check(mc.len >= 1 && mc.offset + (uint64_t)mc.len <= mc.total &&
                  mc.bytes == f->payload + 8);
        break;
    case PROTO_FSP_SCAN_DONE:
        proto_fsp_parse_scan_done(f, &sd, &err);
        break;
    case PROTO_FSP_ERROR:
        if (proto_fsp_parse_error(f, &code, msg, sizeof msg, &err) == 0)
            check(strlen(msg) < sizeof msg);
        break;
    case PROTO_FSP_HELLO:
        proto_fsp_parse_hello(f, &h, &err);
        break;
    case PROTO_FSP_INFO:
        if (proto_fsp_parse_info(f, &in, &err) == 0) {
            check(proto_fsp_serial_valid(in.serial));
            char *s = proto_fsp_build_info(&in);
            free(s);
        }
        break;
    case PROTO_FSP_RESULT:
        if (proto_fsp_parse_result(f, &r, &err) == 0) {
            char *s = proto_fsp_build_result(&r);
            free(s);
        }
        break;
    default:
        break;
    }
}

static uint8_t reenc[PROTO_FSP_MAX_FRAME];

static void decode_all(proto_fsp_decoder *d, const uint8_t *data, size_t len,
                       size_t piece)
{
    while (len > 0) {
        size_t n = piece < len ? piece : len;
        const uint8_t *p = data;
        size_t left = n;
        proto_fsp_event ev;
        do {
            size_t used = proto_fsp_decode(d, p, left, &ev);
            check(used <= left);
            check(used > 0 || ev.kind != PROTO_FSP_EV_NONE || left == 0);
            p += used;
            left -= used;
            if (ev.kind == PROTO_FSP_EV_FRAME) {
                size_t sz;
                check(proto_fsp_encode(ev.frame.type, ev.frame.seq,
                                       ev.frame.payload, ev.frame.len, reenc,
                                       sizeof reenc, &sz) == 0);
                check(memcmp(reenc + 12, ev.frame.payload, ev.frame.len) ==
                      0);
                parse_payload(&ev.frame);
            }
        } while (left > 0 || ev.kind != PROTO_FSP_EV_NONE);
        data += n;
        len -= n;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    static proto_fsp_decoder *d;
    if (!d)
        d = proto_fsp_decoder_new(0);
    proto_fsp_decoder_reset(d);
    uint8_t mode = data[0];
    data++;
    size--;
    if ((mode & 1) == 0) {
        static const size_t pieces[8] = {1, 2, 3, 7, 13, 64, 4096, 1 << 20};
        decode_all(d, data, size, pieces[(mode >> 1) & 7]);
        return 0;
    }
    if (size < 1 || size - 1 > PROTO_FSP_MAX_PAYLOAD)
        return 0;
    static uint8_t frame[PROTO_FSP_MAX_FRAME];
    size_t sz;
    check(proto_fsp_encode(data[0], (uint16_t)(mode * 257), data + 1,
                           size - 1, frame, sizeof frame, &sz) == 0);
    decode_all(d, frame, sz, (size_t)1 << 20);
    return 0;
}
