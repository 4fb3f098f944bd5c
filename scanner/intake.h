/* intake.h — what scanner.c (the registry of scanners, one thread per
 * connection, the public API) and discovery.c (the intake thread:
 * hotplug, udev monitor, libusb event handling) share. Internal to
 * libfacetscan.
 *
 * Locking: in->mu guards the lists of connections and known scanners and
 * the retired counters; a connection's smu guards its session and its
 * transport pointer. Lock order: in->mu before smu, never the reverse. */
#ifndef SCAN_INTAKE_H
#define SCAN_INTAKE_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>

#include <libudev.h>
#include <libusb.h>

#include "scanner.h"

typedef struct scan_conn scan_conn;
typedef struct scan_known scan_known;

struct scan_intake {
    scan_match list[SCAN_MATCH_MAX];
    size_t nlist;
    scan_callbacks cb;
    scan_options opt;

    /* discovery.c */
    libusb_context *usb;
    libusb_hotplug_callback_handle hotplug[SCAN_MATCH_MAX];
    size_t nhotplug;
    struct udev *udev;
    struct udev_monitor *mon;
    int wake[2];
    pthread_t thread;
    bool thread_started;
    atomic_bool stop;

    /* scanner.c */
    pthread_mutex_t mu;
    scan_conn *conns;
    scan_known *known;
    scan_metrics retired; /* counters of closed connections */
};

/* A device that matches the list appeared at addr (called by discovery
 * with in->mu not held): unless a connection to addr exists, start one. */
void scan_conn_arrive(scan_intake *in, const scan_devaddr *addr);

/* The device at addr left: its connection stops and closes. */
void scan_conn_leave(scan_intake *in, const scan_devaddr *addr);

/* Joins and frees connections whose threads have ended. */
void scan_conn_reap(scan_intake *in);

/* Asks the intake thread to look at its wake pipe (thread-safe). */
void scan_intake_wake(scan_intake *in);

/* Sets up libusb hotplug and the hidraw monitor, finds the devices
 * already present and starts the intake thread. 0 or a negative errno
 * with err set; the caller then stops and releases as on shutdown. */
int scan_discovery_start(scan_intake *in, geo_err *err);

/* Stops the intake thread and releases what discovery set up; the
 * connections must have been stopped before the libusb context goes. */
void scan_discovery_stop_thread(scan_intake *in);
void scan_discovery_release(scan_intake *in);

#endif
