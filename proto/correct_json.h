/* correct_json.h — JSON forms of the facet-merging report (lib/correct/merge.h),
 * the cluster-collapse report (lib/correct/clusters.h) and the automatic
 * correction's report (lib/correct/correct.h), shared by the `facet` CLI and the
 * daemon's pipeline.
 *
 * Shapes (lengths mm, volumes mm³; a non-finite number is null):
 *   group:    {"facets": [ids], "merged": bool, "reason": "..." (only when
 *              not merged), "facet": index in the output or null, "plane":
 *              [a,b,c,d], "contour", "hanging", "lifts", "joins",
 *              "new_vertices", "moved", "max_lift", "dev_before",
 *              "dev_after", "volume_change"}
 *   merge:    {"groups": n, "merged", "failed", "rounds",
 *              "statement_violations", "vertices_before", "facets_before",
 *              "vertices_after", "facets_after", "volume_before",
 *              "volume_after", "group_list": [group...],
 *              "moved_vertices": [{"vertex", "by": [dx,dy,dz], "distance"}]}
 *   collapse: {"radius", "clusters", "collapsed", "rolled_back",
 *              "attempts", "vertices_before", "vertices_after",
 *              "facets_before", "facets_after", "max_displacement",
 *              "replanar_steps", "cluster_list": [{"vertices": [ids],
 *              "vertex": new index or null}]}
 *   correct:  {"vertices_before", "facets_before", "vertices_after",
 *              "facets_after", "volume_before", "volume_after",
 *              "volume_change", "hausdorff", "rounds", "merge_passes",
 *              "reoriented_facets", "clusters": {"found", "collapsed",
 *              "rolled_back", "max_displacement"}, "merge": merge (its
 *              group ids numbered per pass, see lib/correct/correct.h; "facet" of
 *              a group is its index after that pass), "convex": null
 *              (not asked for) or {"used", "reason" (why not, or null),
 *              "groups", "planes", "dropped", "redundant", "narrow",
 *              "concavity", "deviation", "bound"}, "moved_vertices":
 *              [...], "valid": after.valid, "before": stats, "after":
 *              stats (proto/stats_json.h)}
 *
 * Every function returns a new reference (json_decref) or NULL on
 * out-of-memory; inputs are only read. Thread-safe. */
#ifndef PROTO_CORRECT_JSON_H
#define PROTO_CORRECT_JSON_H

#include <jansson.h>

#include "clusters.h"
#include "correct.h"
#include "merge.h"


json_t *proto_merge_report_to_json(const geo_merge_report *r);

json_t *proto_collapse_report_to_json(const geo_collapse_report *r);

json_t *proto_correct_report_to_json(const geo_correct_report *r);

#endif
