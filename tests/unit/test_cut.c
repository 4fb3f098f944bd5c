/* test_cut.c — the plane cut (lib/cut/cut.h, Palachev 2012, §3): every case of the
 * paper on hand-built models, exact ordering of crossings, the §3.4
 * variant, refusals, and random planes on non-convex and convex models
 * (validity of every result, volumes of the two halves adding up, convex
 * results equal to the half-space intersection with one more plane). */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cut.h"
#include "cut_shapes.h"
#include "model_io.h"
#include "predicates.h"
#include "stats.h"
#include "topo.h"
#include "vec.h"

static double tol_of(const geo_poly *p)
{
    return 1e-9 * (1.0 + geo_poly_size(p));
}

/* NULL when geo_inspect finds p valid, else what it found wrong. */
static const char *inspect_problem(const geo_poly *p)
{
    static char msg[1024];
    geo_stats st;
    geo_err err = {{0}};
    if (geo_inspect(p, NULL, NULL, &st, &err) < 0) {
        snprintf(msg, sizeof msg, "inspect failed: %s", err.msg);
        return msg;
    }
    const char *bad = NULL;
    if (!st.valid) {
        snprintf(msg, sizeof msg,
                 "inspect: closed %d, nonmanifold vertices %u, low degree %u, "
                 "orientation %d, nonplanarity %.3g (eps %.3g), "
                 "self-intersections %u, degenerate facets %u",
                 st.closed, st.nonmanifold_vertices, st.low_degree_vertices,
                 (int)st.orientation, st.max_nonplanarity, st.eps,
                 st.self_intersecting_facets, st.degenerate_facets);
        bad = msg;
    }
    geo_stats_clear(&st);
    return bad;
}

/* Cuts p by (a,b,c,d), asserts success and a valid (or empty) result. */
static geo_poly *cut_ok(const geo_poly *p, double a, double b, double c,
                        double d, geo_cut_report *rep)
{
    double pl[4] = {a, b, c, d};
    geo_poly *out = geo_poly_new();
    geo_err err = {{0}};
    int r = geo_cut(p, pl, NULL, NULL, out, rep, &err);
    if (r != 0)
        fail_msg("geo_cut(%g,%g,%g,%g) = %d: %s", a, b, c, d, r, err.msg);
    if (!rep->empty) {
        const char *bad = cs_check_valid(out, tol_of(p));
        if (!bad)
            bad = inspect_problem(out);
        if (bad)
            fail_msg("cut by (%g,%g,%g,%g): %s", a, b, c, d, bad);
    } else {
        assert_int_equal(out->nfacets, 0);
    }
    return out;
}

static int cut_code(const geo_poly *p, double a, double b, double c, double d,
                    const geo_cut_opts *opts, geo_err *err)
{
    double pl[4] = {a, b, c, d};
    geo_poly *out = geo_poly_new();
    geo_cut_report rep;
    int r = geo_cut(p, pl, opts, NULL, out, &rep, err);
    if (r < 0)
        assert_int_equal(out->nfacets, 0);
    geo_poly_free(out);
    return r;
}

static void assert_close(double x, double y, double rel)
{
    if (!(fabs(x - y) <= rel * (1.0 + fabs(y))))
        fail_msg("%.17g != %.17g", x, y);
}

/* ---- exact ordering ------------------------------------------------ */

static void test_crossing_order_is_exact_below_rounding(void **state)
{
    (void)state;
    const double pl[4] = {0, 0, 1, 0};
    const double a0[3] = {0, 0, -1}, a1[3] = {1, 0, 2}; /* x = 1/3 */
    const double b0[3] = {0, 1, -2}, b1[3] = {1, 1, 4}; /* x = 1/3 too */
    double third = 1.0 / 3.0; /* just below 1/3 */
    double up = nextafter(third, 1.0);
    const double v0[3] = {third, 5, 0}, v1[3] = {up, 5, 0};
    assert_int_equal(geo_plane_crossing_cmp(pl, a0, a1, b0, b1, 0), 0);
    assert_int_equal(geo_plane_crossing_cmp(pl, a0, a1, v0, NULL, 0), 1);
    assert_int_equal(geo_plane_crossing_cmp(pl, a0, a1, v1, NULL, 0), -1);
    assert_int_equal(geo_plane_crossing_cmp(pl, v1, NULL, a0, a1, 0), 1);
    /* far apart: decided by the filter, same answers */
    const double c0[3] = {2, 0, -1}, c1[3] = {3, 0, 1}; /* x = 2.5 */
    assert_int_equal(geo_plane_crossing_cmp(pl, a0, a1, c0, c1, 0), -1);
    assert_int_equal(geo_plane_crossing_cmp(pl, c1, c0, a1, a0, 0), 1);
    /* a plane with inexact coefficients: still consistent both ways */
    const double q[4] = {0.1, 0.2, 0.7, -0.3};
    const double d0[3] = {1, 1, -1}, d1[3] = {1, 1, 2};
    const double e0[3] = {1, 1 + 0x1p-50, -1}, e1[3] = {1, 1 + 0x1p-50, 2};
    int s = geo_plane_crossing_cmp(q, d0, d1, e0, e1, 1);
    assert_int_equal(s, -1);
    assert_int_equal(geo_plane_crossing_cmp(q, e0, e1, d0, d1, 1), -s);
}

