/* fuzz_http_request.c — libFuzzer target: raw bytes sent to facetd's HTTP
 * server as one client connection (request line, headers, framing,
 * bodies, pipelined requests), the whole server in this process: the
 * libmicrohttpd daemon with facetd's routes, over a loopback socket, on a
 * SQLite store in a temporary directory, no workers.
 *
 * Property: no crash or sanitizer report anywhere in the server, and
 * whatever is answered is an HTTP/1.x status line, never 500 (a 500 is a
 * defect of the server, not of the client). A connection the server
 * keeps open (an event stream does, legitimately) is cut by the client
 * at the deadline; the server's own limits on slow and held connections
 * are tested in tests/integration/hostile_http.sh. */
#include <errno.h>
#include <ftw.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "http_listen.h"
#include "http_server.h"
#include "metrics.h"
#include "store.h"

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum {
    DEADLINE_MS = 1500,   /* a connection the server has not ended by then */
    QUIET_MS = 0,         /* after a whole answer to all that was sent the
                             client closes at once: a kept-alive connection
                             whose client half-closed is seen closed only
                             at the idle timeout (a pipelined request
                             behind the first is still read and parsed by
                             the server, its answer is not checked) */
    TRIM_EVERY = 200,     /* inputs between emptying the store */
    QUEUE_SIZE = 16,
};

static http_env env;
static http_server *hs;
static struct sockaddr_storage addr;
static socklen_t addrlen;
static char dir[4096];

static int remove_one(const char *path, const struct stat *st, int type,
                      struct FTW *ftw)
{
    (void)st;
    (void)type;
    (void)ftw;
    return remove(path);
}

/* The store's files go with the process. */
static void cleanup(void)
{
    if (hs)
        http_server_stop(hs);
    hs = NULL;
    if (dir[0])
        nftw(dir, remove_one, 8, FTW_DEPTH | FTW_PHYS);
}

static void die(const char *what, const char *why)
{
    fprintf(stderr, "fuzz_http_request: %s: %s\n", what, why);
    abort();
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    geo_err err = {{0}};
    const char *tmp = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/fuzz-http-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir))
        die("mkdtemp", strerror(errno));
    atexit(cleanup);
    http_env_init(&env);
    env.s = store_sqlite_open(dir, &err);
    if (!env.s)
        die("store", err.msg);
    env.m = metrics_new(http_route_names, http_nroutes);
    if (!env.m)
        die("metrics", "out of memory");
    env.workers = 1;
    atomic_store(&env.max_body, 1u << 20);
    atomic_store(&env.max_wait_ms, 50);
    atomic_store(&env.keepalive_ms, 100);
    atomic_store(&env.max_waiters, 8);
    atomic_store(&env.queue_size, QUEUE_SIZE);
    atomic_store(&env.inspect_max_facets, 20000);
    atomic_store(&env.inspect_timeout_ms, 300);
    atomic_store(&env.max_query_args, 100);
    int fd;
    if (http_listen_open("127.0.0.1:0", 64, &fd, &err) < 0)
        die("listen", err.msg);
    addrlen = sizeof addr;
    if (getsockname(fd, (struct sockaddr *)&addr, &addrlen) < 0)
        die("getsockname", strerror(errno));
    http_config hc = {
        .listen_fd = fd,
        .threads = 1,
        .max_connections = 64,
        .timeout_s = 2,
        .connection_memory = 64 * 1024,
        .header_timeout_ms = 1000,
        .per_client_connections = 0,
    };
    hs = http_server_start(&env, &hc, &err);
    if (!hs)
        die("http_server_start", err.msg);
    atomic_store(&env.ready, 1);
    return 0;
}

static int64_t now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

/* Cancels and deletes every job, so accepted submissions keep reaching
 * the store instead of a full queue. */
