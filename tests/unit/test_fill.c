/* test_fill.c — checked hole filling on any mesh (lib/mesh/fill.h): missing
 * planar facets come back as one facet each (the brilliant's volume
 * exactly), holes touching at a vertex are separate loops, a large hole
 * of a curved mesh is filled validly at the density around it, and a
 * hole whose every patch would intersect the mesh stays open with its
 * reason and nothing added, unless the mesh is an assembly whose parts
 * already cross there (parts_overlap). */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fill.h"
#include "gen_sphere.h"
#include "model_io.h"
#include "stats.h"
#include "topo.h"
#include "vec.h"

static geo_poly *load(const char *name)
{
    geo_err err;
    geo_poly *p = proto_model_read_file(tu_model_path(name), PROTO_FMT_UNKNOWN,
                                        NULL, &err);
    assert_non_null(p);
    return p;
}

static void test_missing_planar_facets_come_back_as_one_facet_each(void **s)
{
    (void)s;
    geo_poly *p = load("brilliant.holes.json");
    geo_poly *truth = load("brilliant.truth.json");
    uint32_t nv = p->nverts, nf = p->nfacets;
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nloops, 2);
    assert_int_equal(rep.nplanar, 2);
    assert_int_equal(rep.nopen, 0);
    assert_int_equal(p->nfacets, 121);
    assert_int_equal(p->nfacets, nf + 2);
    assert_int_equal(p->nverts, nv);
    double v = geo_poly_volume(p), vt = geo_poly_volume(truth);
    assert_true(fabs(v - vt) <= 1e-9 * vt);
    assert_true(tu_is_valid(p));
    for (uint32_t h = 0; h < 2; h++) {
        assert_int_equal(rep.holes[h].status, GEO_HOLE_FILLED_PLANAR);
        assert_int_equal(rep.holes[h].facets_added, 1);
        assert_true(rep.holes[h].max_dihedral_deg > 0);
    }
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(truth);
    geo_poly_free(p);
}

/* Two square holes in the top of a block touching at one corner vertex:
 * the top is a 3×3 grid of unit cells at z = 0 with cells (0,0) and
 * (1,1) missing, the block closed by four walls and a bottom at z = −1. */
static geo_poly *block_with_touching_holes(void)
{
    geo_poly *p = geo_poly_new();
    for (int j = 0; j <= 3; j++)
        for (int i = 0; i <= 3; i++) {
            double v[3] = {i, j, 0};
            geo_poly_add_vertex(p, v);
        }
    static const double bottom[4][3] = {
        {0, 0, -1}, {3, 0, -1}, {3, 3, -1}, {0, 3, -1}};
    for (int k = 0; k < 4; k++)
        geo_poly_add_vertex(p, bottom[k]);
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++) {
            if ((i == 0 && j == 0) || (i == 1 && j == 1))
                continue;
            uint32_t a = (uint32_t)(j * 4 + i);
            uint32_t q[4] = {a, a + 1, a + 5, a + 4};
            geo_poly_add_facet(p, q, 4);
        }
    /* walls: the top border counter-clockwise seen from above, corner to
     * corner, closed through the two bottom corners below its ends */
    static const uint32_t side[4][4] = {
        {0, 1, 2, 3}, {3, 7, 11, 15}, {15, 14, 13, 12}, {12, 8, 4, 0}};
    for (int k = 0; k < 4; k++) {
        uint32_t w[6] = {16 + (uint32_t)k, 16 + (uint32_t)(k + 1) % 4,
                         side[k][3], side[k][2], side[k][1], side[k][0]};
        geo_poly_add_facet(p, w, 6);
    }
    uint32_t under[4] = {16, 19, 18, 17};
    geo_poly_add_facet(p, under, 4);
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

/* A block 2 × 2 × 1 whose top is a 2 × 2 grid of which only the triangle
 * (0,0) (1,0) (1,1) is left: the rest of the top is one planar hole whose
 * loop runs along two edges of that triangle, round the grid's centre. */