/* ---- simple and paper cases --------------------------------------- */

static void test_box_cut_in_half(void **state)
{
    (void)state;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
    geo_poly *p = tu_box(lo, hi);
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, 2, -3, &rep); /* z ≤ 1.5 */
    assert_close(geo_poly_volume(o), 3.0, 1e-12);
    assert_int_equal(rep.components, 1);
    assert_int_equal(rep.new_facets, 1);
    assert_int_equal(rep.split_facets, 4);
    assert_int_equal(rep.removed_facets, 1);
    assert_int_equal(rep.removed_vertices, 4);
    assert_int_equal(rep.new_vertices, 4);
    assert_int_equal(o->nverts, 8);
    assert_int_equal(o->nfacets, 6);
    assert_int_equal(rep.first_new_facet, 5);
    /* the new facet lies on the plane with its normal outward */
    assert_close(o->planes[5][2], 1.0, 1e-15);
    assert_close(o->planes[5][3], -1.5, 1e-15);
    assert_close(rep.volume_before, 6.0, 1e-12);
    assert_close(rep.volume_after, 3.0, 1e-12);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_notch_cube_u_shaped_section(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, 1, -8, &rep); /* across the notch */
    assert_close(geo_poly_volume(o), 768.0, 1e-12);
    assert_int_equal(rep.components, 1);
    /* the U-shaped new facet has the notch's 4 crossings + 4 corners */
    uint32_t f = rep.first_new_facet;
    assert_int_equal(geo_poly_facet_size(o, f), 8);
    geo_poly_free(o);
    /* the other side: a U-shaped block */
    o = cut_ok(p, 0, 0, -1, 8, &rep);
    assert_close(geo_poly_volume(o), 936.0 - 768.0, 1e-12);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_notch_floor_in_plane_ends_inside_new_facet(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, 1, -6, &rep); /* through the notch floor */
    assert_close(geo_poly_volume(o), 600.0, 1e-12);
    /* a plain box remains: the floor is inside the one new facet and the
     * two notch corners left on the x = 10 edge were hanging */
    assert_int_equal(rep.components, 1);
    assert_int_equal(o->nfacets, 6);
    assert_int_equal(o->nverts, 8);
    assert_int_equal(rep.hanging_dropped, 2);
    assert_int_equal(geo_poly_facet_size(o, rep.first_new_facet), 4);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_notch_floor_facing_away_is_dropped(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, -1, 6, &rep); /* keep z ≥ 6 */
    assert_close(geo_poly_volume(o), 336.0, 1e-12);
    assert_int_equal(rep.components, 1);
    /* the non-convex x = 10 facet falls into two pieces */
    assert_int_equal(rep.split_facets, 4);
    assert_int_equal(rep.pieces, 5);
    /* the new facet is the U: 4 corners + 4 notch corners */
    assert_int_equal(geo_poly_facet_size(o, rep.first_new_facet), 8);
    geo_poly_free(o);
    geo_poly_free(p);
}

static geo_poly *l_prism(void)
{
    static const double xy[6][2] = {{0, 0}, {10, 0}, {10, 4},
                                    {4, 4}, {4, 10}, {0, 10}};
    return cs_prism(xy, 6, 0, 6);
}

static void test_l_prism_cuts(void **state)
{
    (void)state;
    geo_poly *p = l_prism();
    assert_close(geo_poly_volume(p), 384.0, 1e-12);
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, -1, 0, 0, 7, &rep); /* keep x ≥ 7 */
    assert_close(geo_poly_volume(o), 72.0, 1e-12);
    geo_poly_free(o);
    /* y ≤ 4: the inner wall y = 4 lies in the plane facing along it */
    o = cut_ok(p, 0, 1, 0, -4, &rep);
    assert_close(geo_poly_volume(o), 240.0, 1e-12);
    assert_int_equal(o->nverts, 8);
    assert_int_equal(o->nfacets, 6);
    geo_poly_free(o);
    /* y ≥ 4 keeps the arm; the inner wall faces away and is dropped */
    o = cut_ok(p, 0, -1, 0, 4, &rep);
    assert_close(geo_poly_volume(o), 144.0, 1e-12);
    assert_int_equal(o->nfacets, 6);
    geo_poly_free(o);
    /* diagonal through the reflex corner's vertical edge, which then lies
     * inside the new facet with both of its facets removed: the corner's
     * two vertices are left hanging on the new facet and dropped */
    o = cut_ok(p, 1, 1, 0, -8, &rep);
    assert_close(geo_poly_volume(o), 192.0, 1e-12);
    assert_int_equal(o->nverts, 6);
    assert_int_equal(o->nfacets, 5);
    assert_int_equal(rep.hanging_dropped, 2);
    /* the other side: the two arms would touch only along that edge */
    geo_err err = {{0}};
    assert_int_equal(cut_code(p, -1, -1, 0, 8, NULL, &err), -ENOTSUP);
    geo_poly *q = cut_ok(p, -1, -1, 0, 8.5, &rep);
    assert_int_equal(rep.components, 2);
    /* L area 64 minus the triangle x + y ≤ 8.5 less its corner 0.125 */
    assert_close(geo_poly_volume(q), (64.0 - (8.5 * 8.5 / 2 - 0.125)) * 6, 1e-12);
    geo_poly_free(q);
    geo_poly_free(o);
    geo_poly_free(p);
}

