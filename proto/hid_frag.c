/* hid_frag.c — FSP/1 frames to 64-byte HID reports and back.
 *
 * Reassembler invariant: active is true exactly while a first fragment has
 * been accepted and its last fragment has not; buf[0 .. n) then holds the
 * fragments so far and n ≤ max. */
#include "hid_frag.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "fsp.h"

size_t proto_hid_report_count(size_t len)
{
    return (len + PROTO_HID_FRAG_MAX - 1) / PROTO_HID_FRAG_MAX;
}

void proto_hid_fragment(const uint8_t *frame, size_t len, size_t k,
                        uint8_t out[PROTO_HID_REPORT_SIZE])
{
    size_t count = proto_hid_report_count(len);
    size_t off = k * PROTO_HID_FRAG_MAX;
    size_t n = len - off < PROTO_HID_FRAG_MAX ? len - off : PROTO_HID_FRAG_MAX;
    memset(out, 0, PROTO_HID_REPORT_SIZE);
    out[0] = PROTO_HID_REPORT_ID;
    out[1] = (uint8_t)((k == 0 ? PROTO_HID_FIRST : 0) |
                       (k + 1 == count ? PROTO_HID_LAST : 0));
    out[2] = (uint8_t)n;
    memcpy(out + 3, frame + off, n);
}

struct proto_hid_reasm {
    uint8_t *buf;
    size_t n, max;
    bool active;
};

proto_hid_reasm *proto_hid_reasm_new(size_t max_frame)
{
    if (max_frame == 0)
        max_frame = PROTO_FSP_MAX_FRAME;
    proto_hid_reasm *r = calloc(1, sizeof *r);
    if (!r)
        return NULL;
    r->buf = malloc(max_frame);
    if (!r->buf) {
        free(r);
        return NULL;
    }
    r->max = max_frame;
    return r;
}

proto_hid_reasm *proto_hid_reasm_free(proto_hid_reasm *r)
{
    if (r) {
        free(r->buf);
        free(r);
    }
    return NULL;
}

/* Drops any partial frame. */
static void proto_hid_reasm_reset(proto_hid_reasm *r)
{
    r->n = 0;
    r->active = false;
}

proto_hid_status proto_hid_reasm_push(proto_hid_reasm *r,
                                      const uint8_t *report, size_t len,
                                      const uint8_t **ret_frame,
                                      size_t *ret_len)
{
    if (len != PROTO_HID_REPORT_SIZE || report[0] != PROTO_HID_REPORT_ID ||
        (report[1] & ~(PROTO_HID_FIRST | PROTO_HID_LAST))) {
        proto_hid_reasm_reset(r);
        return PROTO_HID_E_REPORT;
    }
    size_t n = report[2];
    if (n == 0 || n > PROTO_HID_FRAG_MAX) {
        proto_hid_reasm_reset(r);
        return PROTO_HID_E_LENGTH;
    }
    for (size_t i = 3 + n; i < PROTO_HID_REPORT_SIZE; i++) {
        if (report[i]) {
            proto_hid_reasm_reset(r);
            return PROTO_HID_E_REPORT;
        }
    }
    proto_hid_status st = PROTO_HID_MORE;
    if (report[1] & PROTO_HID_FIRST) {
        if (r->active)
            st = PROTO_HID_E_RESTART;
        r->active = true;
        r->n = 0;
    } else if (!r->active) {
        return PROTO_HID_E_NO_FIRST;
    }
    if (n > r->max - r->n) {
        proto_hid_reasm_reset(r);
        return PROTO_HID_E_OVERLONG;
    }
    memcpy(r->buf + r->n, report + 3, n);
    r->n += n;
    if (!(report[1] & PROTO_HID_LAST)) {
        *ret_frame = NULL;
        *ret_len = 0;
        return st;
    }
    /* A restarted frame that completes in the same report still reports
     * the restart; the caller counts the loss and takes the frame. */
    *ret_frame = r->buf;
    *ret_len = r->n;
    r->active = false;
    return st == PROTO_HID_E_RESTART ? st : PROTO_HID_FRAME;
}
