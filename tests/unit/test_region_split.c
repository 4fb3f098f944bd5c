/* test_region_split.c — splitting planar regions with holes into simple
 * pieces (lib/cut/region_split.h): every piece is a simple counter-clockwise
 * polygon without a repeated point, the pieces tile the region (every
 * input edge used once in its own direction, every other edge twice in
 * opposite directions by two different pieces, areas adding up), and a
 * part with a hole gives at least two pieces. Annulus, several holes,
 * an island in a hole, holes touching the outer loop or each other at a
 * point (as separate loops and as one loop passing the point twice),
 * random holes and islands, and bad input. */
#include "testutil.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "predicates.h"
#include "region_split.h"

enum { MAXP = 4096, MAXL = 256 };

typedef struct region {
    uint32_t npts, nloops;
    double pts[MAXP][2];
    uint32_t start[MAXL + 1];
    uint32_t idx[MAXP];
} region;

static uint32_t add_pt(region *g, double x, double y)
{
    g->pts[g->npts][0] = x;
    g->pts[g->npts][1] = y;
    return g->npts++;
}

static void begin_loop(region *g)
{
    g->start[g->nloops + 1] = g->start[g->nloops];
}

static void loop_pt(region *g, uint32_t i)
{
    g->idx[g->start[g->nloops + 1]++] = i;
}

static void end_loop(region *g)
{
    g->nloops++;
}

/* A loop through new points given as x, y pairs. */
static void add_loop(region *g, const double (*xy)[2], uint32_t n)
{
    begin_loop(g);
    for (uint32_t i = 0; i < n; i++)
        loop_pt(g, add_pt(g, xy[i][0], xy[i][1]));
    end_loop(g);
}

static double area_of(const double (*P)[2], const uint32_t *v, uint32_t n)
{
    double s = 0;
    for (uint32_t i = 0; i < n; i++) {
        const double *a = P[v[i]], *b = P[v[(i + 1) % n]];
        s += a[0] * b[1] - b[0] * a[1];
    }
    return 0.5 * s;
}

static bool seg_meet(const double *a, const double *b, const double *c,
                     const double *d)
{
    int o1 = geo_orient2d(a, b, c), o2 = geo_orient2d(a, b, d);
    int o3 = geo_orient2d(c, d, a), o4 = geo_orient2d(c, d, b);
    if (o1 * o2 < 0 && o3 * o4 < 0)
        return true;
    for (int k = 0; k < 4; k++) {
        const double *p = k == 0 ? c : k == 1 ? d : k == 2 ? a : b;
        const double *s0 = k < 2 ? a : c, *s1 = k < 2 ? b : d;
        int o = k == 0 ? o1 : k == 1 ? o2 : k == 2 ? o3 : o4;
        if (o == 0 && fmin(s0[0], s1[0]) <= p[0] && p[0] <= fmax(s0[0], s1[0]) &&
            fmin(s0[1], s1[1]) <= p[1] && p[1] <= fmax(s0[1], s1[1]))
            return true;
    }
    return false;
}

/* NULL when piece v[0..n) is a simple counter-clockwise polygon. */
static const char *piece_problem(const double (*P)[2], const uint32_t *v,
                                 uint32_t n)
{
    if (n < 3)
        return "fewer than 3 points";
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = i + 1; j < n; j++)
            if (v[i] == v[j])
                return "a point twice";
    if (!(area_of(P, v, n) > 0))
        return "not counter-clockwise";
    for (uint32_t i = 0; i < n; i++) {
        const double *a = P[v[i]], *b = P[v[(i + 1) % n]];
        for (uint32_t j = i + 1; j < n; j++) {
            const double *c = P[v[j]], *d = P[v[(j + 1) % n]];
            if (j == i + 1 || (i == 0 && j == n - 1)) {
                /* neighbours: they must not fold back onto each other */
                const double *o = j == i + 1 ? b : a;
                const double *x = j == i + 1 ? a : b;
                const double *y = j == i + 1 ? d : c;
                if (geo_orient2d(x, o, y) == 0 &&
                    (x[0] - o[0]) * (y[0] - o[0]) + (x[1] - o[1]) * (y[1] - o[1]) > 0)
                    return "a spike";
                continue;
            }
            if (seg_meet(a, b, c, d))
                return "two edges meet";
        }
    }
    return NULL;
}

