/* test_robustness.c — kernels and writers given what users give them by
 * mistake: empty models, models without facets, uninitialised reports,
 * facets with very many vertices, device files as outputs. Each test is
 * a defect that once crashed, hung or lost data. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "clusters.h"
#include "correct.h"
#include "cut.h"
#include "fill.h"
#include "hausdorff.h"
#include "merge.h"
#include "model_io.h"
#include "poly.h"
#include "replanar.h"
#include "selfint.h"
#include "stats.h"

/* A model with n vertices and no facets (n = 0: the empty model). */
static geo_poly *no_facets(uint32_t n)
{
    geo_poly *p = geo_poly_new();
    assert_non_null(p);
    for (uint32_t i = 0; i < n; i++) {
        double v[3] = {i, i % 2, i % 3};
        assert_true(geo_poly_add_vertex(p, v) >= 0);
    }
    return p;
}

/* A prism over a regular n-gon of radius 1, height 1: two n-gon caps
 * and n side quads, outward. */
static geo_poly *prism(uint32_t n)
{
    geo_poly *p = geo_poly_new();
    assert_non_null(p);
    for (uint32_t z = 0; z < 2; z++)
        for (uint32_t i = 0; i < n; i++) {
            double a = 2 * M_PI * i / n;
            double v[3] = {cos(a), sin(a), z};
            assert_true(geo_poly_add_vertex(p, v) >= 0);
        }
    uint32_t *cap = malloc(n * sizeof *cap);
    assert_non_null(cap);
    for (uint32_t i = 0; i < n; i++)
        cap[i] = n - 1 - i;
    assert_true(geo_poly_add_facet(p, cap, n) >= 0);
    for (uint32_t i = 0; i < n; i++)
        cap[i] = n + i;
    assert_true(geo_poly_add_facet(p, cap, n) >= 0);
    free(cap);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t q[4] = {i, (i + 1) % n, n + (i + 1) % n, n + i};
        assert_true(geo_poly_add_facet(p, q, 4) >= 0);
    }
    geo_poly_compute_planes(p, GEO_PLANE_UNWEIGHTED);
    return p;
}

static void test_kernels_accept_models_without_facets(void **state)
{
    (void)state;
    for (uint32_t nv = 0; nv <= 5; nv += 5) {
        geo_poly *p = no_facets(nv);
        geo_err err = {{0}};
        geo_stats st;
        assert_int_equal(geo_inspect(p, NULL, NULL, &st, &err), 0);
        assert_int_equal(st.facets, 0);
        geo_stats_clear(&st);

        geo_correct_report cr = {0};
        assert_int_equal(geo_correct(p, NULL, NULL, &cr, &err), -EINVAL);
        assert_non_null(strstr(err.msg, "no facets"));
        geo_correct_report_clear(&cr);

        geo_merge_report mr = {0};
        assert_int_equal(geo_merge_auto(p, NULL, NULL, &mr, &err), 0);
        assert_int_equal(mr.merged, 0);
        geo_merge_report_clear(&mr);

        geo_poly *out = geo_poly_new();
        double plane[4] = {0, 0, 1, -0.5};
        geo_cut_report rep;
        assert_int_equal(geo_cut(p, plane, NULL, NULL, out, &rep, &err), 0);
        assert_int_equal(out->nfacets, 0);
        geo_poly_free(out);

        geo_mesh_fill_report fr = {0};
        assert_int_equal(geo_fill(p, NULL, NULL, &fr, &err), 0);
        geo_mesh_fill_report_clear(&fr);

        if (nv) {
            double to[3] = {0.5, 0.5, 0.5};
            geo_replanar_result res;
            /* a vertex in no facet: a result either way, never a crash */
            int r = geo_move(p, 0, to, GEO_REPLANAR_LOCAL_EXP, NULL,
                                    NULL, NULL, &res, &err);
            assert_true(r == 0 || r == -EINVAL);
        }
        geo_poly_free(p);
    }
}

/* Callers hand geo_collapse an uninitialised report: it once
 * freed whatever the stack held (facetd's worker crashed on every
 * collapse_clusters job whose stack was not zero). */
static void test_collapse_report_is_output_only(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    geo_collapse_report rep;
    memset(&rep, 0xA5, sizeof rep);
    geo_err err = {{0}};
    assert_int_equal(geo_collapse(p, NULL, NULL, &rep, &err), 0);
    assert_int_equal(rep.vertices_before, p->nverts);
    geo_collapse_report_clear(&rep);
    geo_poly_free(p);
}

