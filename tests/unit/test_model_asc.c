/* test_model_asc.c — GemCad .asc designs: the reader builds the exact
 * stone and names the line of every error; the writer turns any convex
 * model into a design that reads back within rounding; generated
 * brilliants have the facets and proportions they were built with. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "design.h"
#include "halfspace.h"
#include "vec.h"
#include "model_io.h"
#include "stone_sim.h"
#include "topo.h"

static geo_poly *read_asc(const char *text, geo_err *err)
{
    return proto_model_read_mem(text, strlen(text), PROTO_FMT_ASC, NULL, err);
}

static void assert_closed(const geo_poly *p)
{
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    assert_true(geo_topo_is_closed_manifold(t));
    geo_topo_free(t);
    assert_true(geo_poly_volume(p) > 0);
}

/* the largest distance of a's vertices from b's and back (both convex:
 * vertex-to-vertex is exact when the vertex sets correspond) */
static double vertex_gap(const geo_poly *a, const geo_poly *b)
{
    double worst = 0;
    for (int pass = 0; pass < 2; pass++) {
        const geo_poly *x = pass ? b : a, *y = pass ? a : b;
        for (uint32_t i = 0; i < x->nverts; i++) {
            double best = INFINITY;
            for (uint32_t j = 0; j < y->nverts; j++) {
                double d = 0;
                for (int k = 0; k < 3; k++)
                    d += (x->verts[i][k] - y->verts[j][k]) *
                         (x->verts[i][k] - y->verts[j][k]);
                best = fmin(best, d);
            }
            worst = fmax(worst, sqrt(best));
        }
    }
    return worst;
}

static void test_reads_an_octagonal_design(void **state)
{
    (void)state;
    const char *text =
        "\xef\xbb\xbfGemCad 5.0\r\n"
        "g96 0.0\r\n"
        "y 8 y\r\n"
        "I 2.42\r\n"
        "H Simple test\r\n"
        "; a comment\r\n"
        "a -41 0.8 96 12 24 36 48 n P1 60 72 84\r\n"
        "a 90 1.0 96 12 24 36 48\r\n"
        "60 72 84 n G\r\n"
        "G cut the girdle\r\n"
        "a 35 0.9 96 12 24 36 48 60 72 84 n C1 G crown\r\n"
        "a 0 0.5 96 n T\r\n"
        "a 0 -0.9 96 n culet\r\n"
        "F footnote\r\n";
    geo_err err = {{0}};
    geo_poly *p = read_asc(text, &err);
    if (!p)
        fail_msg("%s", err.msg);
    assert_closed(p);
    /* 8 + 8 + 8 + table + culet; four-plane girdle corners are single
     * vertices */
    assert_int_equal(p->nfacets, 26);
    assert_int_equal(p->nverts, 8 + 8 + 8 + 8);
    /* the culet: normal −z at distance 0.9 */
    assert_true(fabs(p->planes[25][2] + 1.0) < 1e-15);
    assert_true(fabs(p->planes[25][3] + 0.9) < 1e-15);
    geo_poly_free(p);
}

static void expect_error(const char *text, const char *want)
{
    geo_err err = {{0}};
    geo_poly *p = read_asc(text, &err);
    assert_null(p);
    if (strcmp(err.msg, want) != 0)
        fail_msg("got \"%s\"\nwant \"%s\"", err.msg, want);
}