typedef struct dedge {
    uint32_t a, b, piece;
    bool input;
} dedge;

static int cmp_dedge(const void *x, const void *y)
{
    const dedge *p = x, *q = y;
    uint32_t pa = p->a < p->b ? p->a : p->b, pb = p->a < p->b ? p->b : p->a;
    uint32_t qa = q->a < q->b ? q->a : q->b, qb = q->a < q->b ? q->b : q->a;
    if (pa != qa)
        return pa < qa ? -1 : 1;
    if (pb != qb)
        return pb < qb ? -1 : 1;
    return (p->input < q->input) - (p->input > q->input);
}

/* Splits g and checks everything in the header; returns the pieces
 * (caller clears) and fails the test on any problem. */
static void split_checked_with(const region *g, const double *perr,
                               geo_region_pieces *rp)
{
    geo_err err = {{0}};
    int r = geo_region_split((const double(*)[2])g->pts, perr, g->npts, g->start,
                             g->idx, g->nloops, rp, &err);
    if (r != 0)
        fail_msg("geo_region_split = %d: %s", r, err.msg);
    const double(*P)[2] = (const double(*)[2])g->pts;
    double want = 0, got = 0, scale = 0;
    for (uint32_t l = 0; l < g->nloops; l++) {
        double a = area_of(P, g->idx + g->start[l], g->start[l + 1] - g->start[l]);
        want += a;
        scale += fabs(a);
    }
    size_t ne = 0, cap = g->start[g->nloops] + 2 * (size_t)rp->start[rp->npieces];
    dedge *e = malloc(cap * sizeof *e);
    assert_non_null(e);
    for (uint32_t l = 0; l < g->nloops; l++)
        for (uint32_t c = g->start[l]; c < g->start[l + 1]; c++) {
            uint32_t d = c + 1 < g->start[l + 1] ? c + 1 : g->start[l];
            e[ne++] = (dedge){g->idx[c], g->idx[d], UINT32_MAX, true};
        }
    for (uint32_t q = 0; q < rp->npieces; q++) {
        const uint32_t *v = rp->idx + rp->start[q];
        uint32_t n = rp->start[q + 1] - rp->start[q];
        const char *bad = piece_problem(P, v, n);
        if (bad)
            fail_msg("piece %u of %u (%u points): %s", q, rp->npieces, n, bad);
        got += area_of(P, v, n);
        assert_true(rp->part[q] < rp->nparts);
        for (uint32_t i = 0; i < n; i++)
            e[ne++] = (dedge){v[i], v[(i + 1) % n], q, false};
    }
    if (!(fabs(got - want) <= 1e-12 * scale))
        fail_msg("pieces' area %.17g, region's %.17g", got, want);
    /* an input edge: once in a piece, in its direction; any other edge:
     * twice, opposite, in two different pieces */
    qsort(e, ne, sizeof *e, cmp_dedge);
    for (size_t i = 0; i < ne;) {
        size_t j = i;
        while (j < ne && cmp_dedge(&e[i], &e[j]) == 0)
            j++;
        size_t k = j;
        /* same undirected edge, any kind */
        while (k < ne && ((e[k].a == e[i].a && e[k].b == e[i].b) ||
                          (e[k].a == e[i].b && e[k].b == e[i].a)))
            k++;
        if (e[i].input) {
            /* input edges come first for their key */
            uint32_t nin = (uint32_t)(j - i), used = 0;
            for (size_t x = j; x < k; x++) {
                if (e[x].a != e[i].a || e[x].b != e[i].b)
                    fail_msg("input edge %u-%u used backwards", e[i].a, e[i].b);
                used++;
            }
            if (used != nin)
                fail_msg("input edge %u-%u used %u times", e[i].a, e[i].b, used);
        } else {
            if (k - i != 2 || e[i].a != e[i + 1].b || e[i].piece == e[i + 1].piece)
                fail_msg("diagonal %u-%u: %zu uses", e[i].a, e[i].b, k - i);
        }
        i = k;
    }
    free(e);
}

