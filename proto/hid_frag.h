/* hid_frag.h — carrying FSP/1 frames over 64-byte HID reports.
 *
 * Report layout (64 bytes, the same in both directions):
 *   byte 0   report id, always 1
 *   byte 1   flags: bit0 first fragment of a frame, bit1 last fragment;
 *            the other bits are 0
 *   byte 2   fragment length, 1..61
 *   3 ..     the fragment, then zero bytes up to 64
 * A frame goes out as consecutive reports, the first flagged first, the
 * last flagged last (a one-report frame has both flags). Fragments of two
 * frames never interleave in one direction.
 *
 * The fragmenter is a pure function; the reassembler is a small state
 * machine that checks every report and reports each failure as a typed
 * result so that callers can count them. Reentrant; one reassembler per
 * direction and thread. */
#ifndef PROTO_HID_FRAG_H
#define PROTO_HID_FRAG_H

#include <stddef.h>
#include <stdint.h>

enum {
    PROTO_HID_REPORT_SIZE = 64,
    PROTO_HID_REPORT_ID = 1,
    PROTO_HID_FRAG_MAX = 61,
    PROTO_HID_FIRST = 0x01,
    PROTO_HID_LAST = 0x02,
};

/* Reports needed for a frame of len bytes (0 for len 0). */
size_t proto_hid_report_count(size_t len);

/* Writes report k (0-based, k < proto_hid_report_count(len)) of the frame
 * frame[0 .. len) into out. */
void proto_hid_fragment(const uint8_t *frame, size_t len, size_t k,
                        uint8_t out[PROTO_HID_REPORT_SIZE]);

typedef enum proto_hid_status {
    PROTO_HID_MORE = 0,        /* fragment stored, frame not complete yet */
    PROTO_HID_FRAME = 1,       /* a frame is complete: *ret_frame, *ret_len */
    /* failures; the report is dropped and, except for E_RESTART, so is
     * any partial frame */
    PROTO_HID_E_REPORT = -1,   /* wrong size, report id, flag bits, padding */
    PROTO_HID_E_LENGTH = -2,   /* fragment length 0 or over 61 */
    PROTO_HID_E_NO_FIRST = -3, /* a middle or last fragment with no first */
    PROTO_HID_E_OVERLONG = -4, /* the frame grew beyond the limit */
    /* a first fragment arrived while a frame was incomplete: the partial
     * frame is dropped and the new one started (the report is kept; when
     * it is also the last fragment, *ret_frame and *ret_len hold the new
     * frame as for PROTO_HID_FRAME, otherwise *ret_frame is NULL) */
    PROTO_HID_E_RESTART = -5,
} proto_hid_status;


typedef struct proto_hid_reasm proto_hid_reasm;

/* A reassembler for frames of at most max_frame bytes (0 means the FSP/1
 * maximum, 65,552). NULL on out-of-memory. */
proto_hid_reasm *proto_hid_reasm_new(size_t max_frame);

/* Frees r (NULL accepted); returns NULL. */
proto_hid_reasm *proto_hid_reasm_free(proto_hid_reasm *r);


/* Takes one report of len bytes (a report must be exactly 64 bytes).
 * On PROTO_HID_FRAME, *ret_frame points at *ret_len bytes owned by r,
 * valid until the next call. */
proto_hid_status proto_hid_reasm_push(proto_hid_reasm *r,
                                      const uint8_t *report, size_t len,
                                      const uint8_t **ret_frame,
                                      size_t *ret_len);

#endif
