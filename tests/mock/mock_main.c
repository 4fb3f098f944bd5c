/* mock_main.c — fsp-mock, the mocked USB scanner harness for the tests.
 *
 *   fsp-mock [--control FIFO] [--log FILE] [--preload LIST] [-- PROGRAM ARGS]
 *
 * Re-executes itself under LD_PRELOAD=libumockdev-preload.so.0 (preceded
 * by the AddressSanitizer runtime when the harness itself is sanitized,
 * since a sanitized program needs it first), builds a umockdev testbed
 * (mock_usb.h), starts PROGRAM in it (inheriting UMOCKDEV_DIR and the
 * preload), and obeys one command per line from FIFO (created if
 * missing) or standard input:
 *
 *   plug bulk|hid SERIAL [VID:PID]   a scanner appears (default 1d50:6150
 *                                    bulk, 1d50:6151 HID)
 *   unplug SERIAL                    it disappears
 *   model SERIAL FILE [json|fmb1]    the model its scans send
 *   scan SERIAL                      the operator starts a scan
 *   corrupt SERIAL model K           MODEL frame K of the next scan is
 *                                    sent once with a broken CRC
 *   corrupt SERIAL done              SCAN_DONE carries a wrong model CRC
 *   unplug-after SERIAL N            unplug after N MODEL frames
 *   stall SERIAL on|off|after N      the device goes silent (at once, or
 *                                    after N MODEL frames) / resumes
 *   status [SERIAL]                  one "status {json}" line per device
 *   run PROGRAM ARGS...              start a program in the testbed
 *   kill [SIGNAL]                    signal it (default TERM)
 *   quit
 *
 * Output (FILE or standard output), one line each: "ready ROOT", "ok
 * COMMAND ...", "err COMMAND: why", "event SERIAL what" (hello, result
 * {...}, done-acked, nak N, dropped, abandoned, unplugged, ...),
 * "child-exit STATUS". */
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <link.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include "mock_usb.h"

static FILE *out;
static pthread_mutex_t out_mu = PTHREAD_MUTEX_INITIALIZER;

