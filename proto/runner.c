/* runner.c — the op table and the pipeline loop (runner.h).
 * Invariant: an entry exists in ops[] only for a kernel that is part of
 * this build; everything else about an op (its name, its parameters)
 * lives in proto/pipeline.c. */
#include "runner.h"

#include <errno.h>
#include <assert.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "clusters.h"
#include "compare.h"
#include "compare_json.h"
#include "correct.h"
#include "correct_json.h"
#include "cut.h"
#include "fill.h"
#include "fill_json.h"
#include "inversion.h"
#include "merge.h"
#include "replanar.h"
#include "replanar_json.h"
#include "report.h"
#include "report_json.h"
#include "stats.h"
#include "stats_json.h"
#include "stitch.h"
#include "tri_report_json.h"
#include "triangulate.h"

/* Runs one operation on *model (may replace it, freeing the old one).
 * Adds its report to *ret_report (a new object it creates) and summary
 * fields to summary. 0 or a negative errno with err set. */
typedef int (*op_fn)(const proto_op *op, geo_poly **model, const geo_ctx *ctx,
                     json_t **ret_report, json_t *summary, geo_err *err);

/* An operation that makes the model from a frep input f (*model is NULL
 * on entry); otherwise like op_fn. */
typedef int (*frep_fn)(const proto_op *op, const geo_frep *f,
                       geo_poly **model, const geo_ctx *ctx,
                       json_t **ret_report, json_t *summary, geo_err *err);

typedef struct op_entry {
    op_fn run;
    bool changes_model; /* false for read-only ops such as inspect */
    frep_fn run_frep;   /* set (and run NULL) for ops taking a frep */
} op_entry;

/* Why st is not valid, in the order of geo_stats' definition. */
static void invalid_reason(const geo_stats *st, char *buf, size_t size)
{
    if (!st->closed)
        snprintf(buf, size, "not closed (%u boundary edges)",
                 st->boundary_edges);
    else if (st->nonmanifold_vertices)
        snprintf(buf, size, "%u non-manifold vertices",
                 st->nonmanifold_vertices);
    else if (st->low_degree_vertices)
        snprintf(buf, size, "%u vertices in fewer than 3 facets",
                 st->low_degree_vertices);
    else if (st->inverted_facets)
        snprintf(buf, size, "%u inverted facets", st->inverted_facets);
    else if (st->orientation != GEO_ORIENT_OUTWARD)
        snprintf(buf, size, "orientation %s (volume %.3g mm^3)",
                 geo_orientation_name(st->orientation), st->volume);
    else if (st->max_nonplanarity > st->eps)
        snprintf(buf, size, "a facet %.3g mm out of its plane (tolerance "
                 "%.3g mm)", st->max_nonplanarity, st->eps);
    else if (st->selfint.count)
        snprintf(buf, size, "%llu self-intersections",
                 (unsigned long long)st->selfint.count);
    else
        snprintf(buf, size, "%u degenerate facets", st->degenerate_facets);
}

/* inspect (lib/inspect/stats.h): every statistic of the model, unchanged.
 * With *model_changed (an earlier op changed the model) an invalid model
 * fails unless the op keeps invalid results. */
