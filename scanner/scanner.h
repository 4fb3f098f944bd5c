/* scanner.h — USB scanner intake: the public interface of libfacetscan.
 *
 * scan_intake_start() starts one intake thread that watches for scanners
 * (libusb hotplug for bulk devices, a libudev monitor for hidraw devices,
 * and an enumeration of what is already plugged in), and one thread per
 * connected scanner that opens it, greets it (HELLO → INFO) and runs the
 * FSP/1 session (session.h) on its transport. A finished scan's model
 * bytes are handed to on_scan_complete; the daemon turns them into a job
 * and, when the job ends, calls scan_send_result() so that the scanner
 * gets a RESULT frame. RESULTs reach a scanner in the order of its scans,
 * also across a re-plug. A scanner that leaves is closed and its partial
 * scan dropped; it stays listed as offline.
 *
 * Scanners are told apart by their serial (INFO's "serial", equal to the
 * USB serial string): 1..63 characters of [A-Za-z0-9._:-].
 *
 * Threads and callbacks: callbacks run on intake-owned threads (the
 * intake thread or a scanner's thread), possibly concurrently for two
 * scanners, never concurrently for one. They may call every scan_*
 * function except scan_intake_stop. They should return quickly: a
 * scanner's frames wait while its callback runs.
 *
 * Every function is thread-safe. Errors are negative errno values. */
#ifndef SCAN_SCANNER_H
#define SCAN_SCANNER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "config.h"
#include "fsp.h"
#include "model_io.h"

typedef struct scan_intake scan_intake;

/* What a scanner said about itself in INFO, and where it is attached. */
typedef struct scan_device_info {
    char serial[PROTO_FSP_TEXT_MAX + 1];
    char vendor[PROTO_FSP_TEXT_MAX + 1];
    char model[PROTO_FSP_TEXT_MAX + 1];
    char firmware[PROTO_FSP_TEXT_MAX + 1];
    uint32_t contours;        /* contours of a full scan */
    uint16_t vid, pid;
    scan_kind kind;
    char path[64];            /* "usb:001/004" or "/dev/hidraw0" */
} scan_device_info;

typedef enum scan_state {
    SCAN_STATE_IDLE = 0,
    SCAN_STATE_SCANNING,
    SCAN_STATE_OFFLINE,
} scan_state;

/* "idle", "scanning", "offline". */
const char *scan_state_name(scan_state st);

/* One row of scan_list(). */
typedef struct scan_device_status {
    scan_device_info info;   /* only serial is set while !seen */
    bool seen;               /* INFO arrived since the intake started;
                                false for a scanner known only from
                                scan_owe_result */
    scan_state state;
    uint32_t progress_done, progress_total; /* last PROGRESS of the scan
                                               in progress, else 0 */
    char last_job[PROTO_FSP_TEXT_MAX + 1];  /* "" before the first job */
    uint64_t scans_completed, scans_dropped;
    int64_t last_seen_ms;    /* CLOCK_REALTIME of the last frame, ms */
} scan_device_status;

/* Counters over every scanner since the intake started (a scanner's
 * counts survive its unplugging). */
typedef struct scan_metrics {
    uint64_t frames_in, frames_out;
    uint64_t crc_errors;          /* frames failing their CRC */
    uint64_t bad_frames;          /* bad magic, over-long, bad payloads */
    uint64_t seq_errors;
    uint64_t naks_sent, naks_received;
    uint64_t reassembly_failures; /* HID reports dropped */
    uint64_t devices_connected;   /* scanners greeted and attached now */
    uint64_t scans_completed, scans_dropped;
    uint64_t model_bytes;         /* of completed scans */
} scan_metrics;

