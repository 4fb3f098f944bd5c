/* test_classify.c — the point-vs-plane forms of
 * "Tests of graphic elements", agree with each other
 * and with exact integer arithmetic, cross3 tells crossing / touching /
 * missing exactly, conv3 and the facet convexity test find convex and
 * non-convex models and polygons. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "classify.h"
#include "gen_convex.h"
#include "model_io.h"
#include "predicates.h"

__extension__ typedef __int128 i128;

static int sign128(i128 v) { return (v > 0) - (v < 0); }

/* The closed plane z = 1 in every form, with normal +z. */
static void plane_forms(double z, geo_plane_spec ret[3])
{
    ret[0] = (geo_plane_spec){.form = GEO_PLANE_IMPLICIT,
                              .coef = {0, 0, 1, -z}};
    ret[1] = (geo_plane_spec){.form = GEO_PLANE_POINT_NORMAL,
                              .point = {0.25, 0.75, z}, .normal = {0, 0, 2}};
    ret[2] = (geo_plane_spec){.form = GEO_PLANE_THREE_POINTS,
                              .pts = {{0, 0, z}, {1, 0, z}, {0, 1, z}}};
}

static void test_four_forms_agree_on_signs_and_paper_values(void **state)
{
    (void)state;
    /* the plane 2x − y + 3z − 4 = 0, in each form */
    double coef[4] = {2, -1, 3, -4};
    double p0[3] = {2, 0, 0}, n[3] = {2, -1, 3};
    double a[3] = {2, 0, 0}, b[3] = {0, 2, 2}, c[3] = {0, -4, 0};
    /* the right-hand normal of a, b, c must be +n for the signs to agree */
    double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    double ac[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double cr[3] = {ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2],
                    ab[0] * ac[1] - ab[1] * ac[0]};
    assert_true(cr[0] * n[0] + cr[1] * n[1] + cr[2] * n[2] > 0);
    uint64_t rng = 7;
    for (int i = 0; i < 2000; i++) {
        double q[3];
        for (int k = 0; k < 3; k++)
            q[k] = (double)(int)(geo_rand_next(&rng) % 21) - 10;
        i128 exact = 2 * (i128)q[0] - (i128)q[1] + 3 * (i128)q[2] - 4;
        int s = sign128(exact);
        assert_int_equal(geo_nf_implicit_sign(coef, q), s);
        assert_int_equal(geo_nf_normal_sign(p0, n, q), s);
        assert_int_equal(geo_nf3_sign(a, b, c, q), s);
        /* values: nfF and nfN equal the expression; nf3 is it scaled by
         * |(b − a) × (c − b)| / |n| */
        assert_true(geo_nf_implicit(coef, q) == (double)exact);
        assert_true(geo_nf_normal(p0, n, q) == (double)exact);
        double scale = cr[0] / n[0];
        assert_true(fabs(geo_nf3(a, b, c, q) - scale * (double)exact) < 1e-9);
    }
}

/* N·(p − p0) on coordinates far from the origin: forming the offset
 * D = −N·p0 in doubles loses the answer, the exact point+normal sign
 * does not. References in 128-bit integers. */
static void test_point_normal_sign_is_exact_where_offset_rounds(void **state)
{
    (void)state;
    uint64_t rng = 2024;
    int wrong_naive = 0;
    for (int t = 0; t < 20000; t++) {
        int64_t P0[3], D[3], N[3];
        for (int k = 0; k < 3; k++) {
            P0[k] = ((int64_t)1 << 50) + (int64_t)(geo_rand_next(&rng) % 1000);
            N[k] = (int64_t)(geo_rand_next(&rng) % 2001) - 1000;
        }
        /* a direction nearly perpendicular to N */
        D[0] = N[1];
        D[1] = -N[0];
        D[2] = (int64_t)(geo_rand_next(&rng) % 3) - 1;
        double p0[3], n[3], p[3];
        for (int k = 0; k < 3; k++) {
            p0[k] = (double)P0[k] * 0x1p-20;
            n[k] = (double)N[k];
            p[k] = (double)(P0[k] + D[k]) * 0x1p-20;
        }
        i128 ex = 0;
        for (int k = 0; k < 3; k++)
            ex += (i128)N[k] * D[k];
        int s = sign128(ex);
        assert_int_equal(geo_nf_normal_sign(p0, n, p), s);
        double plane[4] = {n[0], n[1], n[2],
                           -(n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2])};
        double naive = plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] +
                       plane[3];
        wrong_naive += ((naive > 0) - (naive < 0)) != s;
    }
    /* the case is hard: the rounded offset form is wrong often */
    assert_true(wrong_naive > 100);
}

