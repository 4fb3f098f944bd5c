/* test_stats.c — geo_inspect's known answers on the sample models and on
 * hand-built defects (holes, non-manifold edges and vertices, degenerate
 * facets, non-planarity, short-edge clusters, near-coplanar neighbours,
 * degree histograms), independence of the thread count, and the JSON
 * keys of proto_stats_to_json. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gen_garbage.h"
#include "gen_sphere.h"
#include "model_io.h"
#include "parallel.h"
#include "stats.h"
#include "stats_json.h"
#include "vec.h"

static geo_poly *load(const char *name)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(tu_model_path(name), PROTO_FMT_UNKNOWN,
                                        NULL, &err);
    if (!p)
        fail_msg("%s: %s", name, err.msg);
    return p;
}

static geo_stats inspect(const geo_poly *p, const geo_inspect_opts *o)
{
    geo_stats s;
    geo_err err = {{0}};
    if (geo_inspect(p, o, NULL, &s, &err) != 0)
        fail_msg("inspect: %s", err.msg);
    return s;
}

static void test_valid_sample_models(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        uint32_t v, f;
    } models[] = {{"brilliant.truth.json", 238, 121},
                  {"brilliant.scan-k100.json", 2114, 1059},
                  {"brilliant.scan-k400.json", 3612, 1808},
                  {"brilliant.scan-k800.json", 4404, 2204},
                  {"notch-cube.json", 16, 10},
                  {"l-prism.json", 12, 8}};
    for (size_t i = 0; i < sizeof models / sizeof *models; i++) {
        geo_poly *p = load(models[i].name);
        geo_stats s = inspect(p, NULL);
        assert_int_equal(s.vertices, models[i].v);
        assert_int_equal(s.facets, models[i].f);
        /* Euler: a closed genus-0 surface */
        assert_int_equal((int)s.vertices - (int)s.edges + (int)s.facets, 2);
        assert_true(s.closed);
        assert_int_equal(s.holes, 0);
        assert_int_equal(s.orientation, GEO_ORIENT_OUTWARD);
        assert_int_equal(s.selfint.count, 0);
        assert_int_equal(s.degenerate_facets, 0);
        assert_int_equal(s.inverted_facets, 0);
        assert_true(s.max_nonplanarity <= s.eps);
        assert_true(s.valid);
        geo_stats_clear(&s);
        geo_poly_free(p);
    }
    geo_poly *p = load("notch-cube.json");
    geo_stats s = inspect(p, NULL);
    assert_true(fabs(s.volume - 936.0) < 1e-9);
    assert_int_equal(s.nonconvex_facets, 2); /* top and x = 10: notched */
    assert_int_equal(s.max_degree, 3);
    assert_int_equal(s.degree_count[3], 16);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

static void test_broken_sample_models(void **state)
{
    (void)state;
    geo_poly *p = load("notch-cube.flipped.json");
    geo_stats s = inspect(p, NULL);
    assert_int_equal(s.orientation, GEO_ORIENT_INCONSISTENT);
    assert_int_equal(s.inconsistent_facets, 1);
    assert_true(s.closed);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);

    p = load("brilliant.holes.json");
    s = inspect(p, NULL);
    assert_int_equal(s.holes, 2);
    assert_false(s.closed);
    assert_true(s.boundary_edges > 0);
    assert_int_equal(s.orientation, GEO_ORIENT_OUTWARD);
    assert_int_equal(s.selfint.count, 0);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);

    /* the culet pushed up through the table (facet 0): every listed pair
     * of distinct facets involves the table */
    p = load("brilliant.selfint.json");
    s = inspect(p, NULL);
    assert_true(s.selfint.count >= 3);
    assert_true(s.selfint.facet_flags[0] & GEO_SI_PAIR);
    for (uint32_t i = 0; i < s.selfint.npairs; i++)
        if (s.selfint.pairs[i][0] != s.selfint.pairs[i][1])
            assert_int_equal(s.selfint.pairs[i][0], 0);
    assert_true(s.closed);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

/* The box [0,1]×[0,2]×[0,3] with facet f rebuilt by the caller. */
static geo_poly *box123(void)
{
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 2, 3};
    return tu_box(lo, hi);
}