static void say(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

static void say(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    pthread_mutex_lock(&out_mu);
    vfprintf(out, fmt, ap);
    fputc('\n', out);
    fflush(out);
    pthread_mutex_unlock(&out_mu);
    va_end(ap);
}

static void on_event(void *user, const char *serial, const char *line)
{
    (void)user;
    say("event %s %s", serial, line);
}

/* --- the program under test ------------------------------------------- */

static pid_t child = -1;
static int child_fd = -1;

#ifdef __SANITIZE_ADDRESS__
static int find_asan(struct dl_phdr_info *info, size_t size, void *arg)
{
    (void)size;
    if (info->dlpi_name && strstr(info->dlpi_name, "libasan.so")) {
        snprintf(arg, 512, "%s", info->dlpi_name);
        return 1;
    }
    return 0;
}
#endif

/* libumockdev-preload.so.0, after the ASan runtime if this harness (and
 * so, in the tests, the program) is built with AddressSanitizer. */
static void default_preload(char *buf, size_t cap)
{
    char asan[512] = "";
#ifdef __SANITIZE_ADDRESS__
    dl_iterate_phdr(find_asan, asan);
#endif
    snprintf(buf, cap, "%s%slibumockdev-preload.so.0", asan,
             asan[0] ? ":" : "");
}

static int spawn(char **argv, const char *preload)
{
    if (child > 0)
        return -EBUSY;
    pid_t pid = fork();
    if (pid < 0)
        return -errno;
    if (pid == 0) {
        setenv("LD_PRELOAD", preload, 1);
        execvp(argv[0], argv);
        fprintf(stderr, "fsp-mock: %s: %s\n", argv[0], strerror(errno));
        _exit(127);
    }
    child = pid;
    child_fd = (int)syscall(SYS_pidfd_open, pid, 0);
    return 0;
}

static void reap_child(void)
{
    int st;
    if (child > 0 && waitpid(child, &st, WNOHANG) == child) {
        say("child-exit %d", WIFEXITED(st) ? WEXITSTATUS(st)
                                           : 128 + WTERMSIG(st));
        child = -1;
        if (child_fd >= 0)
            close(child_fd);
        child_fd = -1;
    }
}

static void stop_child(void)
{
    if (child <= 0)
        return;
    kill(child, SIGTERM);
    for (int i = 0; i < 100 && child > 0; i++) {
        usleep(50000);
        reap_child();
    }
    if (child > 0) {
        kill(child, SIGKILL);
        waitpid(child, NULL, 0);
        child = -1;
    }
}

/* --- commands --------------------------------------------------------- */

typedef struct model_arg {
    uint8_t *bytes;
    size_t len;
    uint8_t format;
    int r;
} model_arg;

static void do_model(mock_fspdev *e, void *arg)
{
    model_arg *m = arg;
    m->r = mock_fspdev_set_model(e, m->bytes, m->len, m->format);
}

static void do_scan(mock_fspdev *e, void *arg)
{
    *(int *)arg = mock_fspdev_scan(e, mock_now_ms());
}

static void do_corrupt_model(mock_fspdev *e, void *arg)
{
    mock_fspdev_corrupt_model(e, *(unsigned *)arg);
}

static void do_corrupt_done(mock_fspdev *e, void *arg)
{
    (void)arg;
    mock_fspdev_corrupt_done(e, true);
}

static void do_unplug_after(mock_fspdev *e, void *arg)
{
    mock_fspdev_unplug_after(e, *(unsigned *)arg);
}

static void do_stall(mock_fspdev *e, void *arg)
{
    mock_fspdev_stall(e, *(bool *)arg);
}

static void do_stall_after(mock_fspdev *e, void *arg)
{
    mock_fspdev_stall_after(e, *(unsigned *)arg);
}

static void print_status(mock_dev *d, void *arg)
{
    (void)arg;
    char *s = mock_dev_status_json(d);
    say("status %s", s ? s : "{}");
    free(s);
}

static uint8_t *read_file(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    uint8_t *buf = NULL;
    size_t n = 0, cap = 0;
    for (;;) {
        if (n == cap) {
            cap = cap ? 2 * cap : 1 << 16;
            uint8_t *b = realloc(buf, cap);
            if (!b) {
                free(buf);
                fclose(f);
                return NULL;
            }
            buf = b;
        }
        size_t r = fread(buf + n, 1, cap - n, f);
        n += r;
        if (r == 0)
            break;
    }
    fclose(f);
    *len = n;
    return buf;
}

/* Handles one command; returns false for quit. */
static bool command(mock_bed *bed, char *line, const char *preload)
{
    char *argv[64];
    int argc = 0;
    for (char *tok = strtok(line, " \t\r\n"); tok && argc < 63;
         tok = strtok(NULL, " \t\r\n"))
        argv[argc++] = tok;
    argv[argc] = NULL;
    if (argc == 0)
        return true;
    const char *cmd = argv[0];
    char err[256] = "";
    mock_dev *d = argc >= 2 ? mock_bed_find(bed, argv[1]) : NULL;
    bool needs_dev = strcmp(cmd, "unplug") == 0 || strcmp(cmd, "model") == 0 ||
                     strcmp(cmd, "scan") == 0 ||
                     strcmp(cmd, "corrupt") == 0 ||
                     strcmp(cmd, "unplug-after") == 0 ||
                     strcmp(cmd, "stall") == 0;
    if (needs_dev && !d) {
        say("err %s: no device %s plugged in", cmd, argc >= 2 ? argv[1] : "");
        return true;
    }
    if (strcmp(cmd, "quit") == 0) {
        say("ok quit");
        return false;
    } else if (strcmp(cmd, "plug") == 0 && argc >= 3) {
        bool hid = strcmp(argv[1], "hid") == 0;
        unsigned vid = 0x1d50, pid = hid ? 0x6151 : 0x6150;
        if ((!hid && strcmp(argv[1], "bulk") != 0) ||
            (argc >= 4 && sscanf(argv[3], "%x:%x", &vid, &pid) != 2)) {
            say("err plug: usage: plug bulk|hid SERIAL [VID:PID]");
            return true;
        }
        mock_dev *nd = mock_bed_plug(bed, hid ? SCAN_KIND_HID : SCAN_KIND_BULK,
                                     (uint16_t)vid, (uint16_t)pid, argv[2],
                                     err, sizeof err);
        if (nd)
            say("ok plug %s %s", argv[2], mock_dev_node(nd));
        else
            say("err plug: %s", err);
    } else if (strcmp(cmd, "unplug") == 0) {
        mock_dev_unplug(d);
        say("ok unplug %s", argv[1]);
    } else if (strcmp(cmd, "model") == 0 && argc >= 3) {
        model_arg m = {0};
        m.format = argc >= 4 && strcmp(argv[3], "fmb1") == 0
                       ? PROTO_FSP_MODEL_FMB1
                       : PROTO_FSP_MODEL_JSON;
        m.bytes = read_file(argv[2], &m.len);
        if (!m.bytes) {
            say("err model: %s: %s", argv[2], strerror(errno));
            return true;
        }
        mock_dev_with(d, do_model, &m);
        free(m.bytes);
        if (m.r < 0)
            say("err model: %s", strerror(-m.r));
        else
            say("ok model %s %zu", argv[1], m.len);
    } else if (strcmp(cmd, "scan") == 0) {
        int r = 0;
        mock_dev_with(d, do_scan, &r);
        if (r < 0)
            say("err scan: %s", r == -EBUSY ? "already scanning" : "no model");
        else
            say("ok scan %s", argv[1]);
    } else if (strcmp(cmd, "corrupt") == 0 && argc >= 3) {
        if (strcmp(argv[2], "done") == 0) {
            mock_dev_with(d, do_corrupt_done, NULL);
        } else if (strcmp(argv[2], "model") == 0 && argc >= 4) {
            unsigned k = (unsigned)strtoul(argv[3], NULL, 10);
            mock_dev_with(d, do_corrupt_model, &k);
        } else {
            say("err corrupt: usage: corrupt SERIAL model K | done");
            return true;
        }
        say("ok corrupt %s", argv[1]);
    } else if (strcmp(cmd, "unplug-after") == 0 && argc >= 3) {
        unsigned n = (unsigned)strtoul(argv[2], NULL, 10);
        mock_dev_with(d, do_unplug_after, &n);
        say("ok unplug-after %s %u", argv[1], n);
    } else if (strcmp(cmd, "stall") == 0 && argc >= 4 &&
               strcmp(argv[2], "after") == 0) {
        unsigned k = (unsigned)strtoul(argv[3], NULL, 10);
        mock_dev_with(d, do_stall_after, &k);
        say("ok stall %s after %u", argv[1], k);
    } else if (strcmp(cmd, "stall") == 0 && argc >= 3) {
        bool on = strcmp(argv[2], "on") == 0;
        mock_dev_with(d, do_stall, &on);
        say("ok stall %s %s", argv[1], on ? "on" : "off");
    } else if (strcmp(cmd, "status") == 0) {
        if (argc >= 2 && !d)
            say("err status: no device %s plugged in", argv[1]);
        else if (d)
            print_status(d, NULL);
        else
            mock_bed_foreach(bed, print_status, NULL);
        say("ok status");
    } else if (strcmp(cmd, "run") == 0 && argc >= 2) {
        int r = spawn(argv + 1, preload);
        if (r < 0)
            say("err run: %s", strerror(-r));
        else
            say("ok run %d", (int)child);
    } else if (strcmp(cmd, "kill") == 0) {
        int sig = argc >= 2 ? atoi(argv[1]) : SIGTERM;
        if (child > 0 && kill(child, sig ? sig : SIGTERM) == 0)
            say("ok kill");
        else
            say("err kill: no program running");
    } else {
        say("err %s: unknown command or missing arguments", cmd);
    }
    return true;
}

int main(int argc, char **argv)
{
    const char *control = NULL, *log = NULL;
    char preload[1024];
    default_preload(preload, sizeof preload);
    int i = 1;
    for (; i < argc; i++) {
        if (strcmp(argv[i], "--control") == 0 && i + 1 < argc) {
            control = argv[++i];
        } else if (strcmp(argv[i], "--log") == 0 && i + 1 < argc) {
            log = argv[++i];
        } else if (strcmp(argv[i], "--preload") == 0 && i + 1 < argc) {
            snprintf(preload, sizeof preload, "%s", argv[++i]);
        } else if (strcmp(argv[i], "--") == 0) {
            i++;
            break;
        } else {
            fprintf(stderr,
                    "usage: fsp-mock [--control FIFO] [--log FILE] "
                    "[--preload LIST] [-- PROGRAM ARGS...]\n");
            return 2;
        }
    }
    /* umockdev's testbed resolves /sys paths through its preload library,
     * in this process as in the program under test: run under it */
    const char *cur = getenv("LD_PRELOAD");
    if (!cur || !strstr(cur, "libumockdev-preload")) {
        setenv("LD_PRELOAD", preload, 1);
        execv("/proc/self/exe", argv);
        fprintf(stderr, "fsp-mock: re-exec: %s\n", strerror(errno));
        return 1;
    }
    out = log ? fopen(log, "a") : stdout;
    if (!out) {
        fprintf(stderr, "fsp-mock: %s: %s\n", log, strerror(errno));
        return 1;
    }
    signal(SIGPIPE, SIG_IGN);
    int cmd_fd = 0;
    if (control) {
        if (mkfifo(control, 0600) < 0 && errno != EEXIST) {
            fprintf(stderr, "fsp-mock: %s: %s\n", control, strerror(errno));
            return 1;
        }
        /* read-write, so that writers coming and going never cause EOF */
        cmd_fd = open(control, O_RDWR | O_NONBLOCK | O_CLOEXEC);
        if (cmd_fd < 0) {
            fprintf(stderr, "fsp-mock: %s: %s\n", control, strerror(errno));
            return 1;
        }
    }
    char err[256];
    mock_bed *bed = mock_bed_new(on_event, NULL, err, sizeof err);
    if (!bed) {
        fprintf(stderr, "fsp-mock: %s\n", err);
        return 1;
    }
    say("ready %s", mock_bed_root(bed));
    if (i < argc) {
        int r = spawn(argv + i, preload);
        if (r < 0)
            say("err run: %s", strerror(-r));
        else
            say("ok run %d", (int)child);
    }

    char buf[4096];
    size_t have = 0;
    bool running = true;
    while (running) {
        uint64_t next = mock_bed_tick(bed), now = mock_now_ms();
        int timeout = 200;
        if (next != UINT64_MAX && next > now && next - now < 200)
            timeout = (int)(next - now);
        struct pollfd fds[2] = {{.fd = cmd_fd, .events = POLLIN},
                                {.fd = child_fd, .events = POLLIN}};
        int r = poll(fds, child_fd >= 0 ? 2 : 1, timeout);
        if (r < 0 && errno != EINTR)
            break;
        if (fds[0].revents & (POLLIN | POLLHUP)) {
            ssize_t n = read(cmd_fd, buf + have, sizeof buf - 1 - have);
            if (n == 0 && !control)
                running = false;
            if (n > 0)
                have += (size_t)n;
            char *nl;
            while (running && (nl = memchr(buf, '\n', have)) != NULL) {
                *nl = '\0';
                size_t used = (size_t)(nl - buf) + 1;
                char line[4096];
                memcpy(line, buf, used);
                memmove(buf, buf + used, have - used);
                have -= used;
                running = command(bed, line, preload);
            }
            if (have == sizeof buf - 1)
                have = 0; /* an overlong line is dropped */
        }
        reap_child();
    }
    stop_child();
    mock_bed_free(bed);
    if (control) {
        close(cmd_fd);
        unlink(control);
    }
    if (out != stdout)
        fclose(out);
    return 0;
}