static geo_poly *block_with_a_triangle_in_its_open_top(void)
{
    geo_poly *p = geo_poly_new();
    for (int j = 0; j <= 2; j++)
        for (int i = 0; i <= 2; i++) {
            double v[3] = {i, j, 0};
            geo_poly_add_vertex(p, v);
        }
    static const double bottom[4][3] = {
        {0, 0, -1}, {2, 0, -1}, {2, 2, -1}, {0, 2, -1}};
    for (int k = 0; k < 4; k++)
        geo_poly_add_vertex(p, bottom[k]);
    uint32_t tri[3] = {0, 1, 4};
    geo_poly_add_facet(p, tri, 3);
    static const uint32_t side[4][3] = {
        {0, 1, 2}, {2, 5, 8}, {8, 7, 6}, {6, 3, 0}};
    for (int k = 0; k < 4; k++) {
        uint32_t w[5] = {9 + (uint32_t)k, 9 + (uint32_t)(k + 1) % 4,
                         side[k][2], side[k][1], side[k][0]};
        geo_poly_add_facet(p, w, 5);
    }
    uint32_t under[4] = {9, 12, 11, 10};
    geo_poly_add_facet(p, under, 4);
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

/* One facet over that hole would meet the triangle along two edges and
 * leave the grid's centre in two facets only (a stress test of random
 * patches cut from flat gem facets made such holes: "filled_planar",
 * model invalid). The hole is triangulated instead. */
static void test_planar_hole_sharing_two_edges_with_a_facet_is_triangulated(
    void **s)
{
    (void)s;
    geo_poly *p = block_with_a_triangle_in_its_open_top();
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nloops, 1);
    assert_int_equal(rep.nfilled, 1);
    assert_int_equal(rep.holes[0].status, GEO_HOLE_FILLED);
    assert_true(tu_is_valid(p));
    assert_true(fabs(geo_poly_volume(p) - 4.0) < 1e-12);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

static void test_holes_touching_at_a_vertex_are_two_loops(void **s)
{
    (void)s;
    geo_poly *p = block_with_touching_holes();
    uint32_t nf = p->nfacets;
    geo_topo *t = geo_topo_build(p, NULL);
    uint32_t *ls, *lc, nl;
    assert_int_equal(geo_topo_boundary_loops(p, t, &ls, &lc, &nl), 0);
    assert_int_equal(nl, 2);
    for (uint32_t l = 0; l < nl; l++) {
        assert_int_equal(ls[l + 1] - ls[l], 4);
        /* each loop is closed: every edge ends where the next begins */
        for (uint32_t k = ls[l]; k < ls[l + 1]; k++) {
            uint32_t nx = k + 1 < ls[l + 1] ? k + 1 : ls[l];
            assert_int_equal(p->fidx[geo_topo_next(p, t, lc[k])],
                             p->fidx[lc[nx]]);
        }
    }
    free(ls), free(lc);
    geo_topo_free(t);
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nloops, 2);
    assert_int_equal(rep.nplanar, 2);
    assert_int_equal(p->nfacets, nf + 2);
    /* each hole got its own square: the pinch is one fan again */
    for (uint32_t h = 0; h < 2; h++)
        assert_int_equal(rep.holes[h].nverts, 4);
    assert_true(tu_is_valid(p));
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* Removes the facets whose centre has z > zcut. */
static void cut_cap(geo_poly *p, double zcut)
{
    bool *keep = malloc(p->nfacets * sizeof *keep);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double c[3];
        geo_poly_facet_center(p, f, c);
        keep[f] = c[2] <= zcut;
    }
    assert_int_equal(geo_poly_compact(p, keep, NULL, NULL), 0);
    free(keep);
}

static void test_large_curved_hole_filled_validly_at_mesh_density(void **s)
{
    (void)s;
    geo_poly *p = gs_sphere(88, 1.0);
    cut_cap(p, 0.5);
    uint32_t nv0 = p->nverts;
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nloops, 1);
    assert_int_equal(rep.nfilled, 1);
    const geo_mesh_hole *h = &rep.holes[0];
    assert_true(h->nverts >= 450 && h->nverts <= 550);
    assert_int_equal(h->status, GEO_HOLE_FILLED);
    assert_int_equal(p->nverts, nv0 + h->verts_added);
    assert_true(h->verts_added > 1000);
    assert_true(h->edge_ratio > 0.5 && h->edge_ratio < 2.0);
    assert_true(tu_is_valid(p));
    /* faired, not flat: the patch rises towards the sphere's pole */
    double top = 0;
    for (uint32_t v = nv0; v < p->nverts; v++)
        top = p->verts[v][2] > top ? p->verts[v][2] : top;
    assert_true(top > 0.8);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* The unit box without its top: five facets, one square hole. */
