/* selfint.c — exact facet/facet and facet/self intersection tests and the
 * parallel BVH pair search behind geo_selfint_find (model: selfint.h).
 *
 * Invariants: every decision is a sign from lib/core/predicates.h on input
 * coordinates; a vertex listed by a facet is on that facet's reference
 * plane by definition (side 0), so contacts at shared vertices and along
 * shared edges are recognised by index, never by coordinates. Results do
 * not depend on the order in which pairs are tested. */
#include "selfint.h"

#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "fbvh.h"
#include "predicates.h"
#include "vec.h"

/* ---------------------------------------------------------------- 2D */

static inline void proj(const double p[3], int axis, double r[2])
{
    r[0] = p[(axis + 1) % 3];
    r[1] = p[(axis + 2) % 3];
}

static inline int cmp(double a, double b)
{
    return (a > b) - (a < b);
}

static inline const double *V(const geo_poly *p, uint32_t v)
{
    return p->verts[v];
}

/* q, known to lie on the line ab, lies on the closed segment ab. */
static bool on_segment(const double a[2], const double b[2], const double q[2])
{
    for (int k = 0; k < 2; k++) {
        double lo = a[k] < b[k] ? a[k] : b[k], hi = a[k] < b[k] ? b[k] : a[k];
        if (q[k] < lo || q[k] > hi)
            return false;
    }
    return true;
}

/* Collinear closed segments ab and cd: do they share a point other than
 * a (when excl_a) or b (when excl_b)? Compared along the coordinate in
 * which the four points spread most (exact comparisons). */
static bool collinear_contact(const double a[2], const double b[2],
                              bool excl_a, bool excl_b, const double c[2],
                              const double d[2])
{
    double e0 = fabs(a[0] - b[0]) + fabs(c[0] - d[0]) + fabs(a[0] - c[0]);
    double e1 = fabs(a[1] - b[1]) + fabs(c[1] - d[1]) + fabs(a[1] - c[1]);
    int k = e0 >= e1 ? 0 : 1;
    double lo1 = fmin(a[k], b[k]), hi1 = fmax(a[k], b[k]);
    double lo2 = fmin(c[k], d[k]), hi2 = fmax(c[k], d[k]);
    double lo = fmax(lo1, lo2), hi = fmin(hi1, hi2);
    if (lo > hi)
        return false;
    if (lo < hi)
        return true;
    /* a single common point, at coordinate lo: is it an excluded end? */
    if (excl_a && a[k] == lo)
        return false;
    if (excl_b && b[k] == lo)
        return false;
    return true;
}

/* Do closed segments ab and cd share a point other than a (excl_a) or
 * b (excl_b)? */
static bool seg_contact(const double a[2], const double b[2], bool excl_a,
                        bool excl_b, const double c[2], const double d[2])
{
    int o1 = geo_orient2d(a, b, c), o2 = geo_orient2d(a, b, d);
    if (o1 == 0 && o2 == 0)
        return collinear_contact(a, b, excl_a, excl_b, c, d);
    if (o1 * o2 > 0)
        return false;
    int o3 = geo_orient2d(c, d, a), o4 = geo_orient2d(c, d, b);
    if (o3 * o4 > 0)
        return false;
    /* one common point; it is a when a lies on line cd (the lines differ) */
    if (o3 == 0 && excl_a)
        return false;
    if (o4 == 0 && excl_b)
        return false;
    return true;
}

/* Winding test of q against facet f projected by `axis`: +1 inside, 0 on
 * the boundary, −1 outside (Sunday's crossing rule, exact). */
static int point_in_facet2(const geo_poly *p, uint32_t f, int axis,
                           const double q[2])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *fv = geo_poly_facet(p, f);
    double a[2], b[2];
    int wn = 0;
    proj(V(p, fv[n - 1]), axis, a);
    for (uint32_t i = 0; i < n; i++) {
        proj(V(p, fv[i]), axis, b);
        int o = geo_orient2d(a, b, q);
        if (o == 0 && on_segment(a, b, q))
            return 0;
        if (a[1] <= q[1]) {
            if (b[1] > q[1] && o > 0)
                wn++;
        } else if (b[1] <= q[1] && o < 0) {
            wn--;
        }
        a[0] = b[0], a[1] = b[1];
    }
    return wn ? 1 : -1;
}

/* Does the direction from vertex k of facet f towards q point strictly
 * into the facet (2D, projected by axis, polygon turn `turn`)? */
static bool wedge_inside(const geo_poly *p, uint32_t f, int axis, int turn,
                         uint32_t k, const double q[2])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *fv = geo_poly_facet(p, f);
    double u[2], v[2], x[2];
    proj(V(p, fv[(k + n - 1) % n]), axis, u);
    proj(V(p, fv[k]), axis, v);
    proj(V(p, fv[(k + 1) % n]), axis, x);
    int corner = geo_orient2d(u, v, x) * turn;
    int l1 = geo_orient2d(u, v, q) * turn, l2 = geo_orient2d(v, x, q) * turn;
    if (corner > 0)
        return l1 > 0 && l2 > 0;
    if (corner < 0)
        return l1 > 0 || l2 > 0;
    /* flat corner: interior is left of the line, unless x turns back */
    for (int c = 0; c < 2; c++) {
        int s1 = cmp(v[c], u[c]), s2 = cmp(x[c], v[c]);
        if (s1 != 0)
            return s2 == s1 && l1 > 0;
    }
    return false;
}

/* ------------------------------------------------------------ shapes */

static bool collinear3(const double a[3], const double b[3], const double c[3])
{
    return geo_orient2d_proj(a, b, c, 0) == 0 &&
           geo_orient2d_proj(a, b, c, 1) == 0 &&
           geo_orient2d_proj(a, b, c, 2) == 0;
}

/* The turn (+1 counter-clockwise, −1 clockwise) of facet f projected by
 * dropping `axis`: exact at the lexicographically lowest projected vertex
 * (a convex corner of a simple polygon); the Newell normal's sign when that
 * corner is flat. */
static int turn_in_axis(const geo_poly *p, uint32_t f, int axis)
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *fv = geo_poly_facet(p, f);
    uint32_t lo = 0;
    double lp[2];
    proj(V(p, fv[0]), axis, lp);
    for (uint32_t i = 1; i < n; i++) {
        double q[2];
        proj(V(p, fv[i]), axis, q);
        if (q[0] < lp[0] || (q[0] == lp[0] && q[1] < lp[1]))
            lo = i, lp[0] = q[0], lp[1] = q[1];
    }
    int t = geo_orient2d_proj(V(p, fv[(lo + n - 1) % n]), V(p, fv[lo]),
                              V(p, fv[(lo + 1) % n]), axis);
    if (t == 0) {
        double nw[3];
        geo_poly_facet_area_vector(p, f, nw);
        t = nw[axis] < 0 ? -1 : 1;
    }
    return t;
}

/* The first of the facet's vertices fv[0..n) farthest from x (by the
 * rounded distance, ties to the first). The square root is taken only
 * for a squared distance above every one before: a smaller or equal one
 * cannot have a larger root. */
static inline uint32_t farthest(const geo_poly *p, const uint32_t *fv,
                                uint32_t n, const double x[3])
{
    uint32_t k = 0;
    double best = -1, best2 = -1;
    for (uint32_t i = 0; i < n; i++) {
        double d[3];
        geo_vsub(V(p, fv[i]), x, d);
        double d2 = geo_vdot(d, d);
        if (!(d2 > best2))
            continue;
        best2 = d2;
        double len = sqrt(d2);
        if (len > best)
            best = len, k = i;
    }
    return k;
}

/* Whether facet fv[0..n) is a strictly convex polygon in the projection
 * dropping `axis`, turning `turn`: every corner turns strictly that way
 * (corner[i] · turn > 0 for the exact corner signs given) and the edge
 * direction goes round once. Each edge turns the direction by less than
 * a half turn, so its half plane (upper: y > 0, or y = 0 and x > 0;
 * exact comparisons of coordinates) changes at most once per corner and
 * twice per revolution: twice in all means once round. A closed polygon
 * turning one way at every corner and once round in all is the boundary
 * of a convex polygon — simple, so the pairwise edge test is not
 * needed. False means "not shown", not "not convex". */
static bool strictly_convex(const geo_poly *p, const uint32_t *fv, uint32_t n,
                            int axis, int turn, const int8_t *corner)
{
    for (uint32_t i = 0; i < n; i++)
        if (corner[i] * turn <= 0)
            return false;
    int u = (axis + 1) % 3, w = (axis + 2) % 3;
    uint32_t changes = 0;
    const double *a = V(p, fv[n - 1]), *b = V(p, fv[0]);
    /* the half plane without short-circuit branches (unpredictable) */
    int up = (b[w] > a[w]) | ((b[w] == a[w]) & (b[u] > a[u]));
    for (uint32_t i = 0; i < n; i++) {
        a = b;
        b = V(p, fv[i + 1 < n ? i + 1 : 0]);
        int next = (b[w] > a[w]) | ((b[w] == a[w]) & (b[u] > a[u]));
        changes += (uint32_t)(next ^ up);
        up = next;
    }
    return changes == 2;
}

