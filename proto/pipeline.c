/* pipeline.c — parsing and writing the job pipeline (pipeline.h).
 * Invariant: every parameter of every op has exactly one reader here and
 * one writer in op_to_json, so canonical JSON parses back to the same
 * structs; defaults are set before reading, so an absent key keeps its
 * default. */
#include "pipeline.h"

#include "compare.h"
#include "frep_grid.h"
#include "model_io.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const op_names[PROTO_OP_COUNT] = {
    [PROTO_OP_INSPECT] = "inspect",
    [PROTO_OP_COLLAPSE] = "collapse",
    [PROTO_OP_MERGE] = "merge",
    [PROTO_OP_CUT] = "cut",
    [PROTO_OP_MOVE] = "move",
    [PROTO_OP_INVERSION_STATS] = "inversion_stats",
    [PROTO_OP_TRIANGULATE] = "triangulate",
    [PROTO_OP_FILL] = "fill",
    [PROTO_OP_STITCH] = "stitch",
    [PROTO_OP_CORRECT] = "correct",
    [PROTO_OP_REPORT] = "report",
    [PROTO_OP_COMPARE] = "compare",
};

/* Names of earlier releases, still accepted for one release so that saved
 * pipelines run; each use is reported (proto_op.alias) as deprecated.
 * "inversion-stats" is the CLI's spelling. */
static const struct {
    const char *name;
    proto_op_kind kind;
} op_aliases[] = {
    {"auto", PROTO_OP_CORRECT},
    {"merge_facets", PROTO_OP_MERGE},
    {"fill_holes", PROTO_OP_FILL},
    {"move_vertex", PROTO_OP_MOVE},
    {"collapse_clusters", PROTO_OP_COLLAPSE},
    {"inversion-stats", PROTO_OP_INVERSION_STATS},
};

/* Parameters each op accepts, "op" included, NULL-terminated. */
static const char *const op_keys[PROTO_OP_COUNT][8] = {
    [PROTO_OP_INSPECT] = {"op", "keep_invalid"},
    [PROTO_OP_COLLAPSE] = {"op", "radius"},
    [PROTO_OP_MERGE] = {"op", "max_angle_deg", "max_deviation",
                               "views", "groups"},
    [PROTO_OP_CUT] = {"op", "plane"},
    [PROTO_OP_MOVE] = {"op", "vertex", "to", "by", "schedule",
                              "max_steps"},
    [PROTO_OP_INVERSION_STATS] = {"op", "samples", "magnitudes", "seed",
                                  "schedule"},
    [PROTO_OP_TRIANGULATE] = {"op", "quad_levels", "binary_levels", "fill",
                              "refine", "fair", "sharpen"},
    [PROTO_OP_FILL] = {"op", "weight", "refine", "fair", "parts_overlap",
                       "remove_crossing"},
    [PROTO_OP_STITCH] = {"op"},
    [PROTO_OP_REPORT] = {"op", "gear", "axis", "scan"},
    [PROTO_OP_COMPARE] = {"op", "reference", "axis"},
    [PROTO_OP_CORRECT] = {"op", "radius", "max_angle_deg", "max_deviation",
                       "views", "convex"},
};

static const char *const sched_names[] = {"local-exp", "scaled",
                                          "global-exp", "least-norm"};
static const char *const fill_names[] = {"area", "edges"};
static const char *const fair_names[] = {"none", "uniform", "length"};

static const double default_magnitudes[] = {1,     .5,     .1,    .05,
                                            .01,   .005,   .001,  .0005,
                                            .0001, .00005};

const char *proto_op_name(proto_op_kind kind)
{
    return (unsigned)kind < PROTO_OP_COUNT ? op_names[kind] : NULL;
}

/* The op called name, or -1; *alias = the deprecated name used, or NULL. */
static int find_op(const char *name, const char **alias)
{
    *alias = NULL;
    for (int i = 0; i < PROTO_OP_COUNT; i++)
        if (strcmp(name, op_names[i]) == 0)
            return i;
    for (size_t i = 0; i < sizeof op_aliases / sizeof *op_aliases; i++)
        if (strcmp(name, op_aliases[i].name) == 0) {
            *alias = op_aliases[i].name;
            return (int)op_aliases[i].kind;
        }
    return -1;
}

