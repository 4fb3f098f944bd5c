/* test_bvh.c — every BVH query returns exactly what a brute-force scan of
 * the boxes returns (random boxes, many duplicates), and the pair tasks
 * partition the self-pairs; the grid tree's pairs are those of its
 * stored boxes, a superset of the exact ones, and the tree is checked for
 * shape (each item once, boxes the unions of their items and the grid
 * boxes of the exact ones, bounded depth) on random, identical,
 * NaN-centred, infinite, touching and out-of-range boxes. */
#include "testutil.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "fbvh.h"
#include "gen_sphere.h"
#include "vec.h"

enum { N = 3000 };

static geo_bbox *random_boxes(uint32_t n, uint64_t seed)
{
    geo_bbox *b = malloc(n * sizeof *b);
    for (uint32_t i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) {
            /* a coarse grid gives many identical centroids */
            double c = (double)(geo_rand_next(&seed) % 40) * 0.25;
            double e = geo_rand_unit(&seed) * 0.5;
            b[i].lo[k] = c - e;
            b[i].hi[k] = c + e;
        }
    }
    return b;
}

static bool collect(void *user, uint32_t item)
{
    unsigned char *seen = user;
    seen[item]++;
    return true;
}

static void test_query_box_matches_brute_force(void **state)
{
    (void)state;
    geo_bbox *b = random_boxes(N, 1);
    geo_bvh *h = geo_bvh_build(b, N, NULL);
    assert_non_null(h);
    uint64_t rng = 99;
    for (int q = 0; q < 200; q++) {
        geo_bbox qb;
        for (int k = 0; k < 3; k++) {
            double c = geo_rand_unit(&rng) * 10, e = geo_rand_unit(&rng);
            qb.lo[k] = c - e;
            qb.hi[k] = c + e;
        }
        unsigned char seen[N] = {0};
        geo_bvh_query_box(h, &qb, collect, seen);
        for (uint32_t i = 0; i < N; i++)
            assert_int_equal(seen[i], geo_bbox_overlap(&b[i], &qb) ? 1 : 0);
    }
    geo_bvh_free(h);
    free(b);
}

static void test_query_plane_is_conservative(void **state)
{
    (void)state;
    geo_bbox *b = random_boxes(N, 2);
    geo_bvh *h = geo_bvh_build(b, N, NULL);
    uint64_t rng = 5;
    for (int q = 0; q < 100; q++) {
        double pl[4] = {geo_rand_unit(&rng) - 0.5, geo_rand_unit(&rng) - 0.5,
                        geo_rand_unit(&rng) - 0.5, 0};
        pl[3] = -(pl[0] + pl[1] + pl[2]) * 5;
        unsigned char seen[N] = {0};
        geo_bvh_query_plane(h, pl, collect, seen);
        for (uint32_t i = 0; i < N; i++) {
            /* a box with corners on both sides (or on) must be reported */
            int pos = 0, neg = 0;
            for (int c = 0; c < 8; c++) {
                double p[3] = {(c & 1) ? b[i].hi[0] : b[i].lo[0],
                               (c & 2) ? b[i].hi[1] : b[i].lo[1],
                               (c & 4) ? b[i].hi[2] : b[i].lo[2]};
                double v = pl[0] * p[0] + pl[1] * p[1] + pl[2] * p[2] + pl[3];
                pos |= v >= 0;
                neg |= v <= 0;
            }
            if (pos && neg)
                assert_int_equal(seen[i], 1);
            assert_true(seen[i] <= 1);
        }
    }
    geo_bvh_free(h);
    free(b);
}

