/* test_triangulate_random_gems.c — the F-rep triangulation on gems of
 * random proportions and orientations (tests/support/gen_frep.h,
 * gf_gem_random; even seeds keep the girdle parallel to the rays, odd
 * ones turn the gem anywhere) at Q_LEV 6 and 7: closed, manifold, outward
 * oriented, free of self-intersections, exact normals inside the facets,
 * true edges on the mesh away from the corners. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>

#include "gem_check.h"
#include "gen_frep.h"
#include "triangulate.h"

static void test_random_gems_are_valid(void **state)
{
    (void)state;
    /* even seeds keep the girdle parallel to the rays, odd ones turn the
     * gem anywhere */
    static const struct {
        uint64_t seed;
        uint32_t q;
    } runs[] = {{1, 6}, {2, 6}, {3, 6}, {4, 6}, {7, 7}};
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
        uint64_t seed = runs[i].seed;
        uint32_t q = runs[i].q;
        json_t *j = gf_gem_random(seed);
        geo_frep *f = gem_frep_from_json(j);
        geo_tri_report rep;
        geo_poly *m = gem_triangulate(f, q, &rep);
        char what[64];
        snprintf(what, sizeof what, "random gem %llu q%u",
                 (unsigned long long)seed, q);
        gem_assert_valid(m, &rep, what);
        double v = rep.voxel[0], d[5];
        gem_edge_distances(j, m, v, d);
        if (!(d[1] < 1e-9 * v && d[0] < 1.5 * v))
            fail_msg("%s: edges %g (median), %g (max) voxels off", what,
                     d[1] / v, d[0] / v);
        geo_tri_report_clear(&rep);
        geo_poly_free(m);
        geo_frep_free(f);
        json_decref(j);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_random_gems_are_valid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
