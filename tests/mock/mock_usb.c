/* mock_usb.c — mocked scanners on a umockdev testbed: sysfs devices,
 * usbdevfs URB handling for bulk devices and report-at-a-time hidraw for
 * HID devices (see mock_usb.h; the measured facts behind these choices
 * are in the project's USB mocking notes).
 *
 * Bulk invariants:
 * - each client (an open file of the device node) has its own lists of
 *   pending IN URBs and of completed URBs waiting to be reaped, as the
 *   kernel keeps them per file;
 * - the device node is a FIFO with a one-page buffer that is full (not
 *   writable) exactly when no client has a URB to reap: libusb polls the
 *   node for POLLOUT, so it sleeps until a URB completes instead of
 *   spinning on REAPURBNDELAY;
 * - every IN URB completes as soon as device bytes exist (a short
 *   transfer), so the host sees one continuous byte stream.
 * HID invariants:
 * - reports from the device wait in a queue; the pty behind the hidraw
 *   node holds one byte exactly while that queue is non-empty, which
 *   makes poll() report readability; a read() is answered with one whole
 *   report through umockdev (the pty would merge and split reports), and
 *   the read that empties the queue consumes the pty's byte;
 * - a write() is one whole report, reassembled into host frames here;
 * - unplugging closes the pty, so the client's poll() reports POLLHUP.
 * All state of a device is guarded by its mutex; umockdev's worker thread
 * and the harness's thread both take it. */
#include "mock_usb.h"

#include <errno.h>
#include <fcntl.h>
#include <linux/hidraw.h>
#include <linux/usbdevice_fs.h>
#include <pthread.h>
#include <pty.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include <umockdev.h>

#include "hid_frag.h"

enum { BUS = 1, EP_OUT = 0x01, EP_IN = 0x81 };

typedef struct urb_rec {
    struct urb_rec *next;
    UMockdevIoctlData *urb; /* owned reference */
    UMockdevIoctlData *buf; /* owned reference, NULL for no buffer */
    unsigned long addr;     /* the URB's address in the client */
    uint8_t type, ep;
    int len, status, actual;
} urb_rec;

typedef struct urb_list {
    urb_rec *head, *tail;
} urb_list;

typedef struct client_st {
    struct client_st *next;
    mock_dev *dev;
    UMockdevIoctlClient *client; /* owned reference */
    urb_list pending; /* IN URBs waiting for device bytes */
    urb_list done;    /* completed, waiting to be reaped */
    unsigned claimed; /* interface bit mask */
} client_st;

typedef struct hid_read {
    struct hid_read *next;
    UMockdevIoctlClient *client; /* owned reference */
} hid_read;

struct mock_dev {
    mock_dev *next;
    mock_bed *bed;
    scan_kind kind;
    uint16_t vid, pid;
    char serial[PROTO_FSP_TEXT_MAX + 1];
    int devnum;
    char node[64];
    char *sys_usb, *sys_hidraw; /* g_free */
    UMockdevIoctlBase *handler;
    pthread_mutex_t mu;
    mock_fspdev *eng;
    bool gone;
    /* bulk */
    int fifo;
    bool fifo_ready;
    uint8_t *out;
    size_t out_len, out_cap;
    client_st *clients;
    /* HID */
    int ptm, pts;
    proto_hid_reasm *reasm;
    uint8_t (*reports)[PROTO_HID_REPORT_SIZE];
    size_t rep_head, rep_n, rep_cap;
    bool ready_byte;
    hid_read *reads;
};

struct mock_bed {
    UMockdevTestbed *tb;
    char *root; /* g_free */
    char *hub;  /* g_free */
    pthread_mutex_t mu;
    mock_dev *devs;
    int next_devnum, next_hidraw, next_hid;
    mock_event_fn on_event;
    void *user;
};

uint64_t mock_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000u + (uint64_t)ts.tv_nsec / 1000000u;
}

static void dev_event(void *user, const char *line)
{
    mock_dev *d = user;
    if (d->bed->on_event)
        d->bed->on_event(d->bed->user, d->serial, line);
}

/* --- descriptors ----------------------------------------------------------- */

static const uint8_t report_desc[] = {
    0x06, 0x00, 0xff, /* usage page (vendor 0xff00) */
    0x09, 0x01,       /* usage 1 */
    0xa1, 0x01,       /* collection (application) */
    0x85, 0x01,       /*   report id 1 */
    0x09, 0x02,       /*   usage 2 */
    0x15, 0x00,       /*   logical minimum 0 */
    0x26, 0xff, 0x00, /*   logical maximum 255 */
    0x75, 0x08,       /*   report size 8 */
    0x95, 0x3f,       /*   report count 63 */
    0x81, 0x02,       /*   input (data, variable, absolute) */
    0x09, 0x03,       /*   usage 3 */
    0x15, 0x00, 0x26, 0xff, 0x00, 0x75, 0x08, 0x95, 0x3f,
    0x91, 0x02,       /*   output (data, variable, absolute) */
    0xc0,             /* end collection */
};

