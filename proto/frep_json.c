/* frep_json.c — the frep-object/1 reader: walks the JSON tree once,
 * validating every field with its path, and builds the geo_frep bottom-up.
 * The shape count and nesting are checked before recursing, so the
 * recursion depth is at most max_depth. */
#include "frep_json.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model_codec.h"

void proto_frep_limits_default(proto_frep_limits *lim)
{
    lim->max_shapes = 100000;
    lim->max_depth = 32;
    lim->max_bytes = (size_t)64 << 20;
}

typedef struct reader {
    geo_frep *f;
    proto_frep_limits lim;
    uint32_t nshapes;
    geo_err *err;
    char path[512];
} reader;

static const char *const SHAPE_KEYS[] = {
    "sphere", "ellipsoid", "quadric", "halfspace",
    "perturbed", "union", "intersection", "difference",
};
enum { NSHAPE_KEYS = sizeof SHAPE_KEYS / sizeof SHAPE_KEYS[0] };

/* Appends to the current path; returns the old length for path_pop. */
static size_t path_push(reader *r, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static size_t path_push(reader *r, const char *fmt, ...)
{
    size_t len = strlen(r->path);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->path + len, sizeof r->path - len, fmt, ap);
    va_end(ap);
    return len;
}

static void path_pop(reader *r, size_t len)
{
    r->path[len] = '\0';
}

static int fail(reader *r, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static int fail(reader *r, const char *fmt, ...)
{
    if (r->err) {
        char msg[400];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, sizeof msg, fmt, ap);
        va_end(ap);
        geo_err_set(r->err, -EINVAL, "%s: %s", r->path, msg);
    }
    return -EINVAL;
}

/* Reads a member that must be a finite number. */
static int get_number(reader *r, const json_t *obj, const char *key,
                      double *ret)
{
    size_t l = path_push(r, ".%s", key);
    const json_t *v = json_object_get(obj, key);
    int rc = 0;
    if (!v)
        rc = fail(r, "missing");
    else if (!json_is_number(v))
        rc = fail(r, "expected a number");
    else if (!isfinite(json_number_value(v)))
        rc = fail(r, "not a finite number");
    else
        *ret = json_number_value(v);
    path_pop(r, l);
    return rc;
}

/* Reads n finite numbers from a JSON array (the path names the array). */
static int get_vec(reader *r, const json_t *v, size_t n, double *ret)
{
    if (!json_is_array(v))
        return fail(r, "expected an array of %zu numbers", n);
    if (json_array_size(v) != n)
        return fail(r, "expected %zu numbers, got %zu", n,
                    json_array_size(v));
    for (size_t i = 0; i < n; i++) {
        const json_t *x = json_array_get(v, i);
        if (!json_is_number(x) || !isfinite(json_number_value(x))) {
            size_t l = path_push(r, "[%zu]", i);
            int rc = fail(r, "expected a number");
            path_pop(r, l);
            return rc;
        }
        ret[i] = json_number_value(x);
    }
    return 0;
}

static int get_member_vec(reader *r, const json_t *obj, const char *key,
                          size_t n, double *ret)
{
    size_t l = path_push(r, ".%s", key);
    const json_t *v = json_object_get(obj, key);
    int rc = v ? get_vec(r, v, n, ret) : fail(r, "missing");
    path_pop(r, l);
    return rc;
}

/* Which shape key obj holds; -1 with an error when none or several. */
static int shape_key(reader *r, const json_t *obj)
{
    if (!json_is_object(obj))
        return fail(r, "expected a shape object"), -1;
    int found = -1;
    for (int k = 0; k < NSHAPE_KEYS; k++) {
        if (!json_object_get(obj, SHAPE_KEYS[k]))
            continue;
        if (found >= 0)
            return fail(r, "two shapes in one object (\"%s\" and \"%s\")",
                        SHAPE_KEYS[found], SHAPE_KEYS[k]),
                   -1;
        found = k;
    }
    if (found < 0)
        return fail(r, "expected one of sphere, ellipsoid, quadric, "
                       "halfspace, perturbed, union, intersection, "
                       "difference"),
               -1;
    return found;
}