static void test_query_ray_finds_every_hit_box(void **state)
{
    (void)state;
    geo_bbox *b = random_boxes(N, 3);
    geo_bvh *h = geo_bvh_build(b, N, NULL);
    uint64_t rng = 11;
    for (int q = 0; q < 20; q++) {
        double o[3] = {geo_rand_unit(&rng) * 10, geo_rand_unit(&rng) * 10,
                       geo_rand_unit(&rng) * 10};
        double d[3] = {geo_rand_unit(&rng) - 0.5, geo_rand_unit(&rng) - 0.5,
                       q % 5 == 0 ? 0 : geo_rand_unit(&rng) - 0.5};
        unsigned char seen[N] = {0};
        geo_bvh_query_ray(h, o, d, INFINITY, collect, seen);
        /* brute force: sample the ray densely; any sample inside a box
         * means that box must have been reported */
        for (uint32_t i = 0; i < N; i++) {
            bool hit = false;
            for (int s = 0; s <= 1000 && !hit; s++) {
                double t = s * 0.04, p[3];
                for (int k = 0; k < 3; k++)
                    p[k] = o[k] + t * d[k];
                hit = geo_bbox_contains(&b[i], p);
            }
            if (hit)
                assert_int_equal(seen[i], 1);
        }
    }
    geo_bvh_free(h);
    free(b);
}

typedef struct pairs {
    uint32_t n;
    uint8_t *count; /* N*N */
} pairs;

static bool count_pair(void *user, uint32_t a, uint32_t b)
{
    pairs *p = user;
    if (a > b) {
        uint32_t t = a;
        a = b;
        b = t;
    }
    p->count[(size_t)a * p->n + b]++;
    return true;
}

static void test_pair_tasks_report_each_overlap_once(void **state)
{
    (void)state;
    const uint32_t n = 800;
    geo_bbox *b = random_boxes(n, 4);
    geo_bvh *h = geo_bvh_build(b, n, NULL);
    for (uint32_t cap = 1; cap <= 512; cap *= 8) {
        uint32_t ta[512], tb[512];
        uint32_t nt = geo_bvh_pair_tasks(h, ta, tb, cap);
        assert_true(nt >= 1 && nt <= cap);
        pairs p = {n, calloc((size_t)n * n, 1)};
        for (uint32_t t = 0; t < nt; t++)
            geo_bvh_pairs(h, ta[t], tb[t], count_pair, &p);
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = i + 1; j < n; j++)
                assert_int_equal(p.count[(size_t)i * n + j],
                                 geo_bbox_overlap(&b[i], &b[j]) ? 1 : 0);
        free(p.count);
    }
    geo_bvh_free(h);
    free(b);
}

/* The grid coordinate of x on axis k of h, as fbvh.h defines it. */
static double grid(const geo_fbvh *h, int k, double x)
{
    double far = h->scale > 0 ? h->origin[k] + GEO_FBVH_CELLS / h->scale
                              : h->origin[k];
    if (x <= h->origin[k])
        return 0;
    if (x >= far)
        return GEO_FBVH_CELLS;
    double g = (x - h->origin[k]) * h->scale;
    return g < GEO_FBVH_CELLS ? g : GEO_FBVH_CELLS;
}

/* The compact tree: each node's box the union of its items' stored
 * boxes, each item once, and each stored box the grid box of the exact
 * one (floor of lo, ceil of hi; empty for a NaN bound). Returns the
 * depth. */