/* Device + configuration descriptors as sysfs "descriptors" holds them. */
static size_t usb_descriptors(uint8_t *out, scan_kind kind, uint16_t vid,
                              uint16_t pid, bool hub)
{
    uint8_t dev[18] = {18, 1, 0x00, 0x02, hub ? 9 : 0, 0, hub ? 1 : 0, 64,
                       (uint8_t)vid, (uint8_t)(vid >> 8), (uint8_t)pid,
                       (uint8_t)(pid >> 8), 0x00, 0x01, 1, 2, hub ? 0 : 3, 1};
    size_t n = 0;
    memcpy(out, dev, 18);
    n += 18;
    uint8_t *cfg = out + n;
    uint8_t head[9] = {9, 2, 0, 0, 1, 1, 0, 0x80, 50};
    memcpy(out + n, head, 9);
    n += 9;
    if (hub) {
        uint8_t itf[9] = {9, 4, 0, 0, 1, 9, 0, 0, 0};
        uint8_t ep[7] = {7, 5, 0x81, 3, 4, 0, 12};
        memcpy(out + n, itf, 9);
        n += 9;
        memcpy(out + n, ep, 7);
        n += 7;
    } else if (kind == SCAN_KIND_BULK) {
        uint8_t itf[9] = {9, 4, 0, 0, 2, 0xff, 0, 0, 0};
        uint8_t ep_out[7] = {7, 5, EP_OUT, 2, 0x00, 0x02, 0};
        uint8_t ep_in[7] = {7, 5, EP_IN, 2, 0x00, 0x02, 0};
        memcpy(out + n, itf, 9);
        n += 9;
        memcpy(out + n, ep_out, 7);
        n += 7;
        memcpy(out + n, ep_in, 7);
        n += 7;
    } else {
        uint8_t itf[9] = {9, 4, 0, 0, 2, 3, 0, 0, 0};
        uint8_t hid[9] = {9, 0x21, 0x11, 0x01, 0, 1, 0x22,
                          (uint8_t)sizeof report_desc, 0};
        uint8_t ep_in[7] = {7, 5, EP_IN, 3, 64, 0, 1};
        uint8_t ep_out[7] = {7, 5, EP_OUT, 3, 64, 0, 1};
        memcpy(out + n, itf, 9);
        n += 9;
        memcpy(out + n, hid, 9);
        n += 9;
        memcpy(out + n, ep_in, 7);
        n += 7;
        memcpy(out + n, ep_out, 7);
        n += 7;
    }
    size_t total = (size_t)(out + n - cfg);
    cfg[2] = (uint8_t)total;
    cfg[3] = (uint8_t)(total >> 8);
    return n;
}

/* A USB string descriptor (UTF-16LE of ASCII text). */
static size_t string_desc(uint8_t *out, const char *s)
{
    size_t n = strlen(s);
    if (n > 126)
        n = 126;
    out[0] = (uint8_t)(2 + 2 * n);
    out[1] = 3;
    for (size_t i = 0; i < n; i++) {
        out[2 + 2 * i] = (uint8_t)s[i];
        out[3 + 2 * i] = 0;
    }
    return 2 + 2 * n;
}

/* Writes a file (the binary attributes, created before umockdev adds the
 * device so that its single "add" uevent finds them). */
static int write_file(const char *path, const void *data, size_t len)
{
    char *dir = g_path_get_dirname(path);
    g_mkdir_with_parents(dir, 0755);
    g_free(dir);
    FILE *f = fopen(path, "wb");
    if (!f)
        return -errno;
    size_t w = fwrite(data, 1, len, f);
    int r = fclose(f);
    return w == len && r == 0 ? 0 : -EIO;
}

/* --- bulk: URBs -------------------------------------------------------------- */

static void urb_push(urb_list *l, urb_rec *r)
{
    r->next = NULL;
    if (l->tail)
        l->tail->next = r;
    else
        l->head = r;
    l->tail = r;
}

static urb_rec *urb_pop(urb_list *l)
{
    urb_rec *r = l->head;
    if (r) {
        l->head = r->next;
        if (!l->head)
            l->tail = NULL;
    }
    return r;
}

static void urb_free(urb_rec *r)
{
    if (r->buf)
        g_object_unref(r->buf);
    g_object_unref(r->urb);
    free(r);
}

static void urb_list_free(urb_list *l)
{
    urb_rec *r;
    while ((r = urb_pop(l)) != NULL)
        urb_free(r);
}

/* Makes the FIFO writable iff some client has a URB to reap. */
static void fifo_update(mock_dev *d)
{
    bool ready = false;
    for (client_st *c = d->clients; c && !ready; c = c->next)
        ready = c->done.head != NULL;
    if (ready == d->fifo_ready)
        return;
    char buf[4096];
    if (ready) {
        while (read(d->fifo, buf, sizeof buf) > 0)
            ;
    } else {
        memset(buf, 0, sizeof buf);
        while (write(d->fifo, buf, sizeof buf) > 0)
            ;
        while (write(d->fifo, buf, 1) > 0)
            ;
    }
    d->fifo_ready = ready;
}

/* Moves the engine's frames into the byte stream and completes pending IN
 * URBs with it. */
static void pump_bulk(mock_dev *d)
{
    size_t n;
    uint8_t *f;
    while ((f = mock_fspdev_next_frame(d->eng, &n)) != NULL) {
        if (d->out_len + n > d->out_cap) {
            size_t cap = (d->out_len + n) * 2;
            uint8_t *o = realloc(d->out, cap);
            if (!o) {
                free(f);
                break;
            }
            d->out = o;
            d->out_cap = cap;
        }
        memcpy(d->out + d->out_len, f, n);
        d->out_len += n;
        free(f);
    }
    for (client_st *c = d->clients; c; c = c->next) {
        while (d->out_len > 0 && c->pending.head) {
            urb_rec *r = urb_pop(&c->pending);
            size_t k = d->out_len < (size_t)r->len ? d->out_len
                                                   : (size_t)r->len;
            memcpy(r->buf->data, d->out, k);
            memmove(d->out, d->out + k, d->out_len - k);
            d->out_len -= k;
            r->actual = (int)k;
            r->status = 0;
            urb_push(&c->done, r);
        }
    }
    fifo_update(d);
}