static void test_errors_name_line_and_reason(void **state)
{
    (void)state;
    expect_error("GemCad 5.0\ng 0 0\na 41 1 96\n",
                 "line 2: gear 0: must be a whole number of teeth, 1..10000");
    expect_error("GemCad 5.0\ng 96 0\na 200 1 96\n",
                 "line 3: angle 200: must lie within -90..90 degrees");
    expect_error("g 96 0\na 41 1 96 24\na 41\n",
                 "line 3: tier: expected a distance after the angle");
    expect_error("g 96 0\na 41 1\na -41 1 96 24 48 72\n",
                 "line 2: tier: no index (truncated line?)");
    expect_error("g 96 0\na 41 1 96 x\n",
                 "line 2: tier: expected an index, \"n NAME\" or \"G "
                 "text\", found \"x\"");
    expect_error("g 96 0\na 41 1 96 24 48 72\n",
                 "line 2: the facets do not bound a stone: no pavilion facets "
                 "(a design in progress?) (the planes do not bound the "
                 "region: it is unbounded towards +x)");
    /* a pavilion cut, the crown not yet (as files in progress are) */
    expect_error("g 96 0\na -90 1 3 27 51 75\n n G\na -45 0.8 3 27 51 75\n",
                 "line 4: the facets do not bound a stone: no crown facets "
                 "(a design in progress?) (the planes do not bound the "
                 "region: it is unbounded towards +z)");
    expect_error("g 96 0\na 90 1 3 27 51 75\n",
                 "line 2: the facets do not bound a stone: no crown or "
                 "pavilion facets (the planes do not bound the region: it "
                 "is unbounded towards +z)");
    expect_error("g 96 0\na 45 -1 96 24 48 72\na -45 -1 96 24 48 72\n",
                 "line 3: the facets bound nothing: this facet leaves no "
                 "interior of those before it");
    expect_error("g 96 0\nz 1\n", "line 2: unknown record \"z\"");
    expect_error("GemCad 5.0\n", "line 1: no facets: a design needs \"a "
                                 "ANGLE DIST INDEX...\" tiers");
}

/* The gear as GemCad's manual has it: index OFFSET at the bottom of the
 * top view (−y), counting counter-clockwise for N > 0 and clockwise for
 * N < 0. A one-facet probe: a pyramid whose only tilted crown facet is
 * at the index asked; its normal's azimuth tells where the index lies. */
static void expect_index_direction(const char *gear, const char *idx,
                                   double want_x, double want_y)
{
    char text[256];
    snprintf(text, sizeof text, "%s\na 45 0.5 %s\na -90 1 0 24 48 72\n"
             "a 0 1 96\na -0 1 96\n", gear, idx);
    geo_err err = {{0}};
    geo_poly *p = read_asc(text, &err);
    if (!p)
        fail_msg("%s: %s", gear, err.msg);
    const double *q = p->planes[0];
    double h = hypot(q[0], q[1]);
    if (fabs(q[0] / h - want_x) > 1e-12 || fabs(q[1] / h - want_y) > 1e-12)
        fail_msg("%s index %s: azimuth (%g, %g), want (%g, %g)", gear, idx,
                 q[0] / h, q[1] / h, want_x, want_y);
    geo_poly_free(p);
}

static void test_gear_direction_and_offset(void **state)
{
    (void)state;
    expect_index_direction("g 96 0", "96", 0, -1);  /* at the bottom */
    expect_index_direction("g 96 0", "24", 1, 0);   /* counter-clockwise */
    expect_index_direction("g 96 0", "48", 0, 1);
    expect_index_direction("g -96 48.0", "96", 0, 1); /* 96 at the top */
    expect_index_direction("g -96 48.0", "-96", 0, 1);
    expect_index_direction("g -96 48.0", "24", 1, 0); /* clockwise */
    expect_index_direction("g -96 48.0", "72", -1, 0);
    expect_index_direction("g 64 0", "16", 1, 0);
    expect_index_direction("g 64 32", "0", 0, 1);
    expect_index_direction("g 96 12", "12", 0, -1);
    expect_index_direction("g -96 48", "1.5", sin(5.625 * M_PI / 180),
                           cos(5.625 * M_PI / 180));
    expect_error("g 96 97\na 41 1 96\n",
                 "line 1: gear offset 97: must be an index within -96..96");
}

static void assert_convex(const geo_poly *p)
{
    double eps = geo_poly_eps(p);
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (uint32_t v = 0; v < p->nverts; v++)
            assert_true(geo_plane_eval(p->planes[f], p->verts[v]) <= eps);
}

/* Published designs (tests/data/designs/public): closed outward convex
 * stones of the expected facets, the volume of an independent half-space
 * clipper to 1e-9, and convert → .asc → convert within 1 µm. */
