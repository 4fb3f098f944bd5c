/* job.c — job states, ids, times and the JSON view of a job (job.h). */
#include "job.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <time.h>

static const char *const state_names[JOB_NSTATES] = {
    "queued", "running", "succeeded", "failed", "canceled",
};

void job_rec_clear(job_rec *r)
{
    if (!r)
        return;
    free(r->pipeline);
    free(r->error);
    free(r->summary);
    memset(r, 0, sizeof *r);
}

const char *job_state_name(job_state s)
{
    return (unsigned)s < JOB_NSTATES ? state_names[s] : NULL;
}

int job_state_from_name(const char *s)
{
    for (int i = 0; s && i < JOB_NSTATES; i++)
        if (strcmp(s, state_names[i]) == 0)
            return i;
    return -1;
}

bool job_state_terminal(job_state s)
{
    return s == JOB_SUCCEEDED || s == JOB_FAILED || s == JOB_CANCELED;
}

static const char b32[] = "0123456789ABCDEFGHJKMNPQRSTVWXYZ";

static void fallback_random(unsigned char *buf, size_t n)
{
    static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
    static uint64_t state;
    pthread_mutex_lock(&lock);
    if (!state) {
        struct timespec ts;
        clock_gettime(CLOCK_MONOTONIC, &ts);
        state = (uint64_t)ts.tv_nsec ^ ((uint64_t)ts.tv_sec << 32) ^
                (uint64_t)(uintptr_t)&ts;
    }
    for (size_t i = 0; i < n; i++) {
        uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        buf[i] = (unsigned char)(z ^ (z >> 31));
    }
    pthread_mutex_unlock(&lock);
}

void job_id_new(char ret[JOB_ID_LEN + 1], int64_t now_ms)
{
    unsigned char rnd[10];
    if (getrandom(rnd, sizeof rnd, GRND_NONBLOCK) != (ssize_t)sizeof rnd)
        fallback_random(rnd, sizeof rnd);
    /* 128 bits: 48 of time, 80 random; 26 digits of 5 bits (130 bits,
     * the top two always zero as in ULID). */
    unsigned char bits[16];
    uint64_t t = (uint64_t)now_ms;
    for (int i = 0; i < 6; i++)
        bits[i] = (unsigned char)(t >> (40 - 8 * i));
    memcpy(bits + 6, rnd, sizeof rnd);
    for (int d = 0; d < JOB_ID_LEN; d++) {
        int bit = 130 - 5 * (d + 1); /* position of this digit's low bit */
        unsigned v = 0;
        for (int b = 4; b >= 0; b--) {
            int pos = bit + b; /* bit index from the least significant */
            unsigned one = 0;
            if (pos < 128) {
                int byte = 15 - pos / 8;
                one = (bits[byte] >> (pos % 8)) & 1u;
            }
            v = (v << 1) | one;
        }
        ret[d] = b32[v];
    }
    ret[JOB_ID_LEN] = '\0';
}

bool job_id_valid(const char *s)
{
    if (!s || strlen(s) != JOB_ID_LEN)
        return false;
    for (const char *p = s; *p; p++)
        if (!strchr(b32, *p))
            return false;
    return s[0] <= '7';
}

int64_t job_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

int64_t job_mono_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000 + ts.tv_nsec / 1000000;
}

void job_time_format(int64_t ms, char *buf, size_t size)
{
    time_t s = (time_t)(ms / 1000);
    struct tm tm;
    gmtime_r(&s, &tm);
    snprintf(buf, size, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ",
             tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour,
             tm.tm_min, tm.tm_sec, (int)(ms % 1000));
}

static int set_time(json_t *o, const char *key, int64_t ms)
{
    if (!ms)
        return json_object_set_new(o, key, json_null());
    char buf[40];
    job_time_format(ms, buf, sizeof buf);
    return json_object_set_new(o, key, json_string(buf));
}

/* Parsed JSON text or, if it does not parse (it always should: the store
 * only keeps what the daemon wrote), the text as a string. */
static json_t *embedded(const char *text)
{
    if (!text)
        return json_null();
    json_t *v = json_loads(text, JSON_DECODE_ANY, NULL);
    return v ? v : json_string(text);
}

json_t *job_to_json(const job_rec *r)
{
    json_t *o = json_object();
    if (!o)
        return NULL;
    char path[64];
    snprintf(path, sizeof path, "/v1/jobs/%s", r->id);
    json_t *links = json_object();
    int e = 0;
    e |= json_object_set_new(o, "id", json_string(r->id));
    e |= json_object_set_new(o, "state",
                             json_string(job_state_name(r->state)));
    e |= json_object_set_new(o, "progress", json_real(r->progress));
    e |= json_object_set_new(
        o, "priority",
        json_string(r->priority == JOB_PRIO_HIGH ? "high" : "normal"));
    e |= json_object_set_new(o, "source", json_string(r->source));
    e |= json_object_set_new(o, "label", json_string(r->label));
    if (r->node[0])
        e |= json_object_set_new(o, "node", json_string(r->node));
    e |= json_object_set_new(o, "pipeline", embedded(r->pipeline));
    e |= set_time(o, "created", r->created_ms);
    e |= set_time(o, "started", r->started_ms);
    e |= set_time(o, "finished", r->finished_ms);
    e |= json_object_set_new(o, "attempts", json_integer(r->attempts));
    e |= json_object_set_new(o, "cancel_requested",
                             json_boolean(r->cancel_requested));
    e |= json_object_set_new(o, "error",
                             r->error ? json_string(r->error) : json_null());
    e |= json_object_set_new(o, "summary", embedded(r->summary));
    e |= json_object_set_new(o, "version", json_integer(r->version));
    if (!links) {
        json_decref(o);
        return NULL;
    }
    e |= json_object_set_new(links, "self", json_string(path));
    if (r->state == JOB_SUCCEEDED) {
        char p2[80];
        snprintf(p2, sizeof p2, "%s/model", path);
        e |= json_object_set_new(links, "model", json_string(p2));
        snprintf(p2, sizeof p2, "%s/stats", path);
        e |= json_object_set_new(links, "stats", json_string(p2));
    }
    char p3[80];
    snprintf(p3, sizeof p3, "%s/events", path);
    e |= json_object_set_new(links, "events", json_string(p3));
    e |= json_object_set_new(o, "links", links);
    if (e) {
        json_decref(o);
        return NULL;
    }
    return o;
}

uint64_t job_hash64(const void *data, size_t n)
{
    const unsigned char *p = data;
    uint64_t h = 0xcbf29ce484222325ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 0x100000001b3ULL;
    }
    return h;
}

uint64_t job_digest64(const void *data, size_t n)
{
    const unsigned char *p = data;
    uint64_t h = 0x9E3779B97F4A7C15u ^ n;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        uint64_t w;
        memcpy(&w, p + i, 8);
        h = (h ^ w) * 0xff51afd7ed558ccdu;
        h ^= h >> 29;
    }
    uint64_t tail = 0;
    for (; i < n; i++)
        tail = tail << 8 | p[i];
    h = (h ^ tail) * 0xc4ceb9fe1a85ec53u;
    return h ^ h >> 32;
}