static void split_checked(const region *g, geo_region_pieces *rp)
{
    split_checked_with(g, NULL, rp);
}

static uint32_t pieces_of_part(const geo_region_pieces *rp, uint32_t part)
{
    uint32_t n = 0;
    for (uint32_t q = 0; q < rp->npieces; q++)
        n += rp->part[q] == part;
    return n;
}

static const double sq10[4][2] = {{0, 0}, {10, 0}, {10, 10}, {0, 10}};

static void test_annulus_gives_two_pieces(void **state)
{
    (void)state;
    static region g;
    memset(&g, 0, sizeof g);
    static const double hole[4][2] = {{3, 3}, {3, 7}, {7, 7}, {7, 3}};
    add_loop(&g, sq10, 4);
    add_loop(&g, hole, 4);
    geo_region_pieces rp;
    split_checked(&g, &rp);
    assert_int_equal(rp.nparts, 1);
    assert_int_equal(rp.nholes, 1);
    assert_int_equal(rp.nsplit, 1);
    assert_int_equal(rp.npieces, 2);
    geo_region_pieces_clear(&rp);
}

static void test_simple_parts_are_returned_unchanged(void **state)
{
    (void)state;
    static region g;
    memset(&g, 0, sizeof g);
    static const double u[8][2] = {{0, 0}, {10, 0}, {10, 10}, {7, 10},
                                   {7, 3},  {3, 3},  {3, 10},  {0, 10}};
    static const double far[3][2] = {{20, 0}, {25, 0}, {20, 5}};
    add_loop(&g, u, 8);
    add_loop(&g, far, 3);
    geo_region_pieces rp;
    split_checked(&g, &rp);
    assert_int_equal(rp.nparts, 2);
    assert_int_equal(rp.nsplit, 0);
    assert_int_equal(rp.npieces, 2);
    assert_memory_equal(rp.idx, g.idx, 11 * sizeof *g.idx);
    geo_region_pieces_clear(&rp);
}

static void test_several_holes(void **state)
{
    (void)state;
    for (int nh = 2; nh <= 3; nh++) {
        static region g;
        memset(&g, 0, sizeof g);
        static const double wide[4][2] = {{0, 0}, {30, 0}, {30, 10}, {0, 10}};
        add_loop(&g, wide, 4);
        for (int h = 0; h < nh; h++) {
            double x = 3 + 9 * h;
            const double hole[4][2] = {{x, 3}, {x, 7}, {x + 4, 7}, {x + 4, 3}};
            add_loop(&g, hole, 4);
        }
        geo_region_pieces rp;
        split_checked(&g, &rp);
        assert_int_equal(rp.nholes, nh);
        assert_true(rp.npieces >= 2);
        print_message("# %d holes in a row: %u pieces\n", nh, rp.npieces);
        geo_region_pieces_clear(&rp);
    }
}

static void test_island_in_a_hole_is_a_part_of_its_own(void **state)
{
    (void)state;
    static region g;
    memset(&g, 0, sizeof g);
    static const double hole[4][2] = {{2, 2}, {2, 8}, {8, 8}, {8, 2}};
    static const double island[4][2] = {{4, 4}, {6, 4}, {6, 6}, {4, 6}};
    static const double inner[3][2] = {{4.5, 4.5}, {5, 5.5}, {5.5, 4.5}};
    add_loop(&g, island, 4); /* parts are numbered in loop order */
    add_loop(&g, sq10, 4);
    add_loop(&g, hole, 4);
    geo_region_pieces rp;
    split_checked(&g, &rp);
    assert_int_equal(rp.nparts, 2);
    assert_int_equal(pieces_of_part(&rp, 0), 1);
    assert_true(pieces_of_part(&rp, 1) >= 2);
    geo_region_pieces_clear(&rp);
    /* and a hole in the island: it belongs to the island, not the frame */
    add_loop(&g, inner, 3);
    split_checked(&g, &rp);
    assert_int_equal(rp.nholes, 2);
    assert_true(pieces_of_part(&rp, 0) >= 2);
    assert_true(pieces_of_part(&rp, 1) >= 2);
    geo_region_pieces_clear(&rp);
}

