/* test_triangulate.c — the F-rep triangulation end to end on the test
 * objects (tests/data/frep/) at low levels: every output is a closed,
 * manifold, outward oriented surface of the right genus without
 * self-intersections, its vertices lie on F = 0, its volume approaches
 * the true one, the gem keeps its edges sharp, the result does not depend
 * on the thread count, and cancellation and bad bounds are reported. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "frep_json.h"
#include "gen_frep.h"
#include "parallel.h"
#include "selfint.h"
#include "topo.h"
#include "triangulate.h"

static geo_frep *load(const char *name)
{
    char path[512];
    snprintf(path, sizeof path, "tests/data/frep/%s.json", name);
    geo_err err = {{0}};
    geo_frep *f = proto_frep_read_file(path, NULL, &err);
    if (!f)
        fail_msg("%s", err.msg);
    return f;
}

static geo_poly *run(const geo_frep *f, uint32_t q, uint32_t b,
                     const geo_ctx *ctx, geo_tri_report *rep)
{
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    o.quad_levels = q;
    o.binary_levels = b;
    geo_poly *m = NULL;
    geo_err err = {{0}};
    int rc = geo_triangulate(f, &o, ctx, &m, rep, &err);
    if (rc != 0)
        fail_msg("triangulate: %d %s", rc, err.msg);
    return m;
}

/* Closed, manifold, consistently outward, no self-intersections, the
 * given Euler characteristic; the report agrees. */
static void assert_valid(const geo_poly *m, const geo_tri_report *rep,
                         int64_t euler)
{
    geo_topo *t = geo_topo_build(m, NULL);
    assert_non_null(t);
    assert_true(geo_topo_is_closed_manifold(t));
    geo_topo_free(t);
    assert_true(geo_poly_volume(m) > 0);
    for (uint32_t f = 0; f < m->nfacets; f++)
        assert_int_equal(geo_poly_facet_size(m, f), 3);
    geo_selfint si;
    assert_int_equal(geo_selfint_find(m, NULL, NULL, NULL, &si, NULL), 0);
    assert_int_equal(si.count, 0);
    geo_selfint_clear(&si);
    const geo_frep_metrics *q = &rep->quality;
    assert_int_equal(q->boundary_edges, 0);
    assert_int_equal(q->nonmanifold_edges, 0);
    assert_int_equal(q->nonmanifold_vertices, 0);
    assert_int_equal(q->euler, euler);
    assert_int_equal(rep->self_intersections, 0);
    assert_int_equal(rep->fill.nopen, 0);
    assert_int_equal(q->nfacets, m->nfacets);
}

static void test_smooth_objects_give_valid_surfaces_on_f_zero(void **state)
{
    (void)state;
    struct {
        const char *name;
        int64_t euler;
        double volume; /* 0: not known in closed form */
    } objs[] = {
        {"sphere", 2, 4.0 / 3.0 * M_PI * 0.216},
        {"ellipsoid", 2, 4.0 / 3.0 * M_PI * 0.8 * 0.55 * 0.4},
        {"blob83", 2, 0},
        {"torus", 0, 0},
    };
    for (size_t i = 0; i < sizeof objs / sizeof objs[0]; i++) {
        geo_frep *f = load(objs[i].name);
        geo_tri_report rep;
        geo_poly *m = run(f, 6, 7, NULL, &rep);
        assert_valid(m, &rep, objs[i].euler);
        /* every vertex on the surface, far below the voxel size */
        assert_true(rep.quality.dev_max < 1e-9 * rep.voxel[0]);
        if (objs[i].volume > 0)
            assert_true(fabs(rep.quality.volume - objs[i].volume) <
                        0.01 * objs[i].volume);
        assert_true(rep.quality.ndev_mean < 3.0);
        assert_true(rep.t_total > 0);
        geo_tri_report_clear(&rep);
        geo_poly_free(m);
        geo_frep_free(f);
    }
}

static void test_finer_levels_approach_the_sphere(void **state)
{
    (void)state;
    geo_frep *f = load("sphere");
    double want = 4.0 / 3.0 * M_PI * 0.216, err_prev = INFINITY;
    for (uint32_t q = 5; q <= 7; q++) {
        geo_tri_report rep;
        geo_poly *m = run(f, q, q + 1, NULL, &rep);
        double e = fabs(rep.quality.volume - want);
        assert_true(e < err_prev);
        err_prev = e;
        geo_tri_report_clear(&rep);
        geo_poly_free(m);
    }
    assert_true(err_prev < 0.003 * want);
    geo_frep_free(f);
}

static void test_silhouette_walls_become_fair_triangles(void **state)
{
    (void)state;
    /* where the sphere turns parallel to the rays, the walls between the
     * last points of the columns are long slivers unless refinement can
     * flip them into the triangles beside them (22° normal error before) */
    geo_frep *f = load("sphere");
    geo_tri_report rep;
    geo_poly *m = run(f, 8, 9, NULL, &rep);
    assert_valid(m, &rep, 2);
    if (!(rep.quality.ndev_max < 2.0))
        fail_msg("normal deviation %g°", rep.quality.ndev_max);
    geo_tri_report_clear(&rep);
    geo_poly_free(m);
    geo_frep_free(f);
}