/* Number of intervals of the line x = c inside a simple polygon. */
static int intervals_on_line(const double (*xy)[2], uint32_t n, double c)
{
    int crossings = 0;
    for (uint32_t i = 0; i < n; i++) {
        const double *a = xy[i], *b = xy[(i + 1) % n];
        if ((a[0] < c) != (b[0] < c))
            crossings++;
    }
    return crossings / 2;
}

static void test_star_prism_splits_into_several_pieces(void **state)
{
    (void)state;
    enum { PTS = 5 };
    geo_poly *p = cs_star_prism(PTS, 1.0, 3.0, 2.0);
    double xy[2 * PTS][2];
    for (uint32_t i = 0; i < 2 * PTS; i++) {
        xy[i][0] = p->verts[i][0];
        xy[i][1] = p->verts[i][1];
    }
    double vol = geo_poly_volume(p);
    for (double c = -2.7; c < 2.8; c += 0.37) {
        geo_cut_report rep, rep2;
        geo_poly *o = cut_ok(p, -1, 0, 0, c, &rep); /* keep x ≥ c */
        geo_poly *q = cut_ok(p, 1, 0, 0, -c, &rep2);
        int k = intervals_on_line((const double(*)[2])xy, 2 * PTS, c);
        assert_int_equal(rep.components, k);
        assert_int_equal(rep2.components, k);
        /* top and bottom stars split into as many pieces as the kept side
         * has parts; the halves add up */
        assert_true(rep.pieces >= rep.split_facets);
        assert_close(geo_poly_volume(o) + geo_poly_volume(q), vol, 1e-12);
        geo_poly_free(o);
        geo_poly_free(q);
    }
    /* a plane whose kept side holds two separate tips: the top and the
     * bottom star each fall into two pieces */
    assert_int_equal(intervals_on_line((const double(*)[2])xy, 2 * PTS, 1.1), 2);
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, -1, 0, 0, 1.1, &rep);
    assert_int_equal(rep.components, 2);
    assert_int_equal(rep.pieces, rep.split_facets + 2);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_comb_gives_one_component_per_prong(void **state)
{
    (void)state;
    for (uint32_t prongs = 2; prongs <= 3; prongs++) {
        geo_poly *p = cs_comb_prism(prongs);
        double vol = ((2.0 * prongs - 1) * 2 + 6.0 * prongs) * 3;
        assert_close(geo_poly_volume(p), vol, 1e-12);
        geo_cut_report rep;
        geo_poly *o = cut_ok(p, 0, -1, 0, 5, &rep); /* keep y ≥ 5 */
        assert_int_equal(rep.components, prongs);
        assert_int_equal(rep.new_facets, prongs);
        assert_close(geo_poly_volume(o), 9.0 * prongs, 1e-12);
        geo_poly_free(o);
        o = cut_ok(p, 0, 1, 0, -5, &rep); /* keep y ≤ 5 */
        assert_int_equal(rep.components, prongs);
        /* the top and bottom combs are cut but stay one piece each */
        assert_int_equal(rep.pieces, rep.split_facets);
        assert_close(geo_poly_volume(o), vol - 9.0 * prongs, 1e-12);
        geo_poly_free(o);
        /* through the bar's top edge y = 2, where the gaps' floors lie in
         * the plane facing away: the bar stays, gaps' floors dropped */
        o = cut_ok(p, 0, 1, 0, -2, &rep);
        assert_close(geo_poly_volume(o), (2.0 * prongs - 1) * 2 * 3, 1e-12);
        assert_int_equal(rep.components, 1);
        assert_int_equal(o->nfacets, 6);
        geo_poly_free(o);
        geo_poly_free(p);
    }
}

static void test_vertices_and_edges_on_plane(void **state)
{
    (void)state;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    geo_cut_report rep;
    /* through two opposite vertical edges: a triangular prism */
    geo_poly *o = cut_ok(p, 1, -1, 0, 0, &rep);
    assert_close(geo_poly_volume(o), 0.5, 1e-15);
    assert_int_equal(o->nverts, 6);
    assert_int_equal(o->nfacets, 5);
    assert_int_equal(rep.new_vertices, 0);
    geo_poly_free(o);
    /* through three vertices: a corner tetrahedron cut off */
    o = cut_ok(p, 1, 1, 1, -1, &rep);
    assert_close(geo_poly_volume(o), 1.0 / 6.0, 1e-15);
    assert_int_equal(o->nverts, 4);
    geo_poly_free(o);
    o = cut_ok(p, -1, -1, -1, 1, &rep);
    assert_close(geo_poly_volume(o), 5.0 / 6.0, 1e-15);
    assert_int_equal(o->nverts, 7);
    assert_int_equal(o->nfacets, 7);
    geo_poly_free(o);
    /* through one vertex and the midpoints of two edges */
    o = cut_ok(p, 1, 1, 0.5, -1, &rep);
    geo_poly *q = cut_ok(p, -1, -1, -0.5, 1, &rep);
    assert_close(geo_poly_volume(o) + geo_poly_volume(q), 1.0, 1e-14);
    geo_poly_free(o);
    geo_poly_free(q);
    geo_poly_free(p);
}