/* The notch cube's top facet listed from its vertex (10,3,10): the
 * paper's first three vertices then make a reflex corner whose normal
 * points into the cube; the reference corner keeps nfG's sign outward. */
static void test_facet_sign_uses_a_convex_reference_corner(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    assert_non_null(p);
    /* facet 1 is 4,5,8,9,10,11,6,7; rotate it to start at 8 */
    uint32_t *fv = p->fidx + p->fstart[1];
    uint32_t rot[8] = {8, 9, 10, 11, 6, 7, 4, 5};
    for (int i = 0; i < 8; i++)
        fv[i] = rot[i];
    double above[3] = {1, 1, 11}, below[3] = {1, 1, 9}, on[3] = {2, 2, 10};
    const double(*V)[3] = (const double(*)[3])p->verts;
    assert_int_equal(geo_nf3_sign(V[8], V[9], V[10], above), -1);
    assert_int_equal(geo_nf_facet_sign(p, 1, above), 1);
    assert_int_equal(geo_nf_facet_sign(p, 1, below), -1);
    assert_int_equal(geo_nf_facet_sign(p, 1, on), 0);
    assert_true(geo_nf_facet(p, 1, above) > 0);
    assert_true(geo_facet_is_planar_exact(p, 1));
    geo_plane_spec spec;
    geo_plane_spec_facet(p, 1, &spec);
    assert_int_equal(geo_plane_spec_sign(&spec, above), 1);
    assert_true(geo_plane_spec_value(&spec, below) < 0);
    geo_poly_free(p);
}

static void test_facet_ref_survives_collinear_corners(void **state)
{
    (void)state;
    double up[3] = {1, 1, 1}, down[3] = {1, 1, -1};
    /* the first three vertices are collinear: the paper's nfG is 0 for
     * every point, the reference corner is not */
    static const double sq[5][3] = {
        {0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
    static const uint32_t sidx[] = {0, 1, 2, 3, 4}, sstart[] = {0, 5};
    geo_poly *p = geo_poly_from_arrays(5, &sq[0][0], 1, sstart, sidx, NULL,
                                       NULL);
    assert_non_null(p);
    assert_int_equal(geo_nf3_sign(sq[0], sq[1], sq[2], up), 0);
    assert_int_equal(geo_nf_facet_sign(p, 0, up), 1);
    assert_int_equal(geo_nf_facet_sign(p, 0, down), -1);
    geo_poly_free(p);

    /* a needle at the lexicographically smallest vertex (-1,1): its two
     * neighbours are both (0,1), so the choice falls back to the largest
     * corner turning the polygon's way */
    static const double nd[7][3] = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0},
                                    {0, 1, 0}, {-1, 1, 0}, {0, 1, 0}};
    static const uint32_t nidx[] = {0, 1, 2, 3, 4, 5, 6}, nstart[] = {0, 7};
    p = geo_poly_from_arrays(7, &nd[0][0], 1, nstart, nidx, NULL, NULL);
    assert_non_null(p);
    uint32_t r[3];
    geo_facet_ref(p, 0, r);
    const double(*V)[3] = (const double(*)[3])p->verts;
    assert_int_equal(geo_orient2d_proj(V[r[0]], V[r[1]], V[r[2]], 2), 1);
    assert_int_equal(geo_nf_facet_sign(p, 0, up), 1);
    assert_int_equal(geo_nf_facet_sign(p, 0, down), -1);
    geo_poly_free(p);
}

