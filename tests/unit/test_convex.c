/* test_convex.c — the convex path of the correction (lib/correct/
 * convex.h): true planes recovered from a simulated scan facet by facet,
 * the result valid and convex, a non-convex model declined untouched, and
 * geo_correct taking the path when asked. Princess, brilliant, emerald
 * and one published fancy's scans at K = 100 and 400 keep it under two
 * seconds. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "classify.h"
#include "convex.h"
#include "correct.h"
#include "design.h"
#include "fidelity.h"
#include "merge.h"
#include "merge_shapes.h"
#include "model_cmp.h"
#include "stone_sim.h"
#include "tu_load.h"
#include "vec.h"

/* The scan's view count and noise as geo_correct reads them. */
static void scan_scale(const geo_poly *scan, uint32_t *views, double *noise)
{
    geo_merge_opts mo;
    geo_merge_opts_default(&mo);
    geo_err err;
    assert_int_equal(geo_merge_view_grid(scan, views, NULL), 0);
    assert_int_equal(geo_merge_surface_noise(scan, NULL, &mo, NULL, noise, &err), 0);
}

static geo_poly *convex_correct(const geo_poly *scan, enum geo_convex_fit fit,
                                geo_convex_report *rep)
{
    uint32_t views;
    double noise;
    scan_scale(scan, &views, &noise);
    geo_poly *q = NULL;
    geo_err err;
    geo_merge_opts mo;
    geo_merge_opts_default(&mo);
    int r = geo_correct_convex(scan, NULL, views, noise, geo_merge_max_deviation(&mo, scan),
                               fit, NULL, &q, rep, &err);
    if (r != 0)
        fail_msg("convex path declined: %s", r == 1 ? rep->reason : err.msg);
    return q;
}

static void assert_valid_convex(const geo_poly *p)
{
    const char *bad = ms_invalid(p);
    if (bad)
        fail_msg("result not valid: %s", bad);
    geo_conv3_result cv;
    assert_int_equal(geo_conv3(p, NULL, &cv), 0);
    assert_true(cv.convex);
}

/* Noise-free, the hinges and the silhouettes both give the stone back:
 * every facet one to one within 0.1° and 5 µm. */
