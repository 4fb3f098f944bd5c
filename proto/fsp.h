/* fsp.h — FSP/1, the frames of the USB scanner wire protocol (proto/FSP1.md
 * is the full description a firmware engineer implements from).
 *
 * A frame, all integers little-endian:
 *   "FSP1" | u8 type | u8 flags | u16 seq | u32 payload length | payload |
 *   u32 CRC-32 (IEEE, proto/crc32.h) of everything before it.
 * The header is 12 bytes, the trailer 4; a payload is at most 65,536 bytes.
 * The flags byte is reserved: encoders write 0, the decoder passes it on
 * and callers ignore it.
 *
 * This file holds the encoder, an incremental decoder that turns any split
 * of a byte stream into frames (resynchronising on bad magic, bad CRC and
 * oversized lengths, each reported once as a typed event so that callers
 * can count them), and one builder and one strict parser per payload type.
 *
 * Thread safety: all functions are reentrant; one decoder must not be used
 * by two threads at once. Nothing here logs, allocates without saying so,
 * or keeps global state. */
#ifndef PROTO_FSP_H
#define PROTO_FSP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctx.h"

enum {
    PROTO_FSP_HEADER_SIZE = 12,
    PROTO_FSP_CRC_SIZE = 4,
    PROTO_FSP_OVERHEAD = PROTO_FSP_HEADER_SIZE + PROTO_FSP_CRC_SIZE,
    PROTO_FSP_MAX_PAYLOAD = 65536,
    PROTO_FSP_MAX_FRAME = PROTO_FSP_MAX_PAYLOAD + PROTO_FSP_OVERHEAD,
    /* model bytes in one MODEL frame, and MODEL frames a device may have
     * sent without an ACK */
    PROTO_FSP_MODEL_CHUNK_MAX = 16384,
    PROTO_FSP_MODEL_WINDOW = 4,
    /* longest text field of INFO and HELLO (bytes, without the NUL) */
    PROTO_FSP_TEXT_MAX = 63,
};

typedef enum proto_fsp_type {
    PROTO_FSP_HELLO = 0x01,        /* host→dev, JSON {"host","version"} */
    PROTO_FSP_GET_INFO = 0x02,     /* host→dev, empty */
    PROTO_FSP_START_SCAN = 0x03,   /* host→dev, u8 mode */
    PROTO_FSP_ACK = 0x04,          /* both, u16 seq */
    PROTO_FSP_NAK = 0x05,          /* both, u16 seq */
    PROTO_FSP_ABORT = 0x06,        /* host→dev, empty */
    PROTO_FSP_RESULT = 0x07,       /* host→dev, JSON summary of the job */
    PROTO_FSP_INFO = 0x81,         /* dev→host, JSON */
    PROTO_FSP_SCAN_STARTED = 0x82, /* dev→host, u8 mode, u32 contours */
    PROTO_FSP_PROGRESS = 0x83,     /* dev→host, u32 done, u32 total */
    PROTO_FSP_MODEL = 0x84,        /* dev→host, u32 total, u32 offset, bytes */
    PROTO_FSP_SCAN_DONE = 0x85,    /* dev→host, u32 total, u32 crc, u8 fmt */
    PROTO_FSP_ERROR = 0x86,        /* both, u16 code, UTF-8 message */
} proto_fsp_type;

typedef enum proto_fsp_mode {
    PROTO_FSP_MODE_QUICK = 0,
    PROTO_FSP_MODE_ACCURACY = 1,
    PROTO_FSP_MODE_HI_ACCURACY = 2,
} proto_fsp_mode;

/* SCAN_DONE's format byte. */
typedef enum proto_fsp_model_format {
    PROTO_FSP_MODEL_JSON = 0, /* facet-model/1 */
    PROTO_FSP_MODEL_FMB1 = 1,
} proto_fsp_model_format;

/* ERROR codes. */
enum {
    PROTO_FSP_ERR_BAD_FRAME = 1,
    PROTO_FSP_ERR_BUSY = 2,
    PROTO_FSP_ERR_SCAN_DROPPED = 3,
    PROTO_FSP_ERR_BAD_REQUEST = 4,
};

/* The name of a frame type ("HELLO", "MODEL", ...), "unknown" otherwise.
 * Static string. */
const char *proto_fsp_type_name(uint8_t type);

/* True for the thirteen types above. */
bool proto_fsp_type_known(uint8_t type);

/* One frame. payload points at len bytes owned by whoever filled the
 * struct (the decoder: valid until its next call). */