static void control_urb(mock_dev *d, urb_rec *r)
{
    r->status = -EPIPE;
    r->actual = 0;
    if (!r->buf || r->len < 8)
        return;
    uint8_t *p = r->buf->data;
    uint8_t req = p[1];
    uint16_t value = (uint16_t)(p[2] | p[3] << 8);
    uint16_t wlen = (uint16_t)(p[6] | p[7] << 8);
    uint8_t desc[256];
    size_t n = 0;
    if (req == 6 && (value >> 8) == 3) { /* GET_DESCRIPTOR(STRING) */
        uint8_t idx = (uint8_t)value;
        if (idx == 0) {
            uint8_t lang[4] = {4, 3, 0x09, 0x04};
            memcpy(desc, lang, 4);
            n = 4;
        } else if (idx <= 3) {
            const char *s = idx == 1   ? "Facet Test"
                            : idx == 2 ? "Mock Scanner"
                                       : d->serial;
            n = string_desc(desc, s);
        } else {
            return;
        }
    } else if (req == 6 && (value >> 8) == 1) { /* GET_DESCRIPTOR(DEVICE) */
        uint8_t all[128];
        usb_descriptors(all, d->kind, d->vid, d->pid, false);
        memcpy(desc, all, 18);
        n = 18;
    } else {
        return;
    }
    if (n > wlen)
        n = wlen;
    if (n > (size_t)r->len - 8)
        n = (size_t)r->len - 8;
    memcpy(p + 8, desc, n);
    r->actual = (int)n;
    r->status = 0;
}

static void complete(UMockdevIoctlClient *c, long res, int err)
{
    umockdev_ioctl_client_complete(c, res, err);
}

static void submit_urb(mock_dev *d, client_st *cs, UMockdevIoctlClient *client,
                       UMockdevIoctlData *arg)
{
    GError *gerr = NULL;
    UMockdevIoctlData *u =
        umockdev_ioctl_data_resolve(arg, 0, sizeof(struct usbdevfs_urb), &gerr);
    if (!u) {
        g_clear_error(&gerr);
        complete(client, -1, EFAULT);
        return;
    }
    struct usbdevfs_urb *urb = (struct usbdevfs_urb *)u->data;
    UMockdevIoctlData *b = NULL;
    if (urb->buffer_length > 0) {
        b = umockdev_ioctl_data_resolve(u, offsetof(struct usbdevfs_urb, buffer),
                                        (gsize)urb->buffer_length, &gerr);
        if (!b) {
            g_clear_error(&gerr);
            g_object_unref(u);
            complete(client, -1, EFAULT);
            return;
        }
    }
    if (d->gone) {
        if (b)
            g_object_unref(b);
        g_object_unref(u);
        complete(client, -1, ENODEV);
        return;
    }
    urb_rec *r = calloc(1, sizeof *r);
    r->urb = u;
    r->buf = b;
    r->addr = u->client_addr;
    r->type = urb->type;
    r->ep = urb->endpoint;
    r->len = urb->buffer_length;
    if (r->type == USBDEVFS_URB_TYPE_CONTROL) {
        control_urb(d, r);
        urb_push(&cs->done, r);
    } else if (r->type == USBDEVFS_URB_TYPE_BULK && r->ep == EP_OUT) {
        if (b)
            mock_fspdev_input(d->eng, b->data, (size_t)r->len, mock_now_ms());
        r->actual = r->len;
        r->status = 0;
        urb_push(&cs->done, r);
    } else if (r->type == USBDEVFS_URB_TYPE_BULK && r->ep == EP_IN && b) {
        urb_push(&cs->pending, r);
    } else {
        r->status = -EPIPE;
        urb_push(&cs->done, r);
    }
    complete(client, 0, 0);
    pump_bulk(d);
}

static void reap_urb(mock_dev *d, client_st *cs, UMockdevIoctlClient *client,
                     UMockdevIoctlData *arg)
{
    urb_rec *r = urb_pop(&cs->done);
    if (!r) {
        complete(client, -1, d->gone ? ENODEV : EAGAIN);
        fifo_update(d);
        return;
    }
    struct usbdevfs_urb *urb = (struct usbdevfs_urb *)r->urb->data;
    urb->status = r->status;
    urb->actual_length = r->actual;
    GError *gerr = NULL;
    UMockdevIoctlData *slot =
        umockdev_ioctl_data_resolve(arg, 0, sizeof(void *), &gerr);
    if (!slot) {
        g_clear_error(&gerr);
        urb_free(r);
        complete(client, -1, EFAULT);
        fifo_update(d);
        return;
    }
    umockdev_ioctl_data_set_ptr(slot, 0, r->urb);
    g_object_unref(slot);
    complete(client, 0, 0);
    urb_free(r);
    fifo_update(d);
}

static void discard_urb(mock_dev *d, client_st *cs, UMockdevIoctlClient *client,
                        UMockdevIoctlData *arg)
{
    unsigned long addr = *(unsigned long *)arg->data;
    urb_rec **pp = &cs->pending.head, *prev = NULL;
    while (*pp && (*pp)->addr != addr) {
        prev = *pp;
        pp = &(*pp)->next;
    }
    urb_rec *r = *pp;
    if (!r) {
        complete(client, -1, EINVAL);
        return;
    }
    *pp = r->next;
    if (cs->pending.tail == r)
        cs->pending.tail = prev;
    r->status = -ENOENT;
    r->actual = 0;
    urb_push(&cs->done, r);
    complete(client, 0, 0);
    fifo_update(d);
}