static geo_poly *open_box(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    bool keep[6] = {true, false, true, true, true, true}; /* no top */
    assert_int_equal(geo_poly_compact(p, keep, NULL, NULL), 0);
    return p;
}

/* A unit box without its top and a closed column 0.2 wide standing in the
 * opening from z = zlo to 50, far taller than any dome the lift tries:
 * every disc spanning the rim crosses the column. From zlo < 0 the column
 * goes through the floor too (the two parts already cross); from zlo in
 * (0, 1) it stands free inside the box (they do not). */
static geo_poly *open_box_with_column(double zlo)
{
    geo_poly *p = open_box();
    const double blo[3] = {0.4, 0.4, zlo}, bhi[3] = {0.6, 0.6, 50};
    geo_poly *b = tu_box(blo, bhi);
    uint32_t off = p->nverts;
    for (uint32_t v = 0; v < b->nverts; v++)
        geo_poly_add_vertex(p, b->verts[v]);
    for (uint32_t f = 0; f < b->nfacets; f++) {
        uint32_t q[4];
        for (int k = 0; k < 4; k++)
            q[k] = geo_poly_facet(b, f)[k] + off;
        int64_t nf = geo_poly_add_facet(p, q, 4);
        memcpy(p->planes[nf], b->planes[f], sizeof p->planes[0]);
    }
    geo_poly_free(b);
    return p;
}

/* Fills p with o (NULL: defaults) and checks its one hole stays open as
 * crossing the mesh, nothing added or removed. The report is returned
 * for the caller's own checks (release with geo_mesh_fill_report_clear). */
static void fill_leaves_hole_open(geo_poly *p, const geo_mesh_fill_opts *o,
                                  geo_mesh_fill_report *rep)
{
    uint32_t nv = p->nverts, nf = p->nfacets;
    assert_int_equal(geo_fill(p, o, NULL, rep, NULL), 0);
    assert_int_equal(rep->nloops, 1);
    assert_int_equal(rep->nfilled, 0);
    assert_int_equal(rep->nopen, 1);
    assert_int_equal(rep->nremoved, 0);
    assert_int_equal(rep->holes[0].status, GEO_HOLE_INTERSECTS);
    assert_int_equal(rep->holes[0].facets_added, 0);
    assert_int_equal(p->nverts, nv);
    assert_int_equal(p->nfacets, nf);
}

