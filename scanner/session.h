/* session.h — the host side of one FSP/1 session with one scanner: the
 * state machine of proto/FSP1.md on top of any transport.
 *
 * The session does no I/O and reads no clock: the caller feeds it the
 * bytes a transport read, the current time (milliseconds of any
 * monotonic clock), and sends the frames it queues. That keeps it the
 * same for libusb, hidraw and the in-memory transport of the unit tests,
 * and lets the tests drive its timeouts with a fake clock.
 *
 * What it does:
 * - greeting: HELLO (sequence numbers restart), then every other frame is
 *   ignored until INFO; GET_INFO is sent again every info_retry_ms while
 *   no INFO arrives;
 * - a scan: SCAN_STARTED, PROGRESS, MODEL chunks placed at their offsets
 *   (in any order; each valid one ACKed), SCAN_DONE ACKed once the whole
 *   model is present and its CRC-32 matches (with defer_done_ack, once
 *   the caller also says it kept the scan), or NAKed — after the third
 *   NAK of SCAN_DONE the scan is dropped (the device drops it too);
 * - checks: a frame with a bad CRC, a gap in the device's sequence
 *   numbers, or a payload that fails its checks is NAKed (a missing frame
 *   is NAKed again every resend_ms); a frame NAKed max_naks times drops
 *   the scan (with ABORT); a scan without any frame for scan_timeout_ms
 *   is dropped (with ABORT); a jump in the sequence numbers far outside
 *   the window restarts the session with HELLO, which abandons the scan;
 * - the host's own RESULT and ABORT frames are re-sent every resend_ms
 *   until ACKed (at most three times), and any recent host frame the
 *   device NAKs is sent again with its original sequence number.
 *
 * Thread safety: none inside; the caller serialises every call on one
 * session (scanner.c holds a per-device mutex). Event callbacks run
 * inside the call that caused them and must not call back into the
 * session. */
#ifndef SCAN_SESSION_H
#define SCAN_SESSION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "fsp.h"
#include "transport.h"

typedef struct scan_session_cfg {
    int scan_timeout_ms;     /* give up a scan after this long without a
                                frame; default 30,000 */
    int resend_ms;           /* re-send unACKed RESULT/ABORT, re-NAK a
                                missing frame; default 5,000 */
    int info_retry_ms;       /* GET_INFO again while no INFO; 2,000 */
    int max_naks;            /* NAKs of one frame before the scan is
                                dropped; default 5 */
    uint32_t max_model;      /* largest model accepted, bytes; 64 MiB */
    char host_version[PROTO_FSP_TEXT_MAX + 1]; /* HELLO's "version" */
    bool defer_done_ack;     /* false (default): a complete scan's
                                SCAN_DONE is ACKed at once; true: only
                                when scan_session_ack_done says the scan
                                was kept, so that a host which must store
                                it first never ACKs a scan it lost */
} scan_session_cfg;

/* Fills the defaults above (host_version "0.1.0"). */
void scan_session_cfg_default(scan_session_cfg *cfg);

/* Counters since the session was created (never reset by HELLO). */
typedef struct scan_session_stats {
    uint64_t frames_in;       /* valid frames decoded */
    uint64_t frames_out;      /* frames handed out by next_frame */
    uint64_t crc_errors;      /* frames that failed their CRC */
    uint64_t bad_magic;       /* losses of sync (bytes skipped) */
    uint64_t too_long;        /* headers over the payload limit */
    uint64_t bad_frames;      /* payloads failing checks, wrong types */
    uint64_t seq_errors;      /* gaps and jumps in sequence numbers */
    uint64_t ignored;         /* frames before INFO */
    uint64_t acks_sent, naks_sent, naks_received;
    uint64_t scans_started, scans_completed, scans_dropped;
    uint64_t model_bytes;     /* model bytes of completed scans */
    uint64_t restarts;        /* HELLOs after the first */
} scan_session_stats;