/* geo_facet_shape_of, inlined at each call below so that the triangle's
 * instance (n = 3, most facets of a mesh) has its loops unrolled. */
static inline __attribute__((always_inline)) void
shape_of(const geo_poly *p, uint32_t f, const uint32_t *fv, uint32_t n,
         geo_facet_shape *ret)
{
    memset(ret, 0, sizeof *ret);
    ret->turn = 1;
    ret->axis = 2;

    /* a: farthest from the vertex mean; b: farthest from a; c: largest
     * triangle with a, b. Chosen in floating point, checked exactly. */
    double m[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++)
        geo_vadd(m, V(p, fv[i]), m);
    geo_vscale(m, 1.0 / n, m);
    uint32_t ia = farthest(p, fv, n, m), ib = farthest(p, fv, n, V(p, fv[ia])),
             ic = 0;
    double best;
    const double *A = V(p, fv[ia]), *B = V(p, fv[ib]);
    if (A[0] == B[0] && A[1] == B[1] && A[2] == B[2]) {
        ret->degenerate = true; /* a single distinct point */
        ret->ref[0] = ret->ref[1] = ret->ref[2] = fv[0];
        return;
    }
    best = -1;
    double ab[3], nrm[3] = {0, 0, 0};
    geo_vsub(B, A, ab);
    for (uint32_t i = 0; i < n; i++) {
        double ac[3], c[3];
        geo_vsub(V(p, fv[i]), A, ac);
        geo_vcross(ab, ac, c);
        double d = geo_vdot(c, c);
        /* selections, not a branch: the first largest */
        ic = d > best ? i : ic;
        best = d > best ? d : best;
    }
    if (best > -1) { /* the cross product again, for the chosen vertex */
        double ac[3];
        geo_vsub(V(p, fv[ic]), A, ac);
        geo_vcross(ab, ac, nrm);
    }
    if (collinear3(A, B, V(p, fv[ic]))) {
        /* rounding may hide a non-collinear vertex: look exactly */
        ic = n;
        for (uint32_t i = 0; i < n && ic == n; i++)
            if (!collinear3(A, B, V(p, fv[i])))
                ic = i;
        if (ic == n) {
            ret->degenerate = true;
            ret->ref[0] = fv[ia], ret->ref[1] = fv[ib], ret->ref[2] = fv[ia];
            return;
        }
        double ac[3];
        geo_vsub(V(p, fv[ic]), A, ac);
        geo_vcross(ab, ac, nrm);
    }
    ret->ref[0] = fv[ia], ret->ref[1] = fv[ib], ret->ref[2] = fv[ic];
    int axis = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(nrm[k]) > fabs(nrm[axis]))
            axis = k;
    ret->axis = (int8_t)axis;
    if (n == 3) {
        /* a triangle's three corners turn alike (cyclic rotations of
         * one orient2d); three non-collinear points bound a convex
         * polygon that cannot touch itself: no corner and no edge tests,
         * the answers the general path gives */
        ret->turn = (int8_t)geo_orient2d_proj(V(p, fv[0]), V(p, fv[1]),
                                              V(p, fv[2]), axis);
        if (ret->turn == 0) {
            double nw[3];
            geo_poly_facet_area_vector(p, f, nw);
            ret->turn = nw[axis] < 0 ? -1 : 1;
        }
        ret->simple = ret->convex = true;
        return;
    }

    /* each corner's exact turn, once: the polygon's turn (at its lowest
     * projected vertex, as turn_in_axis), the convexity test and the
     * strictly convex shortcut of the simplicity test all read them
     * (facets of more than 64 vertices: turn_in_axis and the pairwise
     * test) */
    enum { SMALL = 64 };
    int8_t corner[SMALL] = {0};
    bool shortcut = n <= SMALL;
    if (shortcut) {
        int u = (axis + 1) % 3, w = (axis + 2) % 3;
        uint32_t lo = 0;
        for (uint32_t i = 0; i < n; i++) {
            const double *x = V(p, fv[i]), *l = V(p, fv[lo]);
            lo = x[u] < l[u] || (x[u] == l[u] && x[w] < l[w]) ? i : lo;
            corner[i] = (int8_t)geo_orient2d_proj(
                V(p, fv[i ? i - 1 : n - 1]), x, V(p, fv[i + 1 < n ? i + 1 : 0]),
                axis);
        }
        ret->turn = corner[lo];
        if (ret->turn == 0) {
            double nw[3];
            geo_poly_facet_area_vector(p, f, nw);
            ret->turn = nw[axis] < 0 ? -1 : 1;
        }
    } else {
        ret->turn = (int8_t)turn_in_axis(p, f, axis);
    }
    if (shortcut && strictly_convex(p, fv, n, axis, ret->turn, corner)) {
        ret->simple = ret->convex = true;
        return;
    }
    ret->simple = !geo_facet_self_intersects(p, f, ret);
    ret->convex = ret->simple;
    for (uint32_t i = 0; i < n && ret->convex; i++)
        ret->convex = (shortcut ? corner[i]
                                : geo_orient2d_proj(V(p, fv[(i + n - 1) % n]),
                                                    V(p, fv[i]),
                                                    V(p, fv[(i + 1) % n]),
                                                    axis)) *
                          ret->turn >= 0;
}

void geo_facet_shape_of(const geo_poly *p, uint32_t f, geo_facet_shape *ret)
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *fv = geo_poly_facet(p, f);
    if (n == 3)
        shape_of(p, f, fv, 3, ret);
    else
        shape_of(p, f, fv, n, ret);
}

/* ------------------------------------------------ own-polygon tests */

/* Edges i and j (i < j) of facet f (n vertices fv, projected by axis)
 * meet other than at a vertex both list. */
static bool edges_meet(const geo_poly *p, const uint32_t *fv, uint32_t n,
                       int axis, uint32_t i, uint32_t j)
{
    uint32_t i1 = (i + 1) % n, j1 = (j + 1) % n;
    double a[2], b[2], c[2], d[2];
    proj(V(p, fv[i]), axis, a);
    proj(V(p, fv[i1]), axis, b);
    proj(V(p, fv[j]), axis, c);
    proj(V(p, fv[j1]), axis, d);
    if (i1 == j || j1 == i) {
        /* consecutive edges x→y→z: beyond y they meet only when z turns
         * straight back along x→y (a spike); one orient2d, never on a
         * repeated point */
        const double *x = i1 == j ? a : c, *y = i1 == j ? b : a,
                     *z = i1 == j ? d : b;
        if (geo_orient2d(x, y, z) != 0)
            return false;
        /* collinear: overlap when z lies on y's side towards x; two
         * coincident vertices touch as well */
        int k = x[0] != y[0] ? 0 : 1;
        if (x[k] == y[k] || (y[0] == z[0] && y[1] == z[1]))
            return true;
        return cmp(z[k], y[k]) == cmp(x[k], y[k]);
    }
    bool excl_a = fv[i] == fv[j] || fv[i] == fv[j1];
    bool excl_b = fv[i1] == fv[j] || fv[i1] == fv[j1];
    return seg_contact(a, b, excl_a, excl_b, c, d);
}

typedef struct edge_span {
    double lo, hi;
    uint32_t i;
} edge_span;

static int cmp_span(const void *x, const void *y)
{
    const edge_span *a = x, *b = y;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    return (a->i > b->i) - (a->i < b->i);
}

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

/* A vertex index listed twice. */
static bool repeats_index(const uint32_t *fv, uint32_t n, uint32_t *scratch)
{
    if (!scratch) {
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = i + 1; j < n; j++)
                if (fv[i] == fv[j])
                    return true;
        return false;
    }
    memcpy(scratch, fv, n * sizeof *fv);
    qsort(scratch, n, sizeof *scratch, cmp_u32);
    for (uint32_t i = 1; i < n; i++)
        if (scratch[i] == scratch[i - 1])
            return true;
    return false;
}

bool geo_facet_self_intersects(const geo_poly *p, uint32_t f,
                               const geo_facet_shape *s)
{
    if (s->degenerate)
        return false;
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *fv = geo_poly_facet(p, f);
    if (n == 3)
        return false; /* a triangle of three distinct, non-collinear
                         points never touches itself */
    int axis = s->axis;
    enum { SMALL = 24 };
    /* large facets: sweep along the first projected coordinate so only
     * edges with overlapping extents are compared; without memory for
     * it, the plain O(n²) loop gives the same answer */
    edge_span *spans = n > SMALL ? malloc(n * sizeof *spans) : NULL;
    uint32_t *ids = n > SMALL ? malloc(n * sizeof *ids) : NULL;
    bool hit = repeats_index(fv, n, ids);
    if (!hit && !spans) {
        for (uint32_t i = 0; i < n && !hit; i++)
            for (uint32_t j = i + 1; j < n && !hit; j++)
                hit = edges_meet(p, fv, n, axis, i, j);
    } else if (!hit) {
        for (uint32_t i = 0; i < n; i++) {
            double a[2], b[2];
            proj(V(p, fv[i]), axis, a);
            proj(V(p, fv[(i + 1) % n]), axis, b);
            spans[i].lo = fmin(a[0], b[0]);
            spans[i].hi = fmax(a[0], b[0]);
            spans[i].i = i;
        }
        qsort(spans, n, sizeof *spans, cmp_span);
        for (uint32_t x = 0; x < n && !hit; x++)
            for (uint32_t y = x + 1;
                 y < n && spans[y].lo <= spans[x].hi && !hit; y++) {
                uint32_t i = spans[x].i, j = spans[y].i;
                hit = edges_meet(p, fv, n, axis, i < j ? i : j, i < j ? j : i);
            }
    }
    free(spans);
    free(ids);
    return hit;
}