static void test_convex_edge_in_plane_stays_between_its_facets(void **state)
{
    (void)state;
    /* two tips: (2, 7) touches y = 7 with its vertical edge, (8, 9) is cut */
    static const double xy[8][2] = {{0, 0}, {10, 0}, {10, 6}, {8, 9},
                                    {6, 6}, {4, 6}, {2, 7}, {0, 6}};
    geo_poly *p = cs_prism(xy, 8, 0, 2);
    double vol = geo_poly_volume(p);
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 1, 0, -7, &rep);
    /* the cut-off tip: base 8/3 at y = 7, height 2, thickness 2 */
    assert_close(geo_poly_volume(o), vol - 8.0 / 3.0 * 2.0, 1e-12);
    assert_int_equal(rep.components, 1);
    /* the touching edge keeps its two side facets and both vertices */
    assert_int_equal(rep.removed_vertices, 2);
    geo_poly_free(o);
    o = cut_ok(p, 0, -1, 0, 7, &rep);
    assert_close(geo_poly_volume(o), 8.0 / 3.0 * 2.0, 1e-12);
    assert_int_equal(o->nverts, 6);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_plane_missing_or_touching_is_unchanged_or_empty(void **state)
{
    (void)state;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    static const double planes[][4] = {
        {0, 0, 1, -5},  /* misses, solid kept */
        {1, 1, 0, 0},   /* touches the edge x = y = 0 */
        {1, 1, 1, 0},   /* touches the vertex 0 */
        {0, 0, 1, -1},  /* the top facet lies in it (seed fig. 23) */
    };
    for (size_t i = 0; i < sizeof planes / sizeof planes[0]; i++) {
        geo_cut_report rep;
        const double *q = planes[i];
        geo_poly *o = cut_ok(p, q[0], q[1], q[2], q[3], &rep);
        bool keep = i == 0 || i == 3;
        assert_int_equal(rep.unchanged, keep);
        assert_int_equal(rep.empty, !keep);
        if (keep) {
            assert_int_equal(o->nfacets, 6);
            assert_memory_equal(o->fidx, p->fidx, 24 * sizeof *p->fidx);
        }
        geo_poly_free(o);
        /* the opposite half-space: the other answer (a facet in the
         * plane facing away bounds nothing of the kept side) */
        o = cut_ok(p, -q[0], -q[1], -q[2], -q[3], &rep);
        assert_int_equal(rep.unchanged, !keep);
        assert_int_equal(rep.empty, keep);
        geo_poly_free(o);
    }
    geo_poly_free(p);
}

/* A prism over a polygon with a notch rising from the bottom edge to a
 * reflex vertex at (5, 5). */
static geo_poly *notch_prism(void)
{
    static const double xy[7][2] = {{0, 0}, {4, 0}, {5, 5}, {6, 0},
                                    {10, 0}, {10, 8}, {0, 8}};
    return cs_prism(xy, 7, 0, 2);
}

static void test_reflex_vertex_on_plane(void **state)
{
    (void)state;
    geo_poly *p = notch_prism();
    double vol = geo_poly_volume(p);
    geo_cut_report rep, rep2;
    /* y + z ≤ 7 passes through the top of the reflex edge only: in the
     * top facet that vertex ends one segment of the section and starts
     * the next (kept side), or lies inside one (removed side) */
    geo_poly *o = cut_ok(p, 0, 1, 1, -7, &rep);
    geo_poly *q = cut_ok(p, 0, -1, -1, 7, &rep2);
    assert_close(geo_poly_volume(o) + geo_poly_volume(q), vol, 1e-12);
    assert_int_equal(rep.components, 1);
    assert_int_equal(rep2.components, 1);
    /* the kept side's top facet falls into two pieces at that vertex */
    assert_int_equal(rep.pieces, rep.split_facets + 1);
    geo_poly_free(o);
    geo_poly_free(q);
    geo_poly_free(p);
}

/* A block [−1,1]² × [−1, ·] whose top is a saddle of four triangles
 * around (0, 0, 0), corners at heights +h, −h, +h, −h. */
static geo_poly *saddle_block(double h)
{
    double v[9][3] = {{0, 0, 0}};
    static const double cx[4] = {1, -1, -1, 1}, cy[4] = {1, 1, -1, -1};
    for (int i = 0; i < 4; i++) {
        v[1 + i][0] = v[5 + i][0] = cx[i];
        v[1 + i][1] = v[5 + i][1] = cy[i];
        v[1 + i][2] = i % 2 ? -h : h;
        v[5 + i][2] = -1;
    }
    uint32_t idx[32], start[10], c = 0, f = 0;
    for (uint32_t i = 0; i < 4; i++) {
        uint32_t j = (i + 1) % 4;
        start[f++] = c; /* top triangle, counter-clockwise from above */
        idx[c++] = 0, idx[c++] = 1 + i, idx[c++] = 1 + j;
        start[f++] = c; /* wall, outward */
        idx[c++] = 5 + i, idx[c++] = 5 + j, idx[c++] = 1 + j, idx[c++] = 1 + i;
    }
    start[f++] = c; /* bottom, seen from below */
    for (uint32_t i = 4; i-- > 0;)
        idx[c++] = 5 + i;
    start[f] = c;
    return geo_poly_from_arrays(9, &v[0][0], f, start, idx, NULL, NULL);
}

