/* points_json.c — JSON point lists in, classification names out (see
 * points_json.h). Reading goes through jansson; writing is direct text, a
 * million answers being a few megabytes. */
#include "points_json.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "inside.h"

int proto_points_from_json(const json_t *root, size_t max_points,
                           double (**ret_pts)[3], size_t *ret_n,
                           geo_err *err)
{
    if (max_points == 0)
        max_points = PROTO_POINTS_MAX;
    const json_t *arr = root;
    if (json_is_object(root)) {
        arr = json_object_get(root, "points");
        if (!arr)
            return geo_err_set(err, -EINVAL, "points: missing");
        if (!json_is_array(arr))
            return geo_err_set(err, -EINVAL, "points: expected an array");
    } else if (!json_is_array(root)) {
        return geo_err_set(err, -EINVAL,
                           "expected an array of [x, y, z] points or an "
                           "object with \"points\"");
    }
    size_t n = json_array_size(arr);
    if (n > max_points)
        return geo_err_set(err, -ERANGE,
                           "points: %zu points exceed the limit of %zu", n,
                           max_points);
    double(*pts)[3] = NULL;
    if (n > 0) {
        pts = malloc(n * sizeof *pts);
        if (!pts)
            return geo_err_set(err, -ENOMEM, "points: out of memory");
    }
    for (size_t i = 0; i < n; i++) {
        const json_t *pt = json_array_get(arr, i);
        if (!json_is_array(pt)) {
            free(pts);
            return geo_err_set(err, -EINVAL,
                               "points[%zu]: expected an array of 3 numbers",
                               i);
        }
        if (json_array_size(pt) != 3) {
            free(pts);
            return geo_err_set(err, -EINVAL,
                               "points[%zu]: expected 3 numbers, got %zu", i,
                               json_array_size(pt));
        }
        for (size_t k = 0; k < 3; k++) {
            const json_t *c = json_array_get(pt, k);
            double d = json_is_number(c) ? json_number_value(c) : NAN;
            if (!isfinite(d)) {
                free(pts);
                return geo_err_set(err, -EINVAL,
                                   "points[%zu][%zu]: expected a number", i,
                                   k);
            }
            pts[i][k] = d;
        }
    }
    *ret_pts = pts;
    *ret_n = n;
    return 0;
}

int proto_points_read_mem(const void *data, size_t len, size_t max_points,
                          double (**ret_pts)[3], size_t *ret_n, geo_err *err)
{
    json_error_t je;
    json_t *root = json_loadb(data, len, JSON_REJECT_DUPLICATES, &je);
    if (!root)
        return geo_err_set(err, -EINVAL, "line %d, column %d: %s", je.line,
                           je.column, je.text);
    int r = proto_points_from_json(root, max_points, ret_pts, ret_n, err);
    json_decref(root);
    return r;
}

/* A jansson load callback over a FILE that fails past a byte limit. */
typedef struct bounded_file {
    FILE *f;
    size_t left;
    bool over, failed;
} bounded_file;

static size_t read_bounded(void *buffer, size_t buflen, void *user)
{
    bounded_file *b = user;
    size_t want = buflen < b->left + 1 ? buflen : b->left + 1;
    size_t got = fread(buffer, 1, want, b->f);
    if (got > b->left) {
        b->over = true;
        return (size_t)-1;
    }
    if (got == 0 && ferror(b->f)) {
        b->failed = true;
        return (size_t)-1;
    }
    b->left -= got;
    return got;
}

int proto_points_read_file(const char *path, size_t max_points,
                           double (**ret_pts)[3], size_t *ret_n, geo_err *err)
{
    bool is_stdin = strcmp(path, "-") == 0;
    FILE *f = is_stdin ? stdin : fopen(path, "rb");
    if (!f)
        return geo_err_set(err, -errno, "%s: %s", path, strerror(errno));
    bounded_file b = {f, PROTO_POINTS_MAX_BYTES, false, false};
    json_error_t je;
    json_t *root = json_load_callback(read_bounded, &b,
                                      JSON_REJECT_DUPLICATES, &je);
    int r;
    if (b.over)
        r = geo_err_set(err, -ERANGE, "more than %zu bytes (the limit)",
                        (size_t)PROTO_POINTS_MAX_BYTES);
    else if (b.failed)
        r = geo_err_set(err, -EIO, "read error");
    else if (!root)
        r = geo_err_set(err, -EINVAL, "line %d, column %d: %s", je.line,
                        je.column, je.text);
    else
        r = proto_points_from_json(root, max_points, ret_pts, ret_n, err);
    json_decref(root);
    if (!is_stdin)
        fclose(f);
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
