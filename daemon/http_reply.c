/* http_reply.c — queuing responses: JSON bodies, RFC 9457 problems,
 * conditional requests, and access to query arguments and headers.
 * Invariant: every response goes through http_reply, which records the
 * status and body size for metrics and sets the headers every response
 * carries. */
#include "http.h"

#include <ctype.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum MHD_Result http_reply(http_req *r, unsigned status, const char *ctype,
                           char *buf, size_t len, bool take_buf,
                           const char *const *headers)
{
    struct MHD_Response *resp = MHD_create_response_from_buffer(
        len, buf, take_buf ? MHD_RESPMEM_MUST_FREE : MHD_RESPMEM_PERSISTENT);
    if (!resp) {
        if (take_buf)
            free(buf);
        return MHD_NO;
    }
    if (ctype)
        MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    for (size_t i = 0; headers && headers[i] && headers[i + 1]; i += 2)
        MHD_add_response_header(resp, headers[i], headers[i + 1]);
    r->status = status;
    r->bytes_out += r->method == HTTP_HEAD ? 0 : len;
    enum MHD_Result ret = MHD_queue_response(r->conn, status, resp);
    MHD_destroy_response(resp);
    return ret;
}

/* Sends text (malloc'd, taken) with a trailing newline, which makes curl
 * output and logs readable. */
static enum MHD_Result reply_text_line(http_req *r, unsigned status,
                                       const char *ctype, char *text,
                                       const char *const *headers)
{
    size_t n = strlen(text);
    char *nl = realloc(text, n + 2);
    if (nl) {
        text = nl;
        text[n++] = '\n';
        text[n] = '\0';
    }
    return http_reply(r, status, ctype, text, n, true, headers);
}

enum MHD_Result http_reply_json(http_req *r, unsigned status, json_t *body,
                                const char *const *headers)
{
    char *text = body ? json_dumps(body, JSON_COMPACT) : NULL;
    json_decref(body);
    if (!text)
        return http_problem(r, 500, "out-of-memory", "Out of memory", NULL,
                            NULL, "the response could not be built");
    return reply_text_line(r, status, "application/json", text, headers);
}

/* Length of the well-formed UTF-8 sequence at s (RFC 3629: no overlong
 * forms, no surrogates, nothing above U+10FFFF), 0 when there is none. */
static size_t utf8_seq(const unsigned char *s)
{
    unsigned c = s[0];
    if (c < 0x80)
        return 1;
    size_t n = c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3
             : c >= 0xf0 && c <= 0xf4 ? 4 : 0;
    if (!n)
        return 0;
    unsigned lo = 0x80, hi = 0xbf;
    if (c == 0xe0)
        lo = 0xa0;
    else if (c == 0xed)
        hi = 0x9f;
    else if (c == 0xf0)
        lo = 0x90;
    else if (c == 0xf4)
        hi = 0x8f;
    if (s[1] < lo || s[1] > hi)
        return 0;
    for (size_t i = 2; i < n; i++)
        if (s[i] < 0x80 || s[i] > 0xbf)
            return 0;
    return n;
}

void http_utf8_scrub(char *dst, size_t size, const char *src)
{
    static const char hex[] = "0123456789ABCDEF";
    const unsigned char *s = (const unsigned char *)src;
    size_t o = 0;
    while (*s && size) {
        size_t n = utf8_seq(s);
        if (n) {
            if (o + n >= size)
                break;
            memcpy(dst + o, s, n);
            o += n;
            s += n;
        } else {
            if (o + 4 >= size)
                break;
            dst[o++] = '\\';
            dst[o++] = 'x';
            dst[o++] = hex[*s >> 4];
            dst[o++] = hex[*s & 15];
            s++;
        }
    }
    if (size)
        dst[o] = '\0';
}