typedef struct scan_session_events {
    void *user;
    /* INFO arrived (after HELLO or GET_INFO). */
    void (*on_info)(void *user, const proto_fsp_info *info);
    /* SCAN_STARTED arrived, or a MODEL frame began a scan whose
     * SCAN_STARTED was lost (mode 255, contours 0). */
    void (*on_scan_started)(void *user, uint8_t mode, uint32_t contours);
    void (*on_progress)(void *user, uint32_t done, uint32_t total);
    /* A scan completed and was ACKed (with defer_done_ack: its SCAN_DONE
     * awaits scan_session_ack_done). bytes is malloc'd and now belongs
     * to the callee (who frees it); format is a proto_fsp_model_format. */
    void (*on_scan_complete)(void *user, uint8_t *bytes, size_t len,
                             uint8_t format);
    /* A scan was dropped; why is a short static or stack text. */
    void (*on_scan_dropped)(void *user, const char *why);
    /* The device sent ERROR code with message msg. */
    void (*on_device_error)(void *user, uint16_t code, const char *msg);
} scan_session_events;

typedef struct scan_session scan_session;

/* A new session (no frame queued yet: call scan_session_hello). cfg NULL
 * means defaults; ev may be NULL or have NULL members. NULL on OOM. */
scan_session *scan_session_new(const scan_session_cfg *cfg,
                               const scan_session_events *ev);

/* Frees s and every queued frame (NULL accepted); returns NULL. */
scan_session *scan_session_free(scan_session *s);

/* (Re)starts the session: drops a scan in progress, forgets queued and
 * awaited frames, restarts both sequence counters and queues HELLO.
 * -ENOMEM leaves the session without a HELLO queued. */
int scan_session_hello(scan_session *s, uint64_t now_ms);

/* Feeds bytes read from the transport. Frames and errors are handled as
 * described above; replies are queued. */
void scan_session_input(scan_session *s, const uint8_t *data, size_t len,
                        uint64_t now_ms);

/* Handles every timeout that has expired at now_ms. */
void scan_session_tick(scan_session *s, uint64_t now_ms);

/* The earliest time at which scan_session_tick has something to do,
 * UINT64_MAX when nothing is pending. */
uint64_t scan_session_deadline(const scan_session *s);

/* Queues START_SCAN with mode 0..2. -EAGAIN before INFO arrived, -EBUSY
 * while a scan is in progress, -EINVAL for a bad mode, -ENOMEM. */
int scan_session_start_scan(scan_session *s, uint8_t mode, uint64_t now_ms);

/* Queues RESULT (re-sent until ACKed). -EAGAIN before INFO, -EINVAL when
 * r does not serialise, -ENOMEM. */
int scan_session_send_result(scan_session *s, const proto_fsp_result *r,
                             uint64_t now_ms);

/* With defer_done_ack: answers the SCAN_DONE of the scan last completed.
 * kept: ACK it (the scan counts as completed); else the scan counts as
 * dropped and ABORT (re-sent until ACKed) ends it on the device. Until
 * then a re-sent SCAN_DONE is ignored. -ENOENT when no answer is owed
 * (none completed since, or a HELLO restarted the session), -ENOMEM. */
int scan_session_ack_done(scan_session *s, bool kept, uint64_t now_ms);

/* Drops the scan in progress, if any, and queues ABORT. -EAGAIN before
 * INFO, -ENOMEM. */
int scan_session_abort(scan_session *s, uint64_t now_ms);


/* Sends every queued frame through t, each with timeout_ms. 0, or the
 * transport's negative errno (the failed frame is lost; later frames
 * stay queued). */
int scan_session_flush(scan_session *s, scan_transport *t, int timeout_ms);

/* True once INFO arrived after the last HELLO. */
bool scan_session_ready(const scan_session *s);

/* True while a scan is in progress; then *ret_done and *ret_total hold
 * its last PROGRESS (both 0 before any). Either pointer may be NULL. */
bool scan_session_scanning(const scan_session *s, uint32_t *ret_done,
                           uint32_t *ret_total);

/* The counters. */
const scan_session_stats *scan_session_get_stats(const scan_session *s);

#endif
