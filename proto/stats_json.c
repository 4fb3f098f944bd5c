/* stats_json.c — geo_stats → JSON object (keys in stats_json.h). Every
 * json_object_set_new steals its value, so a failed step leaks nothing:
 * the object is dropped whole. */
#include "stats_json.h"

#include <stdio.h>

static json_t *pairs_json(const geo_selfint *si)
{
    json_t *a = json_array();
    for (uint32_t i = 0; a && i < si->npairs; i++) {
        json_t *pr = json_pack("[II]", (json_int_t)si->pairs[i][0],
                               (json_int_t)si->pairs[i][1]);
        if (!pr || json_array_append_new(a, pr) < 0) {
            json_decref(a);
            return NULL;
        }
    }
    return a;
}

json_t *proto_stats_to_json(const geo_stats *s)
{
    json_t *o = json_object();
    json_t *cop = json_object(), *deg = json_object();
    json_t *si = json_pack("{s:I,s:o*}", "count",
                           (json_int_t)s->selfint.count, "pairs",
                           pairs_json(&s->selfint));
    if (!o || !cop || !deg || !si || !json_object_get(si, "pairs"))
        goto oom;
    for (int k = 0; k < GEO_STATS_NCOPLANAR; k++) {
        char key[32];
        snprintf(key, sizeof key, "%g", s->coplanar_deg[k]);
        if (json_object_set_new(cop, key,
                                json_integer(s->near_coplanar[k])) < 0)
            goto oom;
    }
    for (uint32_t d = 0; s->degree_count && d <= s->max_degree; d++) {
        if (!s->degree_count[d])
            continue;
        char key[16];
        snprintf(key, sizeof key, "%u", d);
        if (json_object_set_new(deg, key, json_integer(s->degree_count[d])) <
            0)
            goto oom;
    }
    int rc = 0;
    rc |= json_object_set_new(o, "vertices", json_integer(s->vertices));
    rc |= json_object_set_new(o, "edges", json_integer(s->edges));
    rc |= json_object_set_new(o, "facets", json_integer(s->facets));
    rc |= json_object_set_new(o, "closed", json_boolean(s->closed));
    rc |= json_object_set_new(o, "boundary_edges",
                              json_integer(s->boundary_edges));
    rc |= json_object_set_new(o, "holes", json_integer(s->holes));
    rc |= json_object_set_new(o, "nonmanifold_edges",
                              json_integer(s->nonmanifold_edges));
    rc |= json_object_set_new(o, "nonmanifold_vertices",
                              json_integer(s->nonmanifold_vertices));
    rc |= json_object_set_new(o, "low_degree_vertices",
                              json_integer(s->low_degree_vertices));
    rc |= json_object_set_new(o, "orientation",
                              json_string(geo_orientation_name(s->orientation)));
    rc |= json_object_set_new(o, "inconsistent_facets",
                              json_integer(s->inconsistent_facets));
    rc |= json_object_set_new(o, "inverted_facets",
                              json_integer(s->inverted_facets));
    rc |= json_object_set_new(o, "shells", json_integer(s->shells));
    rc |= json_object_set_new(o, "orientable", json_boolean(s->orientable));
    rc |= json_object_set_new(o, "volume", json_real(s->volume));
    rc |= json_object_set_new(o, "area", json_real(s->area));
    rc |= json_object_set_new(o, "max_nonplanarity",
                              json_real(s->max_nonplanarity));
    rc |= json_object_set_new(o, "eps", json_real(s->eps));
    rc |= json_object_set_new(o, "nonconvex_facets",
                              json_integer(s->nonconvex_facets));
    rc |= json_object_set_new(o, "degenerate_facets",
                              json_integer(s->degenerate_facets));
    rc |= json_object_set_new(o, "degenerate_edges",
                              json_integer(s->degenerate_edges));
    rc |= json_object_set_new(o, "self_intersections", si);
    si = NULL;
    rc |= json_object_set_new(o, "self_intersecting_facets",
                              json_integer(s->self_intersecting_facets));
    rc |= json_object_set_new(o, "near_coplanar_pairs", cop);
    cop = NULL;
    rc |= json_object_set_new(o, "vertex_degrees", deg);
    deg = NULL;
    rc |= json_object_set_new(o, "short_edge_radius",
                              json_real(s->short_edge_radius));
    rc |= json_object_set_new(o, "short_edge_clusters",
                              json_integer(s->short_edge_clusters));
    rc |= json_object_set_new(o, "short_edge_cluster_vertices",
                              json_integer(s->short_edge_cluster_vertices));
    rc |= json_object_set_new(o, "valid", json_boolean(s->valid));
    if (rc == 0)
        return o;
oom:
    json_decref(o);
    json_decref(cop);
    json_decref(deg);
    json_decref(si);
    return NULL;
}