static gboolean on_usb_ioctl(UMockdevIoctlBase *base,
                             UMockdevIoctlClient *client, gpointer user)
{
    (void)base;
    mock_dev *d = user;
    client_st *cs = g_object_get_data(G_OBJECT(client), "mock-client");
    unsigned long req = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
    GError *gerr = NULL;
    pthread_mutex_lock(&d->mu);
    if (!cs) {
        complete(client, -1, EBADF);
    } else if (req == USBDEVFS_GET_CAPABILITIES) {
        UMockdevIoctlData *v =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(uint32_t), &gerr);
        if (v) {
            /* scatter-gather: libusb submits one URB per transfer */
            uint32_t caps = USBDEVFS_CAP_ZERO_PACKET |
                            USBDEVFS_CAP_BULK_CONTINUATION |
                            USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                            USBDEVFS_CAP_BULK_SCATTER_GATHER;
            memcpy(v->data, &caps, sizeof caps);
            g_object_unref(v);
            complete(client, 0, 0);
        } else {
            complete(client, -1, EFAULT);
        }
    } else if (req == USBDEVFS_CLAIMINTERFACE ||
               req == USBDEVFS_RELEASEINTERFACE) {
        UMockdevIoctlData *v =
            umockdev_ioctl_data_resolve(arg, 0, sizeof(unsigned int), &gerr);
        unsigned itf = v ? *(unsigned int *)v->data : 32;
        if (v)
            g_object_unref(v);
        if (itf >= 32) {
            complete(client, -1, EINVAL);
        } else if (req == USBDEVFS_RELEASEINTERFACE) {
            cs->claimed &= ~(1u << itf);
            complete(client, 0, 0);
        } else {
            bool busy = false;
            for (client_st *o = d->clients; o; o = o->next)
                busy |= o != cs && (o->claimed & (1u << itf));
            if (d->gone) {
                complete(client, -1, ENODEV);
            } else if (busy) {
                complete(client, -1, EBUSY);
            } else {
                cs->claimed |= 1u << itf;
                complete(client, 0, 0);
            }
        }
    } else if (req == USBDEVFS_GETDRIVER) {
        complete(client, -1, ENODATA);
    } else if (req == USBDEVFS_SUBMITURB) {
        submit_urb(d, cs, client, arg);
    } else if (req == USBDEVFS_REAPURBNDELAY) {
        reap_urb(d, cs, client, arg);
    } else if (req == USBDEVFS_DISCARDURB) {
        discard_urb(d, cs, client, arg);
    } else {
        complete(client, -1, ENOTTY);
    }
    g_clear_error(&gerr);
    pthread_mutex_unlock(&d->mu);
    return TRUE;
}

/* --- clients ------------------------------------------------------------------ */

static void client_gone(GObject *obj, GParamSpec *pspec, gpointer user)
{
    (void)pspec;
    mock_dev *d = user;
    UMockdevIoctlClient *client = UMOCKDEV_IOCTL_CLIENT(obj);
    if (umockdev_ioctl_client_get_connected(client))
        return;
    pthread_mutex_lock(&d->mu);
    for (client_st **pp = &d->clients; *pp; pp = &(*pp)->next) {
        client_st *c = *pp;
        if (c->client != client)
            continue;
        *pp = c->next;
        urb_list_free(&c->pending);
        urb_list_free(&c->done);
        g_object_set_data(G_OBJECT(client), "mock-client", NULL);
        g_object_unref(c->client);
        free(c);
        break;
    }
    for (hid_read **pp = &d->reads; *pp;) {
        hid_read *h = *pp;
        if (h->client == client) {
            *pp = h->next;
            g_object_unref(h->client);
            free(h);
        } else {
            pp = &h->next;
        }
    }
    if (d->kind == SCAN_KIND_BULK)
        fifo_update(d);
    pthread_mutex_unlock(&d->mu);
}

static void on_client(UMockdevIoctlBase *base, UMockdevIoctlClient *client,
                      gpointer user)
{
    (void)base;
    mock_dev *d = user;
    client_st *c = calloc(1, sizeof *c);
    if (!c)
        return;
    c->dev = d;
    c->client = g_object_ref(client);
    pthread_mutex_lock(&d->mu);
    c->next = d->clients;
    d->clients = c;
    g_object_set_data(G_OBJECT(client), "mock-client", c);
    pthread_mutex_unlock(&d->mu);
    g_signal_connect(client, "notify::connected", G_CALLBACK(client_gone), d);
}

/* --- HID ----------------------------------------------------------------------- */

/* Answers a waiting read() with the oldest report. */
static void deliver_report(mock_dev *d, UMockdevIoctlClient *client)
{
    uint8_t rep[PROTO_HID_REPORT_SIZE];
    memcpy(rep, d->reports[d->rep_head], sizeof rep);
    d->rep_head = (d->rep_head + 1) % d->rep_cap;
    d->rep_n--;
    if (d->rep_n == 0 && d->ready_byte) {
        /* the client's own read() takes the readiness byte off the pty */
        int e = 0;
        GError *gerr = NULL;
        umockdev_ioctl_client_execute(client, &e, &gerr);
        g_clear_error(&gerr);
        d->ready_byte = false;
    }
    UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
    size_t n = (size_t)arg->data_len < sizeof rep ? (size_t)arg->data_len
                                                  : sizeof rep;
    memcpy(arg->data, rep, n);
    complete(client, (long)n, 0);
}