static void test_gem_edges_stay_sharp(void **state)
{
    (void)state;
    json_t *j = gf_gem();
    double *planes, *segs;
    int np = gf_halfspaces(j, &planes);
    int ns = gf_polytope_edges((const double(*)[4])planes, np, &segs);
    json_decref(j);
    geo_frep *f = load("gem");
    geo_tri_report rep;
    geo_poly *m = run(f, 6, 7, NULL, &rep);
    assert_valid(m, &rep, 2);
    assert_true(rep.sharpen.nedge_splits > 0);
    /* away from the edges the facets are flat: normals exact */
    assert_true(rep.quality.nsmooth > m->nverts / 3);
    assert_true(rep.quality.sdev_max < 1.0);
    /* away from the corners the true edges lie on the mesh for most of
     * their length (a chamfer would put the median near a quarter voxel);
     * nowhere are they cut deeper than a voxel */
    double v = rep.voxel[0], d[5];
    gf_edge_distances(m, segs, ns, 0.25 * v, 1.5 * v, d);
    assert_true(d[1] < 1e-9 * v);
    assert_true(d[0] < v);
    free(planes), free(segs);
    geo_tri_report_clear(&rep);
    geo_poly_free(m);
    geo_frep_free(f);
}

static void test_union_crease_is_recovered(void **state)
{
    (void)state;
    geo_frep *f = load("two-spheres");
    geo_tri_report rep;
    geo_poly *m = run(f, 6, 7, NULL, &rep);
    assert_valid(m, &rep, 2);
    assert_true(rep.sharpen.nedge_splits + rep.sharpen.nsnaps > 10);
    /* points on the crease circle lie on both spheres */
    uint32_t on_crease = 0;
    for (uint32_t v = 0; v < m->nverts; v++) {
        uint32_t pc[4];
        on_crease += geo_frep_pieces_at(f, m->verts[v], 1e-9, pc, 4) == 2;
    }
    assert_true(on_crease > 20);
    geo_tri_report_clear(&rep);
    geo_poly_free(m);
    geo_frep_free(f);
}

static void test_result_does_not_depend_on_threads(void **state)
{
    (void)state;
    geo_frep *f = load("blob83");
    geo_tri_report r1, r2;
    geo_poly *m1 = run(f, 6, 7, NULL, &r1);
    par_pool *pool = par_pool_new(3);
    assert_non_null(pool);
    geo_ctx ctx = {.parallel_for = par_for, .pf_user = pool};
    geo_poly *m2 = run(f, 6, 7, &ctx, &r2);
    assert_int_equal(m1->nverts, m2->nverts);
    assert_int_equal(m1->nfacets, m2->nfacets);
    assert_memory_equal(m1->verts, m2->verts, m1->nverts * sizeof m1->verts[0]);
    assert_memory_equal(m1->fidx, m2->fidx,
                        geo_poly_ncorners(m1) * sizeof m1->fidx[0]);
    par_pool_free(pool);
    geo_tri_report_clear(&r1);
    geo_tri_report_clear(&r2);
    geo_poly_free(m1);
    geo_poly_free(m2);
    geo_frep_free(f);
}

static int cancel_at_half(void *user, double fraction)
{
    int *calls = user;
    (*calls)++;
    return fraction > 0.5;
}

static void test_cancel_and_bad_bounds_are_reported(void **state)
{
    (void)state;
    geo_frep *f = load("ellipsoid");
    int calls = 0;
    geo_ctx ctx = {.progress = cancel_at_half, .user = &calls};
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    o.quad_levels = 6;
    o.binary_levels = 7;
    geo_poly *m = NULL;
    geo_err err = {{0}};
    assert_int_equal(geo_triangulate(f, &o, &ctx, &m, NULL, &err),
                     -ECANCELED);
    assert_null(m);
    assert_true(calls > 3);
    geo_frep_free(f);

    const char *tight = "{\"format\":\"frep-object/1\","
                        "\"bounds\":[[-0.5,-0.5,-0.5],[0.5,0.5,0.5]],"
                        "\"shape\":{\"sphere\":{\"center\":[0,0,0],"
                        "\"radius\":0.7}}}";
    f = proto_frep_read_mem(tight, strlen(tight), NULL, &err);
    assert_non_null(f);
    assert_int_equal(geo_triangulate(f, &o, NULL, &m, NULL, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "reaches the boundary"));
    o.quad_levels = 0;
    assert_int_equal(geo_triangulate(f, &o, NULL, &m, NULL, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "quad levels"));
    geo_frep_free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_smooth_objects_give_valid_surfaces_on_f_zero),
        cmocka_unit_test(test_finer_levels_approach_the_sphere),
        cmocka_unit_test(test_silhouette_walls_become_fair_triangles),
        cmocka_unit_test(test_gem_edges_stay_sharp),
        cmocka_unit_test(test_union_crease_is_recovered),
        cmocka_unit_test(test_result_does_not_depend_on_threads),
        cmocka_unit_test(test_cancel_and_bad_bounds_are_reported),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