static void trim_store(void)
{
    geo_err err = {{0}};
    job_rec *jobs = NULL;
    size_t n = 0;
    store_filter f = {.state = -1, .limit = 1000};
    if (store_list(env.s, &f, &jobs, &n, &err) < 0)
        die("store_list", err.msg);
    for (size_t i = 0; i < n; i++) {
        store_cancel(env.s, jobs[i].id, NULL, &err);
        store_remove(env.s, jobs[i].id, &err);
        job_rec_clear(&jobs[i]);
    }
    free(jobs);
}

/* The first status line of what the server answered: "HTTP/1.x NNN". */
static void check_status(const char *resp, size_t n)
{
    static int echo = -1;
    if (echo < 0)
        echo = getenv("FUZZ_HTTP_ECHO") != NULL; /* replaying by hand */
    if (echo)
        fprintf(stderr, "answer: %.*s\n", (int)(n > 12 ? 12 : n), resp);
    if (n == 0)
        return; /* closed without an answer: allowed for garbage */
    if (n < 12 || memcmp(resp, "HTTP/1.", 7) != 0 || resp[8] != ' ')
        die("answer", "not an HTTP status line");
    if (memcmp(resp + 9, "500", 3) == 0)
        die("answer", "500 Internal Server Error");
}

/* Whether resp[0..n) holds at least one whole response with a
 * Content-Length (what every finished route answers): then the client has
 * its answer and need not wait for the server's idle timeout. */
static bool answer_complete(const char *resp, size_t n)
{
    const char *end = memmem(resp, n, "\r\n\r\n", 4);
    if (!end)
        return false;
    size_t head = (size_t)(end - resp) + 4;
    for (const char *p = resp; p < end; p++) {
        if ((p == resp || p[-1] == '\n') &&
            (size_t)(end - p) > 15 && strncasecmp(p, "content-length:", 15) == 0)
            return n >= head + strtoull(p + 15, NULL, 10);
    }
    return false;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static unsigned inputs;
    if (++inputs % TRIM_EVERY == 0)
        trim_store();
    int c = socket(addr.ss_family, SOCK_STREAM | SOCK_NONBLOCK, 0);
    if (c < 0)
        die("socket", strerror(errno));
    if (connect(c, (struct sockaddr *)&addr, addrlen) < 0 &&
        errno != EINPROGRESS)
        die("connect", strerror(errno));
    static char resp[1 << 16];
    size_t got = 0, sent = 0;
    bool wr_open = true;
    int64_t deadline = now_ms() + DEADLINE_MS;
    for (;;) {
        int64_t left = deadline - now_ms();
        if (left <= 0)
            break; /* held open (an event stream, a slow path): cut it */
        /* a whole answer to all that was sent: what has already arrived
         * behind it is still read */
        bool answered = !wr_open && answer_complete(resp, got);
        if (answered && left > QUIET_MS)
            left = QUIET_MS;
        struct pollfd p = {c, POLLIN | (wr_open ? POLLOUT : 0), 0};
        int pr = poll(&p, 1, (int)left);
        if (pr < 0 && errno != EINTR)
            die("poll", strerror(errno));
        if (pr == 0 && answered)
            break;
        if (wr_open && (p.revents & POLLOUT)) {
            ssize_t w = sent < size ? send(c, data + sent, size - sent,
                                           MSG_NOSIGNAL) : 0;
            if (w > 0)
                sent += (size_t)w;
            if (sent == size || (w < 0 && errno != EAGAIN)) {
                /* the end of the request in a segment of its own: the
                 * server's edge-triggered poll sees it even when it has
                 * already read the data */
                usleep(200);
                shutdown(c, SHUT_WR);
                wr_open = false;
            }
        }
        if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
            size_t room = sizeof resp - got;
            char sink[4096];
            ssize_t r = room ? recv(c, resp + got, room, 0)
                             : recv(c, sink, sizeof sink, 0);
            if (r > 0)
                got += room ? (size_t)r : 0;
            else if (r == 0 || (errno != EAGAIN && errno != EINTR))
                break; /* the server ended the connection */
        }
    }
    check_status(resp, got);
    close(c);
    return 0;
}