/* -------------------------------------------------------- pair test */

/* Per-call scratch for a pair: sides and shared-vertex positions. */
typedef struct pair_scratch {
    uint32_t cap;
    int8_t *sf, *sg;   /* sides of F's vertices vs π_G, G's vs π_F */
    int32_t *fpos;     /* for each vertex of F: its position in G or −1 */
    int32_t *gpos;     /* for each vertex of G: its position in F or −1 */
} pair_scratch;

static int scratch_reserve(pair_scratch *s, uint32_t n)
{
    if (n <= s->cap)
        return 0;
    int8_t *sf = realloc(s->sf, n), *sg = sf ? realloc(s->sg, n) : NULL;
    if (sf)
        s->sf = sf;
    if (sg)
        s->sg = sg;
    int32_t *fp = sg ? realloc(s->fpos, n * sizeof *fp) : NULL;
    if (fp)
        s->fpos = fp;
    int32_t *gp = fp ? realloc(s->gpos, n * sizeof *gp) : NULL;
    if (gp)
        s->gpos = gp;
    if (!gp)
        return -ENOMEM;
    s->cap = n;
    return 0;
}

static void scratch_free(pair_scratch *s)
{
    free(s->sf), free(s->sg), free(s->fpos), free(s->gpos);
    memset(s, 0, sizeof *s);
}

typedef struct facet_ref {
    uint32_t id, n;
    const uint32_t *v;
    const geo_facet_shape *s;
    uint64_t mask; /* vertex_mask of its vertices */
    /* NULL, or the facet's keys (vertex << 32 | position) sorted: large
     * facets get them once per search, so that matching a small facet's
     * vertices against them costs O(|G| log |F|), not O(|F|·|G|) */
    const uint64_t *sorted;
} facet_ref;

/* One bit per vertex index: facets whose masks share no bit share no
 * vertex, and a vertex whose bit the other facet lacks is not in it. */
static inline uint64_t vertex_bit(uint32_t v)
{
    /* the low bits: neighbouring facets' vertices, numbered close
     * together, spread over all 64 (a multiplicative hash measured
     * slightly worse on scans) */
    return 1ULL << (v & 63);
}

static uint64_t vertex_mask(const uint32_t *v, uint32_t n)
{
    uint64_t m = 0;
    for (uint32_t i = 0; i < n; i++)
        m |= vertex_bit(v[i]);
    return m;
}

static facet_ref facet_at(const geo_poly *p, uint32_t f,
                          const geo_facet_shape *s)
{
    facet_ref r = {f, geo_poly_facet_size(p, f), geo_poly_facet(p, f), s, 0,
                   NULL};
    r.mask = vertex_mask(r.v, r.n);
    return r;
}

/* The first position of vertex v in F, or −1: a binary search in its
 * sorted keys when it has them, else a scan without a branch per
 * comparison. */