static void test_saddle_vertex_on_plane(void **state)
{
    (void)state;
    geo_poly *p = saddle_block(0.5);
    assert_null(cs_check_valid(p, 1e-12));
    /* below: the section is two triangles meeting at the saddle vertex,
     * which become two new facets; the solid stays manifold there */
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, 1, 0, &rep);
    assert_int_equal(rep.components, 2);
    assert_int_equal(rep.new_facets, 2);
    /* above: two blobs touching only at the saddle vertex */
    geo_err err = {{0}};
    assert_int_equal(cut_code(p, 0, 0, -1, 0, NULL, &err), -ENOTSUP);
    assert_non_null(strstr(err.msg, "touch itself"));
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_pinching_results_are_refused(void **state)
{
    (void)state;
    geo_err err = {{0}};
    geo_poly *p = notch_prism();
    /* y ≤ 5 touches the reflex vertical edge from inside: the two kept
     * halves would share only that edge */
    assert_int_equal(cut_code(p, 0, 1, 0, -5, NULL, &err), -ENOTSUP);
    assert_non_null(strstr(err.msg, "reflex edge"));
    /* y ≥ 5 keeps one block, the edge only touching it */
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, -1, 0, 5, &rep);
    assert_close(geo_poly_volume(o), 10.0 * 3 * 2, 1e-12);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_cavity_apex_on_plane(void **state)
{
    (void)state;
    geo_poly *p = cs_dented_box(4);
    assert_null(cs_check_valid(p, 1e-12));
    assert_close(geo_poly_volume(p), 1000.0 - 64.0 / 3.0, 1e-12);
    geo_err err = {{0}};
    /* keeping below the apex: the new facet would pass over it */
    assert_int_equal(cut_code(p, 0, 0, 1, -4, NULL, &err), -ENOTSUP);
    assert_non_null(strstr(err.msg, "cavity"));
    /* a little lower the dent is a hole in the section: the square with
     * the dent's square cross-section (side 1) taken out */
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, 1, -3, &rep);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    assert_close(geo_poly_volume(o), 300.0 - (64.0 - 1.0) / 3.0, 1e-12);
    geo_poly_free(o);
    /* keeping above: a plain block, the apex gone */
    o = cut_ok(p, 0, 0, -1, 4, &rep);
    assert_close(geo_poly_volume(o), 600.0, 1e-12);
    assert_int_equal(o->nverts, 8);
    geo_poly_free(o);
    geo_poly_free(p);
    /* the apex of a peak of the solid on the plane is fine: the new facet
     * keeps away from it */
    p = cs_dented_box(-4);
    double vol = 1000.0 + 64.0 / 3.0;
    assert_close(geo_poly_volume(p), vol, 1e-12);
    o = cut_ok(p, 1.5, 0, -1, -11.5, &rep);
    geo_poly *q = cut_ok(p, -1.5, 0, 1, 11.5, &rep);
    assert_close(geo_poly_volume(o) + geo_poly_volume(q), vol, 1e-12);
    geo_poly_free(o);
    geo_poly_free(q);
    geo_poly_free(p);
}

static void test_section_with_hole_becomes_several_facets(void **state)
{
    (void)state;
    geo_poly *p = cs_frame();
    assert_close(geo_poly_volume(p), 336.0, 1e-12);
    /* along the ring's plane: one component, an annulus, which
     * facet-model/1 holds as several coplanar facets */
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, 1, -2, &rep);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    assert_close(geo_poly_volume(o), 168.0, 1e-12);
    geo_poly_free(o);
    /* across the ring: two components, two halves */
    o = cut_ok(p, 1, 0, 0, -5, &rep);
    assert_int_equal(rep.components, 2);
    assert_int_equal(rep.new_facets, 2);
    assert_close(geo_poly_volume(o), 168.0, 1e-12);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_rejects_bad_input(void **state)
{
    (void)state;
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    geo_err err = {{0}};
    assert_int_equal(cut_code(p, 0, 0, 0, 1, NULL, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "zero"));
    assert_int_equal(cut_code(p, NAN, 0, 1, 1, NULL, &err), -EINVAL);
    assert_int_equal(cut_code(p, INFINITY, 0, 1, 1, NULL, &err), -EINVAL);
    /* an open model */
    geo_poly *open = tu_seed003_example();
    assert_int_equal(cut_code(open, 0, 0, 1, -3, NULL, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "closed"));
    geo_poly_free(open);
    geo_poly_free(p);
}

static int cancel_at_once(void *user, double fraction)
{
    (void)user;
    (void)fraction;
    return 1;
}

