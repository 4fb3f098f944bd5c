/* test_designs.c — designs of every shape (tests/support/design.h) as
 * truths: each builds with every listed facet present, reads back from
 * its .asc as a closed convex stone of those facets in that order, with
 * the volume of an independent clipper; the report finds its table, gives
 * every facet the design's tier, and finds the design's mains at their
 * angles (within 0.02°). */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "design.h"
#include "model_io.h"
#include "report.h"
#include "stone_sim.h"
#include "topo.h"
#include "vec.h"

typedef struct mains {
    uint32_t n;
    double min, max, mean;
} mains;

static mains design_mains(const design_cut *d, int tier)
{
    mains m = {0, INFINITY, -INFINITY, 0};
    for (uint32_t i = 0; i < d->n; i++)
        if (d->f[i].main && d->f[i].tier == tier) {
            double a = fabs(d->f[i].angle_deg);
            m.n++, m.min = fmin(m.min, a), m.max = fmax(m.max, a),
            m.mean += a;
        }
    if (m.n)
        m.mean /= m.n;
    return m;
}

static int failures;

static void check_mains(const char *what, const mains *want, uint32_t n,
                        const geo_range *got)
{
    if (n != want->n) {
        print_error("%s: %u mains, the design has %u\n", what, n, want->n);
        failures++;
    } else if (n && (fabs(got->mean - want->mean) > 0.02 ||
                     fabs(got->min - want->min) > 0.02 ||
                     fabs(got->max - want->max) > 0.02)) {
        print_error("%s: mains %g..%g mean %g, the design's %g..%g mean "
                    "%g\n", what, got->min, got->max, got->mean, want->min,
                    want->max, want->mean);
        failures++;
    }
}

/* One design end to end; returns its facet count. */
static uint32_t check_design(const design_fancy *fd, const char *name)
{
    design_cut d;
    if (design_fancy_build(fd, &d) < 0)
        fail_msg("%s: does not build", name);
    char *text = design_asc(&d);
    assert_non_null(text);
    geo_err err = {{0}};
    proto_read_report rep;
    geo_poly *p = proto_model_read_mem_ex(text, strlen(text), PROTO_FMT_ASC,
                                          NULL, &rep, &err);
    free(text);
    if (!p)
        fail_msg("%s: %s", name, err.msg);
    assert_int_equal(rep.plane_mismatches, 0);
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    assert_true(geo_topo_is_closed_manifold(t));
    geo_topo_free(t);
    if (p->nfacets != d.n)
        fail_msg("%s: %u facets read, the design lists %u", name, p->nfacets,
                 d.n);
    double eps = geo_poly_eps(p);
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (uint32_t v = 0; v < p->nverts; v++)
            assert_true(geo_plane_eval(p->planes[f], p->verts[v]) <= eps);
    double *pl = design_planes(&d);
    assert_non_null(pl);
    geo_poly *q = sim_halfspace_intersection(pl, d.n, 10.0);
    assert_non_null(q);
    double va = geo_poly_volume(p), vb = geo_poly_volume(q);
    if (!(fabs(va - vb) <= 1e-9 * vb))
        fail_msg("%s: volume %.17g, independent %.17g", name, va, vb);
    geo_poly_free(q);
    free(pl);
    geo_report r;
    if (geo_report_compute(p, NULL, 96, &r, &err) < 0)
        fail_msg("%s: %s", name, err.msg);
    for (uint32_t f = 0; f < d.n; f++)
        if ((int)r.facets[f].tier != d.f[f].tier)
            fail_msg("%s: facet %u (angle %g, azimuth %g) reported %s, the "
                     "design's %s", name, f, d.f[f].angle_deg,
                     d.f[f].azimuth_deg, geo_tier_name(r.facets[f].tier),
                     geo_tier_name((enum geo_tier)d.f[f].tier));
    mains cm = design_mains(&d, GEO_TIER_CROWN);
    mains pm = design_mains(&d, GEO_TIER_PAVILION);
    char what[96];
    snprintf(what, sizeof what, "%s crown", name);
    check_mains(what, &cm, r.crown_mains, &r.crown_angle_deg);
    snprintf(what, sizeof what, "%s pavilion", name);
    check_mains(what, &pm, r.pavilion_mains, &r.pavilion_angle_deg);
    uint32_t n = d.n;
    print_message("# %-28s %3u facets (%u left out), L/W %.3f, crown %u "
                  "mains %.2f..%.2f, pavilion %u mains %.2f..%.2f\n", name,
                  n, d.dropped, r.length_to_width, cm.n, cm.n ? cm.min : 0,
                  cm.n ? cm.max : 0, pm.n, pm.n ? pm.min : 0,
                  pm.n ? pm.max : 0);
    geo_report_free(&r);
    geo_poly_free(p);
    design_free(&d);
    return n;
}

static void test_every_shape_and_variants(void **state)
{
    (void)state;
    for (int s = 0; s < DESIGN_NSHAPES; s++) {
        design_fancy fd;
        char name[64];
        design_fancy_default((enum design_shape)s, &fd);
        snprintf(name, sizeof name, "%s", design_shape_name(s));
        check_design(&fd, name);
        for (uint64_t seed = 1; seed <= 6; seed++) {
            design_fancy_random((enum design_shape)s, seed, &fd);
            snprintf(name, sizeof name, "%s-random-%llu",
                     design_shape_name(s), (unsigned long long)seed);
            check_design(&fd, name);
        }
    }
    if (failures)
        fail_msg("%d designs' mains differ from the report's", failures);
}

/* The files of the collection are the generator's designs. */
static void test_collection_files(void **state)
{
    (void)state;
    for (int s = 0; s < DESIGN_NSHAPES; s++) {
        char name[64];
        snprintf(name, sizeof name, "%s.asc", design_shape_name(s));
        geo_err err = {{0}};
        geo_poly *p = design_load(design_path(name), DESIGN_WIDTH_MM, &err);
        if (!p)
            fail_msg("%s", err.msg);
        design_fancy fd;
        design_cut d;
        design_fancy_default((enum design_shape)s, &fd);
        assert_int_equal(design_fancy_build(&fd, &d), 0);
        assert_int_equal(p->nfacets, d.n);
        geo_report r;
        assert_int_equal(geo_report_compute(p, NULL, 96, &r, &err), 0);
        assert_int_equal(r.crown_mains, design_mains(&d, GEO_TIER_CROWN).n);
        assert_int_equal(r.pavilion_mains,
                         design_mains(&d, GEO_TIER_PAVILION).n);
        geo_report_free(&r);
        design_free(&d);
        geo_poly_free(p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_shape_and_variants),
        cmocka_unit_test(test_collection_files),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