static void test_hole_touching_outer_loop_at_a_point(void **state)
{
    (void)state;
    /* as separate loops sharing the point (10, 5) */
    static region g;
    memset(&g, 0, sizeof g);
    uint32_t o[5], h[2];
    static const double out5[5][2] = {{0, 0}, {10, 0}, {10, 5}, {10, 10}, {0, 10}};
    begin_loop(&g);
    for (int i = 0; i < 5; i++)
        loop_pt(&g, o[i] = add_pt(&g, out5[i][0], out5[i][1]));
    end_loop(&g);
    h[0] = add_pt(&g, 6, 4);
    h[1] = add_pt(&g, 6, 6);
    begin_loop(&g);
    loop_pt(&g, o[2]), loop_pt(&g, h[0]), loop_pt(&g, h[1]);
    end_loop(&g);
    geo_region_pieces rp;
    split_checked(&g, &rp);
    assert_int_equal(rp.npieces, 2);
    geo_region_pieces_clear(&rp);
    /* as one loop passing (10, 5) twice, the way a section's boundary
     * is walked */
    g.nloops = 0;
    g.start[0] = 0;
    begin_loop(&g);
    uint32_t walk[8] = {o[0], o[1], o[2], h[0], h[1], o[2], o[3], o[4]};
    for (int i = 0; i < 8; i++)
        loop_pt(&g, walk[i]);
    end_loop(&g);
    split_checked(&g, &rp);
    assert_int_equal(rp.nsplit, 1);
    assert_int_equal(rp.npieces, 2);
    geo_region_pieces_clear(&rp);
    /* a hole touching the outer loop at two points cuts the square in
     * two parts that are not given as loops of their own: refused */
    g.nloops = 0;
    g.npts = 0;
    g.start[0] = 0;
    static const double out6[6][2] = {{0, 0}, {5, 0}, {10, 0}, {10, 10}, {5, 10}, {0, 10}};
    begin_loop(&g);
    uint32_t q[6];
    for (int i = 0; i < 6; i++)
        loop_pt(&g, q[i] = add_pt(&g, out6[i][0], out6[i][1]));
    end_loop(&g);
    uint32_t l = add_pt(&g, 4, 5), r = add_pt(&g, 6, 5);
    begin_loop(&g);
    loop_pt(&g, q[1]), loop_pt(&g, l), loop_pt(&g, q[4]), loop_pt(&g, r);
    end_loop(&g);
    geo_err err = {{0}};
    assert_int_equal(geo_region_split((const double(*)[2])g.pts, NULL, g.npts, g.start,
                                      g.idx, g.nloops, &rp, &err), -EINVAL);
    assert_non_null(strstr(err.msg, "more than one point"));
}

static void test_holes_touching_each_other(void **state)
{
    (void)state;
    static region g;
    memset(&g, 0, sizeof g);
    add_loop(&g, sq10, 4);
    uint32_t c = add_pt(&g, 5, 5);
    uint32_t a[2] = {add_pt(&g, 2, 4), add_pt(&g, 2, 6)};
    uint32_t b[2] = {add_pt(&g, 8, 6), add_pt(&g, 8, 4)};
    begin_loop(&g);
    loop_pt(&g, c), loop_pt(&g, a[0]), loop_pt(&g, a[1]);
    end_loop(&g);
    begin_loop(&g);
    loop_pt(&g, c), loop_pt(&g, b[0]), loop_pt(&g, b[1]);
    end_loop(&g);
    geo_region_pieces rp;
    split_checked(&g, &rp);
    assert_int_equal(rp.nholes, 2);
    geo_region_pieces_clear(&rp);
    /* the same two holes as one clockwise loop through c twice */
    g.nloops = 1;
    begin_loop(&g);
    uint32_t w[6] = {c, a[0], a[1], c, b[0], b[1]};
    for (int i = 0; i < 6; i++)
        loop_pt(&g, w[i]);
    end_loop(&g);
    split_checked(&g, &rp);
    assert_int_equal(rp.nholes, 1);
    geo_region_pieces_clear(&rp);
}