static void test_cancel_leaves_output_empty(void **state)
{
    (void)state;
    geo_poly *p = cs_sphere(20, 20, 0.2);
    geo_ctx ctx = {0};
    ctx.progress = cancel_at_once;
    double pl[4] = {0.3, 0.1, 1, -0.1};
    geo_poly *out = geo_poly_new();
    geo_err err = {{0}};
    assert_int_equal(geo_cut(p, pl, NULL, &ctx, out, NULL, &err), -ECANCELED);
    assert_int_equal(out->nfacets, 0);
    geo_poly_free(out);
    geo_poly_free(p);
}

/* ---- §3.4 variant --------------------------------------------------- */

/* The unit box with its top corners at different heights: the top facet
 * is not planar, the sides are. */
static geo_poly *tilted_top_box(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *p = tu_box(lo, hi);
    p->verts[5][2] = 1.02; /* (1,0,1) */
    p->verts[6][2] = 1.01; /* (0,1,1) */
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

static void test_main_facet_variant_replaces_nonplanar_facet(void **state)
{
    (void)state;
    geo_poly *p = tilted_top_box();
    geo_cut_opts opts;
    geo_cut_opts_default(&opts);
    opts.main_facet = 1; /* the top */
    double pl[4] = {0, 0, 1, -1};
    geo_poly *out = geo_poly_new();
    geo_cut_report rep;
    geo_err err = {{0}};
    assert_int_equal(geo_cut(p, pl, &opts, NULL, out, &rep, &err), 0);
    assert_null(cs_check_valid(out, 1e-12));
    assert_int_equal(rep.components, 1);
    assert_int_equal(out->nfacets, 6);
    assert_int_equal(out->nverts, 8);
    assert_close(geo_poly_volume(out), 1.0, 1e-14);
    /* the new facet is the old top made planar */
    uint32_t f = rep.first_new_facet;
    for (uint32_t j = 0; j < 4; j++)
        assert_close(out->verts[geo_poly_facet(out, f)[j]][2], 1.0, 1e-15);
    geo_poly_free(out);
    /* a main facet with a vertex on the kept side is an error */
    opts.main_facet = 2;
    assert_int_equal(cut_code(p, 0, 0, 1, -1, &opts, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "main facet"));
    geo_poly_free(p);
    /* a section of two components is refused for a merge */
    geo_poly *comb = cs_comb_prism(2);
    uint32_t tip = GEO_NONE;
    for (uint32_t g = 0; g < comb->nfacets && tip == GEO_NONE; g++)
        if (comb->planes[g][1] > 0.5 &&
            comb->verts[geo_poly_facet(comb, g)[0]][1] == 8)
            tip = g;
    assert_int_not_equal(tip, GEO_NONE);
    opts.main_facet = tip;
    assert_int_equal(cut_code(comb, 0, 1, 0, -5, &opts, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "2 components"));
    geo_poly_free(comb);
}

/* ---- random planes ------------------------------------------------ */

static void random_plane_in_box(const geo_poly *p, uint64_t *seed,
                                double ret[4])
{
    double lo[3], hi[3], x[3], n[3];
    geo_poly_bbox(p, lo, hi);
    do {
        for (int k = 0; k < 3; k++)
            n[k] = 2 * geo_rand_unit(seed) - 1;
    } while (geo_vdot(n, n) > 1 || geo_vdot(n, n) < 1e-4);
    for (int k = 0; k < 3; k++)
        x[k] = lo[k] + (hi[k] - lo[k]) * (0.05 + 0.9 * geo_rand_unit(seed));
    memcpy(ret, n, sizeof n);
    ret[3] = -geo_vdot(n, x);
}

/* Cuts by random planes and their opposites: both valid, volumes adding
 * up to the original to 1e-9 relative; none refused. Returns how many
 * sections had a hole (more new facets than components). */
static int check_random_halves(const geo_poly *p, uint64_t seed, int count)
{
    double vol = geo_poly_volume(p);
    int holed = 0;
    for (int i = 0; i < count; i++) {
        double pl[4], neg[4];
        random_plane_in_box(p, &seed, pl);
        for (int k = 0; k < 4; k++)
            neg[k] = -pl[k];
        geo_poly *a = geo_poly_new(), *b = geo_poly_new();
        geo_cut_report ra, rb;
        geo_err ea = {{0}}, eb = {{0}};
        int r1 = geo_cut(p, pl, NULL, NULL, a, &ra, &ea);
        int r2 = geo_cut(p, neg, NULL, NULL, b, &rb, &eb);
        if (r1 || r2)
            fail_msg("plane %d (%.17g,%.17g,%.17g,%.17g): %s / %s", i,
                     pl[0], pl[1], pl[2], pl[3], ea.msg, eb.msg);
        const char *ba = ra.empty ? NULL : cs_check_valid(a, tol_of(p));
        if (!ba && !ra.empty)
            ba = inspect_problem(a);
        const char *bb = rb.empty ? NULL : cs_check_valid(b, tol_of(p));
        if (!bb && !rb.empty)
            bb = inspect_problem(b);
        if (ba || bb)
            fail_msg("plane %d (%.17g,%.17g,%.17g,%.17g): %s / %s", i,
                     pl[0], pl[1], pl[2], pl[3], ba ? ba : "ok",
                     bb ? bb : "ok");
        double va = ra.empty ? 0 : geo_poly_volume(a);
        double vb = rb.empty ? 0 : geo_poly_volume(b);
        if (!(fabs(va + vb - vol) <= 1e-9 * vol))
            fail_msg("plane %d: %.17g + %.17g != %.17g", i, va, vb, vol);
        assert_int_equal(ra.components, rb.components);
        holed += ra.new_facets > ra.components;
        geo_poly_free(a);
        geo_poly_free(b);
    }
    return holed;
}

static void test_random_planes_nonconvex_models(void **state)
{
    (void)state;
    /* the notch cube has sections with a hole (a plane clipping the
     * notch's inner corner), the ring and the bumpy sphere many; none is
     * refused */
    struct {
        geo_poly *p;
        int min_holed;
    } models[] = {{tu_notch_cube(), 3}, {l_prism(), 0},
                  {cs_star_prism(7, 1.0, 2.5, 1.5), 0}, {cs_comb_prism(3), 0},
                  {notch_prism(), 0}, {cs_sphere(24, 32, 0.25), 3},
                  {cs_frame(), 3}};
    for (size_t i = 0; i < sizeof models / sizeof models[0]; i++) {
        assert_non_null(models[i].p);
        assert_null(cs_check_valid(models[i].p, 1e-9));
        int holed = check_random_halves(models[i].p, 100 + i, 150);
        if (holed < models[i].min_holed)
            fail_msg("model %zu: only %d of 150 sections with a hole", i, holed);
        geo_poly_free(models[i].p);
    }
}

static geo_poly *load(const char *name)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(tu_model_path(name), PROTO_FMT_UNKNOWN,
                                        NULL, &err);
    if (!p)
        fail_msg("%s: %s", name, err.msg);
    return p;
}

