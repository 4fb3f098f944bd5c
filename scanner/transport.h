/* transport.h — the one small interface through which the scan session
 * talks to a scanner, whatever carries the bytes: libusb bulk endpoints
 * (usb_libusb.c), HID reports through hidraw (usb_hidapi.c), or memory in
 * the unit tests. The session above it is the same for all of them.
 *
 * The contract every implementation keeps:
 * - write sends exactly one whole FSP/1 frame, in order with every other
 *   write (HID never interleaves the fragments of two frames);
 * - read returns bytes of the device's frame stream (bulk: any split of
 *   it; HID: whole reassembled frames, so a failed reassembly loses only
 *   that frame and is counted in reassembly_failures);
 * - read and write block for at most timeout_ms (timeout_ms < 0: no
 *   limit) and return -ECANCELED promptly once cancel was called;
 * - errors: -ETIMEDOUT (nothing within the timeout), -ECANCELED,
 *   -ENODEV (the device is gone: every later call fails the same way),
 *   -EIO (any other transfer failure), -ENOMEM;
 * - one thread may read while another writes; two concurrent writers or
 *   two concurrent readers are not allowed; cancel may be called from any
 *   thread at any time before close.
 */
#ifndef SCAN_TRANSPORT_H
#define SCAN_TRANSPORT_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

#include "ctx.h"

typedef enum scan_kind {
    SCAN_KIND_BULK = 0, /* vendor interface 0xFF, bulk OUT 0x01 / IN 0x81 */
    SCAN_KIND_HID = 1,  /* hidraw, 64-byte reports with report id 1 */
} scan_kind;

/* Where a matched device is: USB bus and address for bulk devices, the
 * hidraw node for HID devices. */
typedef struct scan_devaddr {
    scan_kind kind;
    uint16_t vid, pid;
    uint8_t bus, address;   /* bulk */
    char path[64];          /* HID: "/dev/hidraw0" */
} scan_devaddr;

typedef struct scan_transport scan_transport;

typedef struct scan_transport_ops {
    const char *name; /* "bulk", "hid", "mem" */
    /* Opens the device at addr. backend is the implementation's shared
     * state (usb_libusb.c: its scan_usb_backend; hidapi: NULL). On
     * success stores a new transport in *ret (freed by close) and, when
     * the device has one, its USB serial string in serial[0 .. cap).
     * Errors: -ENODEV (gone), -EBUSY (claimed elsewhere), -EIO, -ENOMEM,
     * each with a message in err. */
    int (*open)(void *backend, const scan_devaddr *addr, scan_transport **ret,
                char *serial, size_t serial_cap, geo_err *err);
    int (*write)(scan_transport *t, const uint8_t *frame, size_t len,
                 int timeout_ms);
    /* Returns the number of bytes stored in buf[0 .. cap) (at least 1),
     * or a negative errno as above. cap must be at least 65,552 bytes for
     * the HID transport (one whole frame). */
    ssize_t (*read)(scan_transport *t, uint8_t *buf, size_t cap,
                    int timeout_ms);
    void (*cancel)(scan_transport *t);
    /* Cancels, waits for outstanding transfers, releases the device and
     * frees t. */
    void (*close)(scan_transport *t);
} scan_transport_ops;

/* The part every transport shares; implementations embed it first. */
struct scan_transport {
    const scan_transport_ops *ops;
    /* HID reports dropped by the reassembler (proto/hid_frag.h errors) */
    atomic_uint_fast64_t reassembly_failures;
};

/* The implementations. */
extern const scan_transport_ops scan_libusb_ops;
extern const scan_transport_ops scan_hidapi_ops;

#endif
