/* test_orient.c — orientation: a flipped facet is the minority and is
 * repaired, an inverted model is inward and repaired by flipping all
 * (planes too), several inconsistent patches are 2-coloured, shells are
 * judged separately, a Möbius band is reported non-orientable and left
 * untouched. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gen_sphere.h"
#include "model_io.h"
#include "orient.h"
#include "topo.h"

static geo_poly *load(const char *name)
{
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(tu_model_path(name), PROTO_FMT_UNKNOWN,
                                        NULL, &err);
    if (!p)
        fail_msg("%s: %s", name, err.msg);
    return p;
}

static geo_orient_report analyze(const geo_poly *p, uint8_t *flip)
{
    geo_topo *t = geo_topo_build(p, NULL);
    assert_non_null(t);
    geo_orient_report r;
    assert_int_equal(geo_orient_analyze(p, t, flip, &r, NULL), 0);
    geo_topo_free(t);
    return r;
}

/* Same facets as cycles (any rotation) with the same planes. */
static void assert_same_facets(const geo_poly *a, const geo_poly *b)
{
    assert_int_equal(a->nfacets, b->nfacets);
    for (uint32_t f = 0; f < a->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(a, f);
        assert_int_equal(n, geo_poly_facet_size(b, f));
        const uint32_t *x = geo_poly_facet(a, f), *y = geo_poly_facet(b, f);
        uint32_t r = 0;
        while (r < n && y[r] != x[0])
            r++;
        assert_true(r < n);
        for (uint32_t i = 0; i < n; i++)
            assert_int_equal(x[i], y[(i + r) % n]);
        for (int k = 0; k < 4; k++)
            assert_true(fabs(a->planes[f][k] - b->planes[f][k]) < 1e-12);
    }
}

static void test_sample_models_orientation(void **state)
{
    (void)state;
    const char *outward[] = {"brilliant.truth.json", "brilliant.scan-k400.json",
                             "brilliant.holes.json", "notch-cube.json",
                             "l-prism.json"};
    for (size_t i = 0; i < sizeof outward / sizeof *outward; i++) {
        geo_poly *p = load(outward[i]);
        geo_orient_report r = analyze(p, NULL);
        assert_int_equal(r.orientation, GEO_ORIENT_OUTWARD);
        assert_int_equal(r.ninconsistent, 0);
        assert_int_equal(r.nshells, 1);
        assert_true(r.orientable);
        assert_true(r.volume > 0);
        geo_poly_free(p);
    }
}

static void test_flipped_facet_is_the_minority_and_repaired(void **state)
{
    (void)state;
    geo_poly *p = load("notch-cube.flipped.json");
    geo_poly *good = load("notch-cube.json");
    uint8_t flip[16];
    geo_orient_report r = analyze(p, flip);
    assert_int_equal(r.orientation, GEO_ORIENT_INCONSISTENT);
    assert_int_equal(r.ninconsistent, 1);
    for (uint32_t f = 0; f < p->nfacets; f++)
        assert_int_equal(flip[f], f == 1);
    /* with the minority flipped the volume is the true one */
    assert_true(fabs(r.volume - 936.0) < 1e-9);
    geo_orient_report rep;
    assert_int_equal(geo_orient_repair(p, &rep, NULL), 0);
    assert_int_equal(rep.nflipped, 1);
    assert_same_facets(p, good);
    r = analyze(p, NULL);
    assert_int_equal(r.orientation, GEO_ORIENT_OUTWARD);
    geo_poly_free(p);
    geo_poly_free(good);
}

static void test_inverted_model_is_inward_and_repaired(void **state)
{
    (void)state;
    geo_poly *good = load("brilliant.truth.json");
    geo_poly *p = geo_poly_copy(good);
    for (uint32_t f = 0; f < p->nfacets; f++)
        geo_poly_flip_facet(p, f);
    geo_orient_report r = analyze(p, NULL);
    assert_int_equal(r.orientation, GEO_ORIENT_INWARD);
    assert_int_equal(r.ninconsistent, 0);
    assert_int_equal(r.ninverted_shells, 1);
    assert_true(r.volume < 0);
    geo_orient_report rep;
    assert_int_equal(geo_orient_repair(p, &rep, NULL), 0);
    assert_int_equal(rep.nflipped, p->nfacets);
    assert_same_facets(p, good); /* planes negated back too */
    geo_poly_free(p);
    geo_poly_free(good);
}

