/* discovery.c — finding scanners: libusb hotplug callbacks for bulk
 * devices, a libudev monitor for hidraw devices, an enumeration of both at
 * start-up, and the intake thread that drives them.
 *
 * The intake thread sleeps in one poll() on libusb's file descriptors (so
 * it is also the thread that runs every libusb transfer callback), the
 * udev monitor's socket and a wake pipe. libusb tells it through the
 * pollfd notifiers when a newly opened device adds a descriptor, and the
 * connection threads through the wake pipe when they end. Nothing here
 * polls on a timer: poll() sleeps until an event or libusb's next timeout. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <hidapi.h>

#include "intake.h"

void scan_intake_wake(scan_intake *in)
{
    char c = 1;
    ssize_t r = write(in->wake[1], &c, 1);
    (void)r; /* a full pipe already holds a wake-up */
}

static int LIBUSB_CALL hotplug_cb(libusb_context *ctx, libusb_device *dev,
                                  libusb_hotplug_event event, void *user)
{
    (void)ctx;
    scan_intake *in = user;
    struct libusb_device_descriptor dd;
    if (libusb_get_device_descriptor(dev, &dd) != 0)
        return 0;
    scan_devaddr a = {.kind = SCAN_KIND_BULK,
                      .vid = dd.idVendor,
                      .pid = dd.idProduct,
                      .bus = libusb_get_bus_number(dev),
                      .address = libusb_get_device_address(dev)};
    snprintf(a.path, sizeof a.path, "usb:%03u/%03u", a.bus, a.address);
    if (!scan_match_find(in->list, in->nlist, a.vid, a.pid, SCAN_KIND_BULK))
        return 0;
    if (event == LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED)
        scan_conn_arrive(in, &a);
    else
        scan_conn_leave(in, &a);
    return 0;
}

static void LIBUSB_CALL pollfd_added(int fd, short events, void *user)
{
    (void)fd;
    (void)events;
    scan_intake_wake(user);
}

static void LIBUSB_CALL pollfd_removed(int fd, void *user)
{
    (void)fd;
    scan_intake_wake(user);
}

/* Fills a from a hidraw udev device whose HID parent matches the list. */
static bool hidraw_addr(scan_intake *in, struct udev_device *d,
                        scan_devaddr *a)
{
    const char *node = udev_device_get_devnode(d);
    if (!node || strlen(node) >= sizeof a->path)
        return false;
    memset(a, 0, sizeof *a);
    a->kind = SCAN_KIND_HID;
    snprintf(a->path, sizeof a->path, "%s", node);
    struct udev_device *hid =
        udev_device_get_parent_with_subsystem_devtype(d, "hid", NULL);
    const char *id = hid ? udev_device_get_property_value(hid, "HID_ID")
                         : NULL;
    unsigned bus, vid, pid;
    if (!id || sscanf(id, "%x:%x:%x", &bus, &vid, &pid) != 3 ||
        bus != 3 /* BUS_USB */ || vid > 0xffff || pid > 0xffff)
        return false;
    a->vid = (uint16_t)vid;
    a->pid = (uint16_t)pid;
    return scan_match_find(in->list, in->nlist, a->vid, a->pid,
                           SCAN_KIND_HID) != NULL;
}

static void udev_event(scan_intake *in, struct udev_device *d)
{
    const char *action = udev_device_get_action(d);
    scan_devaddr a;
    if (!action || strcmp(action, "add") == 0) {
        if (hidraw_addr(in, d, &a))
            scan_conn_arrive(in, &a);
    } else if (strcmp(action, "remove") == 0) {
        const char *node = udev_device_get_devnode(d);
        if (node && strlen(node) < sizeof a.path) {
            memset(&a, 0, sizeof a);
            a.kind = SCAN_KIND_HID;
            snprintf(a.path, sizeof a.path, "%s", node);
            scan_conn_leave(in, &a);
        }
    }
}

static void enumerate_hidraw(scan_intake *in)
{
    struct udev_enumerate *e = udev_enumerate_new(in->udev);
    if (!e)
        return;
    udev_enumerate_add_match_subsystem(e, "hidraw");
    udev_enumerate_scan_devices(e);
    struct udev_list_entry *it;
    udev_list_entry_foreach(it, udev_enumerate_get_list_entry(e))
    {
        struct udev_device *d =
            udev_device_new_from_syspath(in->udev, udev_list_entry_get_name(it));
        if (d) {
            udev_event(in, d);
            udev_device_unref(d);
        }
    }
    udev_enumerate_unref(e);
}

enum { MAX_FDS = 64 };