static void pump_hid(mock_dev *d)
{
    size_t n;
    uint8_t *f;
    while ((f = mock_fspdev_next_frame(d->eng, &n)) != NULL) {
        size_t count = proto_hid_report_count(n);
        if (d->rep_n + count > d->rep_cap) {
            size_t cap = (d->rep_n + count) * 2;
            uint8_t(*r)[PROTO_HID_REPORT_SIZE] =
                malloc(cap * PROTO_HID_REPORT_SIZE);
            if (!r) {
                free(f);
                break;
            }
            for (size_t i = 0; i < d->rep_n; i++)
                memcpy(r[i], d->reports[(d->rep_head + i) % d->rep_cap],
                       PROTO_HID_REPORT_SIZE);
            free(d->reports);
            d->reports = r;
            d->rep_head = 0;
            d->rep_cap = cap;
        }
        for (size_t k = 0; k < count; k++)
            proto_hid_fragment(f, n, k,
                               d->reports[(d->rep_head + d->rep_n++) %
                                          d->rep_cap]);
        free(f);
    }
    while (d->rep_n > 0 && d->reads) {
        hid_read *h = d->reads;
        d->reads = h->next;
        deliver_report(d, h->client);
        g_object_unref(h->client);
        free(h);
    }
    if (d->rep_n > 0 && !d->ready_byte && d->ptm >= 0) {
        if (write(d->ptm, "r", 1) == 1)
            d->ready_byte = true;
    }
}

static gboolean on_hid_ioctl(UMockdevIoctlBase *base,
                             UMockdevIoctlClient *client, gpointer user)
{
    (void)base;
    mock_dev *d = user;
    unsigned long req = umockdev_ioctl_client_get_request(client);
    UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
    GError *gerr = NULL;
    UMockdevIoctlData *v = NULL;
    pthread_mutex_lock(&d->mu);
    if (req == HIDIOCGRDESCSIZE &&
        (v = umockdev_ioctl_data_resolve(arg, 0, sizeof(int), &gerr))) {
        int size = (int)sizeof report_desc;
        memcpy(v->data, &size, sizeof size);
        complete(client, 0, 0);
    } else if (req == HIDIOCGRDESC &&
               (v = umockdev_ioctl_data_resolve(
                    arg, 0, sizeof(struct hidraw_report_descriptor), &gerr))) {
        struct hidraw_report_descriptor *rd = (void *)v->data;
        rd->size = sizeof report_desc;
        memcpy(rd->value, report_desc, sizeof report_desc);
        complete(client, 0, 0);
    } else if (req == HIDIOCGRAWINFO &&
               (v = umockdev_ioctl_data_resolve(
                    arg, 0, sizeof(struct hidraw_devinfo), &gerr))) {
        struct hidraw_devinfo *di = (void *)v->data;
        di->bustype = 3;
        di->vendor = (__s16)d->vid;
        di->product = (__s16)d->pid;
        complete(client, 0, 0);
    } else if (_IOC_TYPE(req) == 'H' &&
               (_IOC_NR(req) == 0x04 || _IOC_NR(req) == 0x05 ||
                _IOC_NR(req) == 0x08) &&
               _IOC_SIZE(req) > 0 &&
               (v = umockdev_ioctl_data_resolve(arg, 0, _IOC_SIZE(req),
                                                &gerr))) {
        const char *s = _IOC_NR(req) == 0x04   ? "Facet Test Mock Scanner"
                        : _IOC_NR(req) == 0x05 ? "usb-mock-1/input0"
                                               : d->serial;
        size_t n = strlen(s) + 1;
        if (n > _IOC_SIZE(req))
            n = _IOC_SIZE(req);
        memcpy(v->data, s, n);
        complete(client, (long)n, 0);
    } else {
        complete(client, -1, gerr ? EFAULT : ENOTTY);
    }
    if (v)
        g_object_unref(v);
    g_clear_error(&gerr);
    pthread_mutex_unlock(&d->mu);
    return TRUE;
}

static gboolean on_hid_read(UMockdevIoctlBase *base,
                            UMockdevIoctlClient *client, gpointer user)
{
    (void)base;
    mock_dev *d = user;
    pthread_mutex_lock(&d->mu);
    if (d->gone) {
        complete(client, -1, EIO);
    } else if (d->rep_n > 0) {
        deliver_report(d, client);
    } else {
        /* a blocking read waits for the next report */
        hid_read *h = calloc(1, sizeof *h);
        if (h) {
            h->client = g_object_ref(client);
            hid_read **pp = &d->reads;
            while (*pp)
                pp = &(*pp)->next;
            *pp = h;
        } else {
            complete(client, -1, ENOMEM);
        }
    }
    pthread_mutex_unlock(&d->mu);
    return TRUE;
}

static gboolean on_hid_write(UMockdevIoctlBase *base,
                             UMockdevIoctlClient *client, gpointer user)
{
    (void)base;
    mock_dev *d = user;
    UMockdevIoctlData *arg = umockdev_ioctl_client_get_arg(client);
    pthread_mutex_lock(&d->mu);
    if (d->gone) {
        complete(client, -1, EIO);
    } else {
        const uint8_t *frame;
        size_t len;
        proto_hid_status st = proto_hid_reasm_push(
            d->reasm, arg->data, (size_t)arg->data_len, &frame, &len);
        if ((st == PROTO_HID_FRAME || st == PROTO_HID_E_RESTART) && frame)
            mock_fspdev_input(d->eng, frame, len, mock_now_ms());
        if (st < 0)
            dev_event(d, "hid-reassembly-error");
        complete(client, arg->data_len, 0);
        pump_hid(d);
    }
    pthread_mutex_unlock(&d->mu);
    return TRUE;
}

/* --- devices ---------------------------------------------------------------- */

static void pump(mock_dev *d)
{
    if (d->gone)
        return;
    if (d->kind == SCAN_KIND_BULK)
        pump_bulk(d);
    else
        pump_hid(d);
}

void mock_dev_with(mock_dev *d, void (*fn)(mock_fspdev *e, void *arg),
                   void *arg)
{
    pthread_mutex_lock(&d->mu);
    fn(d->eng, arg);
    pump(d);
    pthread_mutex_unlock(&d->mu);
}

const char *mock_dev_node(const mock_dev *d)
{
    return d->node;
}

