/* test_cut_holes.c — plane cuts of non-convex solids whose section has
 * holes (lib/cut/cut.h with lib/cut/region_split.h): a ring cut along its plane,
 * a block with two and three holes, an island in a hole, a cavity's cross
 * section, the notch cube's inner corner clipped, a hole touching the
 * outer boundary at a vertex, a torus along its plane; the pinches that
 * no valid polyhedron can represent are refused with a message naming the
 * way out, and moving the plane that way works; the §3.4 variant keeps
 * its one-facet rule; random
 * planes, and planes through vertices, on non-convex models: every result
 * valid by geo_inspect, halves adding up, no refusal but true pinches. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cut.h"
#include "cut_check.h"
#include "cut_shapes.h"
#include "hole_shapes.h"
#include "vec.h"

static void assert_close(double x, double y, double rel)
{
    if (!(fabs(x - y) <= rel * (1.0 + fabs(y))))
        fail_msg("%.17g != %.17g", x, y);
}

/* Cuts p by the plane and its opposite; both must succeed with valid
 * results adding up to p. Returns the plane side's report. */
static geo_cut_report both_ok(const geo_poly *p, double a, double b, double c,
                              double d, geo_cut_report *opposite)
{
    const double pl[4] = {a, b, c, d};
    cc_halves h;
    const char *bad = cc_cut_both(p, pl, &h);
    if (bad)
        fail_msg("plane (%g,%g,%g,%g): %s", a, b, c, d, bad);
    for (int s = 0; s < 2; s++)
        if (h.code[s] != 0)
            fail_msg("plane (%g,%g,%g,%g) side %d: %d %s", a, b, c, d, s,
                     h.code[s], h.err[s].msg);
    if (opposite)
        *opposite = h.rep[1];
    return h.rep[0];
}

/* The result of one cut, asserted valid. */
static geo_poly *cut_valid(const geo_poly *p, double a, double b, double c,
                           double d, geo_cut_report *rep)
{
    const double pl[4] = {a, b, c, d};
    geo_poly *out = geo_poly_new();
    geo_err err = {{0}};
    int r = geo_cut(p, pl, NULL, NULL, out, rep, &err);
    if (r != 0)
        fail_msg("geo_cut(%g,%g,%g,%g) = %d: %s", a, b, c, d, r, err.msg);
    const char *bad = cc_result_problem(p, out);
    if (bad)
        fail_msg("cut (%g,%g,%g,%g): %s", a, b, c, d, bad);
    return out;
}

static bool has_vertex_at(const geo_poly *p, const double x[3])
{
    for (uint32_t v = 0; v < p->nverts; v++)
        if (geo_vdist(p->verts[v], x) == 0)
            return true;
    return false;
}

/* ---- sections with holes -------------------------------------------- */

static void test_ring_cut_along_its_plane_gives_an_annulus_of_facets(void **state)
{
    (void)state;
    geo_poly *p = cs_frame();
    geo_cut_report rep, opp;
    rep = both_ok(p, 0, 0, 1, -2, &opp);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    assert_int_equal(opp.components, 1);
    assert_true(opp.new_facets >= 2);
    geo_poly *o = cut_valid(p, 0, 0, 1, -2, &rep);
    assert_close(geo_poly_volume(o), 168.0, 1e-12);
    /* the new facets lie in z = 2, face +z and cover the annulus */
    double area = 0;
    for (uint32_t f = rep.first_new_facet; f < o->nfacets; f++) {
        const uint32_t *vs = geo_poly_facet(o, f);
        for (uint32_t j = 0; j < geo_poly_facet_size(o, f); j++)
            assert_true(o->verts[vs[j]][2] == 2.0);
        assert_close(o->planes[f][2], 1.0, 1e-15);
        area += geo_poly_facet_area(o, f);
    }
    assert_close(area, 100.0 - 16.0, 1e-12);
    print_message("# ring cut along its plane: %u facets for the annulus\n",
                  rep.new_facets);
    geo_poly_free(o);
    /* tilted through the ring: still one annulus */
    rep = both_ok(p, 0.1, -0.05, 1, -2, NULL);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    geo_poly_free(p);
    /* a triangulated torus along its plane: an annulus of crossings */
    p = hs_torus(48, 24, 2, 1);
    rep = both_ok(p, 0, 0, 1, -0.01, NULL);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    geo_poly_free(p);
}

