/* test_triangulate_gems.c — the F-rep triangulation on cut gems, objects
 * with hard edges everywhere and faces parallel to the rays (the girdle):
 * the test gem at Q_LEV 7 and the same gem built from its unrounded
 * generator values are closed, manifold, outward oriented and free of
 * self-intersections; flat facets get exact normals and the true edges
 * lie on the mesh. Random gems: test_triangulate_random_gems.c; Q_LEV 8
 * and 9 are measured by bench_triangulate (too slow for the sanitized
 * suite). */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>

#include "gem_check.h"
#include "gen_frep.h"
#include "triangulate.h"

static void test_gem_at_q7_is_valid_with_sharp_edges(void **state)
{
    (void)state;
    json_t *j = json_load_file("tests/data/frep/gem.json", 0, NULL);
    assert_non_null(j);
    geo_frep *f = gem_frep_from_json(j);
    geo_tri_report rep;
    geo_poly *m = gem_triangulate(f, 7, &rep);
    gem_assert_valid(m, &rep, "gem q7");
    /* the girdle's walls are recovered: pieces between wall ends found */
    assert_true(rep.sharpen.nmiddle_splits > 0);
    double v = rep.voxel[0], d[5];
    gem_edge_distances(j, m, v, d);
    assert_true(d[1] < 1e-9 * v); /* on the mesh for most of the length */
    assert_true(d[3] < 0.5 * v);
    assert_true(d[0] < v);
    geo_tri_report_clear(&rep);
    geo_poly_free(m);
    geo_frep_free(f);
    json_decref(j);
}

static void test_gem_from_unrounded_values_is_valid(void **state)
{
    (void)state;
    /* exact symmetry: ties between facets on the rays and at corners */
    json_t *j = gf_gem();
    geo_frep *f = gem_frep_from_json(j);
    geo_tri_report rep;
    geo_poly *m = gem_triangulate(f, 6, &rep);
    gem_assert_valid(m, &rep, "unrounded gem q6");
    geo_tri_report_clear(&rep);
    geo_poly_free(m);
    geo_frep_free(f);
    json_decref(j);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gem_at_q7_is_valid_with_sharp_edges),
        cmocka_unit_test(test_gem_from_unrounded_values_is_valid),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