static void test_unfillable_hole_stays_open_with_reason(void **s)
{
    (void)s;
    geo_poly *p = open_box_with_column(-1);
    geo_mesh_fill_report rep;
    fill_leaves_hole_open(p, NULL, &rep);
    assert_true(rep.nrejected >= 1);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* parts_overlap: the box's lid may cross the column only where the two
 * parts crossed already. Through the floor: the hole is filled, and every
 * crossing of the result is between a box facet (the patch's included)
 * and a column facet, none inside one part. Standing free inside: the
 * lid would make two parts cross that did not, so the hole stays open. */
static void test_parts_overlap_crosses_only_parts_that_crossed(void **s)
{
    (void)s;
    geo_mesh_fill_opts o;
    geo_mesh_fill_opts_default(&o);
    o.parts_overlap = true;
    geo_poly *p = open_box_with_column(-1);
    const uint32_t column0 = 5, column1 = 10; /* after the 5 box facets */
    uint32_t nf = p->nfacets;
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, &o, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nfilled, 1);
    assert_true(rep.holes[0].status == GEO_HOLE_FILLED_PLANAR ||
                rep.holes[0].status == GEO_HOLE_FILLED);
    assert_true(p->nfacets > nf);
    geo_stats st;
    geo_inspect_opts io;
    geo_inspect_opts_default(&io);
    io.selfint.max_pairs = 100000;
    assert_int_equal(geo_inspect(p, &io, NULL, &st, NULL), 0);
    assert_true(st.selfint.npairs > 0);
    assert_int_equal(st.selfint.npairs, st.selfint.count);
    for (uint32_t k = 0; k < st.selfint.npairs; k++) {
        uint32_t a = st.selfint.pairs[k][0], b = st.selfint.pairs[k][1];
        bool a_col = a >= column0 && a <= column1;
        bool b_col = b >= column0 && b <= column1;
        assert_true(a_col != b_col);
    }
    geo_stats_clear(&st);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);

    p = open_box_with_column(0.2);
    fill_leaves_hole_open(p, &o, &rep);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* remove_crossing: a sphere with its cap cut away and a triangular flap
 * on the rim folded across the opening and out through the far side. The
 * plain fill cannot make it valid (the flap crosses the sphere whatever
 * closes the hole); removing the flap first (it crosses the most facets;
 * the ones it pierces stay) gives a valid closed solid. A mesh whose
 * crossing facets touch no hole is filled as without the option. */
static void test_flap_across_the_opening_is_removed_then_filled(void **s)
{
    (void)s;
    geo_poly *p = gs_sphere(16, 1.0);
    cut_cap(p, 0.6);
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    uint32_t a = UINT32_MAX, b = UINT32_MAX; /* the rim edge farthest +x */
    double best = -INFINITY;
    for (uint32_t c = 0; c < t->ncorners; c++) {
        if (t->edge_kind[c] != GEO_EDGE_BOUNDARY)
            continue;
        uint32_t u = p->fidx[c], v = p->fidx[geo_topo_next(p, t, c)];
        double x = p->verts[u][0] + p->verts[v][0];
        if (x > best)
            best = x, a = u, b = v;
    }
    geo_topo_free(t);
    const double apex[3] = {-1.6, 0, 0.3};
    uint32_t c = (uint32_t)geo_poly_add_vertex(p, apex);
    uint32_t tri[3] = {b, a, c}; /* the rim edge run the other way */
    int64_t nf = geo_poly_add_facet(p, tri, 3);
    assert_true(nf >= 0);
    geo_poly_facet_fit_plane(p, (uint32_t)nf, GEO_PLANE_UNWEIGHTED,
                             p->planes[nf]);
    geo_poly *q = geo_poly_copy(p);

    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nremoved, 0);
    assert_false(tu_is_valid(p));
    geo_mesh_fill_report_clear(&rep);

    geo_mesh_fill_opts o;
    geo_mesh_fill_opts_default(&o);
    o.remove_crossing = true;
    assert_int_equal(geo_fill(q, &o, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nremoved, 1);
    assert_int_equal(rep.nopen, 0);
    assert_true(tu_is_valid(q));
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(q);
    geo_poly_free(p);

    /* crossing facets of two parts: removing them would take more than
     * a twentieth of the facets, so nothing is removed */
    p = open_box_with_column(-1);
    fill_leaves_hole_open(p, &o, &rep);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* remove_crossing away from the holes: a sphere with its cap cut away
 * and, far from the opening, one vertex pushed in through the far wall,
 * so its fan crosses the facets there. No patch over the hole can mend
 * that; with the option the fan and the facets it pierces go, their holes
 * are filled with the cap's, and the result is a valid closed solid. */
static void test_crossing_inside_the_mesh_is_removed_then_filled(void **s)
{
    (void)s;
    geo_poly *p = gs_sphere(16, 1.0);
    cut_cap(p, 0.6);
    uint32_t far = 0; /* the vertex farthest along +x */
    for (uint32_t v = 1; v < p->nverts; v++)
        if (p->verts[v][0] > p->verts[far][0])
            far = v;
    p->verts[far][0] = -1.3;
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    geo_poly *q = geo_poly_copy(p);
    uint32_t nf = p->nfacets;

    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nremoved, 0);
    assert_false(tu_is_valid(p));
    geo_mesh_fill_report_clear(&rep);

    geo_mesh_fill_opts o;
    geo_mesh_fill_opts_default(&o);
    o.remove_crossing = true;
    assert_int_equal(geo_fill(q, &o, NULL, &rep, NULL), 0);
    /* the vertex's fan and at least one facet it pierces, within the cap */
    assert_true(rep.nremoved > 6 && rep.nremoved <= nf / 20);
    assert_true(rep.nloops >= 3); /* the cap's and the two new openings */
    assert_int_equal(rep.nopen, 0);
    assert_true(tu_is_valid(q));
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(q);
    geo_poly_free(p);
}

/* A mesh from another tool may mix both windings: an open box with one
 * wall reversed. Its facets are made consistent before the hole is
 * filled (the wall is reversed back; facets keep their indices), and the
 * result is a valid closed solid. */
static void test_inconsistent_open_mesh_is_oriented_then_filled(void **s)
{
    (void)s;
    geo_poly *p = open_box();
    geo_poly *q = geo_poly_copy(p);
    geo_poly_flip_facet(p, 2);
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nopen, 0);
    assert_int_equal(rep.nreversed, 1);
    assert_true(tu_is_valid(p));
    for (uint32_t f = 0; f < q->nfacets; f++) /* each wall as it was */
        for (int k = 0; k < 4; k++)
            assert_true(fabs(p->planes[f][k] - q->planes[f][k]) < 1e-12);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(q);
    geo_poly_free(p);
}

