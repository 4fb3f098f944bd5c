/* usb_libusb.c — the bulk transport: FSP/1 over the bulk endpoints of a
 * vendor-specific interface (class 0xFF, OUT 0x01, IN 0x81), with
 * asynchronous libusb transfers.
 *
 * Event handling: this file never calls libusb_handle_events itself.
 * Another thread (the intake thread, discovery.c) handles the events of
 * the libusb context passed to open; transfer callbacks run there and
 * wake the reader or writer through a condition variable. No thread
 * polls or spins.
 *
 * Invariants: one IN transfer is in flight whenever the receive buffer
 * has room for a whole transfer and the device is neither gone nor
 * failed, so the device can always send; rx[0 .. rx_len) are bytes
 * received and not read yet. in_busy / out_busy / ctl_busy are true
 * exactly while the transfer is submitted (between submit and callback),
 * and close waits for all three to clear before freeing anything. */
#include <errno.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <libusb.h>

#include "transport.h"

enum {
    EP_OUT = 0x01,
    EP_IN = 0x81,
    IN_SIZE = 65536,          /* one IN transfer */
    RX_CAP = 4 * IN_SIZE,     /* bytes buffered for the reader */
    CTL_TIMEOUT_MS = 1000,
};

typedef struct usb_transport {
    scan_transport base;
    libusb_device_handle *h;
    int iface;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    struct libusb_transfer *in, *out, *ctl;
    bool in_busy, out_busy, ctl_busy;
    int out_status, ctl_status;
    bool gone, failed, canceled;
    uint8_t *rx;
    size_t rx_len;
} usb_transport;

static uint64_t mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

/* Waits on cv until deadline (ms of CLOCK_MONOTONIC; UINT64_MAX: none).
 * Returns false when the deadline passed. */
static bool wait_until(usb_transport *u, uint64_t deadline)
{
    if (deadline == UINT64_MAX) {
        pthread_cond_wait(&u->cv, &u->mu);
        return true;
    }
    uint64_t now = mono_ms();
    if (now >= deadline)
        return false;
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    uint64_t ns = (uint64_t)ts.tv_nsec + (deadline - now) * 1000000u;
    ts.tv_sec += (time_t)(ns / 1000000000u);
    ts.tv_nsec = (long)(ns % 1000000000u);
    pthread_cond_timedwait(&u->cv, &u->mu, &ts);
    return true;
}

static uint64_t deadline_of(int timeout_ms)
{
    return timeout_ms < 0 ? UINT64_MAX : mono_ms() + (uint64_t)timeout_ms;
}

static int map_status(enum libusb_transfer_status st)
{
    switch (st) {
    case LIBUSB_TRANSFER_COMPLETED: return 0;
    case LIBUSB_TRANSFER_NO_DEVICE: return -ENODEV;
    case LIBUSB_TRANSFER_TIMED_OUT: return -ETIMEDOUT;
    case LIBUSB_TRANSFER_CANCELLED: return -ECANCELED;
    default: return -EIO;
    }
}

static int map_error(int e)
{
    switch (e) {
    case LIBUSB_ERROR_NO_DEVICE: return -ENODEV;
    case LIBUSB_ERROR_NOT_FOUND: return -ENODEV;
    case LIBUSB_ERROR_BUSY: return -EBUSY;
    case LIBUSB_ERROR_ACCESS: return -EACCES;
    case LIBUSB_ERROR_NO_MEM: return -ENOMEM;
    case LIBUSB_ERROR_TIMEOUT: return -ETIMEDOUT;
    default: return -EIO;
    }
}

/* Called with mu held. */
static void submit_in(usb_transport *u)
{
    if (u->in_busy || u->gone || u->failed || u->canceled ||
        RX_CAP - u->rx_len < IN_SIZE)
        return;
    int r = libusb_submit_transfer(u->in);
    if (r == 0)
        u->in_busy = true;
    else if (r == LIBUSB_ERROR_NO_DEVICE)
        u->gone = true;
    else
        u->failed = true;
}

static void LIBUSB_CALL in_cb(struct libusb_transfer *t)
{
    usb_transport *u = t->user_data;
    pthread_mutex_lock(&u->mu);
    u->in_busy = false;
    switch (t->status) {
    case LIBUSB_TRANSFER_COMPLETED:
        memcpy(u->rx + u->rx_len, t->buffer, (size_t)t->actual_length);
        u->rx_len += (size_t)t->actual_length;
        submit_in(u);
        break;
    case LIBUSB_TRANSFER_NO_DEVICE:
        u->gone = true;
        break;
    case LIBUSB_TRANSFER_CANCELLED:
        break;
    default:
        u->failed = true;
        break;
    }
    pthread_cond_broadcast(&u->cv);
    pthread_mutex_unlock(&u->mu);
}

