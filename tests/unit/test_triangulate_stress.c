/* test_triangulate_stress.c — objects of the kinds a random stress test
 * of the F-rep triangulation broke on, each reduced to its smallest
 * form: a box far from the origin for its size (the samples closer than
 * the doubles there), sheets thinner than a column, empty objects. Every
 * output must be a valid closed surface, every refusal a clear error. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frep_json.h"
#include "selfint.h"
#include "tri_report_json.h"
#include "topo.h"
#include "triangulate.h"

static geo_frep *parse(const char *text)
{
    geo_err err = {{0}};
    geo_frep *f = proto_frep_read_mem(text, strlen(text), NULL, &err);
    if (!f)
        fail_msg("%s", err.msg);
    return f;
}

static int run(const geo_frep *f, uint32_t q, geo_poly **m,
               geo_tri_report *rep, geo_err *err)
{
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    o.quad_levels = q;
    o.binary_levels = q + 1;
    return geo_triangulate(f, &o, NULL, m, rep, err);
}

/* Closed, manifold, outward, no self-intersections. */
static void assert_valid(const geo_poly *m)
{
    geo_topo *t = geo_topo_build(m, NULL);
    assert_non_null(t);
    assert_true(geo_topo_is_closed_manifold(t));
    geo_topo_free(t);
    assert_true(geo_poly_volume(m) > 0);
    geo_selfint si;
    assert_int_equal(geo_selfint_find(m, NULL, NULL, NULL, &si, NULL), 0);
    assert_int_equal(si.count, 0);
    geo_selfint_clear(&si);
}

static void test_box_too_small_for_its_position_is_refused(void **state)
{
    (void)state;
    /* beyond the coordinate range of a model: refused when read (a 2 mm
     * box at 1e15 hung in refinement: its samples were closer than the
     * doubles there) */
    static const char far[] =
        "{\"format\":\"frep-object/1\","
        "\"bounds\":[[999999999999999,-1,-1],[1000000000000001,1,1]],"
        "\"shape\":{\"sphere\":{\"center\":[1e15,0,0],\"radius\":0.5}}}";
    geo_err err = {{0}};
    assert_null(proto_frep_read_mem(far, strlen(far), NULL, &err));
    assert_non_null(strstr(err.msg, "bounds: corners must lie within"));
    /* within the range, but samples closer than 2^-32 of the coordinates */
    geo_frep *f = parse(
        "{\"format\":\"frep-object/1\","
        "\"bounds\":[[499999999.999,-0.001,-0.001],"
        "[500000000.001,0.001,0.001]],"
        "\"shape\":{\"sphere\":{\"center\":[5e8,0,0],\"radius\":0.0005}}}");
    geo_poly *m = NULL;
    geo_tri_report rep = {0};
    memset(&err, 0, sizeof err);
    assert_int_equal(run(f, 6, &m, &rep, &err), -EINVAL);
    assert_null(m);
    assert_non_null(strstr(err.msg, "resolution"));
    geo_tri_report_clear(&rep);
    geo_frep_free(f);
}

/* A sphere smaller than a column: its samples fill one column (or one
 * row of columns), whose section across the row is a single column; it
 * used to come out as two coplanar quads facing opposite ways. Now such
 * a part is removed, and nothing being left it is reported as empty. */
static void test_part_one_column_thick_is_not_a_double_sheet(void **state)
{
    (void)state;
    geo_frep *f = parse(
        "{\"format\":\"frep-object/1\",\"bounds\":[[-1,-1,-1],[1,1,1]],"
        "\"shape\":{\"sphere\":{\"center\":[0.1234,-0.2345,0.3456],"
        "\"radius\":0.02}}}");
    geo_poly *m = NULL;
    geo_tri_report rep = {0};
    geo_err err = {{0}};
    assert_int_equal(run(f, 6, &m, &rep, &err), 0);
    assert_true(rep.empty);
    assert_int_equal(m->nfacets, 0);
    geo_poly_free(m);
    geo_tri_report_clear(&rep);
    geo_frep_free(f);
}

/* Two spheres whose union leaves a crack one column wide between them
 * (seen from the rays): the crack's two walls were the same quads facing
 * both ways, a double sheet inside the object. */
