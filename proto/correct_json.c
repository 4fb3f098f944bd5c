/* correct_json.c — merge, collapse and correction reports as JSON (shapes
 * in correct_json.h). Any allocation failure makes the whole value NULL. */
#include "correct_json.h"

#include <math.h>

#include "stats_json.h"

static void put(json_t *obj, const char *key, json_t *val, bool *ok)
{
    if (!val || json_object_set_new(obj, key, val) < 0)
        *ok = false;
}

static json_t *num(double x)
{
    return isfinite(x) ? json_real(x) : json_null();
}

static json_t *index_or_null(uint32_t i)
{
    return i == UINT32_MAX ? json_null() : json_integer(i);
}

static json_t *finish(json_t *v, bool ok)
{
    if (!ok) {
        json_decref(v);
        return NULL;
    }
    return v;
}

/* The model's size before and after, in the order of every report. */
static void put_sizes(json_t *o, uint32_t vertices_before,
                      uint32_t facets_before, uint32_t vertices_after,
                      uint32_t facets_after, bool *ok)
{
    put(o, "vertices_before", json_integer(vertices_before), ok);
    put(o, "facets_before", json_integer(facets_before), ok);
    put(o, "vertices_after", json_integer(vertices_after), ok);
    put(o, "facets_after", json_integer(facets_after), ok);
}

/* A report object and the array of its list: both, or false and neither. */
static bool report_with_list(json_t **ret_o, json_t **ret_list)
{
    *ret_o = json_object();
    *ret_list = json_array();
    if (*ret_o && *ret_list)
        return true;
    json_decref(*ret_o);
    json_decref(*ret_list);
    return false;
}

static json_t *u32_array(const uint32_t *a, uint32_t n)
{
    json_t *arr = json_array();
    for (uint32_t i = 0; arr && i < n; i++)
        if (json_array_append_new(arr, json_integer(a[i])) < 0) {
            json_decref(arr);
            return NULL;
        }
    return arr;
}

static json_t *moved_to_json(const geo_moved_vertex *m, uint32_t n)
{
    json_t *arr = json_array();
    for (uint32_t i = 0; arr && i < n; i++) {
        double d = sqrt(m[i].by[0] * m[i].by[0] + m[i].by[1] * m[i].by[1] +
                        m[i].by[2] * m[i].by[2]);
        json_t *o = json_pack("{s:i, s:[f,f,f], s:f}", "vertex",
                              (json_int_t)m[i].vertex, "by", m[i].by[0],
                              m[i].by[1], m[i].by[2], "distance", d);
        if (!o || json_array_append_new(arr, o) < 0) {
            json_decref(arr);
            return NULL;
        }
    }
    return arr;
}

static json_t *proto_merge_group_to_json(const geo_merge_report *r,
                                         uint32_t gi)
{
    const geo_merge_group *g = &r->groups[gi];
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put(o, "facets", u32_array(r->facets + g->first, g->count), &ok);
    put(o, "merged", json_boolean(g->status == 0), &ok);
    if (g->status != 0)
        put(o, "reason", json_string(g->reason), &ok);
    put(o, "facet", index_or_null(g->status == 0 ? g->out_facet : UINT32_MAX), &ok);
    if (g->status == 0) {
        json_t *pl = json_pack("[f,f,f,f]", g->plane[0], g->plane[1],
                               g->plane[2], g->plane[3]);
        put(o, "plane", pl, &ok);
    }
    put(o, "contour", json_integer(g->contour), &ok);
    put(o, "hanging", json_integer(g->hanging), &ok);
    put(o, "lifts", json_integer(g->lifts), &ok);
    put(o, "joins", json_integer(g->joins), &ok);
    put(o, "new_vertices", json_integer(g->new_vertices), &ok);
    put(o, "moved", json_integer(g->moved), &ok);
    put(o, "max_lift", num(g->max_lift), &ok);
    put(o, "dev_before", num(g->dev_before), &ok);
    put(o, "dev_after", num(g->dev_after), &ok);
    put(o, "volume_change", num(g->volume_change), &ok);
    return finish(o, ok);
}

json_t *proto_merge_report_to_json(const geo_merge_report *r)
{
    json_t *o, *groups;
    if (!report_with_list(&o, &groups))
        return NULL;
    bool ok = true;
    for (uint32_t g = 0; ok && g < r->ngroups; g++) {
        json_t *x = proto_merge_group_to_json(r, g);
        if (!x || json_array_append_new(groups, x) < 0)
            ok = false;
    }
    put(o, "groups", json_integer(r->ngroups), &ok);
    put(o, "merged", json_integer(r->merged), &ok);
    put(o, "failed", json_integer(r->failed), &ok);
    put(o, "rounds", json_integer(r->rounds), &ok);
    put(o, "statement_violations", json_integer(r->statement_violations), &ok);
    put(o, "views", json_integer(r->views), &ok);
    put(o, "noise", num(r->noise), &ok);
    put(o, "max_deviation", num(r->max_dev), &ok);
    put(o, "bevels", json_integer(r->bevels), &ok);
    put_sizes(o, r->vertices_before, r->facets_before, r->vertices_after,
              r->facets_after, &ok);
    put(o, "volume_before", num(r->volume_before), &ok);
    put(o, "volume_after", num(r->volume_after), &ok);
    put(o, "group_list", groups, &ok);
    put(o, "moved_vertices", moved_to_json(r->moved, r->nmoved), &ok);
    return finish(o, ok);
}