/* Large facets take the sorted-key path of the pair search; it must find
 * exactly what the pairwise test (linear matching) finds, on a valid
 * prism and on one with a cap vertex pushed through the other cap. */
static void test_selfint_large_facets_match_pairwise(void **state)
{
    (void)state;
    for (int push = 0; push < 2; push++) {
        uint32_t n = 100;
        geo_poly *p = prism(n);
        if (push)
            p->verts[n + 7][2] = -0.5; /* top vertex below the bottom cap */
        geo_err err = {{0}};
        geo_selfint si;
        assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &si, &err), 0);
        geo_facet_shape *sh = malloc(p->nfacets * sizeof *sh);
        assert_non_null(sh);
        for (uint32_t f = 0; f < p->nfacets; f++)
            geo_facet_shape_of(p, f, &sh[f]);
        uint64_t count = 0;
        for (uint32_t f = 0; f < p->nfacets; f++) {
            count += !sh[f].degenerate && !sh[f].simple;
            for (uint32_t g = f + 1; g < p->nfacets; g++) {
                int a = geo_facets_intersect(p, f, g, &sh[f], &sh[g]);
                int b = geo_facets_intersect(p, g, f, &sh[g], &sh[f]);
                assert_int_equal(a, b); /* symmetric */
                count += a > 0;
            }
        }
        assert_int_equal(si.count, count);
        if (!push)
            assert_int_equal(si.count, 0);
        else
            assert_true(si.count > 0);
        free(sh);
        geo_selfint_clear(&si);
        geo_poly_free(p);
    }
}

/* A 20,000-gon prism: each of its 20,000 side quads meets both caps'
 * boxes. Matching and classifying the quad, not the cap, keeps this well
 * under a second (it took tens of seconds with O(|cap|) work per pair). */
static void test_selfint_large_cap_is_valid(void **state)
{
    (void)state;
    geo_poly *p = prism(20000);
    geo_err err = {{0}};
    geo_stats st;
    assert_int_equal(geo_inspect(p, NULL, NULL, &st, &err), 0);
    assert_true(st.valid);
    assert_int_equal(st.selfint.count, 0);
    geo_stats_clear(&st);
    geo_poly_free(p);
}

/* The Hausdorff estimate searches large convex facets as triangle fans:
 * a prism and its copy lifted by d are d apart. */
static void test_hausdorff_large_convex_facets(void **state)
{
    (void)state;
    geo_poly *a = prism(2000), *b = prism(2000);
    const double d = 1e-3;
    for (uint32_t v = 0; v < b->nverts; v++)
        b->verts[v][2] += d;
    geo_poly_compute_planes(b, GEO_PLANE_UNWEIGHTED);
    double h;
    geo_err err = {{0}};
    assert_int_equal(geo_hausdorff(a, b, &h, &err), 0);
    assert_true(fabs(h - d) < 1e-12);
    atomic_int cancel = 1;
    geo_ctx ctx = {.cancel = &cancel};
    assert_int_equal(geo_hausdorff_ctx(a, b, &ctx, &h, &err), -ECANCELED);
    geo_poly_free(a);
    geo_poly_free(b);
}

/* Writing to an existing device must write into it, not rename a file
 * over it (which replaced /dev/null or /dev/full with a regular file). */
static void test_write_to_device_keeps_the_device(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    geo_err err = {{0}};
    assert_int_equal(proto_model_write_file(p, "/dev/null", PROTO_FMT_JSON,
                                            &err), 0);
    struct stat st;
    assert_int_equal(stat("/dev/null", &st), 0);
    assert_true(S_ISCHR(st.st_mode));
    if (stat("/dev/full", &st) == 0 && S_ISCHR(st.st_mode)) {
        assert_int_equal(proto_model_write_file(p, "/dev/full",
                                                PROTO_FMT_JSON, &err),
                         -ENOSPC);
        assert_non_null(strstr(err.msg, "/dev/full"));
        assert_int_equal(stat("/dev/full", &st), 0);
        assert_true(S_ISCHR(st.st_mode));
    }
    assert_true(proto_model_write_file(p, "/tmp", PROTO_FMT_JSON, &err) < 0);
    geo_poly_free(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kernels_accept_models_without_facets),
        cmocka_unit_test(test_collapse_report_is_output_only),
        cmocka_unit_test(test_selfint_large_facets_match_pairwise),
        cmocka_unit_test(test_selfint_large_cap_is_valid),
        cmocka_unit_test(test_hausdorff_large_convex_facets),
        cmocka_unit_test(test_write_to_device_keeps_the_device),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