static int32_t position_in(const facet_ref *F, uint32_t v)
{
    if (!F->sorted) {
        int32_t first = -1;
        for (uint32_t i = F->n; i-- > 0;)
            first = F->v[i] == v ? (int32_t)i : first;
        return first;
    }
    uint64_t key = (uint64_t)v << 32;
    uint32_t lo = 0, hi = F->n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (F->sorted[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo < F->n && (uint32_t)(F->sorted[lo] >> 32) == v)
        return (int32_t)(uint32_t)F->sorted[lo];
    return -1;
}

static int side_of(const geo_poly *p, const facet_ref *F, const double x[3])
{
    const uint32_t *r = F->s->ref;
    return geo_orient3d(V(p, r[0]), V(p, r[1]), V(p, r[2]), x);
}

/* F's reference plane prepared for many side_of queries. */
static void plane_of(const geo_poly *p, const facet_ref *F,
                     geo_orient3d_plane *ret)
{
    const uint32_t *r = F->s->ref;
    geo_orient3d_plane_init(ret, V(p, r[0]), V(p, r[1]), V(p, r[2]));
}

/* Positions i, j of F are consecutive (an edge of F, either direction). */
static bool is_edge(const facet_ref *F, int32_t i, int32_t j)
{
    if (i < 0 || j < 0)
        return false;
    uint32_t d = (uint32_t)(i > j ? i - j : j - i);
    return d == 1 || d == F->n - 1;
}

/* Segment ab lying on π_F (by classification); ia/ib its endpoints'
 * positions in F or −1. Does it meet closed F anywhere but at a listed
 * endpoint? 2D in F's projection. */
static bool segment_hits_facet(const geo_poly *p, const facet_ref *F,
                               const double a3[3], const double b3[3],
                               int32_t ia, int32_t ib, int axis, int turn)
{
    double a[2], b[2];
    proj(a3, axis, a);
    proj(b3, axis, b);
    double c[2];
    proj(V(p, F->v[F->n - 1]), axis, c);
    for (uint32_t k = 0; k < F->n; k++) {
        uint32_t k0 = k ? k - 1 : F->n - 1;
        double d[2];
        proj(V(p, F->v[k]), axis, d);
        bool excl_a = ia >= 0 && ((uint32_t)ia == k0 || (uint32_t)ia == k);
        bool excl_b = ib >= 0 && ((uint32_t)ib == k0 || (uint32_t)ib == k);
        if (seg_contact(a, b, excl_a, excl_b, c, d))
            return true;
        c[0] = d[0], c[1] = d[1];
    }
    /* no boundary contact: the segment is wholly inside or outside */
    if (ia < 0)
        return point_in_facet2(p, F->id, axis, a) > 0;
    if (ib < 0)
        return point_in_facet2(p, F->id, axis, b) > 0;
    return wedge_inside(p, F->id, axis, turn, (uint32_t)ia, b);
}

/* Point x on π_F (by classification, not listed by F): in closed F? */
static bool point_hits_facet(const geo_poly *p, const facet_ref *F,
                             const double x[3])
{
    double q[2];
    proj(x, F->s->axis, q);
    return point_in_facet2(p, F->id, F->s->axis, q) >= 0;
}

/* Segment pq crosses π_F strictly (p and q on opposite sides). Where is
 * the crossing point with respect to closed F: +1 inside, 0 on its
 * boundary, −1 outside? Winding number of the line pq with respect to F's
 * polygon seen along pq: h, h2 are sides against two planes through pq
 * (their intersection), t the turn of each edge around pq. The winding's
 * sign convention does not matter: only ≠ 0 is used. */
static int segment_pierces_facet(const geo_poly *p, const facet_ref *F,
                                  const double P[3], const double Q[3])
{
    /* First in F's own projection: the crossing point projects onto the
     * projected segment, so when that segment and the projected polygon
     * have no point in common the crossing is outside F. This settles the
     * segments that run nearly in π_F (an edge of a coplanar neighbour):
     * seen along them F collapses to a sliver of the width of its
     * non-planarity, and the winding below could then put the crossing
     * anywhere on the line through pq. */
    {
        int axis = F->s->axis;
        double a2[2], b2[2], c[2], e[2];
        proj(P, axis, a2);
        proj(Q, axis, b2);
        proj(V(p, F->v[F->n - 1]), axis, c);
        bool contact = false;
        for (uint32_t i = 0; i < F->n && !contact; i++) {
            proj(V(p, F->v[i]), axis, e);
            contact = seg_contact(a2, b2, false, false, c, e);
            c[0] = e[0], c[1] = e[1];
        }
        if (!contact && point_in_facet2(p, F->id, axis, a2) < 0)
            return -1;
    }
    double d[3];
    geo_vsub(Q, P, d);
    int j = 0; /* the axis pq moves most along; the others span H, H2 */
    for (int k = 1; k < 3; k++)
        if (fabs(d[k]) > fabs(d[j]))
            j = k;
    int k1 = (j + 1) % 3, k2 = (j + 2) % 3;
    double s1[3] = {P[0], P[1], P[2]}, s2[3] = {P[0], P[1], P[2]};
    /* a unit-ish step that cannot vanish in rounding */
    s1[k1] = P[k1] + (1.0 + fabs(P[k1]) + fabs(d[j]));
    s2[k2] = P[k2] + (1.0 + fabs(P[k2]) + fabs(d[j]));

    const double *a = V(p, F->v[F->n - 1]);
    int ha = geo_orient3d(P, Q, s1, a), h2a = 2; /* 2: not computed */
    int wn = 0;
    for (uint32_t i = 0; i < F->n; i++) {
        const double *b = V(p, F->v[i]);
        int hb = geo_orient3d(P, Q, s1, b), h2b = 2;
        int t = geo_orient3d(P, Q, a, b);
        if (t == 0) {
            /* the edge's line meets line pq (or is parallel): on it? */
            if (ha != 0 || hb != 0) {
                if (ha * hb <= 0)
                    return 0;
            } else {
                if (h2a == 2)
                    h2a = geo_orient3d(P, Q, s2, a);
                h2b = geo_orient3d(P, Q, s2, b);
                if (h2a * h2b <= 0)
                    return 0;
            }
        }
        if (ha <= 0) {
            if (hb > 0 && t > 0)
                wn++;
        } else if (hb <= 0 && t < 0) {
            wn--;
        }
        a = b, ha = hb, h2a = h2b;
    }
    return wn ? 1 : -1;
}

/* Facets F, G (both) lie in one plane (all of one's vertices on the
 * other's reference plane). 2D overlap in `base`'s projection, shared
 * vertices and edges excepted. */
static bool coplanar_overlap(const geo_poly *p, const facet_ref *F,
                             const facet_ref *G, const int32_t *fpos,
                             const int32_t *gpos, int axis)
{
    /* each polygon's turn in this common projection */
    int tf = F->s->axis == axis ? F->s->turn : turn_in_axis(p, F->id, axis);
    int tg = G->s->axis == axis ? G->s->turn : turn_in_axis(p, G->id, axis);
    /* 1. boundaries: any contact but at a common vertex; shared edges
     *    must have the two facets on opposite sides */
    for (uint32_t i = 0; i < F->n; i++) {
        uint32_t i1 = (i + 1) % F->n;
        double a[2], b[2];
        proj(V(p, F->v[i]), axis, a);
        proj(V(p, F->v[i1]), axis, b);
        for (uint32_t j = 0; j < G->n; j++) {
            uint32_t j1 = (j + 1) % G->n;
            uint32_t fa = F->v[i], fb = F->v[i1], ga = G->v[j], gb = G->v[j1];
            if ((fa == ga && fb == gb) || (fa == gb && fb == ga)) {
                /* interior side of each: left of its own direction times
                 * its turn, seen along F's direction a→b */
                int side_f = tf;
                int side_g = (ga == fa ? 1 : -1) * tg;
                if (side_f == side_g)
                    return true;
                continue;
            }
            double c[2], d[2];
            proj(V(p, ga), axis, c);
            proj(V(p, gb), axis, d);
            bool excl_a = fa == ga || fa == gb, excl_b = fb == ga || fb == gb;
            if (seg_contact(a, b, excl_a, excl_b, c, d))
                return true;
        }
    }
    /* 2. a vertex one facet does not share, inside the other */
    for (uint32_t j = 0; j < G->n; j++) {
        double q[2];
        if (gpos[j] >= 0)
            continue;
        proj(V(p, G->v[j]), axis, q);
        if (point_in_facet2(p, F->id, axis, q) >= 0)
            return true;
    }
    for (uint32_t i = 0; i < F->n; i++) {
        double q[2];
        if (fpos[i] >= 0)
            continue;
        proj(V(p, F->v[i]), axis, q);
        if (point_in_facet2(p, G->id, axis, q) >= 0)
            return true;
    }
    /* 3. an edge between two shared vertices that the other facet does
     *    not have: a chord, inside or outside as a whole */
    for (uint32_t j = 0; j < G->n; j++) {
        uint32_t j1 = (j + 1) % G->n;
        if (gpos[j] < 0 || gpos[j1] < 0 || is_edge(F, gpos[j], gpos[j1]))
            continue;
        double q[2];
        proj(V(p, G->v[j1]), axis, q);
        if (wedge_inside(p, F->id, axis, tf, (uint32_t)gpos[j], q))
            return true;
    }
    for (uint32_t i = 0; i < F->n; i++) {
        uint32_t i1 = (i + 1) % F->n;
        if (fpos[i] < 0 || fpos[i1] < 0 || is_edge(G, fpos[i], fpos[i1]))
            continue;
        double q[2];
        proj(V(p, F->v[i1]), axis, q);
        if (wedge_inside(p, G->id, axis, tg, (uint32_t)fpos[i], q))
            return true;
    }
    return false;
}

/* G touches π_F only at its vertices of side 0 and the edges between
 * them (G lies on one side). Any of those in F, shared ones excepted? */
static bool touching_hits(const geo_poly *p, const facet_ref *F,
                          const facet_ref *G, const int8_t *sg,
                          const int32_t *gpos)
{
    for (uint32_t j = 0; j < G->n; j++) {
        if (sg[j] != 0)
            continue;
        const double *x = V(p, G->v[j]);
        if (gpos[j] < 0 && point_hits_facet(p, F, x))
            return true;
        uint32_t j1 = (j + 1) % G->n;
        if (sg[j1] != 0 || is_edge(F, gpos[j], gpos[j1]))
            continue;
        if (segment_hits_facet(p, F, x, V(p, G->v[j1]), gpos[j], gpos[j1],
                               F->s->axis, F->s->turn))
            return true;
    }
    return false;
}

/* Both F and G straddle the other's plane: their intersection lies on
 * the line π_F ∩ π_G; look for a witness point on an edge (see the
 * completeness argument in the README's Inspection section). */
static bool edges_hit(const geo_poly *p, const facet_ref *F,
                      const facet_ref *G, const int8_t *sg,
                      const int32_t *gpos)
{
    for (uint32_t j = 0; j < G->n; j++) {
        uint32_t j1 = (j + 1) % G->n;
        const double *a = V(p, G->v[j]), *b = V(p, G->v[j1]);
        if (sg[j] == 0 && gpos[j] < 0 && point_hits_facet(p, F, a))
            return true;
        if (sg[j] * sg[j1] < 0) {
            if (segment_pierces_facet(p, F, a, b) >= 0)
                return true;
        } else if (sg[j] == 0 && sg[j1] == 0 &&
                   !is_edge(F, gpos[j], gpos[j1])) {
            if (segment_hits_facet(p, F, a, b, gpos[j], gpos[j1], F->s->axis,
                                   F->s->turn))
                return true;
        }
    }
    return false;
}

/* Convex F and G share exactly the edge uw (positions iu, iw in F, ju in
 * G). In F's projection, if every other vertex of G lies strictly on the
 * other side of the line uw than F, the projections meet only on that
 * line, and each facet's points projecting there form just the edge uw:
 * the pair is legal. A sufficient test, not a necessary one: false means
 * "decide by the general path". Well conditioned where the side tests of
 * the general path are not (nearly coplanar neighbours, like a scan's
 * slivers). */
static bool separated_by_shared_edge(const geo_poly *p, const facet_ref *F,
                                     const facet_ref *G, const int32_t *gpos,
                                     uint32_t iu, uint32_t iw)
{
    geo_orient2d_line uw;
    geo_orient2d_line_init(&uw, V(p, F->v[iu]), V(p, F->v[iw]), F->s->axis);
    int side_f = 0;
    for (uint32_t i = 0; i < F->n && !side_f; i++)
        if (i != iu && i != iw)
            side_f = geo_orient2d_line_sign(&uw, V(p, F->v[i]));
    if (!side_f)
        return false;
    for (uint32_t j = 0; j < G->n; j++)
        if (gpos[j] < 0 && geo_orient2d_line_sign(&uw, V(p, G->v[j])) != -side_f)
            return false;
    return true;
}

/* fpos from gpos: for each position of F, the (last) position of G
 * listing the same vertex, or −1. O(|F| + |G|), so only paid by pairs
 * that get past the first side test. */
static void fill_fpos(const facet_ref *F, const facet_ref *G,
                      const int32_t *gpos, int32_t *fpos)
{
    for (uint32_t i = 0; i < F->n; i++)
        fpos[i] = -1;
    for (uint32_t j = 0; j < G->n; j++)
        if (gpos[j] >= 0)
            fpos[gpos[j]] = (int32_t)j;
}

/* The rest of pair_test once the sides sg of G's vertices against π_F
 * (pos, neg: whether any is positive, negative) and the shared positions
 * are known. */
static bool sided_test(const geo_poly *p, const facet_ref *F,
                       const facet_ref *G, pair_scratch *sc,
                       uint32_t nshared, bool pos, bool neg)
{
    int8_t *sf = sc->sf, *sg = sc->sg;
    int32_t *fpos = sc->fpos, *gpos = sc->gpos;
    geo_orient3d_plane pl;
    if (!(pos && neg) && (pos || neg))
        return touching_hits(p, F, G, sg, gpos);
    fill_fpos(F, G, gpos, fpos);
    if (!pos && !neg)
        return coplanar_overlap(p, F, G, fpos, gpos, F->s->axis);
    pos = neg = false;
    plane_of(p, G, &pl);
    for (uint32_t i = 0; i < F->n; i++) {
        sf[i] = (int8_t)(fpos[i] >= 0
                             ? 0
                             : geo_orient3d_plane_sign(&pl, V(p, F->v[i])));
        pos |= sf[i] > 0;
        neg |= sf[i] < 0;
    }
    if (!pos && !neg)
        return coplanar_overlap(p, G, F, gpos, fpos, G->s->axis);
    if (!(pos && neg))
        return touching_hits(p, G, F, sf, fpos);
    if (edges_hit(p, F, G, sg, gpos) || edges_hit(p, G, F, sf, fpos))
        return true;
    if (nshared < 2)
        return false;
    /* two shared vertices v, w joined by an edge of neither facet: the
     * facets cross along vw when it leaves v into both of them */
    for (uint32_t i = 0; i < F->n; i++) {
        if (fpos[i] < 0)
            continue;
        for (uint32_t k = 0; k < F->n; k++) {
            if (k == i || fpos[k] < 0 || is_edge(F, (int32_t)i, (int32_t)k) ||
                is_edge(G, fpos[i], fpos[k]))
                continue;
            double qf[2], qg[2];
            proj(V(p, F->v[k]), F->s->axis, qf);
            proj(V(p, F->v[k]), G->s->axis, qg);
            if (wedge_inside(p, F->id, F->s->axis, F->s->turn, i, qf) &&
                wedge_inside(p, G->id, G->s->axis, G->s->turn,
                             (uint32_t)fpos[i], qg))
                return true;
        }
    }
    return false;
}

static bool pair_test(const geo_poly *p, const facet_ref *F,
                      const facet_ref *G, pair_scratch *sc)
{
    /* the predicate is symmetric for planar facets: G, whose vertices are
     * matched and classified first, is the smaller when the larger has
     * sorted keys, so that a large facet met by many small ones that only
     * touch its plane (a prism's cap and its sides) costs O(|G| log |F|)
     * per pair instead of O(|F|·|G|); otherwise the lower facet stays F,
     * so that the answer on non-planar garbage is the same as before */
    if (G->sorted && G->n > F->n) {
        const facet_ref *t = F;
        F = G;
        G = t;
    }
    int8_t *sg = sc->sg;
    int32_t *gpos = sc->gpos;
    uint64_t common = F->mask & G->mask;
    bool pos = false, neg = false;
    geo_orient3d_plane pl;
    if (!common) {
        plane_of(p, F, &pl);
        /* no vertex in common (most pairs that are not neighbours): G
         * strictly on one side of π_F is apart, as touching_hits would
         * find with no side 0; anything else takes the general path */
        bool zero = false;
        for (uint32_t j = 0; j < G->n; j++) {
            sg[j] = (int8_t)geo_orient3d_plane_sign(&pl, V(p, G->v[j]));
            pos |= sg[j] > 0;
            neg |= sg[j] < 0;
            zero |= sg[j] == 0;
        }
        if (!zero && !(pos && neg))
            return false;
        for (uint32_t j = 0; j < G->n; j++)
            gpos[j] = -1;
        return sided_test(p, F, G, sc, 0, pos, neg);
    }
    uint32_t nshared = 0, at[2] = {0, 0};
    for (uint32_t j = 0; j < G->n; j++) {
        uint32_t v = G->v[j];
        gpos[j] = common & vertex_bit(v) ? position_in(F, v) : -1;
        if (gpos[j] >= 0) {
            if (nshared < 2)
                at[nshared] = j;
            nshared++;
        }
    }
    if (nshared == 2 && F->s->convex && G->s->convex &&
        gpos[at[0]] != gpos[at[1]]) {
        /* ju, jw: G's positions of the shared vertices, taken so that
         * iu comes before iw in F's order */
        uint32_t ju = at[0], jw = at[1];
        if (gpos[ju] > gpos[jw]) {
            ju = at[1];
            jw = at[0];
        }
        uint32_t iu = (uint32_t)gpos[ju], iw = (uint32_t)gpos[jw];
        if (is_edge(F, (int32_t)iu, (int32_t)iw) &&
            is_edge(G, (int32_t)ju, (int32_t)jw) &&
            separated_by_shared_edge(p, F, G, gpos, iu, iw))
            return false;
    }
    /* after the shared-edge shortcut, which most neighbours in a
     * polygon mesh take without F's plane */
    plane_of(p, F, &pl);
    for (uint32_t j = 0; j < G->n; j++) {
        sg[j] = (int8_t)(gpos[j] >= 0
                             ? 0
                             : geo_orient3d_plane_sign(&pl, V(p, G->v[j])));
        pos |= sg[j] > 0;
        neg |= sg[j] < 0;
    }
    return sided_test(p, F, G, sc, nshared, pos, neg);
}

int geo_facets_intersect(const geo_poly *p, uint32_t f, uint32_t g,
                         const geo_facet_shape *sf, const geo_facet_shape *sg)
{
    if (f == g || sf->degenerate || sg->degenerate)
        return 0;
    facet_ref F = facet_at(p, f, sf), G = facet_at(p, g, sg);
    uint32_t n = F.n > G.n ? F.n : G.n;
    enum { SMALL = 64 };
    int8_t s1[SMALL], s2[SMALL];
    int32_t p1[SMALL], p2[SMALL];
    pair_scratch sc = {SMALL, s1, s2, p1, p2};
    pair_scratch heap = {0};
    if (n > SMALL) {
        if (scratch_reserve(&heap, n) < 0) {
            scratch_free(&heap);
            return -ENOMEM;
        }
        sc = heap;
    }
    bool hit = pair_test(p, &F, &G, &sc);
    scratch_free(&heap);
    return hit;
}

int geo_segment_meets_facet(const geo_poly *p, uint32_t f,
                            const geo_facet_shape *s, const double a[3],
                            const double b[3])
{
    if (s->degenerate)
        return -1;
    facet_ref F = facet_at(p, f, s);
    int sa = side_of(p, &F, a), sb = side_of(p, &F, b);
    if (sa * sb > 0)
        return -1;
    if (sa == 0 && sb == 0)
        return segment_hits_facet(p, &F, a, b, -1, -1, s->axis, s->turn) ? 0
                                                                        : -1;
    if (sa == 0 || sb == 0)
        return point_hits_facet(p, &F, sa == 0 ? a : b) ? 0 : -1;
    return segment_pierces_facet(p, &F, a, b);
}

/* ------------------------------------------------------- the search */

void geo_selfint_opts_default(geo_selfint_opts *o)
{
    o->max_pairs = 1000;
    o->max_tasks = 1024;
    o->simple_fans = NULL;
    o->indices_checked = false;
}

/* Fans of more triangles than this are left to the pair tests. */
enum { FAN_MAX = 64 };

/* geo_selfint_simple_fans for one interior vertex v. The fan's triangles
 * in order around v, each (v, r_i, r_i+1) with r the spokes (the
 * corners' previous vertices; the next triangle's previous vertex is this
 * one's next), r_k+1 = r_1. With every sector of one sign s and no other
 * spoke in the direction of r_1, the fan winds w ≥ 1 times and, were
 * w > 1, the direction of r_1 would come round again strictly inside a
 * sector other than the first and the last (each spans less than a
 * half-turn; a spoke opposite r_1 bounds sectors that cannot hold it): so
 * no such sector containing r_1 means w = 1. */
/* a, b on one line through o in the fan's projection (their orient2d 0,
 * neither at o): whether they lie on the same side of o. A difference of
 * doubles has the sign of the exact one. */
static bool along(const double o[2], const double a[2], const double b[2])
{
    double au = a[0] - o[0], bu = b[0] - o[0];
    if (au != 0)
        return (au > 0) == (bu > 0);
    return (a[1] - o[1] > 0) == (b[1] - o[1] > 0);
}

static bool fan_is_simple(const geo_poly *p, const geo_topo *t, uint32_t v)
{
    uint32_t c0 = t->vstart[v], k = t->vstart[v + 1] - c0;
    if (t->vertex_kind[v] != GEO_VERTEX_INTERIOR || k < 3 || k > FAN_MAX)
        return false;
    const uint32_t *cs = t->vcorners + c0;
    /* every facet a triangle: corner c's facet holds corners 3⌊c/3⌋..+2;
     * the offsets of the next and previous corners by c mod 3 */
    static const int8_t next_off[3] = {1, 1, -2}, prev_off[3] = {2, -1, -1};
#define NEXT(c) (p->fidx[(c) + next_off[(c) % 3]])
#define PREV(c) (p->fidx[(c) + prev_off[(c) % 3]])
    uint32_t r[FAN_MAX + 1];
    /* the fan's order as the topology stores it, either way round */
    bool fwd = NEXT(cs[0]) == PREV(cs[1]);
    for (uint32_t i = 0; i < k; i++) {
        uint32_t a = cs[fwd ? i : k - 1 - i], b = cs[fwd ? (i + 1) % k
                                                        : (2 * k - 2 - i) % k];
        if (NEXT(a) != PREV(b))
            return false;
        r[i] = PREV(a);
    }
#undef NEXT
#undef PREV
    r[k] = r[0];
    /* the axis to drop: the largest component of the fan's normal (any
     * axis is correct; this one leaves the sectors widest) */
    const double *o = p->verts[v];
    double n[3] = {0, 0, 0};
    for (uint32_t i = 0; i < k; i++) {
        double e1[3], e2[3], x[3];
        geo_vsub(p->verts[r[i]], o, e1);
        geo_vsub(p->verts[r[i + 1]], o, e2);
        geo_vcross(e1, e2, x);
        geo_vadd(n, x, n);
    }
    int drop = fabs(n[0]) >= fabs(n[1]) ? (fabs(n[0]) >= fabs(n[2]) ? 0 : 2)
                                        : (fabs(n[1]) >= fabs(n[2]) ? 1 : 2);
    /* the projection (the kept axes in cyclic order, as
     * geo_orient2d_proj takes them): the same numbers, so the same signs */
    int u = (drop + 1) % 3, w = (drop + 2) % 3;
    double o2[2] = {o[u], o[w]}, q[FAN_MAX + 1][2];
    for (uint32_t i = 0; i <= k; i++) {
        q[i][0] = p->verts[r[i]][u];
        q[i][1] = p->verts[r[i]][w];
    }
    int sg = geo_orient2d(o2, q[0], q[1]);
    if (sg == 0)
        return false;
    /* side: of spoke i from r_1 */
    int prev_side = 0;
    for (uint32_t i = 1; i <= k; i++) {
        if (i > 1 && geo_orient2d(o2, q[i - 1], q[i]) != sg)
            return false;
        if (i == k)
            break;
        int side = sg * geo_orient2d(o2, q[0], q[i]);
        /* a spoke along r_1: away from it only (a flat fan's opposite
         * spoke; the signs of the exact differences tell the way) */
        if (side == 0 && along(o2, q[0], q[i]))
            return false;
        /* sector i−1 (from r_i−1 to r_i), not the first: r_1 strictly
         * inside it when r_i−1 lies clockwise of r_1 and r_i
         * counter-clockwise (with s) */
        if (i > 1 && prev_side < 0 && side > 0)
            return false;
        prev_side = side;
    }
    return true;
}

void geo_selfint_simple_fans(const geo_poly *p, const geo_topo *t,
                             uint8_t *ret)
{
    for (uint32_t v = 0; v < p->nverts; v++)
        ret[v] = fan_is_simple(p, t, v);
}

void geo_selfint_clear(geo_selfint *r)
{
    if (!r)
        return;
    free(r->pairs);
    free(r->facet_flags);
    memset(r, 0, sizeof *r);
}

typedef struct pair_list {
    uint32_t (*v)[2];
    size_t n, cap;
} pair_list;

static int cmp_pair(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    if (a[0] != b[0])
        return a[0] < b[0] ? -1 : 1;
    return (a[1] > b[1]) - (a[1] < b[1]);
}

/* Keeps (at least) the `keep` smallest pairs: sorts and truncates when
 * the list doubles past it, so memory stays O(keep). */
static int list_add(pair_list *l, uint32_t a, uint32_t b, uint32_t keep)
{
    if (keep == 0)
        return 0;
    if (l->n == l->cap) {
        if (l->n >= 2 * (size_t)keep) {
            qsort(l->v, l->n, sizeof *l->v, cmp_pair);
            l->n = keep;
        } else {
            size_t c = l->cap ? 2 * l->cap : 64;
            void *nv = realloc(l->v, c * sizeof *l->v);
            if (!nv)
                return -ENOMEM;
            l->v = nv;
            l->cap = c;
        }
    }
    l->v[l->n][0] = a;
    l->v[l->n][1] = b;
    l->n++;
    return 0;
}

typedef struct task_out {
    uint64_t count;
    pair_list list;
    int err;
} task_out;

typedef struct search {
    const geo_poly *p;
    const geo_bvh *h;   /* the caller's tree, or NULL: */
    const geo_fbvh *fh; /* the search's own */
    const geo_ctx *ctx;
    /* per facet, or NULL when every facet is a triangle (all_tri): a
     * triangle's shape is then formed only for the few pairs that reach
     * pair_test (one in a hundred on a mesh), its masks taken from the
     * vertices — not 28 bytes and a shape per facet */
    const geo_facet_shape *shapes;
    const uint64_t *masks; /* vertex_mask of each facet */
    bool all_tri;
    const uint8_t *fans; /* geo_selfint_opts.simple_fans (all_tri only) */
    const uint64_t *const *sorted; /* per facet: sorted keys or NULL;
                                      NULL when no facet has them */
    atomic_uchar *flags;
    uint32_t keep;
    uint32_t maxn;        /* largest facet size */
    uint32_t *ta, *tb;    /* tasks: node pairs */
    task_out *out;
    uint32_t first;       /* index of the batch's first task */
    atomic_int stop;      /* canceled or failed: all tasks stop */
} search;

typedef struct visit_state {
    search *s;
    task_out *out;
    pair_scratch sc;
    uint32_t since_check;
} visit_state;

/* Triangles x and y share one vertex, and y's two others c, d lie
 * strictly on either side of x's plane: true when segment cd misses
 * closed triangle x (the line cd passes on one side of all three of its
 * edges, exact signs). */
static bool free_edge_misses(const geo_poly *p, const uint32_t *x,
                             const uint32_t *y)
{
    int k = 0;
    while (y[k] == x[0] || y[k] == x[1] || y[k] == x[2])
        k++;
    const double *c = V(p, y[k]), *d = V(p, y[(k + 1) % 3]);
    if (y[(k + 1) % 3] == x[0] || y[(k + 1) % 3] == x[1] ||
        y[(k + 1) % 3] == x[2])
        d = V(p, y[(k + 2) % 3]);
    bool pos = false, neg = false;
    for (int i = 0; i < 3; i++) {
        int o = geo_orient3d(c, d, V(p, x[i]), V(p, x[(i + 1) % 3]));
        pos |= o > 0;
        neg |= o < 0;
    }
    return pos && neg;
}

/* Triangles x and y share one or two vertices and one of them has a fan
 * shown simple (geo_selfint_simple_fans): they meet only where they
 * share. Nine index comparisons and at most three bytes of fans: the
 * test most candidate pairs of a mesh end at (on a scan, nine in ten),
 * so it runs before anything else of the pair is read. */
static inline bool shares_simple_fan(const uint8_t *fans, const uint32_t *x,
                                     const uint32_t *y)
{
    /* without branches: the outcomes follow no pattern a predictor
     * learns, and the three bytes of fans are in cache */
    uint32_t x0 = x[0], x1 = x[1], x2 = x[2], y0 = y[0], y1 = y[1],
             y2 = y[2];
    unsigned s0 = (x0 == y0) | (x0 == y1) | (x0 == y2);
    unsigned s1 = (x1 == y0) | (x1 == y1) | (x1 == y2);
    unsigned s2 = (x2 == y0) | (x2 == y1) | (x2 == y2);
    unsigned hit = (s0 & fans[x0]) | (s1 & fans[x1]) | (s2 & fans[x2]);
    /* three shared: the same triangle twice, for pair_test */
    return hit & (s0 + s1 + s2 != 3);
}

/* Whether the closed triangles a and b, sharing no vertex, each strictly
 * across the other's plane (sa: the signs of a's vertices against b's
 * plane, sb of b's against a's, none 0), meet. Each meets the planes'
 * common line in a segment; they meet exactly when the segments overlap,
 * which two signs decide once each triangle is turned so that its lone
 * vertex (the one on its own side of the other's plane) comes first and
 * lies on the other's positive side (Guigue and Devillers 2003, their
 * canonical form and their two orientation tests, with exact signs). */
static bool straddling_meet(const geo_poly *p, const uint32_t *a,
                            const uint32_t *b, const int sa[3],
                            const int sb[3])
{
    /* a's lone vertex first, the order kept (a cyclic turn); flip = b's
     * order reversed so that the lone vertex lies on b's positive side */
    int la = sa[1] == sa[2] ? 0 : sa[0] == sa[2] ? 1 : 2;
    const double *p1 = V(p, a[la]), *q1 = V(p, a[(la + 1) % 3]),
                 *r1 = V(p, a[(la + 2) % 3]);
    bool flip_b = sa[la] < 0;
    uint32_t bb[3] = {b[0], flip_b ? b[2] : b[1], flip_b ? b[1] : b[2]};
    int sbb[3] = {sb[0], flip_b ? sb[2] : sb[1], flip_b ? sb[1] : sb[2]};
    /* the same for b against a (whose order is now p1, q1, r1) */
    int lb = sbb[1] == sbb[2] ? 0 : sbb[0] == sbb[2] ? 1 : 2;
    const double *p2 = V(p, bb[lb]), *q2 = V(p, bb[(lb + 1) % 3]),
                 *r2 = V(p, bb[(lb + 2) % 3]);
    if (sbb[lb] < 0) {
        const double *t = q1;
        q1 = r1;
        r1 = t;
    }
    /* the segments overlap unless b's ends lie beyond a's on either side */
    return geo_orient3d(q1, p2, p1, q2) <= 0 &&
           geo_orient3d(p1, p2, r1, r2) <= 0;
}

/* Two triangles x, y (distinct, non-degenerate): false when one or two
 * exact signs show them apart, true when pair_test must decide. A
 * triangle is exactly planar and its reference plane is its own, so:
 * sharing an edge uw and not coplanar, the planes meet only in the line
 * uw, which each triangle meets only in uw itself — the shared edge;
 * sharing one vertex v, or none, with the other's remaining vertices
 * strictly on one side of a triangle's plane, they can meet only at v —
 * a shared vertex — or not at all; sharing v and each across the other's
 * plane, by where their free edges cross (free_edge_misses); sharing none
 * and each strictly across the other's plane, by where their segments on
 * the planes' common line lie (straddling_meet: true only when they
 * meet, and pair_test then records it). These are pair_test's own
 * answers, reached without its general bookkeeping; every other case
 * (coplanar, touching a plane, a triangle listed twice) goes to it. */
static bool triangles_need_test(const geo_poly *p, const uint32_t *x,
                                const uint32_t *y)
{
    /* which of y's vertices x lists (in_x, a bit per position of y) and
     * which of x's y lists (in_y): nine comparisons, once */
    uint32_t x0 = x[0], x1 = x[1], x2 = x[2], y0 = y[0], y1 = y[1],
             y2 = y[2];
    unsigned e00 = x0 == y0, e01 = x0 == y1, e02 = x0 == y2;
    unsigned e10 = x1 == y0, e11 = x1 == y1, e12 = x1 == y2;
    unsigned e20 = x2 == y0, e21 = x2 == y1, e22 = x2 == y2;
    unsigned in_x = (e00 | e10 | e20) | (e01 | e11 | e21) << 1 |
                    (e02 | e12 | e22) << 2;
    unsigned in_y = (e00 | e01 | e02) | (e10 | e11 | e12) << 1 |
                    (e20 | e21 | e22) << 2;
    unsigned nshared = (in_x & 1) + (in_x >> 1 & 1) + (in_x >> 2);
    if (nshared == 2) {
        int c = in_x == 3 ? 2 : in_x == 5 ? 1 : 0; /* y's own vertex */
        int a = in_y == 3 ? 2 : in_y == 5 ? 1 : 0; /* x's own vertex */
        return geo_orient3d(V(p, y[(c + 1) % 3]), V(p, y[(c + 2) % 3]),
                            V(p, x[a]), V(p, y[c])) == 0;
    }
    if (nshared == 3)
        return true;
    geo_orient3d_plane pl;
    bool straddle = true;
    int sgn[2][3] = {{0}}; /* [0]: y's vertices against x's plane, [1]: x's
                              against y's */
    for (int pass = 0; pass < 2; pass++) {
        const uint32_t *f = pass ? y : x, *g = pass ? x : y;
        unsigned shared = pass ? in_y : in_x; /* g's vertices f lists */
        geo_orient3d_plane_init(&pl, V(p, f[0]), V(p, f[1]), V(p, f[2]));
        bool pos = false, neg = false, zero = false;
        for (int j = 0; j < 3; j++) {
            if (shared >> j & 1)
                continue; /* the shared vertex: on the plane */
            int sg = geo_orient3d_plane_sign(&pl, V(p, g[j]));
            sgn[pass][j] = sg;
            pos |= sg > 0;
            neg |= sg < 0;
            zero |= sg == 0;
        }
        if (!zero && !(pos && neg))
            return false; /* strictly on one side */
        straddle &= !zero;
    }
    if (!straddle)
        return true;
    if (nshared == 0)
        return straddling_meet(p, x, y, sgn[1], sgn[0]);
    /* one shared vertex v, each triangle's free edge strictly across the
     * other's plane: each meets the planes' common line (through v) in a
     * segment from v, and they overlap beyond v exactly when the shorter
     * one's far end — where a free edge crosses the other plane — lies
     * in the other triangle; a contact anywhere on it counts (v is not on
     * a free edge: the triangles are not degenerate) */
    return !(free_edge_misses(p, x, y) && free_edge_misses(p, y, x));
}

static bool visit_pair(void *user, uint32_t a, uint32_t b)
{
    visit_state *vs = user;
    search *s = vs->s;
    if (++vs->since_check >= 2048) {
        vs->since_check = 0;
        if (atomic_load_explicit(&s->stop, memory_order_relaxed) ||
            geo_ctx_canceled(s->ctx)) {
            atomic_store(&s->stop, 1);
            return false;
        }
    }
    /* the lower facet first: on facets that are not planar the test is
     * not symmetric (each facet is its vertices projected along the
     * query), and the answer must not depend on the tree's visit order */
    if (a > b) {
        uint32_t t = a;
        a = b;
        b = t;
    }
    /* before anything else of the pair is read (a pair of a degenerate
     * triangle is skipped below either way) */
    if (s->fans && shares_simple_fan(s->fans, s->p->fidx + 3 * (size_t)a,
                                     s->p->fidx + 3 * (size_t)b))
        return true;
    /* the degenerate flag was set with the shape and never changes */
    if ((atomic_load_explicit(&s->flags[a], memory_order_relaxed) |
         atomic_load_explicit(&s->flags[b], memory_order_relaxed)) &
        GEO_SI_DEGENERATE)
        return true;
    /* every facet a triangle: facet f's corners are 3f..3f+2 */
    if (s->all_tri ? !triangles_need_test(s->p, s->p->fidx + 3 * (size_t)a,
                                          s->p->fidx + 3 * (size_t)b)
               : geo_poly_facet_size(s->p, a) == 3 &&
                     geo_poly_facet_size(s->p, b) == 3 &&
                     !triangles_need_test(s->p, geo_poly_facet(s->p, a),
                                          geo_poly_facet(s->p, b)))
        return true;
    geo_facet_shape sa, sb;
    facet_ref F, G;
    if (s->shapes) {
        F = (facet_ref){a, geo_poly_facet_size(s->p, a),
                        geo_poly_facet(s->p, a), &s->shapes[a], s->masks[a],
                        s->sorted ? s->sorted[a] : NULL};
        G = (facet_ref){b, geo_poly_facet_size(s->p, b),
                        geo_poly_facet(s->p, b), &s->shapes[b], s->masks[b],
                        s->sorted ? s->sorted[b] : NULL};
    } else { /* triangles: no sorted keys */
        geo_facet_shape_of(s->p, a, &sa);
        geo_facet_shape_of(s->p, b, &sb);
        F = facet_at(s->p, a, &sa);
        G = facet_at(s->p, b, &sb);
    }
    if (!pair_test(s->p, &F, &G, &vs->sc))
        return true;
    vs->out->count++;
    atomic_fetch_or_explicit(&s->flags[a], GEO_SI_PAIR, memory_order_relaxed);
    atomic_fetch_or_explicit(&s->flags[b], GEO_SI_PAIR, memory_order_relaxed);
    if (list_add(&vs->out->list, a, b, s->keep) < 0) {
        vs->out->err = -ENOMEM;
        atomic_store(&s->stop, 1);
        return false;
    }
    return true;
}

static int cmp_u64(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return (a > b) - (a < b);
}

/* Facets above this size get sorted vertex keys for the pair tests. */
enum { SORTED_MIN = 32 };

/* The sorted keys of every facet above SORTED_MIN vertices, in one
 * buffer (*keys); (*sorted)[f] points into it or is NULL. Both stay NULL
 * when no facet is that large (a triangle mesh: no per-facet array of
 * NULLs to fill). -ENOMEM. */
static int sort_large_facets(const geo_poly *p, const uint64_t ***sorted,
                             uint64_t **keys)
{
    size_t total = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        if (n > SORTED_MIN)
            total += n;
    }
    *sorted = NULL;
    *keys = NULL;
    if (total == 0)
        return 0;
    *sorted = malloc(((size_t)p->nfacets + 1) * sizeof **sorted);
    *keys = malloc((total + 1) * sizeof **keys);
    if (!*sorted || !*keys)
        return -ENOMEM;
    size_t at = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        (*sorted)[f] = NULL;
        if (n <= SORTED_MIN)
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        uint64_t *k = *keys + at;
        for (uint32_t i = 0; i < n; i++)
            k[i] = (uint64_t)fv[i] << 32 | i;
        qsort(k, n, sizeof *k, cmp_u64);
        (*sorted)[f] = k;
        at += n;
    }
    return 0;
}

