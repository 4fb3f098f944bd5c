/* job_text.c — the job's JSON view written straight as text, byte for
 * byte what json_dumps(job_to_json(r), JSON_COMPACT) gives (job.h).
 *
 * Why: GET /v1/jobs/{id} is the most frequent request; through jansson
 * each one parsed the stored pipeline and summary into trees only to
 * print them again, a quarter of the route's CPU time. Here the stored
 * texts (compact JSON the daemon itself wrote) are copied as they are,
 * after a check that they are one JSON value (the pull tokenizer, no
 * tree); a text that is not is written as a string, as job_to_json does.
 * Strings are escaped and reals printed as jansson does (%.17g, ".0"
 * added to integral values, no '+' or leading zeros in the exponent),
 * which tests/unit/test_job_text.c checks against jansson. */
#include "job.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "json_pull.h"

typedef struct text {
    char *s;
    size_t len, cap;
    bool failed;
} text;

static void put(text *t, const char *s, size_t n)
{
    if (t->failed)
        return;
    if (t->len + n + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 512;
        while (cap < t->len + n + 1)
            cap *= 2;
        char *p = realloc(t->s, cap);
        if (!p) {
            t->failed = true;
            return;
        }
        t->s = p;
        t->cap = cap;
    }
    memcpy(t->s + t->len, s, n);
    t->len += n;
    t->s[t->len] = '\0';
}

static void puts_(text *t, const char *s)
{
    put(t, s, strlen(s));
}

/* A JSON string as jansson writes it without JSON_ENSURE_ASCII and
 * JSON_ESCAPE_SLASH: quotes, backslashes and control characters
 * escaped, everything else as it is. */
static void put_string(text *t, const char *s)
{
    put(t, "\"", 1);
    const char *run = s;
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c >= 0x20 && c != '"' && c != '\\')
            continue;
        put(t, run, (size_t)(s - run));
        char esc[8];
        switch (c) {
        case '"': puts_(t, "\\\""); break;
        case '\\': puts_(t, "\\\\"); break;
        case '\b': puts_(t, "\\b"); break;
        case '\f': puts_(t, "\\f"); break;
        case '\n': puts_(t, "\\n"); break;
        case '\r': puts_(t, "\\r"); break;
        case '\t': puts_(t, "\\t"); break;
        default:
            snprintf(esc, sizeof esc, "\\u%04X", c);
            puts_(t, esc);
        }
        run = s + 1;
    }
    put(t, run, (size_t)(s - run));
    put(t, "\"", 1);
}

/* A real as jansson's jsonp_dtostr with precision 17. */
static void put_real(text *t, double v)
{
    char buf[40];
    int n = snprintf(buf, sizeof buf, "%.17g", v);
    if (n < 0 || (size_t)n >= sizeof buf - 3) {
        t->failed = true;
        return;
    }
    if (!strchr(buf, '.') && !strchr(buf, 'e'))
        strcat(buf, ".0");
    char *e = strchr(buf, 'e');
    if (e) {
        char *start = e + 1, *end = start + 1;
        if (*start == '-')
            start++;
        while (*end == '0')
            end++;
        if (end != start)
            memmove(start, end, strlen(end) + 1);
    }
    puts_(t, buf);
}

static void put_int(text *t, long long v)
{
    char buf[24];
    snprintf(buf, sizeof buf, "%lld", v);
    puts_(t, buf);
}

static void put_key(text *t, const char *key)
{
    put(t, t->len > 1 ? ",\"" : "\"", t->len > 1 ? 2 : 1);
    puts_(t, key);
    put(t, "\":", 2);
}

static void put_time(text *t, const char *key, int64_t ms)
{
    put_key(t, key);
    if (!ms) {
        puts_(t, "null");
        return;
    }
    char buf[40];
    job_time_format(ms, buf, sizeof buf);
    put_string(t, buf);
}

/* Whether s is exactly one JSON object or array (what the store keeps). */
static bool one_json_value(const char *s)
{
    proto_jpull j;
    proto_jpull_init(&j, s, strlen(s));
    proto_jtok k = proto_jpull_next(&j);
    bool ok = (k == PROTO_JT_OBJECT || k == PROTO_JT_ARRAY) &&
              proto_jpull_skip(&j) != PROTO_JT_ERROR &&
              proto_jpull_next(&j) == PROTO_JT_END;
    proto_jpull_clear(&j);
    return ok;
}

static void put_embedded(text *t, const char *key, const char *s)
{
    put_key(t, key);
    if (!s)
        puts_(t, "null");
    else if (one_json_value(s))
        puts_(t, s);
    else
        put_string(t, s);
}

char *job_to_text(const job_rec *r, size_t *ret_len)
{
    text t = {0};
    put(&t, "{", 1);
    put_key(&t, "id");
    put_string(&t, r->id);
    put_key(&t, "state");
    const char *state = job_state_name(r->state);
    if (!state)
        t.failed = true;
    else
        put_string(&t, state);
    put_key(&t, "progress");
    put_real(&t, r->progress);
    put_key(&t, "priority");
    put_string(&t, r->priority == JOB_PRIO_HIGH ? "high" : "normal");
    put_key(&t, "source");
    put_string(&t, r->source);
    put_key(&t, "label");
    put_string(&t, r->label);
    if (r->node[0]) {
        put_key(&t, "node");
        put_string(&t, r->node);
    }
    put_embedded(&t, "pipeline", r->pipeline);
    put_time(&t, "created", r->created_ms);
    put_time(&t, "started", r->started_ms);
    put_time(&t, "finished", r->finished_ms);
    put_key(&t, "attempts");
    put_int(&t, r->attempts);
    put_key(&t, "cancel_requested");
    puts_(&t, r->cancel_requested ? "true" : "false");
    put_key(&t, "error");
    if (r->error)
        put_string(&t, r->error);
    else
        puts_(&t, "null");
    put_embedded(&t, "summary", r->summary);
    put_key(&t, "version");
    put_int(&t, (long long)r->version);
    char path[64];
    snprintf(path, sizeof path, "/v1/jobs/%s", r->id);
    put_key(&t, "links");
    puts_(&t, "{\"self\":");
    put_string(&t, path);
    if (r->state == JOB_SUCCEEDED) {
        puts_(&t, ",\"model\":\"");
        puts_(&t, path);
        puts_(&t, "/model\",\"stats\":\"");
        puts_(&t, path);
        puts_(&t, "/stats\"");
    }
    puts_(&t, ",\"events\":\"");
    puts_(&t, path);
    puts_(&t, "/events\"}}");
    if (t.failed) {
        free(t.s);
        return NULL;
    }
    if (ret_len)
        *ret_len = t.len;
    return t.s;
}