static int64_t read_shape(reader *r, const json_t *obj, uint32_t depth);

/* The node built by a constructor, with its error prefixed by the path. */
static int64_t built(reader *r, int64_t id)
{
    if (id < 0 && r->err && id != -ENOMEM) {
        geo_err_prefix(r->err, r->path);
    }
    return id;
}

static int64_t read_list(reader *r, const json_t *v, uint32_t depth,
                         int kind)
{
    if (!json_is_array(v))
        return fail(r, "expected an array of shapes");
    size_t n = json_array_size(v);
    if (n == 0)
        return fail(r, "expected at least one shape");
    if (kind == 7 && n != 2)
        return fail(r, "expected exactly two shapes, got %zu", n);
    if (n > r->lim.max_shapes)
        return fail(r, "more than %u shapes", r->lim.max_shapes);
    uint32_t *ids = malloc(n * sizeof *ids);
    if (!ids)
        return geo_err_set(r->err, -ENOMEM, "out of memory");
    int64_t id = 0;
    for (size_t i = 0; i < n && id >= 0; i++) {
        size_t l = path_push(r, "[%zu]", i);
        id = read_shape(r, json_array_get(v, i), depth + 1);
        path_pop(r, l);
        if (id >= 0)
            ids[i] = (uint32_t)id;
    }
    if (id >= 0) {
        if (kind == 5)
            id = geo_frep_union(r->f, (uint32_t)n, ids, r->err);
        else if (kind == 6)
            id = geo_frep_intersection(r->f, (uint32_t)n, ids, r->err);
        else
            id = geo_frep_difference(r->f, ids[0], ids[1], r->err);
        id = built(r, id);
    }
    free(ids);
    return id;
}

static int64_t read_perturbed(reader *r, const json_t *v, uint32_t depth)
{
    if (!json_is_object(v))
        return fail(r, "expected an object with base and perturbations");
    size_t l = path_push(r, ".base");
    const json_t *b = json_object_get(v, "base");
    int64_t base = b ? read_shape(r, b, depth + 1) : fail(r, "missing");
    path_pop(r, l);
    if (base < 0)
        return base;
    l = path_push(r, ".perturbations");
    const json_t *list = json_object_get(v, "perturbations");
    int64_t id = 0;
    uint32_t *ids = NULL;
    double *amps = NULL;
    size_t n = 0;
    if (!list) {
        id = fail(r, "missing");
    } else if (!json_is_array(list)) {
        id = fail(r, "expected an array");
    } else if ((n = json_array_size(list)) > r->lim.max_shapes) {
        id = fail(r, "more than %u perturbations", r->lim.max_shapes);
    } else {
        ids = malloc((n + 1) * sizeof *ids);
        amps = malloc((n + 1) * sizeof *amps);
        if (!ids || !amps)
            id = geo_err_set(r->err, -ENOMEM, "out of memory");
    }
    for (size_t i = 0; i < n && id >= 0; i++) {
        size_t l2 = path_push(r, "[%zu]", i);
        const json_t *t = json_array_get(list, i);
        if (json_is_object(t))
            id = get_number(r, t, "amplitude", &amps[i]);
        if (id >= 0)
            id = read_shape(r, t, depth + 1);
        if (id >= 0)
            ids[i] = (uint32_t)id;
        path_pop(r, l2);
    }
    path_pop(r, l);
    if (id >= 0) {
        l = path_push(r, ".perturbed");
        id = built(r, geo_frep_perturbed(r->f, (uint32_t)base, (uint32_t)n,
                                         ids, amps, r->err));
        path_pop(r, l);
    }
    free(ids), free(amps);
    return id;
}