/* The tree's tags (fbvh.h) for a mesh of triangles: a slot's tags are its
 * triangle's vertices whose fans are simple, and values no vertex holds
 * (2^31 + the slot) in place of the others. So the tree does not report
 * a pair sharing a simple fan's vertex: visit_pair's first test, decided
 * before the visit (a pair sharing all three vertices, which that test
 * leaves to pair_test, has no simple fan among them: each such vertex has
 * both triangles on the same two spokes, a fan of two triangles or an
 * edge of more than two). NULL when the indices do not leave room, or
 * out of memory: the visits then decide, as without tags. */
static uint32_t (*fan_tags(const geo_poly *p, const geo_fbvh *h,
                           const uint8_t *fans))[3]
{
    uint32_t n = h->nitems;
    if (p->nverts > UINT32_C(1) << 31 || n > UINT32_C(1) << 31)
        return NULL;
    uint32_t (*t)[3] = malloc(((size_t)n + 1) * sizeof *t);
    if (!t)
        return NULL;
    for (uint32_t k = 0; k < n; k++) {
        const uint32_t *v = p->fidx + 3 * (size_t)h->items[k];
        for (int c = 0; c < 3; c++)
            t[k][c] = fans[v[c]] ? v[c] : UINT32_C(1) << 31 | k;
    }
    return t;
}

