/* tri_report_json.h — the triangulation report (lib/frep/triangulate.h) as
 * JSON, for `facet triangulate --metrics` and the job statistics.
 *
 * Shape (units: model units, degrees, seconds):
 *   {"triangles", "vertices", "surface_points", "voxel": [x, y, z],
 *    "deviation": {"max", "mean", "rms"},
 *    "normal_deviation": {"max", "mean", "p95",
 *                         "away_from_creases": {"vertices", "max", "mean", "p95"}},
 *    "uniformity": {"edge_mean", "edge_cv", "area_mean", "area_cv"},
 *    "holes": {"found", "filled", "left_open", "open": [{"vertices",
 *              "first_vertex", "reason"}, ...]},
 *    "topology": {"boundary_edges", "nonmanifold_edges", "flipped_edges",
 *                 "nonmanifold_vertices", "euler", "self_intersections",
 *                 "degenerate_facets"},
 *    "volume", "area",
 *    "stages": {"quads", "cells_open", "pinched", "refine_splits", "flips",
 *               "hard_splits", "crease_splits", "crease_snaps",
 *               "crease_corners", "crease_middle_splits",
 *               "crease_corner_flips", "crease_refused", "evaluations",
 *               "boxes"},
 *    "time": {"sample", "connect", "fill", "sharpen", "metrics", "total"}}
 * Reentrant; returns NULL on out-of-memory. */
#ifndef PROTO_TRI_REPORT_JSON_H
#define PROTO_TRI_REPORT_JSON_H

#include <jansson.h>

#include "triangulate.h"

json_t *proto_tri_report_to_json(const geo_tri_report *r);

#endif