static void check_noise_free(enum geo_convex_fit fit)
{
    geo_poly *stone = sim_stone(SIM_PRINCESS, 2);
    geo_poly *scan = sim_scan_phase(stone, 400, 1e-6, 0.37, 2);
    assert_non_null(scan);
    geo_convex_report rep;
    geo_poly *q = convex_correct(scan, fit, &rep);
    assert_valid_convex(q);
    sim_fidelity fd;
    assert_int_equal(sim_fidelity_measure(stone, q, 0.1, 0.005, &fd), 0);
    if (fd.recovered != fd.truth)
        fail_msg("%u of %u true facets recovered (worst %u, %.3f°)",
                 fd.recovered, fd.truth, fd.worst_facet, fd.angle_max);
    assert_int_equal(q->nfacets, stone->nfacets);
    geo_poly_free(q);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

static void test_noise_free_scan_gives_back_every_facet(void **state)
{
    (void)state;
    check_noise_free(GEO_CONVEX_FIT_HINGE);
    check_noise_free(GEO_CONVEX_FIT_SILHOUETTE);
}

static void test_noisy_scan_comes_out_valid_and_nearer_the_stone(void **state)
{
    (void)state;
    geo_poly *stone = sim_stone(SIM_BRILLIANT, 3);
    geo_poly *scan = sim_scan_phase(stone, 100, 0.001, 1.1, 3);
    assert_non_null(scan);
    geo_poly *copy = geo_poly_copy(scan);
    geo_convex_report rep;
    geo_poly *q = convex_correct(scan, GEO_CONVEX_FIT_AREA, &rep);
    assert_true(tu_poly_same(scan, copy, 0, 0, NULL, 0)); /* the input is only read */
    assert_valid_convex(q);
    double hs = sim_hausdorff(scan, stone, 2000), hq = sim_hausdorff(q, stone, 2000);
    if (hq > hs)
        fail_msg("Hausdorff to the stone %.2f µm, the scan's %.2f µm", hq * 1e3,
                 hs * 1e3);
    assert_true(rep.deviation <= rep.bound);
    geo_poly_free(q);
    geo_poly_free(copy);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

/* With a micrometre of noise the adjustment to the silhouettes gives
 * back facets the surface fit of the slivers misses: on this brilliant
 * (K = 400, 1 µm) the girdle facets' planes, each known from its two
 * surviving slivers. Measured 51 facets of 121 with the area fit, 64
 * adjusted; the test asks for ten more and a valid result no farther
 * from the stone than the scan. */
static void test_adjustment_recovers_more_than_the_area_fit(void **state)
{
    (void)state;
    geo_poly *stone = sim_stone(SIM_BRILLIANT, 2);
    geo_poly *scan = sim_scan(stone, 400, 1e-3, 2);
    assert_non_null(scan);
    geo_convex_report ra, rs;
    geo_poly *qa = convex_correct(scan, GEO_CONVEX_FIT_AREA, &ra);
    geo_poly *qs = convex_correct(scan, GEO_CONVEX_FIT_SILHOUETTE, &rs);
    /* valid; convex only to the rounding of its vertices: the adjustment
     * makes planes meet where the stone's do, so a vertex solved from
     * three of them may lie a rounding above a fourth */
    const char *bad = ms_invalid(qs);
    if (bad)
        fail_msg("result not valid: %s", bad);
    sim_fidelity fa, fs;
    assert_int_equal(sim_fidelity_measure(stone, qa, 0.1, 0.005, &fa), 0);
    assert_int_equal(sim_fidelity_measure(stone, qs, 0.1, 0.005, &fs), 0);
    if (fs.recovered < fa.recovered + 10)
        fail_msg("adjusted %u, area fit %u of %u", fs.recovered, fa.recovered,
                 fa.truth);
    double hs = sim_hausdorff(scan, stone, 2000);
    double hq = sim_hausdorff(qs, stone, 2000);
    if (hq > hs)
        fail_msg("Hausdorff to the stone %.2f µm, the scan's %.2f µm",
                 hq * 1e3, hs * 1e3);
    geo_poly_free(qa);
    geo_poly_free(qs);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

/* A 2 mm cube with one edge bevelled depth mm deep, corrected as if it
 * were a scan with 1 µm of noise: the number of facets of the result. */
static uint32_t facets_of_bevelled_cube(double depth)
{
    const double s = 1 / sqrt(2.0);
    double pl[7][4] = {{1, 0, 0, -1}, {-1, 0, 0, -1}, {0, 1, 0, -1},
                       {0, -1, 0, -1}, {0, 0, 1, -1}, {0, 0, -1, -1},
                       {s, s, 0, -(2 * s - depth)}};
    geo_poly *scan = sim_halfspace_intersection(&pl[0][0], 7, 10);
    assert_non_null(scan);
    assert_int_equal(scan->nfacets, 7);
    geo_poly *q = NULL;
    geo_convex_report rep;
    geo_err err;
    int r = geo_correct_convex(scan, NULL, 0, 1e-3, 1e-3, GEO_CONVEX_FIT_SILHOUETTE,
                               NULL, &q, &rep, &err);
    if (r != 0)
        fail_msg("declined: %s", r == 1 ? rep.reason : err.msg);
    assert_valid_convex(q);
    uint32_t n = q->nfacets;
    geo_poly_free(q);
    geo_poly_free(scan);
    return n;
}

/* A facet stays only when the scan needs it: a bevel cutting less than
 * the noise is not told from a sharp edge, one cutting forty noise
 * scales is a facet. */
static void test_a_bevel_within_the_noise_is_no_facet(void **state)
{
    (void)state;
    assert_int_equal(facets_of_bevelled_cube(0.5e-3), 6);
    assert_int_equal(facets_of_bevelled_cube(40e-3), 7);
}

static void test_non_convex_model_is_declined_untouched(void **state)
{
    (void)state;
    geo_poly *p = tu_load_model("notch-cube.json");
    assert_non_null(p);
    geo_poly *copy = geo_poly_copy(p);
    geo_poly *q = (geo_poly *)1;
    geo_convex_report rep;
    geo_err err;
    assert_int_equal(geo_correct_convex(p, NULL, 0, 0, 1e-3, GEO_CONVEX_FIT_AREA, NULL,
                                        &q, &rep, &err), 1);
    assert_null(q);
    assert_non_null(strstr(rep.reason, "not convex"));
    assert_true(tu_poly_same(p, copy, 0, 0, NULL, 0));
    geo_poly_free(copy);
    geo_poly_free(p);
}

static void test_correct_takes_the_convex_path_by_default(void **state)
{
    (void)state;
    geo_poly *stone = sim_stone(SIM_PRINCESS, 4);
    geo_poly *scan = sim_scan_phase(stone, 100, 0.001, 0.2, 4);
    geo_poly *raw = geo_poly_copy(scan);
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    assert_true(o.convex);
    geo_correct_report rep;
    geo_err err;
    assert_int_equal(geo_correct(scan, &o, NULL, &rep, &err), 0);
    if (!rep.convex)
        fail_msg("fell back to the merge: %s", rep.convex_report.reason);
    assert_true(rep.after.valid);
    assert_int_equal(rep.nmoved, 0); /* a new model: no input vertex kept */
    /* the result (in scan) is nearer the stone than the raw scan */
    double hs = sim_hausdorff(raw, stone, 2000), hq = sim_hausdorff(scan, stone, 2000);
    if (hq > hs)
        fail_msg("Hausdorff to the stone %.2f µm, the scan's %.2f µm", hq * 1e3,
                 hs * 1e3);
    geo_correct_report_clear(&rep);
    geo_poly_free(raw);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

/* An emerald (seed, K views, 1 µm) corrected by the convex path with the
 * silhouette fit: valid, convex, its report in *rep, and no farther from
 * the stone than factor × the scan. */
static void check_emerald(unsigned seed, uint32_t k, double factor,
                          geo_convex_report *rep, geo_poly **ret)
{
    geo_poly *stone = sim_stone(SIM_EMERALD, seed);
    geo_poly *scan = sim_scan(stone, k, 1e-3, seed);
    assert_non_null(scan);
    geo_poly *q = convex_correct(scan, GEO_CONVEX_FIT_SILHOUETTE, rep);
    assert_valid_convex(q);
    double hs = sim_hausdorff(scan, stone, 2000), hq = sim_hausdorff(q, stone, 2000);
    if (hq > factor * hs)
        fail_msg("Hausdorff to the stone %.2f µm, the scan's %.2f µm", hq * 1e3,
                 hs * 1e3);
    geo_poly_free(scan);
    geo_poly_free(stone);
    *ret = q;
}

/* A step cut's corner facets are narrow but true: without one, its
 * neighbours' planes meet beyond the scan. This emerald (K = 400, 1 µm)
 * had its whole correction declined for it ("the result reaches 0.032 mm
 * outside the scan"); the narrow planes now go only where the stone
 * without them stays within the scan's bound. */
static void test_a_true_narrow_facet_is_kept(void **state)
{
    (void)state;
    geo_convex_report rep;
    geo_poly *q;
    check_emerald(1, 400, 0.9, &rep, &q);
    assert_true(rep.deviation <= rep.bound);
    geo_poly_free(q);
}

/* A scan vertex near an edge lies on the slivers of either facet: how
 * far it may stand outside a result plane is that plane's allowance when
 * it is the larger. With its own group's alone, this emerald (K = 100,
 * 1 µm) was declined ("the scan lies 0.0098 mm outside the result, bound
 * 0.0085 mm") and the merge's result stayed as far from the stone as the
 * scan; the path's is at 0.61 of the scan's distance. */
static void test_a_vertex_may_stand_on_either_facets_slivers(void **state)
{
    (void)state;
    geo_convex_report rep;
    geo_poly *q;
    check_emerald(5, 100, 0.8, &rep, &q);
    geo_poly_free(q);
}

/* Where four or more adjusted planes nearly meet, the half-space kernel
 * contracts a short edge and leaves the merged vertex 1e-9 mm off a
 * plane, above the model's planarity tolerance: this emerald (K = 100,
 * 1 µm) lost its adjusted planes for that ("a vertex 4.1e-09 mm off its
 * facet's plane") and came out with the fitted ones, at 2.4 times the
 * scan's distance from the stone (8.5 µm). The intersection is now made
 * planar by the least move of its vertices, and the adjusted planes
 * stand: 4.9 µm (the scan itself is unusually near, 3.6 µm). */
static void test_adjusted_planes_survive_a_contracted_vertex(void **state)
{
    (void)state;
    geo_convex_report rep;
    geo_poly *q;
    check_emerald(3, 100, 1.5, &rep, &q);
    assert_true(rep.adjusted);
    assert_true(geo_poly_max_nonplanarity(q) <= geo_poly_eps(q));
    geo_poly_free(q);
}

/* The design NAME (tests/data/designs) scanned with k views, 1 µm of
 * noise and seed, corrected by the path: valid (not asked convex
 * exactly, see below) and within factor × the scan's Hausdorff distance
 * of the stone. *ret_stone and *ret (the caller frees both), *rep. */
static void check_design(const char *name, uint32_t k, unsigned seed,
                         double factor, geo_convex_report *rep,
                         geo_poly **ret_stone, geo_poly **ret)
{
    geo_err err;
    geo_poly *stone = design_load(design_path(name), DESIGN_WIDTH_MM, &err);
    if (!stone)
        fail_msg("%s", err.msg);
    geo_poly *scan = sim_scan(stone, k, 1e-3, seed);
    assert_non_null(scan);
    geo_poly *q = convex_correct(scan, GEO_CONVEX_FIT_SILHOUETTE, rep);
    const char *bad = ms_invalid(q);
    if (bad)
        fail_msg("result not valid: %s", bad);
    double hs = sim_hausdorff(scan, stone, 2000),
           hq = sim_hausdorff(q, stone, 2000);
    if (hq > factor * hs)
        fail_msg("Hausdorff to the stone %.2f µm, the scan's %.2f µm",
                 hq * 1e3, hs * 1e3);
    geo_poly_free(scan);
    *ret_stone = stone;
    *ret = q;
}

/* A small true facet between large ones: the rounded end of a published
 * fancy (Strickland's Turkey, public/Turkey.asc) has seven 50° pavilion
 * facets of 0.4–0.8 % of the surface each, 5° from the large 49.5° ones
 * beside them. At K = 100 the roofs of those neighbours' fitted planes
 * (20 µm) hid the seven from the support test, and the result lost them
 * all: 67 facets for 74, 13 µm from the stone where the scan is 5.4 µm.
 * Against the adjusted planes, which have no roof, each cuts deeper than
 * the noise and its own roof, and the corner it cuts off lies far outside
 * the scan: they come back. */
static void test_small_facets_between_large_ones_come_back(void **state)
{
    (void)state;
    geo_convex_report rep;
    geo_poly *stone, *q;
    check_design("public/Turkey.asc", 100, 1, 0.8, &rep, &stone, &q);
    /* convex to the model's planarity tolerance (not exactly, as
     * geo_conv3 asks: where a readmitted plane meets three others 5°
     * apart, the planarised vertex stands a few nanometres beyond a
     * neighbour's polygon) */
    for (uint32_t f = 0; f < q->nfacets; f++)
        for (uint32_t v = 0; v < q->nverts; v++)
            assert_true(geo_plane_eval(q->planes[f], q->verts[v]) <=
                        geo_poly_eps(q));
    assert_true(rep.adjusted);
    assert_true(rep.readmitted >= 7);
    /* every one of the seven has its facet again */
    uint32_t tier = 0, found = 0;
    for (uint32_t f = 0; f < stone->nfacets; f++) {
        const double *n = stone->planes[f];
        if (fabs(n[2] + cos(40.0 * M_PI / 180)) > 1e-3)
            continue;
        tier++;
        double best = 0;
        for (uint32_t g = 0; g < q->nfacets; g++)
            best = fmax(best, n[0] * q->planes[g][0] + n[1] * q->planes[g][1] +
                                  n[2] * q->planes[g][2]);
        found += best > cos(0.5 * M_PI / 180);
    }
    assert_int_equal(tier, 7);
    assert_int_equal(found, 7);
    uint32_t nt = stone->nfacets;
    if (q->nfacets < nt - nt / 20 || q->nfacets > nt + nt / 20)
        fail_msg("%u facets for %u", q->nfacets, nt);
    geo_poly_free(q);
    geo_poly_free(stone);
}

/* A culet a few tens of micrometres wide is narrower than the 20 noise
 * bounds below which a facet is taken for a bevel, and on the fitted
 * planes the stone without it stayed within the check's bound: this
 * radiant (K = 100, 1 µm) came out with its eight pavilion facets meeting
 * 16 µm below the scan, at 5.5 times the scan's distance from the stone.
 * On the adjusted planes a narrow facet goes only when the stone without
 * it stays within three noise bounds of the scan: the culet comes back. */
static void test_a_small_culet_comes_back(void **state)
{
    (void)state;
    geo_convex_report rep;
    geo_poly *stone, *q;
    check_design("radiant.asc", 100, 2, 0.8, &rep, &stone, &q);
    assert_true(rep.readmitted >= 1);
    assert_int_equal(q->nfacets, stone->nfacets);
    /* a culet some 50 µm across, scanned with 1 µm of noise, is known
     * to about a degree (its plane here: 1.1° off) */
    bool culet = false;
    for (uint32_t g = 0; g < q->nfacets; g++)
        culet |= -q->planes[g][2] > cos(3.0 * M_PI / 180);
    assert_true(culet);
    geo_poly_free(q);
    geo_poly_free(stone);
}

/* Two safety nets of the adjustment that a climbing step used to reach:
 * when the adjusted planes were declined, the fitted ones got a second
 * look at the dropped groups (heart-random-1 at K = 100, seed 4: five
 * groups back, 2.1 times the scan's distance from the stone); and a plane
 * a wrong spanning pair turned out of its slivers' cone was held at its
 * fitted place while the others were adjusted again (the same heart at
 * K = 400, seed 1: 1.28 times). Since a step that raises the residuals'
 * scale is refused (convex_refine.c) neither is reached on any design of
 * tests/data/designs at K = 100–800, 1–3 µm, seeds 1–2 (both stay in
 * convex.c for stones that still get there): these two scans are
 * adjusted, no plane turns, and the results stay within what they give
 * now (1.56 and 1.53 times). */
static void test_a_heart_once_declined_is_adjusted(void **state)
{
    (void)state;
    geo_convex_report rep;
    geo_poly *stone, *q;
    check_design("heart-random-1.asc", 100, 4, 1.7, &rep, &stone, &q);
    assert_true(rep.adjusted);
    geo_poly_free(q);
    geo_poly_free(stone);
    check_design("heart-random-1.asc", 400, 1, 1.7, &rep, &stone, &q);
    assert_true(rep.adjusted);
    assert_int_equal(rep.turned, 0);
    geo_poly_free(q);
    geo_poly_free(stone);
}

/* Scan `seed` of the fixed suite (correct_table --suite: the stone of
 * that seed turned by az, scanned with k views at the phase and noise
 * drawn for it) through the convex path: valid, within max_count of the
 * stone's facet count (a fraction) and no farther from the stone than
 * max_ratio × the scan. The report in *rep. */
static void check_suite_scan(enum sim_cut cut, unsigned seed, double az,
                             uint32_t k, double noise, double phase,
                             double max_count, double max_ratio,
                             geo_convex_report *rep)
{
    geo_poly *stone = sim_stone(cut, seed);
    sim_rotate_z(stone, az);
    geo_poly *scan = sim_scan_phase(stone, k, noise, phase, seed);
    assert_non_null(scan);
    geo_poly *q = convex_correct(scan, GEO_CONVEX_FIT_SILHOUETTE, rep);
    const char *bad = ms_invalid(q);
    if (bad)
        fail_msg("result not valid: %s", bad);
    if (fabs((double)q->nfacets - stone->nfacets) > max_count * stone->nfacets)
        fail_msg("%u facets for %u", q->nfacets, stone->nfacets);
    double hs = sim_hausdorff(scan, stone, 2000),
           hq = sim_hausdorff(q, stone, 2000);
    if (hq > max_ratio * hs)
        fail_msg("Hausdorff to the stone %.2f µm, the scan's %.2f µm",
                 hq * 1e3, hs * 1e3);
    geo_poly_free(q);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

/* Scan 1 of the fixed suite (a princess, K = 100, 0.9 µm): the adjusted
 * stone was declined, the scan lying 23 µm outside one plane the
 * adjustment had pushed in, and the fitted stone came out with 56 facets
 * for 29 (their roofs need bevels to stay within the scan). Held at its
 * fitted place, that plane and three more found the same way let their
 * neighbours settle around them: 29 facets, nearer the stone. */
static void test_a_plane_pushed_in_is_held(void **state)
{
    (void)state;
    geo_convex_report rep;
    check_suite_scan(SIM_PRINCESS, 1, 2.9076650091605174, 100,
                     0.000901919348455512, 3.0190035900558327, 0.05, 0.8,
                     &rep);
    assert_true(rep.adjusted);
}

/* Scan 29 of the fixed suite (a princess, K = 800, 2.1 µm): two long
 * slivers side by side at the girdle made a group whose least-squares
 * plane was ill-conditioned, 70° off both of them; that plane cut
 * 0.44 mm into the scan, the stone was declined and the merge took over
 * (43 facets for 29). The plane now keeps within its slivers' cone and
 * the convex path passes (32 facets), nearer the stone than the scan. */
static void test_a_thin_groups_plane_stays_within_its_slivers(void **state)
{
    (void)state;
    geo_convex_report rep;
    check_suite_scan(SIM_PRINCESS, 29, 5.962054783797807, 800,
                     0.0021494486857574287, 0.521468838428742, 0.15, 1.0,
                     &rep);
}

/* The roof over a group is a ridge: nothing where its slivers touch it
 * (its horizontal ends), step · sin a · w / 4 in the middle of a group w
 * wide, and it follows the horizontal distance only. */
static void test_the_roof_rises_from_the_groups_ends(void **state)
{
    (void)state;
    double a = 40 * M_PI / 180, span[1][4] = {{1, 0, 0, 2}};
    double n[3] = {0, -sin(a), cos(a)};
    geo_convex_planes cp = {.ngroups = 1, .step = M_PI / 100, .span = span};
    double mid[3] = {1, 0, 0}, high[3] = {1, 5, 3}, end[3] = {0.1, 0, 0},
           out[3] = {-0.5, 0, 0};
    double top = cp.step * sin(a) * 2 / 4;
    assert_float_equal(geo_convex_roof_at(&cp, 0, n, mid), top, 1e-15);
    assert_float_equal(geo_convex_roof_at(&cp, 0, n, high), top, 1e-15);
    assert_float_equal(geo_convex_roof_at(&cp, 0, n, end),
                       cp.step * sin(a) * 0.1 * 1.9 / 2, 1e-15);
    assert_float_equal(geo_convex_roof_at(&cp, 0, n, out), 0, 0);
    /* a horizontal facet has none; nor has a plane of no group */
    double table[3] = {0, 0, 1};
    assert_float_equal(geo_convex_roof_at(&cp, 0, table, mid), 0, 0);
    assert_float_equal(geo_convex_roof_at(&cp, 1, n, mid), 0, 0);
}

/* Scan 30 of the fixed suite, an emerald at K = 100 with 0.37 µm of
 * noise: its adjusted planes passed within 2 µm of the true facets'
 * centroids and were declined, "the scan lies 0.012 mm outside the
 * result (bound 0.009 mm)", at a vertex 15 µm above the girdle on a
 * crown facet 3.3 mm wide horizontally, 2.45 and 0.83 mm from its ends,
 * where the view step leaves a roof of 12.5 µm; the allowance took the
 * roof over the facet's width along its middle axis of inertia. The
 * fitted planes were given instead: 88 facets for 42, 0.73 of the scan's
 * distance from the stone. With the roof where the vertex is the
 * adjusted planes stand. */
static void test_the_roof_is_where_the_vertex_is(void **state)
{
    (void)state;
    geo_convex_report rep;
    check_suite_scan(SIM_EMERALD, 30, 5.8467406576355812, 100,
                     0.00037257473351821115, 0.65667064398418828, 0.3, 0.5,
                     &rep);
    assert_true(rep.adjusted);
}

/* The same scan through geo_correct's defaults (the convex path, the
 * groups found again at the noise its adjustment measures): the path
 * taken, the result valid, within max_count and max_ratio as above. The
 * report in *rep (the caller clears it). */
static void correct_suite_scan(enum sim_cut cut, unsigned seed, double az,
                               uint32_t k, double noise, double phase,
                               double max_count, double max_ratio,
                               geo_correct_report *rep)
{
    geo_poly *stone = sim_stone(cut, seed);
    sim_rotate_z(stone, az);
    geo_poly *scan = sim_scan_phase(stone, k, noise, phase, seed);
    assert_non_null(scan);
    geo_poly *raw = geo_poly_copy(scan);
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    geo_err err;
    assert_int_equal(geo_correct(scan, &o, NULL, rep, &err), 0);
    if (!rep->convex)
        fail_msg("fell back to the merge: %s", rep->convex_report.reason);
    assert_true(rep->after.valid);
    print_message("# %u facets for %u, noise unit %.2f um, silhouette scale "
                  "%.2f um\n", scan->nfacets, stone->nfacets, rep->noise * 1e3,
                  rep->convex_report.silhouette_scale * 1e3);
    if (fabs((double)scan->nfacets - stone->nfacets) >
        max_count * stone->nfacets)
        fail_msg("%u facets for %u", scan->nfacets, stone->nfacets);
    double hs = sim_hausdorff(raw, stone, 2000),
           hq = sim_hausdorff(scan, stone, 2000);
    if (hq > max_ratio * hs)
        fail_msg("Hausdorff to the stone %.2f µm, the scan's %.2f µm",
                 hq * 1e3, hs * 1e3);
    geo_poly_free(raw);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

/* Scan 194 of the fixed suite (an emerald, K = 400, 3.0 µm): the scan's
 * surface estimate of its noise is 0.79 µm where the adjustment measures
 * the silhouettes' residuals at 2.15 µm, and the long step facets stayed
 * in pieces: 83 facets for 43. geo_correct finds the groups again with
 * 0.6 of that scale as their noise unit: 52 facets, the stone valid and
 * no farther from the true one than the scan (0.79 of its distance). */
static void test_groups_found_again_at_the_measured_noise(void **state)
{
    (void)state;
    geo_correct_report rep;
    correct_suite_scan(SIM_EMERALD, 194, 5.7847798885694566, 400,
                       0.0029652465662865792, 0.83861817994882626, 0.35, 1,
                       &rep);
    assert_true(rep.convex_report.regrouped);
    assert_true(rep.noise > 0.001); /* the estimate: 0.79 µm */
    geo_correct_report_clear(&rep);
}

/* Scan 41 of the fixed suite (a princess, K = 800, 1.8 µm): split into
 * 99 groups at the scan's noise estimate (0.96 µm), its adjustment met a
 * step whose planes' Schur complement the rounding left indefinite (a
 * vertex where nearly parallel pieces of one facet meet) and failed:
 * the fitted stone, 76 facets for 29, and no measured noise to find the
 * groups again with. Damped harder, the step goes through: the groups
 * found again at the measured 2.4 µm, 29 facets, no farther from the
 * stone than the scan. */
static void test_an_indefinite_step_is_damped_not_failed(void **state)
{
    (void)state;
    geo_correct_report rep;
    correct_suite_scan(SIM_PRINCESS, 41, 4.5782852698511078, 800,
                       0.0018269612588868213, 2.1438905050940975, 0.05, 1,
                       &rep);
    assert_true(rep.convex_report.adjusted);
    geo_correct_report_clear(&rep);
}

/* Scan 94 of the fixed suite (an emerald, K = 100, 0.65 µm): the scan's
 * surface estimate is 0.11 µm, its groups 125 for 46 true facets, and
 * the adjusted stone is declined — but the silhouettes' residual scale
 * it measured (0.86 µm) stands, and the groups found again with it give
 * the 46 facets. */
static void test_a_declined_adjustment_still_measures_the_noise(void **state)
{
    (void)state;
    geo_correct_report rep;
    correct_suite_scan(SIM_EMERALD, 94, 4.7498218904327745, 100,
                       0.00065264179020830626, 3.026400892353164, 0.05, 0.5,
                       &rep);
    assert_true(rep.convex_report.regrouped);
    geo_correct_report_clear(&rep);
}

/* geo_convex_view_keys on a simulated scan: the facets of one key all
 * contain one view's direction, distinct keys are distinct views, and
 * the top view's facets contain z. */
static void test_view_keys_name_each_views_facets(void **state)
{
    (void)state;
    const uint32_t k = 100;
    const double phase = 0.3;
    geo_poly *stone = sim_stone(SIM_BRILLIANT, 3);
    geo_poly *scan = sim_scan_phase(stone, k, 1e-3, phase, 3);
    assert_non_null(scan);
    int64_t *key = malloc(scan->nfacets * sizeof *key);
    int64_t view_key[101];
    assert_non_null(key);
    assert_int_equal(geo_convex_view_keys(scan, key), 0);
    for (uint32_t i = 0; i <= k; i++)
        view_key[i] = INT64_MIN;
    uint32_t side = 0, top = 0;
    for (uint32_t j = 0; j < scan->nfacets; j++) {
        const double *m = scan->planes[j];
        if (key[j] < -1)
            continue; /* horizontal: no azimuth */
        /* the views whose direction the plane contains */
        uint32_t found = k + 1;
        for (uint32_t i = 0; i <= k && found > k; i++) {
            double e1[3], e2[3], d[3];
            sim_view_basis(k, phase, i, e1, e2);
            geo_vcross(e1, e2, d);
            geo_vnormalize(d);
            if (fabs(geo_vdot(m, d)) < 1e-9 && (key[j] == -1) == (i == k))
                found = i;
        }
        if (found > k)
            fail_msg("facet %u (key %lld) contains no view of its kind", j,
                     (long long)key[j]);
        if (view_key[found] == INT64_MIN)
            view_key[found] = key[j];
        if (view_key[found] != key[j])
            fail_msg("view %u: keys %lld and %lld", found,
                     (long long)view_key[found], (long long)key[j]);
        side += found < k;
        top += found == k;
    }
    for (uint32_t a = 0; a < k; a++)
        for (uint32_t b = a + 1; b < k; b++)
            if (view_key[a] != INT64_MIN && view_key[a] == view_key[b])
                fail_msg("views %u and %u share key %lld", a, b,
                         (long long)view_key[a]);
    assert_true(side > scan->nfacets / 2);
    assert_true(top > 0);
    free(key);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

/* Two facets of one view through one stone vertex are the edges at one
 * corner of its silhouette, one noisy point: the adjustment measures the
 * vertex there in both directions across the view, once (convex_refine.c,
 * corner). Princesses at K = 100 and 1.5 µm, seeds 1-6, counted facet by
 * facet (0.25°, 5 µm): 82.2 % recovered with the two planes taken as
 * independent measurements along their normals, 92.0 % with corners. */
static void test_a_silhouette_corner_is_one_measurement(void **state)
{
    (void)state;
    uint32_t truth = 0, rec = 0;
    for (unsigned seed = 1; seed <= 6; seed++) {
        geo_poly *stone = sim_stone(SIM_PRINCESS, seed);
        geo_poly *scan = sim_scan(stone, 100, 1.5e-3, seed);
        assert_non_null(scan);
        geo_correct_opts o;
        geo_correct_opts_default(&o);
        geo_correct_report rep;
        geo_err err;
        assert_int_equal(geo_correct(scan, &o, NULL, &rep, &err), 0);
        assert_true(rep.after.valid);
        sim_fidelity fd;
        assert_int_equal(
            sim_fidelity_measure(stone, scan, 0.25, 0.005, &fd), 0);
        truth += fd.truth;
        rec += fd.recovered;
        geo_correct_report_clear(&rep);
        geo_poly_free(scan);
        geo_poly_free(stone);
    }
    print_message("# recovered %u of %u\n", rec, truth);
    assert_true(rec >= 0.88 * truth);
}

/* A Gauss–Newton step that raises the silhouettes' residual scale is
 * not taken (convex_refine.c): on the heart design at K = 100 and 1 µm
 * (seed 1) wrong spanning pairs made the adjustment climb (2.1 → 3.4 µm),
 * the larger noise it reported grouped the stone coarser, and the result
 * came out 84 facets of 178 at 3.1 times the scan's distance from the
 * stone; with the step refused, 107 facets at 1.1 times. */
static void test_a_step_that_raises_the_residuals_is_refused(void **state)
{
    (void)state;
    geo_err err;
    geo_poly *stone = design_load(design_path("heart.asc"), DESIGN_WIDTH_MM,
                                  &err);
    if (!stone)
        fail_msg("%s", err.msg);
    geo_poly *scan = sim_scan(stone, 100, 1e-3, 1);
    assert_non_null(scan);
    geo_poly *raw = geo_poly_copy(scan);
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    geo_correct_report rep;
    assert_int_equal(geo_correct(scan, &o, NULL, &rep, &err), 0);
    assert_true(rep.after.valid);
    double hs = sim_hausdorff(raw, stone, 2000),
           hq = sim_hausdorff(scan, stone, 2000);
    print_message("# %u facets for %u, Hausdorff %.2f µm (the scan's %.2f), "
                  "noise %.2f µm\n", scan->nfacets, stone->nfacets, hq * 1e3,
                  hs * 1e3, rep.noise * 1e3);
    assert_true(rep.noise < 1.3e-3);
    assert_true(hq < 1.5 * hs);
    geo_correct_report_clear(&rep);
    geo_poly_free(raw);
    geo_poly_free(scan);
    geo_poly_free(stone);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_noise_free_scan_gives_back_every_facet),
        cmocka_unit_test(test_noisy_scan_comes_out_valid_and_nearer_the_stone),
        cmocka_unit_test(test_adjustment_recovers_more_than_the_area_fit),
        cmocka_unit_test(test_a_bevel_within_the_noise_is_no_facet),
        cmocka_unit_test(test_non_convex_model_is_declined_untouched),
        cmocka_unit_test(test_correct_takes_the_convex_path_by_default),
        cmocka_unit_test(test_a_true_narrow_facet_is_kept),
        cmocka_unit_test(test_a_vertex_may_stand_on_either_facets_slivers),
        cmocka_unit_test(test_adjusted_planes_survive_a_contracted_vertex),
        cmocka_unit_test(test_small_facets_between_large_ones_come_back),
        cmocka_unit_test(test_a_small_culet_comes_back),
        cmocka_unit_test(test_a_heart_once_declined_is_adjusted),
        cmocka_unit_test(test_a_plane_pushed_in_is_held),
        cmocka_unit_test(test_a_thin_groups_plane_stays_within_its_slivers),
        cmocka_unit_test(test_the_roof_rises_from_the_groups_ends),
        cmocka_unit_test(test_the_roof_is_where_the_vertex_is),
        cmocka_unit_test(test_groups_found_again_at_the_measured_noise),
        cmocka_unit_test(test_an_indefinite_step_is_damped_not_failed),
        cmocka_unit_test(test_a_declined_adjustment_still_measures_the_noise),
        cmocka_unit_test(test_view_keys_name_each_views_facets),
        cmocka_unit_test(test_a_silhouette_corner_is_one_measurement),
        cmocka_unit_test(test_a_step_that_raises_the_residuals_is_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