/* Planes through a vertex as users compute them, d = −n·v in floating
 * point, so that the vertex lies off the plane by a rounding error (and
 * the crossings on its edges would round onto it): the vertex counts as
 * on the plane (lib/core/poly.h's tolerance), every result is valid, and
 * only true pinches are refused (-ENOTSUP). */
static void test_planes_through_vertices_in_floating_point(void **state)
{
    (void)state;
    geo_poly *models[] = {tu_notch_cube(), l_prism(),
                          cs_sphere(24, 32, 0.25), cs_frame(),
                          load("brilliant.scan-k100.json")};
    for (size_t i = 0; i < sizeof models / sizeof models[0]; i++) {
        geo_poly *p = models[i];
        assert_non_null(p);
        uint64_t seed = 900 + i;
        double vol = geo_poly_volume(p);
        int refused = 0, total = 0;
        for (int t = 0; t < 60; t++) {
            double n[3], pl[4], neg[4];
            do {
                for (int k = 0; k < 3; k++)
                    n[k] = 2 * geo_rand_unit(&seed) - 1;
            } while (geo_vdot(n, n) > 1 || geo_vdot(n, n) < 1e-4);
            uint32_t v = (uint32_t)(geo_rand_unit(&seed) * p->nverts);
            const double *x = p->verts[v < p->nverts ? v : 0];
            pl[0] = n[0], pl[1] = n[1], pl[2] = n[2];
            pl[3] = -(n[0] * x[0] + n[1] * x[1] + n[2] * x[2]);
            for (int k = 0; k < 4; k++)
                neg[k] = -pl[k];
            const double *planes[2] = {pl, neg};
            double vols[2] = {0, 0};
            int codes[2];
            for (int h = 0; h < 2; h++) {
                geo_poly *o = geo_poly_new();
                geo_cut_report rep;
                geo_err err = {{0}};
                codes[h] = geo_cut(p, planes[h], NULL, NULL, o, &rep, &err);
                total++;
                if (codes[h] == -ENOTSUP) {
                    refused++;
                } else if (codes[h] != 0) {
                    fail_msg("model %zu plane %d: %s", i, t, err.msg);
                } else if (!rep.empty) {
                    const char *why = cs_check_valid(o, tol_of(p));
                    if (!why)
                        why = inspect_problem(o);
                    if (why)
                        fail_msg("model %zu plane %d (%.17g,%.17g,%.17g,"
                                 "%.17g) through vertex %u: %s", i, t, pl[0],
                                 pl[1], pl[2], pl[3], v, why);
                    vols[h] = geo_poly_volume(o);
                }
                geo_poly_free(o);
            }
            if (codes[0] == 0 && codes[1] == 0 &&
                !(fabs(vols[0] + vols[1] - vol) <= 1e-9 * vol))
                fail_msg("model %zu plane %d: %.17g + %.17g != %.17g", i, t,
                         vols[0], vols[1], vol);
        }
        if (refused * 5 > total)
            fail_msg("model %zu: %d of %d cuts refused", i, refused, total);
        geo_poly_free(p);
    }
}


