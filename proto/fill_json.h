/* fill_json.h — the hole-filling report (lib/mesh/fill.h) as JSON, for `facet
 * fill --report`, the fill_holes operation and the stitch report.
 *
 * Shape (lengths in model units, angles in degrees):
 *   {"loops", "filled", "planar", "left_open", "rejected_patches",
 *    "facets_removed", "facets_split", "facets_reversed",
 *    "vertices_added", "facets_added", "max_dihedral_deg",
 *    "holes": [{"vertices", "first_vertex", "status", "attempt"?,
 *               "facets_added", "vertices_added", "planarity"?,
 *               "max_dihedral_deg"?, "edge_ratio"?}, ...]}
 * status is geo_hole_status_name ("filled", "filled_planar", or why the
 * hole is open: "intersects_mesh", "too_large", "no_triangulation",
 * "not_a_loop", "degenerate"); attempt (geo_fill_attempt_name) is given
 * for holes that were tried, planarity when the loop has a plane, the
 * angle and ratio for filled holes. Reentrant; NULL on out-of-memory. */
#ifndef PROTO_FILL_JSON_H
#define PROTO_FILL_JSON_H

#include <jansson.h>

#include "fill.h"
#include "stats.h"
#include "stitch.h"

json_t *proto_fill_report_to_json(const geo_mesh_fill_report *r);

/* The stitching report (lib/mesh/stitch.h):
 *   {"method": "planes" | "band" | "weld", "planes",
 *    "loops": [l1, l2], "joined": [i1, i2], "loop_vertices": [n1, n2],
 *    "chosen": [c1, c2], "band", "flipped", "swapped", "twist",
 *    "meridians", "rows", "meridian_length", "segment",
 *    "band_vertices", "band_facets", "welded", "welded_loops",
 *    "inserted", "openings": the fill report}
 * NULL on out-of-memory. */
json_t *proto_stitch_report_to_json(const geo_stitch_report *r);

/* The verdict of geo_inspect on a result, with why it is not valid:
 *   {"valid", "volume", "reasons": ["3 boundary edges (1 holes)", ...]}
 * reasons is empty for a valid model and names every failed condition of
 * geo_stats.valid otherwise. NULL on out-of-memory. */
json_t *proto_validity_to_json(const geo_stats *s);

#endif