typedef struct proto_fsp_frame {
    uint8_t type;
    uint8_t flags;
    uint16_t seq;
    uint32_t len;
    const uint8_t *payload;
} proto_fsp_frame;

/* Encodes one frame into out[0 .. 16 + len). payload may be NULL when len
 * is 0; out must not overlap payload. On success returns 0 and stores the
 * frame size in *ret_size. -EMSGSIZE when len exceeds 65,536, -ENOBUFS
 * when cap is smaller than 16 + len (nothing written to *ret_size). */
int proto_fsp_encode(uint8_t type, uint16_t seq, const void *payload,
                     size_t len, uint8_t *out, size_t cap, size_t *ret_size);

/* --- the incremental decoder ------------------------------------------ */

typedef enum proto_fsp_event_kind {
    PROTO_FSP_EV_NONE = 0,
    /* a frame passed every check; ev->frame holds it */
    PROTO_FSP_EV_FRAME,
    /* bytes that do not begin a frame were skipped; reported once each
     * time the stream falls out of step after a good frame (or at the
     * start), however many bytes follow */
    PROTO_FSP_EV_BAD_MAGIC,
    /* a complete frame failed its CRC; ev->frame holds the header it
     * claimed (payload NULL), which may itself be corrupt */
    PROTO_FSP_EV_BAD_CRC,
    /* a header claimed a payload longer than the decoder's limit;
     * ev->frame holds that header (payload NULL) */
    PROTO_FSP_EV_TOO_LONG,
} proto_fsp_event_kind;

typedef struct proto_fsp_event {
    proto_fsp_event_kind kind;
    proto_fsp_frame frame;
} proto_fsp_event;

typedef struct proto_fsp_decoder proto_fsp_decoder;

/* A decoder accepting payloads of at most max_payload bytes (0 means
 * 65,536; larger values are clamped to 65,536). It buffers at most one
 * frame (16 + max_payload bytes, allocated here). NULL on out-of-memory. */
proto_fsp_decoder *proto_fsp_decoder_new(uint32_t max_payload);

/* Frees d (NULL accepted); returns NULL. */
proto_fsp_decoder *proto_fsp_decoder_free(proto_fsp_decoder *d);

/* Forgets any partial frame (e.g. after the device was reopened). */
void proto_fsp_decoder_reset(proto_fsp_decoder *d);

/* Consumes bytes from data[0 .. len) until one event is ready or all bytes
 * are used, and returns how many bytes it consumed; ev->kind is
 * PROTO_FSP_EV_NONE when no event is ready. Call it again with the rest
 * of the bytes (and with len 0 to drain events still pending in the
 * buffer: after an error the decoder rescans the bytes it holds, which
 * may contain further frames). Every call either consumes at least one
 * byte or reports an event, so the loop
 *     while (len > 0 || ev.kind != NONE) { n = decode(...); ... }
 * terminates. A frame's payload stays valid until the next call.
 * After a bad CRC or an oversized length the decoder resumes its search
 * for "FSP1" one byte after the start of the rejected frame, so a frame
 * hidden behind a corrupt length field is still found. */
size_t proto_fsp_decode(proto_fsp_decoder *d, const uint8_t *data, size_t len,
                        proto_fsp_event *ev);

/* Bytes discarded while searching for a frame start since creation. */
uint64_t proto_fsp_decoder_skipped(const proto_fsp_decoder *d);

/* --- payloads ------------------------------------------------------------
 * Parsers take a decoded frame, check its type and exact length (fixed
 * size payloads must have exactly their size), return 0 or -EINVAL with
 * a message in err naming the frame ("MODEL: offset 900 + 200 bytes
 * beyond total 1000"). Builders write into caller memory and return the
 * payload size, or return a malloc'd NUL-terminated JSON text the caller
 * frees (NULL on out-of-memory or invalid fields). */

/* ACK and NAK: the sequence number of the frame acknowledged / wanted. */
size_t proto_fsp_build_seq(uint8_t out[2], uint16_t seq);
int proto_fsp_parse_seq(const proto_fsp_frame *f, uint16_t *ret_seq,
                        geo_err *err);

/* START_SCAN: mode 0..2. */
size_t proto_fsp_build_start_scan(uint8_t out[1], uint8_t mode);
int proto_fsp_parse_start_scan(const proto_fsp_frame *f, uint8_t *ret_mode,
                               geo_err *err);

/* SCAN_STARTED: mode 0..2 and the number of contours the scan takes. */
typedef struct proto_fsp_scan_started {
    uint8_t mode;
    uint32_t contours;
} proto_fsp_scan_started;
size_t proto_fsp_build_scan_started(uint8_t out[5],
                                    const proto_fsp_scan_started *s);
