/* test_stitch.c — Nesterenko's stitching (lib/mesh/stitch.h): two halves of a
 * body with a band of facets removed come back as one valid closed solid
 * close to the original, whichever way the second half is oriented,
 * however differently the halves are sampled and wherever their loops
 * start; meshes side by side are bridged between the vertices facing
 * each other (algorithm 2) and the openings closed; a gem cut unevenly
 * near its girdle is joined as a band; halves of convex stones come back
 * from their facet planes extended across the gap, a non-convex pair by
 * the band, halves on one polyline sampled differently are welded,
 * overlapping halves trimmed back to one plane and welded; the pipeline
 * form
 * takes a model of two pieces and refuses any other. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cut.h"
#include "design.h"
#include "gen_convex.h"
#include "gen_sphere.h"
#include "halfspace.h"
#include "hausdorff.h"
#include "model_io.h"
#include "rim_split.h"
#include "stats.h"
#include "stitch.h"
#include "stone_sim.h"

/* The facets of s whose centre has lo < z < hi (or, with axis 0, x). */
static geo_poly *part(const geo_poly *s, int axis, double lo, double hi)
{
    geo_poly *p = geo_poly_copy(s);
    bool *k = malloc(p->nfacets * sizeof *k);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double c[3];
        geo_poly_facet_center(p, f, c);
        k[f] = c[axis] > lo && c[axis] < hi;
    }
    assert_int_equal(geo_poly_compact(p, k, NULL, NULL), 0);
    free(k);
    return p;
}

static void test_halves_of_a_sphere_become_one_valid_solid(void **s)
{
    (void)s;
    geo_poly *sp = gs_sphere(24, 1.0);
    geo_poly *top = part(sp, 2, 0.2, 9), *bot = part(sp, 2, -9, -0.2);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(top, bot, NULL, NULL, out, &rep, NULL), 0);
    assert_true(rep.band);
    assert_false(rep.flipped2);
    assert_int_equal(rep.meridians, rep.nloop1 > rep.nloop2 ? rep.nloop1
                                                            : rep.nloop2);
    assert_true(rep.rows > 2); /* the 0.4 gap is several edges long */
    assert_int_equal(out->nverts,
                     top->nverts + bot->nverts + rep.band_vertices);
    assert_true(tu_is_valid(out));
    double h = sim_hausdorff(out, sp, 500);
    assert_true(h < 0.02);
    assert_true(fabs(geo_poly_volume(out) - geo_poly_volume(sp)) <
                0.01 * geo_poly_volume(sp));
    geo_stitch_report_clear(&rep);
    geo_poly_free(out), geo_poly_free(top), geo_poly_free(bot);
    geo_poly_free(sp);
}

static void test_second_mesh_turned_over_is_oriented_back(void **s)
{
    (void)s;
    geo_poly *st = sim_stone(SIM_BRILLIANT, 3);
    geo_poly *top = part(st, 2, 0.3, 99), *bot = part(st, 2, -99, -0.3);
    for (uint32_t f = 0; f < bot->nfacets; f++)
        geo_poly_flip_facet(bot, f);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(top, bot, NULL, NULL, out, &rep, NULL), 0);
    assert_true(rep.flipped2);
    assert_true(tu_is_valid(out));
    assert_true(geo_poly_volume(out) > 0.9 * geo_poly_volume(st));
    geo_stitch_report_clear(&rep);
    geo_poly_free(out), geo_poly_free(top), geo_poly_free(bot);
    geo_poly_free(st);
}

static void test_loops_of_very_different_lengths_are_bridged(void **s)
{
    (void)s;
    geo_poly *fine = gs_sphere(40, 1.0), *coarse = gs_sphere(6, 1.0);
    geo_poly *top = part(fine, 2, 0.25, 9), *bot = part(coarse, 2, -9, -0.25);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(top, bot, NULL, NULL, out, &rep, NULL), 0);
    assert_true(rep.nloop1 > 5 * rep.nloop2);
    assert_int_equal(rep.meridians, rep.nloop1);
    assert_true(tu_is_valid(out));
    geo_stitch_report_clear(&rep);
    geo_poly_free(out), geo_poly_free(top), geo_poly_free(bot);
    geo_poly_free(fine), geo_poly_free(coarse);
}