static uint32_t check_fnode(const geo_fbvh *h, uint32_t node,
                            const geo_bbox *in, unsigned char *seen,
                            geo_qbox *ret_box)
{
    const geo_fbvh_node *n = &h->nodes[node];
    geo_qbox box;
    for (int k = 0; k < 3; k++) {
        box.lo[k] = GEO_FBVH_CELLS + 1;
        box.hi[k] = 0;
    }
    uint32_t depth = 1;
    if (n->count) {
        for (uint32_t i = n->child; i < n->child + n->count; i++) {
            const geo_qbox *b = &h->boxes[i];
            const geo_bbox *x = &in[h->items[i]];
            seen[h->items[i]]++;
            bool nan = false;
            for (int k = 0; k < 3; k++)
                nan = nan || isnan(x->lo[k]) || isnan(x->hi[k]);
            geo_qbox q;
            geo_fbvh_quantize(h, x, &q);
            assert_memory_equal(&q, b, sizeof q);
            for (int k = 0; k < 3; k++) {
                if (nan) {
                    assert_int_equal(b->lo[k], GEO_FBVH_CELLS + 1);
                    assert_int_equal(b->hi[k], 0);
                    continue;
                }
                assert_true(b->lo[k] == floor(grid(h, k, x->lo[k])));
                assert_true(b->hi[k] == ceil(grid(h, k, x->hi[k])));
                box.lo[k] = b->lo[k] < box.lo[k] ? b->lo[k] : box.lo[k];
                box.hi[k] = b->hi[k] > box.hi[k] ? b->hi[k] : box.hi[k];
            }
        }
    } else {
        geo_qbox l, r;
        uint32_t dl = check_fnode(h, n->child, in, seen, &l);
        uint32_t dr = check_fnode(h, n->child + 1, in, seen, &r);
        for (int k = 0; k < 3; k++) {
            box.lo[k] = l.lo[k] < r.lo[k] ? l.lo[k] : r.lo[k];
            box.hi[k] = l.hi[k] > r.hi[k] ? l.hi[k] : r.hi[k];
        }
        depth += dl > dr ? dl : dr;
    }
    assert_memory_equal(&box, &n->box, sizeof box);
    *ret_box = box;
    return depth;
}

static bool qbox_overlap(const geo_qbox *a, const geo_qbox *b)
{
    for (int k = 0; k < 3; k++)
        if (!(a->lo[k] <= b->hi[k] && b->lo[k] <= a->hi[k]))
            return false;
    return true;
}

static void test_grid_tree_pairs(void **state)
{
    (void)state;
    const uint32_t n = 800;
    geo_bbox *b = random_boxes(n, 4);
    geo_fbvh *h = geo_fbvh_build(b, n, NULL);
    assert_non_null(h);
    unsigned char seen[800] = {0};
    geo_qbox all;
    uint32_t depth = check_fnode(h, 0, b, seen, &all);
    for (uint32_t i = 0; i < n; i++)
        assert_int_equal(seen[i], 1);
    assert_true(depth <= 30 + 10 + 1);
    uint32_t *slot = malloc(n * sizeof *slot);
    for (uint32_t k = 0; k < n; k++)
        slot[h->items[k]] = k;
    /* every pair whose stored boxes overlap once, so every exactly
     * overlapping pair; whatever the number of tasks */
    for (uint32_t cap = 1; cap <= 512; cap *= 8) {
        uint32_t ta[512], tb[512];
        uint32_t nt = geo_fbvh_pair_tasks(h, ta, tb, cap);
        assert_true(nt >= 1 && nt <= cap);
        pairs p = {n, calloc((size_t)n * n, 1)};
        for (uint32_t t = 0; t < nt; t++)
            geo_fbvh_pairs(h, ta[t], tb[t], count_pair, &p);
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = i + 1; j < n; j++) {
                bool f = qbox_overlap(&h->boxes[slot[i]], &h->boxes[slot[j]]);
                assert_int_equal(p.count[(size_t)i * n + j], f ? 1 : 0);
                if (geo_bbox_overlap(&b[i], &b[j]))
                    assert_true(f);
            }
        free(p.count);
    }
    free(slot);
    geo_fbvh_free(h);
    free(b);
}

/* With tags, exactly the overlapping pairs that share no tag: each item
 * tagged with three of 40 values (some repeated within an item), so that
 * about half the overlapping pairs share one, in both leaf loops. */