static void test_collinear_points_and_bridge_along_edges(void **state)
{
    (void)state;
    /* points of the outer loop and the hole on common lines: candidate
     * bridges run along edges or through points and must be skipped */
    static region g;
    memset(&g, 0, sizeof g);
    static const double out8[8][2] = {{0, 0}, {5, 0}, {10, 0}, {10, 5},
                                      {10, 10}, {5, 10}, {0, 10}, {0, 5}};
    static const double hole8[8][2] = {{3, 3}, {3, 5}, {3, 7}, {5, 7},
                                       {7, 7}, {7, 5}, {7, 3}, {5, 3}};
    add_loop(&g, out8, 8);
    add_loop(&g, hole8, 8);
    geo_region_pieces rp;
    split_checked(&g, &rp);
    assert_true(rp.npieces >= 2);
    geo_region_pieces_clear(&rp);
}

/* A loop around (cx, cy), star-shaped from there (k ≥ 4 points at
 * angles at most 3π/k apart, radii in [0.35 r, r]), counter-clockwise or
 * clockwise. */
static void star_loop(region *g, uint64_t *seed, double cx, double cy,
                      double r, uint32_t k, bool ccw)
{
    double ang[64];
    for (uint32_t i = 0; i < k; i++)
        ang[i] = 2 * M_PI * (i + 0.5 * geo_rand_unit(seed)) / k;
    begin_loop(g);
    for (uint32_t i = 0; i < k; i++) {
        uint32_t j = ccw ? i : k - 1 - i;
        double rad = r * (0.35 + 0.65 * geo_rand_unit(seed));
        loop_pt(g, add_pt(g, cx + rad * cos(ang[j]), cy + rad * sin(ang[j])));
    }
    end_loop(g);
}

static void test_random_holes_and_islands(void **state)
{
    (void)state;
    uint64_t seed = 77;
    static region g;
    uint32_t total_pieces = 0, total_holes = 0;
    for (int trial = 0; trial < 300; trial++) {
        memset(&g, 0, sizeof g);
        uint32_t cells = 1 + (uint32_t)(geo_rand_unit(&seed) * 5);
        double size = 10.0 * cells;
        /* a jagged counter-clockwise outer loop around [0, size]² */
        begin_loop(&g);
        uint32_t per = 2 + (uint32_t)(geo_rand_unit(&seed) * 6);
        static const double corner[4][2] = {{-2, -2}, {1, -2}, {1, 1}, {-2, 1}};
        for (int side = 0; side < 4; side++) {
            loop_pt(&g, add_pt(&g, corner[side][0] < 0 ? -2 : size + 2,
                               corner[side][1] < 0 ? -2 : size + 2));
            for (uint32_t i = 1; i < per; i++) {
                double t = (double)i / per * size, jag = 2.0 * geo_rand_unit(&seed);
                double x = side == 0 ? t : side == 1 ? size + jag
                         : side == 2 ? size - t : -jag;
                double y = side == 0 ? -jag : side == 1 ? t
                         : side == 2 ? size + jag : size - t;
                loop_pt(&g, add_pt(&g, x, y));
            }
        }
        end_loop(&g);
        for (uint32_t cx = 0; cx < cells; cx++)
            for (uint32_t cy = 0; cy < cells; cy++) {
                if (geo_rand_unit(&seed) < 0.3)
                    continue;
                double x = 10.0 * cx + 5, y = 10.0 * cy + 5;
                uint32_t k = 4 + (uint32_t)(geo_rand_unit(&seed) * 10);
                star_loop(&g, &seed, x, y, 4.5, k, false);
                total_holes++;
                if (k >= 6 && geo_rand_unit(&seed) < 0.4) {
                    /* an island well inside the hole (its edges keep at
                     * least 4.5 · 0.35 · cos 45° from the centre) */
                    star_loop(&g, &seed, x, y, 1.0, 3 + k % 5, true);
                }
            }
        geo_region_pieces rp;
        split_checked(&g, &rp);
        total_pieces += rp.npieces;
        geo_region_pieces_clear(&rp);
    }
    print_message("# %u holes, %u pieces\n", total_holes, total_pieces);
}