static void LIBUSB_CALL out_cb(struct libusb_transfer *t)
{
    usb_transport *u = t->user_data;
    pthread_mutex_lock(&u->mu);
    u->out_busy = false;
    u->out_status = map_status(t->status);
    if (u->out_status == 0 && t->actual_length != t->length)
        u->out_status = -EIO;
    if (u->out_status == -ENODEV)
        u->gone = true;
    pthread_cond_broadcast(&u->cv);
    pthread_mutex_unlock(&u->mu);
}

static void LIBUSB_CALL ctl_cb(struct libusb_transfer *t)
{
    usb_transport *u = t->user_data;
    pthread_mutex_lock(&u->mu);
    u->ctl_busy = false;
    u->ctl_status = map_status(t->status);
    pthread_cond_broadcast(&u->cv);
    pthread_mutex_unlock(&u->mu);
}

/* Waits (mu held) until *busy clears; on the deadline cancels the
 * transfer and still waits for its callback, so that the buffer is never
 * freed under libusb. Returns false when it had to cancel. */
static bool wait_transfer(usb_transport *u, struct libusb_transfer *t,
                          bool *busy, uint64_t deadline)
{
    bool in_time = true;
    while (*busy) {
        if (u->canceled || !wait_until(u, deadline)) {
            in_time = false;
            libusb_cancel_transfer(t);
            while (*busy)
                pthread_cond_wait(&u->cv, &u->mu);
        }
    }
    return in_time;
}

/* A GET_DESCRIPTOR(STRING) through the control endpoint; returns the
 * number of bytes received or a negative errno. Called with mu held. */
static int get_string_desc(usb_transport *u, uint8_t index, uint16_t langid,
                           uint8_t *out, size_t cap)
{
    uint8_t *buf = u->ctl->buffer;
    size_t len = cap < 255 ? cap : 255;
    libusb_fill_control_setup(buf, LIBUSB_ENDPOINT_IN,
                              LIBUSB_REQUEST_GET_DESCRIPTOR,
                              (uint16_t)(LIBUSB_DT_STRING << 8 | index),
                              langid, (uint16_t)len);
    libusb_fill_control_transfer(u->ctl, u->h, buf, ctl_cb, u,
                                 CTL_TIMEOUT_MS);
    int r = libusb_submit_transfer(u->ctl);
    if (r < 0)
        return map_error(r);
    u->ctl_busy = true;
    if (!wait_transfer(u, u->ctl, &u->ctl_busy,
                       mono_ms() + CTL_TIMEOUT_MS + 500))
        return -ETIMEDOUT;
    if (u->ctl_status < 0)
        return u->ctl_status;
    int n = u->ctl->actual_length;
    memcpy(out, libusb_control_transfer_get_data(u->ctl), (size_t)n);
    return n;
}

/* The USB serial string as ASCII ('?' for other characters), "" when the
 * device has none. */
static int read_serial(usb_transport *u, uint8_t index, char *serial,
                       size_t cap)
{
    if (cap == 0)
        return 0;
    serial[0] = '\0';
    if (index == 0)
        return 0;
    uint8_t d[255];
    pthread_mutex_lock(&u->mu);
    int n = get_string_desc(u, 0, 0, d, sizeof d);
    uint16_t lang = n >= 4 ? (uint16_t)(d[2] | d[3] << 8) : 0x0409;
    if (n >= 0)
        n = get_string_desc(u, index, lang, d, sizeof d);
    pthread_mutex_unlock(&u->mu);
    if (n < 0)
        return n;
    if (n < 2 || d[1] != LIBUSB_DT_STRING)
        return -EIO;
    size_t k = 0;
    for (int i = 2; i + 1 < n && d[0] > i && k + 1 < cap; i += 2) {
        uint16_t c = (uint16_t)(d[i] | d[i + 1] << 8);
        serial[k++] = (c >= 0x20 && c < 0x7f) ? (char)c : '?';
    }
    serial[k] = '\0';
    return 0;
}

/* The number of the vendor-specific interface with bulk endpoints 0x01
 * (OUT) and 0x81 (IN), or a negative errno. */