static void run_task(void *arg, size_t i)
{
    search *s = arg;
    size_t t = s->first + i;
    visit_state vs = {s, &s->out[t], {0}, 0};
    if (atomic_load(&s->stop))
        return;
    /* ordinary facets: scratch on the stack, no allocation per task */
    enum { SMALL = 64 };
    int8_t s1[SMALL], s2[SMALL];
    int32_t p1[SMALL], p2[SMALL];
    bool heap = s->maxn > SMALL;
    if (!heap) {
        pair_scratch small = {SMALL, s1, s2, p1, p2};
        vs.sc = small;
    } else if (scratch_reserve(&vs.sc, s->maxn) < 0) {
        scratch_free(&vs.sc);
        s->out[t].err = -ENOMEM;
        atomic_store(&s->stop, 1);
        return;
    }
    if (s->fh)
        geo_fbvh_pairs(s->fh, s->ta[t], s->tb[t], visit_pair, &vs);
    else
        geo_bvh_pairs(s->h, s->ta[t], s->tb[t], visit_pair, &vs);
    if (heap)
        scratch_free(&vs.sc);
}

typedef struct shape_job {
    const geo_poly *p;
    geo_facet_shape *shapes;
    uint64_t *masks;
    atomic_uchar *flags;
    uint32_t block;
} shape_job;