/* Smallest distance from a point to a piece edge that is not an input
 * edge and does not end at that point (floating point). */
static double nearest_pass(const region *g, const geo_region_pieces *rp,
                           uint32_t *ret_point)
{
    double best = INFINITY;
    for (uint32_t q = 0; q < rp->npieces; q++) {
        const uint32_t *v = rp->idx + rp->start[q];
        uint32_t n = rp->start[q + 1] - rp->start[q];
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = v[i], b = v[(i + 1) % n];
            bool input = false;
            for (uint32_t l = 0; l < g->nloops && !input; l++)
                for (uint32_t c = g->start[l]; c < g->start[l + 1]; c++) {
                    uint32_t d = c + 1 < g->start[l + 1] ? c + 1 : g->start[l];
                    input |= g->idx[c] == a && g->idx[d] == b;
                }
            if (input)
                continue;
            const double *A = g->pts[a], *B = g->pts[b];
            for (uint32_t x = 0; x < g->npts; x++) {
                if (x == a || x == b)
                    continue;
                const double *X = g->pts[x];
                double dx = B[0] - A[0], dy = B[1] - A[1];
                double t = ((X[0] - A[0]) * dx + (X[1] - A[1]) * dy) /
                           (dx * dx + dy * dy);
                t = t < 0 ? 0 : t > 1 ? 1 : t;
                double d = hypot(X[0] - A[0] - t * dx, X[1] - A[1] - t * dy);
                if (d < best) {
                    best = d;
                    *ret_point = x;
                }
            }
        }
    }
    return best;
}

/* A hair of rounding: a random offset below 2e-15. */
static double hair(uint64_t *seed)
{
    return (geo_rand_unit(seed) - 0.5) * 4e-15;
}

static void test_bounds_keep_diagonals_off_straight_runs(void **state)
{
    (void)state;
    /* A 9 × 5 rectangle with a point at every unit of its sides and
     * unit-square holes on a grid: sides and holes' edges lie on common
     * lines, each point a random hair off them, as the crossings of a
     * plane with facets meeting in one plane are. On the positions alone
     * a diagonal may run along such a line a hair from a point (and a
     * piece may be a sliver); with the bounds, none comes closer to a
     * point than its bound. */
    uint64_t seed = 5;
    static region g;
    double perr[MAXP];
    int near_without = 0;
    for (int trial = 0; trial < 300; trial++) {
        memset(&g, 0, sizeof g);
        const int w = 9, h = 5;
        begin_loop(&g);
        for (int x = 0; x < w; x++)
            loop_pt(&g, add_pt(&g, x ? x + hair(&seed) : 0, x ? hair(&seed) : 0));
        for (int y = 0; y < h; y++)
            loop_pt(&g, add_pt(&g, w + hair(&seed), y));
        for (int x = w; x > 0; x--)
            loop_pt(&g, add_pt(&g, x, h + hair(&seed)));
        for (int y = h; y > 0; y--)
            loop_pt(&g, add_pt(&g, hair(&seed), y));
        end_loop(&g);
        for (int cx = 1; cx < w - 1; cx += 2)
            for (int cy = 1; cy < h - 1; cy += 2) {
                if (geo_rand_unit(&seed) < 0.3)
                    continue;
                const double hx[4] = {cx, cx, cx + 1, cx + 1};
                const double hy[4] = {cy, cy + 1, cy + 1, cy};
                begin_loop(&g);
                for (int k = 0; k < 4; k++)
                    loop_pt(&g, add_pt(&g, hx[k] + hair(&seed), hy[k] + hair(&seed)));
                end_loop(&g);
            }
        for (uint32_t i = 0; i < g.npts; i++)
            perr[i] = 1e-14;
        geo_region_pieces rp;
        split_checked_with(&g, perr, &rp);
        assert_int_equal(rp.nfallback, 0);
        uint32_t x = 0;
        double d = nearest_pass(&g, &rp, &x);
        if (!(d > 1e-14))
            fail_msg("trial %d: a diagonal passes %g from point %u", trial, d, x);
        geo_region_pieces_clear(&rp);
        geo_err err = {{0}};
        assert_int_equal(geo_region_split((const double(*)[2])g.pts, NULL, g.npts,
                                          g.start, g.idx, g.nloops, &rp, &err), 0);
        near_without += !(nearest_pass(&g, &rp, &x) > 1e-14);
        geo_region_pieces_clear(&rp);
    }
    /* what the bounds are for (and why the check above is not vacuous) */
    print_message("# on the positions alone, %d of 300 splits had a diagonal "
                  "a hair from a point\n", near_without);
    assert_true(near_without > 0);
}