/* A vertex no facet uses (other tools' files often carry them) would
 * leave the filled box invalid: an open mesh loses it first; a closed one
 * is left alone. */
static void test_unused_vertex_of_an_open_mesh_is_removed(void **s)
{
    (void)s;
    const double far[3] = {5, 5, 5};
    geo_poly *p = open_box();
    uint32_t nv = p->nverts;
    assert_true(geo_poly_add_vertex(p, far) >= 0);
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nopen, 0);
    assert_int_equal(rep.nunused, 1);
    assert_int_equal(p->nverts, nv);
    assert_true(tu_is_valid(p));
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);

    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    p = tu_box(lo, hi);
    nv = p->nverts;
    assert_true(geo_poly_add_vertex(p, far) >= 0);
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nunused, 0);
    assert_int_equal(p->nverts, nv + 1);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* An open sheet (a flat n × n grid of triangles) has no lid that does
 * not lie on it: the fill bends one into a dome, and the result is a
 * valid closed solid. */
static void test_open_sheet_is_closed_by_a_dome(void **s)
{
    (void)s;
    enum { N = 6 };
    geo_poly *p = geo_poly_new();
    for (int j = 0; j <= N; j++)
        for (int i = 0; i <= N; i++) {
            double v[3] = {i, j, 0};
            geo_poly_add_vertex(p, v);
        }
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            uint32_t a = (uint32_t)(j * (N + 1) + i), b = a + 1,
                     c = a + N + 2, d = a + N + 1;
            uint32_t t1[3] = {a, b, c}, t2[3] = {a, c, d};
            geo_poly_add_facet(p, t1, 3);
            geo_poly_add_facet(p, t2, 3);
        }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nloops, 1);
    assert_int_equal(rep.nopen, 0);
    uint8_t a = rep.holes[0].attempt;
    assert_true(a == GEO_ATTEMPT_LIFT || a == GEO_ATTEMPT_LOWER);
    assert_true(rep.nrejected >= 1); /* the flat lids were refused */
    geo_stats st;
    assert_int_equal(geo_inspect(p, NULL, NULL, &st, NULL), 0);
    assert_true(st.valid);
    assert_true(st.volume > 0);
    geo_stats_clear(&st);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* A flat square cut into a diamond between its edge midpoints and four
 * corner triangles: the loop is the square's rim (eight vertices), the
 * diamond's sides are chords of it and edges of the mesh, so every
 * triangulation of the loop's vertices repeats one or lies on the sheet.
 * A fan from the loop's centre has no such chord; bent into a dome it
 * closes a valid solid. */