static int64_t read_shape(reader *r, const json_t *obj, uint32_t depth)
{
    if (depth > r->lim.max_depth)
        return fail(r, "shapes nested deeper than %u", r->lim.max_depth);
    if (++r->nshapes > r->lim.max_shapes)
        return fail(r, "more than %u shapes", r->lim.max_shapes);
    int k = shape_key(r, obj);
    if (k < 0)
        return -EINVAL;
    const json_t *v = json_object_get(obj, SHAPE_KEYS[k]);
    size_t l = path_push(r, ".%s", SHAPE_KEYS[k]);
    int64_t id = -EINVAL;
    double c[3], rad[3], q[10], rr;
    switch (k) {
    case 0: /* sphere */
        if (!json_is_object(v)) {
            id = fail(r, "expected an object with center and radius");
            break;
        }
        if (get_member_vec(r, v, "center", 3, c) < 0 ||
            get_number(r, v, "radius", &rr) < 0)
            break;
        if (!(rr > 0)) {
            size_t l2 = path_push(r, ".radius");
            id = fail(r, "must be > 0");
            path_pop(r, l2);
            break;
        }
        id = built(r, geo_frep_sphere(r->f, c, rr, r->err));
        break;
    case 1: /* ellipsoid */
        if (!json_is_object(v)) {
            id = fail(r, "expected an object with center and radii");
            break;
        }
        if (get_member_vec(r, v, "center", 3, c) < 0 ||
            get_member_vec(r, v, "radii", 3, rad) < 0)
            break;
        if (!(rad[0] > 0 && rad[1] > 0 && rad[2] > 0)) {
            size_t l2 = path_push(r, ".radii");
            id = fail(r, "every radius must be > 0");
            path_pop(r, l2);
            break;
        }
        id = built(r, geo_frep_ellipsoid(r->f, c, rad, r->err));
        break;
    case 2: /* quadric */
        if (get_vec(r, v, 10, q) < 0)
            break;
        id = built(r, geo_frep_quadric(r->f, q, r->err));
        break;
    case 3: /* halfspace */
        if (!json_is_object(v)) {
            id = fail(r, "expected an object with plane");
            break;
        }
        if (get_member_vec(r, v, "plane", 4, q) < 0)
            break;
        if (q[0] == 0 && q[1] == 0 && q[2] == 0) {
            size_t l2 = path_push(r, ".plane");
            id = fail(r, "the normal (a, b, c) must not be zero");
            path_pop(r, l2);
            break;
        }
        id = built(r, geo_frep_halfspace(r->f, q, r->err));
        break;
    case 4:
        id = read_perturbed(r, v, depth);
        break;
    default:
        id = read_list(r, v, depth, k);
        break;
    }
    path_pop(r, l);
    return id;
}

