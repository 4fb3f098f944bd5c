/* points_json.c — JSON point lists in, classification names out (see
 * points_json.h). Reading goes through the pull tokenizer
 * (proto/json_pull.h) straight into the coordinate array: a million
 * points are 35 MB of text, which as a tree of values took ten times
 * that memory and most of `facet inside`'s time. Writing is direct
 * text, a million answers being a few megabytes. */
#include "points_json.h"

#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "inside.h"
#include "json_pull.h"
#include "model_io.h"

/* The reader's state: the points so far and the first error that is not
 * a syntax error (reported only if the whole text is valid JSON, as a
 * parse into a tree would). */
typedef struct points_reader {
    proto_jpull j;
    size_t max, n, cap;
    double (*pts)[3];
    int code; /* 0, or the first error: -EINVAL, -ERANGE, -ENOMEM */
    char msg[sizeof(((geo_err *)0)->msg)];
} points_reader;

static void fail(points_reader *r, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void fail(points_reader *r, int code, const char *fmt, ...)
{
    if (r->code)
        return;
    r->code = code;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->msg, sizeof r->msg, fmt, ap);
    va_end(ap);
}

static bool is_number(proto_jtok t)
{
    return t == PROTO_JT_INTEGER || t == PROTO_JT_REAL;
}

/* One element of the list, whose first token t was just read. False on a
 * syntax error. */
static bool read_point(points_reader *r, proto_jtok t, size_t i)
{
    if (t != PROTO_JT_ARRAY) {
        fail(r, -EINVAL, "points[%zu]: expected an array of 3 numbers", i);
        return proto_jpull_skip(&r->j) != PROTO_JT_ERROR;
    }
    double xyz[3] = {0, 0, 0};
    size_t k = 0, bad = SIZE_MAX;
    while ((t = proto_jpull_next(&r->j)) != PROTO_JT_ARRAY_END) {
        if (t == PROTO_JT_ERROR)
            return false;
        if (!is_number(t)) {
            if (bad == SIZE_MAX)
                bad = k;
            if (proto_jpull_skip(&r->j) == PROTO_JT_ERROR)
                return false;
        } else if (k < 3) {
            xyz[k] = t == PROTO_JT_INTEGER ? (double)r->j.integer : r->j.real;
        }
        k++;
    }
    if (k != 3)
        fail(r, -EINVAL, "points[%zu]: expected 3 numbers, got %zu", i, k);
    else if (bad != SIZE_MAX)
        fail(r, -EINVAL, "points[%zu][%zu]: expected a number", i, bad);
    else if (!r->code && i < r->max) {
        if (r->n == r->cap) {
            size_t cap = r->cap ? 2 * r->cap : 1024;
            if (cap > r->max)
                cap = r->max;
            void *p = realloc(r->pts, cap * sizeof *r->pts);
            if (!p) {
                fail(r, -ENOMEM, "points: out of memory");
                return true;
            }
            r->pts = p;
            r->cap = cap;
        }
        memcpy(r->pts[r->n++], xyz, sizeof xyz);
    }
    return true;
}

/* The list, its '[' just read: every element is read (and counted) to
 * the end, so that the count limit is reported before any element's
 * error, as it is checked first. False on a syntax error. */
static bool read_list(points_reader *r)
{
    size_t i = 0;
    proto_jtok t;
    while ((t = proto_jpull_next(&r->j)) != PROTO_JT_ARRAY_END) {
        if (t == PROTO_JT_ERROR || !read_point(r, t, i))
            return false;
        i++;
    }
    if (i > r->max) {
        r->code = 0; /* the limit comes first */
        fail(r, -ERANGE, "points: %zu points exceed the limit of %zu", i,
             r->max);
    }
    return true;
}

/* The document: a list, or an object with a "points" list. False on a
 * syntax error. */