const char *proto_op_canonical(const char *name)
{
    const char *alias;
    int kind = find_op(name, &alias);
    return kind < 0 ? NULL : op_names[kind];
}

/* Error at where[i].key (key may be NULL). */
typedef struct place {
    const char *where;
    size_t index;
} place;

#define FAIL(pl, key, ...) fail_at(pl, key, err, __VA_ARGS__)

__attribute__((format(printf, 4, 5)))
static int fail_at(const place *pl, const char *key, geo_err *err,
                   const char *fmt, ...)
{
    if (!err)
        return -EINVAL;
    char msg[sizeof err->msg];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    char head[160];
    const char *w = pl->where ? pl->where : "";
    if (pl->index == (size_t)-1)
        snprintf(head, sizeof head, "%s", w);
    else
        snprintf(head, sizeof head, "%s[%zu]", w, pl->index);
    return geo_err_set(err, -EINVAL, "%s%s%s: %s", head, key ? "." : "",
                       key ? key : "", msg);
}

static int get_number(const json_t *o, const char *key, const place *pl,
                      double lo, double hi, bool lo_open, double *v,
                      geo_err *err)
{
    const json_t *x = json_object_get(o, key);
    if (!x)
        return 0;
    if (!json_is_number(x))
        return FAIL(pl, key, "expected a number");
    double d = json_number_value(x);
    if (!isfinite(d) || d < lo || d > hi || (lo_open && d == lo))
        return FAIL(pl, key, "%g out of range %s%g, %g]", d,
                    lo_open ? "(" : "[", lo, hi);
    *v = d;
    return 0;
}

static int get_uint(const json_t *o, const char *key, const place *pl,
                    uint64_t lo, uint64_t hi, uint64_t *v, geo_err *err)
{
    const json_t *x = json_object_get(o, key);
    if (!x)
        return 0;
    if (!json_is_integer(x))
        return FAIL(pl, key, "expected a whole number");
    json_int_t i = json_integer_value(x);
    if (i < 0 || (uint64_t)i < lo || (uint64_t)i > hi)
        return FAIL(pl, key, "%lld out of range [%llu, %llu]", (long long)i,
                    (unsigned long long)lo, (unsigned long long)hi);
    *v = (uint64_t)i;
    return 0;
}

static int get_u32(const json_t *o, const char *key, const place *pl,
                   uint32_t lo, uint32_t hi, uint32_t *v, geo_err *err)
{
    uint64_t x = *v;
    int r = get_uint(o, key, pl, lo, hi, &x, err);
    *v = (uint32_t)x;
    return r;
}

static int get_bool(const json_t *o, const char *key, const place *pl,
                    bool *v, geo_err *err)
{
    const json_t *x = json_object_get(o, key);
    if (!x)
        return 0;
    if (!json_is_boolean(x))
        return FAIL(pl, key, "expected true or false");
    *v = json_is_true(x);
    return 0;
}

static int get_choice(const json_t *o, const char *key, const place *pl,
                      const char *const *names, int n, int *v, geo_err *err)
{
    const json_t *x = json_object_get(o, key);
    if (!x)
        return 0;
    const char *s = json_string_value(x);
    for (int i = 0; s && i < n; i++)
        if (strcmp(s, names[i]) == 0)
            return *v = i, 0;
    char list[160] = "";
    for (int i = 0; i < n; i++) {
        strncat(list, i ? ", \"" : "\"", sizeof list - strlen(list) - 1);
        strncat(list, names[i], sizeof list - strlen(list) - 1);
        strncat(list, "\"", sizeof list - strlen(list) - 1);
    }
    return FAIL(pl, key, "expected one of %s", list);
}

static int get_schedule(const json_t *o, const place *pl, proto_schedule *v,
                        geo_err *err)
{
    int s = (int)*v;
    int r = get_choice(o, "schedule", pl, sched_names, 4, &s, err);
    *v = (proto_schedule)s;
    return r;
}