static void test_box_measures_and_histogram(void **state)
{
    (void)state;
    geo_poly *p = box123();
    geo_stats s = inspect(p, NULL);
    assert_int_equal(s.edges, 12);
    assert_true(fabs(s.volume - 6.0) < 1e-12);
    assert_true(fabs(s.area - 22.0) < 1e-12);
    assert_int_equal(s.max_degree, 3);
    assert_int_equal(s.degree_count[3], 8);
    for (int k = 0; k < GEO_STATS_NCOPLANAR; k++)
        assert_int_equal(s.near_coplanar[k], 0);
    assert_int_equal(s.short_edge_clusters, 0);
    assert_true(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

static void test_short_edge_clusters_follow_radius(void **state)
{
    (void)state;
    geo_poly *p = box123();
    geo_inspect_opts o;
    geo_inspect_opts_default(&o);
    o.short_edge_radius = 1.5; /* the four edges of length 1 */
    geo_stats s = inspect(p, &o);
    assert_int_equal(s.short_edge_clusters, 4);
    assert_int_equal(s.short_edge_cluster_vertices, 8);
    geo_stats_clear(&s);
    o.short_edge_radius = 2.5; /* lengths 1 and 2: each z level joins */
    s = inspect(p, &o);
    assert_int_equal(s.short_edge_clusters, 2);
    assert_int_equal(s.short_edge_cluster_vertices, 8);
    geo_stats_clear(&s);
    geo_poly_free(p);

    /* the default radius finds the scanner's heaps: many more clusters
     * on a scan than on the true stone */
    geo_poly *truth = load("brilliant.truth.json");
    geo_poly *scan = load("brilliant.scan-k400.json");
    geo_stats st = inspect(truth, NULL), ss = inspect(scan, NULL);
    assert_true(fabs(st.short_edge_radius - 1e-3 * geo_poly_size(truth)) <
                1e-15);
    assert_true(ss.short_edge_clusters > 20 * st.short_edge_clusters);
    geo_stats_clear(&st);
    geo_stats_clear(&ss);
    geo_poly_free(truth);
    geo_poly_free(scan);
}

static void test_pyramid_degrees(void **state)
{
    (void)state;
    const double v[] = {0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0, 1, 1, 1};
    const uint32_t start[] = {0, 4, 7, 10, 13, 16};
    const uint32_t idx[] = {0, 3, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    geo_poly *p = geo_poly_from_arrays(5, v, 5, start, idx, NULL, NULL);
    geo_stats s = inspect(p, NULL);
    assert_int_equal(s.max_degree, 4);
    assert_int_equal(s.degree_count[3], 4);
    assert_int_equal(s.degree_count[4], 1);
    assert_true(fabs(s.volume - 4.0 / 3.0) < 1e-12);
    assert_true(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

static void test_nonmanifold_edge_and_vertex(void **state)
{
    (void)state;
    /* a fin on the box's edge 0-1: three facets on that edge */
    geo_poly *p = box123();
    double x[3] = {0.5, -1, -1};
    uint32_t fin[3] = {1, 0, (uint32_t)geo_poly_add_vertex(p, x)};
    geo_poly_add_facet(p, fin, 3);
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    geo_stats s = inspect(p, NULL);
    assert_int_equal(s.nonmanifold_edges, 1);
    assert_int_equal(s.boundary_edges, 2);
    assert_false(s.closed);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);

    /* two tetrahedra touching at one vertex: closed, but the shared
     * vertex is non-manifold; they do not intersect */
    const double v[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1,
                        -1, 0, 0, 0, -1, 0, 0, 0, -1};
    const uint32_t start[] = {0, 3, 6, 9, 12, 15, 18, 21, 24};
    const uint32_t idx[] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3,
                            0, 4, 5, 0, 6, 4, 0, 5, 6, 4, 6, 5};
    p = geo_poly_from_arrays(7, v, 8, start, idx, NULL, NULL);
    s = inspect(p, NULL);
    assert_true(s.closed);
    assert_int_equal(s.nonmanifold_vertices, 1);
    assert_int_equal(s.shells, 2);
    assert_int_equal(s.selfint.count, 0);
    assert_int_equal(s.orientation, GEO_ORIENT_OUTWARD);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

static void test_degenerate_facet_and_nonplanarity(void **state)
{
    (void)state;
    /* split the box's edge 0-1 (facets y = 0 and z = 0) with its midpoint
     * m and close the gap with the collinear facet (1, m, 0) */
    geo_poly *b = box123();
    double m[3] = {0.5, 0, 0};
    geo_poly *p = geo_poly_new();
    for (uint32_t v = 0; v < b->nverts; v++)
        geo_poly_add_vertex(p, b->verts[v]);
    uint32_t mi = (uint32_t)geo_poly_add_vertex(p, m);
    for (uint32_t f = 0; f < b->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(b, f);
        uint32_t out[5], n = 0;
        for (uint32_t i = 0; i < 4; i++) {
            out[n++] = fv[i];
            if (fv[i] == 0 && fv[(i + 1) % 4] == 1)
                out[n++] = mi; /* the facet running 0 → 1 */
        }
        geo_poly_add_facet(p, out, n);
    }
    uint32_t deg[3] = {1, mi, 0};
    geo_poly_add_facet(p, deg, 3);
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    geo_stats s = inspect(p, NULL);
    assert_true(s.closed);
    assert_int_equal(s.degenerate_facets, 1);
    assert_int_equal(s.low_degree_vertices, 1); /* m is in 2 facets */
    /* m also lies on the edge 1 → 0 of the z = 0 facet (0), which does not
     * list it: a T-junction with the y = 0 facet (2) */
    assert_int_equal(s.selfint.count, 1);
    assert_int_equal(s.selfint.pairs[0][0], 0);
    assert_int_equal(s.selfint.pairs[0][1], 2);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);

    /* a facet whose plane was not negated with it: inverted; its
     * neighbours now disagree with it too */
    p = box123();
    uint32_t *fv = p->fidx + p->fstart[3];
    uint32_t t0 = fv[0];
    fv[0] = fv[3], fv[3] = t0, t0 = fv[1], fv[1] = fv[2], fv[2] = t0;
    s = inspect(p, NULL);
    assert_int_equal(s.inverted_facets, 1);
    assert_int_equal(s.inconsistent_facets, 1);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);

    /* one vertex off its facets' stored planes by 1e-6 */
    p = box123();
    p->verts[7][0] += 1e-6;
    s = inspect(p, NULL);
    assert_true(s.max_nonplanarity > 0.9e-6);
    assert_int_equal(s.selfint.count, 0);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);
    geo_poly_free(b);
}

static void test_near_coplanar_thresholds(void **state)
{
    (void)state;
    /* two squares sharing an edge, bent by 0.7°, 1.5° and 3° */
    const double bends[3] = {0.7, 1.5, 3.0};
    const uint32_t want[3][3] = {{0, 1, 1}, {0, 0, 1}, {0, 0, 0}};
    for (int k = 0; k < 3; k++) {
        double a = bends[k] * M_PI / 180;
        const double v[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                            1, -cos(a), sin(a), 0, -cos(a), sin(a)};
        const uint32_t start[] = {0, 4, 8};
        const uint32_t idx[] = {0, 1, 2, 3, 1, 0, 5, 4};
        geo_poly *p = geo_poly_from_arrays(6, v, 2, start, idx, NULL, NULL);
        geo_stats s = inspect(p, NULL);
        for (int t = 0; t < 3; t++)
            assert_int_equal(s.near_coplanar[t], want[k][t]);
        geo_stats_clear(&s);
        geo_poly_free(p);
    }
    /* the K=400 scan: about 400 pairs within 0.5° and 1,000 within 1°
     * (models README); counts grow with the threshold */
    geo_poly *p = load("brilliant.scan-k400.json");
    geo_stats s = inspect(p, NULL);
    assert_in_range(s.near_coplanar[0], 250, 550);
    assert_in_range(s.near_coplanar[1], 700, 1300);
    assert_true(s.near_coplanar[2] >= s.near_coplanar[1]);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

/* The angle between the two squares' unit Newell normals, in degrees,
 * as the statistics define it (atan2 of the cross and dot products). */
static double bend_angle(const geo_poly *p)
{
    double n1[3], n2[3], x[3];
    geo_poly_facet_area_vector(p, 0, n1);
    geo_poly_facet_area_vector(p, 1, n2);
    geo_vnormalize(n1);
    geo_vnormalize(n2);
    geo_vcross(n1, n2, x);
    return atan2(sqrt(geo_vdot(x, x)), geo_vdot(n1, n2)) * 180.0 / M_PI;
}

static void test_near_coplanar_counts_are_the_angles(void **state)
{
    (void)state;
    /* bends at and a hair around each threshold, and random ones; the
     * thresholds also where no tangent is sure (tiny, above 89°) */
    static const double th[][3] = {{0.5, 1.0, 2.0},
                                   {1e-7, 89.5, 120.0},
                                   {1e-6, 45.0, 89.0}};
    uint64_t rng = 5;
    for (size_t set = 0; set < sizeof th / sizeof *th; set++) {
        geo_inspect_opts o;
        geo_inspect_opts_default(&o);
        memcpy(o.coplanar_deg, th[set], sizeof o.coplanar_deg);
        for (int trial = 0; trial < 400; trial++) {
            double b;
            if (trial < 3 * 9) {
                static const double e[9] = {-1e-6, -1e-9, -1e-12, -1e-15, 0,
                                            1e-15, 1e-12, 1e-9, 1e-6};
                b = th[set][trial / 9] * (1 + e[trial % 9]);
            } else {
                b = 3.0 * geo_rand_unit(&rng);
                if (set == 1)
                    b *= 60;
            }
            double a = b * M_PI / 180;
            const double v[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0,
                                1, -cos(a), sin(a), 0, -cos(a), sin(a)};
            const uint32_t start[] = {0, 4, 8};
            const uint32_t idx[] = {0, 1, 2, 3, 1, 0, 5, 4};
            geo_poly *p = geo_poly_from_arrays(6, v, 2, start, idx, NULL,
                                               NULL);
            assert_non_null(p);
            double ang = bend_angle(p);
            geo_stats s = inspect(p, &o);
            for (int k = 0; k < 3; k++)
                assert_int_equal(s.near_coplanar[k], ang < th[set][k]);
            geo_stats_clear(&s);
            geo_poly_free(p);
        }
    }
}

static void test_inspection_independent_of_thread_count(void **state)
{
    (void)state;
    geo_poly *p = gs_sphere(12, 1.0);
    geo_vscale(p->verts[5], -1.4, p->verts[5]);
    par_pool *pool = par_pool_new(2);
    geo_ctx ctx = {0};
    ctx.parallel_for = par_for;
    ctx.pf_user = pool;
    geo_stats a = inspect(p, NULL), b;
    assert_int_equal(geo_inspect(p, NULL, &ctx, &b, NULL), 0);
    json_t *ja = proto_stats_to_json(&a), *jb = proto_stats_to_json(&b);
    assert_true(a.selfint.count > 0);
    assert_true(json_equal(ja, jb));
    json_decref(ja);
    json_decref(jb);
    geo_stats_clear(&a);
    geo_stats_clear(&b);
    par_pool_free(pool);
    geo_poly_free(p);
}

static void test_empty_and_vertex_only_models(void **state)
{
    (void)state;
    geo_poly *p = geo_poly_new();
    geo_stats s = inspect(p, NULL);
    assert_int_equal(s.facets, 0);
    assert_int_equal(s.selfint.count, 0);
    assert_int_equal(s.orientation, GEO_ORIENT_OUTWARD);
    assert_true(s.valid); /* the empty polyhedron: nothing is wrong */
    json_t *j = proto_stats_to_json(&s);
    assert_non_null(j);
    json_decref(j);
    geo_stats_clear(&s);
    const double x[3] = {1, 2, 3};
    geo_poly_add_vertex(p, x);
    s = inspect(p, NULL);
    assert_int_equal(s.low_degree_vertices, 1);
    assert_int_equal(s.degree_count[0], 1);
    assert_false(s.valid);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

static void test_random_garbage_models_never_fail(void **state)
{
    (void)state;
    /* facets of random indices over a few vertices: non-manifold edges,
     * repeated indices, coincident and collinear points everywhere */
    uint64_t rng = 77;
    for (int trial = 0; trial < 60; trial++) {
        geo_poly *p = gen_garbage_model(&rng);
        assert_non_null(p);
        geo_stats s;
        assert_int_equal(geo_inspect(p, NULL, NULL, &s, NULL), 0);
        json_t *j = proto_stats_to_json(&s);
        assert_non_null(j);
        json_decref(j);
        geo_stats_clear(&s);
        geo_orient_report rep;
        int rc = geo_orient_repair(p, &rep, NULL);
        assert_true(rc == 0 || rc == -EINVAL);
        geo_poly_free(p);
    }
}

static int record_progress(void *user, double fraction)
{
    double *last = user;
    assert_true(fraction >= *last); /* monotonic */
    assert_true(fraction <= 1.0);
    *last = fraction;
    return fraction > 0.5; /* then ask to stop */
}

static void test_progress_is_monotonic_and_cancel_stops(void **state)
{
    (void)state;
    geo_poly *p = gs_sphere(16, 1.0);
    double last = 0;
    geo_ctx ctx = {0};
    ctx.progress = record_progress;
    ctx.user = &last;
    geo_stats s;
    geo_err err = {{0}};
    assert_int_equal(geo_inspect(p, NULL, &ctx, &s, &err), -ECANCELED);
    assert_true(last > 0.5);
    assert_null(s.degree_count);
    assert_null(s.selfint.pairs);
    geo_poly_free(p);
}

static void test_json_has_every_key(void **state)
{
    (void)state;
    geo_poly *p = load("brilliant.selfint.json");
    geo_inspect_opts o;
    geo_inspect_opts_default(&o);
    o.selfint.max_pairs = 2;
    geo_stats s = inspect(p, &o);
    json_t *j = proto_stats_to_json(&s);
    assert_non_null(j);
    static const char *keys[] = {
        "vertices", "edges", "facets", "closed", "boundary_edges", "holes",
        "nonmanifold_edges", "nonmanifold_vertices", "orientation",
        "inconsistent_facets", "volume", "area", "max_nonplanarity",
        "nonconvex_facets", "degenerate_facets", "self_intersections",
        "self_intersecting_facets", "near_coplanar_pairs", "vertex_degrees",
        "short_edge_clusters", "valid"};
    for (size_t i = 0; i < sizeof keys / sizeof *keys; i++)
        if (!json_object_get(j, keys[i]))
            fail_msg("missing key %s", keys[i]);
    json_t *si = json_object_get(j, "self_intersections");
    assert_int_equal(json_integer_value(json_object_get(si, "count")),
                     s.selfint.count);
    assert_int_equal(json_array_size(json_object_get(si, "pairs")), 2);
    json_t *cop = json_object_get(j, "near_coplanar_pairs");
    assert_non_null(json_object_get(cop, "0.5"));
    assert_non_null(json_object_get(cop, "1"));
    assert_non_null(json_object_get(cop, "2"));
    assert_int_equal(json_integer_value(json_object_get(
                         json_object_get(j, "vertex_degrees"), "3")),
                     238);
    assert_string_equal(json_string_value(json_object_get(j, "orientation")),
                        "outward");
    assert_true(json_is_false(json_object_get(j, "valid")));
    json_decref(j);
    geo_stats_clear(&s);
    geo_poly_free(p);
}

/* geo_inspect_topology gives geo_inspect's counts, topology and
 * orientation (and nothing else) on closed, inverted and open models. */
static void test_topology_only_matches_inspect(void **state)
{
    (void)state;
    static const char *const names[] = {
        "notch-cube.json", "notch-cube.flipped.json", "brilliant.holes.json",
        "brilliant.scan-k100.json", "l-prism.json"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        geo_poly *p = load(names[i]);
        geo_stats full = inspect(p, NULL), top;
        geo_err err = {{0}};
        assert_int_equal(geo_inspect_topology(p, NULL, &top, &err), 0);
        assert_int_equal(top.vertices, full.vertices);
        assert_int_equal(top.facets, full.facets);
        assert_int_equal(top.edges, full.edges);
        assert_int_equal(top.boundary_edges, full.boundary_edges);
        assert_int_equal(top.nonmanifold_edges, full.nonmanifold_edges);
        assert_int_equal(top.nonmanifold_vertices, full.nonmanifold_vertices);
        assert_int_equal(top.closed, full.closed);
        assert_int_equal(top.orientation, full.orientation);
        assert_int_equal(top.inconsistent_facets, full.inconsistent_facets);
        assert_int_equal(top.shells, full.shells);
        assert_int_equal(top.orientable, full.orientable);
        /* the rest is not computed */
        assert_int_equal(top.selfint.count, 0);
        assert_false(top.valid);
        geo_stats_clear(&top);
        geo_stats_clear(&full);
        geo_poly_free(p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_valid_sample_models),
        cmocka_unit_test(test_broken_sample_models),
        cmocka_unit_test(test_topology_only_matches_inspect),
        cmocka_unit_test(test_box_measures_and_histogram),
        cmocka_unit_test(test_short_edge_clusters_follow_radius),
        cmocka_unit_test(test_pyramid_degrees),
        cmocka_unit_test(test_nonmanifold_edge_and_vertex),
        cmocka_unit_test(test_degenerate_facet_and_nonplanarity),
        cmocka_unit_test(test_near_coplanar_thresholds),
        cmocka_unit_test(test_near_coplanar_counts_are_the_angles),
        cmocka_unit_test(test_inspection_independent_of_thread_count),
        cmocka_unit_test(test_empty_and_vertex_only_models),
        cmocka_unit_test(test_random_garbage_models_never_fail),
        cmocka_unit_test(test_progress_is_monotonic_and_cancel_stops),
        cmocka_unit_test(test_json_has_every_key),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