static void test_block_with_two_and_three_holes(void **state)
{
    (void)state;
    static const char *const two[] = {"#######",
                                      "#.###.#",
                                      "#######"};
    static const char *const three[] = {"##########",
                                        "#.##.###.#",
                                        "##########",
                                        "##########"};
    struct {
        const char *const *rows;
        uint32_t nrows, cells, holes;
    } blocks[] = {{two, 3, 19, 2}, {three, 4, 37, 3}};
    for (size_t i = 0; i < 2; i++) {
        geo_poly *p = hs_grid_prism(blocks[i].rows, blocks[i].nrows, 2);
        assert_non_null(p);
        assert_null(cc_inspect_problem(p));
        assert_close(geo_poly_volume(p), 2.0 * blocks[i].cells, 1e-12);
        geo_cut_report rep = both_ok(p, 0, 0, 1, -1, NULL);
        assert_int_equal(rep.components, 1);
        assert_true(rep.new_facets >= 2);
        geo_poly *o = cut_valid(p, 0, 0, 1, -1, &rep);
        assert_close(geo_poly_volume(o), blocks[i].cells, 1e-12);
        print_message("# block with %u holes: %u facets for the section\n",
                      blocks[i].holes, rep.new_facets);
        geo_poly_free(o);
        /* tilted, and across a corner: the holes stay holes */
        rep = both_ok(p, 0.02, 0.03, 1, -1, NULL);
        assert_int_equal(rep.components, 1);
        assert_true(rep.new_facets >= 2);
        geo_poly_free(p);
    }
}