static void dev_free(mock_dev *d)
{
    for (client_st *c = d->clients, *n; c; c = n) {
        n = c->next;
        urb_list_free(&c->pending);
        urb_list_free(&c->done);
        g_object_set_data(G_OBJECT(c->client), "mock-client", NULL);
        g_object_unref(c->client);
        free(c);
    }
    for (hid_read *h = d->reads, *n; h; h = n) {
        n = h->next;
        g_object_unref(h->client);
        free(h);
    }
    if (d->fifo >= 0)
        close(d->fifo);
    if (d->ptm >= 0)
        close(d->ptm);
    if (d->pts >= 0)
        close(d->pts);
    if (d->handler)
        g_object_unref(d->handler);
    mock_fspdev_free(d->eng);
    proto_hid_reasm_free(d->reasm);
    free(d->out);
    free(d->reports);
    g_free(d->sys_usb);
    g_free(d->sys_hidraw);
    pthread_mutex_destroy(&d->mu);
    free(d);
}

void mock_dev_unplug(mock_dev *d)
{
    mock_bed *b = d->bed;
    pthread_mutex_lock(&d->mu);
    if (d->gone) {
        pthread_mutex_unlock(&d->mu);
        return;
    }
    d->gone = true;
    for (client_st *c = d->clients; c; c = c->next) {
        urb_rec *r;
        while ((r = urb_pop(&c->pending)) != NULL) {
            r->status = -ENODEV;
            r->actual = 0;
            urb_push(&c->done, r);
        }
    }
    while (d->reads) {
        hid_read *h = d->reads;
        d->reads = h->next;
        complete(h->client, -1, EIO);
        g_object_unref(h->client);
        free(h);
    }
    if (d->kind == SCAN_KIND_BULK) {
        fifo_update(d);
    } else {
        /* closing the pty hangs up every open hidraw file */
        close(d->ptm);
        close(d->pts);
        d->ptm = d->pts = -1;
    }
    pthread_mutex_unlock(&d->mu);
    if (d->sys_hidraw)
        umockdev_testbed_uevent(b->tb, d->sys_hidraw, "remove");
    umockdev_testbed_uevent(b->tb, d->sys_usb, "remove");
    umockdev_testbed_remove_device(b->tb, d->sys_usb);
    char *path = g_build_filename(b->root, d->node, NULL);
    unlink(path);
    g_free(path);
    dev_event(d, "unplugged");
}

mock_dev *mock_bed_find(mock_bed *b, const char *serial)
{
    pthread_mutex_lock(&b->mu);
    mock_dev *d = b->devs;
    while (d && (d->gone || strcmp(d->serial, serial) != 0))
        d = d->next;
    pthread_mutex_unlock(&b->mu);
    return d;
}

static bool attach(mock_bed *b, mock_dev *d, char *err, size_t cap)
{
    GError *gerr = NULL;
    d->handler = umockdev_ioctl_base_new();
    g_signal_connect(d->handler, "client-connected", G_CALLBACK(on_client), d);
    if (d->kind == SCAN_KIND_BULK) {
        g_signal_connect(d->handler, "handle-ioctl", G_CALLBACK(on_usb_ioctl),
                         d);
    } else {
        g_signal_connect(d->handler, "handle-ioctl", G_CALLBACK(on_hid_ioctl),
                         d);
        g_signal_connect(d->handler, "handle-read", G_CALLBACK(on_hid_read),
                         d);
        g_signal_connect(d->handler, "handle-write", G_CALLBACK(on_hid_write),
                         d);
    }
    if (!umockdev_testbed_attach_ioctl(b->tb, d->node, d->handler, &gerr)) {
        snprintf(err, cap, "%s: attach ioctl: %s", d->node,
                 gerr ? gerr->message : "failed");
        g_clear_error(&gerr);
        return false;
    }
    return true;
}

/* Adds the usb_device of d (its descriptors written first). */
static bool add_usb_device(mock_bed *b, mock_dev *d, char *err, size_t cap)
{
    char name[16], busnum[8], devnum[8], busp[8], devp[8], devname[64],
        vid[8], pid[8], product[32];
    snprintf(name, sizeof name, "1-%d", d->devnum - 1);
    snprintf(busnum, sizeof busnum, "%d\n", BUS);
    snprintf(devnum, sizeof devnum, "%d\n", d->devnum);
    snprintf(busp, sizeof busp, "%03d", BUS);
    snprintf(devp, sizeof devp, "%03d", d->devnum);
    snprintf(devname, sizeof devname, "/dev/bus/usb/%03d/%03d", BUS,
             d->devnum);
    snprintf(vid, sizeof vid, "%04x\n", d->vid);
    snprintf(pid, sizeof pid, "%04x\n", d->pid);
    snprintf(product, sizeof product, "%x/%x/100", d->vid, d->pid);
    char serial[80];
    snprintf(serial, sizeof serial, "%s\n", d->serial);
    uint8_t desc[128];
    size_t n = usb_descriptors(desc, d->kind, d->vid, d->pid, false);
    char *path = g_build_filename(b->root, b->hub, name, "descriptors", NULL);
    int r = write_file(path, desc, n);
    g_free(path);
    if (r < 0) {
        snprintf(err, cap, "%s: cannot write descriptors", name);
        return false;
    }
    d->sys_usb = umockdev_testbed_add_device(
        b->tb, "usb", name, b->hub, "busnum", busnum, "devnum", devnum,
        "speed", "480\n", "bConfigurationValue", "1\n", "idVendor", vid,
        "idProduct", pid, "bcdDevice", "0100\n", "manufacturer",
        "Facet Test\n", "product", "Mock Scanner\n", "serial", serial, NULL,
        "SUBSYSTEM", "usb", "DEVTYPE", "usb_device", "DEVNAME", devname,
        "BUSNUM", busp, "DEVNUM", devp, "PRODUCT", product, NULL);
    if (!d->sys_usb) {
        snprintf(err, cap, "%s: testbed refused the device", name);
        return false;
    }
    return true;
}