geo_frep *proto_frep_from_json(const json_t *root,
                               const proto_frep_limits *lim,
                               const char *path_prefix, geo_err *err)
{
    reader r = {.err = err};
    if (lim)
        r.lim = *lim;
    else
        proto_frep_limits_default(&r.lim);
    if (r.lim.max_depth > GEO_FREP_MAX_DEPTH)
        r.lim.max_depth = GEO_FREP_MAX_DEPTH;
    snprintf(r.path, sizeof r.path, "%s", path_prefix ? path_prefix : "");
    const char *sep = r.path[0] ? "." : "";
    if (!json_is_object(root)) {
        if (r.path[0])
            fail(&r, "expected a frep-object/1 object");
        else
            geo_err_set(err, -EINVAL, "expected a frep-object/1 object");
        return NULL;
    }
    size_t l = path_push(&r, "%sformat", sep);
    const json_t *fmt = json_object_get(root, "format");
    if (!fmt || !json_is_string(fmt) ||
        strcmp(json_string_value(fmt), "frep-object/1") != 0) {
        fail(&r, "expected \"frep-object/1\"");
        return NULL;
    }
    path_pop(&r, l);
    double box[2][3];
    l = path_push(&r, "%sbounds", sep);
    const json_t *b = json_object_get(root, "bounds");
    if (!b) {
        fail(&r, "missing");
        return NULL;
    }
    if (!json_is_array(b) || json_array_size(b) != 2) {
        fail(&r, "expected [[x0,y0,z0],[x1,y1,z1]]");
        return NULL;
    }
    for (size_t i = 0; i < 2; i++) {
        size_t l2 = path_push(&r, "[%zu]", i);
        if (get_vec(&r, json_array_get(b, i), 3, box[i]) < 0)
            return NULL;
        path_pop(&r, l2);
    }
    for (int i = 0; i < 3; i++)
        if (!(box[0][i] < box[1][i])) {
            fail(&r, "the first corner must be below the second on every "
                     "axis");
            return NULL;
        }
    /* the mesh made inside must be a model the readers take back (their
     * coordinate range, model_codec.h); beyond it the sampling's
     * arithmetic overflowed (a box of ±1e308 has an infinite side) */
    double side = 0;
    for (int i = 0; i < 3; i++) {
        if (!(fabs(box[0][i]) <= PROTO_MAX_COORD &&
              fabs(box[1][i]) <= PROTO_MAX_COORD)) {
            fail(&r, "corners must lie within ±%g mm", PROTO_MAX_COORD);
            return NULL;
        }
        side = fmax(side, box[1][i] - box[0][i]);
    }
    if (!(side >= PROTO_MIN_EXTENT)) {
        fail(&r, "the box must be at least %g mm across", PROTO_MIN_EXTENT);
        return NULL;
    }
    path_pop(&r, l);
    r.f = geo_frep_new();
    if (!r.f) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    l = path_push(&r, "%sshape", sep);
    const json_t *s = json_object_get(root, "shape");
    int64_t id = s ? read_shape(&r, s, 1) : fail(&r, "missing");
    path_pop(&r, l);
    if (id < 0 || geo_frep_finish(r.f, (uint32_t)id, box[0], box[1], err) < 0)
        return geo_frep_free(r.f);
    return r.f;
}

geo_frep *proto_frep_read_mem(const void *data, size_t len,
                              const proto_frep_limits *lim, geo_err *err)
{
    proto_frep_limits dl;
    if (!lim) {
        proto_frep_limits_default(&dl);
        lim = &dl;
    }
    if (len > lim->max_bytes) {
        geo_err_set(err, -ERANGE, "input of %zu bytes exceeds the limit of "
                                  "%zu", len, lim->max_bytes);
        return NULL;
    }
    json_error_t je;
    json_t *root = json_loadb(data, len, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        geo_err_set(err, -EINVAL, "line %d column %d: %s", je.line,
                    je.column, je.text);
        return NULL;
    }
    geo_frep *f = proto_frep_from_json(root, lim, NULL, err);
    json_decref(root);
    return f;
}

geo_frep *proto_frep_read_file(const char *path, const proto_frep_limits *lim,
                               geo_err *err)
{
    proto_frep_limits dl;
    if (!lim) {
        proto_frep_limits_default(&dl);
        lim = &dl;
    }
    FILE *fp = fopen(path, "rb");
    if (!fp) {
        geo_err_set(err, -errno, "%s: %s", path, strerror(errno));
        return NULL;
    }
    char *buf = NULL;
    size_t len = 0, cap = 0;
    geo_frep *f = NULL;
    for (;;) {
        if (len == cap) {
            size_t nc = cap ? cap * 2 : 65536;
            char *nb = realloc(buf, nc);
            if (!nb) {
                geo_err_set(err, -ENOMEM, "%s: out of memory", path);
                goto out;
            }
            buf = nb;
            cap = nc;
        }
        size_t got = fread(buf + len, 1, cap - len, fp);
        len += got;
        if (len > lim->max_bytes) {
            geo_err_set(err, -ERANGE, "%s: larger than the limit of %zu "
                                      "bytes", path, lim->max_bytes);
            goto out;
        }
        if (got == 0)
            break;
    }
    if (ferror(fp)) {
        geo_err_set(err, -EIO, "%s: read error", path);
        goto out;
    }
    f = proto_frep_read_mem(buf, len, lim, err);
    if (!f)
        geo_err_prefix(err, path);
out:
    fclose(fp);
    free(buf);
    return f;
}