static int find_interface(libusb_device *dev)
{
    struct libusb_config_descriptor *cfg;
    if (libusb_get_active_config_descriptor(dev, &cfg) != 0 &&
        libusb_get_config_descriptor(dev, 0, &cfg) != 0)
        return -EIO;
    int found = -ENOENT;
    for (int i = 0; i < cfg->bNumInterfaces && found < 0; i++) {
        const struct libusb_interface *it = &cfg->interface[i];
        for (int a = 0; a < it->num_altsetting && found < 0; a++) {
            const struct libusb_interface_descriptor *d = &it->altsetting[a];
            if (d->bInterfaceClass != LIBUSB_CLASS_VENDOR_SPEC)
                continue;
            bool in = false, out = false;
            for (int e = 0; e < d->bNumEndpoints; e++) {
                const struct libusb_endpoint_descriptor *ep = &d->endpoint[e];
                if ((ep->bmAttributes & 3) != LIBUSB_TRANSFER_TYPE_BULK)
                    continue;
                in |= ep->bEndpointAddress == EP_IN;
                out |= ep->bEndpointAddress == EP_OUT;
            }
            if (in && out)
                found = d->bInterfaceNumber;
        }
    }
    libusb_free_config_descriptor(cfg);
    return found;
}

static void usb_free(usb_transport *u)
{
    libusb_free_transfer(u->in);
    libusb_free_transfer(u->out);
    if (u->ctl)
        free(u->ctl->buffer);
    libusb_free_transfer(u->ctl);
    pthread_cond_destroy(&u->cv);
    pthread_mutex_destroy(&u->mu);
    free(u->rx);
    free(u);
}

static void usb_close(scan_transport *t)
{
    usb_transport *u = (usb_transport *)t;
    pthread_mutex_lock(&u->mu);
    u->canceled = true;
    if (u->in_busy)
        libusb_cancel_transfer(u->in);
    if (u->out_busy)
        libusb_cancel_transfer(u->out);
    if (u->ctl_busy)
        libusb_cancel_transfer(u->ctl);
    while (u->in_busy || u->out_busy || u->ctl_busy)
        pthread_cond_wait(&u->cv, &u->mu);
    pthread_mutex_unlock(&u->mu);
    if (u->iface >= 0)
        libusb_release_interface(u->h, u->iface);
    libusb_close(u->h);
    free(u->in->buffer);
    usb_free(u);
}

