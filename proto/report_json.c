/* report_json.c — the stone report as JSON (report_json.h). */
#include "report_json.h"

static json_t *range(const geo_range *r)
{
    return json_pack("{s:f, s:f, s:f}", "min", r->min, "max", r->max, "mean",
                     r->mean);
}

static json_t *vec3(const double v[3])
{
    return json_pack("[f, f, f]", v[0], v[1], v[2]);
}

json_t *proto_report_to_json(const geo_report *r)
{
    json_t *facets = json_array();
    for (uint32_t f = 0; f < r->nfacets; f++) {
        const geo_report_facet *F = &r->facets[f];
        json_t *e = json_pack("{s:s, s:f, s:f, s:f, s:f, s:f}", "tier",
                              geo_tier_name(F->tier), "inclination_deg",
                              F->inclination_deg, "azimuth_deg",
                              F->azimuth_deg, "index", F->index,
                              "distance_mm", F->distance_mm, "area_mm2",
                              F->area_mm2);
        if (r->scan) /* null: no sample of the scan is nearest to it */
            json_object_set_new(
                e, "scan_deviation_um",
                r->scan[f].samples
                    ? json_pack("{s:f, s:f}", "max", r->scan[f].max_um,
                                "rms", r->scan[f].rms_um)
                    : json_null());
        json_array_append_new(facets, e);
    }
    json_t *tiers = json_object();
    for (int t = 0; t < 5; t++)
        json_object_set_new(tiers, geo_tier_name((enum geo_tier)t),
                            json_integer(r->tier_count[t]));
    json_t *o = json_object();
    json_object_set_new(o, "table", json_boolean(r->has_table));
    json_object_set_new(o, "axis", vec3(r->axis));
    json_object_set_new(o, "axis_point", vec3(r->center));
    json_object_set_new(o, "table_percent", json_real(r->table_percent));
    json_object_set_new(o, "diameter_mm", range(&r->diameter_mm));
    json_object_set_new(o, "length_mm", json_real(r->length_mm));
    json_object_set_new(o, "width_mm", json_real(r->width_mm));
    json_object_set_new(o, "length_to_width", json_real(r->length_to_width));
    json_object_set_new(o, "total_depth_percent",
                        json_real(r->total_depth_percent));
    json_object_set_new(o, "crown_height_percent",
                        json_real(r->crown_height_percent));
    json_object_set_new(o, "pavilion_depth_percent",
                        json_real(r->pavilion_depth_percent));
    json_object_set_new(o, "girdle_thickness_percent",
                        range(&r->girdle_thickness_percent));
    json_object_set_new(o, "culet_percent", json_real(r->culet_percent));
    json_object_set_new(o, "crown_angle_deg", json_real(r->crown_angle_deg.mean));
    json_object_set_new(o, "crown_angle_spread_deg",
                        json_pack("{s:f, s:f}", "min", r->crown_angle_deg.min,
                                  "max", r->crown_angle_deg.max));
    json_object_set_new(o, "crown_mains", json_integer(r->crown_mains));
    json_object_set_new(o, "pavilion_angle_deg",
                        json_real(r->pavilion_angle_deg.mean));
    json_object_set_new(o, "pavilion_angle_spread_deg",
                        json_pack("{s:f, s:f}", "min",
                                  r->pavilion_angle_deg.min, "max",
                                  r->pavilion_angle_deg.max));
    json_object_set_new(o, "pavilion_mains", json_integer(r->pavilion_mains));
    json_object_set_new(o, "tiers", tiers);
    json_object_set_new(o, "facets", facets);
    return o;
}
