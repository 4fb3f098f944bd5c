/* compare_json.h — the comparison of lib/gem/compare.h as JSON, the one
 * writer behind `facet compare` and the pipeline op `compare`: aligned,
 * rotation_deg, rotation_axis, translation_mm, axis, coverage,
 * hausdorff_mm, mean_distance_mm, volume_difference_relative,
 * matched_facets, unmatched_a, unmatched_b and facets (per matched pair:
 * a, b, angle_deg, offset_mm), in that order (docs/kernels/compare.md). */
#ifndef PROTO_COMPARE_JSON_H
#define PROTO_COMPARE_JSON_H

#include <jansson.h>

#include "compare.h"

/* A new object, or NULL on out-of-memory. */
json_t *proto_compare_to_json(const geo_compare_result *r);

#endif
