/* report_json.h — the stone report of lib/gem/report.h as JSON, the one
 * writer behind `facet report` and the pipeline op `report`: table,
 * axis, axis_point, table_percent, diameter_mm {min, max, mean},
 * length_mm, width_mm, length_to_width, total_depth_percent,
 * crown_height_percent, pavilion_depth_percent, girdle_thickness_percent
 * {min, max, mean}, culet_percent, crown_angle_deg and its spread,
 * crown_mains, pavilion_angle_deg and its spread, pavilion_mains, tiers
 * (count per tier) and facets (per input facet: tier, inclination_deg,
 * azimuth_deg, index, distance_mm, area_mm2). */
#ifndef PROTO_REPORT_JSON_H
#define PROTO_REPORT_JSON_H

#include <jansson.h>

#include "report.h"

/* A new object, or NULL on out-of-memory. */
json_t *proto_report_to_json(const geo_report *r);

#endif