static void test_scattered_and_majority_flips_are_undone(void **state)
{
    (void)state;
    geo_poly *good = gs_sphere(5, 1.0);
    uint64_t rng = 42;
    for (int trial = 0; trial < 2; trial++) {
        /* trial 0: a few scattered facets (several patches, a 2-colouring
         * across many components); trial 1: most of the facets, so the
         * originally right ones are the minority and the shell comes out
         * inward before the final flip */
        geo_poly *p = geo_poly_copy(good);
        uint32_t nflip = 0;
        for (uint32_t f = 0; f < p->nfacets; f++) {
            bool flip = trial == 0 ? geo_rand_unit(&rng) < 0.05
                                   : geo_rand_unit(&rng) < 0.8;
            if (flip) {
                geo_poly_flip_facet(p, f);
                nflip++;
            }
        }
        geo_orient_report r = analyze(p, NULL);
        assert_int_equal(r.orientation, GEO_ORIENT_INCONSISTENT);
        assert_int_equal(r.ninconsistent,
                         trial == 0 ? nflip : p->nfacets - nflip);
        assert_int_equal(geo_orient_repair(p, NULL, NULL), 0);
        assert_same_facets(p, good);
        geo_poly_free(p);
    }
    geo_poly_free(good);
}

static void test_shells_are_judged_separately(void **state)
{
    (void)state;
    /* two disjoint boxes, the second one inverted */
    const double lo1[3] = {0, 0, 0}, hi1[3] = {1, 1, 1};
    const double lo2[3] = {3, 0, 0}, hi2[3] = {5, 2, 2};
    geo_poly *a = tu_box(lo1, hi1), *b = tu_box(lo2, hi2);
    geo_poly *p = geo_poly_copy(a);
    for (uint32_t v = 0; v < b->nverts; v++)
        geo_poly_add_vertex(p, b->verts[v]);
    for (uint32_t f = 0; f < b->nfacets; f++) {
        uint32_t idx[4];
        for (int k = 0; k < 4; k++)
            idx[k] = geo_poly_facet(b, f)[k] + a->nverts;
        int64_t g = geo_poly_add_facet(p, idx, 4);
        memcpy(p->planes[g], b->planes[f], sizeof p->planes[g]);
        geo_poly_flip_facet(p, (uint32_t)g);
    }
    geo_orient_report r = analyze(p, NULL);
    assert_int_equal(r.nshells, 2);
    assert_int_equal(r.ninverted_shells, 1);
    assert_int_equal(r.orientation, GEO_ORIENT_INCONSISTENT);
    geo_orient_report rep;
    assert_int_equal(geo_orient_repair(p, &rep, NULL), 0);
    assert_int_equal(rep.nflipped, 6);
    assert_true(fabs(geo_poly_volume(p) - 9.0) < 1e-12);
    r = analyze(p, NULL);
    assert_int_equal(r.orientation, GEO_ORIENT_OUTWARD);
    geo_poly_free(p);
    geo_poly_free(a);
    geo_poly_free(b);
}

/* Box [0,4]³ with the box [1,3]³ inside; the inner one reversed when
 * `cavity` (a hollow solid), else facing out. */
static geo_poly *hollow_box(bool cavity)
{
    const double lo1[3] = {0, 0, 0}, hi1[3] = {4, 4, 4};
    const double lo2[3] = {1, 1, 1}, hi2[3] = {3, 3, 3};
    geo_poly *a = tu_box(lo1, hi1), *b = tu_box(lo2, hi2);
    geo_poly *p = geo_poly_copy(a);
    for (uint32_t v = 0; v < b->nverts; v++)
        geo_poly_add_vertex(p, b->verts[v]);
    for (uint32_t f = 0; f < b->nfacets; f++) {
        uint32_t idx[4];
        for (int k = 0; k < 4; k++)
            idx[k] = geo_poly_facet(b, f)[k] + a->nverts;
        int64_t g = geo_poly_add_facet(p, idx, 4);
        memcpy(p->planes[g], b->planes[f], sizeof p->planes[g]);
        if (cavity)
            geo_poly_flip_facet(p, (uint32_t)g);
    }
    geo_poly_free(a);
    geo_poly_free(b);
    return p;
}