static void test_crack_one_column_wide_is_closed(void **state)
{
    (void)state;
    geo_frep *f = parse(
        "{\"format\":\"frep-object/1\",\"bounds\":[[-1,-1,-1],[1,1,1]],"
        "\"shape\":{\"union\":["
        "{\"sphere\":{\"center\":[0.309218779760972,0.346133627960337,"
        "-0.265214378168173],\"radius\":0.326932420295218}},"
        "{\"sphere\":{\"center\":[-0.269263872952546,0.149932280002051,"
        "-0.0396599360261204],\"radius\":0.353659375121952}},"
        "{\"sphere\":{\"center\":[0.151534361714253,0.192886824193725,"
        "0.121150751171721],\"radius\":0.140032302616095}}]}}");
    geo_poly *m = NULL;
    geo_tri_report rep = {0};
    geo_err err = {{0}};
    assert_int_equal(run(f, 5, &m, &rep, &err), 0);
    assert_valid(m);
    geo_poly_free(m);
    geo_tri_report_clear(&rep);
    geo_frep_free(f);
}

/* Empty objects (disjoint spheres intersected, a sphere minus a larger
 * one, two half-spaces facing away) are a result, not an error: the
 * empty surface with report->empty set. */
static void test_empty_objects_give_the_empty_surface(void **state)
{
    (void)state;
    static const char *const shapes[] = {
        "{\"intersection\":[{\"sphere\":{\"center\":[-0.5,0,0],"
        "\"radius\":0.3}},{\"sphere\":{\"center\":[0.5,0,0],"
        "\"radius\":0.3}}]}",
        "{\"difference\":[{\"sphere\":{\"center\":[0,0,0],\"radius\":0.3}},"
        "{\"sphere\":{\"center\":[0,0,0],\"radius\":0.5}}]}",
        "{\"intersection\":[{\"halfspace\":{\"plane\":[1,0,0,0.1]}},"
        "{\"halfspace\":{\"plane\":[-1,0,0,0.1]}}]}",
    };
    for (size_t i = 0; i < sizeof shapes / sizeof shapes[0]; i++) {
        char text[512];
        snprintf(text, sizeof text,
                 "{\"format\":\"frep-object/1\","
                 "\"bounds\":[[-1,-1,-1],[1,1,1]],\"shape\":%s}",
                 shapes[i]);
        geo_frep *f = parse(text);
        geo_poly *m = NULL;
        geo_tri_report rep = {0};
        geo_err err = {{0}};
        assert_int_equal(run(f, 5, &m, &rep, &err), 0);
        assert_true(rep.empty);
        assert_int_equal(m->nverts, 0);
        assert_int_equal(m->nfacets, 0);
        assert_int_equal(rep.self_intersections, 0);
        geo_poly_free(m);
        geo_tri_report_clear(&rep);
        geo_frep_free(f);
    }
}

/* A dent of amplitude -1e308: F drops from about 0.06 to -1e300 across
 * the dent's sphere, like a step. The crossing solver crept (regula falsi
 * barely moves against such an end) and returned the sample a voxel
 * away; Newton for new points squared a gradient of 1e303, measured 0
 * and kept points half a voxel off. Every vertex must lie on the true
 * surface: the ball of radius 0.5 outside the dent's ball. */
static void test_huge_amplitude_keeps_vertices_on_the_surface(void **state)
{
    (void)state;
    geo_frep *f = parse(
        "{\"format\":\"frep-object/1\",\"bounds\":[[-1,-1,-1],[1,1,1]],"
        "\"shape\":{\"perturbed\":{\"base\":{\"sphere\":{\"center\":[0,0,0],"
        "\"radius\":0.5}},\"perturbations\":[{\"sphere\":{\"center\":"
        "[0.3,0,0],\"radius\":0.3},\"amplitude\":-1e308}]}}}");
    geo_poly *m = NULL;
    geo_tri_report rep = {0};
    geo_err err = {{0}};
    assert_int_equal(run(f, 5, &m, &rep, &err), 0);
    assert_valid(m);
    double worst = 0;
    for (uint32_t v = 0; v < m->nverts; v++) {
        const double *p = m->verts[v];
        double rb = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        double rq = sqrt((p[0] - 0.3) * (p[0] - 0.3) + p[1] * p[1] +
                         p[2] * p[2]);
        /* on the ball's sphere outside the dent, or on the dent's sphere
         * inside the ball */
        double d = INFINITY;
        if (rq >= 0.3 - 1e-9)
            d = fabs(rb - 0.5);
        if (rb <= 0.5 + 1e-9)
            d = fmin(d, fabs(rq - 0.3));
        worst = fmax(worst, d);
    }
    assert_true(worst < 1e-9);
    geo_poly_free(m);
    geo_tri_report_clear(&rep);
    geo_frep_free(f);
}