static bool plug_bulk(mock_bed *b, mock_dev *d, char *err, size_t cap)
{
    snprintf(d->node, sizeof d->node, "/dev/bus/usb/%03d/%03d", BUS,
             d->devnum);
    char *path = g_build_filename(b->root, d->node, NULL);
    char *dir = g_path_get_dirname(path);
    g_mkdir_with_parents(dir, 0755);
    g_free(dir);
    int r = mkfifo(path, 0666);
    d->fifo = r == 0 ? open(path, O_RDWR | O_NONBLOCK | O_CLOEXEC) : -1;
    g_free(path);
    if (d->fifo < 0) {
        snprintf(err, cap, "%s: cannot make the node: %s", d->node,
                 strerror(errno));
        return false;
    }
    fcntl(d->fifo, F_SETPIPE_SZ, 4096);
    d->fifo_ready = true;
    fifo_update(d);
    return attach(b, d, err, cap) && add_usb_device(b, d, err, cap);
}

static bool plug_hid(mock_bed *b, mock_dev *d, char *err, size_t cap)
{
    int idx = b->next_hidraw++;
    int hidn = b->next_hid++;
    snprintf(d->node, sizeof d->node, "/dev/hidraw%d", idx);
    char ptsname[64];
    if (openpty(&d->ptm, &d->pts, ptsname, NULL, NULL) < 0) {
        snprintf(err, cap, "openpty: %s", strerror(errno));
        return false;
    }
    struct termios tio;
    tcgetattr(d->pts, &tio);
    cfmakeraw(&tio);
    tcsetattr(d->pts, TCSANOW, &tio);
    fcntl(d->ptm, F_SETFL, fcntl(d->ptm, F_GETFL) | O_NONBLOCK);
    fcntl(d->ptm, F_SETFD, FD_CLOEXEC);
    fcntl(d->pts, F_SETFD, FD_CLOEXEC);
    struct stat st;
    fstat(d->pts, &st);
    char *path = g_build_filename(b->root, d->node, NULL);
    char *dir = g_path_get_dirname(path);
    g_mkdir_with_parents(dir, 0755);
    g_free(dir);
    int r = symlink(ptsname, path);
    g_free(path);
    if (r < 0) {
        snprintf(err, cap, "%s: symlink: %s", d->node, strerror(errno));
        return false;
    }
    if (!attach(b, d, err, cap) || !add_usb_device(b, d, err, cap))
        return false;

    char iname[32], hname[48], hidid[48], uniq[80];
    snprintf(iname, sizeof iname, "1-%d:1.0", d->devnum - 1);
    char *intf = umockdev_testbed_add_device(
        b->tb, "usb", iname, d->sys_usb, "bInterfaceNumber", "00\n",
        "bInterfaceClass", "03\n", NULL, "SUBSYSTEM", "usb", "DEVTYPE",
        "usb_interface", "INTERFACE", "3/0/0", NULL);
    snprintf(hname, sizeof hname, "0003:%04X:%04X.%04X", d->vid, d->pid,
             hidn);
    snprintf(hidid, sizeof hidid, "0003:%08X:%08X", d->vid, d->pid);
    snprintf(uniq, sizeof uniq, "%s", d->serial);
    char *hpath = intf ? g_build_filename(b->root, intf, hname,
                                          "report_descriptor", NULL)
                       : NULL;
    bool ok = hpath && write_file(hpath, report_desc, sizeof report_desc) == 0;
    g_free(hpath);
    char *hid = ok ? umockdev_testbed_add_device(
                         b->tb, "hid", hname, intf, NULL, "SUBSYSTEM", "hid",
                         "HID_ID", hidid, "HID_NAME", "Facet Test Mock Scanner",
                         "HID_PHYS", "usb-mock-1/input0", "HID_UNIQ", uniq,
                         NULL)
                   : NULL;
    char rname[32], devattr[32], smaj[16], smin[16], devname[32];
    snprintf(rname, sizeof rname, "hidraw%d", idx);
    snprintf(devattr, sizeof devattr, "%u:%u", major(st.st_rdev),
             minor(st.st_rdev));
    snprintf(smaj, sizeof smaj, "%u", major(st.st_rdev));
    snprintf(smin, sizeof smin, "%u", minor(st.st_rdev));
    snprintf(devname, sizeof devname, "/dev/hidraw%d", idx);
    if (hid) {
        /* the "device" link exists before the hidraw "add" goes out */
        char *link = g_build_filename(b->root, hid, "hidraw", rname, "device",
                                      NULL);
        char *ldir = g_path_get_dirname(link);
        g_mkdir_with_parents(ldir, 0755);
        ok = symlink("../..", link) == 0;
        g_free(ldir);
        g_free(link);
        char *rsub = g_build_filename("hidraw", rname, NULL);
        d->sys_hidraw =
            ok ? umockdev_testbed_add_device(
                     b->tb, "hidraw", rsub, hid, "dev", devattr, NULL,
                     "SUBSYSTEM", "hidraw", "DEVNAME", devname, "MAJOR", smaj,
                     "MINOR", smin, NULL)
               : NULL;
        g_free(rsub);
    }
    g_free(intf);
    g_free(hid);
    if (!d->sys_hidraw) {
        snprintf(err, cap, "%s: testbed refused the HID devices", d->node);
        return false;
    }
    return true;
}