static void test_sample_models_random_planes(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        int planes;
    } models[] = {{"brilliant.truth.json", 200},
                  {"brilliant.scan-k100.json", 60},
                  {"brilliant.scan-k400.json", 40},
                  {"brilliant.scan-k800.json", 20}};
    for (size_t i = 0; i < sizeof models / sizeof models[0]; i++) {
        geo_poly *p = load(models[i].name);
        check_random_halves(p, 7 + i, models[i].planes);
        geo_poly_free(p);
    }
}

static void test_sample_files_match_the_built_models(void **state)
{
    (void)state;
    geo_poly *p = load("notch-cube.json");
    geo_cut_report rep;
    geo_poly *o = cut_ok(p, 0, 0, 1, -8, &rep);
    assert_close(geo_poly_volume(o), 768.0, 1e-12);
    geo_poly_free(o);
    o = cut_ok(p, 0, 0, 1, -6, &rep);
    assert_int_equal(o->nfacets, 6);
    geo_poly_free(o);
    geo_poly_free(p);
    p = load("l-prism.json");
    o = cut_ok(p, 0, 1, 0, -4, &rep);
    assert_close(geo_poly_volume(o), 240.0, 1e-12);
    assert_int_equal(o->nverts, 8);
    geo_poly_free(o);
    geo_poly_free(p);
}

/* For each vertex of a, the distance to the nearest vertex of b. */
static double vertex_set_distance(const geo_poly *a, const geo_poly *b)
{
    double worst = 0;
    for (uint32_t i = 0; i < a->nverts; i++) {
        double best = INFINITY;
        for (uint32_t j = 0; j < b->nverts; j++)
            best = fmin(best, geo_vdist(a->verts[i], b->verts[j]));
        worst = fmax(worst, best);
    }
    return worst;
}

static void test_convex_cut_equals_halfspace_intersection(void **state)
{
    (void)state;
    uint64_t seed = 42;
    int compared = 0;
    for (int trial = 0; trial < 40; trial++) {
        enum { M = 14 };
        double planes[M + 4 + 1][4];
        cs_random_planes(&seed, M, planes);
        geo_poly *p = cs_convex((const double(*)[4])planes, M + 4, 1e-9);
        if (!p)
            continue;
        /* one more plane, through the interior */
        double n[3];
        do {
            for (int k = 0; k < 3; k++)
                n[k] = 2 * geo_rand_unit(&seed) - 1;
        } while (geo_vdot(n, n) > 1 || geo_vdot(n, n) < 1e-3);
        geo_vnormalize(n);
        memcpy(planes[M + 4], n, sizeof n);
        planes[M + 4][3] = -0.6 * geo_rand_unit(&seed);
        geo_poly *want = cs_convex((const double(*)[4])planes, M + 5, 1e-9);
        if (!want) {
            geo_poly_free(p);
            continue;
        }
        geo_cut_report rep;
        geo_poly *got = cut_ok(p, planes[M + 4][0], planes[M + 4][1],
                               planes[M + 4][2], planes[M + 4][3], &rep);
        assert_int_equal(got->nverts, want->nverts);
        assert_int_equal(got->nfacets, want->nfacets);
        assert_true(vertex_set_distance(got, want) < 1e-9);
        assert_true(vertex_set_distance(want, got) < 1e-9);
        assert_close(geo_poly_volume(got), geo_poly_volume(want), 1e-9);
        compared++;
        geo_poly_free(got);
        geo_poly_free(want);
        geo_poly_free(p);
    }
    assert_true(compared >= 20);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_crossing_order_is_exact_below_rounding),
        cmocka_unit_test(test_box_cut_in_half),
        cmocka_unit_test(test_notch_cube_u_shaped_section),
        cmocka_unit_test(test_notch_floor_in_plane_ends_inside_new_facet),
        cmocka_unit_test(test_notch_floor_facing_away_is_dropped),
        cmocka_unit_test(test_l_prism_cuts),
        cmocka_unit_test(test_star_prism_splits_into_several_pieces),
        cmocka_unit_test(test_comb_gives_one_component_per_prong),
        cmocka_unit_test(test_vertices_and_edges_on_plane),
        cmocka_unit_test(test_plane_missing_or_touching_is_unchanged_or_empty),
        cmocka_unit_test(test_convex_edge_in_plane_stays_between_its_facets),
        cmocka_unit_test(test_reflex_vertex_on_plane),
        cmocka_unit_test(test_pinching_results_are_refused),
        cmocka_unit_test(test_saddle_vertex_on_plane),
        cmocka_unit_test(test_section_with_hole_becomes_several_facets),
        cmocka_unit_test(test_cavity_apex_on_plane),
        cmocka_unit_test(test_rejects_bad_input),
        cmocka_unit_test(test_cancel_leaves_output_empty),
        cmocka_unit_test(test_main_facet_variant_replaces_nonplanar_facet),
        cmocka_unit_test(test_random_planes_nonconvex_models),
        cmocka_unit_test(test_convex_cut_equals_halfspace_intersection),
        cmocka_unit_test(test_sample_models_random_planes),
        cmocka_unit_test(test_planes_through_vertices_in_floating_point),
        cmocka_unit_test(test_sample_files_match_the_built_models),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
