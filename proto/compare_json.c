/* compare_json.c — the comparison as JSON (compare_json.h). */
#include "compare_json.h"

static json_t *vec3(const double v[3])
{
    return json_pack("[f, f, f]", v[0], v[1], v[2]);
}

json_t *proto_compare_to_json(const geo_compare_result *r)
{
    json_t *facets = json_array(), *o = json_object();
    int e = !facets || !o;
    for (uint32_t k = 0; !e && k < r->matched; k++) {
        const geo_compare_pair *p = &r->pairs[k];
        e |= json_array_append_new(
            facets, json_pack("{s:I, s:I, s:f, s:f}", "a", (json_int_t)p->a,
                              "b", (json_int_t)p->b, "angle_deg",
                              p->angle_deg, "offset_mm", p->offset_mm));
    }
    if (e) {
        json_decref(facets);
        json_decref(o);
        return NULL;
    }
    e |= json_object_set_new(o, "aligned", json_boolean(r->aligned));
    e |= json_object_set_new(o, "rotation_deg", json_real(r->rotation_deg));
    e |= json_object_set_new(o, "rotation_axis", vec3(r->rotation_axis));
    e |= json_object_set_new(o, "translation_mm", vec3(r->translation));
    e |= json_object_set_new(o, "axis", vec3(r->axis));
    e |= json_object_set_new(o, "coverage", json_real(r->coverage));
    e |= json_object_set_new(o, "hausdorff_mm", json_real(r->hausdorff_mm));
    e |= json_object_set_new(o, "mean_distance_mm",
                             json_real(r->mean_distance_mm));
    e |= json_object_set_new(o, "volume_difference_relative",
                             json_real(r->volume_difference_relative));
    e |= json_object_set_new(o, "matched_facets", json_integer(r->matched));
    e |= json_object_set_new(o, "unmatched_a", json_integer(r->unmatched_a));
    e |= json_object_set_new(o, "unmatched_b", json_integer(r->unmatched_b));
    e |= json_object_set_new(o, "facets", facets);
    if (e) {
        json_decref(o);
        return NULL;
    }
    return o;
}
