/* fuzz_json_pull.c — libFuzzer target: the JSON pull tokenizer on
 * arbitrary bytes against jansson (json_loadb, JSON_REJECT_DUPLICATES):
 * both accept or both refuse with the same text, line and column, and an
 * accepted text gives equal values. Inputs with a NUL byte right after a
 * number or a literal are skipped: jansson drops that byte, the
 * tokenizer refuses it (json_pull.h). */
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "json_pull.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static json_t *build(proto_jpull *j, proto_jtok t, int depth)
{
    json_t *v = NULL;
    switch (t) {
    case PROTO_JT_OBJECT:
        v = json_object();
        for (;;) {
            proto_jtok k = proto_jpull_next(j);
            if (k == PROTO_JT_OBJECT_END)
                return v;
            if (k != PROTO_JT_KEY)
                break;
            char *key = strdup(j->str);
            json_t *e = build(j, proto_jpull_next(j), depth + 1);
            if (!e) {
                free(key);
                break;
            }
            json_object_set_new(v, key, e);
            free(key);
        }
        json_decref(v);
        return NULL;
    case PROTO_JT_ARRAY:
        v = json_array();
        for (;;) {
            proto_jtok k = proto_jpull_next(j);
            if (k == PROTO_JT_ARRAY_END)
                return v;
            json_t *e = build(j, k, depth + 1);
            if (!e)
                break;
            json_array_append_new(v, e);
        }
        json_decref(v);
        return NULL;
    case PROTO_JT_STRING:
        return json_stringn(j->str, j->str_len);
    case PROTO_JT_INTEGER:
        return json_integer(j->integer);
    case PROTO_JT_REAL:
        return json_real(j->real);
    case PROTO_JT_TRUE:
        return json_true();
    case PROTO_JT_FALSE:
        return json_false();
    case PROTO_JT_NULL:
        return json_null();
    default:
        return NULL;
    }
}

static bool nul_after_word(const uint8_t *d, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        unsigned p = d[i - 1] | 0x20;
        if (d[i] == 0 && ((d[i - 1] >= '0' && d[i - 1] <= '9') ||
                          (p >= 'a' && p <= 'z')))
            return true;
    }
    return false;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (nul_after_word(data, size))
        return 0;
    json_error_t je;
    json_t *want = json_loadb((const char *)data, size,
                              JSON_REJECT_DUPLICATES, &je);
    proto_jpull j;
    proto_jpull_init(&j, data, size);
    json_t *got = build(&j, proto_jpull_next(&j), 0);
    proto_jtok end = got ? proto_jpull_next(&j) : PROTO_JT_ERROR;
    if (want) {
        if (!got || end != PROTO_JT_END || !json_equal(want, got))
            abort();
    } else if (end != PROTO_JT_ERROR || j.error.line != je.line ||
               j.error.column != je.column ||
               strcmp(j.error.text, je.text) != 0) {
        abort();
    }
    json_decref(want);
    json_decref(got);
    proto_jpull_clear(&j);
    return 0;
}