static void test_rim_whose_chords_are_mesh_edges_gets_a_dome(void **s)
{
    (void)s;
    static const double v[8][3] = {{-1, -1, 0}, {0, -1, 0}, {1, -1, 0},
                                   {1, 0, 0},   {1, 1, 0},  {0, 1, 0},
                                   {-1, 1, 0},  {-1, 0, 0}};
    static const uint32_t t[4][3] = {{0, 1, 7}, {1, 2, 3}, {3, 4, 5},
                                     {5, 6, 7}};
    static const uint32_t diamond[4] = {1, 3, 5, 7};
    geo_poly *p = geo_poly_new();
    for (int i = 0; i < 8; i++)
        geo_poly_add_vertex(p, v[i]);
    for (int f = 0; f < 4; f++)
        geo_poly_add_facet(p, t[f], 3);
    geo_poly_add_facet(p, diamond, 4);
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nopen, 0);
    for (uint32_t h = 0; h < rep.nloops; h++) {
        uint8_t a = rep.holes[h].attempt;
        assert_true(rep.holes[h].status == GEO_HOLE_FILLED_PLANAR ||
                    a == GEO_ATTEMPT_FAN || a == GEO_ATTEMPT_LIFT ||
                    a == GEO_ATTEMPT_LOWER);
    }
    geo_stats st;
    assert_int_equal(geo_inspect(p, NULL, NULL, &st, NULL), 0);
    assert_true(st.valid);
    geo_stats_clear(&st);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(p);
}

/* An open cone: apex below, a ring of n points on the unit circle around
 * it, waving up and down (a saddle-shaped loop: convex seen from above). */
static geo_poly *open_cone(uint32_t n, double phase)
{
    geo_poly *p = geo_poly_new();
    double apex[3] = {0, 0, -1};
    geo_poly_add_vertex(p, apex);
    for (uint32_t i = 0; i < n; i++) {
        double a = 2 * M_PI * i / n, r = 1;
        double v[3] = {r * cos(a), r * sin(a), 0.25 * cos(2 * a + phase)};
        geo_poly_add_vertex(p, v);
    }
    for (uint32_t i = 0; i < n; i++) {
        uint32_t t[3] = {0, 1 + (i + 1) % n, 1 + i};
        geo_poly_add_facet(p, t, 3);
    }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

static void test_every_weight_fills_a_nonplanar_hole_validly(void **s)
{
    (void)s;
    enum geo_fill_weight ws[3] = {GEO_FILL_AREA, GEO_FILL_EDGES,
                                  GEO_FILL_ANGLE};
    for (int wi = 0; wi < 3; wi++)
        for (int refine = 0; refine < 2; refine++) {
            geo_poly *p = open_cone(60, 0.3 * wi);
            geo_mesh_fill_opts o;
            geo_mesh_fill_opts_default(&o);
            o.fill.weight = ws[wi];
            o.fill.refine = refine;
            geo_mesh_fill_report rep;
            assert_int_equal(geo_fill(p, &o, NULL, &rep, NULL), 0);
            assert_int_equal(rep.nfilled, 1);
            assert_int_equal(rep.nplanar, 0);
            assert_int_equal(rep.holes[0].status, GEO_HOLE_FILLED);
            /* the weight asked for gave a valid patch by itself */
            assert_int_equal(rep.holes[0].attempt, GEO_ATTEMPT_AS_ASKED);
            assert_true(tu_is_valid(p));
            geo_mesh_fill_report_clear(&rep);
            geo_poly_free(p);
        }
}

/* geo_fill on the closed mesh p (freed) finds no loop, splits nothing
 * and leaves every facet as it was. */
static void assert_left_alone(geo_poly *p)
{
    geo_poly *q = geo_poly_copy(p);
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nloops, 0);
    assert_int_equal(rep.nsplit, 0);
    assert_int_equal(p->nfacets, q->nfacets);
    assert_memory_equal(p->fidx, q->fidx,
                        geo_poly_ncorners(p) * sizeof *p->fidx);
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(q);
    geo_poly_free(p);
}

static void test_closed_mesh_is_left_alone(void **s)
{
    (void)s;
    assert_left_alone(load("brilliant.truth.json"));
}

/* A unit cube of quads without its bottom (closed: with it), vertex 6
 * (top, +x+y) moved by 1e-6 along x: the side quad x = 1 is no longer
 * planar to eps (the top and the side y = 1 still hold the vertex), as
 * polygons from other tools are planar only to their digits. */