json_t *proto_collapse_report_to_json(const geo_collapse_report *r)
{
    json_t *o, *list;
    if (!report_with_list(&o, &list))
        return NULL;
    bool ok = true;
    for (uint32_t c = 0; ok && c < r->clusters; c++) {
        json_t *x = json_object();
        bool xok = x != NULL;
        if (xok) {
            put(x, "vertices", u32_array(r->cverts + r->cstart[c],
                                         r->cstart[c + 1] - r->cstart[c]), &xok);
            put(x, "vertex", index_or_null(r->cnew[c]), &xok);
        }
        if (!xok || json_array_append_new(list, x) < 0) {
            if (!xok)
                json_decref(x);
            ok = false;
        }
    }
    put(o, "radius", num(r->radius), &ok);
    put(o, "clusters", json_integer(r->clusters), &ok);
    put(o, "collapsed", json_integer(r->collapsed), &ok);
    put(o, "rolled_back", json_integer(r->rolled_back), &ok);
    put(o, "attempts", json_integer(r->attempts), &ok);
    put(o, "vertices_before", json_integer(r->vertices_before), &ok);
    put(o, "vertices_after", json_integer(r->vertices_after), &ok);
    put(o, "facets_before", json_integer(r->facets_before), &ok);
    put(o, "facets_after", json_integer(r->facets_after), &ok);
    put(o, "max_displacement", num(r->max_displacement), &ok);
    put(o, "replanar_steps", json_integer(r->replanar_steps), &ok);
    put(o, "cluster_list", list, &ok);
    return finish(o, ok);
}

/* The convex path: null when not asked for, else whether it gave the
 * result, and why not when it did not. */
static json_t *convex_to_json(const geo_correct_report *r)
{
    if (!r->convex_tried)
        return json_null();
    const geo_convex_report *c = &r->convex_report;
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put(o, "used", json_boolean(r->convex), &ok);
    put(o, "reason", r->convex || !c->reason[0] ? json_null()
                                                : json_string(c->reason),
        &ok);
    put(o, "groups", json_integer(c->groups), &ok);
    put(o, "planes", json_integer(c->planes), &ok);
    put(o, "dropped", json_integer(c->dropped), &ok);
    put(o, "redundant", json_integer(c->redundant), &ok);
    put(o, "narrow", json_integer(c->narrow), &ok);
    put(o, "readmitted", json_integer(c->readmitted), &ok);
    put(o, "held", json_integer(c->held), &ok);
    put(o, "turned", json_integer(c->turned), &ok);
    put(o, "unneeded", json_integer(c->unneeded), &ok);
    put(o, "clipped", json_integer(c->clipped), &ok);
    put(o, "adjusted", json_boolean(c->adjusted), &ok);
    put(o, "concavity", num(c->concavity), &ok);
    put(o, "deviation", num(c->deviation), &ok);
    put(o, "bound", num(c->bound), &ok);
    put(o, "silhouette_scale", num(c->silhouette_scale), &ok);
    put(o, "regrouped", json_boolean(c->regrouped), &ok);
    return finish(o, ok);
}

json_t *proto_correct_report_to_json(const geo_correct_report *r)
{
    json_t *o = json_object();
    bool ok = o != NULL;
    if (!ok)
        return NULL;
    put_sizes(o, r->vertices_before, r->facets_before, r->vertices_after,
              r->facets_after, &ok);
    put(o, "volume_before", num(r->volume_before), &ok);
    put(o, "volume_after", num(r->volume_after), &ok);
    put(o, "volume_change", num(r->volume_after - r->volume_before), &ok);
    put(o, "hausdorff", num(r->hausdorff), &ok);
    put(o, "rounds", json_integer(r->rounds), &ok);
    put(o, "merge_passes", json_integer(r->merge_passes), &ok);
    put(o, "reoriented_facets", json_integer(r->reoriented_facets), &ok);
    put(o, "views", json_integer(r->views), &ok);
    put(o, "noise", num(r->noise), &ok);
    json_t *cl = json_pack("{s:i, s:i, s:i, s:f}", "found",
                           (json_int_t)r->clusters_found, "collapsed",
                           (json_int_t)r->clusters_collapsed, "rolled_back",
                           (json_int_t)r->clusters_rolled_back,
                           "max_displacement", r->cluster_max_displacement);
    put(o, "clusters", cl, &ok);
    put(o, "merge", proto_merge_report_to_json(&r->merge), &ok);
    put(o, "convex", convex_to_json(r), &ok);
    put(o, "moved_vertices", moved_to_json(r->moved, r->nmoved), &ok);
    put(o, "valid", json_boolean(r->after.valid), &ok);
    put(o, "before", proto_stats_to_json(&r->before), &ok);
    put(o, "after", proto_stats_to_json(&r->after), &ok);
    return finish(o, ok);
}