enum MHD_Result http_problem(http_req *r, unsigned status, const char *slug,
                             const char *title, json_t *errors,
                             const char *const *headers, const char *fmt, ...)
{
    char raw[1024], detail[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(raw, sizeof raw, fmt, ap);
    va_end(ap);
    /* the detail quotes what the client sent (a URL, a header), which
     * need not be UTF-8, or may have been cut mid-character */
    http_utf8_scrub(detail, sizeof detail, raw);
    char type[96];
    snprintf(type, sizeof type, "urn:facetd:problem:%s", slug);
    json_t *o = json_pack("{s:s, s:s, s:i, s:s}", "type", type, "title", title,
                          "status", (json_int_t)status, "detail", detail);
    if (o && errors)
        json_object_set_new(o, "errors", errors);
    else
        json_decref(errors);
    char *text = o ? json_dumps(o, JSON_COMPACT) : NULL;
    json_decref(o);
    if (!text) {
        static const char oom[] = "{\"type\":\"urn:facetd:problem:out-of-"
                                  "memory\",\"title\":\"Out of memory\","
                                  "\"status\":500}\n";
        return http_reply(r, 500, "application/problem+json", (char *)oom,
                          sizeof oom - 1, false, NULL);
    }
    return reply_text_line(r, status, "application/problem+json", text,
                           headers);
}

enum MHD_Result http_malformed_json(http_req *r, const proto_jerror *je)
{
    if (je->code == -ENOMEM)
        return http_problem(r, 500, "out-of-memory", "Internal Server Error",
                            NULL, NULL, "out of memory reading the body");
    json_t *errors = json_pack("[{s:s, s:s, s:i, s:i}]", "path", "",
                               "message", je->text, "line",
                               (json_int_t)je->line, "column",
                               (json_int_t)je->column);
    return http_problem(r, 400, "malformed-json", "Bad Request", errors, NULL,
                        "line %d, column %d: %s", je->line, je->column,
                        je->text);
}

json_t *http_error_entry(const char *msg)
{
    /* A place is a run of path characters before ": ". */
    const char *sep = strstr(msg, ": ");
    size_t plen = 0;
    if (sep) {
        plen = (size_t)(sep - msg);
        for (size_t i = 0; i < plen; i++) {
            char c = msg[i];
            if (!(isalnum((unsigned char)c) || c == '_' || c == '.' ||
                  c == '[' || c == ']' || c == '-')) {
                plen = 0;
                break;
            }
        }
    }
    char clean[2048];
    http_utf8_scrub(clean, sizeof clean, plen ? sep + 2 : msg);
    json_t *path = json_stringn(msg, plen);
    json_t *m = json_string(clean);
    json_t *o = json_object();
    if (!o || !path || !m || json_object_set_new(o, "path", path) < 0 ||
        json_object_set_new(o, "message", m) < 0) {
        json_decref(o);
        return NULL;
    }
    return o;
}

/* Compares an entity tag list (If-None-Match) with etag, weakly: W/ is
 * ignored on both sides (RFC 9110 §13.1.2). */
bool http_not_modified(http_req *r, const char *etag)
{
    const char *inm = http_header(r, MHD_HTTP_HEADER_IF_NONE_MATCH);
    if (!inm)
        return false;
    const char *e = etag;
    if (strncmp(e, "W/", 2) == 0)
        e += 2;
    size_t elen = strlen(e);
    const char *p = inm;
    while (*p) {
        while (*p == ' ' || *p == '\t' || *p == ',')
            p++;
        if (*p == '*')
            return true;
        if (strncmp(p, "W/", 2) == 0)
            p += 2;
        if (*p != '"')
            return false;
        const char *end = strchr(p + 1, '"');
        if (!end)
            return false;
        if ((size_t)(end + 1 - p) == elen && memcmp(p, e, elen) == 0)
            return true;
        p = end + 1;
    }
    return false;
}

const char *http_arg(http_req *r, const char *name)
{
    return MHD_lookup_connection_value(r->conn, MHD_GET_ARGUMENT_KIND, name);
}

const char *http_header(http_req *r, const char *name)
{
    return MHD_lookup_connection_value(r->conn, MHD_HEADER_KIND, name);
}
