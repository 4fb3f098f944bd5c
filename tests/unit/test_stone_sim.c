/* test_stone_sim.c — the scanner simulator produces what the tests of the
 * correction rely on: valid convex stones, and scans that are valid,
 * contain the stone, and split its facets into many near-coplanar ones. */
#include "testutil.h"

#include <math.h>

#include "stone_sim.h"
#include "topo.h"
#include "vec.h"

static void assert_closed_convex(const geo_poly *p)
{
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    assert_true(geo_topo_is_closed_manifold(t));
    geo_topo_free(t);
    assert_true(geo_poly_volume(p) > 0);
    /* convex: every vertex on the inner side of every facet plane */
    double eps = 1e-9;
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (uint32_t v = 0; v < p->nverts; v++)
            assert_true(geo_plane_eval(p->planes[f], p->verts[v]) < eps);
}

static void test_stones_are_valid_convex(void **state)
{
    (void)state;
    for (int cut = SIM_BRILLIANT; cut <= SIM_EMERALD; cut++)
        for (uint64_t seed = 1; seed <= 3; seed++) {
            geo_poly *s = sim_stone((enum sim_cut)cut, seed);
            assert_non_null(s);
            assert_closed_convex(s);
            assert_true(s->nfacets >= 20);
            geo_poly_free(s);
        }
}

static void test_scan_contains_stone_and_splits_facets(void **state)
{
    (void)state;
    geo_poly *s = sim_stone(SIM_BRILLIANT, 1);
    geo_poly *scan = sim_scan(s, 100, 0.001, 1);
    assert_non_null(scan);
    assert_closed_convex(scan);
    /* the scan is a superset of the stone (up to the noise) */
    assert_true(geo_poly_volume(scan) > geo_poly_volume(s) * 0.999);
    assert_true(scan->nfacets > 3 * s->nfacets);
    double h = sim_hausdorff(scan, s, 2000);
    assert_true(h > 0 && h < 0.1);
    geo_poly_free(scan);
    geo_poly_free(s);
}

static void test_hausdorff_of_shifted_box(void **state)
{
    (void)state;
    geo_poly *a = tu_box((double[3]){0, 0, 0}, (double[3]){1, 1, 1});
    geo_poly *b = tu_box((double[3]){0, 0, 0}, (double[3]){1, 1, 1.25});
    assert_true(fabs(sim_hausdorff(a, b, 500) - 0.25) < 1e-12);
    assert_true(fabs(sim_hausdorff_directed(a, b, 500) - 0.25) < 1e-12);
    geo_poly_free(a);
    geo_poly_free(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stones_are_valid_convex),
        cmocka_unit_test(test_scan_contains_stone_and_splits_facets),
        cmocka_unit_test(test_hausdorff_of_shifted_box),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
