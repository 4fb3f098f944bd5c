/* mock_fspdev.h — the device side of FSP/1, as a scanner's firmware plays
 * it, for the mocked scanner of the tests (not part of libfacetscan).
 *
 * The engine does no I/O and reads no clock: the harness feeds it the
 * host's byte stream and the time, and sends the frames it queues. It
 * answers HELLO and GET_INFO with INFO, streams a model as MODEL chunks
 * (at most 16 KiB each, at most four unacknowledged) between SCAN_STARTED
 * / PROGRESS and SCAN_DONE, re-sends what the host NAKs or leaves
 * unacknowledged for 5 s, drops a scan after the third NAK of SCAN_DONE
 * (ERROR 3), ACKs ABORT and RESULT, and records everything the host sent.
 * Faults on request: a corrupted MODEL frame, a wrong model CRC, silence
 * (stall), and a request to be unplugged after n MODEL frames.
 *
 * Not thread-safe: the harness serialises calls. */
#ifndef SCAN_MOCK_FSPDEV_H
#define SCAN_MOCK_FSPDEV_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "fsp.h"

typedef struct mock_fspdev mock_fspdev;

/* What the host did, for the harness's status and the tests. */
typedef struct mock_fspdev_record {
    uint64_t hellos, get_infos, start_scans, acks, naks, aborts, results;
    uint64_t crc_errors;        /* host frames failing their CRC */
    uint64_t scans_started, scans_done, scans_dropped, scans_abandoned;
    uint64_t model_frames, resends;
} mock_fspdev_record;

/* A device describing itself with info; on_event (may be NULL) receives
 * one line of text per notable event ("result {...}", "done-acked",
 * "nak 12", "dropped", "abandoned", "hello"). NULL on OOM. */
mock_fspdev *mock_fspdev_new(const proto_fsp_info *info,
                             void (*on_event)(void *user, const char *line),
                             void *user);
mock_fspdev *mock_fspdev_free(mock_fspdev *d);

/* The model sent for a START_SCAN from the host (copied). */
int mock_fspdev_set_model(mock_fspdev *d, const uint8_t *bytes, size_t len,
                          uint8_t format);

/* The operator starts a scan of the model last set. -EBUSY while
 * scanning, -ENOENT without a model. */
int mock_fspdev_scan(mock_fspdev *d, uint64_t now_ms);

/* Faults, each for the next scan (or the one in progress): the k-th MODEL
 * frame (1-based) goes out once with a broken CRC; SCAN_DONE carries a
 * wrong model CRC; after n MODEL frames the device asks to be unplugged.
 * k or n 0 clears. */
void mock_fspdev_corrupt_model(mock_fspdev *d, unsigned k);
void mock_fspdev_corrupt_done(mock_fspdev *d, bool on);
void mock_fspdev_unplug_after(mock_fspdev *d, unsigned n);
/* Silence: no frame goes out and host frames are discarded until off;
 * stall_after silences the device once n MODEL frames of the next scan
 * went out (0 clears). */
void mock_fspdev_stall(mock_fspdev *d, bool on);
void mock_fspdev_stall_after(mock_fspdev *d, unsigned n);

/* True once the unplug_after count was reached (the harness unplugs). */
bool mock_fspdev_wants_unplug(const mock_fspdev *d);

/* The host's byte stream. */
void mock_fspdev_input(mock_fspdev *d, const uint8_t *data, size_t len,
                       uint64_t now_ms);

/* Re-sends frames left unacknowledged too long. */
void mock_fspdev_tick(mock_fspdev *d, uint64_t now_ms);

/* When tick has something to do next (UINT64_MAX: nothing). */
uint64_t mock_fspdev_deadline(const mock_fspdev *d);

/* The next frame to send (malloc'd for the caller), NULL when none. */
uint8_t *mock_fspdev_next_frame(mock_fspdev *d, size_t *ret_len);

/* Counters, and the device's state as a JSON object (malloc'd). */
const mock_fspdev_record *mock_fspdev_get_record(const mock_fspdev *d);
char *mock_fspdev_status_json(const mock_fspdev *d);

#endif