/* The same mesh with its facets listed in rotated order: its free-edge
 * loop starts elsewhere. */
static geo_poly *rotate_facets(const geo_poly *p, uint32_t by)
{
    geo_poly *q = geo_poly_new();
    for (uint32_t v = 0; v < p->nverts; v++)
        geo_poly_add_vertex(q, p->verts[v]);
    for (uint32_t k = 0; k < p->nfacets; k++) {
        uint32_t f = (k + by) % p->nfacets;
        int64_t nf = geo_poly_add_facet(q, geo_poly_facet(p, f),
                                        geo_poly_facet_size(p, f));
        memcpy(q->planes[nf], p->planes[f], sizeof q->planes[0]);
    }
    return q;
}

static void test_twist_is_chosen_whatever_the_loops_start(void **s)
{
    (void)s;
    geo_poly *sp = gs_sphere(16, 1.0);
    geo_poly *top = part(sp, 2, 0.2, 9), *bot = part(sp, 2, -9, -0.2);
    double len[3];
    for (int k = 0; k < 3; k++) {
        geo_poly *b2 = rotate_facets(bot, (uint32_t)k * 37);
        geo_poly *out = geo_poly_new();
        geo_stitch_report rep;
        assert_int_equal(geo_stitch(top, b2, NULL, NULL, out, &rep, NULL), 0);
        len[k] = rep.meridian_length;
        assert_true(tu_is_valid(out));
        geo_stitch_report_clear(&rep);
        geo_poly_free(out), geo_poly_free(b2);
    }
    assert_true(fabs(len[1] - len[0]) < 1e-9 * len[0]);
    assert_true(fabs(len[2] - len[0]) < 1e-9 * len[0]);
    geo_poly_free(top), geo_poly_free(bot), geo_poly_free(sp);
}

static void test_side_by_side_meshes_bridge_facing_vertices(void **s)
{
    (void)s;
    /* a cap of the sphere cut lengthwise: two open pieces side by side */
    geo_poly *sp = gs_sphere(24, 1.0);
    geo_poly *cap = part(sp, 2, 0.55, 9);
    geo_poly *left = part(cap, 0, -9, -0.1), *right = part(cap, 0, 0.1, 9);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(left, right, NULL, NULL, out, &rep, NULL), 0);
    assert_false(rep.band);
    assert_true(rep.chosen1 < rep.nloop1 && rep.chosen2 < rep.nloop2);
    assert_true(rep.chosen1 >= 2 && rep.chosen2 >= 2);
    /* the rest of the loops is one opening: the cap's rim, closed */
    assert_int_equal(rep.fill.nloops, 1);
    assert_int_equal(rep.fill.nfilled, 1);
    assert_true(tu_is_valid(out));
    geo_stitch_report_clear(&rep);
    geo_poly_free(out), geo_poly_free(left), geo_poly_free(right);
    geo_poly_free(cap), geo_poly_free(sp);
}

/* Halves cut from one mesh share their loop: the zero-width band was
 * made of zero-area facets (every stitch of a model cut in two with one
 * plane was invalid); the loops are welded instead. */
static void test_halves_whose_loops_coincide_are_welded(void **s)
{
    (void)s;
    geo_poly *sp = gs_sphere(16, 1.0);
    geo_poly *top = part(sp, 2, 0.0, 9), *bot = part(sp, 2, -9, 0.0);
    /* the second half a few units in the last place off, as a cut by the
     * opposite plane computes its crossings */
    for (uint32_t v = 0; v < bot->nverts; v++)
        bot->verts[v][0] *= 1 + 4e-16;
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(top, bot, NULL, NULL, out, &rep, NULL), 0);
    assert_int_equal(rep.welded, rep.nloop1);
    assert_int_equal(rep.band_facets, 0);
    assert_int_equal(rep.fill.nloops, 0);
    assert_int_equal(out->nverts, sp->nverts);
    assert_int_equal(out->nfacets, sp->nfacets);
    assert_true(tu_is_valid(out));
    assert_true(fabs(geo_poly_volume(out) - geo_poly_volume(sp)) <
                1e-12 * geo_poly_volume(sp));
    geo_stitch_report_clear(&rep);
    /* turned over, the second half is welded all the same */
    for (uint32_t f = 0; f < bot->nfacets; f++)
        geo_poly_flip_facet(bot, f);
    assert_int_equal(geo_stitch(top, bot, NULL, NULL, out, &rep, NULL), 0);
    assert_true(rep.flipped2);
    assert_int_equal(rep.welded, rep.nloop1);
    assert_true(tu_is_valid(out));
    geo_stitch_report_clear(&rep);
    geo_poly_free(out), geo_poly_free(top), geo_poly_free(bot);
    geo_poly_free(sp);
}

