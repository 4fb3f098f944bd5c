/* job_text.c — the job's JSON view written straight as text, byte for
 * byte what json_dumps(job_to_json(r), JSON_COMPACT) gives (job.h).
 *
 * Why: GET /v1/jobs/{id} is the most frequent request; through jansson
 * each one parsed the stored pipeline and summary into trees only to
 * print them again, a quarter of the route's CPU time. Here the stored
 * texts (compact JSON the daemon itself wrote) are copied as they are,
 * after a check that they are one JSON value (the pull tokenizer, no
 * tree); a text that is not is written as a string, as job_to_json does.
 * Strings are escaped and reals printed as jansson does
 * (proto/json_text.h), which tests/unit/test_job_text.c checks against
 * jansson. */
#include "job.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "json_pull.h"
#include "json_text.h"

typedef proto_text text;

static void put(text *t, const char *s, size_t n)
{
    proto_text_put(t, s, n);
}

static void puts_(text *t, const char *s)
{
    put(t, s, strlen(s));
}

static void put_string(text *t, const char *s)
{
    proto_text_string(t, s, strlen(s));
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
    proto_text_real(&t, r->progress);
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