typedef struct scan_callbacks {
    void *user;
    /* A scanner answered HELLO with INFO (again after every re-plug). */
    void (*on_device)(void *user, const scan_device_info *info);
    /* The scanner with this serial was unplugged or failed. */
    void (*on_device_gone)(void *user, const char *serial);
    /* A scan completed: bytes[0 .. len) (valid during the call only) are
     * a model in format fmt (PROTO_FMT_JSON or PROTO_FMT_FMB1). Return 0
     * and write the id of the job made from it into ret_job (NUL-
     * terminated, 1..63 bytes): a RESULT will be owed for it and the
     * scanner's later RESULTs wait for this one. Return a negative errno
     * to refuse the scan (no RESULT owed). The device's SCAN_DONE is
     * ACKed only after this returns 0 — so a caller that stores the scan
     * here never has a scan ACKed that it then loses — and a refused scan
     * is ended on the device with ABORT. */
    int (*on_scan_complete)(void *user, const char *serial,
                            const uint8_t *bytes, size_t len,
                            proto_format fmt, char *ret_job, size_t job_cap);
    /* PROGRESS of a scan (done ≤ total contours). May be NULL. */
    void (*on_progress)(void *user, const char *serial, uint32_t done,
                        uint32_t total);
    /* Something worth a log line ("scan dropped: ...", "ERROR 2 from
     * device: busy", "cannot open /dev/hidraw0: ..."); serial is "" when
     * not known yet. May be NULL. */
    void (*on_notice)(void *user, const char *serial, const char *msg);
} scan_callbacks;

typedef struct scan_options {
    int scan_timeout_ms;     /* 30,000: scan given up without a frame */
    int resend_ms;           /* 5,000 */
    int io_timeout_ms;       /* 2,000: one frame write */
    uint32_t max_model;      /* 64 MiB */
    char host_version[PROTO_FSP_TEXT_MAX + 1];
} scan_options;

/* Fills the defaults above (host_version "0.1.0"). */
void scan_options_default(scan_options *opt);

/* Starts watching for the devices of list[0 .. n) (config.h). cb and
 * its functions are copied; opt NULL means defaults. Scanners already
 * plugged in are found before this returns (their greeting and on_device
 * follow asynchronously). NULL with err set when libusb, libudev or the
 * thread cannot start. */
scan_intake *scan_intake_start(const scan_match *list, size_t n,
                               const scan_callbacks *cb,
                               const scan_options *opt, geo_err *err);

/* Stops every thread, closes every scanner (partial scans dropped, no
 * on_device_gone calls) and frees in. NULL accepted; returns NULL. Must
 * not be called from a callback. */
scan_intake *scan_intake_stop(scan_intake *in);

/* Every scanner seen since start, online or not, sorted by serial, in a
 * malloc'd array the caller frees. 0 or -ENOMEM. */
int scan_list(scan_intake *in, scan_device_status **ret, size_t *ret_n);

/* The status of one scanner. 0, or -ENOENT when never seen. */
int scan_get(scan_intake *in, const char *serial, scan_device_status *ret);

/* Asks the scanner to start a scan (START_SCAN, mode 0 quick, 1
 * accuracy, 2 hi-accuracy). -ENOENT unknown serial, -ENODEV offline,
 * -EAGAIN not greeted yet, -EBUSY already scanning, -EINVAL bad mode,
 * -EIO the frame could not be written. */
int scan_request_start(scan_intake *in, const char *serial, uint8_t mode);

/* Queues the RESULT of the job r->job made from a scan of this scanner;
 * it is sent once the RESULTs of every earlier scan were sent (at once
 * if the scanner is online, else when it is back). -ENOENT when no
 * RESULT is owed for that job, -EINVAL when r does not serialise. */
int scan_send_result(scan_intake *in, const char *serial,
                     const proto_fsp_result *r);

/* Owes the RESULT of job, made from a scan of serial before this intake
 * started (a daemon restarted while the job waited): it goes ahead of the
 * RESULTs of every scan this intake receives, after those owed by earlier
 * calls, and is sent like theirs once scan_send_result gives it and the
 * scanner is online. A serial never seen is listed as offline (seen
 * false) until it connects. Call it right after scan_intake_start, oldest
 * job first. 0 (also when already owed), -EINVAL for a bad serial or job
 * id, -ENOSPC when the scanner is owed too many RESULTs or too many
 * scanners are known. */
int scan_owe_result(scan_intake *in, const char *serial, const char *job);

/* Sums the counters. */
void scan_get_metrics(scan_intake *in, scan_metrics *ret);

#endif