/* An array of exactly n finite numbers. */
static int get_vec(const json_t *x, const char *key, const place *pl,
                   size_t n, double *v, geo_err *err)
{
    if (!json_is_array(x) || json_array_size(x) != n)
        return FAIL(pl, key, "expected an array of %zu numbers", n);
    for (size_t i = 0; i < n; i++) {
        const json_t *e = json_array_get(x, i);
        if (!json_is_number(e) || !isfinite(json_number_value(e))) {
            char k[64];
            snprintf(k, sizeof k, "%s[%zu]", key, i);
            return FAIL(pl, k, "expected a finite number");
        }
        v[i] = json_number_value(e);
    }
    return 0;
}

static int parse_groups(const json_t *x, const place *pl, proto_op *op,
                        geo_err *err)
{
    if (!json_is_array(x) || json_array_size(x) == 0)
        return FAIL(pl, "groups", "expected a non-empty array of facet "
                    "index arrays");
    size_t ng = json_array_size(x), total = 0;
    if (ng > 1000000)
        return FAIL(pl, "groups", "more than 1000000 groups");
    for (size_t g = 0; g < ng; g++) {
        const json_t *a = json_array_get(x, g);
        char k[64];
        snprintf(k, sizeof k, "groups[%zu]", g);
        if (!json_is_array(a) || json_array_size(a) < 2)
            return FAIL(pl, k, "expected an array of at least 2 facet indices");
        total += json_array_size(a);
        if (total > 16000000)
            return FAIL(pl, "groups", "more than 16000000 facet indices");
    }
    uint32_t *start = malloc((ng + 1) * sizeof *start);
    uint32_t *facets = malloc(total * sizeof *facets);
    if (!start || !facets) {
        free(start);
        free(facets);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    size_t k = 0;
    for (size_t g = 0; g < ng; g++) {
        const json_t *a = json_array_get(x, g);
        start[g] = (uint32_t)k;
        for (size_t i = 0; i < json_array_size(a); i++) {
            const json_t *e = json_array_get(a, i);
            json_int_t v = json_is_integer(e) ? json_integer_value(e) : -1;
            if (v < 0 || v > UINT32_MAX - 1) {
                free(start);
                free(facets);
                char key[80];
                snprintf(key, sizeof key, "groups[%zu][%zu]", g, i);
                return FAIL(pl, key, "expected a facet index");
            }
            facets[k++] = (uint32_t)v;
        }
    }
    start[ng] = (uint32_t)k;
    op->u.merge.ngroups = (uint32_t)ng;
    op->u.merge.gstart = start;
    op->u.merge.gfacets = facets;
    return 0;
}

static void set_defaults(proto_op *op)
{
    memset(&op->u, 0, sizeof op->u);
    switch (op->kind) {
    case PROTO_OP_COLLAPSE:
        op->u.collapse.radius = 0;
        break;
    case PROTO_OP_MERGE:
        op->u.merge.max_angle_deg = 60.0;
        op->u.merge.max_deviation = 0;
        break;
    case PROTO_OP_CORRECT:
        op->u.correct.radius = 0;
        op->u.correct.max_angle_deg = 60.0;
        op->u.correct.max_deviation = 0;
        op->u.correct.convex = true;
        break;
    case PROTO_OP_MOVE:
        op->u.move.schedule = PROTO_SCHED_LEAST_NORM;
        op->u.move.max_steps = 10000;
        break;
    case PROTO_OP_INVERSION_STATS:
        op->u.inversion.samples = 100;
        op->u.inversion.nmagnitudes = sizeof default_magnitudes /
                                      sizeof default_magnitudes[0];
        memcpy(op->u.inversion.magnitudes, default_magnitudes,
               sizeof default_magnitudes);
        op->u.inversion.seed = 1;
        op->u.inversion.schedule = PROTO_SCHED_LOCAL_EXP;
        break;
    case PROTO_OP_TRIANGULATE:
        op->u.triangulate.quad_levels = 9;
        op->u.triangulate.binary_levels = 10;
        op->u.triangulate.refine = true;
        op->u.triangulate.sharpen = true;
        op->u.triangulate.fair = PROTO_FAIR_UNIFORM;
        break;
    case PROTO_OP_FILL:
        op->u.fill.refine = true;
        op->u.fill.fair = true;
        break;
    case PROTO_OP_REPORT:
        op->u.report.gear = 96;
        break;
    default:
        break;
    }
}

static int parse_params(const json_t *o, const place *pl, proto_op *op,
                        geo_err *err)
{
    int r = 0;
    switch (op->kind) {
    case PROTO_OP_INSPECT:
        return get_bool(o, "keep_invalid", pl, &op->u.inspect.keep_invalid,
                        err);
    case PROTO_OP_STITCH:
    case PROTO_OP_COUNT:
        return 0;
    case PROTO_OP_COLLAPSE:
        return get_number(o, "radius", pl, 0, 1e9, false,
                          &op->u.collapse.radius, err);
    case PROTO_OP_REPORT: {
        r = get_u32(o, "gear", pl, 1, 100000, &op->u.report.gear, err);
        const json_t *a = json_object_get(o, "axis");
        if (r == 0 && a) {
            double *v = op->u.report.axis;
            if ((r = get_vec(a, "axis", pl, 3, v, err)) < 0)
                return r;
            if (!(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] > 0))
                return FAIL(pl, "axis", "must be a non-zero vector");
            op->u.report.have_axis = true;
        }
        if (r == 0)
            r = get_bool(o, "scan", pl, &op->u.report.scan, err);
        return r;
    }
    case PROTO_OP_COMPARE: {
        const json_t *a = json_object_get(o, "axis");
        if (a) {
            double *v = op->u.compare.axis;
            if ((r = get_vec(a, "axis", pl, 3, v, err)) < 0)
                return r;
            if (!(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] > 0))
                return FAIL(pl, "axis", "must be a non-zero vector");
            op->u.compare.have_axis = true;
        }
        const json_t *ref = json_object_get(o, "reference");
        if (!ref)
            return FAIL(pl, "reference", "required (the facet-model/1 to "
                        "compare the job's model with)");
        char where[160];
        snprintf(where, sizeof where, "%s[%zu].reference",
                 pl->where ? pl->where : "", pl->index);
        geo_poly *m = proto_model_from_json(ref, NULL, where, err);
        if (!m)
            return -EINVAL;
        /* the reference is the frame: without a table or an axis there
         * is nothing to align on, which the client should hear now */
        double axis[3];
        uint32_t table;
        r = geo_compare_axis(m, op->u.compare.have_axis ? op->u.compare.axis
                                                        : NULL,
                             where, axis, &table, err);
        if (r < 0) {
            geo_poly_free(m);
            return r;
        }
        op->u.compare.reference = m;
        return 0;
    }
    case PROTO_OP_CORRECT:
        r = get_number(o, "radius", pl, 0, 1e9, false,
                       &op->u.correct.radius, err);
        if (r == 0)
            r = get_number(o, "max_angle_deg", pl, 0, 90, true,
                           &op->u.correct.max_angle_deg, err);
        if (r == 0 && op->u.correct.max_angle_deg == 90)
            r = FAIL(pl, "max_angle_deg", "must be below 90");
        if (r == 0)
            r = get_number(o, "max_deviation", pl, 0, 1e9, false,
                           &op->u.correct.max_deviation, err);
        if (r == 0)
            r = get_u32(o, "views", pl, 0, PROTO_MAX_VIEWS,
                        &op->u.correct.views, err);
        if (r == 0)
            r = get_bool(o, "convex", pl, &op->u.correct.convex, err);
        return r;
    case PROTO_OP_MERGE: {
        r = get_number(o, "max_angle_deg", pl, 0, 90, true,
                       &op->u.merge.max_angle_deg, err);
        if (r == 0 && op->u.merge.max_angle_deg == 90)
            r = FAIL(pl, "max_angle_deg", "must be below 90");
        if (r == 0)
            r = get_number(o, "max_deviation", pl, 0, 1e9, false,
                           &op->u.merge.max_deviation, err);
        if (r == 0)
            r = get_u32(o, "views", pl, 0, PROTO_MAX_VIEWS,
                        &op->u.merge.views, err);
        const json_t *g = json_object_get(o, "groups");
        if (r == 0 && g)
            r = parse_groups(g, pl, op, err);
        return r;
    }
    case PROTO_OP_CUT: {
        const json_t *p = json_object_get(o, "plane");
        if (!p)
            return FAIL(pl, "plane", "required");
        double *pv = op->u.cut.plane;
        if ((r = get_vec(p, "plane", pl, 4, pv, err)) < 0)
            return r;
        double n = sqrt(pv[0] * pv[0] + pv[1] * pv[1] + pv[2] * pv[2]);
        if (!(n > 0) || !isfinite(n))
            return FAIL(pl, "plane", "normal (a, b, c) must be non-zero "
                        "with a finite length");
        /* a normal already unit to rounding is kept bit for bit: dividing
         * it by its rounded length again would change it, so the stored
         * canonical JSON would not parse back to the plane that ran */
        if (fabs(n - 1) > 8 * DBL_EPSILON)
            for (int i = 0; i < 4; i++)
                pv[i] /= n;
        return 0;
    }
    case PROTO_OP_MOVE: {
        if (!json_object_get(o, "vertex"))
            return FAIL(pl, "vertex", "required");
        r = get_u32(o, "vertex", pl, 0, UINT32_MAX - 1, &op->u.move.vertex,
                    err);
        const json_t *to = json_object_get(o, "to"),
                     *by = json_object_get(o, "by");
        if (r == 0 && !!to == !!by)
            r = FAIL(pl, NULL, "exactly one of \"to\" and \"by\" is required");
        if (r == 0) {
            op->u.move.relative = by != NULL;
            r = get_vec(to ? to : by, to ? "to" : "by", pl, 3, op->u.move.xyz,
                        err);
        }
        if (r == 0)
            r = get_schedule(o, pl, &op->u.move.schedule, err);
        if (r == 0)
            r = get_u32(o, "max_steps", pl, 1, 100000000,
                        &op->u.move.max_steps, err);
        return r;
    }
    case PROTO_OP_INVERSION_STATS: {
        r = get_u32(o, "samples", pl, 1, 100000, &op->u.inversion.samples,
                    err);
        const json_t *m = json_object_get(o, "magnitudes");
        if (r == 0 && m) {
            size_t n = json_array_size(m);
            if (!json_is_array(m) || n == 0 || n > PROTO_MAX_MAGNITUDES)
                return FAIL(pl, "magnitudes", "expected an array of 1 to %d "
                            "numbers", PROTO_MAX_MAGNITUDES);
            for (size_t i = 0; i < n; i++) {
                const json_t *e = json_array_get(m, i);
                double d = json_is_number(e) ? json_number_value(e) : NAN;
                if (!(d > 0) || !isfinite(d)) {
                    char k[40];
                    snprintf(k, sizeof k, "magnitudes[%zu]", i);
                    return FAIL(pl, k, "expected a positive number");
                }
                op->u.inversion.magnitudes[i] = d;
            }
            op->u.inversion.nmagnitudes = (uint32_t)n;
        }
        if (r == 0)
            r = get_uint(o, "seed", pl, 0, (uint64_t)INT64_MAX,
                         &op->u.inversion.seed, err);
        if (r == 0)
            r = get_schedule(o, pl, &op->u.inversion.schedule, err);
        return r;
    }
    case PROTO_OP_TRIANGULATE: {
        int fill = op->u.triangulate.fill_edges, fair = op->u.triangulate.fair;
        r = get_u32(o, "quad_levels", pl, 1, GEO_FREP_MAX_QLEV,
                    &op->u.triangulate.quad_levels, err);
        if (r == 0)
            r = get_u32(o, "binary_levels", pl, 1, GEO_FREP_MAX_BLEV,
                        &op->u.triangulate.binary_levels, err);
        if (r == 0)
            r = get_choice(o, "fill", pl, fill_names, 2, &fill, err);
        if (r == 0)
            r = get_bool(o, "refine", pl, &op->u.triangulate.refine, err);
        if (r == 0)
            r = get_choice(o, "fair", pl, fair_names, 3, &fair, err);
        if (r == 0)
            r = get_bool(o, "sharpen", pl, &op->u.triangulate.sharpen, err);
        op->u.triangulate.fill_edges = fill == 1;
        op->u.triangulate.fair = (proto_fair)fair;
        return r;
    }
    case PROTO_OP_FILL: {
        static const char *const weights[] = {"area", "length"};
        int w = op->u.fill.weight_length;
        r = get_choice(o, "weight", pl, weights, 2, &w, err);
        op->u.fill.weight_length = w == 1;
        if (r == 0)
            r = get_bool(o, "refine", pl, &op->u.fill.refine, err);
        if (r == 0)
            r = get_bool(o, "fair", pl, &op->u.fill.fair, err);
        if (r == 0)
            r = get_bool(o, "parts_overlap", pl, &op->u.fill.parts_overlap,
                         err);
        if (r == 0)
            r = get_bool(o, "remove_crossing", pl,
                         &op->u.fill.remove_crossing, err);
        return r;
    }
    }
    return r;
}