static void test_cavity_shell_is_rightly_inward(void **state)
{
    (void)state;
    geo_poly *p = hollow_box(true);
    geo_orient_report r = analyze(p, NULL);
    assert_int_equal(r.nshells, 2);
    assert_int_equal(r.ninverted_shells, 0);
    assert_int_equal(r.orientation, GEO_ORIENT_OUTWARD);
    assert_true(fabs(r.volume - 56.0) < 1e-12);
    geo_orient_report rep;
    assert_int_equal(geo_orient_repair(p, &rep, NULL), 0);
    assert_int_equal(rep.nflipped, 0);
    /* the whole hollow solid turned inside out is inward */
    for (uint32_t f = 0; f < p->nfacets; f++)
        geo_poly_flip_facet(p, f);
    r = analyze(p, NULL);
    assert_int_equal(r.orientation, GEO_ORIENT_INWARD);
    assert_int_equal(r.ninverted_shells, 2);
    geo_poly_free(p);

    /* an inner shell facing out is the wrong one: repair turns it */
    p = hollow_box(false);
    geo_poly *want = hollow_box(true);
    r = analyze(p, NULL);
    assert_int_equal(r.ninverted_shells, 1);
    assert_int_equal(r.orientation, GEO_ORIENT_INCONSISTENT);
    assert_int_equal(geo_orient_repair(p, &rep, NULL), 0);
    assert_int_equal(rep.nflipped, 6);
    assert_same_facets(p, want);
    geo_poly_free(p);
    geo_poly_free(want);
}

static void test_moebius_band_is_not_orientable(void **state)
{
    (void)state;
    enum { N = 12 };
    double v[2 * N][3];
    for (int i = 0; i < N; i++) {
        double a = 2 * M_PI * i / N, tw = M_PI * i / N;
        for (int s = 0; s < 2; s++) {
            double w = s ? -0.3 : 0.3;
            v[2 * i + s][0] = (2 + w * cos(tw)) * cos(a);
            v[2 * i + s][1] = (2 + w * cos(tw)) * sin(a);
            v[2 * i + s][2] = w * sin(tw);
        }
    }
    uint32_t idx[4 * N], start[N + 1];
    for (uint32_t i = 0; i < N; i++) {
        uint32_t t0 = 2 * i, b0 = 2 * i + 1;
        uint32_t t1 = 2 * ((i + 1) % N), b1 = t1 + 1;
        if (i == N - 1) { /* the half twist: top meets bottom */
            uint32_t x = t1;
            t1 = b1;
            b1 = x;
        }
        uint32_t q[4] = {t0, b0, b1, t1};
        memcpy(idx + 4 * i, q, sizeof q);
        start[i] = 4 * i;
    }
    start[N] = 4 * N;
    geo_poly *p = geo_poly_from_arrays(2 * N, &v[0][0], N, start, idx, NULL,
                                       NULL);
    assert_non_null(p);
    geo_orient_report r = analyze(p, NULL);
    assert_false(r.orientable);
    assert_int_equal(r.nconflict_edges, 1);
    assert_int_equal(r.orientation, GEO_ORIENT_INCONSISTENT);
    geo_poly *before = geo_poly_copy(p);
    geo_err err = {{0}};
    assert_int_equal(geo_orient_repair(p, NULL, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "not orientable"));
    assert_same_facets(p, before);
    geo_poly_free(before);
    geo_poly_free(p);
}

static void test_orientation_names(void **state)
{
    (void)state;
    assert_string_equal(geo_orientation_name(GEO_ORIENT_OUTWARD), "outward");
    assert_string_equal(geo_orientation_name(GEO_ORIENT_INWARD), "inward");
    assert_string_equal(geo_orientation_name(GEO_ORIENT_INCONSISTENT),
                        "inconsistent");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sample_models_orientation),
        cmocka_unit_test(test_flipped_facet_is_the_minority_and_repaired),
        cmocka_unit_test(test_inverted_model_is_inward_and_repaired),
        cmocka_unit_test(test_scattered_and_majority_flips_are_undone),
        cmocka_unit_test(test_shells_are_judged_separately),
        cmocka_unit_test(test_cavity_shell_is_rightly_inward),
        cmocka_unit_test(test_moebius_band_is_not_orientable),
        cmocka_unit_test(test_orientation_names),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