/* A vertex where ∇F vanishes has an infinite deviation |F|/|∇F|; the
 * report must still become JSON (null there), not fail as if out of
 * memory. */
static void test_report_with_infinite_deviation_becomes_json(void **state)
{
    (void)state;
    geo_tri_report rep = {0};
    rep.quality.dev_max = INFINITY;
    rep.quality.ndev_max = NAN;
    json_t *j = proto_tri_report_to_json(&rep);
    assert_non_null(j);
    assert_true(json_is_null(json_object_get(
        json_object_get(j, "deviation"), "max")));
    assert_true(json_is_real(json_object_get(
        json_object_get(j, "deviation"), "mean")));
    json_decref(j);
}

/* A slab 0.03 thick across a voxel of 0.031 × 0.031 × 0.016, tilted:
 * its sections closed hundreds of tiny pieces on themselves (four
 * triangles of one plane facing both ways), 840 self-intersections.
 * Pieces enclosing next to nothing are dropped; what is left is valid. */
static void test_slab_thinner_than_a_voxel_leaves_no_flat_pieces(void **state)
{
    (void)state;
    geo_frep *f = parse(
        "{\"format\":\"frep-object/1\",\"bounds\":[[-1,-1,-1],[1,1,1]],"
        "\"shape\":{\"intersection\":["
        "{\"halfspace\":{\"plane\":[0.29695949077897915,0.8234829748823665,"
        "0.48341581574786835,-0.015]}},"
        "{\"halfspace\":{\"plane\":[-0.29695949077897915,"
        "-0.8234829748823665,"
        "-0.48341581574786835,-0.015]}},"
        "{\"sphere\":{\"center\":[0,0,0],\"radius\":0.7}}]}}");
    geo_poly *m = NULL;
    geo_tri_report rep = {0};
    geo_err err = {{0}};
    assert_int_equal(run(f, 6, &m, &rep, &err), 0);
    assert_false(rep.empty);
    assert_true(rep.ndropped > 0);
    assert_valid(m);
    assert_int_equal(rep.self_intersections, 0);
    geo_poly_free(m);
    geo_tri_report_clear(&rep);
    geo_frep_free(f);
}

/* The same rotated ellipsoid, given as a quadric with cross terms,
 * about the origin and moved to (47, −39, −24): far from the origin the
 * interval bounds of the cross terms cancelled badly and nothing was
 * pruned (ten times the evaluations). The far one must cost about what
 * the near one does, and both must be valid. */
static void test_quadric_far_from_origin_is_pruned_as_well(void **state)
{
    (void)state;
    static const char *const objs[2] = {
        "{\"format\":\"frep-object/1\","
        "\"bounds\":[[-1,-1,-1],[1,1,1]],\"shape\":{\"quadric\":["
        "-3.2483416195270527,-4.0874857977028505,-2.9265182617824399,"
        "1.5828353509050865,3.9204754853038932,-2.6612729419894836,"
        "0,0,0,1]}}",
        "{\"format\":\"frep-object/1\","
        "\"bounds\":[[46,-40,-25],[48,-38,-23]],\"shape\":{\"quadric\":["
        "-3.2483416195270527,-4.0874857977028505,-2.9265182617824399,"
        "1.5828353509050865,3.9204754853038932,-2.6612729419894836,"
        "303.20414031309377,-299.12574206606797,137.50549563480047,"
        "-11307.183320028422]}}",
    };
    uint64_t evals[2];
    for (int i = 0; i < 2; i++) {
        geo_frep *f = parse(objs[i]);
        geo_poly *m = NULL;
        geo_tri_report rep = {0};
        geo_err err = {{0}};
        assert_int_equal(run(f, 6, &m, &rep, &err), 0);
        assert_valid(m);
        evals[i] = rep.nevals;
        geo_poly_free(m);
        geo_tri_report_clear(&rep);
        geo_frep_free(f);
    }
    assert_true(evals[1] < 2 * evals[0]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_box_too_small_for_its_position_is_refused),
        cmocka_unit_test(test_part_one_column_thick_is_not_a_double_sheet),
        cmocka_unit_test(test_crack_one_column_wide_is_closed),
        cmocka_unit_test(test_empty_objects_give_the_empty_surface),
        cmocka_unit_test(test_huge_amplitude_keeps_vertices_on_the_surface),
        cmocka_unit_test(test_report_with_infinite_deviation_becomes_json),
        cmocka_unit_test(test_slab_thinner_than_a_voxel_leaves_no_flat_pieces),
        cmocka_unit_test(test_quadric_far_from_origin_is_pruned_as_well),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