/* A torus around z (radii 2 and 0.7), nu × nv quads split into
 * triangles, outward. */
static geo_poly *torus(uint32_t nu, uint32_t nv)
{
    geo_poly *p = geo_poly_new();
    for (uint32_t i = 0; i < nu; i++)
        for (uint32_t j = 0; j < nv; j++) {
            double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
            double x[3] = {(2 + 0.7 * cos(v)) * cos(u),
                           (2 + 0.7 * cos(v)) * sin(u), 0.7 * sin(v)};
            geo_poly_add_vertex(p, x);
        }
    for (uint32_t i = 0; i < nu; i++)
        for (uint32_t j = 0; j < nv; j++) {
            uint32_t a = i * nv + j, b = ((i + 1) % nu) * nv + j;
            uint32_t c = ((i + 1) % nu) * nv + (j + 1) % nv;
            uint32_t d = i * nv + (j + 1) % nv;
            uint32_t tri[2][3] = {{a, b, c}, {a, c, d}};
            for (int k = 0; k < 2; k++) {
                uint32_t f = (uint32_t)geo_poly_add_facet(p, tri[k], 3);
                geo_poly_facet_fit_plane(p, f, GEO_PLANE_UNWEIGHTED,
                                         p->planes[f]);
            }
        }
    return p;
}

/* Cut across its hole, each half of a torus has two loops; the pair not
 * chosen was closed by two planar facets on top of each other and left
 * open as intersecting. Both pairs are welded now. */
static void test_every_pair_of_coinciding_loops_is_welded(void **s)
{
    (void)s;
    geo_poly *t = torus(24, 12);
    assert_true(tu_is_valid(t));
    geo_poly *l = part(t, 0, -9, 0.0), *r = part(t, 0, 0.0, 9);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(l, r, NULL, NULL, out, &rep, NULL), 0);
    assert_int_equal(rep.loops1, 2);
    assert_int_equal(rep.loops2, 2);
    assert_int_equal(rep.welded_loops, 1);
    assert_int_equal(rep.welded, 2 * 12);
    assert_int_equal(rep.fill.nloops, 0);
    assert_int_equal(out->nverts, t->nverts);
    assert_true(tu_is_valid(out));
    assert_true(fabs(geo_poly_volume(out) - geo_poly_volume(t)) <
                1e-12 * geo_poly_volume(t));
    geo_stitch_report_clear(&rep);
    geo_poly_free(out), geo_poly_free(l), geo_poly_free(r), geo_poly_free(t);
}

/* The open half of m on the side plane ≤ 0 (the cut's caps dropped). */
static geo_poly *open_half(const geo_poly *m, const double plane[4])
{
    geo_poly *out = geo_poly_new();
    geo_cut_report rep;
    assert_int_equal(geo_cut(m, plane, NULL, NULL, out, &rep, NULL), 0);
    bool *keep = malloc(out->nfacets * sizeof *keep);
    for (uint32_t f = 0; f < out->nfacets; f++)
        keep[f] = f < rep.first_new_facet;
    assert_int_equal(geo_poly_compact(out, keep, NULL, NULL), 0);
    free(keep);
    return out;
}

/* A brilliant cut by a plane tilted 0.5° just below its girdle, a band of
 * 0.28 mm removed: one loop crosses many small facets, so the loops are
 * sampled very unevenly and their vertex means sit apart; cuts like this
 * were taken for side-by-side lines (2 of tests/tools/stitch_halves'
 * first 12 cases: a bridge with 8 self-intersections). Length-weighted
 * centres keep it a band; the facet planes extended across the gap
 * close it validly, 0.065 mm off the stone where the 23 girdle facets
 * wholly inside the band are lost (their neighbours' planes meet beyond
 * them; the straight band of meridians was 0.16 mm off). */
