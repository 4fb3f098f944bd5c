/* fuzz_hid_reassembler.c — libFuzzer target for the HID report
 * reassembler. The input is cut into 64-byte reports (the tail becomes
 * one short report); no input may crash, leak or grow a frame beyond the
 * limit, and every frame that comes out must fragment and reassemble
 * again to itself. Frames are then fed to the FSP/1 decoder, as the HID
 * transport does. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fsp.h"
#include "hid_frag.h"

enum { LIMIT = 4096 };

static void check(int cond)
{
    if (!cond)
        abort();
}

static uint8_t copy[LIMIT];

static void reassemble_again(proto_hid_reasm *r2, const uint8_t *frame,
                             size_t len)
{
    memcpy(copy, frame, len);
    size_t count = proto_hid_report_count(len);
    uint8_t rep[PROTO_HID_REPORT_SIZE];
    for (size_t k = 0; k < count; k++) {
        proto_hid_fragment(copy, len, k, rep);
        const uint8_t *out = NULL;
        size_t n = 0;
        proto_hid_status st = proto_hid_reasm_push(r2, rep, sizeof rep, &out,
                                                   &n);
        if (k + 1 < count) {
            check(st == PROTO_HID_MORE);
        } else {
            check(st == PROTO_HID_FRAME && n == len);
            check(memcmp(out, copy, len) == 0);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* fresh state per input, so a crash replays from its input alone */
    proto_hid_reasm *r = proto_hid_reasm_new(LIMIT);
    proto_hid_reasm *r2 = proto_hid_reasm_new(LIMIT);
    proto_fsp_decoder *d = proto_fsp_decoder_new(0);
    check(r && r2 && d);
    while (size > 0) {
        size_t n = size < PROTO_HID_REPORT_SIZE ? size : PROTO_HID_REPORT_SIZE;
        const uint8_t *frame = NULL;
        size_t len = 0;
        proto_hid_status st = proto_hid_reasm_push(r, data, n, &frame, &len);
        check(st >= PROTO_HID_E_RESTART && st <= PROTO_HID_FRAME);
        if (n < PROTO_HID_REPORT_SIZE)
            check(st == PROTO_HID_E_REPORT);
        if ((st == PROTO_HID_FRAME || st == PROTO_HID_E_RESTART) && frame) {
            check(len >= 1 && len <= LIMIT);
            reassemble_again(r2, frame, len);
            proto_fsp_event ev;
            size_t left = len;
            do {
                size_t used = proto_fsp_decode(d, frame, left, &ev);
                frame += used;
                left -= used;
            } while (left > 0 || ev.kind != PROTO_FSP_EV_NONE);
        }
        data += n;
        size -= n;
    }
    proto_hid_reasm_free(r);
    proto_hid_reasm_free(r2);
    proto_fsp_decoder_free(d);
    return 0;
}