static int usb_open(void *backend, const scan_devaddr *addr,
                    scan_transport **ret, char *serial, size_t serial_cap,
                    geo_err *err)
{
    libusb_context *ctx = backend;
    libusb_device **list;
    ssize_t n = libusb_get_device_list(ctx, &list);
    if (n < 0)
        return geo_err_set(err, map_error((int)n), "usb:%03u/%03u: %s",
                           addr->bus, addr->address,
                           libusb_strerror((int)n));
    libusb_device *dev = NULL;
    for (ssize_t i = 0; i < n && !dev; i++)
        if (libusb_get_bus_number(list[i]) == addr->bus &&
            libusb_get_device_address(list[i]) == addr->address)
            dev = libusb_ref_device(list[i]);
    libusb_free_device_list(list, 1);
    if (!dev)
        return geo_err_set(err, -ENODEV, "usb:%03u/%03u: no such device",
                           addr->bus, addr->address);

    int r = 0;
    usb_transport *u = calloc(1, sizeof *u);
    if (!u) {
        libusb_unref_device(dev);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    u->base.ops = &scan_libusb_ops;
    u->iface = -1;
    pthread_mutex_init(&u->mu, NULL);
    pthread_condattr_t ca;
    pthread_condattr_init(&ca);
    pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    pthread_cond_init(&u->cv, &ca);
    pthread_condattr_destroy(&ca);
    u->rx = malloc(RX_CAP);
    u->in = libusb_alloc_transfer(0);
    u->out = libusb_alloc_transfer(0);
    u->ctl = libusb_alloc_transfer(0);
    uint8_t *inbuf = malloc(IN_SIZE);
    uint8_t *ctlbuf = malloc(LIBUSB_CONTROL_SETUP_SIZE + 255);
    if (!u->rx || !u->in || !u->out || !u->ctl || !inbuf || !ctlbuf) {
        free(inbuf);
        free(ctlbuf);
        usb_free(u);
        libusb_unref_device(dev);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    u->ctl->buffer = ctlbuf;

    struct libusb_device_descriptor dd;
    libusb_get_device_descriptor(dev, &dd);
    int iface = find_interface(dev);
    if (iface < 0) {
        r = geo_err_set(err, -ENODEV,
                        "usb:%03u/%03u: no vendor interface with bulk "
                        "endpoints 0x01/0x81", addr->bus, addr->address);
        goto fail;
    }
    r = libusb_open(dev, &u->h);
    if (r < 0) {
        r = geo_err_set(err, map_error(r), "usb:%03u/%03u: open: %s",
                        addr->bus, addr->address, libusb_strerror(r));
        goto fail;
    }
    r = libusb_claim_interface(u->h, iface);
    if (r < 0) {
        r = geo_err_set(err, map_error(r),
                        "usb:%03u/%03u: claim interface %d: %s", addr->bus,
                        addr->address, iface, libusb_strerror(r));
        goto fail;
    }
    u->iface = iface;
    r = read_serial(u, dd.iSerialNumber, serial, serial_cap);
    if (r < 0) {
        r = geo_err_set(err, r, "usb:%03u/%03u: serial string: error %d",
                        addr->bus, addr->address, r);
        goto fail;
    }
    libusb_fill_bulk_transfer(u->in, u->h, EP_IN, inbuf, IN_SIZE, in_cb, u, 0);
    inbuf = NULL;
    libusb_fill_bulk_transfer(u->out, u->h, EP_OUT, NULL, 0, out_cb, u, 0);
    pthread_mutex_lock(&u->mu);
    submit_in(u);
    r = u->gone ? -ENODEV : u->failed ? -EIO : 0;
    pthread_mutex_unlock(&u->mu);
    if (r < 0) {
        geo_err_set(err, r, "usb:%03u/%03u: cannot submit a bulk IN transfer",
                    addr->bus, addr->address);
        goto fail;
    }
    libusb_unref_device(dev);
    *ret = &u->base;
    return 0;

fail:
    free(inbuf);
    if (u->h) {
        if (u->iface >= 0)
            libusb_release_interface(u->h, u->iface);
        libusb_close(u->h);
    }
    if (u->in->buffer)
        free(u->in->buffer);
    usb_free(u);
    libusb_unref_device(dev);
    return r;
}

static int usb_write(scan_transport *t, const uint8_t *frame, size_t len,
                     int timeout_ms)
{
    usb_transport *u = (usb_transport *)t;
    uint8_t *copy = malloc(len);
    if (!copy)
        return -ENOMEM;
    memcpy(copy, frame, len);
    pthread_mutex_lock(&u->mu);
    int r;
    if (u->canceled)
        r = -ECANCELED;
    else if (u->gone)
        r = -ENODEV;
    else if (u->out_busy)
        r = -EBUSY;
    else
        r = 0;
    if (r == 0) {
        u->out->buffer = copy;
        u->out->length = (int)len;
        r = libusb_submit_transfer(u->out);
        if (r < 0) {
            r = map_error(r);
        } else {
            u->out_busy = true;
            if (!wait_transfer(u, u->out, &u->out_busy,
                               deadline_of(timeout_ms)))
                r = u->canceled ? -ECANCELED : -ETIMEDOUT;
            else
                r = u->out_status;
        }
        u->out->buffer = NULL;
    }
    pthread_mutex_unlock(&u->mu);
    free(copy);
    return r;
}

static ssize_t usb_read(scan_transport *t, uint8_t *buf, size_t cap,
                        int timeout_ms)
{
    usb_transport *u = (usb_transport *)t;
    uint64_t deadline = deadline_of(timeout_ms);
    pthread_mutex_lock(&u->mu);
    ssize_t r;
    for (;;) {
        if (u->canceled) {
            r = -ECANCELED;
            break;
        }
        if (u->rx_len > 0) {
            size_t n = u->rx_len < cap ? u->rx_len : cap;
            memcpy(buf, u->rx, n);
            memmove(u->rx, u->rx + n, u->rx_len - n);
            u->rx_len -= n;
            submit_in(u);
            r = (ssize_t)n;
            break;
        }
        if (u->gone) {
            r = -ENODEV;
            break;
        }
        if (u->failed) {
            r = -EIO;
            break;
        }
        if (!wait_until(u, deadline)) {
            r = -ETIMEDOUT;
            break;
        }
    }
    pthread_mutex_unlock(&u->mu);
    return r;
}

static void usb_cancel(scan_transport *t)
{
    usb_transport *u = (usb_transport *)t;
    pthread_mutex_lock(&u->mu);
    u->canceled = true;
    pthread_cond_broadcast(&u->cv);
    pthread_mutex_unlock(&u->mu);
}

const scan_transport_ops scan_libusb_ops = {
    .name = "bulk",
    .open = usb_open,
    .write = usb_write,
    .read = usb_read,
    .cancel = usb_cancel,
    .close = usb_close,
};
