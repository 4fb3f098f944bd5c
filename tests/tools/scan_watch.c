/* scan_watch.c — a small client of the scanner intake for the integration
 * tests and the intake benchmark: it starts scan_intake_start() with a
 * device list and prints one line per event, and obeys commands on
 * standard input.
 *
 *   scan_watch [--devices LIST] [--scan-timeout MS] [--resend MS]
 *              [--out DIR] [--result auto|manual]
 *
 * Output: "started", "device SERIAL kind=... path=...", "gone SERIAL",
 * "progress SERIAL D/T", "scan SERIAL job=JOB bytes=N crc=HEX format=F
 * ms=T mbps=R model=V/F" (vertices/facets as parsed, or "invalid"),
 * "notice SERIAL text", and the replies below. With --out
 * every model is written to DIR/JOB.model. With --result auto (default)
 * a RESULT goes back as soon as the scan is complete.
 * Commands: "start SERIAL [MODE]", "result SERIAL JOB [STATE]", "list",
 * "metrics", "quit". SIGTERM stops the intake cleanly too. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "crc32.h"
#include "scanner.h"

static pthread_mutex_t mu = PTHREAD_MUTEX_INITIALIZER;
static int wake[2];
static volatile sig_atomic_t stopping;
static const char *out_dir;
static int auto_result = 1;
static int jobs;

typedef struct owed {
    char serial[64], job[64];
} owed;
static owed queue[256];
static size_t nqueue;

typedef struct timing {
    char serial[64];
    struct timespec t0;
} timing;
static timing starts[32];

static void say(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

static void say(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    pthread_mutex_lock(&mu);
    vprintf(fmt, ap);
    putchar('\n');
    fflush(stdout);
    pthread_mutex_unlock(&mu);
    va_end(ap);
}

static double since(const char *serial)
{
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    for (size_t i = 0; i < 32; i++)
        if (strcmp(starts[i].serial, serial) == 0)
            return (double)(now.tv_sec - starts[i].t0.tv_sec) * 1e3 +
                   (double)(now.tv_nsec - starts[i].t0.tv_nsec) / 1e6;
    return 0;
}

static void on_device(void *u, const scan_device_info *d)
{
    (void)u;
    say("device %s kind=%s path=%s vendor=\"%s\" model=\"%s\" fw=%s "
        "contours=%u",
        d->serial, scan_kind_name(d->kind), d->path, d->vendor, d->model,
        d->firmware, d->contours);
}

static void on_gone(void *u, const char *serial)
{
    (void)u;
    say("gone %s", serial);
}

static void on_progress(void *u, const char *serial, uint32_t done,
                        uint32_t total)
{
    (void)u;
    if (done == 0) {
        pthread_mutex_lock(&mu);
        size_t slot = 0;
        for (size_t i = 0; i < 32; i++) {
            if (strcmp(starts[i].serial, serial) == 0 || !starts[i].serial[0]) {
                slot = i;
                break;
            }
        }
        snprintf(starts[slot].serial, sizeof starts[slot].serial, "%s",
                 serial);
        clock_gettime(CLOCK_MONOTONIC, &starts[slot].t0);
        pthread_mutex_unlock(&mu);
    }
    say("progress %s %u/%u", serial, done, total);
}

static int on_scan(void *u, const char *serial, const uint8_t *bytes,
                   size_t len, proto_format fmt, char *job, size_t cap)
{
    (void)u;
    pthread_mutex_lock(&mu);
    int n = ++jobs;
    double ms = since(serial);
    pthread_mutex_unlock(&mu);
    snprintf(job, cap, "job-%d", n);
    if (out_dir) {
        char path[512];
        snprintf(path, sizeof path, "%s/%s.model", out_dir, job);
        FILE *f = fopen(path, "wb");
        if (f) {
            fwrite(bytes, 1, len, f);
            fclose(f);
        }
    }
    /* what the daemon will do with it: parse it as a model */
    geo_err perr;
    geo_poly *p = proto_model_read_mem(bytes, len, fmt, NULL, &perr);
    char parsed[64] = "invalid";
    if (p)
        snprintf(parsed, sizeof parsed, "%u/%u", p->nverts, p->nfacets);
    geo_poly_free(p);
    say("scan %s job=%s bytes=%zu crc=%08x format=%s ms=%.1f mbps=%.2f "
        "model=%s",
        serial, job, len, proto_crc32(bytes, len),
        fmt == PROTO_FMT_FMB1 ? "fmb1" : "json", ms,
        ms > 0 ? (double)len / 1e6 / (ms / 1e3) : 0.0, parsed);
    if (auto_result) {
        pthread_mutex_lock(&mu);
        if (nqueue < 256) {
            snprintf(queue[nqueue].serial, 64, "%s", serial);
            snprintf(queue[nqueue].job, 64, "%s", job);
            nqueue++;
        }
        pthread_mutex_unlock(&mu);
        char c = 1;
        if (write(wake[1], &c, 1) < 0)
            say("notice - wake pipe full");
    }
    return 0;
}

