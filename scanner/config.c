/* config.c — parsing the list of scanner VID:PID:transport entries. */
#include "config.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

const char *scan_kind_name(scan_kind kind)
{
    return kind == SCAN_KIND_HID ? "hid" : "bulk";
}

/* Parses 1..4 hex digits at s[0 .. n). */
static bool parse_hex16(const char *s, size_t n, uint16_t *ret)
{
    if (n == 0 || n > 4)
        return false;
    unsigned v = 0;
    for (size_t i = 0; i < n; i++) {
        int c = (unsigned char)s[i];
        if (!isxdigit(c))
            return false;
        v = v * 16 + (unsigned)(isdigit(c) ? c - '0' : tolower(c) - 'a' + 10);
    }
    *ret = (uint16_t)v;
    return true;
}

static int parse_span(const char *s, size_t n, scan_match *ret, geo_err *err)
{
    while (n > 0 && isspace((unsigned char)*s)) {
        s++;
        n--;
    }
    while (n > 0 && isspace((unsigned char)s[n - 1]))
        n--;
    const char *c1 = memchr(s, ':', n);
    const char *c2 = c1 ? memchr(c1 + 1, ':', n - (size_t)(c1 + 1 - s)) : NULL;
    if (!c1 || !c2)
        return geo_err_set(err, -EINVAL,
                           "\"%.*s\": expected VID:PID:bulk or VID:PID:hid",
                           (int)n, s);
    scan_match m;
    if (!parse_hex16(s, (size_t)(c1 - s), &m.vid))
        return geo_err_set(err, -EINVAL,
                           "\"%.*s\": vendor id must be 1 to 4 hex digits",
                           (int)n, s);
    if (!parse_hex16(c1 + 1, (size_t)(c2 - c1 - 1), &m.pid))
        return geo_err_set(err, -EINVAL,
                           "\"%.*s\": product id must be 1 to 4 hex digits",
                           (int)n, s);
    const char *k = c2 + 1;
    size_t kn = n - (size_t)(k - s);
    if (kn == 4 && strncasecmp(k, "bulk", 4) == 0)
        m.kind = SCAN_KIND_BULK;
    else if (kn == 3 && strncasecmp(k, "hid", 3) == 0)
        m.kind = SCAN_KIND_HID;
    else
        return geo_err_set(err, -EINVAL,
                           "\"%.*s\": transport must be bulk or hid", (int)n,
                           s);
    *ret = m;
    return 0;
}

int scan_match_parse(const char *s, scan_match *ret, geo_err *err)
{
    return parse_span(s, strlen(s), ret, err);
}

int scan_match_list_parse(const char *s, scan_match *ret, size_t cap,
                          size_t *ret_n, geo_err *err)
{
    scan_match tmp[SCAN_MATCH_MAX];
    size_t n = 0;
    const char *p = s;
    for (;;) {
        while (*p == ',' || isspace((unsigned char)*p))
            p++;
        if (!*p)
            break;
        size_t len = strcspn(p, ", \t\r\n");
        if (n == cap || n == SCAN_MATCH_MAX)
            return geo_err_set(err, -EINVAL, "devices[%zu]: more than %zu "
                               "entries", n, cap < SCAN_MATCH_MAX ? cap :
                               (size_t)SCAN_MATCH_MAX);
        int r = parse_span(p, len, &tmp[n], err);
        if (r < 0) {
            char where[32];
            snprintf(where, sizeof where, "devices[%zu]", n);
            geo_err_prefix(err, where);
            return r;
        }
        for (size_t i = 0; i < n; i++)
            if (tmp[i].vid == tmp[n].vid && tmp[i].pid == tmp[n].pid)
                return geo_err_set(err, -EINVAL,
                                   "devices[%zu]: %04x:%04x already listed "
                                   "as devices[%zu]", n, tmp[n].vid,
                                   tmp[n].pid, i);
        n++;
        p += len;
    }
    if (n == 0)
        return geo_err_set(err, -EINVAL, "devices: empty list");
    memcpy(ret, tmp, n * sizeof *ret);
    *ret_n = n;
    return 0;
}

const scan_match *scan_match_find(const scan_match *list, size_t n,
                                  uint16_t vid, uint16_t pid, scan_kind kind)
{
    for (size_t i = 0; i < n; i++)
        if (list[i].vid == vid && list[i].pid == pid && list[i].kind == kind)
            return &list[i];
    return NULL;
}