static void test_cross3_crosses_touches_misses_in_every_form(void **state)
{
    (void)state;
    double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    geo_poly *box = tu_box(lo, hi);
    geo_plane_spec f[3];
    for (int form = 0; form < 3; form++) {
        plane_forms(0.5, f);
        assert_int_equal(geo_cross3(&f[form], box), 1);
        plane_forms(1.0, f); /* the top facet lies on it */
        assert_int_equal(geo_cross3(&f[form], box), 0);
        plane_forms(0.0, f);
        assert_int_equal(geo_cross3(&f[form], box), 0);
        plane_forms(nextafter(1.0, 2.0), f); /* one ulp above the top */
        assert_int_equal(geo_cross3(&f[form], box), -1);
        plane_forms(nextafter(1.0, 0.0), f); /* one ulp below it */
        assert_int_equal(geo_cross3(&f[form], box), 1);
        plane_forms(-3.0, f);
        assert_int_equal(geo_cross3(&f[form], box), -1);
    }
    /* touching along an edge (x + y = 0) and at a vertex (x+y+z = 0) */
    geo_plane_spec edge = {.form = GEO_PLANE_IMPLICIT, .coef = {1, 1, 0, 0}};
    geo_plane_spec vert = {.form = GEO_PLANE_POINT_NORMAL,
                           .point = {0, 0, 0}, .normal = {1, 1, 1}};
    geo_plane_spec diag = {.form = GEO_PLANE_THREE_POINTS,
                           .pts = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
    assert_int_equal(geo_cross3(&edge, box), 0);
    assert_int_equal(geo_cross3(&vert, box), 0);
    assert_int_equal(geo_cross3(&diag, box), 1);
    /* the facet form: a facet's own plane touches a convex model */
    for (uint32_t fc = 0; fc < box->nfacets; fc++) {
        geo_plane_spec s;
        geo_plane_spec_facet(box, fc, &s);
        assert_int_equal(geo_cross3(&s, box), 0);
    }
    geo_poly *empty = geo_poly_new();
    assert_int_equal(geo_cross3(&edge, empty), -1);
    geo_poly_free(empty);
    geo_poly_free(box);
}

static void test_cross3_facet_plane_of_nonconvex_model_crosses(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    /* the notch floor z = 6 (facet 6) cuts the cube */
    geo_plane_spec s;
    geo_plane_spec_facet(p, 6, &s);
    assert_int_equal(geo_cross3(&s, p), 1);
    geo_plane_spec_facet(p, 0, &s); /* the bottom touches */
    assert_int_equal(geo_cross3(&s, p), 0);
    geo_poly_free(p);
}

static void test_conv3_box_and_random_convex_are_convex(void **state)
{
    (void)state;
    double lo[3] = {-1, -2, -3}, hi[3] = {4, 5, 6};
    geo_poly *box = tu_box(lo, hi);
    geo_conv3_result r;
    assert_int_equal(geo_conv3(box, NULL, &r), 0);
    assert_true(r.convex);
    assert_int_equal(r.nabove, 0);
    geo_poly_free(box);
    double c[3] = {3, -1, 2};
    for (uint64_t seed = 1; seed <= 20; seed++) {
        geo_poly *p = gen_convex_polyhedron(seed, 10 + (unsigned)seed * 3, c,
                                            5.0);
        assert_non_null(p);
        assert_true(geo_poly_volume(p) > 0);
        assert_int_equal(geo_conv3(p, NULL, &r), 0);
        assert_true(r.convex);
        assert_int_equal(r.nabove, 0);
        for (uint32_t f = 0; f < p->nfacets; f++)
            assert_true(geo_facet_is_convex(p, f));
        /* inverted: still convex, every facet has the rest above it */
        for (uint32_t f = 0; f < p->nfacets; f++)
            geo_poly_flip_facet(p, f);
        assert_int_equal(geo_conv3(p, NULL, &r), 0);
        assert_true(r.convex);
        assert_int_equal(r.nabove, p->nfacets);
        geo_poly_free(p);
    }
}

static void test_conv3_finds_the_nonconvex_facet_with_witnesses(void **state)
{
    (void)state;
    geo_poly *p = tu_notch_cube();
    geo_conv3_result r;
    assert_int_equal(geo_conv3(p, NULL, &r), 0);
    assert_false(r.convex);
    /* the witnesses lie on both sides of that facet's plane */
    assert_int_equal(geo_nf_facet_sign(p, r.facet, p->verts[r.v_above]), 1);
    assert_int_equal(geo_nf_facet_sign(p, r.facet, p->verts[r.v_below]), -1);
    geo_poly_free(p);
}

static int cancel_at_once(void *user, double fraction)
{
    (void)fraction;
    int *calls = user;
    return ++*calls >= 1;
}

static void test_conv3_stops_when_canceled(void **state)
{
    (void)state;
    double c[3] = {0, 0, 0};
    geo_poly *p = gen_convex_polyhedron(5, 200, c, 1.0);
    assert_non_null(p);
    assert_true(p->nfacets > 8);
    int calls = 0;
    geo_ctx ctx = {.progress = cancel_at_once, .user = &calls};
    geo_conv3_result r = {.convex = false, .facet = 12345};
    assert_int_equal(geo_conv3(p, &ctx, &r), -ECANCELED);
    assert_int_equal(r.facet, 12345);
    assert_int_equal(calls, 1);
    atomic_int flag = 1;
    geo_ctx flagged = {.cancel = &flag};
    assert_int_equal(geo_conv3(p, &flagged, &r), -ECANCELED);
    assert_int_equal(r.facet, 12345);
    geo_poly_free(p);
}

static geo_poly *one_facet(const double (*v)[3], uint32_t n)
{
    uint32_t idx[32], start[2] = {0, n};
    for (uint32_t i = 0; i < n; i++)
        idx[i] = i;
    return geo_poly_from_arrays(n, &v[0][0], 1, start, idx, NULL, NULL);
}

static void test_facet_convexity_of_polygons(void **state)
{
    (void)state;
    geo_poly *notch = tu_notch_cube();
    assert_true(geo_facet_is_convex(notch, 0));
    assert_false(geo_facet_is_convex(notch, 1)); /* the notched top */
    assert_false(geo_facet_is_convex(notch, 5)); /* the notched side */
    geo_poly_free(notch);

    /* a tilted convex pentagon with a straight corner */
    static const double pent[5][3] = {
        {0, 0, 0}, {2, 0, 2}, {4, 0, 4}, {4, 3, 4}, {0, 3, 0}};
    geo_poly *p = one_facet(pent, 5);
    assert_true(geo_facet_is_convex(p, 0));
    geo_poly_free(p);

    /* the pentagram: every corner turns left, yet it winds twice */
    double star[5][3];
    for (int i = 0; i < 5; i++) {
        double t = 2.0 * M_PI * (2 * i) / 5.0;
        star[i][0] = cos(t);
        star[i][1] = sin(t);
        star[i][2] = 0;
    }
    p = one_facet((const double(*)[3])star, 5);
    assert_false(geo_facet_is_convex(p, 0));
    geo_poly_free(p);

    /* a spike: straight corner folding back */
    static const double spike[5][3] = {
        {0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {2, 4, 0}, {2, 1, 0}};
    p = one_facet(spike, 5);
    assert_false(geo_facet_is_convex(p, 0));
    geo_poly_free(p);

    /* a reflex corner one ulp deep */
    static const double flat[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0},
                                      {0.5, 0.5, 0}};
    double dent[4][3];
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            dent[i][k] = flat[i][k];
    dent[3][0] = nextafter(0.5, 1.0); /* just right of the diagonal */
    p = one_facet((const double(*)[3])dent, 4);
    assert_false(geo_facet_is_convex(p, 0));
    geo_poly_free(p);
    dent[3][0] = nextafter(0.5, 0.0); /* just left: convex */
    p = one_facet((const double(*)[3])dent, 4);
    assert_true(geo_facet_is_convex(p, 0));
    geo_poly_free(p);
}

/* The sample stones: the truth and the scans are convex (the scans are
 * intersections of half-spaces with rounded vertices, still exactly
 * convex by conv3), the self-intersecting one and the non-convex prisms
 * are not. */
static void test_conv3_on_sample_models(void **state)
{
    (void)state;
    static const struct {
        const char *name;
        bool convex;
        uint32_t nonconvex_facets;
    } cases[] = {
        {"brilliant.truth.json", true, 0},
        {"brilliant.scan-k100.json", true, 0},
        {"brilliant.scan-k400.json", true, 0},
        {"brilliant.selfint.json", false, 2},
        {"l-prism.json", false, 2},
        {"notch-cube.json", false, 2},
    };
    for (size_t m = 0; m < sizeof cases / sizeof cases[0]; m++) {
        geo_err err = {{0}};
        geo_poly *p = proto_model_read_file(tu_model_path(cases[m].name),
                                            PROTO_FMT_UNKNOWN, NULL, &err);
        assert_non_null(p);
        geo_conv3_result r;
        assert_int_equal(geo_conv3(p, NULL, &r), 0);
        assert_int_equal(r.convex, cases[m].convex);
        uint32_t nc = 0;
        for (uint32_t f = 0; f < p->nfacets; f++)
            nc += !geo_facet_is_convex(p, f);
        assert_int_equal(nc, cases[m].nonconvex_facets);
        geo_poly_free(p);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_four_forms_agree_on_signs_and_paper_values),
        cmocka_unit_test(test_point_normal_sign_is_exact_where_offset_rounds),
        cmocka_unit_test(test_facet_sign_uses_a_convex_reference_corner),
        cmocka_unit_test(test_facet_ref_survives_collinear_corners),
        cmocka_unit_test(test_cross3_crosses_touches_misses_in_every_form),
        cmocka_unit_test(test_cross3_facet_plane_of_nonconvex_model_crosses),
        cmocka_unit_test(test_conv3_box_and_random_convex_are_convex),
        cmocka_unit_test(test_conv3_finds_the_nonconvex_facet_with_witnesses),
        cmocka_unit_test(test_conv3_stops_when_canceled),
        cmocka_unit_test(test_facet_convexity_of_polygons),
        cmocka_unit_test(test_conv3_on_sample_models),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