static void on_notice(void *u, const char *serial, const char *msg)
{
    (void)u;
    say("notice %s %s", serial[0] ? serial : "-", msg);
}

static void on_term(int sig)
{
    (void)sig;
    stopping = 1;
    char c = 0;
    if (write(wake[1], &c, 1) < 0)
        stopping = 1;
}

static void send_result(scan_intake *in, const char *serial, const char *job,
                        const char *state)
{
    proto_fsp_result r = {.facets_before = 812, .facets_after = 57,
                          .self_intersections = 0, .valid = true};
    snprintf(r.job, sizeof r.job, "%s", job);
    snprintf(r.state, sizeof r.state, "%s", state);
    snprintf(r.url, sizeof r.url, "/v1/jobs/%s", job);
    int rc = scan_send_result(in, serial, &r);
    if (rc < 0)
        say("err result %s %s: %s", serial, job, strerror(-rc));
    else
        say("ok result %s %s", serial, job);
}

static void command(scan_intake *in, char *line, int *running)
{
    char *argv[8];
    int argc = 0;
    for (char *t = strtok(line, " \t\r\n"); t && argc < 8;
         t = strtok(NULL, " \t\r\n"))
        argv[argc++] = t;
    if (argc == 0)
        return;
    if (strcmp(argv[0], "quit") == 0) {
        *running = 0;
    } else if (strcmp(argv[0], "start") == 0 && argc >= 2) {
        int mode = argc >= 3 ? atoi(argv[2]) : 0;
        int r = scan_request_start(in, argv[1], (uint8_t)mode);
        if (r < 0)
            say("err start %s: %s", argv[1], strerror(-r));
        else
            say("ok start %s", argv[1]);
    } else if (strcmp(argv[0], "result") == 0 && argc >= 3) {
        send_result(in, argv[1], argv[2], argc >= 4 ? argv[3] : "succeeded");
    } else if (strcmp(argv[0], "list") == 0) {
        scan_device_status *st;
        size_t n;
        if (scan_list(in, &st, &n) == 0) {
            for (size_t i = 0; i < n; i++)
                say("scanner %s state=%s progress=%u/%u last_job=%s "
                    "completed=%llu dropped=%llu",
                    st[i].info.serial, scan_state_name(st[i].state),
                    st[i].progress_done, st[i].progress_total,
                    st[i].last_job[0] ? st[i].last_job : "-",
                    (unsigned long long)st[i].scans_completed,
                    (unsigned long long)st[i].scans_dropped);
            free(st);
        }
        say("ok list %zu", n);
    } else if (strcmp(argv[0], "metrics") == 0) {
        scan_metrics m;
        scan_get_metrics(in, &m);
        say("metrics frames_in=%llu frames_out=%llu crc_errors=%llu "
            "bad_frames=%llu seq_errors=%llu naks_sent=%llu "
            "naks_received=%llu reassembly_failures=%llu "
            "devices_connected=%llu scans_completed=%llu "
            "scans_dropped=%llu model_bytes=%llu",
            (unsigned long long)m.frames_in, (unsigned long long)m.frames_out,
            (unsigned long long)m.crc_errors, (unsigned long long)m.bad_frames,
            (unsigned long long)m.seq_errors, (unsigned long long)m.naks_sent,
            (unsigned long long)m.naks_received,
            (unsigned long long)m.reassembly_failures,
            (unsigned long long)m.devices_connected,
            (unsigned long long)m.scans_completed,
            (unsigned long long)m.scans_dropped,
            (unsigned long long)m.model_bytes);
    } else {
        say("err %s: unknown command", argv[0]);
    }
}

