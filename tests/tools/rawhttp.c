/* rawhttp.c — raw HTTP/1.1 over loopback for the hostile-client tests
 * (it connects to 127.0.0.1 only):
 *   rawhttp send PORT MS
 *       sends stdin as it is, prints the answer until the server closes
 *       or MS pass; "elapsed_ms N closed|open" on stderr; exit 0 when the
 *       server closed the connection, 3 when it was still open.
 *   rawhttp slow PORT BIND_ADDR N SECONDS
 *       opens N connections from BIND_ADDR (a 127.x.y.z address), sends
 *       the start of a request and then one header byte per second on
 *       each for SECONDS; prints "connected N closed C open O
 *       first_close_s X last_close_s Y" (closed = by the server).
 *   rawhttp replay PORT FILE COUNT THREADS
 *       sends COUNT requests, cycling through the raw requests of FILE
 *       (separated by lines "%%"), each on its own connection, from
 *       THREADS threads; prints "requests N seconds S" and one line per
 *       status "status 404 N" (000: no answer within 5 s). */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static int dial(int port, const char *bind_addr)
{
    int fd = socket(AF_INET, SOCK_STREAM, 0);
    if (fd < 0)
        return -1;
    struct sockaddr_in a = {.sin_family = AF_INET};
    if (bind_addr) {
        if (inet_pton(AF_INET, bind_addr, &a.sin_addr) != 1 ||
            (ntohl(a.sin_addr.s_addr) >> 24) != 127 ||
            bind(fd, (struct sockaddr *)&a, sizeof a) < 0) {
            close(fd);
            return -1;
        }
    }
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons((unsigned short)port);
    if (connect(fd, (struct sockaddr *)&a, sizeof a) < 0) {
        close(fd);
        return -1;
    }
    return fd;
}

static int cmd_send(int port, int ms)
{
    static char req[1 << 20];
    size_t n = fread(req, 1, sizeof req, stdin);
    int fd = dial(port, NULL);
    if (fd < 0) {
        perror("connect");
        return 1;
    }
    double t0 = now_s();
    size_t off = 0;
    while (off < n) {
        ssize_t w = send(fd, req + off, n - off, MSG_NOSIGNAL);
        if (w <= 0)
            break; /* the server may close early: read its answer */
        off += (size_t)w;
    }
    bool closed = false;
    char buf[65536];
    for (;;) {
        int left = ms - (int)((now_s() - t0) * 1000);
        if (left <= 0)
            break;
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, left) <= 0)
            break;
        ssize_t r = recv(fd, buf, sizeof buf, 0);
        if (r <= 0) {
            closed = true;
            break;
        }
        fwrite(buf, 1, (size_t)r, stdout);
    }
    fflush(stdout);
    fprintf(stderr, "elapsed_ms %d %s\n", (int)((now_s() - t0) * 1000),
            closed ? "closed" : "open");
    close(fd);
    return closed ? 0 : 3;
}

static int cmd_slow(int port, const char *bind_addr, int n, int secs)
{
    int *fd = calloc((size_t)n, sizeof *fd);
    if (!fd)
        return 1;
    static const char start[] = "GET /livez HTTP/1.1\r\nHost: x\r\nX-Slow: ";
    int connected = 0, closed = 0;
    double t0 = now_s(), first = -1, last = -1;
    for (int i = 0; i < n; i++) {
        fd[i] = dial(port, bind_addr);
        if (fd[i] < 0)
            continue;
        connected++;
        if (send(fd[i], start, sizeof start - 1, MSG_NOSIGNAL) < 0) {
            close(fd[i]);
            fd[i] = -1;
            closed++;
        }
    }
    struct pollfd *p = calloc((size_t)n, sizeof *p);
    if (!p)
        return 1;
    double next_byte = now_s() + 1;
    while (now_s() - t0 < secs) {
        int k = 0;
        for (int i = 0; i < n; i++)
            if (fd[i] >= 0)
                p[k++] = (struct pollfd){fd[i], POLLIN, 0};
        poll(p, (nfds_t)k, 100);
        for (int j = 0; j < k; j++) {
            if (!p[j].revents)
                continue;
            char b[512];
            if (recv(p[j].fd, b, sizeof b, MSG_DONTWAIT) > 0)
                continue; /* an answer (a refusal) before the close */
            for (int i = 0; i < n; i++)
                if (fd[i] == p[j].fd) {
                    close(fd[i]);
                    fd[i] = -1;
                }
            closed++;
            last = now_s() - t0;
            if (first < 0)
                first = last;
        }
        if (now_s() >= next_byte) {
            next_byte += 1;
            for (int i = 0; i < n; i++)
                if (fd[i] >= 0)
                    send(fd[i], "a", 1, MSG_NOSIGNAL);
        }
    }
    int open_now = 0;
    for (int i = 0; i < n; i++)
        if (fd[i] >= 0) {
            open_now++;
            close(fd[i]);
        }
    printf("connected %d closed %d open %d first_close_s %.1f "
           "last_close_s %.1f\n", connected, closed, open_now, first, last);
    free(p);
    free(fd);
    return 0;
}