static void run_shapes(void *arg, size_t i)
{
    shape_job *j = arg;
    uint32_t lo = (uint32_t)i * j->block, hi = lo + j->block;
    if (hi > j->p->nfacets)
        hi = j->p->nfacets;
    for (uint32_t f = lo; f < hi; f++) {
        if (!j->shapes) {
            /* a triangle is simple and convex, degenerate exactly when
             * its corners are collinear (what geo_facet_shape_of finds) */
            const uint32_t *v = j->p->fidx + 3 * (size_t)f;
            atomic_init(&j->flags[f],
                        collinear3(V(j->p, v[0]), V(j->p, v[1]),
                                   V(j->p, v[2]))
                            ? GEO_SI_DEGENERATE
                            : 0);
            continue;
        }
        geo_facet_shape *s = &j->shapes[f];
        geo_facet_shape_of(j->p, f, s);
        j->masks[f] = vertex_mask(geo_poly_facet(j->p, f),
                                  geo_poly_facet_size(j->p, f));
        unsigned char fl = 0;
        if (s->degenerate)
            fl = GEO_SI_DEGENERATE;
        else if (!s->simple)
            fl = GEO_SI_SELF | GEO_SI_NONCONVEX;
        else if (!s->convex)
            fl = GEO_SI_NONCONVEX;
        atomic_init(&j->flags[f], fl);
    }
}