static void test_public_designs(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        uint32_t listed, facets;
    } files[] = {{"public/SRB.asc", 73, 73},
                 {"public/Compear125.asc", 67, 67},
                 {"public/CubeIllusionTri.asc", 51, 51},
                 {"public/Turkey.asc", 74, 74}};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        const char *path = design_path(files[i].name);
        geo_err err = {{0}};
        proto_read_report rep;
        geo_poly *p = proto_model_read_file_ex(path, PROTO_FMT_ASC, NULL,
                                               &rep, &err);
        if (!p)
            fail_msg("%s", err.msg);
        assert_closed(p);
        assert_convex(p);
        assert_int_equal(rep.plane_mismatches, 0);
        double pl[4 * 256], angle[256];
        uint32_t n = design_file_planes(path, pl, angle, 256);
        assert_int_equal(n, files[i].listed);
        assert_int_equal(p->nfacets, files[i].facets);
        geo_poly *q = sim_halfspace_intersection(pl, n, 10.0);
        assert_non_null(q);
        double va = geo_poly_volume(p), vb = geo_poly_volume(q);
        char *buf = NULL;
        size_t len = 0;
        assert_int_equal(proto_model_write_mem(p, PROTO_FMT_ASC, &buf, &len,
                                               &err), 0);
        geo_poly *b = proto_model_read_mem(buf, len, PROTO_FMT_ASC, NULL,
                                           &err);
        if (!b)
            fail_msg("%s: round trip: %s", files[i].name, err.msg);
        assert_int_equal(b->nfacets, p->nfacets);
        double hd = sim_hausdorff(p, b, 2000);
        print_message("# %s: %u facets, volume %.12g mm3, independent "
                      "%.3g relative, round trip Hausdorff %.3g mm\n",
                      files[i].name, p->nfacets, va, fabs(va - vb) / vb, hd);
        if (fabs(va - vb) > 1e-9 * vb)
            fail_msg("%s: volume %.17g, independent %.17g", files[i].name,
                     va, vb);
        if (!(hd < 1e-3))
            fail_msg("%s: round trip Hausdorff %g mm", files[i].name, hd);
        free(buf);
        geo_poly_free(b);
        geo_poly_free(q);
        geo_poly_free(p);
    }
}

/* Any convex model → design → model: within rounding. */
static void test_round_trip_of_convex_models(void **state)
{
    (void)state;
    for (int cut = SIM_BRILLIANT; cut <= SIM_JUBILEE96; cut++) {
        geo_poly *s = sim_stone((enum sim_cut)cut, 5);
        assert_non_null(s);
        /* move it off the origin: the writer's origin header restores it */
        for (uint32_t v = 0; v < s->nverts; v++)
            s->verts[v][0] += 3.25, s->verts[v][2] -= 1.5;
        geo_poly_compute_planes(s, GEO_PLANE_UNWEIGHTED);
        char *buf = NULL;
        size_t len = 0;
        geo_err err = {{0}};
        assert_int_equal(proto_model_write_mem(s, PROTO_FMT_ASC, &buf, &len,
                                               &err), 0);
        geo_poly *b = proto_model_read_mem(buf, len, PROTO_FMT_ASC, NULL,
                                           &err);
        if (!b)
            fail_msg("cut %d: %s", cut, err.msg);
        assert_int_equal(b->nfacets, s->nfacets);
        double gap = vertex_gap(s, b);
        if (gap > 1e-9)
            fail_msg("cut %d: round trip moved a vertex by %g mm", cut, gap);
        free(buf);
        geo_poly_free(b);
        geo_poly_free(s);
    }
}

/* Generated brilliants: every tier's facets present, a closed stone,
 * and the table perimeter ratio as asked (measured here from the
 * vertices, independently of the generator's formulas). */