typedef struct replay {
    int port;
    char **req;
    size_t *len;
    size_t nreq;
    long count;
    atomic_long next;
    atomic_long status[1000];
} replay;

/* One request on a new connection: its status, 0 without an answer. */
static int one(int port, const char *req, size_t len)
{
    int fd = dial(port, NULL);
    if (fd < 0)
        return 0;
    size_t off = 0;
    while (off < len) {
        ssize_t w = send(fd, req + off, len - off, MSG_NOSIGNAL);
        if (w <= 0)
            break;
        off += (size_t)w;
    }
    char buf[16384];
    size_t got = 0;
    double t0 = now_s();
    /* the status line is all that counts; the server closes or we stop */
    while (got < 12 && now_s() - t0 < 5) {
        struct pollfd p = {fd, POLLIN, 0};
        if (poll(&p, 1, 200) <= 0)
            continue;
        ssize_t r = recv(fd, buf + got, sizeof buf - got - 1, 0);
        if (r <= 0)
            break;
        got += (size_t)r;
    }
    close(fd);
    buf[got] = '\0';
    int st = 0;
    if (got >= 12 && strncmp(buf, "HTTP/1.", 7) == 0)
        st = atoi(buf + 9);
    return st > 0 && st < 1000 ? st : 0;
}

static void *replay_thread(void *arg)
{
    replay *rp = arg;
    long i;
    while ((i = atomic_fetch_add(&rp->next, 1)) < rp->count) {
        size_t k = (size_t)i % rp->nreq;
        atomic_fetch_add(&rp->status[one(rp->port, rp->req[k], rp->len[k])],
                         1);
    }
    return NULL;
}

static int cmd_replay(int port, const char *file, long count, int threads)
{
    FILE *f = fopen(file, "rb");
    if (!f) {
        perror(file);
        return 1;
    }
    static char data[8 << 20];
    size_t n = fread(data, 1, sizeof data - 1, f);
    fclose(f);
    data[n] = '\0';
    static replay rp;
    rp.port = port;
    rp.count = count;
    rp.req = calloc(4096, sizeof *rp.req);
    rp.len = calloc(4096, sizeof *rp.len);
    if (!rp.req || !rp.len)
        return 1;
    char *p = data;
    while (*p && rp.nreq < 4096) {
        char *sep = strstr(p, "\n%%\n");
        size_t l = sep ? (size_t)(sep - p) : strlen(p);
        rp.req[rp.nreq] = p;
        rp.len[rp.nreq++] = l;
        if (!sep)
            break;
        p = sep + 4;
    }
    if (!rp.nreq)
        return 1;
    pthread_t th[64];
    if (threads > 64)
        threads = 64;
    double t0 = now_s();
    for (int i = 0; i < threads; i++)
        pthread_create(&th[i], NULL, replay_thread, &rp);
    for (int i = 0; i < threads; i++)
        pthread_join(th[i], NULL);
    printf("requests %ld seconds %.1f\n", count, now_s() - t0);
    for (int s = 0; s < 1000; s++)
        if (atomic_load(&rp.status[s]))
            printf("status %03d %ld\n", s, atomic_load(&rp.status[s]));
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 6 && strcmp(argv[1], "replay") == 0)
        return cmd_replay(atoi(argv[2]), argv[3], atol(argv[4]),
                          atoi(argv[5]));
    if (argc == 4 && strcmp(argv[1], "send") == 0)
        return cmd_send(atoi(argv[2]), atoi(argv[3]));
    if (argc == 6 && strcmp(argv[1], "slow") == 0)
        return cmd_slow(atoi(argv[2]), argv[3], atoi(argv[4]),
                        atoi(argv[5]));
    fprintf(stderr, "usage: rawhttp send PORT MS < request\n"
                    "       rawhttp slow PORT BIND_ADDR N SECONDS\n"
                    "       rawhttp replay PORT FILE COUNT THREADS\n");
    return 2;
}
