/* loadgen.c — a small closed-loop load generator for facetd's job API,
 * used by tests/bench/bench_http.sh. Each client thread keeps one HTTP/1.1
 * connection to 127.0.0.1 (and nothing else: it refuses other hosts) and
 * repeats a job's round trip:
 *   flow    POST /v1/jobs, GET /v1/jobs/{id}?wait=60, GET .../stats
 *   submit  POST /v1/jobs only
 * until the duration or the job count is reached, then prints
 *   jobs: N, jobs_per_s: X, job_p50_ms: X, job_p99_ms: X, errors: N
 * (job latency = the whole round trip of one job).
 *
 * usage: loadgen PORT BODY_FILE CLIENTS SECONDS [MAX_JOBS] [flow|submit] */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

typedef struct shared {
    int port;
    const char *body;
    size_t body_len;
    double end;          /* monotonic seconds */
    long max_jobs;
    int flow;
    atomic_long started, done, errors;
} shared;

typedef struct client {
    shared *sh;
    int fd;
    char *buf;
    size_t cap;
    double *lat;         /* job latencies, ms */
    size_t nlat, caplat;
} client;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static int dial(client *c)
{
    if (c->fd >= 0)
        close(c->fd);
    c->fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    struct sockaddr_in sa = {.sin_family = AF_INET,
                             .sin_port = htons((uint16_t)c->sh->port)};
    sa.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    int one = 1;
    setsockopt(c->fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    return connect(c->fd, (struct sockaddr *)&sa, sizeof sa);
}

static int send_all(int fd, const char *p, size_t n)
{
    while (n) {
        ssize_t w = send(fd, p, n, MSG_NOSIGNAL);
        if (w <= 0)
            return -1;
        p += w;
        n -= (size_t)w;
    }
    return 0;
}

/* Reads one response into c->buf; returns the status, -1 on error. The
 * body starts at *ret_body and is NUL-terminated. */
static int read_response(client *c, char **ret_body)
{
    size_t len = 0;
    char *hdr_end = NULL;
    long clen = -1;
    for (;;) {
        if (len + 65536 + 1 > c->cap) {
            c->cap = (len + 65536 + 1) * 2;
            c->buf = realloc(c->buf, c->cap);
        }
        ssize_t r = recv(c->fd, c->buf + len, c->cap - len - 1, 0);
        if (r <= 0)
            return -1;
        len += (size_t)r;
        c->buf[len] = '\0';
        if (!hdr_end && (hdr_end = strstr(c->buf, "\r\n\r\n"))) {
            const char *cl = strcasestr(c->buf, "\r\nContent-Length:");
            if (!cl || cl > hdr_end)
                return -1;
            clen = strtol(cl + 17, NULL, 10);
        }
        if (hdr_end && (long)(len - (size_t)(hdr_end + 4 - c->buf)) >= clen)
            break;
    }
    *ret_body = hdr_end + 4;
    return (int)strtol(c->buf + 9, NULL, 10);
}

static int request(client *c, const char *method, const char *path,
                   const char *body, size_t blen, char **ret_body)
{
    char head[512];
    int n = snprintf(head, sizeof head,
                     "%s %s HTTP/1.1\r\nHost: 127.0.0.1\r\n%s"
                     "Content-Length: %zu\r\n\r\n", method, path,
                     body ? "Content-Type: application/json\r\n" : "", blen);
    for (int attempt = 0; attempt < 2; attempt++) {
        if (send_all(c->fd, head, (size_t)n) == 0 &&
            (!body || send_all(c->fd, body, blen) == 0)) {
            int st = read_response(c, ret_body);
            if (st > 0)
                return st;
        }
        if (dial(c) < 0)
            return -1;
    }
    return -1;
}

static void *run(void *arg)
{
    client *c = arg;
    shared *sh = c->sh;
    c->fd = -1;
    if (dial(c) < 0) {
        atomic_fetch_add(&sh->errors, 1);
        return NULL;
    }
    while (now() < sh->end) {
        if (sh->max_jobs && atomic_fetch_add(&sh->started, 1) >= sh->max_jobs)
            break;
        double t0 = now();
        char *b;
        int st = request(c, "POST", "/v1/jobs", sh->body, sh->body_len, &b);
        char *idp = st == 202 ? strstr(b, "\"id\":\"") : NULL;
        if (!idp) {
            atomic_fetch_add(&sh->errors, 1);
            continue;
        }
        char id[27];
        memcpy(id, idp + 6, 26);
        id[26] = '\0';
        if (sh->flow) {
            char path[96];
            snprintf(path, sizeof path, "/v1/jobs/%s?wait=60", id);
            st = request(c, "GET", path, NULL, 0, &b);
            if (st != 200 || !strstr(b, "\"state\":\"succeeded\"")) {
                atomic_fetch_add(&sh->errors, 1);
                continue;
            }
            snprintf(path, sizeof path, "/v1/jobs/%s/stats", id);
            if (request(c, "GET", path, NULL, 0, &b) != 200) {
                atomic_fetch_add(&sh->errors, 1);
                continue;
            }
        }
        if (c->nlat == c->caplat) {
            c->caplat = c->caplat ? 2 * c->caplat : 1024;
            c->lat = realloc(c->lat, c->caplat * sizeof *c->lat);
        }
        c->lat[c->nlat++] = (now() - t0) * 1e3;
        atomic_fetch_add(&sh->done, 1);
    }
    close(c->fd);
    return NULL;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: loadgen PORT BODY_FILE CLIENTS SECONDS "
                        "[MAX_JOBS] [flow|submit]\n");
        return 2;
    }
    shared sh = {.port = atoi(argv[1])};
    FILE *f = fopen(argv[2], "rb");
    if (!f) {
        perror(argv[2]);
        return 2;
    }
    fseek(f, 0, SEEK_END);
    sh.body_len = (size_t)ftell(f);
    rewind(f);
    char *body = malloc(sh.body_len);
    if (fread(body, 1, sh.body_len, f) != sh.body_len) {
        perror(argv[2]);
        return 2;
    }
    fclose(f);
    sh.body = body;
    int nclients = atoi(argv[3]);
    double secs = atof(argv[4]);
    sh.max_jobs = argc > 5 ? atol(argv[5]) : 0;
    sh.flow = argc > 6 ? strcmp(argv[6], "submit") != 0 : 1;
    if (nclients < 1 || secs <= 0 || sh.port <= 0) {
        fprintf(stderr, "loadgen: bad arguments\n");
        return 2;
    }
    double t0 = now();
    sh.end = t0 + secs;
    client *cs = calloc((size_t)nclients, sizeof *cs);
    pthread_t *th = calloc((size_t)nclients, sizeof *th);
    for (int i = 0; i < nclients; i++) {
        cs[i].sh = &sh;
        pthread_create(&th[i], NULL, run, &cs[i]);
    }
    size_t total = 0;
    for (int i = 0; i < nclients; i++) {
        pthread_join(th[i], NULL);
        total += cs[i].nlat;
    }
    double elapsed = now() - t0;
    double *all = malloc((total ? total : 1) * sizeof *all);
    size_t k = 0;
    for (int i = 0; i < nclients; i++) {
        memcpy(all + k, cs[i].lat, cs[i].nlat * sizeof *all);
        k += cs[i].nlat;
        free(cs[i].lat);
        free(cs[i].buf);
    }
    qsort(all, total, sizeof *all, cmp);
    printf("jobs: %zu\n", total);
    printf("jobs_per_s: %.1f\n", (double)total / elapsed);
    printf("job_p50_ms: %.2f\n", total ? all[total / 2] : 0.0);
    printf("job_p99_ms: %.2f\n", total ? all[(size_t)((double)total * 0.99)] : 0.0);
    printf("errors: %ld\n", atomic_load(&sh.errors));
    free(all);
    free(cs);
    free(th);
    free(body);
    return atomic_load(&sh.errors) ? 1 : 0;
}