int proto_fsp_parse_scan_started(const proto_fsp_frame *f,
                                 proto_fsp_scan_started *ret, geo_err *err);

/* PROGRESS: done ≤ total contours. */
typedef struct proto_fsp_progress {
    uint32_t done, total;
} proto_fsp_progress;
size_t proto_fsp_build_progress(uint8_t out[8], const proto_fsp_progress *p);
int proto_fsp_parse_progress(const proto_fsp_frame *f,
                             proto_fsp_progress *ret, geo_err *err);

/* MODEL: bytes [offset, offset + len) of a model of total bytes. The
 * parser checks 1 ≤ len ≤ 16,384 and offset + len ≤ total; ret->bytes
 * points into the frame's payload. The builder writes 8 + len bytes
 * (out must hold them; bytes must not overlap out). */
typedef struct proto_fsp_model_chunk {
    uint32_t total, offset, len;
    const uint8_t *bytes;
} proto_fsp_model_chunk;
size_t proto_fsp_build_model(uint8_t *out, uint32_t total, uint32_t offset,
                             const uint8_t *bytes, uint32_t len);
int proto_fsp_parse_model(const proto_fsp_frame *f,
                          proto_fsp_model_chunk *ret, geo_err *err);

/* SCAN_DONE: the model's total length, its CRC-32, its format (0, 1). */
typedef struct proto_fsp_scan_done {
    uint32_t total, crc;
    uint8_t format;
} proto_fsp_scan_done;
size_t proto_fsp_build_scan_done(uint8_t out[9], const proto_fsp_scan_done *d);
int proto_fsp_parse_scan_done(const proto_fsp_frame *f,
                              proto_fsp_scan_done *ret, geo_err *err);

/* ERROR: a code and a UTF-8 message without NUL bytes. The builder
 * truncates the message (at a character boundary) to fit cap and
 * returns the payload size (0 if cap < 2). The parser copies the message
 * into msg[0 .. msg_cap) (truncated at a character boundary,
 * NUL-terminated; msg may be NULL when msg_cap is 0). */
size_t proto_fsp_build_error(uint8_t *out, size_t cap, uint16_t code,
                             const char *msg);
int proto_fsp_parse_error(const proto_fsp_frame *f, uint16_t *ret_code,
                          char *msg, size_t msg_cap, geo_err *err);

/* HELLO: {"host": "facetd", "version": "0.1.0"}. */
typedef struct proto_fsp_hello {
    char host[PROTO_FSP_TEXT_MAX + 1];
    char version[PROTO_FSP_TEXT_MAX + 1];
} proto_fsp_hello;
char *proto_fsp_build_hello(const proto_fsp_hello *h);
int proto_fsp_parse_hello(const proto_fsp_frame *f, proto_fsp_hello *ret,
                          geo_err *err);

/* INFO: {"vendor","model","serial","firmware": strings, "contours": n}.
 * The serial names the scanner everywhere (job sources "usb:<serial>",
 * URLs), so it must be 1..63 characters from [A-Za-z0-9._:-]; the other
 * strings are at most 63 bytes of UTF-8. Unknown keys are ignored,
 * duplicate keys rejected. */
typedef struct proto_fsp_info {
    char vendor[PROTO_FSP_TEXT_MAX + 1];
    char model[PROTO_FSP_TEXT_MAX + 1];
    char serial[PROTO_FSP_TEXT_MAX + 1];
    char firmware[PROTO_FSP_TEXT_MAX + 1];
    uint32_t contours;
} proto_fsp_info;
char *proto_fsp_build_info(const proto_fsp_info *info);
int proto_fsp_parse_info(const proto_fsp_frame *f, proto_fsp_info *ret,
                         geo_err *err);

/* True when s is a valid scanner serial (see INFO). */
bool proto_fsp_serial_valid(const char *s);

/* RESULT: the summary of the job a scan became. Counts are -1 when not
 * known (a failed job), and are then written as JSON null. */
typedef struct proto_fsp_result {
    char job[PROTO_FSP_TEXT_MAX + 1];   /* job id */
    char state[16];                     /* succeeded, failed, canceled */
    char url[128];                      /* the job's path, /v1/jobs/{id} */
    int64_t facets_before, facets_after;
    int64_t self_intersections;
    bool valid;
} proto_fsp_result;
char *proto_fsp_build_result(const proto_fsp_result *r);
int proto_fsp_parse_result(const proto_fsp_frame *f, proto_fsp_result *ret,
                           geo_err *err);

#endif