static void test_gem_halves_cut_unevenly_are_joined_as_a_band(void **s)
{
    (void)s;
    geo_err err = {{0}};
    geo_poly *m = proto_model_read_file(tu_model_path("brilliant.truth.json"),
                                        PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(m);
    double t = 0.5 * M_PI / 180, n[3] = {sin(t), 0, cos(t)}, z = -0.014,
           band = 0.28;
    double top[4] = {-n[0], -n[1], -n[2], z + band / 2};
    double bot[4] = {n[0], n[1], n[2], -z + band / 2};
    geo_poly *a = open_half(m, top), *b = open_half(m, bot);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
    assert_true(rep.band);
    assert_false(rep.flipped2);
    assert_int_equal(rep.fill.nopen, 0);
    assert_true(tu_is_valid(out));
    double hd;
    assert_int_equal(geo_hausdorff(out, m, &hd, NULL), 0);
    if (!(hd < 0.1))
        fail_msg("Hausdorff %.4f mm", hd);
    assert_int_equal(rep.method, GEO_STITCH_PLANES);
    geo_stitch_report_clear(&rep);
    geo_poly_free(a), geo_poly_free(b), geo_poly_free(out), geo_poly_free(m);
}

/* The two halves of m with the band |n·x + d| < band/2 removed, opened. */
static void halves(const geo_poly *m, const double n[3], double d, double band,
                   geo_poly **top, geo_poly **bot)
{
    double pt[4] = {-n[0], -n[1], -n[2], -d + band / 2};
    double pb[4] = {n[0], n[1], n[2], d + band / 2};
    *top = open_half(m, pt);
    *bot = open_half(m, pb);
}

/* The region inside every facet plane of a and b, exactly. */
static geo_poly *all_halfspaces(const geo_poly *a, const geo_poly *b)
{
    uint32_t n = a->nfacets + b->nfacets;
    double *pl = malloc((size_t)n * 4 * sizeof *pl);
    for (uint32_t f = 0; f < a->nfacets; f++)
        memcpy(pl + 4 * f, a->planes[f], 4 * sizeof *pl);
    for (uint32_t f = 0; f < b->nfacets; f++)
        memcpy(pl + 4 * (a->nfacets + f), b->planes[f], 4 * sizeof *pl);
    geo_poly *h = NULL;
    uint32_t *src = NULL;
    assert_int_equal(geo_halfspace_intersect(pl, n, -1, &h, &src, NULL, NULL), 0);
    free(pl), free(src);
    return h;
}

/* A brilliant with a 0.4 mm band removed across its crown, tilted 3.4°:
 * every facet the band crosses keeps a piece on one side at least, so
 * the facet planes extended across the gap rebuild the stone — the
 * straight band of meridians was 0.11 mm off where it cut the corners
 * of the crown's facets. The result is the intersection of all the
 * halves' facet half-spaces (both halves are convex). */
static void test_convex_stone_comes_back_from_its_facet_planes(void **s)
{
    (void)s;
    geo_err err = {{0}};
    geo_poly *m = proto_model_read_file(tu_model_path("brilliant.truth.json"),
                                        PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(m);
    double t = 3.4 * M_PI / 180, n[3] = {sin(t), 0, cos(t)};
    geo_poly *a, *b;
    halves(m, n, -0.365, 0.4, &a, &b);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
    assert_true(tu_is_valid(out));
    double hd;
    assert_int_equal(geo_hausdorff(out, m, &hd, NULL), 0);
    if (!(hd < 0.05))
        fail_msg("Hausdorff %.4f mm", hd);
    assert_int_equal(rep.method, GEO_STITCH_PLANES);
    assert_string_equal(geo_stitch_method_name(rep.method), "planes");
    assert_true(rep.planes > 8);
    geo_poly *h = all_halfspaces(a, b);
    double v = geo_poly_volume(out), vh = geo_poly_volume(h);
    if (!(fabs(v - vh) <= 1e-9 * vh))
        fail_msg("volume %.12f, of all the half-spaces %.12f", v, vh);
    geo_stitch_report_clear(&rep);
    /* the second half turned over: oriented back, then the same planes */
    for (uint32_t f = 0; f < b->nfacets; f++)
        geo_poly_flip_facet(b, f);
    assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
    assert_true(rep.flipped2);
    assert_int_equal(rep.method, GEO_STITCH_PLANES);
    assert_true(tu_is_valid(out));
    if (!(fabs(geo_poly_volume(out) - vh) <= 1e-9 * vh))
        fail_msg("turned over: volume %.12f, of all the half-spaces %.12f",
                 geo_poly_volume(out), vh);
    geo_stitch_report_clear(&rep);
    geo_poly_free(h), geo_poly_free(a), geo_poly_free(b), geo_poly_free(out);
    geo_poly_free(m);
}

/* Random convex polyhedra cut at random planes with bands of 0.05–0.5 of
 * their radius of 3 removed: every result is valid; when the planes
 * closed it, it is the intersection of all the halves' half-spaces. */
static void test_random_convex_halves_are_valid(void **s)
{
    (void)s;
    uint64_t seed = 7;
    int planes = 0;
    for (int i = 0; i < 12; i++) {
        double c[3] = {0, 0, 0};
        geo_poly *m = gen_convex_polyhedron(100 + i, 24, c, 3.0);
        double th = geo_rand_unit(&seed) * 0.3, az = geo_rand_unit(&seed) * 6.28;
        double n[3] = {sin(th) * cos(az), sin(th) * sin(az), cos(th)};
        double d = (geo_rand_unit(&seed) - 0.5) * 1.5,
               band = 0.05 + geo_rand_unit(&seed) * 0.45;
        geo_poly *a, *b;
        halves(m, n, d, band, &a, &b);
        geo_poly *out = geo_poly_new();
        geo_stitch_report rep;
        assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
        if (!tu_is_valid(out))
            fail_msg("case %d (method %s) not valid", i,
                     geo_stitch_method_name(rep.method));
        if (rep.method == GEO_STITCH_PLANES) {
            geo_poly *h = all_halfspaces(a, b);
            double v = geo_poly_volume(out), vh = geo_poly_volume(h);
            if (!(fabs(v - vh) <= 1e-9 * vh))
                fail_msg("case %d: volume %.12f, of all the half-spaces %.12f",
                         i, v, vh);
            geo_poly_free(h);
            planes++;
        }
        geo_stitch_report_clear(&rep);
        geo_poly_free(a), geo_poly_free(b), geo_poly_free(out), geo_poly_free(m);
    }
    assert_true(planes >= 10);
}

/* Halves that overlap (a band of −0.05…−0.5 mm: each reaches past the
 * cut) are cut back to the plane midway between their loops and welded
 * there: the body itself comes back (its volume to 1e-9), on random
 * convex bodies and on the brilliant; halves apart by a gap are not
 * trimmed. */
static void test_overlapping_halves_are_trimmed_back_to_the_body(void **s)
{
    (void)s;
    uint64_t seed = 11;
    geo_err err = {{0}};
    for (int i = 0; i < 13; i++) {
        double c[3] = {0, 0, 0};
        geo_poly *m = i < 12 ? gen_convex_polyhedron(200 + i, 24, c, 3.0)
                             : proto_model_read_file(
                                   tu_model_path("brilliant.truth.json"),
                                   PROTO_FMT_UNKNOWN, NULL, &err);
        assert_non_null(m);
        double th = geo_rand_unit(&seed) * 0.3, az = geo_rand_unit(&seed) * 6.28;
        double n[3] = {sin(th) * cos(az), sin(th) * sin(az), cos(th)};
        double d = (geo_rand_unit(&seed) - 0.5) * (i < 12 ? 1.5 : 0.4),
               band = 0.05 + geo_rand_unit(&seed) * 0.45;
        for (int gap = 0; gap < 2; gap++) {
            geo_poly *a, *b;
            halves(m, n, d, gap ? band : -band, &a, &b);
            geo_poly *out = geo_poly_new();
            geo_stitch_report rep;
            assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
            if (!tu_is_valid(out))
                fail_msg("case %d (%s) not valid", i, gap ? "gap" : "overlap");
            assert_int_equal(rep.trimmed, !gap);
            if (!gap) {
                assert_int_equal(rep.method, GEO_STITCH_WELD);
                double v = geo_poly_volume(out), vm = geo_poly_volume(m);
                if (!(fabs(v - vm) <= 1e-9 * vm))
                    fail_msg("case %d: volume %.12f, the body's %.12f", i, v,
                             vm);
            }
            geo_stitch_report_clear(&rep);
            geo_poly_free(a), geo_poly_free(b), geo_poly_free(out);
        }
        geo_poly_free(m);
    }
}

/* A five-pointed star prism cut across: the planes of its sides meet
 * inside it (not convex about the gap), so their intersection is not the
 * loops and the band of meridians joins the halves, validly and on the
 * prism's own sides. */
static void test_non_convex_pair_is_joined_by_the_band(void **s)
{
    (void)s;
    geo_poly *m = geo_poly_new();
    for (int z = 0; z < 2; z++)
        for (int k = 0; k < 10; k++) {
            double r = k % 2 ? 0.4 : 1.0, a = k * M_PI / 5;
            double x[3] = {r * cos(a), r * sin(a), z ? 1.0 : -1.0};
            geo_poly_add_vertex(m, x);
        }
    uint32_t bot[10], top[10];
    for (uint32_t k = 0; k < 10; k++)
        bot[k] = 9 - k, top[k] = 10 + k;
    geo_poly_add_facet(m, bot, 10);
    geo_poly_add_facet(m, top, 10);
    for (uint32_t k = 0; k < 10; k++) {
        uint32_t q[4] = {k, (k + 1) % 10, 10 + (k + 1) % 10, 10 + k};
        geo_poly_add_facet(m, q, 4);
    }
    geo_poly_compute_planes(m, GEO_PLANE_UNWEIGHTED);
    assert_true(tu_is_valid(m));
    double n[3] = {0, 0, 1};
    geo_poly *a, *b;
    halves(m, n, 0.1, 0.4, &a, &b);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
    assert_int_equal(rep.method, GEO_STITCH_BAND);
    assert_true(rep.band_facets > 0);
    assert_true(tu_is_valid(out));
    double hd;
    assert_int_equal(geo_hausdorff(out, m, &hd, NULL), 0);
    if (!(hd < 1e-6))
        fail_msg("Hausdorff %.3g mm", hd);
    geo_stitch_report_clear(&rep);
    geo_poly_free(a), geo_poly_free(b), geo_poly_free(out), geo_poly_free(m);
}

/* A brilliant cut in two by one plane, the lower half's rim sampled
 * twice as densely (each rim edge split, its facet cut there): the
 * loops lie on one polyline but not vertex for vertex. Each loop's
 * vertices go into the other's edges and the seam is welded: the stone
 * comes back exactly (the band of zero width was invalid). */
static void test_halves_on_one_polyline_sampled_differently_are_welded(void **s)
{
    (void)s;
    geo_err err = {{0}};
    geo_poly *m = proto_model_read_file(tu_model_path("brilliant.truth.json"),
                                        PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(m);
    double t = 6 * M_PI / 180, n[3] = {0, sin(t), cos(t)};
    geo_poly *a, *b0;
    halves(m, n, 0.3, 0, &a, &b0);
    geo_poly *b = rim_split(b0);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
    assert_int_equal(rep.method, GEO_STITCH_WELD);
    assert_int_equal(rep.nloop2, 2 * rep.nloop1);
    assert_int_equal(rep.welded, rep.nloop1);
    assert_int_equal(rep.inserted, rep.nloop1);
    assert_int_equal(rep.band_facets, 0);
    assert_true(tu_is_valid(out));
    assert_int_equal(out->nverts, a->nverts + b->nverts - rep.welded);
    double hd;
    assert_int_equal(geo_hausdorff(out, m, &hd, NULL), 0);
    if (!(hd < 1e-9))
        fail_msg("Hausdorff %.3g mm", hd);
    double v = geo_poly_volume(out), vm = geo_poly_volume(m);
    if (!(fabs(v - vm) <= 1e-9 * vm))
        fail_msg("volume %.12f, the stone's %.12f", v, vm);
    geo_stitch_report_clear(&rep);
    geo_poly_free(a), geo_poly_free(b0), geo_poly_free(b), geo_poly_free(out);
    geo_poly_free(m);
}

/* A trilliant cut 16° tilted near its culet, a tenth of its height
 * removed: the lower loop is small and sits off the upper loop's axis by
 * more than half its radius, so the loops were taken for side-by-side
 * ones (a bridge 0.5 mm off the stone); each is planar and wholly beyond
 * the other's plane, so they face across a gap and the facet planes
 * give the stone back. */
static void test_small_loop_off_axis_still_faces_across_the_gap(void **s)
{
    (void)s;
    geo_err err = {{0}};
    geo_poly *m = proto_model_read_file(design_path("trilliant.asc"),
                                        PROTO_FMT_UNKNOWN, NULL, &err);
    assert_non_null(m);
    double lo, hi, blo[3], bhi[3];
    geo_poly_bbox(m, blo, bhi);
    lo = blo[2], hi = bhi[2];
    double t = 16 * M_PI / 180, n[3] = {sin(t), 0, cos(t)};
    geo_poly *a, *b;
    halves(m, n, -(lo + 0.15 * (hi - lo)), 0.1 * (hi - lo), &a, &b);
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch(a, b, NULL, NULL, out, &rep, NULL), 0);
    assert_true(rep.band);
    assert_true(tu_is_valid(out));
    double hd;
    assert_int_equal(geo_hausdorff(out, m, &hd, NULL), 0);
    if (!(hd < 1e-6))
        fail_msg("Hausdorff %.4f mm", hd);
    assert_int_equal(rep.method, GEO_STITCH_PLANES);
    geo_stitch_report_clear(&rep);
    geo_poly_free(a), geo_poly_free(b), geo_poly_free(out), geo_poly_free(m);
}

static void test_pipeline_form_needs_exactly_two_pieces(void **s)
{
    (void)s;
    geo_poly *sp = gs_sphere(12, 1.0);
    geo_poly *top = part(sp, 2, 0.2, 9), *bot = part(sp, 2, -9, -0.2);
    /* both halves in one model */
    geo_poly *two = geo_poly_copy(top);
    for (uint32_t v = 0; v < bot->nverts; v++)
        geo_poly_add_vertex(two, bot->verts[v]);
    for (uint32_t f = 0; f < bot->nfacets; f++) {
        uint32_t q[8], k = geo_poly_facet_size(bot, f);
        for (uint32_t i = 0; i < k; i++)
            q[i] = geo_poly_facet(bot, f)[i] + top->nverts;
        int64_t nf = geo_poly_add_facet(two, q, k);
        memcpy(two->planes[nf], bot->planes[f], sizeof two->planes[0]);
    }
    geo_poly *out = geo_poly_new();
    geo_stitch_report rep;
    assert_int_equal(geo_stitch_pieces(two, NULL, NULL, out, &rep, NULL), 0);
    assert_true(tu_is_valid(out));
    geo_stitch_report_clear(&rep);
    geo_err err;
    assert_int_equal(geo_stitch_pieces(top, NULL, NULL, out, &rep, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "one piece"));
    assert_int_equal(out->nfacets, 0);
    /* a closed mesh has no free edge to stitch */
    assert_int_equal(geo_stitch(sp, bot, NULL, NULL, out, &rep, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "no free-edge loop"));
    geo_poly_free(out), geo_poly_free(two);
    geo_poly_free(top), geo_poly_free(bot), geo_poly_free(sp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_halves_of_a_sphere_become_one_valid_solid),
        cmocka_unit_test(test_second_mesh_turned_over_is_oriented_back),
        cmocka_unit_test(test_loops_of_very_different_lengths_are_bridged),
        cmocka_unit_test(test_twist_is_chosen_whatever_the_loops_start),
        cmocka_unit_test(test_side_by_side_meshes_bridge_facing_vertices),
        cmocka_unit_test(test_pipeline_form_needs_exactly_two_pieces),
        cmocka_unit_test(test_halves_whose_loops_coincide_are_welded),
        cmocka_unit_test(test_every_pair_of_coinciding_loops_is_welded),
        cmocka_unit_test(test_gem_halves_cut_unevenly_are_joined_as_a_band),
        cmocka_unit_test(test_overlapping_halves_are_trimmed_back_to_the_body),
        cmocka_unit_test(test_convex_stone_comes_back_from_its_facet_planes),
        cmocka_unit_test(test_random_convex_halves_are_valid),
        cmocka_unit_test(test_non_convex_pair_is_joined_by_the_band),
        cmocka_unit_test(test_halves_on_one_polyline_sampled_differently_are_welded),
        cmocka_unit_test(test_small_loop_off_axis_still_faces_across_the_gap),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