static void test_generated_brilliants(void **state)
{
    (void)state;
    for (uint64_t seed = 1; seed <= 12; seed++) {
        design_brilliant b;
        design_brilliant_random(seed, &b);
        char *text = design_brilliant_asc(&b);
        assert_non_null(text);
        geo_err err = {{0}};
        geo_poly *p = read_asc(text, &err);
        if (!p)
            fail_msg("seed %llu: %s", (unsigned long long)seed, err.msg);
        assert_closed(p);
        uint32_t want = 8 + 16 + b.girdle_facets + 8 + 8 + 16 + 1 +
                        (b.culet_percent > 0);
        if (p->nfacets != want)
            fail_msg("seed %llu: %u facets, want %u",
                     (unsigned long long)seed, p->nfacets, want);
        /* the table: the facet with normal +z */
        uint32_t tf = UINT32_MAX;
        for (uint32_t f = 0; f < p->nfacets; f++)
            if (p->planes[f][2] > 1 - 1e-12)
                tf = f;
        assert_true(tf != UINT32_MAX);
        double per = 0;
        uint32_t n = geo_poly_facet_size(p, tf);
        const uint32_t *ix = geo_poly_facet(p, tf);
        for (uint32_t k = 0; k < n; k++) {
            const double *a = p->verts[ix[k]], *c = p->verts[ix[(k + 1) % n]];
            per += hypot(a[0] - c[0], a[1] - c[1]);
        }
        double outline = b.girdle_facets * 2 * tan(M_PI / b.girdle_facets);
        if (fabs(100 * per / outline - b.table_percent) > 1e-9)
            fail_msg("seed %llu: table %.12g %%, want %.12g %%",
                     (unsigned long long)seed, 100 * per / outline,
                     b.table_percent);
        free(text);
        geo_poly_free(p);
    }
}

/* Every design of the collection is a valid truth for the simulator:
 * closed, as wide as asked, and its scan contains it. */
static void test_collection_designs_scan(void **state)
{
    (void)state;
    static const char *const names[] = {"round-brilliant.asc",
                                        "round-brilliant-culet-64.asc"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        geo_err err = {{0}};
        geo_poly *p = design_load(design_path(names[i]), DESIGN_WIDTH_MM,
                                  &err);
        if (!p)
            fail_msg("%s", err.msg);
        assert_closed(p);
        double w = 0;
        for (uint32_t a = 0; a < p->nverts; a++)
            for (uint32_t b = 0; b < p->nverts; b++)
                w = fmax(w, hypot(p->verts[a][0] - p->verts[b][0],
                                  p->verts[a][1] - p->verts[b][1]));
        assert_true(fabs(w - DESIGN_WIDTH_MM) < 1e-9);
        geo_poly *scan = sim_scan(p, 60, 0.001, 1);
        assert_non_null(scan);
        assert_closed(scan);
        assert_true(geo_poly_volume(scan) > 0.999 * geo_poly_volume(p));
        geo_poly_free(scan);
        geo_poly_free(p);
    }
}

static void test_width_scaling(void **state)
{
    (void)state;
    geo_poly *p = tu_box((double[3]){-1, -2, 0}, (double[3]){2, 2, 1});
    geo_err err = {{0}};
    assert_int_equal(proto_model_scale_to_width(p, 10.0, &err), 0);
    /* the box's diagonal across z was 5 */
    assert_true(fabs(p->verts[7][0] - 4.0) < 1e-12);
    assert_true(fabs(geo_poly_volume(p) - 12.0 * 8.0) < 1e-9);
    for (uint32_t f = 0; f < p->nfacets; f++) /* planes scaled too */
        for (uint32_t v = 0; v < p->nverts; v++)
            assert_true(geo_plane_eval(p->planes[f], p->verts[v]) < 1e-12);
    assert_int_equal(proto_model_scale_to_width(p, -1.0, &err), -EINVAL);
    geo_poly_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reads_an_octagonal_design),
        cmocka_unit_test(test_errors_name_line_and_reason),
        cmocka_unit_test(test_gear_direction_and_offset),
        cmocka_unit_test(test_public_designs),
        cmocka_unit_test(test_round_trip_of_convex_models),
        cmocka_unit_test(test_generated_brilliants),
        cmocka_unit_test(test_collection_designs_scan),
        cmocka_unit_test(test_width_scaling),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