int geo_selfint_find(const geo_poly *p, const geo_bvh *bvh,
                     const geo_selfint_opts *opts, const geo_ctx *ctx,
                     geo_selfint *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    geo_selfint_opts o;
    if (opts)
        o = *opts;
    else
        geo_selfint_opts_default(&o);
    if (o.max_tasks < 8)
        o.max_tasks = 8;
    int rc = o.indices_checked ? 0 : geo_poly_validate_indices(p, err);
    if (rc < 0)
        return rc;
    uint32_t nf = p->nfacets;
    if (bvh && bvh->nitems != nf)
        return geo_err_set(err, -EINVAL,
                           "self-intersection: the BVH has %u items for %u "
                           "facets", bvh->nitems, nf);
    uint32_t maxn = 3;
    for (uint32_t f = 0; f < nf; f++)
        if (geo_poly_facet_size(p, f) > maxn)
            maxn = geo_poly_facet_size(p, f);
    search s = {0};
    geo_fbvh *own = NULL;
    geo_facet_shape *shapes = NULL;
    uint64_t *masks = NULL;
    if (maxn > 3) {
        shapes = malloc(((size_t)nf + 1) * sizeof *shapes);
        masks = malloc(((size_t)nf + 1) * sizeof *masks);
    }
    const uint64_t **sorted = NULL;
    uint64_t *keys = NULL;
    atomic_uchar *flags = malloc(((size_t)nf + 1) * sizeof *flags);
    uint8_t *plain = malloc((size_t)nf + 1);
    uint32_t *ta = malloc((size_t)o.max_tasks * sizeof *ta);
    uint32_t *tb = malloc((size_t)o.max_tasks * sizeof *tb);
    task_out *out = NULL;
    uint32_t ntasks = 0, (*tags)[3] = NULL;
    pair_list all = {0};
    if ((maxn > 3 && (!shapes || !masks)) || !flags || !plain || !ta ||
        !tb || sort_large_facets(p, &sorted, &keys) < 0)
        goto oom;

    shape_job sj = {p, shapes, masks, flags, 4096};
    geo_ctx_parallel_for(ctx, (nf + sj.block - 1) / sj.block, run_shapes, &sj);
    if ((rc = geo_ctx_progress(ctx, 0.05)) < 0)
        goto fail;
    if (!bvh) {
        /* the answer does not depend on the tree: the fastest to build,
         * the smallest */
        own = geo_fbvh_build_facets(p, err);
        if (!own)
            goto oom;
    }
    if ((rc = geo_ctx_progress(ctx, 0.15)) < 0)
        goto fail;
    if (own && maxn == 3 && o.simple_fans &&
        (tags = fan_tags(p, own, o.simple_fans)))
        own->tags = (const uint32_t (*)[3])tags;

    ntasks = own ? geo_fbvh_pair_tasks(own, ta, tb, o.max_tasks)
                 : geo_bvh_pair_tasks(bvh, ta, tb, o.max_tasks);
    out = calloc((size_t)ntasks + 1, sizeof *out);
    if (!out)
        goto oom;
    s.p = p, s.h = bvh, s.fh = own, s.ctx = ctx;
    s.shapes = shapes, s.masks = masks;
    s.all_tri = maxn == 3;
    s.fans = s.all_tri ? o.simple_fans : NULL;
    s.flags = flags;
    s.sorted = sorted;
    s.keep = o.max_pairs, s.maxn = maxn, s.ta = ta, s.tb = tb, s.out = out;
    atomic_init(&s.stop, 0);
    /* batches, so that progress and cancellation are seen from the
     * calling thread between them: up to 16, one per 16,384 facets (each
     * batch wakes the caller's pool, which costs more than a small
     * model's whole search; the tasks check cancellation themselves) */
    uint32_t nbatch = 1 + nf / 16384;
    if (nbatch > 16)
        nbatch = 16;
    uint32_t per = (ntasks + nbatch - 1) / nbatch;
    if (per == 0)
        per = 1;
    for (uint32_t b0 = 0; b0 < ntasks; b0 += per) {
        uint32_t cnt = ntasks - b0 < per ? ntasks - b0 : per;
        s.first = b0;
        geo_ctx_parallel_for(ctx, cnt, run_task, &s);
        for (uint32_t t = b0; t < b0 + cnt; t++)
            if (out[t].err < 0) {
                rc = out[t].err;
                goto oom;
            }
        if (atomic_load(&s.stop) || geo_ctx_canceled(ctx)) {
            rc = -ECANCELED;
            goto fail;
        }
        if ((rc = geo_ctx_progress(ctx, 0.15 + 0.85 * (b0 + cnt) /
                                                  (double)ntasks)) < 0)
            goto fail;
    }

    /* merge: self-intersecting facets as (f, f), then every task's pairs */
    uint64_t count = 0;
    for (uint32_t f = 0; f < nf; f++) {
        plain[f] = atomic_load_explicit(&flags[f], memory_order_relaxed);
        if (plain[f] & GEO_SI_SELF) {
            count++;
            if (list_add(&all, f, f, o.max_pairs) < 0)
                goto oom;
        }
        if (plain[f] & (GEO_SI_PAIR | GEO_SI_SELF))
            ret->nflagged++;
        if (plain[f] & GEO_SI_DEGENERATE)
            ret->ndegenerate++;
    }
    for (uint32_t t = 0; t < ntasks; t++) {
        count += out[t].count;
        for (size_t k = 0; k < out[t].list.n; k++)
            if (list_add(&all, out[t].list.v[k][0], out[t].list.v[k][1],
                         o.max_pairs) < 0)
                goto oom;
    }
    if (all.n)
        qsort(all.v, all.n, sizeof *all.v, cmp_pair);
    if (all.n > o.max_pairs)
        all.n = o.max_pairs;
    ret->count = count;
    ret->npairs = (uint32_t)all.n;
    ret->pairs = all.n ? (uint32_t (*)[2])all.v : NULL;
    if (!all.n)
        free(all.v);
    all.v = NULL;
    ret->nfacets = nf;
    ret->facet_flags = plain;
    plain = NULL;
    rc = geo_ctx_progress(ctx, 1.0);
    if (rc < 0)
        goto fail;
    goto done;
oom:
    rc = geo_err_set(err, -ENOMEM, "self-intersection: out of memory");
fail:
    if (rc == -ECANCELED)
        geo_err_set(err, rc, "self-intersection: canceled");
    geo_selfint_clear(ret);
done:
    for (uint32_t t = 0; out && t < ntasks; t++)
        free(out[t].list.v);
    free(out);
    free(all.v);
    geo_fbvh_free(own);
    free(tags);
    free(shapes);
    free(masks);
    free(sorted);
    free(keys);
    free(flags);
    free(plain);
    free(ta);
    free(tb);
    return rc;
}