int main(int argc, char **argv)
{
    const char *devices = SCAN_DEFAULT_DEVICES;
    scan_options opt;
    scan_options_default(&opt);
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--devices") == 0 && i + 1 < argc)
            devices = argv[++i];
        else if (strcmp(argv[i], "--scan-timeout") == 0 && i + 1 < argc)
            opt.scan_timeout_ms = atoi(argv[++i]);
        else if (strcmp(argv[i], "--resend") == 0 && i + 1 < argc)
            opt.resend_ms = atoi(argv[++i]);
        else if (strcmp(argv[i], "--out") == 0 && i + 1 < argc)
            out_dir = argv[++i];
        else if (strcmp(argv[i], "--result") == 0 && i + 1 < argc)
            auto_result = strcmp(argv[++i], "auto") == 0;
        else {
            fprintf(stderr, "usage: scan_watch [--devices LIST] "
                            "[--scan-timeout MS] [--resend MS] [--out DIR] "
                            "[--result auto|manual]\n");
            return 2;
        }
    }
    scan_match list[SCAN_MATCH_MAX];
    size_t n;
    geo_err err;
    if (scan_match_list_parse(devices, list, SCAN_MATCH_MAX, &n, &err) < 0) {
        fprintf(stderr, "scan_watch: %s\n", err.msg);
        return 2;
    }
    if (pipe(wake) < 0)
        return 1;
    fcntl(wake[1], F_SETFL, O_NONBLOCK);
    struct sigaction sa = {.sa_handler = on_term};
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    scan_callbacks cb = {.on_device = on_device,
                         .on_device_gone = on_gone,
                         .on_scan_complete = on_scan,
                         .on_progress = on_progress,
                         .on_notice = on_notice};
    scan_intake *in = scan_intake_start(list, n, &cb, &opt, &err);
    if (!in) {
        fprintf(stderr, "scan_watch: %s\n", err.msg);
        return 1;
    }
    say("started");
    char buf[4096];
    size_t have = 0;
    int running = 1;
    while (running && !stopping) {
        struct pollfd fds[2] = {{.fd = 0, .events = POLLIN},
                                {.fd = wake[0], .events = POLLIN}};
        if (poll(fds, 2, -1) < 0 && errno != EINTR)
            break;
        if (fds[1].revents & POLLIN) {
            char c[64];
            if (read(wake[0], c, sizeof c) < 0)
                break;
            owed todo[256];
            pthread_mutex_lock(&mu);
            size_t k = nqueue;
            memcpy(todo, queue, k * sizeof *todo);
            nqueue = 0;
            pthread_mutex_unlock(&mu);
            for (size_t i = 0; i < k; i++)
                send_result(in, todo[i].serial, todo[i].job, "succeeded");
        }
        if (fds[0].revents & (POLLIN | POLLHUP)) {
            ssize_t r = read(0, buf + have, sizeof buf - 1 - have);
            if (r <= 0)
                break;
            have += (size_t)r;
            char *nl;
            while (running && (nl = memchr(buf, '\n', have)) != NULL) {
                *nl = '\0';
                char line[4096];
                size_t used = (size_t)(nl - buf) + 1;
                memcpy(line, buf, used);
                memmove(buf, buf + used, have - used);
                have -= used;
                command(in, line, &running);
            }
            if (have == sizeof buf - 1)
                have = 0;
        }
    }
    scan_intake_stop(in);
    say("stopped");
    return 0;
}