static bool read_document(points_reader *r)
{
    proto_jtok t = proto_jpull_next(&r->j);
    if (t == PROTO_JT_ARRAY)
        return read_list(r);
    if (t != PROTO_JT_OBJECT)
        return t != PROTO_JT_ERROR;
    bool found = false;
    while ((t = proto_jpull_next(&r->j)) == PROTO_JT_KEY) {
        bool points = strcmp(r->j.str, "points") == 0;
        t = proto_jpull_next(&r->j);
        if (t == PROTO_JT_ERROR)
            return false;
        if (!points) {
            if (proto_jpull_skip(&r->j) == PROTO_JT_ERROR)
                return false;
            continue;
        }
        found = true;
        if (t == PROTO_JT_ARRAY) {
            if (!read_list(r))
                return false;
        } else {
            fail(r, -EINVAL, "points: expected an array");
            if (proto_jpull_skip(&r->j) == PROTO_JT_ERROR)
                return false;
        }
    }
    if (t == PROTO_JT_ERROR)
        return false;
    if (!found)
        fail(r, -EINVAL, "points: missing");
    return true;
}

int proto_points_read_mem(const void *data, size_t len, size_t max_points,
                          double (**ret_pts)[3], size_t *ret_n, geo_err *err)
{
    points_reader r = {.max = max_points ? max_points : PROTO_POINTS_MAX};
    proto_jpull_init(&r.j, data, len);
    bool ok = read_document(&r);
    /* the rest of the text: the tokenizer checks it is only whitespace */
    if (ok && proto_jpull_next(&r.j) == PROTO_JT_ERROR)
        ok = false;
    int rc;
    if (!ok)
        rc = geo_err_set(err, r.j.error.code, "line %d, column %d: %s",
                         r.j.error.line, r.j.error.column, r.j.error.text);
    else if (r.code)
        rc = geo_err_set(err, r.code, "%s", r.msg);
    else {
        *ret_pts = r.n ? r.pts : NULL;
        *ret_n = r.n;
        r.pts = r.n ? NULL : r.pts;
        rc = 0;
    }
    free(r.pts);
    proto_jpull_clear(&r.j);
    return rc;
}

int proto_points_read_file(const char *path, size_t max_points,
                           double (**ret_pts)[3], size_t *ret_n, geo_err *err)
{
    bool is_stdin = strcmp(path, "-") == 0;
    int fd = is_stdin ? STDIN_FILENO : open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return geo_err_set(err, -errno, "%s: %s", path, strerror(errno));
    char *data = NULL;
    size_t len = 0;
    int r = proto_read_fd_all(fd, PROTO_POINTS_MAX_BYTES, &data, &len, err);
    if (!is_stdin)
        close(fd);
    if (r == 0)
        r = proto_points_read_mem(data, len, max_points, ret_pts, ret_n, err);
    free(data);
    if (r != 0)
        geo_err_prefix(err, path);
    return r;
}

const char *proto_loc_name(int loc)
{
    switch (loc) {
    case GEO_LOC_INSIDE:
        return "inside";
    case GEO_LOC_BOUNDARY:
        return "boundary";
    case GEO_LOC_OUTSIDE:
        return "outside";
    }
    return "invalid";
}

char *proto_locs_to_text(const int8_t *loc, size_t n, size_t *ret_len)
{
    /* the longest item is "boundary" with quotes and a comma: 11 bytes */
    size_t cap = 11 * n + 4;
    char *s = malloc(cap);
    if (!s)
        return NULL;
    size_t len = 0;
    s[len++] = '[';
    for (size_t i = 0; i < n; i++) {
        const char *name = proto_loc_name(loc[i]);
        size_t l = strlen(name);
        if (i)
            s[len++] = ',';
        s[len++] = '"';
        memcpy(s + len, name, l);
        len += l;
        s[len++] = '"';
    }
    s[len++] = ']';
    s[len++] = '\n';
    s[len] = '\0';
    if (ret_len)
        *ret_len = len;
    return s;
}
