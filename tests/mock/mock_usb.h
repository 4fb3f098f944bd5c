/* mock_usb.h — mocked FSP/1 scanners on a umockdev testbed, for the tests
 * (not part of libfacetscan). A program started with the testbed's
 * environment and LD_PRELOAD=libumockdev-preload.so.0 finds the devices
 * through unmodified libusb, hidapi and libudev:
 * - bulk: a usb_device with a vendor interface (bulk OUT 0x01 / IN 0x81)
 *   whose usbdevfs ioctls (SUBMITURB, REAPURBNDELAY, DISCARDURB, claims,
 *   control transfers for the string descriptors) are answered here;
 * - HID: usb_device → usb_interface → hid (HID_ID, HID_UNIQ, report
 *   descriptor) → hidrawN, whose reads and writes are served one whole
 *   64-byte report at a time.
 * Each device plays the device side of FSP/1 (mock_fspdev.h).
 *
 * Threads: umockdev answers the clients on its own worker thread; every
 * function here may be called from any thread (each device has a mutex). */
#ifndef SCAN_MOCK_USB_H
#define SCAN_MOCK_USB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mock_fspdev.h"
#include "transport.h"

typedef struct mock_bed mock_bed;
typedef struct mock_dev mock_dev;

/* Receives one line per device event (serial, then the engine's text). */
typedef void (*mock_event_fn)(void *user, const char *serial,
                              const char *line);

/* A testbed with one USB bus (root hub 1-0). Sets UMOCKDEV_DIR in the
 * environment. NULL with a message in err on failure. */
mock_bed *mock_bed_new(mock_event_fn on_event, void *user, char *err,
                       size_t err_cap);

/* Unplugs every device, frees the testbed and its temporary directory.
 * NULL accepted; returns NULL. */
mock_bed *mock_bed_free(mock_bed *b);

/* The testbed's root directory (UMOCKDEV_DIR). */
const char *mock_bed_root(const mock_bed *b);

/* Plugs in a scanner. NULL with err set when the serial is invalid or
 * already plugged in, or the testbed refuses. */
mock_dev *mock_bed_plug(mock_bed *b, scan_kind kind, uint16_t vid,
                        uint16_t pid, const char *serial, char *err,
                        size_t err_cap);

/* The plugged-in device with this serial, or NULL. */
mock_dev *mock_bed_find(mock_bed *b, const char *serial);

/* Unplugs d (pending transfers fail with ENODEV, the hidraw node hangs
 * up, "remove" uevents go out). d stays valid until mock_bed_free. */
void mock_dev_unplug(mock_dev *d);

/* Runs fn on d's engine with d locked, then sends what it queued. */
void mock_dev_with(mock_dev *d, void (*fn)(mock_fspdev *e, void *arg),
                   void *arg);

/* The node clients open ("/dev/bus/usb/001/002", "/dev/hidraw0"). */
const char *mock_dev_node(const mock_dev *d);

/* Runs every device's timers; returns the next deadline (ms, CLOCK_
 * MONOTONIC; UINT64_MAX: none). Also unplugs devices whose engine asked
 * for it. */
uint64_t mock_bed_tick(mock_bed *b);

/* Calls fn for every device plugged in now. */
void mock_bed_foreach(mock_bed *b, void (*fn)(mock_dev *d, void *arg),
                      void *arg);

/* The engine's status JSON for d (malloc'd), with "kind" and "node". */
char *mock_dev_status_json(mock_dev *d);

/* Milliseconds of CLOCK_MONOTONIC. */
uint64_t mock_now_ms(void);

#endif