static void op_free(proto_op *op)
{
    if (op->kind == PROTO_OP_COMPARE) {
        geo_poly_free(op->u.compare.reference);
        op->u.compare.reference = NULL;
    }
    if (op->kind == PROTO_OP_MERGE) {
        free(op->u.merge.gstart);
        free(op->u.merge.gfacets);
        op->u.merge.gstart = op->u.merge.gfacets = NULL;
    }
}

static int parse_op(const json_t *v, const place *pl, proto_op *op,
                    geo_err *err)
{
    const char *name = NULL;
    if (json_is_string(v)) {
        name = json_string_value(v);
    } else if (json_is_object(v)) {
        const json_t *n = json_object_get(v, "op");
        if (!n)
            return FAIL(pl, "op", "required (the operation's name)");
        if (!(name = json_string_value(n)))
            return FAIL(pl, "op", "expected a string");
    } else {
        return FAIL(pl, NULL, "expected an operation name or object");
    }
    const char *alias;
    int kind = find_op(name, &alias);
    if (kind < 0)
        return FAIL(pl, json_is_object(v) ? "op" : NULL,
                    "unknown operation '%.64s'", name);
    op->kind = (proto_op_kind)kind;
    set_defaults(op);
    op->alias = alias;
    const char *key;
    const json_t *val;
    if (json_is_object(v))
        json_object_foreach((json_t *)v, key, val) {
            bool known = false;
            for (int i = 0; op_keys[kind][i]; i++)
                known |= strcmp(key, op_keys[kind][i]) == 0;
            if (!known)
                return FAIL(pl, key, "unknown parameter of %s", name);
        }
    /* a bare name is the op with no parameters: what it requires (cut's
     * plane, move's vertex) is still required */
    json_t *none = json_is_object(v) ? NULL : json_object();
    if (!json_is_object(v) && !none)
        return geo_err_set(err, -ENOMEM, "out of memory");
    int r = parse_params(none ? none : v, pl, op, err);
    json_decref(none);
    if (r < 0)
        op_free(op);
    return r;
}