static void test_island_in_a_hole_is_a_component_of_its_own(void **state)
{
    (void)state;
    static const char *const map[] = {"#######",
                                      "#.....#",
                                      "#.....#",
                                      "#..#..#",
                                      "#.....#",
                                      "#.....#",
                                      "#######"};
    geo_poly *p = hs_grid_prism(map, 7, 3);
    assert_non_null(p);
    assert_null(cc_inspect_problem(p));
    geo_cut_report opp;
    geo_cut_report rep = both_ok(p, 0, 0, 1, -1.5, &opp);
    assert_int_equal(rep.components, 2);
    assert_int_equal(opp.components, 2);
    /* the pillar's section is one square, the ring's at least two facets */
    assert_true(rep.new_facets >= 3);
    geo_poly *o = cut_valid(p, 0, 0, 1, -1.5, &rep);
    assert_close(geo_poly_volume(o), 25.0 * 1.5, 1e-12);
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_cavity_cross_section_is_a_hole(void **state)
{
    (void)state;
    const double lo[3] = {0, 0, 0}, hi[3] = {10, 10, 10};
    const double ilo[3] = {3, 3, 3}, ihi[3] = {7, 7, 7};
    geo_poly *p = hs_hollow_box(lo, hi, ilo, ihi);
    assert_null(cc_inspect_problem(p));
    assert_close(geo_poly_volume(p), 1000.0 - 64.0, 1e-12);
    geo_cut_report rep = both_ok(p, 0, 0, 1, -5, NULL);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    geo_poly *o = cut_valid(p, 0, 0, 1, -5, &rep);
    assert_close(geo_poly_volume(o), 500.0 - 32.0, 1e-12);
    geo_poly_free(o);
    /* obliquely through the cavity */
    rep = both_ok(p, 0.3, -0.2, 1, -5.1, NULL);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    /* the plane through the cavity's floor, keeping below: the floor lies
     * in the plane facing along it and ends inside the new facet, which
     * then has no hole; keeping above, the floor bounds the kept part */
    rep = both_ok(p, 0, 0, 1, -3, NULL);
    assert_int_equal(rep.components, 1);
    assert_int_equal(rep.new_facets, 1);
    geo_poly_free(p);
}

static void test_notch_cube_inner_corner_clipped(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    /* x + z = c for 12 < c < 16 meets the notch only near its inner
     * corner edge x = z = 6: the section is a rectangle with a hole */
    for (double c = 12.5; c < 16; c += 1.0) {
        geo_cut_report rep = both_ok(p, 1, 0, 1, -c, NULL);
        assert_int_equal(rep.components, 1);
        assert_true(rep.new_facets >= 2);
    }
    /* tilted a little around every axis */
    geo_cut_report rep = both_ok(p, 1, 0.05, 0.9, -12.7, NULL);
    assert_true(rep.new_facets >= 2);
    geo_poly_free(p);
}

static void test_hole_touching_outer_boundary_at_a_vertex(void **state)
{
    (void)state;
    geo_poly *p = hs_saddle_ring();
    assert_null(cc_inspect_problem(p));
    /* below: the annulus touching itself at the saddle, split so that no
     * facet passes the saddle twice */
    geo_cut_report rep;
    geo_poly *o = cut_valid(p, 0, 0, 1, -2, &rep);
    assert_int_equal(rep.components, 1);
    assert_true(rep.new_facets >= 2);
    const double s[3] = {5, 1.5, 2};
    assert_true(has_vertex_at(o, s));
    uint32_t at_s = 0;
    for (uint32_t f = rep.first_new_facet; f < o->nfacets; f++) {
        const uint32_t *vs = geo_poly_facet(o, f);
        for (uint32_t j = 0; j < geo_poly_facet_size(o, f); j++)
            at_s += geo_vdist(o->verts[vs[j]], s) == 0;
    }
    assert_int_equal(at_s, 2);
    geo_poly_free(o);
    /* above: the two humps meet only at the saddle; no valid polyhedron */
    double pl[4] = {0, 0, -1, 2};
    o = geo_poly_new();
    geo_err err = {{0}};
    assert_int_equal(geo_cut(p, pl, NULL, NULL, o, &rep, &err), -ENOTSUP);
    assert_non_null(strstr(err.msg, "touch itself"));
    geo_poly_free(o);
    geo_poly_free(p);
}

static void test_straight_runs_of_the_section_stay_straight(void **state)
{
    (void)state;
    /* The plate's holes are unit cells: the plane meets the walls x = 7 of
     * two holes in points of one line, each rounded a hair off it. A
     * diagonal from one hole's corner to the other's along that line would
     * graze the corner between them (found as a contact by the
     * inspection); the split keeps every diagonal clear of the points by
     * more than their rounding bounds. */
    static const char *const plate[] = {"#########", "#.##.##.#", "#########",
                                        "##.###.##", "#########"};
    geo_poly *p = hs_grid_prism(plate, 5, 2);
    geo_cut_report rep = both_ok(p, 0.74198471331035853, -0.039341021863811054,
                                 -0.54685690047647206, -4.8433004635939971, NULL);
    assert_true(rep.new_facets >= 2);
    geo_poly_free(p);
}

/* ---- pinches: refused, with the way out that works ------------------- */

/* A prism over a polygon with a notch rising from the bottom edge to a
 * reflex vertex at (5, 5). */
static geo_poly *notch_prism(void)
{
    static const double xy[7][2] = {{0, 0}, {4, 0}, {5, 5}, {6, 0},
                                    {10, 0}, {10, 8}, {0, 8}};
    return cs_prism(xy, 7, 0, 2);
}

static geo_poly *l_prism(void)
{
    static const double xy[6][2] = {{0, 0}, {10, 0}, {10, 4},
                                    {4, 4}, {4, 10}, {0, 10}};
    return cs_prism(xy, 6, 0, 6);
}

/* Block [−1,1]² × [−1, ·] with a saddle top around (0, 0, 0). */
static geo_poly *saddle_block(void)
{
    double v[9][3] = {{0, 0, 0}};
    static const double cx[4] = {1, -1, -1, 1}, cy[4] = {1, 1, -1, -1};
    for (int i = 0; i < 4; i++) {
        v[1 + i][0] = v[5 + i][0] = cx[i];
        v[1 + i][1] = v[5 + i][1] = cy[i];
        v[1 + i][2] = i % 2 ? -0.5 : 0.5;
        v[5 + i][2] = -1;
    }
    uint32_t idx[32], start[10], c = 0, f = 0;
    for (uint32_t i = 0; i < 4; i++) {
        uint32_t j = (i + 1) % 4;
        start[f++] = c;
        idx[c++] = 0, idx[c++] = 1 + i, idx[c++] = 1 + j;
        start[f++] = c;
        idx[c++] = 5 + i, idx[c++] = 5 + j, idx[c++] = 1 + j, idx[c++] = 1 + i;
    }
    start[f++] = c;
    for (uint32_t i = 4; i-- > 0;)
        idx[c++] = 5 + i;
    start[f] = c;
    return geo_poly_from_arrays(9, &v[0][0], f, start, idx, NULL, NULL);
}

static void test_pinches_are_refused_and_moving_the_plane_works(void **state)
{
    (void)state;
    struct {
        geo_poly *p;
        double plane[4];
        const char *why;
    } cases[] = {
        {notch_prism(), {0, 1, 0, -5}, "reflex edge"},
        {l_prism(), {-1, -1, 0, 8}, "reflex edge"},
        {cs_dented_box(4), {0, 0, 1, -4}, "cavity"},
        {saddle_block(), {0, 0, -1, 0}, "touch itself"},
        {hs_saddle_ring(), {0, 0, -1, 2}, "touch itself"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        geo_poly *p = cases[i].p;
        assert_non_null(p);
        geo_poly *o = geo_poly_new();
        geo_cut_report rep;
        geo_err err = {{0}};
        assert_int_equal(geo_cut(p, cases[i].plane, NULL, NULL, o, &rep, &err),
                         -ENOTSUP);
        assert_int_equal(o->nfacets, 0);
        if (!strstr(err.msg, cases[i].why) || !strstr(err.msg, "no valid") ||
            !strstr(err.msg, "plane[3]"))
            fail_msg("case %zu: %s", i, err.msg);
        geo_poly_free(o);
        /* the message's way out: plane[3] a little larger or smaller */
        double delta = 1e-6 * geo_poly_size(p) * geo_vlen(cases[i].plane);
        for (int s = -1; s <= 1; s += 2) {
            double q[4];
            memcpy(q, cases[i].plane, sizeof q);
            q[3] += s * delta;
            cc_halves h;
            const char *bad = cc_cut_both(p, q, &h);
            if (bad || h.code[0] || h.code[1])
                fail_msg("case %zu moved by %+g: %s / %s / %s", i, s * delta,
                         bad ? bad : "ok", h.err[0].msg, h.err[1].msg);
        }
        geo_poly_free(p);
    }
}

static void test_main_facet_variant_refuses_a_section_with_a_hole(void **state)
{
    (void)state;
    geo_poly *p = cs_frame();
    /* a top trapezoid of the ring as the main facet, the plane just
     * below the top: one component, but with a hole */
    uint32_t top = GEO_NONE;
    for (uint32_t f = 0; f < p->nfacets && top == GEO_NONE; f++)
        if (p->planes[f][2] > 0.5)
            top = f;
    assert_int_not_equal(top, GEO_NONE);
    geo_cut_opts opts;
    geo_cut_opts_default(&opts);
    opts.main_facet = top;
    double pl[4] = {0, 0, 1, -3.5};
    geo_poly *o = geo_poly_new();
    geo_cut_report rep;
    geo_err err = {{0}};
    assert_int_equal(geo_cut(p, pl, &opts, NULL, o, &rep, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "hole"));
    assert_non_null(strstr(err.msg, "exactly one"));
    assert_int_equal(o->nfacets, 0);
    /* without the variant the same plane is an ordinary cut */
    geo_poly_free(o);
    o = cut_valid(p, 0, 0, 1, -3.5, &rep);
    assert_true(rep.new_facets >= 2);
    geo_poly_free(o);
    geo_poly_free(p);
}

/* ---- random planes ---------------------------------------------------- */

static const char *const u_map[] = {"#..#", "#..#", "####"};
static const char *const plate_map[] = {"#########", "#.##.##.#", "#########",
                                        "##.###.##", "#########"};
static const char *const pillar_map[] = {"#####", "#...#", "#.#.#", "#...#",
                                         "#####"};

typedef struct model {
    const char *name;
    geo_poly *p;
    bool integral; /* vertex coordinates are multiples of 1/2 */
} model;

static uint32_t make_models(model *m)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {10, 10, 10};
    const double ilo[3] = {3, 4, 2}, ihi[3] = {7, 6, 8};
    uint32_t n = 0;
    m[n++] = (model){"notch cube", tu_notch_cube(), true};
    m[n++] = (model){"L prism", l_prism(), true};
    m[n++] = (model){"U prism", hs_grid_prism(u_map, 3, 2), true};
    m[n++] = (model){"star prism", cs_star_prism(7, 1.0, 2.5, 1.5), false};
    m[n++] = (model){"hollow box", hs_hollow_box(lo, hi, ilo, ihi), true};
    m[n++] = (model){"ring", cs_frame(), true};
    m[n++] = (model){"plate with 5 holes", hs_grid_prism(plate_map, 5, 2), true};
    m[n++] = (model){"ring with a pillar", hs_grid_prism(pillar_map, 5, 3), true};
    m[n++] = (model){"saddle ring", hs_saddle_ring(), true};
    m[n++] = (model){"dented box", cs_dented_box(4), true};
    m[n++] = (model){"bumpy sphere", cs_sphere(24, 32, 0.25), false};
    m[n++] = (model){"torus", hs_torus(24, 12, 2, 1), false};
    for (uint32_t i = 0; i < n; i++) {
        assert_non_null(m[i].p);
        const char *bad = cc_inspect_problem(m[i].p);
        if (bad)
            fail_msg("%s: %s", m[i].name, bad);
    }
    return n;
}

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

static void test_random_planes_refuse_nothing(void **state)
{
    (void)state;
    model m[16];
    uint32_t nm = make_models(m);
    uint64_t seed = 2024;
    enum { PLANES = 150 };
    for (uint32_t i = 0; i < nm; i++) {
        uint32_t holed = 0, refused = 0, pieces = 0;
        for (int t = 0; t < PLANES; t++) {
            double pl[4];
            random_plane_in_box(m[i].p, &seed, pl);
            cc_halves h;
            const char *bad = cc_cut_both(m[i].p, pl, &h);
            if (bad)
                fail_msg("%s, plane (%.17g,%.17g,%.17g,%.17g): %s", m[i].name,
                         pl[0], pl[1], pl[2], pl[3], bad);
            if (h.code[0] || h.code[1]) {
                refused++;
                print_message("# %s refused: %s / %s\n", m[i].name,
                              h.err[0].msg, h.err[1].msg);
                continue;
            }
            assert_int_equal(h.rep[0].components, h.rep[1].components);
            if (h.rep[0].new_facets > h.rep[0].components) {
                holed++;
                pieces += h.rep[0].new_facets;
            }
        }
        print_message("# %-18s %d random planes: %u refused, %u with a holed "
                      "section (%u facets for them)\n", m[i].name, PLANES,
                      refused, holed, pieces);
        assert_int_equal(refused, 0);
        /* the models with holes in most sections really exercise them */
        if (strstr(m[i].name, "notch") || strstr(m[i].name, "ring") ||
            strstr(m[i].name, "plate") || strstr(m[i].name, "hollow") ||
            strstr(m[i].name, "torus"))
            assert_true(holed >= 5);
        geo_poly_free(m[i].p);
    }
}

static int64_t rand_int(uint64_t *seed, int lo, int hi)
{
    return lo + (int64_t)(geo_rand_unit(seed) * (hi - lo + 1));
}

/* A plane through one, two or three random vertices of p, with integer
 * normal components, so that it passes through them exactly (p's
 * coordinates are multiples of 1/2). False when degenerate. */
static bool plane_through_vertices(const geo_poly *p, uint64_t *seed,
                                   double ret[4])
{
    int through = (int)rand_int(seed, 1, 3);
    const double *v[3];
    for (int k = 0; k < 3; k++)
        v[k] = p->verts[rand_int(seed, 0, (int)p->nverts - 1) % p->nverts];
    double n[3], r[3], a[3], b[3];
    for (int k = 0; k < 3; k++)
        r[k] = (double)rand_int(seed, -2, 2);
    geo_vsub(v[1], v[0], a);
    geo_vsub(v[2], v[0], b);
    if (through == 1)
        memcpy(n, r, sizeof n);
    else if (through == 2)
        geo_vcross(a, r, n);
    else
        geo_vcross(a, b, n);
    /* doubled so that n·v is an integer for half-integer coordinates */
    for (int k = 0; k < 3; k++)
        ret[k] = 2 * n[k];
    if (ret[0] == 0 && ret[1] == 0 && ret[2] == 0)
        return false;
    ret[3] = -geo_vdot(ret, v[0]);
    return true;
}

static void test_planes_through_vertices_refuse_only_pinches(void **state)
{
    (void)state;
    model m[16];
    uint32_t nm = make_models(m);
    uint64_t seed = 99;
    enum { PLANES = 200 };
    uint32_t total = 0, pinches = 0, kinds[3] = {0, 0, 0};
    static const char *const kind_words[3] = {"reflex edge", "cavity",
                                              "touch itself"};
    for (uint32_t i = 0; i < nm; i++) {
        uint32_t tried = 0, refused = 0;
        for (int t = 0; t < PLANES && m[i].integral; t++) {
            double pl[4];
            if (!plane_through_vertices(m[i].p, &seed, pl))
                continue;
            tried++;
            cc_halves h;
            const char *bad = cc_cut_both(m[i].p, pl, &h);
            if (bad)
                fail_msg("%s, plane (%g,%g,%g,%g): %s", m[i].name, pl[0], pl[1],
                         pl[2], pl[3], bad);
            bool any = false;
            for (int s = 0; s < 2; s++) {
                if (h.code[s] == 0)
                    continue;
                any = true;
                const char *msg = h.err[s].msg;
                if (h.code[s] != -ENOTSUP || !strstr(msg, "no valid") ||
                    !strstr(msg, "plane[3]"))
                    fail_msg("%s, plane (%g,%g,%g,%g) side %d: %d %s", m[i].name,
                             pl[0], pl[1], pl[2], pl[3], s, h.code[s], msg);
                for (int w = 0; w < 3; w++)
                    kinds[w] += strstr(msg, kind_words[w]) != NULL;
            }
            if (!any)
                continue;
            refused++;
            /* a true pinch: the plane moved either way cuts validly */
            double delta = 1e-6 * geo_poly_size(m[i].p) * geo_vlen(pl);
            for (int s = -1; s <= 1; s += 2) {
                double q[4];
                memcpy(q, pl, sizeof q);
                q[3] += s * delta;
                bad = cc_cut_both(m[i].p, q, &h);
                if (bad || h.code[0] || h.code[1])
                    fail_msg("%s, plane (%g,%g,%g,%g) moved by %+g: %s / %s / %s",
                             m[i].name, pl[0], pl[1], pl[2], pl[3], s * delta,
                             bad ? bad : "ok", h.err[0].msg, h.err[1].msg);
            }
        }
        if (tried)
            print_message("# %-18s %u planes through vertices: %u refused as "
                          "pinches\n", m[i].name, tried, refused);
        total += tried;
        pinches += refused;
        geo_poly_free(m[i].p);
    }
    print_message("# all: %u planes through vertices, %u refused as pinches "
                  "(sides: %u along a reflex edge, %u at a cavity apex, %u at a "
                  "vertex with two fans)\n", total, pinches, kinds[0], kinds[1],
                  kinds[2]);
    assert_true(total > 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ring_cut_along_its_plane_gives_an_annulus_of_facets),
        cmocka_unit_test(test_block_with_two_and_three_holes),
        cmocka_unit_test(test_island_in_a_hole_is_a_component_of_its_own),
        cmocka_unit_test(test_cavity_cross_section_is_a_hole),
        cmocka_unit_test(test_notch_cube_inner_corner_clipped),
        cmocka_unit_test(test_hole_touching_outer_boundary_at_a_vertex),
        cmocka_unit_test(test_straight_runs_of_the_section_stay_straight),
        cmocka_unit_test(test_pinches_are_refused_and_moving_the_plane_works),
        cmocka_unit_test(test_main_facet_variant_refuses_a_section_with_a_hole),
        cmocka_unit_test(test_random_planes_refuse_nothing),
        cmocka_unit_test(test_planes_through_vertices_refuse_only_pinches),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
