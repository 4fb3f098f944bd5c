/* test_selfint_triangles.c — the search's shortcut for pairs of
 * triangles (one or two exact signs instead of the general pair test)
 * gives the general test's answer on every pair: random triangles on a
 * 3×3×3 grid sharing no vertex, one, two (an edge, either direction) or
 * all three, so that coplanar, touching, folded and crossing pairs all
 * occur many times; and pairs each across the other's plane sharing no
 * vertex (real and grid coordinates), the case two signs decide. */
#include "testutil.h"

#include <stdlib.h>

#include "predicates.h"
#include "selfint.h"

/* The pair answer of the search (its shortcut, then pair_test). */
static bool search_says(const geo_poly *p)
{
    geo_selfint si;
    geo_err err = {{0}};
    assert_int_equal(geo_selfint_find(p, NULL, NULL, NULL, &si, &err), 0);
    bool hit = si.count > 0 && si.npairs > 0 && si.pairs[0][0] == 0 &&
               si.pairs[0][1] == 1;
    geo_selfint_clear(&si);
    return hit;
}

/* The general pair test's answer (no shortcut). */
static bool general_says(const geo_poly *p)
{
    geo_facet_shape s0, s1;
    geo_facet_shape_of(p, 0, &s0);
    geo_facet_shape_of(p, 1, &s1);
    int r = geo_facets_intersect(p, 0, 1, &s0, &s1);
    assert_true(r >= 0);
    return r == 1;
}

/* Triangles fidx[0..2] and fidx[3..5] over the vertices v; *ok when
 * neither is degenerate (the pairs both tests answer). */
static geo_poly *two_triangles(double v[6][3], const uint32_t fidx[6],
                               bool *ok)
{
    uint32_t fstart[3] = {0, 3, 6};
    geo_poly *p = geo_poly_from_arrays(6, &v[0][0], 2, fstart, fidx, NULL,
                                       NULL);
    assert_non_null(p);
    geo_facet_shape s0, s1;
    geo_facet_shape_of(p, 0, &s0);
    geo_facet_shape_of(p, 1, &s1);
    *ok = !s0.degenerate && !s1.degenerate;
    return p;
}

static void test_triangle_pairs_agree_with_the_general_test(void **state)
{
    (void)state;
    uint64_t rng = 18;
    uint32_t tested = 0, hits = 0, by_shared[4] = {0};
    for (int trial = 0; trial < 20000; trial++) {
        double v[6][3];
        for (int i = 0; i < 6; i++)
            for (int k = 0; k < 3; k++)
                v[i][k] = (double)(geo_rand_next(&rng) % 3);
        /* the second triangle takes 0..3 of the first's indices, at
         * random positions and in either direction */
        uint32_t shared = (uint32_t)(geo_rand_next(&rng) % 4);
        uint32_t a[3] = {0, 1, 2}, b[3] = {3, 4, 5};
        uint32_t rot = (uint32_t)(geo_rand_next(&rng) % 3);
        for (uint32_t s = 0; s < shared; s++)
            b[s] = a[(s + rot) % 3];
        if (geo_rand_next(&rng) & 1) {
            uint32_t t = b[0];
            b[0] = b[2];
            b[2] = t;
        }
        uint32_t fidx[6] = {a[0], a[1], a[2], b[0], b[1], b[2]};
        bool ok;
        geo_poly *p = two_triangles(v, fidx, &ok);
        if (ok) {
            bool want = general_says(p), got = search_says(p);
            if (want != got)
                fail_msg("trial %d (%u shared): general %d, search %d", trial,
                         shared, want, got);
            tested++;
            hits += want;
            by_shared[shared]++;
        }
        geo_poly_free(p);
    }
    /* the draw reaches every case, intersecting and apart */
    assert_true(tested > 5000);
    assert_true(hits > 500 && hits < tested - 500);
    for (int s = 0; s < 4; s++)
        assert_true(by_shared[s] > 500);
}

/* Whether each of the two triangles of p has its vertices strictly on
 * both sides of the other's plane. */
static bool both_straddle(const geo_poly *p)
{
    for (int t = 0; t < 2; t++) {
        const uint32_t *f = p->fidx + 3 * t, *g = p->fidx + 3 * (1 - t);
        int pos = 0, neg = 0;
        for (int j = 0; j < 3; j++) {
            int s = geo_orient3d(p->verts[f[0]], p->verts[f[1]],
                                 p->verts[f[2]], p->verts[g[j]]);
            pos += s > 0;
            neg += s < 0;
        }
        if (!pos || !neg || pos + neg != 3)
            return false;
    }
    return true;
}

/* Two triangles sharing no vertex, each across the other's plane (the
 * canonical form and two signs of the search decide): random real
 * coordinates and a 5×5×5 grid, the second triangle moved about the
 * first so that crossing, apart and (on the grid) touching pairs all
 * occur many times, in every vertex order. */
static void test_straddling_pairs_agree_with_the_general_test(void **state)
{
    (void)state;
    uint64_t rng = 7;
    uint32_t tested = 0, hits = 0;
    for (int trial = 0; trial < 60000; trial++) {
        bool grid = trial % 2;
        double v[6][3];
        for (int i = 0; i < 6; i++)
            for (int k = 0; k < 3; k++)
                v[i][k] = grid ? (double)(geo_rand_next(&rng) % 5)
                               : geo_rand_unit(&rng) * 4;
        static const uint32_t fidx[6] = {0, 1, 2, 3, 4, 5};
        bool ok;
        geo_poly *p = two_triangles(v, fidx, &ok);
        if (ok && both_straddle(p)) {
            bool want = general_says(p), got = search_says(p);
            if (want != got)
                fail_msg("trial %d: general %d, search %d", trial, want, got);
            tested++;
            hits += want;
        }
        geo_poly_free(p);
    }
    assert_true(tested > 5000);
    print_message("# %u straddling pairs, %u meeting\n", tested, hits);
    assert_true(hits > 1000 && hits < tested - 1000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_triangle_pairs_agree_with_the_general_test),
        cmocka_unit_test(test_straddling_pairs_agree_with_the_general_test),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
