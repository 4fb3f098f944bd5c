/* fill_json.c — geo_mesh_fill_report → JSON (see fill_json.h). */
#include "fill_json.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>

static json_t *hole_json(const geo_mesh_hole *h)
{
    bool filled = h->status == GEO_HOLE_FILLED ||
                  h->status == GEO_HOLE_FILLED_PLANAR;
    bool tried = filled || h->status == GEO_HOLE_INTERSECTS;
    json_t *o = json_pack(
        "{s:I, s:I, s:s, s:I, s:I}", "vertices", (json_int_t)h->nverts,
        "first_vertex", (json_int_t)h->first_vertex, "status",
        geo_hole_status_name(h->status), "facets_added",
        (json_int_t)h->facets_added, "vertices_added",
        (json_int_t)h->verts_added);
    if (!o)
        return NULL;
    int e = 0;
    if (tried)
        e |= json_object_set_new(o, "attempt", json_string(geo_fill_attempt_name(
                                                   h->attempt)));
    if (isfinite(h->planarity))
        e |= json_object_set_new(o, "planarity", json_real(h->planarity));
    if (filled) {
        e |= json_object_set_new(o, "max_dihedral_deg",
                                 json_real(h->max_dihedral_deg));
        e |= json_object_set_new(o, "edge_ratio", json_real(h->edge_ratio));
    }
    if (e) {
        json_decref(o);
        return NULL;
    }
    return o;
}

json_t *proto_fill_report_to_json(const geo_mesh_fill_report *r)
{
    json_t *holes = json_array();
    if (!holes)
        return NULL;
    for (uint32_t i = 0; i < r->nloops; i++) {
        json_t *h = hole_json(&r->holes[i]);
        if (!h || json_array_append_new(holes, h) < 0) {
            json_decref(holes);
            return NULL;
        }
    }
    return json_pack("{s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, s:I, "
                     "s:I, s:f, s:o}",
                     "loops", (json_int_t)r->nloops, "filled",
                     (json_int_t)r->nfilled, "planar", (json_int_t)r->nplanar,
                     "left_open", (json_int_t)r->nopen, "rejected_patches",
                     (json_int_t)r->nrejected, "facets_removed",
                     (json_int_t)r->nremoved, "facets_split",
                     (json_int_t)r->nsplit, "facets_reversed",
                     (json_int_t)r->nreversed, "vertices_unused",
                     (json_int_t)r->nunused, "vertices_welded",
                     (json_int_t)r->nwelded, "vertices_added",
                     (json_int_t)r->verts_added, "facets_added",
                     (json_int_t)r->facets_added, "max_dihedral_deg",
                     r->max_dihedral_deg, "holes", holes);
}

static int reason(json_t *a, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static int reason(json_t *a, const char *fmt, ...)
{
    char buf[160];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    return json_array_append_new(a, json_string(buf));
}

json_t *proto_validity_to_json(const geo_stats *s)
{
    json_t *a = json_array();
    if (!a)
        return NULL;
    int e = 0;
    if (!s->closed)
        e |= reason(a, "not closed: %u boundary edges (%u holes)",
                    s->boundary_edges, s->holes);
    if (s->nonmanifold_edges)
        e |= reason(a, "%u non-manifold edges", s->nonmanifold_edges);
    if (s->nonmanifold_vertices)
        e |= reason(a, "%u non-manifold vertices", s->nonmanifold_vertices);
    if (s->low_degree_vertices)
        e |= reason(a, "%u vertices in fewer than 3 facets",
                    s->low_degree_vertices);
    /* "inconsistent" has three causes; say which (lib/inspect/orient.h) */
    if (s->orientation == GEO_ORIENT_INCONSISTENT && !s->orientable)
        e |= reason(a, "orientation inconsistent: a shell is not "
                    "orientable");
    else if (s->orientation == GEO_ORIENT_INCONSISTENT &&
             s->inconsistent_facets == 0)
        e |= reason(a, "orientation inconsistent: of its %u shells some "
                    "face outward, some inward", s->shells);
    else if (s->orientation != GEO_ORIENT_OUTWARD)
        e |= reason(a, "orientation %s (%u inconsistent facets)",
                    geo_orientation_name(s->orientation),
                    s->inconsistent_facets);
    if (s->inverted_facets)
        e |= reason(a, "%u inverted facets", s->inverted_facets);
    if (!(s->max_nonplanarity <= s->eps))
        e |= reason(a, "non-planar facets: %.3g > eps %.3g",
                    s->max_nonplanarity, s->eps);
    if (s->selfint.count)
        e |= reason(a, "%llu self-intersections",
                    (unsigned long long)s->selfint.count);
    if (s->degenerate_facets)
        e |= reason(a, "%u degenerate facets", s->degenerate_facets);
    json_t *o = json_pack("{s:b, s:f, s:o}", "valid", s->valid, "volume",
                          s->volume, "reasons", a);
    if (e) {
        json_decref(o);
        return NULL;
    }
    return o;
}

json_t *proto_stitch_report_to_json(const geo_stitch_report *r)
{
    json_t *fill = proto_fill_report_to_json(&r->fill);
    if (!fill)
        return NULL;
    return json_pack(
        "{s:s, s:I, s:[I,I], s:[I,I], s:[I,I], s:[I,I], s:b, s:b, s:b, s:I,"
        " s:I, s:I, s:f, s:f, s:I, s:I, s:I, s:I, s:I, s:b, s:o}",
        "method", geo_stitch_method_name(r->method), "planes",
        (json_int_t)r->planes, "loops", (json_int_t)r->loops1, (json_int_t)r->loops2, "joined",
        (json_int_t)r->loop1, (json_int_t)r->loop2, "loop_vertices",
        (json_int_t)r->nloop1, (json_int_t)r->nloop2, "chosen",
        (json_int_t)r->chosen1, (json_int_t)r->chosen2, "band", r->band,
        "flipped", r->flipped2, "swapped", r->swapped, "twist",
        (json_int_t)r->twist, "meridians", (json_int_t)r->meridians, "rows",
        (json_int_t)r->rows, "meridian_length", r->meridian_length, "segment",
        r->segment, "band_vertices", (json_int_t)r->band_vertices,
        "band_facets", (json_int_t)r->band_facets, "welded",
        (json_int_t)r->welded, "welded_loops", (json_int_t)r->welded_loops,
        "inserted", (json_int_t)r->inserted, "trimmed", r->trimmed,
        "openings", fill);
}
