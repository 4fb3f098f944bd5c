/* scanners.h — facetd's side of the USB scanner intake (scanner/
 * scanner.h): a finished scan becomes a high-priority job with source
 * "usb:SERIAL" and the pipeline configured for that scanner model, and
 * the job's end goes back to the scanner as a RESULT frame.
 *
 * Nothing lost: on_scan_complete stores the job (store_put commits it,
 * fsync included) before it returns, and the intake ACKs the device's
 * SCAN_DONE only after that; a scan that cannot be kept (its model does
 * not parse, the store fails) is refused and the device gets ABORT.
 * Scanner jobs are not bounded by QueueSize: a scanner is paced by its
 * mechanics, and a refused scan is work the operator has to redo.
 *
 * RESULTs: the module keeps the jobs it owes a RESULT for. A job that
 * ends on a local worker is answered at once (scanners_job_done wakes
 * the sender thread); every owed job is also looked up in the store once
 * a second, so a job canceled while queued, deleted, or finished on
 * another node is answered too (a deleted one as "canceled"). The intake
 * sends RESULTs in scan order, and to an unplugged scanner once it is
 * back. At start the store's queued and running usb: jobs are owed again
 * (scan_owe_result), so jobs interrupted by a restart still answer their
 * scanner. Not kept across a restart: a RESULT owed for a job that had
 * already ended (its scanner was unplugged, or facetd stopped between
 * the end and the send) — the job itself stays in the store.
 *
 * Pipelines: [Scanners] Pipeline= for every scanner, or the PIPELINE of
 * a Scanner= line for that model. Each is checked against this build at
 * start: an operation the build lacks is a start-up error, so a scan is
 * never taken for a job that could only be refused — except that when
 * nothing was configured and the default "auto" is not in the build, the
 * intake stays off (with a warning) rather than keep facetd from
 * serving HTTP.
 *
 * Threads: the intake's threads call in (on_scan_complete, notices);
 * one sender thread sends RESULTs; every function below is thread-safe
 * except new/start/free, which the main thread calls in order. */
#ifndef FACETD_SCANNERS_H
#define FACETD_SCANNERS_H

#include <stdbool.h>
#include <stdint.h>

#include <jansson.h>

#include "cfg.h"
#include "job.h"
#include "job_pool.h"
#include "metrics.h"
#include "scanner.h"
#include "store.h"

typedef struct scanners scanners;

/* Reads the [Scanners] settings of c and checks every pipeline against
 * this build. 0 with *ret (whose intake may be off: scanners_enabled);
 * -ENOTSUP with err naming the setting when a configured pipeline uses
 * an operation this build lacks; -EINVAL for a pipeline file that no
 * longer parses; -ENOMEM. */
int scanners_new(const cfg *c, scanners **ret, geo_err *err);

/* True when the intake runs (or will once started); else *why (may be
 * NULL) says why not. */
bool scanners_enabled(scanners *sc, const char **why);

/* Owes again the RESULTs of the store's unfinished usb: jobs and starts
 * the intake and the sender thread; s, pool and m are borrowed and must
 * outlive the intake (see scanners_detach_pool for pool). No-op when the
 * intake is off. 0, or a negative errno with err. */
int scanners_start(scanners *sc, store *s, job_pool *pool, metrics *m,
                   geo_err *err);

/* A job ended on a local worker (the pool's done callback). Only jobs
 * whose source is usb:SERIAL concern it. Quick; never blocks on I/O. */
void scanners_job_done(scanners *sc, const job_rec *job);

/* From now on new scan jobs wake no worker pool (they wait in the store
 * for the next start); call before the pool stops. */
void scanners_detach_pool(scanners *sc);

/* Applies reloadable settings (Pipeline=, per-model pipelines are read
 * again from their files). A pipeline the build cannot run keeps the
 * running ones and returns -ENOTSUP with err. */
int scanners_reload(scanners *sc, const cfg *c, geo_err *err);

/* Stops the intake (partial scans dropped) and the sender thread, then
 * frees sc. Accepts NULL; returns NULL. */
scanners *scanners_free(scanners *sc);

/* {"enabled": bool, "disabled_reason"?: text, "scanners": [scanner...]}
 * for GET /v1/scanners (see scanners_status_json), NULL on OOM. */
json_t *scanners_list_json(scanners *sc);

/* One scanner as JSON: serial, vendor, model, firmware, contours,
 * usb_id "vvvv:pppp", transport bulk|hid, path, state idle|scanning|
 * offline, progress 0..1 with contours_done/contours_total, last_job and
 * last_job_url (null before the first), scans_completed, scans_dropped,
 * last_seen (RFC 3339) and pipeline (the one its scans get). Fields the
 * scanner has not told yet (seen false: known only as owed a RESULT) are
 * null. 0, -ENOENT (unknown serial or intake off), -ENOMEM. */
int scanners_status_json(scanners *sc, const char *serial, json_t **ret);

/* Asks a scanner to start a scan (START_SCAN with mode 0 quick, 1
 * accuracy, 2 hi-accuracy). The errors of scan_request_start: -ENOENT
 * (also when the intake is off), -ENODEV offline, -EAGAIN not greeted
 * yet, -EBUSY scanning, -EINVAL, -EIO. */
int scanners_request_scan(scanners *sc, const char *serial, uint8_t mode);

/* The intake's counters and the module's own, for /metrics. */
void scanners_get_metrics(scanners *sc, metrics_scanners *ret);

#endif
