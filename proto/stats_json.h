/* stats_json.h — the inspection statistics (lib/inspect/stats.h) as a JSON object:
 * the body `facet inspect` prints and the daemon serves.
 *
 * Keys (definitions in lib/inspect/stats.h): vertices, edges, facets, closed,
 * boundary_edges, holes, nonmanifold_edges, nonmanifold_vertices,
 * orientation ("outward" | "inward" | "inconsistent"),
 * inconsistent_facets, volume (mm³), area (mm²), max_nonplanarity (mm),
 * nonconvex_facets, degenerate_facets, self_intersections {count, pairs:
 * [[a, b], ...] sorted, capped; [f, f] is a facet intersecting itself},
 * self_intersecting_facets, near_coplanar_pairs {"0.5": n, "1": n,
 * "2": n} (keys are the thresholds in degrees, %g), vertex_degrees
 * {"3": n, ...} (degrees with at least one vertex), short_edge_clusters,
 * valid. Also: eps, inverted_facets, shells, orientable,
 * low_degree_vertices, degenerate_edges, short_edge_radius,
 * short_edge_cluster_vertices.
 *
 * Ownership: the returned value is new (json_decref); NULL on
 * out-of-memory. Reentrant. */
#ifndef PROTO_STATS_JSON_H
#define PROTO_STATS_JSON_H

#include <jansson.h>

#include "stats.h"

json_t *proto_stats_to_json(const geo_stats *s);

#endif