static void test_rejects_bad_input(void **state)
{
    (void)state;
    static region g;
    memset(&g, 0, sizeof g);
    static const double line[3][2] = {{0, 0}, {1, 1}, {2, 2}};
    add_loop(&g, line, 3);
    geo_region_pieces rp;
    geo_err err = {{0}};
    const double(*P)[2] = (const double(*)[2])g.pts;
    assert_int_equal(geo_region_split(P, NULL, g.npts, g.start, g.idx, g.nloops, &rp, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "zero area"));
    assert_int_equal(rp.npieces, 0);
    /* a hole outside every part */
    memset(&g, 0, sizeof g);
    static const double cw[3][2] = {{0, 0}, {0, 1}, {1, 0}};
    add_loop(&g, cw, 3);
    assert_int_equal(geo_region_split(P, NULL, g.npts, g.start, g.idx, g.nloops, &rp, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "not inside"));
    /* two indices at one position */
    memset(&g, 0, sizeof g);
    static const double twin[4][2] = {{0, 0}, {1, 0}, {1, 0}, {0, 1}};
    add_loop(&g, twin, 4);
    assert_int_equal(geo_region_split(P, NULL, g.npts, g.start, g.idx, g.nloops, &rp, &err),
                     -EINVAL);
    assert_non_null(strstr(err.msg, "same position"));
    /* index out of range */
    g.idx[1] = 99;
    assert_int_equal(geo_region_split(P, NULL, g.npts, g.start, g.idx, g.nloops, &rp, &err),
                     -EINVAL);
    /* a hole crossing the outer loop: no valid bridge or ear */
    memset(&g, 0, sizeof g);
    static const double crossing[4][2] = {{8, 3}, {8, 7}, {12, 7}, {12, 3}};
    add_loop(&g, sq10, 4);
    add_loop(&g, crossing, 4);
    int r = geo_region_split(P, NULL, g.npts, g.start, g.idx, g.nloops, &rp, &err);
    assert_int_equal(r, -EINVAL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_annulus_gives_two_pieces),
        cmocka_unit_test(test_simple_parts_are_returned_unchanged),
        cmocka_unit_test(test_several_holes),
        cmocka_unit_test(test_island_in_a_hole_is_a_part_of_its_own),
        cmocka_unit_test(test_hole_touching_outer_loop_at_a_point),
        cmocka_unit_test(test_holes_touching_each_other),
        cmocka_unit_test(test_collinear_points_and_bridge_along_edges),
        cmocka_unit_test(test_random_holes_and_islands),
        cmocka_unit_test(test_bounds_keep_diagonals_off_straight_runs),
        cmocka_unit_test(test_rejects_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