/* The pipeline "correct" names: the post-scan correction. */
static const char *const correct_ops[] = {"inspect", "correct", "inspect"};

int proto_pipeline_from_json(const json_t *v, const char *where,
                             proto_pipeline *ret, geo_err *err)
{
    place whole = {where, (size_t)-1};
    json_t *expanded = NULL;
    const char *whole_alias = NULL;
    if (json_is_string(v)) {
        const char *s = json_string_value(v);
        if (strcmp(s, "auto") == 0)
            whole_alias = "auto";
        else if (strcmp(s, "correct") != 0)
            return FAIL(&whole, NULL, "expected an array of operations or "
                        "\"correct\"");
        expanded = json_array();
        size_t nops = sizeof correct_ops / sizeof *correct_ops;
        for (size_t i = 0; expanded && i < nops; i++)
            if (json_array_append_new(expanded,
                                      json_string(correct_ops[i])) < 0)
                expanded = (json_decref(expanded), NULL);
        if (!expanded)
            return geo_err_set(err, -ENOMEM, "out of memory");
        v = expanded;
    }
    if (!json_is_array(v))
        return FAIL(&whole, NULL,
                    "expected an array of operations or \"correct\"");
    size_t n = json_array_size(v);
    int r = 0;
    if (n == 0)
        r = FAIL(&whole, NULL, "expected at least one operation");
    else if (n > PROTO_PIPELINE_MAX_OPS)
        r = FAIL(&whole, NULL, "more than %d operations",
                 PROTO_PIPELINE_MAX_OPS);
    proto_op *ops = r ? NULL : calloc(n, sizeof *ops);
    if (!r && !ops)
        r = geo_err_set(err, -ENOMEM, "out of memory");
    size_t done = 0;
    for (; r == 0 && done < n; done++) {
        place pl = {where, done};
        r = parse_op(json_array_get(v, done), &pl, &ops[done], err);
        if (r < 0)
            break;
    }
    json_decref(expanded);
    if (r < 0) {
        for (size_t i = 0; i < done; i++)
            op_free(&ops[i]);
        free(ops);
        return r;
    }
    if (whole_alias)
        ops[1].alias = whole_alias; /* "auto" named the correct op */
    ret->nops = n;
    ret->ops = ops;
    return 0;
}