static geo_poly *open_cube_nonplanar(bool closed)
{
    double xyz[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                        {0, 0, 1}, {1, 0, 1}, {1 + 1e-6, 1, 1}, {0, 1, 1}};
    static const uint32_t quads[] = {4, 5, 6, 7, 0, 1, 5, 4, 1, 2, 6, 5,
                                     2, 3, 7, 6, 3, 0, 4, 7, 0, 3, 2, 1};
    uint32_t nf = closed ? 6 : 5, start[7];
    for (uint32_t f = 0; f <= nf; f++)
        start[f] = 4 * f;
    geo_poly *p = geo_poly_from_arrays(8, &xyz[0][0], nf, start, quads, NULL,
                                       NULL);
    assert_non_null(p);
    return p;
}

static void test_nonplanar_facets_are_split_when_filling(void **s)
{
    (void)s;
    geo_poly *p = open_cube_nonplanar(false);
    assert_true(geo_poly_max_nonplanarity(p) > geo_poly_eps(p));
    geo_poly *q = geo_poly_copy(p);
    geo_mesh_fill_report rep;
    assert_int_equal(geo_fill(p, NULL, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nsplit, 1);
    assert_int_equal(rep.nfilled, 1);
    assert_true(tu_is_valid(p));
    /* a split facet keeps its index as a triangle of its own corners;
     * the planar ones keep theirs as they were */
    for (uint32_t f = 0; f < q->nfacets; f++) {
        const uint32_t *a = geo_poly_facet(p, f), *b = geo_poly_facet(q, f);
        if (geo_poly_facet_size(p, f) == 4) {
            assert_memory_equal(a, b, 4 * sizeof *a);
            continue;
        }
        assert_int_equal(geo_poly_facet_size(p, f), 3);
        for (int k = 0; k < 3; k++) {
            bool in = false;
            for (int j = 0; j < 4; j++)
                in |= a[k] == b[j];
            assert_true(in);
        }
    }
    geo_mesh_fill_report_clear(&rep);
    /* without the split the same hole leaves an invalid solid */
    geo_mesh_fill_opts o;
    geo_mesh_fill_opts_default(&o);
    o.split_nonplanar = false;
    geo_poly_free(p);
    p = geo_poly_copy(q);
    assert_int_equal(geo_fill(p, &o, NULL, &rep, NULL), 0);
    assert_int_equal(rep.nsplit, 0);
    assert_false(tu_is_valid(p));
    geo_mesh_fill_report_clear(&rep);
    geo_poly_free(q);
    geo_poly_free(p);
}

static void test_closed_nonplanar_mesh_is_left_alone(void **s)
{
    (void)s;
    geo_poly *p = open_cube_nonplanar(true);
    assert_true(geo_poly_max_nonplanarity(p) > geo_poly_eps(p));
    assert_left_alone(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_missing_planar_facets_come_back_as_one_facet_each),
        cmocka_unit_test(test_holes_touching_at_a_vertex_are_two_loops),
        cmocka_unit_test(test_large_curved_hole_filled_validly_at_mesh_density),
        cmocka_unit_test(test_unfillable_hole_stays_open_with_reason),
        cmocka_unit_test(test_parts_overlap_crosses_only_parts_that_crossed),
        cmocka_unit_test(test_flap_across_the_opening_is_removed_then_filled),
        cmocka_unit_test(test_crossing_inside_the_mesh_is_removed_then_filled),
        cmocka_unit_test(test_inconsistent_open_mesh_is_oriented_then_filled),
        cmocka_unit_test(test_unused_vertex_of_an_open_mesh_is_removed),
        cmocka_unit_test(test_open_sheet_is_closed_by_a_dome),
        cmocka_unit_test(test_rim_whose_chords_are_mesh_edges_gets_a_dome),
        cmocka_unit_test(test_every_weight_fills_a_nonplanar_hole_validly),
        cmocka_unit_test(test_closed_mesh_is_left_alone),
        cmocka_unit_test(test_nonplanar_facets_are_split_when_filling),
        cmocka_unit_test(test_closed_nonplanar_mesh_is_left_alone),
        cmocka_unit_test(
            test_planar_hole_sharing_two_edges_with_a_facet_is_triangulated),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