static int inspect_checked(const proto_op *op, geo_poly **model,
                           const geo_ctx *ctx, bool model_changed,
                           json_t **ret_report, json_t *summary, geo_err *err)
{
    geo_stats st;
    int r = geo_inspect(*model, NULL, ctx, &st, err);
    if (r < 0)
        return r;
    if (model_changed && !st.valid && !op->u.inspect.keep_invalid) {
        char why[160];
        invalid_reason(&st, why, sizeof why);
        geo_stats_clear(&st);
        return geo_err_set(err, -EINVAL, "the result is not a valid "
                           "polyhedron: %s (keep_invalid: true keeps it)",
                           why);
    }
    json_t *rep = proto_stats_to_json(&st);
    int e = !rep;
    e |= json_object_set_new(summary, "valid", json_boolean(st.valid));
    e |= json_object_set_new(summary, "closed", json_boolean(st.closed));
    e |= json_object_set_new(summary, "orientation",
                             json_string(geo_orientation_name(st.orientation)));
    e |= json_object_set_new(summary, "self_intersections",
                             json_integer((json_int_t)st.selfint.count));
    geo_stats_clear(&st);
    if (e) {
        json_decref(rep);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    *ret_report = rep;
    return 0;
}

/* report (lib/gem/report.h): the stone's tiers, proportions and facet
 * table, model unchanged; with scan, each facet's deviation from input
 * (the job's model as submitted). A model without a table (a rough) and
 * no axis is not an error of the job, whose model is still the result:
 * the report says {"table": false, "reason": ...} and the summary has no
 * proportions. */
static int run_report(const proto_op *op, geo_poly **model,
                      const geo_poly *input, json_t **ret_report,
                      json_t *summary, geo_err *err)
{
    geo_report rep;
    geo_err why = {{0}};
    int r = geo_report_compute(*model, op->u.report.have_axis
                                           ? op->u.report.axis : NULL,
                               op->u.report.gear, &rep, &why);
    if (r == -ENOMEM)
        return geo_err_set(err, r, "%s", why.msg);
    json_t *j;
    int e = 0;
    if (r < 0) {
        j = json_pack("{s:b, s:s}", "table", 0, "reason", why.msg);
    } else {
        if (op->u.report.scan && input &&
            (r = geo_report_scan_deviation(&rep, *model, input, err)) < 0) {
            geo_report_free(&rep);
            return r;
        }
        j = proto_report_to_json(&rep);
        if (rep.has_table) {
            e |= json_object_set_new(summary, "table_percent",
                                     json_real(rep.table_percent));
            e |= json_object_set_new(summary, "crown_angle_deg",
                                     json_real(rep.crown_angle_deg.mean));
            e |= json_object_set_new(summary, "pavilion_angle_deg",
                                     json_real(rep.pavilion_angle_deg.mean));
            e |= json_object_set_new(summary, "total_depth_percent",
                                     json_real(rep.total_depth_percent));
        }
        geo_report_free(&rep);
    }
    if (e || !j) {
        json_decref(j);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    *ret_report = j;
    return 0;
}

/* compare (lib/gem/compare.h): the job's model (B) laid onto the
 * op's reference (A) and measured; the model is not changed. The summary
 * gets compare_aligned, compare_rotation_deg, compare_hausdorff_mm and
 * compare_mean_distance_mm (apart from correct's hausdorff). */
static int run_compare(const proto_op *op, geo_poly **model,
                       const geo_ctx *ctx, json_t **ret_report,
                       json_t *summary, geo_err *err)
{
    geo_compare_opts o = {
        .axis = op->u.compare.have_axis ? op->u.compare.axis : NULL,
        .name_a = "reference", .name_b = "model"};
    geo_compare_result res;
    int r = geo_compare(op->u.compare.reference, *model, &o, ctx, &res, err);
    if (r < 0)
        return r;
    json_t *j = proto_compare_to_json(&res);
    int e = !j;
    e |= json_object_set_new(summary, "compare_aligned",
                             json_boolean(res.aligned));
    e |= json_object_set_new(summary, "compare_rotation_deg",
                             json_real(res.rotation_deg));
    e |= json_object_set_new(summary, "compare_hausdorff_mm",
                             json_real(res.hausdorff_mm));
    e |= json_object_set_new(summary, "compare_mean_distance_mm",
                             json_real(res.mean_distance_mm));
    geo_compare_free(&res);
    if (e) {
        json_decref(j);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    *ret_report = j;
    return 0;
}

static int run_inspect(const proto_op *op, geo_poly **model,
                       const geo_ctx *ctx, json_t **ret_report,
                       json_t *summary, geo_err *err)
{
    return inspect_checked(op, model, ctx, false, ret_report, summary, err);
}

/* triangulate (lib/frep/triangulate.h): the frep input to a closed mesh; the
 * report is the quality report (proto/tri_report_json.h). */
static int run_triangulate(const proto_op *op, const geo_frep *f,
                           geo_poly **model, const geo_ctx *ctx,
                           json_t **ret_report, json_t *summary, geo_err *err)
{
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    o.quad_levels = op->u.triangulate.quad_levels;
    o.binary_levels = op->u.triangulate.binary_levels;
    o.fill = op->u.triangulate.fill_edges ? GEO_FILL_EDGES : GEO_FILL_AREA;
    o.refine = op->u.triangulate.refine;
    o.sharpen = op->u.triangulate.sharpen;
    o.fair = op->u.triangulate.fair == PROTO_FAIR_LENGTH    ? GEO_FAIR_LENGTH
             : op->u.triangulate.fair == PROTO_FAIR_UNIFORM ? GEO_FAIR_UNIFORM
                                                            : GEO_FAIR_NONE;
    geo_tri_report rep;
    geo_poly *m = NULL;
    int r = geo_triangulate(f, &o, ctx, &m, &rep, err);
    if (r < 0)
        return r;
    json_t *j = proto_tri_report_to_json(&rep);
    const geo_frep_metrics *q = &rep.quality;
    int e = !j;
    e |= json_object_set_new(summary, "closed",
                             json_boolean(q->boundary_edges == 0 &&
                                          q->nonmanifold_edges == 0));
    e |= json_object_set_new(summary, "self_intersections",
                             json_integer((json_int_t)rep.self_intersections));
    e |= json_object_set_new(summary, "empty", json_boolean(rep.empty));
    geo_tri_report_clear(&rep);
    if (e) {
        json_decref(j);
        geo_poly_free(m);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    geo_poly_free(*model);
    *model = m;
    *ret_report = j;
    return 0;
}

/* Hands a kernel's JSON report over, or fails with -ENOMEM. */
static int give_report(json_t *rep, json_t **ret_report, geo_err *err)
{
    if (!rep)
        return geo_err_set(err, -ENOMEM, "out of memory");
    *ret_report = rep;
    return 0;
}

/* collapse (lib/correct/clusters.h): radius 0 means the kernel's
 * default relative to the model's size. */
static int run_collapse(const proto_op *op, geo_poly **model,
                        const geo_ctx *ctx, json_t **ret_report,
                        json_t *summary, geo_err *err)
{
    (void)summary;
    geo_collapse_opts o;
    geo_collapse_opts_default(&o);
    o.radius = op->u.collapse.radius;
    geo_collapse_report rep;
    int r = geo_collapse(*model, &o, ctx, &rep, err);
    if (r < 0)
        return r;
    json_t *j = proto_collapse_report_to_json(&rep);
    geo_collapse_report_clear(&rep);
    return give_report(j, ret_report, err);
}

/* merge (lib/correct/merge.h): the given groups, or automatic ones. */
static int run_merge(const proto_op *op, geo_poly **model, const geo_ctx *ctx,
                     json_t **ret_report, json_t *summary, geo_err *err)
{
    (void)summary;
    geo_merge_opts o;
    geo_merge_opts_default(&o);
    o.max_angle_deg = op->u.merge.max_angle_deg;
    o.max_deviation = op->u.merge.max_deviation;
    o.views = op->u.merge.views;
    geo_merge_report rep = {0};
    int r = op->u.merge.ngroups
                ? geo_merge_groups(*model, op->u.merge.ngroups,
                                   op->u.merge.gstart, op->u.merge.gfacets,
                                   &o, ctx, &rep, err)
                : geo_merge_auto(*model, &o, ctx, &rep, err);
    if (r < 0)
        return r;
    json_t *j = proto_merge_report_to_json(&rep);
    geo_merge_report_clear(&rep);
    return give_report(j, ret_report, err);
}

/* correct (lib/correct/correct.h): the whole post-scan correction, the same call as
 * `facet correct`, so the daemon serves the same model. */
static int run_correct(const proto_op *op, geo_poly **model, const geo_ctx *ctx,
                    json_t **ret_report, json_t *summary, geo_err *err)
{
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    o.collapse.radius = op->u.correct.radius;
    o.merge.max_angle_deg = op->u.correct.max_angle_deg;
    o.merge.max_deviation = op->u.correct.max_deviation;
    o.merge.views = op->u.correct.views;
    o.convex = op->u.correct.convex;
    geo_correct_report rep;
    int r = geo_correct(*model, &o, ctx, &rep, err);
    if (r < 0)
        return r;
    json_t *j = proto_correct_report_to_json(&rep);
    int e = json_object_set_new(summary, "hausdorff", json_real(rep.hausdorff));
    e |= json_object_set_new(summary, "groups_merged",
                             json_integer(rep.merge.merged));
    geo_correct_report_clear(&rep);
    if (e) {
        json_decref(j);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    return give_report(j, ret_report, err);
}

/* 0 when p is a valid closed solid (lib/inspect/stats.h), else -EINVAL
 * with err "OP: the result is not a valid closed solid: REASONS" — the
 * ops that close meshes fail their job rather than pass an invalid model
 * on as a success. */
static int require_valid(const geo_poly *p, const char *op,
                         const geo_ctx *ctx, geo_err *err)
{
    geo_stats st;
    int r = geo_inspect(p, NULL, ctx, &st, err);
    if (r < 0)
        return r;
    bool valid = st.valid;
    json_t *vj = valid ? NULL : proto_validity_to_json(&st);
    geo_stats_clear(&st);
    if (valid)
        return 0;
    char text[400] = "";
    size_t n = 0;
    json_t *why = vj ? json_object_get(vj, "reasons") : NULL;
    for (size_t i = 0; why && i < json_array_size(why) && n < sizeof text;
         i++)
        n += (size_t)snprintf(text + n, sizeof text - n, "%s%s",
                              i ? "; " : "",
                              json_string_value(json_array_get(why, i)));
    json_decref(vj);
    return geo_err_set(err, -EINVAL, "%s: the result is not a valid closed "
                       "solid: %s", op, text);
}

/* fill (lib/mesh/fill.h): every hole closed and checked; a result that is
 * not valid (a hole left open: the report's reason) fails the job. */
static int run_fill(const proto_op *op, geo_poly **model,
                          const geo_ctx *ctx, json_t **ret_report,
                          json_t *summary, geo_err *err)
{
    geo_mesh_fill_opts o;
    geo_mesh_fill_opts_default(&o);
    o.fill.weight =
        op->u.fill.weight_length ? GEO_FILL_EDGES : GEO_FILL_AREA;
    o.fill.refine = op->u.fill.refine;
    o.fill.fair = op->u.fill.fair ? GEO_FAIR_UNIFORM : GEO_FAIR_NONE;
    o.parts_overlap = op->u.fill.parts_overlap;
    o.remove_crossing = op->u.fill.remove_crossing;
    geo_mesh_fill_report rep;
    int r = geo_fill(*model, &o, ctx, &rep, err);
    if (r < 0)
        return r;
    json_t *j = proto_fill_report_to_json(&rep);
    int e = !j;
    e |= json_object_set_new(summary, "holes_filled", json_integer(rep.nfilled));
    e |= json_object_set_new(summary, "holes_left_open",
                             json_integer(rep.nopen));
    uint32_t nopen = rep.nopen;
    char first[96] = "";
    for (uint32_t i = 0; i < rep.nloops && !first[0]; i++) {
        const geo_mesh_hole *h = &rep.holes[i];
        if (h->status != GEO_HOLE_FILLED &&
            h->status != GEO_HOLE_FILLED_PLANAR)
            snprintf(first, sizeof first, " (hole %u, %u vertices at vertex "
                     "%u: %s)", i, h->nverts, h->first_vertex,
                     geo_hole_status_name(h->status));
    }
    geo_mesh_fill_report_clear(&rep);
    if (e) {
        json_decref(j);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    if ((r = require_valid(*model, "fill", ctx, err)) < 0) {
        json_decref(j);
        if (r == -EINVAL && nopen) {
            char tail[160];
            snprintf(tail, sizeof tail, "; %u holes left open%s", nopen,
                     first);
            size_t have = strlen(err->msg);
            if (have + 1 < sizeof err->msg)
                snprintf(err->msg + have, sizeof err->msg - have, "%.*s",
                         (int)(sizeof err->msg - have - 1), tail);
        }
        return r;
    }
    *ret_report = j;
    return 0;
}

/* stitch (lib/mesh/stitch.h): the model's two pieces joined into one. */
static int run_stitch(const proto_op *op, geo_poly **model, const geo_ctx *ctx,
                      json_t **ret_report, json_t *summary, geo_err *err)
{
    (void)op;
    geo_poly *out = geo_poly_new();
    if (!out)
        return geo_err_set(err, -ENOMEM, "out of memory");
    geo_stitch_report rep;
    int r = geo_stitch_pieces(*model, NULL, ctx, out, &rep, err);
    if (r < 0) {
        geo_poly_free(out);
        return r;
    }
    json_t *j = proto_stitch_report_to_json(&rep);
    int e = !j;
    e |= json_object_set_new(summary, "stitch_openings_left",
                             json_integer(rep.fill.nopen));
    geo_stitch_report_clear(&rep);
    if (e) {
        json_decref(j);
        geo_poly_free(out);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    if ((r = require_valid(out, "stitch", ctx, err)) < 0) {
        json_decref(j);
        geo_poly_free(out);
        return r;
    }
    geo_poly_free(*model);
    *model = out;
    *ret_report = j;
    return 0;
}

/* cut (lib/cut/cut.h, Palachev 2012, §3): keeps plane(p) ≤ 0 and closes the
 * section; an unchanged or empty result is reported, not an error. */
static int run_cut(const proto_op *op, geo_poly **model, const geo_ctx *ctx,
                   json_t **ret_report, json_t *summary, geo_err *err)
{
    (void)summary;
    geo_poly *out = geo_poly_new();
    if (!out)
        return geo_err_set(err, -ENOMEM, "out of memory");
    geo_cut_report rep;
    int r = geo_cut(*model, op->u.cut.plane, NULL, ctx, out, &rep, err);
    if (r < 0) {
        geo_poly_free(out);
        return r;
    }
    json_t *o = json_pack(
        "{s:[ffff], s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:b, s:b, s:f, "
        "s:f, s:I, s:I}", "plane", op->u.cut.plane[0], op->u.cut.plane[1],
        op->u.cut.plane[2], op->u.cut.plane[3], "components",
        (json_int_t)rep.components, "new_facets", (json_int_t)rep.new_facets,
        "split_facets", (json_int_t)rep.split_facets, "pieces",
        (json_int_t)rep.pieces, "removed_facets",
        (json_int_t)rep.removed_facets, "new_vertices",
        (json_int_t)rep.new_vertices, "removed_vertices",
        (json_int_t)rep.removed_vertices, "hanging_dropped",
        (json_int_t)rep.hanging_dropped, "unchanged", rep.unchanged, "empty",
        rep.empty, "volume_before", rep.volume_before, "volume_after",
        rep.volume_after, "vertices", (json_int_t)out->nverts, "facets",
        (json_int_t)out->nfacets);
    if (!o) {
        geo_poly_free(out);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    geo_poly_free(*model);
    *model = out;
    *ret_report = o;
    return 0;
}

static enum geo_replanar_schedule schedule_of(proto_schedule s)
{
    return s == PROTO_SCHED_SCALED       ? GEO_REPLANAR_SCALED
           : s == PROTO_SCHED_GLOBAL_EXP ? GEO_REPLANAR_GLOBAL_EXP
           : s == PROTO_SCHED_LEAST_NORM ? GEO_REPLANAR_LEAST_NORM
                                         : GEO_REPLANAR_LOCAL_EXP;
}

/* move (lib/replanar/replanar.h, Palachev 2012, §4): places the vertex and
 * re-planarises. A result that is not a valid polyhedron (no convergence
 * within max_steps, a self-intersection, an inverted facet) fails the
 * job, as `facet move` refuses to write it: nothing invalid is passed on.
 * The report has the run's summary and its iteration log. */
static int run_move(const proto_op *op, geo_poly **model,
                           const geo_ctx *ctx, json_t **ret_report,
                           json_t *summary, geo_err *err)
{
    (void)summary;
    geo_poly *p = *model;
    uint32_t v = op->u.move.vertex;
    if (v >= p->nverts)
        return geo_err_set(err, -EINVAL, "vertex: %u out of range (%u "
                           "vertices)", v, p->nverts);
    double to[3];
    for (int k = 0; k < 3; k++)
        to[k] = op->u.move.xyz[k] + (op->u.move.relative ? p->verts[v][k] : 0);
    enum geo_replanar_schedule s = schedule_of(op->u.move.schedule);
    geo_replanar_opts o;
    geo_replanar_opts_default(&o, s);
    o.max_steps = op->u.move.max_steps;
    geo_replanar_log log = {0};
    geo_replanar_result res;
    int r = geo_move(p, v, to, s, &o, ctx, &log, &res, err);
    if (r < 0) {
        geo_replanar_log_clear(&log);
        return r;
    }
    if (!geo_replanar_result_valid(&res)) {
        geo_replanar_log_clear(&log);
        return geo_err_set(err, -EINVAL, "moving vertex %u does not give a "
                           "valid polyhedron (%s after %u steps, S2 %.3g mm)",
                           v, !res.converged ? "no convergence"
                              : res.nselfint > 0 ? "self-intersections"
                              : res.ninverted > 0 ? "inverted facets"
                                                  : "volume not positive",
                           res.steps, res.s2);
    }
    json_t *rep = json_object();
    int e = !rep;
    if (rep) {
        e |= json_object_set_new(rep, "vertex", json_integer(v));
        e |= json_object_set_new(rep, "to", json_pack("[fff]", to[0], to[1],
                                                       to[2]));
        e |= json_object_set_new(rep, "result",
                                 proto_replanar_result_to_json(&res, s));
        e |= json_object_set_new(rep, "log", proto_replanar_log_to_json(&log));
    }
    geo_replanar_log_clear(&log);
    if (e) {
        json_decref(rep);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    *ret_report = rep;
    return 0;
}

/* inversion_stats (lib/replanar/inversion.h, Palachev 2012, §4.3.4): the model is only
 * read; the runs go through ctx's parallel_for (the daemon's pool), the
 * op's seed replaces the job's. */
static int run_inversion_stats(const proto_op *op, geo_poly **model,
                               const geo_ctx *ctx, json_t **ret_report,
                               json_t *summary, geo_err *err)
{
    (void)summary;
    geo_inversion_opts o;
    geo_inversion_opts_default(&o);
    o.samples = op->u.inversion.samples;
    o.nmagnitudes = op->u.inversion.nmagnitudes;
    memcpy(o.magnitudes, op->u.inversion.magnitudes,
           o.nmagnitudes * sizeof o.magnitudes[0]);
    o.schedule = schedule_of(op->u.inversion.schedule);
    geo_replanar_opts_default(&o.replanar, o.schedule);
    geo_ctx c = {0};
    if (ctx)
        c = *ctx;
    c.seed = op->u.inversion.seed;
    geo_inversion_stats st = {0};
    int r = geo_inversion_stats_run(*model, &o, &c, &st, err);
    if (r < 0)
        return r;
    json_t *rep = proto_inversion_stats_to_json(&st);
    geo_inversion_stats_clear(&st);
    if (!rep)
        return geo_err_set(err, -ENOMEM, "out of memory");
    *ret_report = rep;
    return 0;
}

static const op_entry ops[PROTO_OP_COUNT] = {
    [PROTO_OP_INSPECT] = {run_inspect, false},
    [PROTO_OP_COLLAPSE] = {run_collapse, true},
    [PROTO_OP_MERGE] = {run_merge, true},
    [PROTO_OP_TRIANGULATE] = {NULL, true, run_triangulate},
    [PROTO_OP_FILL] = {run_fill, true},
    [PROTO_OP_STITCH] = {run_stitch, true},
    [PROTO_OP_CORRECT] = {run_correct, true},
    [PROTO_OP_CUT] = {run_cut, true},
    [PROTO_OP_MOVE] = {run_move, true},
    [PROTO_OP_INVERSION_STATS] = {run_inversion_stats, false},
    [PROTO_OP_REPORT] = {NULL, false}, /* run_report, given the input */
    [PROTO_OP_COMPARE] = {run_compare, false},
};

int runner_check_input(const proto_pipeline *p, bool frep, geo_err *err)
{
    for (size_t i = 0; i < p->nops; i++) {
        proto_op_kind k = p->ops[i].kind;
        bool takes_frep = (unsigned)k < PROTO_OP_COUNT && ops[k].run_frep;
        if (takes_frep && (!frep || i > 0))
            return geo_err_set(err, -EINVAL,
                               "pipeline[%zu]: op '%s' needs a 'frep' input "
                               "and must come first", i, proto_op_name(k));
        if (frep && i == 0 && !takes_frep)
            return geo_err_set(err, -EINVAL,
                               "pipeline[0]: op '%s' cannot take a 'frep' "
                               "input; start with 'triangulate'",
                               proto_op_name(k));
    }
    return 0;
}

int runner_check_model(const proto_pipeline *p, const geo_poly *m,
                       geo_err *err)
{
    for (size_t i = 0; i < p->nops; i++) {
        const proto_op *op = &p->ops[i];
        if (op->kind == PROTO_OP_MOVE && op->u.move.vertex >= m->nverts)
            return geo_err_set(err, -EINVAL, "pipeline[%zu].vertex: %u out "
                               "of range (%u vertices)", i, op->u.move.vertex,
                               m->nverts);
        if (op->kind == PROTO_OP_MERGE && op->u.merge.ngroups) {
            uint32_t n = op->u.merge.gstart[op->u.merge.ngroups];
            for (uint32_t k = 0; k < n; k++)
                if (op->u.merge.gfacets[k] >= m->nfacets)
                    return geo_err_set(err, -EINVAL, "pipeline[%zu].groups: "
                                       "facet %u out of range (%u facets)",
                                       i, op->u.merge.gfacets[k], m->nfacets);
        }
        if (ops[op->kind].changes_model)
            break; /* later indices name the changed model */
    }
    return 0;
}

bool runner_changes_model(const proto_pipeline *p)
{
    for (size_t i = 0; i < p->nops; i++)
        if (ops[p->ops[i].kind].changes_model)
            return true;
    return false;
}

/* Maps an operation's progress into its share of the whole run. */
typedef struct sub_progress {
    const geo_ctx *outer;
    double base, span;
} sub_progress;

static int sub_report(void *user, double fraction)
{
    sub_progress *s = user;
    if (fraction < 0)
        fraction = 0;
    if (fraction > 1)
        fraction = 1;
    return geo_ctx_progress(s->outer, s->base + s->span * fraction) < 0;
}

static double mono_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec / 1e9;
}

static int add_counts(json_t *summary, const char *suffix, const geo_poly *p)
{
    char k1[32], k2[32];
    snprintf(k1, sizeof k1, "vertices_%s", suffix);
    snprintf(k2, sizeof k2, "facets_%s", suffix);
    return json_object_set_new(summary, k1, json_integer(p->nverts)) |
           json_object_set_new(summary, k2, json_integer(p->nfacets));
}

static int run_pipeline(const proto_pipeline *p, const geo_frep *frep,
                        geo_poly **model, const geo_ctx *ctx,
                        runner_op_timer timer, void *timer_user,
                        json_t **ret_stats, json_t **ret_summary,
                        geo_err *err)
{
    int r = runner_check_input(p, frep != NULL, err);
    if (r < 0)
        return r;
    json_t *stats = json_object(), *list = json_array(),
           *summary = json_object();
    json_t *before = NULL, *after = NULL;
    bool changed = false;
    double t_start = mono_seconds();
    /* the model as submitted, kept only for a report that measures the
     * result against it */
    geo_poly *input = NULL;
    for (size_t i = 0; i < p->nops && *model && !input; i++)
        if (p->ops[i].kind == PROTO_OP_REPORT && p->ops[i].u.report.scan &&
            !(input = geo_poly_copy(*model))) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto fail;
        }
    if (!stats || !list || !summary ||
        (*model && add_counts(summary, "before", *model))) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    for (size_t i = 0; i < p->nops; i++) {
        const proto_op *op = &p->ops[i];
        sub_progress sp = {ctx, (double)i / (double)p->nops,
                           1.0 / (double)p->nops};
        geo_ctx sub = {0};
        if (ctx)
            sub = *ctx;
        sub.progress = sub_report;
        sub.user = &sp;
        if (geo_ctx_progress(ctx, sp.base) < 0) {
            r = geo_err_set(err, -ECANCELED, "canceled");
            goto fail;
        }
        json_t *report = NULL;
        double t0 = mono_seconds();
        /* every op the parser knows has its kernel in the table */
        assert((unsigned)op->kind < PROTO_OP_COUNT &&
               (ops[op->kind].run || ops[op->kind].run_frep ||
                op->kind == PROTO_OP_REPORT));
        r = ops[op->kind].run_frep
                ? ops[op->kind].run_frep(op, frep, model, &sub, &report,
                                         summary, err)
            : op->kind == PROTO_OP_INSPECT
                ? inspect_checked(op, model, &sub, changed, &report, summary,
                                  err)
            : op->kind == PROTO_OP_REPORT
                ? run_report(op, model, input, &report, summary, err)
                : ops[op->kind].run(op, model, &sub, &report, summary, err);
        double secs = mono_seconds() - t0;
        if (timer)
            timer(timer_user, op->kind, secs);
        if (r < 0) {
            json_decref(report);
            char where[64];
            snprintf(where, sizeof where, "pipeline[%zu] (%s)", i,
                     proto_op_name(op->kind));
            geo_err_prefix(err, where);
            goto fail;
        }
        changed |= ops[op->kind].changes_model;
        if (op->kind == PROTO_OP_INSPECT && report) {
            if (!before)
                before = json_incref(report);
            else if (changed) {
                json_decref(after);
                after = json_incref(report);
            }
        }
        json_t *entry = json_pack("{s:s, s:f, s:o}", "op",
                                  proto_op_name(op->kind), "ms", secs * 1e3,
                                  "report", report ? report : json_null());
        if (!entry || json_array_append_new(list, entry) < 0) {
            r = geo_err_set(err, -ENOMEM, "out of memory");
            goto fail;
        }
    }
    if (geo_ctx_progress(ctx, 1.0) < 0) {
        r = geo_err_set(err, -ECANCELED, "canceled");
        goto fail;
    }
    /* json_object_set_new consumes its value even when it fails. */
    int e = json_object_set_new(stats, "ops", list);
    e |= json_object_set_new(stats, "before", before ? before : json_null());
    e |= json_object_set_new(stats, "after", after ? after : json_null());
    list = before = after = NULL;
    e |= add_counts(summary, "after", *model);
    e |= json_object_set_new(summary, "ms",
                             json_real((mono_seconds() - t_start) * 1e3));
    if (e) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto fail;
    }
    geo_poly_free(input);
    *ret_stats = stats;
    *ret_summary = summary;
    return 0;
fail:
    geo_poly_free(input);
    json_decref(stats);
    json_decref(list);
    json_decref(summary);
    json_decref(before);
    json_decref(after);
    return r;
}

int runner_run(const proto_pipeline *p, geo_poly **model, const geo_ctx *ctx,
               runner_op_timer timer, void *timer_user, json_t **ret_stats,
               json_t **ret_summary, geo_err *err)
{
    return run_pipeline(p, NULL, model, ctx, timer, timer_user, ret_stats,
                        ret_summary, err);
}

int runner_run_frep(const proto_pipeline *p, const geo_frep *f,
                    geo_poly **ret_model, const geo_ctx *ctx,
                    runner_op_timer timer, void *timer_user,
                    json_t **ret_stats, json_t **ret_summary, geo_err *err)
{
    geo_poly *m = NULL;
    int r = run_pipeline(p, f, &m, ctx, timer, timer_user, ret_stats,
                         ret_summary, err);
    if (r < 0) {
        geo_poly_free(m);
        m = NULL;
    }
    *ret_model = m;
    return r;
}