size_t proto_pipeline_deprecations(const proto_pipeline *p, char *buf,
                                   size_t size)
{
    size_t count = 0, len = 0;
    if (size)
        buf[0] = 0;
    for (size_t i = 0; i < p->nops; i++) {
        const proto_op *op = &p->ops[i];
        if (!op->alias)
            continue;
        bool seen = false;
        for (size_t j = 0; j < i; j++)
            seen |= p->ops[j].alias && strcmp(p->ops[j].alias, op->alias) == 0;
        if (seen)
            continue;
        if (len < size) {
            int w = snprintf(buf + len, size - len,
                             "%sop '%s' is deprecated: use '%s'",
                             count ? "; " : "", op->alias, op_names[op->kind]);
            if (w > 0)
                len += (size_t)w;
        }
        count++;
    }
    return count;
}

void proto_pipeline_free(proto_pipeline *p)
{
    if (!p)
        return;
    for (size_t i = 0; i < p->nops; i++)
        op_free(&p->ops[i]);
    free(p->ops);
    p->ops = NULL;
    p->nops = 0;
}

static json_t *vec(const double *v, size_t n)
{
    json_t *a = json_array();
    for (size_t i = 0; a && i < n; i++)
        if (json_array_append_new(a, json_real(v[i])) < 0)
            a = (json_decref(a), NULL);
    return a;
}