mock_dev *mock_bed_plug(mock_bed *b, scan_kind kind, uint16_t vid,
                        uint16_t pid, const char *serial, char *err,
                        size_t err_cap)
{
    if (!proto_fsp_serial_valid(serial)) {
        snprintf(err, err_cap, "bad serial \"%s\"", serial);
        return NULL;
    }
    if (mock_bed_find(b, serial)) {
        snprintf(err, err_cap, "%s is already plugged in", serial);
        return NULL;
    }
    mock_dev *d = calloc(1, sizeof *d);
    if (!d) {
        snprintf(err, err_cap, "out of memory");
        return NULL;
    }
    d->bed = b;
    d->kind = kind;
    d->vid = vid;
    d->pid = pid;
    d->fifo = d->ptm = d->pts = -1;
    snprintf(d->serial, sizeof d->serial, "%s", serial);
    pthread_mutex_init(&d->mu, NULL);
    proto_fsp_info info = {"Facet Test", "Mock Scanner", "", "1.0.0", 400};
    snprintf(info.serial, sizeof info.serial, "%s", serial);
    d->eng = mock_fspdev_new(&info, dev_event, d);
    d->reasm = proto_hid_reasm_new(0);
    pthread_mutex_lock(&b->mu);
    d->devnum = b->next_devnum++;
    pthread_mutex_unlock(&b->mu);
    bool ok = d->eng && d->reasm &&
              (kind == SCAN_KIND_BULK ? plug_bulk(b, d, err, err_cap)
                                      : plug_hid(b, d, err, err_cap));
    if (!ok) {
        if (d->sys_usb)
            umockdev_testbed_remove_device(b->tb, d->sys_usb);
        dev_free(d);
        return NULL;
    }
    pthread_mutex_lock(&b->mu);
    d->next = b->devs;
    b->devs = d;
    pthread_mutex_unlock(&b->mu);
    dev_event(d, kind == SCAN_KIND_BULK ? "plugged bulk" : "plugged hid");
    return d;
}

mock_bed *mock_bed_new(mock_event_fn on_event, void *user, char *err,
                       size_t err_cap)
{
    mock_bed *b = calloc(1, sizeof *b);
    if (!b) {
        snprintf(err, err_cap, "out of memory");
        return NULL;
    }
    pthread_mutex_init(&b->mu, NULL);
    b->on_event = on_event;
    b->user = user;
    b->next_devnum = 2;
    b->tb = umockdev_testbed_new();
    b->root = umockdev_testbed_get_root_dir(b->tb);
    uint8_t desc[128];
    size_t n = usb_descriptors(desc, SCAN_KIND_BULK, 0x1d6b, 0x0002, true);
    char *path = g_build_filename(b->root, "sys/devices/usb1/descriptors",
                                  NULL);
    int r = write_file(path, desc, n);
    g_free(path);
    if (r == 0)
        b->hub = umockdev_testbed_add_device(
            b->tb, "usb", "usb1", NULL, "busnum", "1\n", "devnum", "1\n",
            "speed", "480\n", "bConfigurationValue", "1\n", "idVendor",
            "1d6b\n", "idProduct", "0002\n", "bDeviceClass", "09\n", NULL,
            "SUBSYSTEM", "usb", "DEVTYPE", "usb_device", "DEVNAME",
            "/dev/bus/usb/001/001", "BUSNUM", "001", "DEVNUM", "001", NULL);
    if (!b->hub) {
        snprintf(err, err_cap, "testbed: cannot add the root hub");
        return mock_bed_free(b);
    }
    return b;
}

mock_bed *mock_bed_free(mock_bed *b)
{
    if (!b)
        return NULL;
    for (mock_dev *d = b->devs; d; d = d->next)
        mock_dev_unplug(d);
    if (b->tb)
        g_object_unref(b->tb);
    while (b->devs) {
        mock_dev *d = b->devs;
        b->devs = d->next;
        dev_free(d);
    }
    g_free(b->root);
    g_free(b->hub);
    pthread_mutex_destroy(&b->mu);
    free(b);
    return NULL;
}

const char *mock_bed_root(const mock_bed *b)
{
    return b->root;
}

uint64_t mock_bed_tick(mock_bed *b)
{
    uint64_t next = UINT64_MAX, now = mock_now_ms();
    mock_dev *unplug[64];
    size_t nu = 0;
    pthread_mutex_lock(&b->mu);
    for (mock_dev *d = b->devs; d; d = d->next) {
        pthread_mutex_lock(&d->mu);
        if (!d->gone) {
            mock_fspdev_tick(d->eng, now);
            pump(d);
            uint64_t t = mock_fspdev_deadline(d->eng);
            if (t < next)
                next = t;
            if (mock_fspdev_wants_unplug(d->eng) && nu < 64)
                unplug[nu++] = d;
        }
        pthread_mutex_unlock(&d->mu);
    }
    pthread_mutex_unlock(&b->mu);
    for (size_t i = 0; i < nu; i++)
        mock_dev_unplug(unplug[i]);
    return next;
}

void mock_bed_foreach(mock_bed *b, void (*fn)(mock_dev *d, void *arg),
                      void *arg)
{
    pthread_mutex_lock(&b->mu);
    for (mock_dev *d = b->devs; d; d = d->next)
        if (!d->gone)
            fn(d, arg);
    pthread_mutex_unlock(&b->mu);
}

char *mock_dev_status_json(mock_dev *d)
{
    pthread_mutex_lock(&d->mu);
    char *s = mock_fspdev_status_json(d->eng);
    pthread_mutex_unlock(&d->mu);
    if (!s)
        return NULL;
    /* splice "kind" and "node" into the engine's object */
    size_t n = strlen(s) + 128;
    char *o = malloc(n);
    if (o)
        snprintf(o, n, "{\"kind\":\"%s\",\"node\":\"%s\",%s",
                 d->kind == SCAN_KIND_BULK ? "bulk" : "hid", d->node, s + 1);
    free(s);
    return o;
}
