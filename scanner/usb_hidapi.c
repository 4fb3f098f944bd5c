/* usb_hidapi.c — the HID transport: FSP/1 frames cut into 64-byte reports
 * (proto/hid_frag.h) through hidapi's hidraw backend.
 *
 * hidapi gives no file descriptor to wait on together with a wake-up, so
 * a read waits in slices of SLICE_MS and checks the cancel flag between
 * them: cancellation takes effect within one slice, and an idle scanner
 * costs ten wake-ups a second. An unplugged device ends a read at once
 * (hidraw reports POLLHUP). Reports that fail reassembly are dropped and
 * counted in reassembly_failures; read returns only whole frames.
 *
 * hidapi 0.13's hid_read_timeout and hid_write both rewrite the device's
 * error string, so they must not run at the same time: io serialises
 * them. A writer announces itself in want before it waits for io, and
 * the reader steps aside between slices, so a write waits at most one
 * slice.
 *
 * hid_init() must have run (scan_intake_start does it) before open. */
#include <errno.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <wchar.h>

#include <hidapi.h>

#include "fsp.h"
#include "hid_frag.h"
#include "transport.h"

enum { SLICE_MS = 100 };

typedef struct hid_transport {
    scan_transport base;
    hid_device *h;
    proto_hid_reasm *reasm;
    atomic_bool canceled, gone;
    pthread_mutex_t io;
    pthread_cond_t idle;  /* signalled when a writer got io */
    atomic_int want;      /* writers waiting for io */
} hid_transport;

static uint64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

static void ascii_of(const wchar_t *w, char *out, size_t cap)
{
    size_t k = 0;
    for (; w && *w && k + 1 < cap; w++)
        out[k++] = (*w >= 0x20 && *w < 0x7f) ? (char)*w : '?';
    out[k] = '\0';
}

static void hid_tr_close(scan_transport *t)
{
    hid_transport *h = (hid_transport *)t;
    if (h->h)
        hid_close(h->h);
    proto_hid_reasm_free(h->reasm);
    pthread_cond_destroy(&h->idle);
    pthread_mutex_destroy(&h->io);
    free(h);
}

static int hid_tr_open(void *backend, const scan_devaddr *addr,
                       scan_transport **ret, char *serial, size_t serial_cap,
                       geo_err *err)
{
    (void)backend;
    hid_transport *h = calloc(1, sizeof *h);
    if (!h)
        return geo_err_set(err, -ENOMEM, "out of memory");
    h->base.ops = &scan_hidapi_ops;
    pthread_mutex_init(&h->io, NULL);
    pthread_cond_init(&h->idle, NULL);
    h->reasm = proto_hid_reasm_new(0);
    if (!h->reasm) {
        hid_tr_close(&h->base);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    h->h = hid_open_path(addr->path);
    if (!h->h) {
        const wchar_t *why = hid_error(NULL);
        char msg[200];
        ascii_of(why, msg, sizeof msg);
        hid_tr_close(&h->base);
        return geo_err_set(err, -ENODEV, "%s: %s", addr->path,
                           msg[0] ? msg : "cannot open");
    }
    if (serial_cap) {
        wchar_t w[PROTO_FSP_TEXT_MAX + 1];
        serial[0] = '\0';
        if (hid_get_serial_number_string(h->h, w, PROTO_FSP_TEXT_MAX + 1) == 0)
            ascii_of(w, serial, serial_cap);
    }
    *ret = &h->base;
    return 0;
}

static int hid_tr_write(scan_transport *t, const uint8_t *frame, size_t len,
                        int timeout_ms)
{
    (void)timeout_ms;
    hid_transport *h = (hid_transport *)t;
    if (atomic_load(&h->canceled))
        return -ECANCELED;
    if (atomic_load(&h->gone))
        return -ENODEV;
    uint8_t rep[PROTO_HID_REPORT_SIZE];
    size_t count = proto_hid_report_count(len);
    int r = 0;
    atomic_fetch_add(&h->want, 1);
    pthread_mutex_lock(&h->io);
    atomic_fetch_sub(&h->want, 1);
    pthread_cond_broadcast(&h->idle);
    for (size_t k = 0; k < count && r == 0; k++) {
        proto_hid_fragment(frame, len, k, rep);
        int n = hid_write(h->h, rep, sizeof rep);
        if (n != (int)sizeof rep) {
            /* hidraw fails a write to an unplugged device; any other
             * failure has left half a frame on the wire either way */
            atomic_store(&h->gone, true);
            r = -ENODEV;
        }
    }
    pthread_mutex_unlock(&h->io);
    return r;
}

static ssize_t hid_tr_read(scan_transport *t, uint8_t *buf, size_t cap,
                           int timeout_ms)
{
    hid_transport *h = (hid_transport *)t;
    uint64_t deadline = timeout_ms < 0 ? UINT64_MAX
                                       : mono_ms() + (uint64_t)timeout_ms;
    uint8_t rep[PROTO_HID_REPORT_SIZE];
    for (;;) {
        if (atomic_load(&h->canceled))
            return -ECANCELED;
        if (atomic_load(&h->gone))
            return -ENODEV;
        uint64_t now = mono_ms();
        if (now >= deadline && timeout_ms >= 0)
            return -ETIMEDOUT;
        int slice = SLICE_MS;
        if (deadline != UINT64_MAX && deadline - now < (uint64_t)slice)
            slice = (int)(deadline - now);
        pthread_mutex_lock(&h->io);
        while (atomic_load(&h->want) > 0)
            pthread_cond_wait(&h->idle, &h->io);
        int n = hid_read_timeout(h->h, rep, sizeof rep, slice);
        pthread_mutex_unlock(&h->io);
        if (n < 0) {
            atomic_store(&h->gone, true);
            return -ENODEV;
        }
        if (n == 0)
            continue;
        const uint8_t *frame;
        size_t flen;
        proto_hid_status st = proto_hid_reasm_push(h->reasm, rep, (size_t)n,
                                                   &frame, &flen);
        if (st < 0)
            atomic_fetch_add(&h->base.reassembly_failures, 1);
        if ((st == PROTO_HID_FRAME || st == PROTO_HID_E_RESTART) && frame) {
            if (flen > cap) {
                atomic_fetch_add(&h->base.reassembly_failures, 1);
                continue;
            }
            memcpy(buf, frame, flen);
            return (ssize_t)flen;
        }
    }
}

static void hid_tr_cancel(scan_transport *t)
{
    atomic_store(&((hid_transport *)t)->canceled, true);
}

const scan_transport_ops scan_hidapi_ops = {
    .name = "hid",
    .open = hid_tr_open,
    .write = hid_tr_write,
    .read = hid_tr_read,
    .cancel = hid_tr_cancel,
    .close = hid_tr_close,
};
