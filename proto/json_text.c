/* json_text.c — json_dumps's text, byte for byte, for documents of many
 * reals (json_text.h). jansson formats each real with snprintf("%.17g"),
 * which is most of the time of a 750-number report; here the digits come
 * from proto_decimal_format_g17's exact integer arithmetic, and the rest
 * follows jansson 2.14's dump.c: separators, indentation, string escapes,
 * the ".0" of an integral real and the exponent without '+' or leading
 * zeros. */
#include "json_text.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "decimal.h"

typedef proto_text out;

void proto_text_put(proto_text *o, const char *s, size_t n)
{
    if (o->failed)
        return;
    if (o->len + n + 1 > o->cap) {
        size_t cap = o->cap ? o->cap : 512;
        while (cap < o->len + n + 1)
            cap *= 2;
        char *t = realloc(o->s, cap);
        if (!t) {
            o->failed = true;
            return;
        }
        o->s = t;
        o->cap = cap;
    }
    memcpy(o->s + o->len, s, n);
    o->len += n;
    o->s[o->len] = '\0';
}

static void put(out *o, const char *s, size_t n)
{
    proto_text_put(o, s, n);
}

static void put_indent(out *o, size_t flags, int depth, bool space)
{
    int n = (int)(flags & JSON_MAX_INDENT);
    if (n > 0) {
        put(o, "\n", 1);
        for (int i = 0; i < depth * n; i++)
            put(o, " ", 1);
    } else if (space && !(flags & JSON_COMPACT)) {
        put(o, " ", 1);
    }
}

void proto_text_string(proto_text *o, const char *s, size_t n)
{
    put(o, "\"", 1);
    size_t run = 0;
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)s[i];
        if (c >= 0x20 && c != '"' && c != '\\')
            continue;
        put(o, s + run, i - run);
        run = i + 1;
        char esc[8];
        switch (c) {
        case '"': put(o, "\\\"", 2); break;
        case '\\': put(o, "\\\\", 2); break;
        case '\b': put(o, "\\b", 2); break;
        case '\f': put(o, "\\f", 2); break;
        case '\n': put(o, "\\n", 2); break;
        case '\r': put(o, "\\r", 2); break;
        case '\t': put(o, "\\t", 2); break;
        default:
            snprintf(esc, sizeof esc, "\\u%04X", c);
            put(o, esc, 6);
        }
    }
    put(o, s + run, n - run);
    put(o, "\"", 1);
}

/* jansson's jsonp_dtostr with precision 17. */
void proto_text_real(proto_text *o, double v)
{
    char b[PROTO_DECIMAL_MAX + 4];
    size_t n = proto_decimal_format_g17(b, v);
    if (strspn(b, "0123456789-") == n) {
        b[n++] = '.';
        b[n++] = '0';
        b[n] = '\0';
    }
    char *e = strchr(b, 'e');
    if (e) {
        char *start = e + 1, *end = start + 1;
        if (*start == '-')
            start++;
        while (*end == '0')
            end++;
        if (end != start) {
            memmove(start, end, n - (size_t)(end - b) + 1);
            n -= (size_t)(end - start);
        }
    }
    put(o, b, n);
}

static void dump(out *o, const json_t *j, size_t flags, int depth)
{
    char b[32];
    switch (json_typeof(j)) {
    case JSON_NULL: put(o, "null", 4); return;
    case JSON_TRUE: put(o, "true", 4); return;
    case JSON_FALSE: put(o, "false", 5); return;
    case JSON_INTEGER:
        put(o, b, (size_t)snprintf(b, sizeof b, "%" JSON_INTEGER_FORMAT,
                                   json_integer_value(j)));
        return;
    case JSON_REAL: proto_text_real(o, json_real_value(j)); return;
    case JSON_STRING:
        proto_text_string(o, json_string_value(j), json_string_length(j));
        return;
    case JSON_ARRAY: {
        size_t n = json_array_size(j);
        if (n == 0) {
            put(o, "[]", 2);
            return;
        }
        put(o, "[", 1);
        put_indent(o, flags, depth + 1, false);
        for (size_t i = 0; i < n; i++) {
            dump(o, json_array_get(j, i), flags, depth + 1);
            if (i + 1 < n) {
                put(o, ",", 1);
                put_indent(o, flags, depth + 1, true);
            } else {
                put_indent(o, flags, depth, false);
            }
        }
        put(o, "]", 1);
        return;
    }
    case JSON_OBJECT: {
        void *it = json_object_iter((json_t *)j);
        if (!it) {
            put(o, "{}", 2);
            return;
        }
        const char *sep = flags & JSON_COMPACT ? ":" : ": ";
        put(o, "{", 1);
        put_indent(o, flags, depth + 1, false);
        while (it) {
            const char *k = json_object_iter_key(it);
            proto_text_string(o, k, json_object_iter_key_len(it));
            put(o, sep, strlen(sep));
            dump(o, json_object_iter_value(it), flags, depth + 1);
            it = json_object_iter_next((json_t *)j, it);
            if (it) {
                put(o, ",", 1);
                put_indent(o, flags, depth + 1, true);
            } else {
                put_indent(o, flags, depth, false);
            }
        }
        put(o, "}", 1);
        return;
    }
    }
}

char *proto_json_dumps(const json_t *j, size_t flags)
{
    /* what this writer does not do itself, jansson does */
    size_t own = JSON_MAX_INDENT | JSON_COMPACT | JSON_PRESERVE_ORDER;
    if (!j || (flags & ~own) || (!json_is_object(j) && !json_is_array(j)))
        return json_dumps(j, flags);
    out o = {0};
    put(&o, "", 0);
    dump(&o, j, flags, 0);
    if (o.failed) {
        free(o.s);
        return NULL;
    }
    return o.s;
}