static void test_grid_tree_pairs_without_shared_tags(void **state)
{
    (void)state;
    const uint32_t n = 800;
    geo_bbox *b = random_boxes(n, 4);
    geo_fbvh *h = geo_fbvh_build(b, n, NULL);
    assert_non_null(h);
    uint32_t (*tags)[3] = malloc(n * sizeof *tags), (*by_item)[3] =
                                                       malloc(n * sizeof *by_item);
    uint32_t *slot = malloc(n * sizeof *slot);
    uint64_t r = 12345;
    for (uint32_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            r = r * 6364136223846793005u + 1442695040888963407u;
            by_item[i][c] = (uint32_t)(r >> 33) % 40;
        }
    for (uint32_t k = 0; k < n; k++) {
        slot[h->items[k]] = k;
        memcpy(tags[k], by_item[h->items[k]], sizeof tags[k]);
    }
    h->tags = (const uint32_t (*)[3])tags;
    uint32_t shared = 0, reported = 0;
    for (uint32_t cap = 1; cap <= 512; cap *= 8) {
        uint32_t ta[512], tb[512];
        uint32_t nt = geo_fbvh_pair_tasks(h, ta, tb, cap);
        pairs p = {n, calloc((size_t)n * n, 1)};
        for (uint32_t t = 0; t < nt; t++)
            geo_fbvh_pairs(h, ta[t], tb[t], count_pair, &p);
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = i + 1; j < n; j++) {
                bool common = false;
                for (int x = 0; x < 3; x++)
                    for (int y = 0; y < 3; y++)
                        common |= by_item[i][x] == by_item[j][y];
                bool f = qbox_overlap(&h->boxes[slot[i]], &h->boxes[slot[j]]);
                shared += f && common;
                reported += p.count[(size_t)i * n + j];
                assert_int_equal(p.count[(size_t)i * n + j],
                                 f && !common ? 1 : 0);
            }
        free(p.count);
    }
    assert_true(shared > 100 && reported > 100);
    free(tags), free(by_item), free(slot);
    geo_fbvh_free(h);
    free(b);
}

static void test_grid_tree_of_equal_and_nan_boxes(void **state)
{
    (void)state;
    /* all centres in one grid cell, a few NaN: median splits, every item
     * once, depth of a balanced tree */
    enum { M = 1000 };
    geo_bbox *b = malloc(M * sizeof *b);
    for (uint32_t i = 0; i < M; i++)
        for (int k = 0; k < 3; k++) {
            b[i].lo[k] = i % 7 == 3 ? NAN : 1.0;
            b[i].hi[k] = 2.0;
        }
    geo_fbvh *h = geo_fbvh_build(b, M, NULL);
    assert_non_null(h);
    unsigned char seen[M] = {0};
    geo_qbox all;
    uint32_t depth = check_fnode(h, 0, b, seen, &all);
    for (uint32_t i = 0; i < M; i++)
        assert_int_equal(seen[i], 1);
    assert_true(depth <= 10);
    geo_fbvh_free(h);
    free(b);
    h = geo_fbvh_build(NULL, 0, NULL);
    assert_non_null(h);
    uint32_t ta[4], tb[4];
    assert_int_equal(geo_fbvh_pair_tasks(h, ta, tb, 4), 0);
    geo_fbvh_free(h);
}

/* Bounds far apart, infinite, touching exactly and a hair apart: every
 * pair that overlaps exactly overlaps on the grid. */
static void test_grid_tree_rounds_outward(void **state)
{
    (void)state;
    const double t = 1.0 / 3, u = nextafter(t, 1);
    geo_bbox b[7] = {{{-1e300, 0.1, t}, {1e300, 0.1, t}},
                     {{3.4028235677973366e38, -0.1, -t},
                      {3.4028235677973366e38, -0.1, -t}},
                     {{0, 0, 0}, {0, 0, 0}},
                     {{-INFINITY, 0.1, u}, {0, 0.2, 1}},
                     {{t, t, t}, {u, u, u}},
                     {{u, u, u}, {1, 1, 1}},
                     {{0, 0, 0}, {t, t, t}}};
    geo_fbvh *h = geo_fbvh_build(b, 7, NULL);
    assert_non_null(h);
    unsigned char seen[7] = {0};
    geo_qbox all;
    check_fnode(h, 0, b, seen, &all);
    uint32_t slot[7];
    for (uint32_t k = 0; k < 7; k++)
        slot[h->items[k]] = k;
    for (uint32_t i = 0; i < 7; i++)
        for (uint32_t j = 0; j < 7; j++)
            if (geo_bbox_overlap(&b[i], &b[j]))
                assert_true(qbox_overlap(&h->boxes[slot[i]],
                                         &h->boxes[slot[j]]));
    geo_fbvh_free(h);
    /* a small model far from the origin: its cells are its own */
    geo_bbox c[2] = {{{1e6, 1e6, 1e6}, {1e6 + 1e-6, 1e6, 1e6}},
                     {{1e6 + 2e-6, 1e6, 1e6}, {1e6 + 3e-6, 1e6, 1e6}}};
    h = geo_fbvh_build(c, 2, NULL);
    assert_non_null(h);
    assert_false(qbox_overlap(&h->boxes[0], &h->boxes[1]));
    geo_fbvh_free(h);
}

