/* tri_report_json.c — geo_tri_report → JSON (see tri_report_json.h). */
#include "tri_report_json.h"

#include <math.h>

/* A number, or null where it is not finite (JSON has no infinity: the
 * deviation |F|/|∇F| is infinite at a vertex where ∇F vanishes, and
 * json_pack's "f" refused it, which the callers took for out-of-memory). */
static json_t *num(double x)
{
    return isfinite(x) ? json_real(x) : json_null();
}

json_t *proto_tri_report_to_json(const geo_tri_report *r)
{
    const geo_frep_metrics *q = &r->quality;
    json_t *open = json_array();
    if (!open)
        return NULL;
    for (uint32_t i = 0; i < r->fill.nholes; i++) {
        const geo_hole_report *h = &r->fill.holes[i];
        if (h->status == GEO_HOLE_FILLED)
            continue;
        json_array_append_new(
            open, json_pack("{s:I, s:I, s:s}", "vertices", (json_int_t)h->nverts,
                            "first_vertex", (json_int_t)h->first_vertex,
                            "reason", geo_hole_status_name(h->status)));
    }
    json_t *j = json_pack(
        "{s:I, s:I, s:I, s:[o,o,o],"
        " s:{s:o, s:o, s:o},"
        " s:{s:o, s:o, s:o, s:{s:I, s:o, s:o, s:o}},"
        " s:{s:o, s:o, s:o, s:o},"
        " s:{s:I, s:I, s:I, s:o},"
        " s:{s:I, s:I, s:I, s:I, s:I, s:I, s:I},"
        " s:o, s:o}",
        "triangles", (json_int_t)q->nfacets, "vertices", (json_int_t)q->nverts,
        "surface_points", (json_int_t)r->npoints, "voxel", num(r->voxel[0]),
        num(r->voxel[1]), num(r->voxel[2]),
        "deviation", "max", num(q->dev_max), "mean", num(q->dev_mean),
        "rms", num(q->dev_rms),
        "normal_deviation", "max", num(q->ndev_max), "mean",
        num(q->ndev_mean), "p95", num(q->ndev_p95), "away_from_creases",
        "vertices", (json_int_t)q->nsmooth, "max", num(q->sdev_max), "mean",
        num(q->sdev_mean), "p95", num(q->sdev_p95),
        "uniformity", "edge_mean", num(q->edge_mean), "edge_cv",
        num(q->edge_cv),
        "area_mean", num(q->area_mean), "area_cv", num(q->area_cv),
        "holes", "found", (json_int_t)r->fill.nholes, "filled",
        (json_int_t)r->fill.nfilled, "left_open", (json_int_t)r->fill.nopen,
        "open", open,
        "topology", "boundary_edges", (json_int_t)q->boundary_edges,
        "nonmanifold_edges", (json_int_t)q->nonmanifold_edges, "flipped_edges",
        (json_int_t)q->flipped_edges, "nonmanifold_vertices",
        (json_int_t)q->nonmanifold_vertices, "euler", (json_int_t)q->euler,
        "self_intersections", (json_int_t)r->self_intersections,
        "degenerate_facets", (json_int_t)r->ndegenerate,
        "volume", num(q->volume), "area", num(q->area));
    if (!j)
        return NULL;
    json_t *stages = json_pack(
        "{s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I}", "quads",
        (json_int_t)r->connect.nquads, "cells_open",
        (json_int_t)r->connect.nopen, "pinched", (json_int_t)r->npinched,
        "refine_splits", (json_int_t)r->fill.nsplits, "flips",
        (json_int_t)r->fill.nflips, "hard_splits",
        (json_int_t)r->fill.nhard_splits, "crease_splits",
        (json_int_t)r->sharpen.nedge_splits, "crease_snaps",
        (json_int_t)r->sharpen.nsnaps, "crease_corners",
        (json_int_t)r->sharpen.ncorners, "evaluations", (json_int_t)r->nevals,
        "boxes", (json_int_t)r->nboxes);
    if (stages &&
        (json_object_set_new(stages, "crease_middle_splits",
                             json_integer(r->sharpen.nmiddle_splits)) < 0 ||
         json_object_set_new(stages, "crease_corner_flips",
                             json_integer(r->sharpen.ncorner_flips)) < 0 ||
         json_object_set_new(stages, "crease_refused",
                             json_integer(r->sharpen.nrejected)) < 0 ||
         json_object_set_new(stages, "empty_pieces_dropped",
                             json_integer(r->ndropped)) < 0)) {
        json_decref(stages);
        stages = NULL;
    }
    json_t *time = json_pack("{s:f, s:f, s:f, s:f, s:f, s:f}", "sample",
                             r->t_sample, "connect", r->t_connect, "fill",
                             r->t_fill, "sharpen", r->t_sharpen, "metrics",
                             r->t_metrics, "total", r->t_total);
    if (!stages || !time ||
        json_object_set_new(j, "empty", json_boolean(r->empty)) < 0 ||
        json_object_set_new(j, "stages", stages) < 0 ||
        json_object_set_new(j, "time", time) < 0) {
        json_decref(j);
        return NULL;
    }
    return j;
}