static json_t *op_to_json(const proto_op *op)
{
    json_t *o = json_object();
    if (!o)
        return NULL;
    int e = json_object_set_new(o, "op", json_string(op_names[op->kind]));
    switch (op->kind) {
    case PROTO_OP_INSPECT:
        if (op->u.inspect.keep_invalid)
            e |= json_object_set_new(o, "keep_invalid", json_true());
        break;
    case PROTO_OP_COLLAPSE:
        e |= json_object_set_new(o, "radius", json_real(op->u.collapse.radius));
        break;
    case PROTO_OP_MERGE:
        e |= json_object_set_new(o, "max_angle_deg",
                                 json_real(op->u.merge.max_angle_deg));
        e |= json_object_set_new(o, "max_deviation",
                                 json_real(op->u.merge.max_deviation));
        e |= json_object_set_new(o, "views", json_integer(op->u.merge.views));
        if (op->u.merge.ngroups) {
            json_t *gs = json_array();
            for (uint32_t g = 0; gs && g < op->u.merge.ngroups; g++) {
                json_t *a = json_array();
                for (uint32_t k = op->u.merge.gstart[g];
                     a && k < op->u.merge.gstart[g + 1]; k++)
                    if (json_array_append_new(
                            a, json_integer(op->u.merge.gfacets[k])) < 0)
                        a = (json_decref(a), NULL);
                if (!a || json_array_append_new(gs, a) < 0)
                    gs = (json_decref(gs), NULL);
            }
            e |= json_object_set_new(o, "groups", gs);
        }
        break;
    case PROTO_OP_CUT:
        e |= json_object_set_new(o, "plane", vec(op->u.cut.plane, 4));
        break;
    case PROTO_OP_CORRECT:
        e |= json_object_set_new(o, "radius", json_real(op->u.correct.radius));
        e |= json_object_set_new(o, "max_angle_deg",
                                 json_real(op->u.correct.max_angle_deg));
        e |= json_object_set_new(o, "max_deviation",
                                 json_real(op->u.correct.max_deviation));
        e |= json_object_set_new(o, "views",
                                 json_integer(op->u.correct.views));
        e |= json_object_set_new(o, "convex",
                                 json_boolean(op->u.correct.convex));
        break;
    case PROTO_OP_MOVE:
        e |= json_object_set_new(o, "vertex", json_integer(op->u.move.vertex));
        e |= json_object_set_new(o, op->u.move.relative ? "by" : "to",
                                 vec(op->u.move.xyz, 3));
        e |= json_object_set_new(o, "schedule",
                                 json_string(sched_names[op->u.move.schedule]));
        e |= json_object_set_new(o, "max_steps",
                                 json_integer(op->u.move.max_steps));
        break;
    case PROTO_OP_INVERSION_STATS:
        e |= json_object_set_new(o, "samples",
                                 json_integer(op->u.inversion.samples));
        e |= json_object_set_new(o, "magnitudes",
                                 vec(op->u.inversion.magnitudes,
                                     op->u.inversion.nmagnitudes));
        e |= json_object_set_new(o, "seed",
                                 json_integer((json_int_t)op->u.inversion.seed));
        e |= json_object_set_new(
            o, "schedule", json_string(sched_names[op->u.inversion.schedule]));
        break;
    case PROTO_OP_TRIANGULATE:
        e |= json_object_set_new(o, "quad_levels",
                                 json_integer(op->u.triangulate.quad_levels));
        e |= json_object_set_new(o, "binary_levels",
                                 json_integer(op->u.triangulate.binary_levels));
        e |= json_object_set_new(
            o, "fill", json_string(fill_names[op->u.triangulate.fill_edges]));
        e |= json_object_set_new(o, "refine",
                                 json_boolean(op->u.triangulate.refine));
        e |= json_object_set_new(
            o, "fair", json_string(fair_names[op->u.triangulate.fair]));
        e |= json_object_set_new(o, "sharpen",
                                 json_boolean(op->u.triangulate.sharpen));
        break;
    case PROTO_OP_REPORT:
        e |= json_object_set_new(o, "gear",
                                 json_integer(op->u.report.gear));
        if (op->u.report.have_axis)
            e |= json_object_set_new(o, "axis", vec(op->u.report.axis, 3));
        if (op->u.report.scan)
            e |= json_object_set_new(o, "scan", json_true());
        break;
    case PROTO_OP_COMPARE:
        e |= json_object_set_new(o, "reference",
                                 proto_model_to_json(op->u.compare.reference));
        if (op->u.compare.have_axis)
            e |= json_object_set_new(o, "axis", vec(op->u.compare.axis, 3));
        break;
    case PROTO_OP_FILL:
        e |= json_object_set_new(
            o, "weight",
            json_string(op->u.fill.weight_length ? "length" : "area"));
        e |= json_object_set_new(o, "refine",
                                 json_boolean(op->u.fill.refine));
        e |= json_object_set_new(o, "fair", json_boolean(op->u.fill.fair));
        e |= json_object_set_new(o, "parts_overlap",
                                 json_boolean(op->u.fill.parts_overlap));
        e |= json_object_set_new(o, "remove_crossing",
                                 json_boolean(op->u.fill.remove_crossing));
        break;
    default:
        break;
    }
    if (e) {
        json_decref(o);
        return NULL;
    }
    return o;
}

json_t *proto_pipeline_to_json(const proto_pipeline *p)
{
    json_t *a = json_array();
    for (size_t i = 0; a && i < p->nops; i++) {
        json_t *o = op_to_json(&p->ops[i]);
        if (!o || json_array_append_new(a, o) < 0)
            a = (json_decref(a), NULL);
    }
    return a;
}

int proto_pipeline_copy(const proto_pipeline *src, proto_pipeline *ret)
{
    /* the canonical JSON round-trips exactly (see proto_pipeline_to_json) */
    json_t *j = proto_pipeline_to_json(src);
    if (!j)
        return -ENOMEM;
    geo_err err;
    int r = proto_pipeline_from_json(j, NULL, ret, &err);
    json_decref(j);
    return r < 0 ? -ENOMEM : 0;
}

void proto_pipeline_set_views(proto_pipeline *p, uint32_t views)
{
    for (size_t i = 0; i < p->nops; i++) {
        proto_op *op = &p->ops[i];
        if (op->kind == PROTO_OP_MERGE && op->u.merge.views == 0)
            op->u.merge.views = views;
        else if (op->kind == PROTO_OP_CORRECT && op->u.correct.views == 0)
            op->u.correct.views = views;
    }
}