static void *intake_main(void *arg)
{
    scan_intake *in = arg;
    struct pollfd fds[MAX_FDS];
    while (!atomic_load(&in->stop)) {
        size_t n = 0;
        fds[n++] = (struct pollfd){.fd = in->wake[0], .events = POLLIN};
        int mon_fd = in->mon ? udev_monitor_get_fd(in->mon) : -1;
        if (mon_fd >= 0)
            fds[n++] = (struct pollfd){.fd = mon_fd, .events = POLLIN};
        size_t usb_first = n;
        int timeout = -1;
        if (in->usb) {
            const struct libusb_pollfd **lp = libusb_get_pollfds(in->usb);
            for (size_t i = 0; lp && lp[i] && n < MAX_FDS; i++)
                fds[n++] = (struct pollfd){.fd = lp[i]->fd,
                                           .events = lp[i]->events};
            libusb_free_pollfds(lp);
            struct timeval tv;
            if (libusb_get_next_timeout(in->usb, &tv) == 1)
                timeout = (int)(tv.tv_sec * 1000 + (tv.tv_usec + 999) / 1000);
        }
        int r = poll(fds, n, timeout);
        if (r < 0 && errno != EINTR)
            break;
        if (fds[0].revents & POLLIN) {
            char buf[64];
            while (read(in->wake[0], buf, sizeof buf) > 0)
                ;
            scan_conn_reap(in);
        }
        if (in->usb) {
            bool usb_ready = r == 0;
            for (size_t i = usb_first; i < n; i++)
                usb_ready |= fds[i].revents != 0;
            if (usb_ready) {
                struct timeval zero = {0, 0};
                libusb_handle_events_timeout_completed(in->usb, &zero, NULL);
            }
        }
        if (mon_fd >= 0 && (fds[1].revents & POLLIN)) {
            struct udev_device *d;
            while ((d = udev_monitor_receive_device(in->mon)) != NULL) {
                udev_event(in, d);
                udev_device_unref(d);
            }
        }
    }
    return NULL;
}

void scan_discovery_release(scan_intake *in)
{
    for (size_t i = 0; i < in->nhotplug; i++)
        libusb_hotplug_deregister_callback(in->usb, in->hotplug[i]);
    in->nhotplug = 0;
    if (in->usb) {
        libusb_set_pollfd_notifiers(in->usb, NULL, NULL, NULL);
        libusb_exit(in->usb);
        in->usb = NULL;
    }
    if (in->mon)
        in->mon = udev_monitor_unref(in->mon);
    if (in->udev)
        in->udev = udev_unref(in->udev);
    for (int i = 0; i < 2; i++) {
        if (in->wake[i] >= 0)
            close(in->wake[i]);
        in->wake[i] = -1;
    }
}

void scan_discovery_stop_thread(scan_intake *in)
{
    atomic_store(&in->stop, true);
    if (in->thread_started) {
        scan_intake_wake(in);
        pthread_join(in->thread, NULL);
        in->thread_started = false;
    }
}

int scan_discovery_start(scan_intake *in, geo_err *err)
{
    in->wake[0] = in->wake[1] = -1;
    if (pipe2(in->wake, O_CLOEXEC | O_NONBLOCK) < 0)
        return geo_err_set(err, -errno, "wake pipe: %s", strerror(errno));
    bool bulk = false, hid = false;
    for (size_t i = 0; i < in->nlist; i++) {
        bulk |= in->list[i].kind == SCAN_KIND_BULK;
        hid |= in->list[i].kind == SCAN_KIND_HID;
    }
    int r = 0;
    if (bulk) {
        r = libusb_init(&in->usb);
        if (r < 0) {
            in->usb = NULL;
            return geo_err_set(err, -EIO, "libusb: %s", libusb_strerror(r));
        }
        if (!libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG))
            return geo_err_set(err, -ENOTSUP, "libusb: no hotplug support");
        libusb_set_pollfd_notifiers(in->usb, pollfd_added, pollfd_removed,
                                    in);
    }
    if (hid) {
        /* hid_init is not thread-safe: run it before any connection */
        if (hid_init() != 0)
            return geo_err_set(err, -EIO, "hidapi: cannot initialise");
        in->udev = udev_new();
        in->mon = in->udev ? udev_monitor_new_from_netlink(in->udev, "udev")
                           : NULL;
        if (!in->mon ||
            udev_monitor_filter_add_match_subsystem_devtype(in->mon, "hidraw",
                                                            NULL) < 0 ||
            udev_monitor_enable_receiving(in->mon) < 0)
            return geo_err_set(err, -EIO,
                               "udev: cannot monitor hidraw devices");
        int fd = udev_monitor_get_fd(in->mon);
        fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) | O_NONBLOCK);
    }
    /* the monitor listens before the enumeration, so a device plugged in
     * between the two is seen at least once (duplicates are ignored); the
     * enumeration runs before the intake thread uses the udev context */
    if (hid)
        enumerate_hidraw(in);
    /* the intake thread must handle libusb events before the hotplug
     * enumeration starts connections that wait for transfers */
    r = pthread_create(&in->thread, NULL, intake_main, in);
    if (r != 0)
        return geo_err_set(err, -r, "intake thread: %s", strerror(r));
    in->thread_started = true;
    for (size_t i = 0; bulk && i < in->nlist; i++) {
        if (in->list[i].kind != SCAN_KIND_BULK)
            continue;
        r = libusb_hotplug_register_callback(
            in->usb,
            LIBUSB_HOTPLUG_EVENT_DEVICE_ARRIVED |
                LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT,
            LIBUSB_HOTPLUG_ENUMERATE, in->list[i].vid, in->list[i].pid,
            LIBUSB_HOTPLUG_MATCH_ANY, hotplug_cb, in,
            &in->hotplug[in->nhotplug]);
        if (r < 0)
            return geo_err_set(err, -EIO, "libusb hotplug: %s",
                               libusb_strerror(r));
        in->nhotplug++;
    }
    return 0;
}
