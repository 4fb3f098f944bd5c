/* test_report.c — the proportions of generated brilliants come back as
 * they were built (angles to 0.02°, table to 0.1 %), every facet's tier
 * is right, and a model without a table is refused unless an axis is
 * given. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "design.h"
#include "model_io.h"
#include "report.h"

static void test_generated_brilliants_come_back(void **state)
{
    (void)state;
    double worst_angle = 0, worst_table = 0;
    for (uint64_t seed = 1; seed <= 40; seed++) {
        design_brilliant b;
        design_brilliant_random(seed, &b);
        char *text = design_brilliant_asc(&b);
        assert_non_null(text);
        geo_err err = {{0}};
        geo_poly *p = proto_model_read_mem(text, strlen(text), PROTO_FMT_ASC,
                                           NULL, &err);
        free(text);
        if (!p)
            fail_msg("%s", err.msg);
        assert_int_equal(proto_model_scale_to_width(p, 6.5, &err), 0);
        geo_report r;
        if (geo_report_compute(p, NULL, 96, &r, &err) < 0)
            fail_msg("seed %llu: %s", (unsigned long long)seed, err.msg);
        worst_angle = fmax(worst_angle,
                           fabs(r.crown_angle_deg.mean - b.crown_deg));
        worst_angle = fmax(worst_angle,
                           fabs(r.pavilion_angle_deg.mean - b.pavilion_deg));
        worst_table = fmax(worst_table,
                           fabs(r.table_percent - b.table_percent));
        assert_int_equal(r.crown_mains, 8);
        assert_int_equal(r.pavilion_mains, 8);
        /* the design's tiers: table; bezels, stars, upper halves; girdle;
         * pavilion mains and lower halves; culet */
        assert_int_equal(r.tier_count[GEO_TIER_TABLE], 1);
        assert_int_equal(r.tier_count[GEO_TIER_CROWN], 8 + 8 + 16);
        assert_int_equal(r.tier_count[GEO_TIER_GIRDLE], b.girdle_facets);
        assert_int_equal(r.tier_count[GEO_TIER_PAVILION], 8 + 16);
        assert_int_equal(r.tier_count[GEO_TIER_CULET], b.culet_percent > 0);
        if (b.culet_percent > 0 && fabs(r.culet_percent - b.culet_percent) >
                                       0.02 * b.culet_percent + 1e-9)
            fail_msg("seed %llu: culet %g %%, built %g %%",
                     (unsigned long long)seed, r.culet_percent,
                     b.culet_percent);
        /* each facet's tier from the design's own tier by angle */
        for (uint32_t f = 0; f < p->nfacets; f++) {
            double nz = p->planes[f][2];
            enum geo_tier want = nz > 1 - 1e-12    ? GEO_TIER_TABLE
                                 : nz < -1 + 1e-12 ? GEO_TIER_CULET
                                 : fabs(nz) < 1e-12 ? GEO_TIER_GIRDLE
                                 : nz > 0           ? GEO_TIER_CROWN
                                                    : GEO_TIER_PAVILION;
            assert_int_equal(r.facets[f].tier, want);
        }
        assert_true(fabs(r.diameter_mm.max - 6.5) < 1e-9);
        geo_report_free(&r);
        geo_poly_free(p);
    }
    print_message("# worst crown/pavilion angle error %.3g deg, table %.3g %%\n",
                  worst_angle, worst_table);
    if (worst_angle > 0.02 || worst_table > 0.1)
        fail_msg("worst angle error %g deg, table %g %%", worst_angle,
                 worst_table);
}

static void test_no_table_needs_an_axis(void **state)
{
    (void)state;
    /* an octahedron: no facet's normal within 10° of any axis we give */
    static const char *text = "g 96 0\na 54.7356 1 0 24 48 72\n"
                              "a -54.7356 1 0 24 48 72\n";
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_mem(text, strlen(text), PROTO_FMT_ASC,
                                       NULL, &err);
    assert_non_null(p);
    geo_report r;
    assert_int_equal(geo_report_compute(p, NULL, 96, &r, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "no table"));
    const double axis[3] = {0, 0, 2};
    assert_int_equal(geo_report_compute(p, axis, 96, &r, &err), 0);
    assert_false(r.has_table);
    assert_int_equal(r.tier_count[GEO_TIER_CROWN], 4);
    assert_int_equal(r.tier_count[GEO_TIER_PAVILION], 4);
    assert_true(fabs(r.facets[1].azimuth_deg - 90) < 1e-9);
    assert_true(fabs(r.facets[1].index - 24) < 1e-9);
    geo_report_free(&r);
    geo_poly_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_generated_brilliants_come_back),
        cmocka_unit_test(test_no_table_needs_an_axis),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