/* Over a polyhedron's facets (the grid from its vertices): the stored
 * boxes are the grid boxes of the facets' exact ones, and the pairs
 * those of the stored boxes, every exactly overlapping pair among them;
 * also with a vertex far out and one unused at infinity. */
static void test_grid_tree_over_facets(void **state)
{
    (void)state;
    geo_poly *s = gs_sphere(5, 1.0);
    assert_non_null(s);
    for (int round = 0; round < 2; round++) {
        if (round == 1) {
            geo_vscale(s->verts[7], 40.0, s->verts[7]);
            const double inf[3] = {INFINITY, 0, -INFINITY};
            assert_true(geo_poly_add_vertex(s, inf) >= 0);
        }
        uint32_t n = s->nfacets;
        geo_bbox *b = malloc(n * sizeof *b);
        assert_non_null(b);
        for (uint32_t f = 0; f < n; f++)
            geo_poly_facet_bbox(s, f, &b[f]);
        geo_fbvh *h = geo_fbvh_build_facets(s, NULL);
        assert_non_null(h);
        unsigned char *seen = calloc(n, 1);
        geo_qbox all;
        check_fnode(h, 0, b, seen, &all);
        for (uint32_t i = 0; i < n; i++)
            assert_int_equal(seen[i], 1);
        uint32_t *slot = malloc(n * sizeof *slot);
        for (uint32_t k = 0; k < n; k++)
            slot[h->items[k]] = k;
        pairs p = {n, calloc((size_t)n * n, 1)};
        geo_fbvh_pairs(h, 0, 0, count_pair, &p);
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = i + 1; j < n; j++) {
                bool f = qbox_overlap(&h->boxes[slot[i]], &h->boxes[slot[j]]);
                assert_int_equal(p.count[(size_t)i * n + j], f ? 1 : 0);
                if (geo_bbox_overlap(&b[i], &b[j]))
                    assert_true(f);
            }
        free(p.count);
        free(slot);
        free(seen);
        geo_fbvh_free(h);
        free(b);
    }
    geo_poly_free(s);
}

static void test_empty_and_single(void **state)
{
    (void)state;
    geo_bvh *h = geo_bvh_build(NULL, 0, NULL);
    assert_non_null(h);
    geo_bbox q = {{0, 0, 0}, {1, 1, 1}};
    unsigned char seen[1] = {0};
    assert_true(geo_bvh_query_box(h, &q, collect, seen));
    uint32_t ta[4], tb[4];
    assert_int_equal(geo_bvh_pair_tasks(h, ta, tb, 4), 0);
    geo_bvh_free(h);
    h = geo_bvh_build(&q, 1, NULL);
    geo_bvh_query_box(h, &q, collect, seen);
    assert_int_equal(seen[0], 1);
    geo_bvh_free(h);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_query_box_matches_brute_force),
        cmocka_unit_test(test_query_plane_is_conservative),
        cmocka_unit_test(test_query_ray_finds_every_hit_box),
        cmocka_unit_test(test_pair_tasks_report_each_overlap_once),
        cmocka_unit_test(test_empty_and_single),
        cmocka_unit_test(test_grid_tree_pairs),
        cmocka_unit_test(test_grid_tree_pairs_without_shared_tags),
        cmocka_unit_test(test_grid_tree_of_equal_and_nan_boxes),
        cmocka_unit_test(test_grid_tree_rounds_outward),
        cmocka_unit_test(test_grid_tree_over_facets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
