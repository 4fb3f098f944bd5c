/* hole_fill.c — minimum-weight hole triangulation, refinement with edge
 * restoration and hard-edge splits, umbrella-operator fairing (see
 * hole_fill.h for the method and its contracts).
 *
 * Invariants: `edges` holds every undirected edge of the mesh as it will
 * be once the patches found so far are added, so no chord is ever created
 * twice; the refinement works on a geo_tmesh holding only the region's
 * triangles, whose boundary edges (twin outside the region) are never
 * touched. */
#include "hole_fill.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grow.h"
#include "edgemap.h"
#include "spchol.h"
#include "topo.h"
#include "trimesh.h"
#include "vec.h"

const char *geo_hole_status_name(enum geo_hole_status s)
{
    switch (s) {
    case GEO_HOLE_FILLED:
        return "filled";
    case GEO_HOLE_TOO_LARGE:
        return "too_large";
    case GEO_HOLE_NOT_A_LOOP:
        return "not_a_loop";
    case GEO_HOLE_NO_TRIANGULATION:
        return "no_triangulation";
    case GEO_HOLE_DEGENERATE:
        return "degenerate";
    case GEO_HOLE_INTERSECTS:
        return "intersects_mesh";
    case GEO_HOLE_FILLED_PLANAR:
        return "filled_planar";
    }
    return "unknown";
}

void geo_fill_opts_default(geo_fill_opts *o)
{
    memset(o, 0, sizeof *o);
    o->weight = GEO_FILL_AREA;
    o->refine = true;
    o->fair = GEO_FAIR_UNIFORM;
    o->density = 1.0;
    o->hard_angle_deg = 45.0;
    o->max_dp_vertices = 128;
    o->max_hole_vertices = 100000;
    o->fair_iterations = 50;
    o->check_each = true;
}

void geo_fill_stats_clear(geo_fill_stats *stats)
{
    if (!stats)
        return;
    free(stats->holes);
    memset(stats, 0, sizeof *stats);
}

typedef struct filler {
    geo_poly *p;
    geo_fill_opts o;
    geo_edgemap edges;  /* undirected edges, current + committed patches */
    double up[3];        /* unit mean normal of the loop being filled */
    uint32_t (*tris)[3]; /* patch triangles of all holes */
    size_t ntris, cap;
    uint64_t *log;       /* edges added for the loop being filled */
    size_t nlog, cap_log;
} filler;

/* Adds undirected edge a–b to the edge set, logging it when new so a
 * failed loop can take it back. */
static int add_edge(filler *F, uint32_t a, uint32_t b)
{
    uint64_t key = geo_edge_ukey(a, b);
    if (geo_edgemap_get(&F->edges, key) != UINT32_MAX)
        return 0;
    if (geo_grow((void **)&F->log, &F->cap_log, F->nlog + 1,
                 sizeof *F->log) < 0)
        return -ENOMEM;
    if (geo_edgemap_put(&F->edges, key, 1) < 0)
        return -ENOMEM;
    F->log[F->nlog++] = key;
    return 0;
}

static int push_tri(filler *F, uint32_t a, uint32_t b, uint32_t c)
{
    if (F->ntris == F->cap) {
        size_t nc = F->cap ? 2 * F->cap : 256;
        uint32_t(*nt)[3] = realloc(F->tris, nc * sizeof *nt);
        if (!nt)
            return -ENOMEM;
        F->tris = nt;
        F->cap = nc;
    }
    F->tris[F->ntris][0] = a;
    F->tris[F->ntris][1] = b;
    F->tris[F->ntris][2] = c;
    F->ntris++;
    return 0;
}

static bool has_edge(const filler *F, uint32_t a, uint32_t b)
{
    return geo_edgemap_get(&F->edges, geo_edge_ukey(a, b)) != UINT32_MAX;
}

/* ω of triangle (a, b, c); INFINITY for a degenerate one. ret_n gets
 * the cross product of its edges (as listed: twice the area along the
 * normal). */
static double tri_weight(const filler *F, uint32_t a, uint32_t b, uint32_t c,
                         double ret_n[3])
{
    const double *pa = F->p->verts[a], *pb = F->p->verts[b],
                 *pc = F->p->verts[c];
    double e1[3], e2[3];
    geo_vsub(pb, pa, e1);
    geo_vsub(pc, pa, e2);
    geo_vcross(e1, e2, ret_n);
    double area = 0.5 * geo_vlen(ret_n);
    double per = geo_vdist(pa, pb) + geo_vdist(pb, pc) + geo_vdist(pc, pa);
    if (!(area > 1e-14 * per * per))
        return INFINITY;
    return F->o.weight == GEO_FILL_EDGES ? per : area;
}

/* Unit normal of triangle (a, b, c) as listed; zero when degenerate. */
static void tri_normal(const filler *F, uint32_t a, uint32_t b, uint32_t c,
                       double ret[3])
{
    double e1[3], e2[3];
    geo_vsub(F->p->verts[b], F->p->verts[a], e1);
    geo_vsub(F->p->verts[c], F->p->verts[a], e2);
    geo_vcross(e1, e2, ret);
    if (geo_vnormalize(ret) == 0)
        ret[0] = ret[1] = ret[2] = 0;
}

/* Angle between unit normals n1 and n2 (radians, 0 = the surface goes on
 * flat); 0 when either is zero (nothing known across that edge). */
static double normal_angle(const double n1[3], const double n2[3])
{
    if (geo_vdot(n1, n1) == 0 || geo_vdot(n2, n2) == 0)
        return 0.0;
    double x[3];
    geo_vcross(n1, n2, x);
    return atan2(geo_vlen(x), geo_vdot(n1, n2));
}

/* Liepa's order for GEO_FILL_ANGLE: the larger dihedral angle loses, area
 * breaks ties (angles within 1e-9 rad count as equal, so rounding noise
 * on a flat loop leaves the choice to the area). */
static bool angle_less(double a1, double w1, double a2, double w2)
{
    if (a1 < a2 - 1e-9)
        return true;
    if (a1 > a2 + 1e-9)
        return false;
    return w1 < w2;
}

/* Whether unit normals n1 and n2 (both known) point more than 120° apart:
 * the two facets fold onto each other (the bound fair() uses too). */
static bool turned_back(const double n1[3], const double n2[3])
{
    return geo_vdot(n1, n1) > 0 && geo_vdot(n2, n2) > 0 &&
           geo_vdot(n1, n2) < -0.5;
}

/* Whether triangle (w_i, w_m, w_k) of an n-gon, with edge cross product
 * nt (not degenerate), obeys dp's rules at strictness strict. */
static bool admissible(const filler *F, const uint32_t *w, double (*en)[3],
                       int strict, uint32_t i, uint32_t m, uint32_t k,
                       uint32_t n, const double nt[3])
{
    if (F->o.admit && !F->o.admit(F->o.admit_user, w[i], w[m], w[k]))
        return false;
    if (strict >= 2 && !(geo_vdot(nt, F->up) > 0))
        return false;
    if (strict < 1 || !en)
        return true;
    double u[3];
    geo_vscale(nt, 1.0 / geo_vlen(nt), u);
    return !((m == i + 1 && turned_back(u, en[i])) ||
             (k == m + 1 && turned_back(u, en[m])) ||
             (i == 0 && k == n - 1 && turned_back(u, en[n - 1])));
}

/* Whether every edge of polygon w[0..n) lies on some triangle of its
 * vertices that dp admits at strictness strict — else dp cannot succeed
 * (a loop closing a cone steeper than 60° with a flat lid, say), and
 * this O(n²) look saves its O(n³) run. */
static bool edges_coverable(const filler *F, const uint32_t *w, uint32_t n,
                            double (*en)[3], int strict)
{
    for (uint32_t j = 0; j < n; j++) {
        bool found = false;
        for (uint32_t x = 0; x < n && !found; x++) {
            uint32_t j1 = (j + 1) % n;
            if (x == j || x == j1)
                continue;
            /* the triangle's corners in polygon order */
            uint32_t c[3] = {j, j1, x}, t;
            for (int a = 0; a < 2; a++)
                for (int b = 0; b < 2 - a; b++)
                    if (c[b] > c[b + 1])
                        t = c[b], c[b] = c[b + 1], c[b + 1] = t;
            double nt[3];
            if (isfinite(tri_weight(F, w[c[0]], w[c[1]], w[c[2]], nt)))
                found = admissible(F, w, en, strict, c[0], c[1], c[2], n,
                                   nt);
        }
        if (!found)
            return false;
    }
    return true;
}

/* Liepa's dynamic programme on polygon w[0..n). en, when not NULL, holds
 * for each polygon edge w[i] → w[i+1 mod n] the unit normal of the facet
 * across it (zero: none); TN[i,k] is the normal of the triangle the
 * chosen triangulation of (w_i … w_k) puts on the chord (i, k) (the facet
 * across, for a polygon edge), which GEO_FILL_ANGLE weighs by. strict
 * restricts the triangles: from 1 on, none may turn back over the facet
 * across a polygon edge (turned_back: the patch would fold onto the mesh
 * around the hole); from 2 on, each must also face the side F->up points
 * to (on a loop that is simple seen along its mean normal this is a
 * patch without folds). Returns 0, 1 when no admissible triangulation
 * exists, or -ENOMEM. Commits its triangles and chords on success. */
static int dp(filler *F, const uint32_t *w, uint32_t n,
              double (*en)[3], int strict, geo_hole_report *rep)
{
    size_t nn = (size_t)n * n;
    bool angle = F->o.weight == GEO_FILL_ANGLE;
    double *W = malloc(nn * sizeof *W);
    double *A = angle ? malloc(nn * sizeof *A) : NULL;
    double(*TN)[3] = angle ? malloc(nn * sizeof *TN) : NULL;
    uint32_t *M = malloc(nn * sizeof *M);
    uint8_t *ok = malloc(nn);
    uint32_t(*stack)[2] = malloc((size_t)n * sizeof *stack);
    /* for the area and edge weights: W transposed (WT[k·n + m] =
     * W[m·n + k], so the inner loop reads both halves contiguously), the
     * chord lengths and the polygon's points, so a triangle costs one
     * cross product and at most one square root */
    double *WT = angle ? NULL : malloc(nn * sizeof *WT);
    double *LEN = angle ? NULL : malloc(nn * sizeof *LEN);
    double(*P)[3] = angle ? NULL : malloc((size_t)n * sizeof *P);
    int rc = 0;
    if (!W || !M || !ok || !stack || (angle && (!A || !TN)) ||
        (!angle && (!WT || !LEN || !P))) {
        rc = -ENOMEM;
        goto out;
    }
    if (!angle) {
        for (uint32_t i = 0; i < n; i++)
            memcpy(P[i], F->p->verts[w[i]], sizeof P[i]);
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t k = i + 1; k < n; k++)
                LEN[(size_t)i * n + k] = geo_vdist(P[i], P[k]);
    }
    static const double zero[3] = {0, 0, 0};
    const double *closing = en ? en[n - 1] : zero;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t k = i + 1; k < n; k++) {
            bool side = k == i + 1 || (i == 0 && k == n - 1);
            ok[(size_t)i * n + k] =
                side || (w[i] != w[k] && !has_edge(F, w[i], w[k]));
        }
    for (uint32_t i = 0; i + 1 < n; i++) {
        size_t ik = (size_t)i * n + i + 1;
        W[ik] = 0.0;
        if (WT)
            WT[(size_t)(i + 1) * n + i] = 0.0;
        if (angle)
            A[ik] = 0.0;
        if (TN) /* the facet across a loop edge, seen from the patch */
            memcpy(TN[ik], en ? en[i] : zero, sizeof TN[ik]);
    }
    for (uint32_t gap = 2; gap < n; gap++)
        for (uint32_t i = 0; i + gap < n; i++) {
            uint32_t k = i + gap;
            size_t ik = (size_t)i * n + k;
            bool top = i == 0 && k == n - 1;
            double best = INFINITY, besta = INFINITY;
            uint32_t bm = i + 1;
            if (angle)
                A[ik] = INFINITY;
            for (uint32_t m = i + 1; m < k && ok[ik] && angle; m++) {
                size_t im = (size_t)i * n + m, mk = (size_t)m * n + k;
                double ws = W[im] + W[mk];
                double a = A[im] > A[mk] ? A[im] : A[mk];
                if (!angle_less(a, ws, besta, best))
                    continue;
                double nt[3];
                double t = tri_weight(F, w[i], w[m], w[k], nt);
                if (!isfinite(t) ||
                    !admissible(F, w, en, strict, i, m, k, n, nt))
                    continue;
                geo_vnormalize(nt);
                a = fmax(a, normal_angle(nt, TN[im]));
                a = fmax(a, normal_angle(nt, TN[mk]));
                if (top)
                    a = fmax(a, normal_angle(nt, closing));
                if (angle_less(a, ws + t, besta, best)) {
                    besta = a;
                    best = ws + t;
                    bm = m;
                }
            }
            const double *Wi = angle ? NULL : W + (size_t)i * n;
            const double *Wk = angle ? NULL : WT + (size_t)k * n;
            for (uint32_t m = i + 1; m < k && ok[ik] && !angle; m++) {
                double ws = Wi[m] + Wk[m];
                if (ws >= best)
                    continue;
                /* tri_weight on the tables: same rule, same values */
                double e1[3], e2[3], nt[3];
                geo_vsub(P[m], P[i], e1);
                geo_vsub(P[k], P[i], e2);
                geo_vcross(e1, e2, nt);
                double n2 = geo_vdot(nt, nt);
                double per = LEN[(size_t)i * n + m] + LEN[(size_t)m * n + k] +
                             LEN[ik];
                double area = 0.5 * sqrt(n2);
                if (!(area > 1e-14 * per * per))
                    continue;
                double t = ws + (F->o.weight == GEO_FILL_EDGES ? per : area);
                if (t < best && admissible(F, w, en, strict, i, m, k, n, nt)) {
                    best = t;
                    bm = m;
                }
            }
            if (angle)
                A[ik] = besta;
            if (TN && isfinite(best))
                tri_normal(F, w[i], w[bm], w[k], TN[ik]);
            else if (TN)
                memcpy(TN[ik], zero, sizeof TN[ik]);
            W[ik] = best;
            if (WT)
                WT[(size_t)k * n + i] = best;
            M[ik] = bm;
        }
    if (!isfinite(W[n - 1])) {
        rc = 1;
        goto out;
    }
    size_t top = 0, first = F->ntris;
    stack[top][0] = 0;
    stack[top][1] = n - 1;
    top++;
    while (top > 0) {
        top--;
        uint32_t i = stack[top][0], k = stack[top][1];
        if (k - i < 2)
            continue;
        uint32_t m = M[(size_t)i * n + k];
        if ((rc = push_tri(F, w[i], w[m], w[k])) < 0)
            goto out;
        stack[top][0] = i;
        stack[top][1] = m;
        stack[top + 1][0] = m;
        stack[top + 1][1] = k;
        top += 2;
    }
    for (size_t t = first; t < F->ntris; t++)
        for (int e = 0; e < 3; e++)
            if ((rc = add_edge(F, F->tris[t][e], F->tris[t][(e + 1) % 3])) <
                0)
                goto out;
    rep->ntriangles += (uint32_t)(F->ntris - first);
    rep->weight += W[n - 1];
    if (angle && A[n - 1] > rep->max_angle)
        rep->max_angle = A[n - 1];
out:
    free(W), free(A), free(TN), free(M), free(ok), free(stack);
    free(WT), free(LEN), free(P);
    return rc;
}

/* Unit Newell normal of polygon w[0..n) (zero when it has none): the
 * polygon turns counter-clockwise seen from its tip. */
static void newell_normal(const filler *F, const uint32_t *w, uint32_t n,
                          double ret[3])
{
    ret[0] = ret[1] = ret[2] = 0;
    for (uint32_t i = 0; i < n; i++) {
        const double *a = F->p->verts[w[i]], *b = F->p->verts[w[(i + 1) % n]];
        ret[0] += (a[1] - b[1]) * (a[2] + b[2]);
        ret[1] += (a[2] - b[2]) * (a[0] + b[0]);
        ret[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    if (geo_vnormalize(ret) == 0)
        ret[0] = ret[1] = ret[2] = 0;
}

/* Whether the chord from w[a] to w[b] leaves w[a] inside the polygon's
 * angle there (from the next edge counter-clockwise to the previous one),
 * seen along the polygon's mean normal nw. */
static bool within_corner(const filler *F, const uint32_t *w, uint32_t n,
                          const double nw[3], uint32_t a, uint32_t b)
{
    const double *pa = F->p->verts[w[a]];
    double e[3], x[3], y[3], c[3];
    geo_vsub(F->p->verts[w[(a + 1) % n]], pa, e);
    geo_vsub(F->p->verts[w[(a + n - 1) % n]], pa, x);
    geo_vsub(F->p->verts[w[b]], pa, y);
    /* counter-clockwise angle from e, in [0, 2π) */
    geo_vcross(e, x, c);
    double ax = atan2(geo_vdot(c, nw), geo_vdot(e, x));
    geo_vcross(e, y, c);
    double ay = atan2(geo_vdot(c, nw), geo_vdot(e, y));
    if (ax < 0)
        ax += 2 * M_PI;
    if (ay < 0)
        ay += 2 * M_PI;
    return ay > 0 && ay < ax;
}

/* Twice the signed area of triangle (p, q, r) seen along nw. */
static double orient_along(const double nw[3], const double p[3],
                           const double q[3], const double r[3])
{
    double u[3], v[3], c[3];
    geo_vsub(q, p, u);
    geo_vsub(r, p, v);
    geo_vcross(u, v, c);
    return geo_vdot(c, nw);
}

/* Whether chord w[a]–w[b] crosses or touches an edge of polygon w[0..n)
 * other than those at its ends, seen along nw (floating point: choosing
 * a bridge decides nothing about the mesh's topology). */
static bool chord_crosses(const filler *F, const uint32_t *w, uint32_t n,
                          const double nw[3], uint32_t a, uint32_t b)
{
    const double *pa = F->p->verts[w[a]], *pb = F->p->verts[w[b]];
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = (i + 1) % n;
        if (i == a || j == a || i == b || j == b)
            continue;
        const double *p = F->p->verts[w[i]], *q = F->p->verts[w[j]];
        double d1 = orient_along(nw, pa, pb, p), d2 = orient_along(nw, pa, pb, q);
        if ((d1 > 0 && d2 > 0) || (d1 < 0 && d2 < 0))
            continue;
        double d3 = orient_along(nw, p, q, pa), d4 = orient_along(nw, p, q, pb);
        if (!((d3 > 0 && d4 > 0) || (d3 < 0 && d4 < 0)))
            return true;
    }
    return false;
}

typedef struct chord {
    double score;
    uint32_t lo, hi;
} chord;

/* The order chords are looked at in: by score, ties in the order they
 * were listed (as a stable sort would give). */
static bool chord_before(const chord *c, uint32_t x, uint32_t y)
{
    return c[x].score < c[y].score || (c[x].score == c[y].score && x < y);
}

/* Sifts heap[i] down in the min-heap heap[0..n) of chord indices. */
static void chord_sift(const chord *c, uint32_t *heap, uint32_t n, uint32_t i)
{
    for (;;) {
        uint32_t l = 2 * i + 1, r = l + 1, m = i;
        if (l < n && chord_before(c, heap[l], heap[m]))
            m = l;
        if (r < n && chord_before(c, heap[r], heap[m]))
            m = r;
        if (m == i)
            return;
        uint32_t t = heap[i];
        heap[i] = heap[m];
        heap[m] = t;
        i = m;
    }
}

/* The bridge of polygon w[0..n): of the chords from ≤ 256 evenly spaced
 * vertices to the opposite third of the loop, the one shortest relative
 * to the loop length it cuts off (the smaller side's arc) — on a round
 * loop a diameter meeting the loop squarely, not a chord leaving thin
 * wedges — among those that, seen along the polygon's mean normal, leave
 * both ends inside the polygon's angle there and cross no edge (of the
 * 64 best): a chord over the mesh leaves pieces that can only be closed
 * by folding over the loop's facets (a jagged rim's teeth stick out past
 * a chord grazing it). Without such a chord, the best one. 0, 1 (no
 * admissible chord) or -ENOMEM. */
static int choose_bridge(const filler *F, const uint32_t *w, uint32_t n,
                         uint32_t *ret_a, uint32_t *ret_b)
{
    uint32_t nstarts = n < 256 ? n : 256, nc = 0;
    double *arc = malloc(((size_t)n + 1) * sizeof *arc);
    chord *c = malloc(((size_t)nstarts * (n / 3 + 2) + 1) * sizeof *c);
    if (!arc || !c) {
        free(arc), free(c);
        return -ENOMEM;
    }
    arc[0] = 0;
    for (uint32_t i = 0; i < n; i++)
        arc[i + 1] = arc[i] + geo_vdist(F->p->verts[w[i]],
                                        F->p->verts[w[(i + 1) % n]]);
    for (uint32_t si = 0; si < nstarts; si++) {
        uint32_t a = (uint32_t)((uint64_t)si * n / nstarts);
        for (uint32_t d = n / 3; d <= 2 * n / 3; d++) {
            uint32_t b = (a + d) % n, lo = a < b ? a : b, hi = a < b ? b : a;
            if (w[lo] == w[hi] || has_edge(F, w[lo], w[hi]))
                continue;
            double len = geo_vdist(F->p->verts[w[lo]], F->p->verts[w[hi]]);
            double cut = arc[hi] - arc[lo];
            if (arc[n] - cut < cut)
                cut = arc[n] - cut;
            if (cut > 0 && isfinite(len / cut))
                c[nc++] = (chord){len / cut, lo, hi};
        }
    }
    free(arc);
    int rc = 1;
    if (nc > 0) {
        /* the chords in order of score, popped from a heap: only the few
         * looked at are ordered, not all n²/3 */
        uint32_t *heap = malloc((size_t)nc * sizeof *heap);
        if (!heap) {
            free(c);
            return -ENOMEM;
        }
        for (uint32_t k = 0; k < nc; k++)
            heap[k] = k;
        for (uint32_t k = nc / 2; k-- > 0;)
            chord_sift(c, heap, nc, k);
        double nw[3];
        newell_normal(F, w, n, nw);
        uint32_t pick = heap[0], tried = 0, left = nc;
        while (left > 0 && tried < 64) {
            uint32_t k = heap[0];
            heap[0] = heap[--left];
            chord_sift(c, heap, left, 0);
            if (!within_corner(F, w, n, nw, c[k].lo, c[k].hi) ||
                !within_corner(F, w, n, nw, c[k].hi, c[k].lo))
                continue;
            tried++;
            if (!chord_crosses(F, w, n, nw, c[k].lo, c[k].hi)) {
                pick = k;
                break;
            }
        }
        free(heap);
        *ret_a = c[pick].lo;
        *ret_b = c[pick].hi;
        rc = 0;
    }
    free(c);
    return rc;
}

/* Triangulates polygon w[0..n) (edge normals en as in dp, may be NULL),
 * cutting it by bridges while it is longer than max_dp_vertices. 0, 1 (no
 * admissible triangulation) or -ENOMEM. Recursion depth is O(log n): each
 * cut leaves at most 2n/3 + 1. */
static int fill_poly(filler *F, const uint32_t *w, uint32_t n,
                     double (*en)[3], geo_hole_report *rep)
{
    if (n <= F->o.max_dp_vertices) {
        /* a patch that folds only when nothing else fits: the minimum
         * area alone lays inverted slivers along jagged loops (three
         * teeth of a round loop's rim span one) and folds over the
         * loop's facets */
        int rc = 1;
        for (int strict = 2; strict >= 0 && rc == 1; strict--)
            if (strict == 0 || edges_coverable(F, w, n, en, strict))
                rc = dp(F, w, n, en, strict, rep);
        return rc;
    }
    uint32_t ba, bb;
    int rc = choose_bridge(F, w, n, &ba, &bb);
    if (rc != 0)
        return rc;
    rc = add_edge(F, w[ba], w[bb]);
    if (rc < 0)
        return rc;
    rep->nbridges++;
    uint32_t n1 = bb - ba + 1, n2 = n - bb + ba + 1;
    uint32_t *w2 = malloc((size_t)n2 * sizeof *w2);
    double(*en1)[3] = en ? malloc((size_t)n1 * sizeof *en1) : NULL;
    double(*en2)[3] = en ? malloc((size_t)n2 * sizeof *en2) : NULL;
    if (!w2 || (en && (!en1 || !en2))) {
        free(w2), free(en1), free(en2);
        return -ENOMEM;
    }
    memcpy(w2, w + bb, (size_t)(n - bb) * sizeof *w2);
    memcpy(w2 + (n - bb), w, (size_t)(ba + 1) * sizeof *w2);
    if (en) {
        /* the bridge's side: until the first half is in, the surface
         * across it is taken as the loop's mean plane (its Newell normal,
         * oriented like the patch), so the first half does not tilt
         * freely at the bridge and leave the second half a fold */
        memcpy(en1, en + ba, (size_t)(n1 - 1) * sizeof *en1);
        newell_normal(F, w, n, en1[n1 - 1]);
        memcpy(en2, en + bb, (size_t)(n - bb) * sizeof *en2);
        memcpy(en2 + (n - bb), en, (size_t)ba * sizeof *en2);
        memset(en2[n2 - 1], 0, sizeof en2[0]);
    }
    size_t first = F->ntris;
    rc = fill_poly(F, w + ba, n1, en1, rep);
    if (rc == 0 && en) {
        /* the second half sees the first half's triangle on the bridge */
        for (size_t t = first; t < F->ntris; t++) {
            const uint32_t *tv = F->tris[t];
            int hits = (tv[0] == w[ba] || tv[1] == w[ba] || tv[2] == w[ba]) +
                       (tv[0] == w[bb] || tv[1] == w[bb] || tv[2] == w[bb]);
            if (hits == 2) {
                tri_normal(F, tv[0], tv[1], tv[2], en2[n2 - 1]);
                break;
            }
        }
    }
    if (rc == 0)
        rc = fill_poly(F, w2, n2, en2, rep);
    free(w2), free(en1), free(en2);
    return rc;
}

/* Fills one loop; on failure the loop's triangles and chords are taken
 * back. Returns 0 or -ENOMEM; the outcome is in rep->status. */
static int fill_loop(filler *F, const uint32_t *w, uint32_t n,
                     double (*en)[3], geo_hole_report *rep)
{
    if (n < 3) {
        rep->status = GEO_HOLE_DEGENERATE;
        return 0;
    }
    if (n > F->o.max_hole_vertices) {
        rep->status = GEO_HOLE_TOO_LARGE;
        return 0;
    }
    size_t first = F->ntris;
    F->nlog = 0;
    newell_normal(F, w, n, F->up);
    int rc = fill_poly(F, w, n, en, rep);
    if (rc < 0)
        return rc;
    if (rc == 1) {
        for (size_t k = 0; k < F->nlog; k++)
            geo_edgemap_del(&F->edges, F->log[k]);
        F->ntris = first;
        rep->ntriangles = 0;
        rep->weight = 0;
        rep->max_angle = 0;
        rep->status = GEO_HOLE_NO_TRIANGULATION;
        return 0;
    }
    rep->status = GEO_HOLE_FILLED;
    return 0;
}

/* Least-squares plane of facet f, as geo_poly_facet_fit_plane gives it
 * unweighted; for a triangle, directly the plane through its corners
 * (what the fit finds, without the eigen-solver). */
static void fit_plane(const geo_poly *p, uint32_t f, double ret[4])
{
    if (geo_poly_facet_size(p, f) != 3) {
        geo_poly_facet_fit_plane(p, f, GEO_PLANE_UNWEIGHTED, ret);
        return;
    }
    const uint32_t *v = geo_poly_facet(p, f);
    double n[3], c[3];
    geo_poly_facet_area_vector(p, f, n);
    if (geo_vnormalize(n) == 0) {
        /* collinear: as the fit falls back to */
        geo_poly_facet_fit_plane(p, f, GEO_PLANE_UNWEIGHTED, ret);
        return;
    }
    for (int k = 0; k < 3; k++)
        c[k] = (p->verts[v[0]][k] + p->verts[v[1]][k] + p->verts[v[2]][k]) /
               3.0;
    memcpy(ret, n, sizeof n);
    ret[3] = -geo_vdot(n, c);
}

/* ---- refinement ---- */

/* What a facet of the refinement region is (its tag in the tmesh; split
 * pieces inherit it): one of the mesh's, or a triangle of a patch made
 * here. */
enum { REGION_GIVEN = 1, REGION_PATCH = 2 };

typedef struct refiner {
    geo_fill_opts o;
    geo_tmesh m;
    geo_edgemap outside; /* undirected edges of facets outside the region */
    double *s;           /* desired edge length per vertex */
    size_t cap_s;
    uint64_t budget;     /* vertices refinement may still add */
    double cos_hard;
    geo_edgemap hard;    /* undirected hard edges (found once, see below) */
    geo_tmesh_probe probe;
    geo_fill_stats *st;
} refiner;

/* Moves point p, made from the nfrom vertices from[], onto the surface
 * (opts.place, or opts.project). 0, or -EDOM when either refuses it. */
static int place_point(const refiner *R, double p[3], const uint32_t *from,
                       uint32_t nfrom)
{
    if (R->o.place) {
        const double *fp[3];
        for (uint32_t k = 0; k < nfrom; k++)
            fp[k] = R->m.v[from[k]];
        return R->o.place(R->o.project_user, p, fp, nfrom) ? 0 : -EDOM;
    }
    if (R->o.project && !R->o.project(R->o.project_user, p))
        return -EDOM;
    return 0;
}

/* Whether replacing region triangles old[0..nold) by newt[0..nnew)
 * (GEO_TMESH_NEWV standing at x) keeps the surface free of contacts
 * within two rings of them (geo_tmesh_clashes; the tmesh holds the
 * facets outside the region too, so contacts with them are seen). 1
 * clear, 0 not, or -ENOMEM. */
static int clear_of(refiner *R, const uint32_t *old, uint32_t nold,
                    const uint32_t (*newt)[3], uint32_t nnew, const double x[3])
{
    if (!R->o.check_each)
        return 1; /* the caller checks the finished patch instead */
    int rc = geo_tmesh_clashes(&R->m, &R->probe, old, nold, newt, nnew,
                               UINT32_MAX, x, 2);
    return rc < 0 ? rc : !rc;
}

/* Adds vertex q (already placed) with desired length sv. Returns its
 * index, -ERANGE when the budget is spent, or -ENOMEM. */
static int64_t new_vertex(refiner *R, const double q[3], double sv)
{
    if (R->budget == 0)
        return -ERANGE;
    if (R->m.nv >= R->cap_s) {
        size_t nc = 2 * R->cap_s + 64;
        double *ns = realloc(R->s, nc * sizeof *ns);
        if (!ns)
            return -ENOMEM;
        R->s = ns;
        R->cap_s = nc;
    }
    int64_t x = geo_tmesh_add_vertex(&R->m, q);
    if (x < 0)
        return x;
    R->s[x] = sv;
    R->budget--;
    R->st->nverts_added++;
    return x;
}

static double angle_at(const double *c, const double *a, const double *b)
{
    double u[3], v[3], x[3];
    geo_vsub(a, c, u);
    geo_vsub(b, c, v);
    geo_vcross(u, v, x);
    return atan2(geo_vlen(x), geo_vdot(u, v));
}

/* "Restores" edge a–b: flips it when not Delaunay, or splits it when it
 * is a hard edge that is too long. 1 when the mesh changed, 0 when not,
 * or a negative errno. */
static int relax(refiner *R, uint32_t a, uint32_t b)
{
    geo_tmesh *m = &R->m;
    uint32_t h1 = geo_tmesh_find(m, a, b), h2 = geo_tmesh_find(m, b, a);
    if (h1 == UINT32_MAX || h2 == UINT32_MAX || !m->tag[h1 / 3] ||
        !m->tag[h2 / 3])
        return 0; /* the region's boundary stays fixed */
    uint32_t c = geo_tmesh_opposite(m, h1), d = geo_tmesh_opposite(m, h2);
    uint32_t old[2] = {h1 / 3, h2 / 3};
    const double *pa = m->v[a], *pb = m->v[b], *pc = m->v[c], *pd = m->v[d];
    if (geo_edgemap_get(&R->hard, geo_edge_ukey(a, b)) != UINT32_MAX) {
        double sa = R->s[a], sb = R->s[b];
        if (!(sqrt(2.0) * geo_vdist(pa, pb) > 0.5 * (sa + sb)) ||
            !(sa + sb > 0))
            return 0;
        double S[3];
        for (int k = 0; k < 3; k++)
            S[k] = (sa * pb[k] + sb * pa[k]) / (sa + sb);
        uint32_t ends[2] = {a, b}, X = GEO_TMESH_NEWV;
        if (R->budget == 0 || place_point(R, S, ends, 2) < 0)
            return 0;
        uint32_t nt[4][3] = {{a, X, c}, {X, b, c}, {b, X, d}, {X, a, d}};
        int ok = clear_of(R, old, 2, (const uint32_t(*)[3])nt, 4, S);
        if (ok <= 0)
            return ok;
        int64_t x = new_vertex(R, S, 0.5 * (sa + sb));
        if (x < 0)
            return x == -ERANGE ? 0 : (int)x;
        int rc = geo_tmesh_split_edge(m, a, b, (uint32_t)x);
        if (rc == 0)
            rc = geo_edgemap_put(&R->hard, geo_edge_ukey(a, (uint32_t)x), 1);
        if (rc == 0)
            rc = geo_edgemap_put(&R->hard, geo_edge_ukey((uint32_t)x, b), 1);
        if (rc < 0)
            return rc;
        geo_edgemap_del(&R->hard, geo_edge_ukey(a, b));
        R->st->nhard_splits++;
        return 1;
    }
    /* a degenerate side has a zero normal and does not vote below */
    double n1[3], n2[3];
    geo_tmesh_normal(m, h1 / 3, n1);
    geo_tmesh_normal(m, h2 / 3, n2);
    if (c == d || angle_at(pc, pa, pb) + angle_at(pd, pa, pb) <= M_PI + 1e-9)
        return 0;
    if (geo_edgemap_get(&R->outside, geo_edge_ukey(c, d)) != UINT32_MAX)
        return 0;
    /* nor create an edge across a feature of the surface */
    if (R->o.crosses_feature &&
        R->o.crosses_feature(R->o.project_user, pc, pd))
        return 0;
    /* the flipped pair must not fold over */
    double ns[3], e1[3], e2[3], t1[3], t2[3];
    geo_vadd(n1, n2, ns);
    geo_vsub(pd, pa, e1);
    geo_vsub(pc, pa, e2);
    geo_vcross(e1, e2, t1);
    geo_vsub(pc, pb, e1);
    geo_vsub(pd, pb, e2);
    geo_vcross(e1, e2, t2);
    if (!(geo_vdot(t1, ns) > 0 && geo_vdot(t2, ns) > 0))
        return 0;
    /* nor bend more than a hard edge would, unless the pair bent even
     * more before (slivers along a silhouette) */
    if (geo_vnormalize(t1) == 0 || geo_vnormalize(t2) == 0 ||
        geo_vdot(t1, t2) < fmin(R->cos_hard, geo_vdot(n1, n2)))
        return 0;
    if (geo_tmesh_find(m, c, d) != UINT32_MAX ||
        geo_tmesh_find(m, d, c) != UINT32_MAX)
        return 0;
    uint32_t nt[2][3] = {{a, d, c}, {b, c, d}};
    int ok = clear_of(R, old, 2, (const uint32_t(*)[3])nt, 2, pa);
    if (ok <= 0)
        return ok;
    int rc = geo_tmesh_flip(m, a, b);
    if (rc == -EEXIST)
        return 0;
    if (rc < 0)
        return rc;
    R->st->nflips++;
    return 1;
}

/* Restores every interior edge until none changes (bounded sweeps). */
static int relax_all(refiner *R)
{
    for (int sweep = 0; sweep < 64; sweep++) {
        uint32_t changed = 0, nt = R->m.nt;
        for (uint32_t t = 0; t < nt; t++)
            for (int k = 0; k < 3 && !R->m.dead[t] && R->m.tag[t]; k++) {
                uint32_t a = R->m.t[t][k], b = R->m.t[t][(k + 1) % 3];
                if (a > b)
                    continue;
                int rc = relax(R, a, b);
                if (rc < 0)
                    return rc;
                changed += (uint32_t)rc;
            }
        if (changed == 0)
            return 0;
    }
    return 0;
}

static int refine_passes(refiner *R, const geo_ctx *ctx)
{
    double alpha = R->o.density;
    /* restore first: a minimum-weight patch may be all slivers (every
     * triangulation of a flat loop has the same area), whose centroids
     * would never pass the split test */
    int rc0 = relax_all(R);
    if (rc0 < 0)
        return rc0;
    for (int pass = 0; pass < 64; pass++) {
        if (geo_ctx_canceled(ctx))
            return -ECANCELED;
        uint32_t nsplit = 0, nt = R->m.nt;
        for (uint32_t t = 0; t < nt && R->budget > 0; t++) {
            if (R->m.dead[t] || !R->m.tag[t])
                continue;
            uint32_t v[3] = {R->m.t[t][0], R->m.t[t][1], R->m.t[t][2]};
            double c[3] = {0, 0, 0}, sc = 0;
            for (int k = 0; k < 3; k++) {
                geo_vadd(c, R->m.v[v[k]], c);
                sc += R->s[v[k]];
            }
            geo_vscale(c, 1.0 / 3.0, c);
            sc /= 3.0;
            bool split = true;
            for (int k = 0; k < 3 && split; k++) {
                double d = alpha * geo_vdist(c, R->m.v[v[k]]);
                split = d > sc && d > R->s[v[k]];
            }
            if (!split)
                continue;
            if (place_point(R, c, v, 3) < 0)
                continue;
            uint32_t X = GEO_TMESH_NEWV;
            uint32_t nt3[3][3] = {{v[0], v[1], X}, {v[1], v[2], X},
                                  {v[2], v[0], X}};
            int ok = clear_of(R, &t, 1, (const uint32_t(*)[3])nt3, 3, c);
            if (ok < 0)
                return ok;
            if (!ok)
                continue;
            int64_t x = new_vertex(R, c, sc);
            if (x == -ERANGE)
                break;
            if (x < 0)
                return (int)x;
            int rc = geo_tmesh_split_tri(&R->m, t, (uint32_t)x);
            if (rc < 0)
                return rc;
            nsplit++;
            R->st->nsplits++;
            for (int k = 0; k < 3; k++)
                if ((rc = relax(R, v[k], v[(k + 1) % 3])) < 0)
                    return rc;
        }
        if (nsplit == 0)
            return 0;
        int rc = relax_all(R);
        if (rc < 0)
            return rc;
    }
    return 0;
}

/* Desired edge lengths: the mean length of each vertex's edges outside
 * the region; vertices with none inherit from their region neighbours. */
static int desired_lengths(refiner *R, const geo_poly *p,
                           const uint8_t *in_region)
{
    uint32_t nv = p->nverts;
    uint32_t *cnt = calloc((size_t)nv + 1, sizeof *cnt);
    if (!cnt)
        return -ENOMEM;
    double *s = R->s;
    for (uint32_t v = 0; v < nv; v++)
        s[v] = 0;
    double total = 0;
    uint64_t ntotal = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (in_region[f])
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        for (uint32_t i = 0; i < k; i++) {
            uint32_t a = fv[i], b = fv[(i + 1) % k];
            double len = geo_vdist(p->verts[a], p->verts[b]);
            s[a] += len, cnt[a]++;
            s[b] += len, cnt[b]++;
            total += len;
            ntotal++;
        }
    }
    for (uint32_t v = 0; v < nv; v++)
        if (cnt[v])
            s[v] /= cnt[v];
    double fallback = ntotal ? total / (double)ntotal : 0.0;
    if (ntotal == 0) {
        /* no outside at all: the region's own mean edge length */
        for (uint32_t t = 0; t < R->m.nt; t++)
            for (int k = 0; k < 3 && R->m.tag[t]; k++) {
                total += geo_vdist(R->m.v[R->m.t[t][k]],
                                   R->m.v[R->m.t[t][(k + 1) % 3]]);
                ntotal++;
            }
        fallback = ntotal ? total / (double)ntotal : 1.0;
    }
    for (int sweep = 0; sweep < 32; sweep++) {
        uint32_t filled = 0, missing = 0;
        for (uint32_t t = 0; t < R->m.nt; t++) {
            if (!R->m.tag[t])
                continue;
            const uint32_t *tv = R->m.t[t];
            double sum = 0;
            uint32_t known = 0;
            for (int k = 0; k < 3; k++)
                if (cnt[tv[k]])
                    sum += s[tv[k]], known++;
            for (int k = 0; k < 3; k++) {
                if (cnt[tv[k]])
                    continue;
                if (known) {
                    s[tv[k]] = sum / known;
                    cnt[tv[k]] = UINT32_MAX; /* inherited */
                    filled++;
                } else {
                    missing++;
                }
            }
        }
        if (missing == 0 || filled == 0)
            break;
    }
    for (uint32_t v = 0; v < nv; v++)
        if (!cnt[v])
            s[v] = fallback;
    free(cnt);
    return 0;
}

/* Replaces p's facets: those outside the region, then the refined
 * triangles; vertices from m (a superset of p's). */
static int write_back(geo_poly *p, const uint8_t *in_region,
                      const geo_tmesh *m)
{
    geo_poly *q = geo_poly_new();
    uint32_t live = 0;
    for (uint32_t t = 0; t < m->nt; t++)
        live += !m->dead[t] && m->tag[t];
    if (!q || geo_poly_reserve(q, m->nv, (size_t)p->nfacets + live,
                               geo_poly_ncorners(p) + 3 * (size_t)live) < 0)
        goto oom;
    for (uint32_t v = 0; v < m->nv; v++)
        if (geo_poly_add_vertex(q, m->v[v]) < 0)
            goto oom;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (in_region[f])
            continue;
        int64_t nf = geo_poly_add_facet(q, geo_poly_facet(p, f),
                                        geo_poly_facet_size(p, f));
        if (nf < 0)
            goto oom;
        memcpy(q->planes[nf], p->planes[f], sizeof q->planes[0]);
    }
    for (uint32_t t = 0; t < m->nt; t++) {
        if (m->dead[t] || !m->tag[t])
            continue;
        int64_t nf = geo_poly_add_facet(q, m->t[t], 3);
        if (nf < 0)
            goto oom;
        fit_plane(q, (uint32_t)nf, q->planes[nf]);
    }
    geo_poly tmp = *p;
    *p = *q;
    *q = tmp;
    geo_poly_free(q);
    return 0;
oom:
    geo_poly_free(q);
    return -ENOMEM;
}

/* Whether a vertex of facet f has a mark of at least level. */
static bool facet_marked(const geo_poly *p, uint32_t f, const uint8_t *mark,
                         uint8_t level)
{
    const uint32_t *fv = geo_poly_facet(p, f);
    uint32_t k = geo_poly_facet_size(p, f);
    for (uint32_t i = 0; i < k; i++)
        if (mark[fv[i]] >= level)
            return true;
    return false;
}

static int refine(geo_poly *p, uint8_t *in_region, const geo_fill_opts *o,
                  geo_fill_stats *st, const geo_ctx *ctx)
{
    refiner R = {.o = *o, .st = st};
    R.cos_hard = cos(o->hard_angle_deg * M_PI / 180.0);
    int rc = -ENOMEM;
    uint64_t nreg = 0;
    uint8_t *near = NULL;
    if (geo_tmesh_init(&R.m, &p->verts[0][0], p->nverts) < 0 ||
        geo_edgemap_init(&R.outside, 64) < 0)
        goto out;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (!in_region[f])
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        int64_t t = geo_tmesh_add(&R.m, fv[0], fv[1], fv[2], in_region[f]);
        if (t == -EEXIST)
            in_region[f] = 0; /* not manifold there: leave it alone */
        else if (t < 0)
            goto out;
        else
            nreg++;
    }
    /* outside triangles near the region join the tmesh as fixed context
     * (tag 0), so the contact checks (two rings around each operation)
     * see them: those with a vertex within one edge of a region vertex.
     * Non-triangles and facets that would repeat a directed edge are left
     * out of it. */
    near = calloc((size_t)p->nverts + 1, 1);
    if (!near)
        goto out;
    for (uint32_t t = 0; t < R.m.nt; t++)
        for (int k = 0; k < 3; k++)
            near[R.m.t[t][k]] = 2;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (in_region[f] || !facet_marked(p, f, near, 2))
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < geo_poly_facet_size(p, f); i++)
            if (!near[fv[i]])
                near[fv[i]] = 1;
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (in_region[f] || !facet_marked(p, f, near, 1))
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        /* an edge between region vertices belongs to such a facet */
        for (uint32_t i = 0; i < k; i++)
            if (geo_edgemap_put(&R.outside,
                                geo_edge_ukey(fv[i], fv[(i + 1) % k]), 1) < 0)
                goto out;
        if (k == 3 && geo_tmesh_add(&R.m, fv[0], fv[1], fv[2], 0) == -ENOMEM)
            goto out;
    }
    if (geo_ctx_canceled(ctx)) {
        rc = -ECANCELED;
        goto out;
    }
    st->nregion_facets = (uint32_t)nreg;
    R.cap_s = (size_t)p->nverts + 64;
    R.s = malloc(R.cap_s * sizeof *R.s);
    if (!R.s)
        goto out;
    if ((rc = desired_lengths(&R, p, in_region)) < 0)
        goto out;
    /* hard edges are a property of the region as given (or of the
     * surface, when its normals are known): transient bends while it is
     * being refined must not start cascades of splits */
    if (geo_edgemap_init(&R.hard, 16) < 0)
        goto out;
    for (uint32_t t = 0; t < R.m.nt; t++)
        for (int k = 0; k < 3 && R.m.tag[t]; k++) {
            uint32_t a = R.m.t[t][k], b = R.m.t[t][(k + 1) % 3];
            uint32_t h2 = geo_tmesh_find(&R.m, b, a);
            if (a > b || h2 == UINT32_MAX || !R.m.tag[h2 / 3])
                continue;
            double n1[3], n2[3];
            if (o->hard_edge) {
                bool hard = o->hard_edge(o->project_user, R.m.v[a], R.m.v[b]);
                if (hard &&
                    geo_edgemap_put(&R.hard, geo_edge_ukey(a, b), 1) < 0)
                    goto out;
                continue;
            }
            /* a chord of a minimum-weight patch is no feature of the
             * surface: kept from flips it left fans of slivers at the
             * loop, which folded the faired patch */
            if (R.m.tag[t] == REGION_PATCH || R.m.tag[h2 / 3] == REGION_PATCH)
                continue;
            if (geo_tmesh_normal(&R.m, t, n1) > 0 &&
                geo_tmesh_normal(&R.m, h2 / 3, n2) > 0 &&
                geo_vdot(n1, n2) < R.cos_hard - 1e-12 &&
                geo_edgemap_put(&R.hard, geo_edge_ukey(a, b), 1) < 0)
                goto out;
        }
    R.budget = 64 * nreg + 1024;
    if ((rc = refine_passes(&R, ctx)) < 0)
        goto out;
    rc = write_back(p, in_region, &R.m);
out:
    geo_tmesh_destroy(&R.m);
    geo_edgemap_destroy(&R.outside);
    geo_edgemap_destroy(&R.hard);
    geo_tmesh_probe_destroy(&R.probe);
    free(R.s);
    free(near);
    return rc;
}

/* ---- fairing ---- */

typedef struct adjacency {
    uint32_t *start; /* nverts + 1 */
    uint32_t *nb;    /* sorted, unique neighbours */
} adjacency;

static int build_adjacency(const geo_poly *p, adjacency *A)
{
    uint32_t nv = p->nverts;
    size_t nc = geo_poly_ncorners(p);
    uint32_t *deg = calloc((size_t)nv + 1, sizeof *deg);
    A->start = calloc((size_t)nv + 2, sizeof *A->start);
    A->nb = malloc((2 * nc + 1) * sizeof *A->nb);
    if (!deg || !A->start || !A->nb) {
        free(deg);
        return -ENOMEM;
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        for (uint32_t i = 0; i < k; i++) {
            deg[fv[i]]++;
            deg[fv[(i + 1) % k]]++;
        }
    }
    for (uint32_t v = 0; v < nv; v++)
        A->start[v + 1] = A->start[v] + deg[v];
    memset(deg, 0, (size_t)nv * sizeof *deg);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        for (uint32_t i = 0; i < k; i++) {
            uint32_t a = fv[i], b = fv[(i + 1) % k];
            A->nb[A->start[a] + deg[a]++] = b;
            A->nb[A->start[b] + deg[b]++] = a;
        }
    }
    /* sort and squeeze out duplicates in place */
    uint32_t out = 0;
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t s0 = A->start[v], s1 = A->start[v + 1];
        /* a vertex has a handful of neighbours: insertion sort */
        for (uint32_t i = s0 + 1; i < s1; i++) {
            uint32_t x = A->nb[i], j = i;
            for (; j > s0 && A->nb[j - 1] > x; j--)
                A->nb[j] = A->nb[j - 1];
            A->nb[j] = x;
        }
        A->start[v] = out;
        for (uint32_t i = s0; i < s1; i++)
            if (i == s0 || A->nb[i] != A->nb[i - 1])
                A->nb[out++] = A->nb[i];
    }
    A->start[nv] = out;
    free(deg);
    return 0;
}

/* U¹ at vertex q with weights w(q,i) = 1 or |q − p_i|, where vertex `moved`
 * is taken at position x. */
static void umbrella1(const geo_poly *p, const adjacency *A, uint32_t q,
                      uint32_t moved, const double x[3], bool length,
                      double ret[3])
{
    const double *pq = q == moved ? x : p->verts[q];
    double sum[3] = {0, 0, 0}, wsum = 0;
    for (uint32_t k = A->start[q]; k < A->start[q + 1]; k++) {
        uint32_t i = A->nb[k];
        const double *pi = i == moved ? x : p->verts[i];
        double w = length ? geo_vdist(pq, pi) : 1.0;
        geo_vmadd(sum, w, pi, sum);
        wsum += w;
    }
    if (!(wsum > 0)) {
        ret[0] = ret[1] = ret[2] = 0;
        return;
    }
    for (int k = 0; k < 3; k++)
        ret[k] = -pq[k] + sum[k] / wsum;
}

/* |U²(x)| for vertex v placed at x (length weights). */
static double u2_norm(const geo_poly *p, const adjacency *A, uint32_t v,
                      const double x[3])
{
    double u[3], acc[3] = {0, 0, 0}, wsum = 0, ui[3];
    umbrella1(p, A, v, v, x, true, u);
    for (uint32_t k = A->start[v]; k < A->start[v + 1]; k++) {
        uint32_t i = A->nb[k];
        double w = geo_vdist(x, p->verts[i]);
        umbrella1(p, A, i, v, x, true, ui);
        geo_vmadd(acc, w, ui, acc);
        wsum += w;
    }
    if (!(wsum > 0))
        return 0;
    double r[3];
    for (int k = 0; k < 3; k++)
        r[k] = -u[k] + acc[k] / wsum;
    return geo_vlen(r);
}

/* Mean length of v's edges. */
static double local_length(const geo_poly *p, const adjacency *A, uint32_t v)
{
    double sum = 0;
    uint32_t n = A->start[v + 1] - A->start[v];
    for (uint32_t k = A->start[v]; k < A->start[v + 1]; k++)
        sum += geo_vdist(p->verts[v], p->verts[A->nb[k]]);
    return n ? sum / n : 0.0;
}

/* U²(p) = 0 for w = 1, solved for p (neighbours fixed):
 *   p·(1 + (1/n) Σ 1/n_i) = (2/n) Σ p_i − (1/n) Σ (1/n_i) Σ_{j≠p} p_ij. */
static void solve_uniform(const geo_poly *p, const adjacency *A, uint32_t v,
                          double ret[3])
{
    uint32_t n = A->start[v + 1] - A->start[v];
    double s1[3] = {0, 0, 0}, s2[3] = {0, 0, 0}, inv = 0;
    for (uint32_t k = A->start[v]; k < A->start[v + 1]; k++) {
        uint32_t i = A->nb[k];
        uint32_t ni = A->start[i + 1] - A->start[i];
        geo_vadd(s1, p->verts[i], s1);
        inv += 1.0 / ni;
        for (uint32_t q = A->start[i]; q < A->start[i + 1]; q++)
            if (A->nb[q] != v)
                geo_vmadd(s2, 1.0 / ni, p->verts[A->nb[q]], s2);
    }
    double den = 1.0 + inv / n;
    for (int k = 0; k < 3; k++)
        ret[k] = (2.0 / n * s1[k] - s2[k] / n) / den;
}

/* Steepest descent on |U²| with length weights; the step along the
 * anti-gradient comes from a parabola through three samples, refined
 * three times. */
static void solve_length(const geo_poly *p, const adjacency *A, uint32_t v,
                         double ret[3])
{
    double x[3] = {p->verts[v][0], p->verts[v][1], p->verts[v][2]};
    double ell = local_length(p, A, v);
    if (!(ell > 0)) {
        memcpy(ret, x, sizeof x);
        return;
    }
    double fx = u2_norm(p, A, v, x), h = 1e-4 * ell;
    for (int it = 0; it < 6 && fx > 1e-12 * ell; it++) {
        double g[3];
        for (int k = 0; k < 3; k++) {
            double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
            xp[k] += h;
            xm[k] -= h;
            g[k] = (u2_norm(p, A, v, xp) - u2_norm(p, A, v, xm)) / (2 * h);
        }
        if (geo_vnormalize(g) == 0)
            break;
        /* f along the anti-gradient: samples at a = 0, t, 2t */
        double a[3] = {0, 0.25 * ell, 0.5 * ell}, f[3];
        f[0] = fx;
        for (int q = 1; q < 3; q++) {
            double y[3];
            geo_vmadd(x, -a[q], g, y);
            f[q] = u2_norm(p, A, v, y);
        }
        for (int refine_step = 0; refine_step < 3; refine_step++) {
            double d1 = (f[1] - f[0]) / (a[1] - a[0]);
            double d2 = (f[2] - f[1]) / (a[2] - a[1]);
            double curv = (d2 - d1) / (a[2] - a[0]);
            double am;
            if (curv > 0)
                am = 0.5 * (a[0] + a[1]) - d1 / (2 * curv);
            else
                am = f[2] < f[0] ? a[2] * 2 : a[1] * 0.5;
            if (!(am > 0) || am > 2 * ell)
                am = a[1] * 0.5;
            double y[3];
            geo_vmadd(x, -am, g, y);
            double fm = u2_norm(p, A, v, y);
            /* replace the worst sample */
            int worst = 0;
            for (int q = 1; q < 3; q++)
                if (f[q] > f[worst])
                    worst = q;
            if (fm >= f[worst])
                break;
            a[worst] = am;
            f[worst] = fm;
            /* keep the samples ordered by a */
            for (int i = 0; i < 2; i++)
                for (int j = 0; j < 2 - i; j++)
                    if (a[j] > a[j + 1]) {
                        double ta = a[j], tf = f[j];
                        a[j] = a[j + 1], f[j] = f[j + 1];
                        a[j + 1] = ta, f[j + 1] = tf;
                    }
        }
        int best = 0;
        for (int q = 1; q < 3; q++)
            if (f[q] < f[best])
                best = q;
        if (!(f[best] < fx))
            break;
        geo_vmadd(x, -a[best], g, x);
        fx = f[best];
    }
    memcpy(ret, x, sizeof x);
}

/* The unknowns of the U² = 0 system: S[0 .. *ret_nu) the free vertices
 * that are not pinned and have neighbours, then S[*ret_nu .. *ret_m) their
 * neighbours that are fixed (the ring); loc maps a vertex to its place in
 * S or UINT32_MAX. S and loc are malloc'd. 0 or -ENOMEM. */
static int fair_unknowns(const geo_poly *p, const adjacency *A,
                         uint32_t first_free, const uint8_t *pinned,
                         uint32_t **ret_S, uint32_t **ret_loc,
                         uint32_t *ret_nu, uint32_t *ret_m)
{
    uint32_t nv = p->nverts, nfree = nv - first_free, m = 0;
    size_t ring = 0;
    for (uint32_t k = 0; k < nfree; k++)
        ring += A->start[first_free + k + 1] - A->start[first_free + k];
    uint32_t *loc = malloc(((size_t)nv + 1) * sizeof *loc);
    uint32_t *S = malloc((nfree + ring + 1) * sizeof *S);
    if (!loc || !S) {
        free(loc), free(S);
        return -ENOMEM;
    }
    memset(loc, 0xff, (size_t)nv * sizeof *loc);
    for (uint32_t k = 0; k < nfree; k++) {
        uint32_t v = first_free + k;
        if (!pinned[k] && A->start[v + 1] > A->start[v]) {
            loc[v] = m;
            S[m++] = v;
        }
    }
    uint32_t nu = m;
    for (uint32_t u = 0; u < nu; u++)
        for (uint32_t q = A->start[S[u]]; q < A->start[S[u] + 1]; q++)
            if (loc[A->nb[q]] == UINT32_MAX) {
                loc[A->nb[q]] = m;
                S[m++] = A->nb[q];
            }
    *ret_S = S;
    *ret_loc = loc;
    *ret_nu = nu;
    *ret_m = m;
    return 0;
}

/* b = −K·x̃ over the unknowns (K = L·D⁻¹·L, x̃ the positions with the
 * unknowns at zero): the right-hand side of K_ff·x_f = −K_fb·x_b. z is
 * scratch over S. */
static void fair_rhs(const geo_poly *p, const adjacency *A, const uint32_t *S,
                     const uint32_t *loc, uint32_t nu, uint32_t m,
                     double (*z)[3], double (*b)[3])
{
#define DEG(v) ((double)(A->start[(v) + 1] - A->start[(v)]))
    for (uint32_t s2 = 0; s2 < m; s2++) {
        uint32_t v = S[s2];
        double acc[3] = {0, 0, 0};
        if (s2 >= nu)
            geo_vscale(p->verts[v], DEG(v), acc);
        for (uint32_t q = A->start[v]; q < A->start[v + 1]; q++)
            if (loc[A->nb[q]] >= nu)
                geo_vsub(acc, p->verts[A->nb[q]], acc);
        geo_vscale(acc, 1.0 / DEG(v), z[s2]);
    }
    for (uint32_t u = 0; u < nu; u++) {
        uint32_t v = S[u];
        double acc[3];
        geo_vscale(z[u], DEG(v), acc);
        for (uint32_t q = A->start[v]; q < A->start[v + 1]; q++)
            geo_vsub(acc, z[loc[A->nb[q]]], acc);
        geo_vscale(acc, -1.0, b[u]);
    }
#undef DEG
}

/* Bound on the entries of the Cholesky factor of a fairing system (12
 * bytes each, so at most 192 MB): the 14,300 free vertices of a 1,000-
 * vertex hole need 1.7 million; the factor grows as n log n. */
#define GEO_FAIR_DIRECT_MAX_NNZ (16u << 20)

/* U²(p) = 0 at every free vertex at once, for w = 1, solved directly:
 * K_ff = (L·D⁻¹·L)_ff is assembled once — K[u][t] = Σ_s L[s][u]·L[s][t]
 * / D_s over the vertices s next to both — and factored by lib/core/spchol.h
 * (nested dissection; O(n^1.5) against conjugate gradients' O(n²) for a
 * patch of n vertices, and exact). Writes the solution into p; returns
 * 0, -ERANGE (the factor would be too large), -EDOM (K_ff is not
 * positive definite: some free vertices see no fixed one), -ENOMEM or
 * -ECANCELED; p is unchanged on error. */
static int fair_direct(geo_poly *p, const adjacency *A, uint32_t first_free,
                       const uint8_t *pinned, geo_fill_stats *st,
                       const geo_ctx *ctx)
{
    uint32_t *S = NULL, *loc = NULL, nu = 0, m = 0;
    uint32_t *rp = NULL, *ci = NULL, *pos = NULL;
    double *val = NULL, (*z)[3] = NULL, (*b)[3] = NULL;
    geo_spchol *fac = NULL;
    int rc = fair_unknowns(p, A, first_free, pinned, &S, &loc, &nu, &m);
    if (rc < 0 || nu == 0)
        goto out;
    rc = -ENOMEM;
#define DEG(v) (A->start[(v) + 1] - A->start[(v)])
    /* row u's entries are among the neighbours' neighbours */
    size_t cap = 0;
    for (uint32_t u = 0; u < nu; u++) {
        uint32_t v = S[u];
        cap += DEG(v) + 1;
        for (uint32_t q = A->start[v]; q < A->start[v + 1]; q++)
            cap += DEG(A->nb[q]) + 1;
    }
    rp = malloc(((size_t)nu + 1) * sizeof *rp);
    ci = malloc((cap + 1) * sizeof *ci);
    val = malloc((cap + 1) * sizeof *val);
    pos = malloc(((size_t)nu + 1) * sizeof *pos);
    z = malloc(((size_t)m + 1) * sizeof *z);
    b = malloc(((size_t)nu + 1) * sizeof *b);
    if (!rp || !ci || !val || !pos || !z || !b || cap >= UINT32_MAX)
        goto out;
    memset(pos, 0xff, (size_t)nu * sizeof *pos);
    rp[0] = 0;
    uint32_t nz = 0;
    for (uint32_t u = 0; u < nu; u++) {
        uint32_t v = S[u], row0 = nz;
        for (uint32_t qs = A->start[v]; qs <= A->start[v + 1]; qs++) {
            /* s runs over v's neighbours, then v itself */
            uint32_t sv = qs < A->start[v + 1] ? A->nb[qs] : v;
            double ds = (double)DEG(sv);
            double a = (sv == v ? ds : -1.0) / ds; /* L[s][v] / D_s */
            for (uint32_t qt = A->start[sv]; qt <= A->start[sv + 1]; qt++) {
                uint32_t tv = qt < A->start[sv + 1] ? A->nb[qt] : sv;
                uint32_t t = loc[tv];
                if (t >= nu)
                    continue;
                double add = a * (tv == sv ? ds : -1.0);
                if (pos[t] == UINT32_MAX) {
                    pos[t] = nz;
                    ci[nz] = t;
                    val[nz++] = add;
                } else {
                    val[pos[t]] += add;
                }
            }
        }
        for (uint32_t q = row0; q < nz; q++)
            pos[ci[q]] = UINT32_MAX;
        rp[u + 1] = nz;
    }
#undef DEG
    rc = geo_spchol_factor(nu, rp, ci, val, GEO_SPCHOL_DISSECTION,
                           GEO_FAIR_DIRECT_MAX_NNZ, ctx, &fac);
    if (rc < 0)
        goto out;
    fair_rhs(p, A, S, loc, nu, m, z, b);
    if ((rc = geo_spchol_solve3(fac, b)) < 0)
        goto out;
    for (uint32_t u = 0; u < nu; u++)
        memcpy(p->verts[S[u]], b[u], sizeof b[u]);
    st->nfair_sweeps++;
out:
    geo_spchol_free(fac);
    free(S), free(loc), free(rp), free(ci), free(val), free(pos), free(z),
        free(b);
    return rc;
}

/* U²(p) = 0 at every free vertex at once, for w = 1. With L = D − Adj
 * (D the neighbour counts), U¹ = −D⁻¹L·x and U² = D⁻¹L·D⁻¹L·x, so the
 * conditions are K_ff·x_f = −K_fb·x_b with K = L·D⁻¹·L symmetric and,
 * restricted to the free vertices of a patch attached to fixed ones,
 * positive definite: solved by conjugate gradients with K's diagonal as
 * preconditioner (the seed's per-vertex closed form is one Jacobi step of
 * this system; sweeping it needs O(patch diameter²) sweeps to carry the
 * fixed boundary's shape inside, CG about O(diameter)). Starts from the
 * current positions; stops at a residual of 1e-4 of the first (the shape no longer changes
 * visibly: on a 1,000-vertex hole in a sphere the mean distance to the
 * sphere is the same as at 1e-6), or after
 * GEO_FAIR_CG_MAX_ITER iterations. Writes the solution into p; returns 0,
 * -ENOMEM or -ECANCELED (p unchanged then). */
#define GEO_FAIR_CG_MAX_ITER 5000
static int fair_cg(geo_poly *p, const adjacency *A, uint32_t first_free,
                   const uint8_t *pinned, geo_fill_stats *st,
                   const geo_ctx *ctx)
{
    uint32_t nu = 0, m = 0, *loc = NULL, *S = NULL;
    double(*buf)[3] = NULL, *diag = NULL;
    int rc = fair_unknowns(p, A, first_free, pinned, &S, &loc, &nu, &m);
    if (rc < 0)
        goto out;
    if (nu == 0)
        goto out;
    /* z over S; x, b, r, d, Kd, h over the unknowns */
    buf = malloc(((size_t)m + 6 * (size_t)nu) * sizeof *buf);
    diag = malloc((size_t)nu * sizeof *diag);
    if (!buf || !diag) {
        rc = -ENOMEM;
        goto out;
    }
    double(*z)[3] = buf, (*x)[3] = buf + m, (*b)[3] = x + nu, (*r)[3] = b + nu,
          (*d)[3] = r + nu, (*Kd)[3] = d + nu, (*h)[3] = Kd + nu;
#define DEG(v) ((double)(A->start[(v) + 1] - A->start[(v)]))
    for (uint32_t u = 0; u < nu; u++) {
        uint32_t v = S[u];
        double sum = DEG(v);
        for (uint32_t q = A->start[v]; q < A->start[v + 1]; q++)
            sum += 1.0 / DEG(A->nb[q]);
        diag[u] = sum;
        memcpy(x[u], p->verts[v], sizeof x[u]);
    }
    fair_rhs(p, A, S, loc, nu, m, z, b);
    /* Kd = K·d over the unknowns (d zero on everything fixed) */
#define APPLY_K(in, out)                                                      \
    do {                                                                      \
        for (uint32_t s2 = 0; s2 < m; s2++) {                                 \
            uint32_t v = S[s2];                                               \
            double acc[3] = {0, 0, 0};                                        \
            if (s2 < nu)                                                      \
                geo_vscale(in[s2], DEG(v), acc);                              \
            for (uint32_t q = A->start[v]; q < A->start[v + 1]; q++)          \
                if (loc[A->nb[q]] < nu)                                       \
                    geo_vsub(acc, in[loc[A->nb[q]]], acc);                    \
            geo_vscale(acc, 1.0 / DEG(v), z[s2]);                             \
        }                                                                     \
        for (uint32_t u = 0; u < nu; u++) {                                   \
            uint32_t v = S[u];                                                \
            double acc[3];                                                    \
            geo_vscale(z[u], DEG(v), acc);                                    \
            for (uint32_t q = A->start[v]; q < A->start[v + 1]; q++)          \
                geo_vsub(acc, z[loc[A->nb[q]]], acc);                         \
            memcpy(out[u], acc, sizeof acc);                                  \
        }                                                                     \
    } while (0)
    APPLY_K(x, Kd);
    double rz[3] = {0, 0, 0}, r0[3] = {0, 0, 0};
    for (uint32_t u = 0; u < nu; u++)
        for (int c = 0; c < 3; c++) {
            r[u][c] = b[u][c] - Kd[u][c];
            h[u][c] = r[u][c] / diag[u];
            d[u][c] = h[u][c];
            rz[c] += r[u][c] * h[u][c];
            r0[c] += r[u][c] * r[u][c];
        }
    bool active[3];
    for (int c = 0; c < 3; c++)
        active[c] = r0[c] > 0;
    uint32_t it = 0;
    for (; it < GEO_FAIR_CG_MAX_ITER && (active[0] || active[1] || active[2]);
         it++) {
        if ((it & 63) == 63 && geo_ctx_canceled(ctx)) {
            rc = -ECANCELED;
            goto out;
        }
        APPLY_K(d, Kd);
        double dKd[3] = {0, 0, 0}, rr[3] = {0, 0, 0}, rz1[3] = {0, 0, 0};
        for (uint32_t u = 0; u < nu; u++)
            for (int c = 0; c < 3; c++)
                dKd[c] += d[u][c] * Kd[u][c];
        double alpha[3];
        for (int c = 0; c < 3; c++) {
            alpha[c] = active[c] && dKd[c] > 0 ? rz[c] / dKd[c] : 0.0;
            if (active[c] && !(dKd[c] > 0))
                active[c] = false;
        }
        for (uint32_t u = 0; u < nu; u++)
            for (int c = 0; c < 3; c++) {
                x[u][c] += alpha[c] * d[u][c];
                r[u][c] -= alpha[c] * Kd[u][c];
                h[u][c] = r[u][c] / diag[u];
                rr[c] += r[u][c] * r[u][c];
                rz1[c] += r[u][c] * h[u][c];
            }
        for (int c = 0; c < 3; c++) {
            if (!active[c])
                continue;
            if (!(rr[c] > 1e-8 * r0[c])) {
                active[c] = false;
                continue;
            }
            double beta = rz1[c] / rz[c];
            rz[c] = rz1[c];
            for (uint32_t u = 0; u < nu; u++)
                d[u][c] = h[u][c] + beta * d[u][c];
        }
    }
#undef APPLY_K
#undef DEG
    for (uint32_t u = 0; u < nu; u++)
        memcpy(p->verts[S[u]], x[u], sizeof x[u]);
    st->nfair_sweeps += it;
out:
    free(loc), free(S), free(buf), free(diag);
    return rc;
}

/* 1 when a facet flagged in touched has no area or meets another flagged
 * facet at an edge at a dihedral angle above 120° (the surface folds back
 * on itself there), else 0; -ENOMEM. Bends are fine: a patch faired into
 * a dome turns its rim triangles far from where the flat patch had them.
 * bad, when not NULL, gets 1 for every such facet (both of a fold). */
static int folds(const geo_poly *p, const uint8_t *touched, uint8_t *bad)
{
    geo_edgemap he;
    size_t n = 0;
    for (uint32_t f = 0; f < p->nfacets; f++)
        n += touched[f] ? geo_poly_facet_size(p, f) : 0;
    if (geo_edgemap_init(&he, n) < 0)
        return -ENOMEM;
    int rc = 0;
    for (uint32_t f = 0; f < p->nfacets && (rc == 0 || (rc == 1 && bad));
         f++) {
        if (!touched[f])
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        double nf[3];
        geo_poly_facet_area_vector(p, f, nf);
        if (geo_vnormalize(nf) == 0) {
            rc = 1;
            if (bad)
                bad[f] = 1;
        }
        for (uint32_t i = 0; i < k && rc >= 0; i++) {
            uint32_t a = fv[i], b = fv[(i + 1) % k];
            uint32_t g = geo_edgemap_get(&he, geo_edge_key(b, a));
            if (g != UINT32_MAX) {
                double ng[3];
                geo_poly_facet_area_vector(p, g, ng);
                geo_vnormalize(ng);
                if (geo_vdot(nf, ng) < -0.5) {
                    rc = 1;
                    if (bad)
                        bad[f] = bad[g] = 1;
                }
            } else if (geo_edgemap_put(&he, geo_edge_key(a, b), f) < 0) {
                rc = -ENOMEM;
            }
        }
    }
    geo_edgemap_destroy(&he);
    return rc;
}

/* Solves U² = 0 for w = 1 (fair_direct, or fair_cg for a factor too
 * large) without folds. With uniform weights the solution depends on
 * the connectivity alone, and a free vertex in front of a tooth of a
 * jagged rim — three of its four neighbours on the loop — is drawn over
 * the tooth. The free corners of folded facets are then held where the
 * unfaired patch had them, lifted along its normal as far as the
 * solution lifted them, and the others solved again (at most four
 * times). flat: the free vertices' unfaired positions; held: per free
 * vertex, fixed (pinned ones on entry; changed). 1 solved without
 * folds, 0 still folded, or a negative errno. */
static int fair_solve(geo_poly *p, const adjacency *A, uint32_t first_free,
                      uint8_t *held, const double (*flat)[3],
                      const uint8_t *touches_free, geo_fill_stats *st,
                      const geo_ctx *ctx)
{
    uint32_t nfree = p->nverts - first_free;
    uint8_t *bad = malloc((size_t)p->nfacets + 1);
    double(*vn)[3] = calloc((size_t)nfree + 1, sizeof *vn);
    int rc = -ENOMEM;
    if (!bad || !vn)
        goto out;
    /* the unfaired patch's vertex normals (planes hold the facets'
     * Newell vectors from before) */
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if (!touches_free[f])
            continue;
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < geo_poly_facet_size(p, f); i++)
            if (fv[i] >= first_free)
                geo_vadd(vn[fv[i] - first_free], p->planes[f],
                         vn[fv[i] - first_free]);
    }
    for (int round = 0; round < 4; round++) {
        rc = fair_direct(p, A, first_free, held, st, ctx);
        if (rc == -ERANGE || rc == -EDOM)
            rc = fair_cg(p, A, first_free, held, st, ctx);
        if (rc < 0)
            goto out;
        memset(bad, 0, p->nfacets);
        if ((rc = folds(p, touches_free, bad)) <= 0) {
            rc = rc == 0 ? 1 : rc;
            goto out;
        }
        uint32_t nheld = 0;
        for (uint32_t f = 0; f < p->nfacets; f++) {
            if (!bad[f])
                continue;
            const uint32_t *fv = geo_poly_facet(p, f);
            for (uint32_t i = 0; i < geo_poly_facet_size(p, f); i++) {
                uint32_t v = fv[i], k = v - first_free;
                if (v < first_free || held[k])
                    continue;
                double d[3], nrm[3];
                geo_vsub(p->verts[v], flat[k], d);
                memcpy(nrm, vn[k], sizeof nrm);
                if (geo_vnormalize(nrm) == 0)
                    nrm[0] = nrm[1] = nrm[2] = 0;
                geo_vmadd(flat[k], geo_vdot(d, nrm), nrm, p->verts[v]);
                held[k] = 1;
                nheld++;
            }
        }
        rc = 0;
        if (nheld == 0)
            break; /* the folds are among fixed vertices */
    }
out:
    free(bad), free(vn);
    return rc;
}

static int fair(geo_poly *p, uint32_t first_free, const geo_fill_opts *o,
                geo_fill_stats *st, const geo_ctx *ctx)
{
    uint32_t nfree = p->nverts - first_free;
    if (nfree == 0 || o->fair == GEO_FAIR_NONE)
        return 0;
    adjacency A = {0};
    uint8_t *pinned = NULL;
    double(*nxt)[3] = malloc((size_t)nfree * sizeof *nxt);
    uint8_t *touches_free = calloc((size_t)p->nfacets + 1, 1);
    int rc = build_adjacency(p, &A);
    if (rc < 0 || !nxt || !touches_free) {
        rc = -ENOMEM;
        goto out;
    }
    /* a free vertex on a hard edge (a piece of a split one) stays: the
     * umbrella would pull it off the feature */
    pinned = calloc((size_t)nfree + 1, 1);
    if (!pinned) {
        rc = -ENOMEM;
        goto out;
    }
    for (uint32_t k = 0; k < nfree; k++) {
        uint32_t v = first_free + k;
        for (uint32_t q = A.start[v]; q < A.start[v + 1] && !pinned[k]; q++)
            pinned[k] = o->hard_edge &&
                        o->hard_edge(o->project_user, p->verts[v],
                                     p->verts[A.nb[q]]);
    }
    /* reference normals: the facets' Newell vectors before fairing */
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < geo_poly_facet_size(p, f); i++)
            touches_free[f] |= fv[i] >= first_free;
        if (touches_free[f])
            geo_poly_facet_area_vector(p, f, p->planes[f]);
    }
    /* without a surface to project on, the uniform system is solved as a
     * whole; a solution that turns a facet over (or collapses it) is
     * dropped for the sweeps below, which undo folds vertex by vertex */
    bool solved = false;
    if (o->fair == GEO_FAIR_UNIFORM && !o->project) {
        for (uint32_t k = 0; k < nfree; k++)
            memcpy(nxt[k], p->verts[first_free + k], sizeof nxt[k]);
        uint8_t *held = malloc((size_t)nfree + 1);
        if (!held) {
            rc = -ENOMEM;
            goto out;
        }
        memcpy(held, pinned, nfree);
        rc = fair_solve(p, &A, first_free, held,
                        (const double(*)[3])nxt, touches_free, st, ctx);
        free(held);
        if (rc < 0)
            goto out;
        solved = rc == 1;
        rc = 0;
        if (!solved)
            for (uint32_t k = 0; k < nfree; k++)
                memcpy(p->verts[first_free + k], nxt[k], sizeof nxt[k]);
    }
    for (uint32_t sweep = 0; sweep < o->fair_iterations && !solved; sweep++) {
        if (geo_ctx_canceled(ctx)) {
            rc = -ECANCELED;
            goto out;
        }
        for (uint32_t k = 0; k < nfree; k++) {
            uint32_t v = first_free + k;
            if (A.start[v + 1] == A.start[v] || pinned[k]) {
                memcpy(nxt[k], p->verts[v], sizeof nxt[k]);
                continue;
            }
            if (o->fair == GEO_FAIR_UNIFORM)
                solve_uniform(p, &A, v, nxt[k]);
            else
                solve_length(p, &A, v, nxt[k]);
            if (o->place) {
                const double *fp[1] = {p->verts[v]};
                if (!o->place(o->project_user, nxt[k], fp, 1))
                    memcpy(nxt[k], p->verts[v], sizeof nxt[k]);
            } else if (o->project &&
                       !o->project(o->project_user, nxt[k])) {
                memcpy(nxt[k], p->verts[v], sizeof nxt[k]);
            }
        }
        /* apply, then undo the moves of every triangle that would turn
         * over or collapse (a fold, e.g. across a crease of the surface) */
        for (uint32_t k = 0; k < nfree; k++) {
            uint32_t v = first_free + k;
            double tmp[3];
            memcpy(tmp, p->verts[v], sizeof tmp);
            memcpy(p->verts[v], nxt[k], sizeof tmp);
            memcpy(nxt[k], tmp, sizeof tmp); /* nxt now holds the old */
        }
        uint32_t undone = 1;
        for (int pass = 0; pass < 8 && undone; pass++) {
            undone = 0;
            for (uint32_t f = 0; f < p->nfacets; f++) {
                if (!touches_free[f])
                    continue;
                double n[3];
                geo_poly_facet_area_vector(p, f, n);
                double nl = geo_vlen(n), ol = geo_vlen(p->planes[f]);
                if (nl > 0 && geo_vdot(n, p->planes[f]) > 0.5 * nl * ol)
                    continue;
                const uint32_t *fv = geo_poly_facet(p, f);
                for (uint32_t i = 0; i < geo_poly_facet_size(p, f); i++)
                    if (fv[i] >= first_free &&
                        memcmp(p->verts[fv[i]], nxt[fv[i] - first_free],
                               sizeof nxt[0]) != 0) {
                        memcpy(p->verts[fv[i]], nxt[fv[i] - first_free],
                               sizeof nxt[0]);
                        undone++;
                    }
            }
        }
        if (undone) /* did not settle: this sweep moves nothing */
            for (uint32_t k = 0; k < nfree; k++)
                memcpy(p->verts[first_free + k], nxt[k], sizeof nxt[0]);
        double worst = 0;
        for (uint32_t k = 0; k < nfree; k++) {
            uint32_t v = first_free + k;
            double ell = local_length(p, &A, v);
            double mv = geo_vdist(nxt[k], p->verts[v]);
            if (ell > 0 && mv / ell > worst)
                worst = mv / ell;
        }
        st->nfair_sweeps++;
        if (worst < 1e-4)
            break;
    }
    /* the moved vertices changed their facets' planes */
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        for (uint32_t i = 0; i < k; i++)
            if (fv[i] >= first_free) {
                fit_plane(p, f, p->planes[f]);
                break;
            }
    }
out:
    free(A.start), free(A.nb), free(nxt), free(touches_free), free(pinned);
    return rc;
}

/* ---- driver ---- */

static int check_opts(const geo_fill_opts *opts, geo_fill_opts *o,
                      geo_err *err)
{
    if (opts)
        *o = *opts;
    else
        geo_fill_opts_default(o);
    if (o->max_dp_vertices < 8)
        o->max_dp_vertices = 8;
    if (o->max_dp_vertices > 4096)
        o->max_dp_vertices = 4096;
    if (!(o->density > 0) || !isfinite(o->density))
        return geo_err_set(err, -EINVAL, "density must be > 0");
    if (!(o->hard_angle_deg > 0 && o->hard_angle_deg <= 180))
        return geo_err_set(err, -EINVAL, "hard angle must be in (0, 180]");
    return 0;
}

/* What every entry point checks first: the options (into *o) and p's
 * indices. */
static int check_input(const geo_poly *p, const geo_fill_opts *opts,
                       geo_fill_opts *o, geo_err *err)
{
    int rc = check_opts(opts, o, err);
    return rc < 0 ? rc : geo_poly_validate_indices(p, err);
}

/* Sets err for a failure of the work itself, which can only be a cancel
 * or out-of-memory; returns rc. */
static int work_failed(int rc, geo_err *err)
{
    return geo_err_set(err, rc, rc == -ECANCELED ? "canceled"
                                                 : "out of memory");
}

/* Refinement and fairing of q in place; in_region may be changed. */
static int refine_and_fair(geo_poly *q, uint8_t *in_region,
                           const geo_fill_opts *o, geo_fill_stats *st,
                           const geo_ctx *ctx)
{
    uint32_t nv0 = q->nverts, nreg = 0;
    for (uint32_t f = 0; f < q->nfacets; f++) {
        if (geo_poly_facet_size(q, f) != 3)
            in_region[f] = 0;
        nreg += in_region[f] != 0;
    }
    int rc = 0;
    if (o->refine && nreg && (rc = refine(q, in_region, o, st, ctx)) < 0)
        return rc;
    if ((rc = geo_ctx_progress(ctx, 0.75)) < 0)
        return rc;
    return fair(q, nv0, o, st, ctx);
}

int geo_refine_region(geo_poly *p, const uint8_t *region,
                      const geo_fill_opts *opts, const geo_ctx *ctx,
                      geo_fill_stats *stats, geo_err *err)
{
    geo_fill_opts o;
    int rc = check_input(p, opts, &o, err);
    if (rc < 0)
        return rc;
    geo_fill_stats st = {0};
    geo_poly *q = geo_poly_copy(p);
    uint8_t *in_region = malloc((size_t)p->nfacets + 1);
    if (!q || !in_region) {
        rc = -ENOMEM;
    } else {
        for (uint32_t f = 0; f < p->nfacets; f++)
            in_region[f] = region[f] ? REGION_GIVEN : 0;
        rc = refine_and_fair(q, in_region, &o, &st, ctx);
    }
    if (rc == 0) {
        geo_poly tmp = *p;
        *p = *q;
        *q = tmp;
        if (stats)
            *stats = st;
    } else {
        work_failed(rc, err);
    }
    geo_poly_free(q);
    free(in_region);
    return rc;
}

int geo_fair_vertices(geo_poly *p, uint32_t first_free,
                      const geo_fill_opts *opts, const geo_ctx *ctx,
                      geo_fill_stats *stats, geo_err *err)
{
    geo_fill_opts o;
    int rc = check_input(p, opts, &o, err);
    if (rc < 0)
        return rc;
    if (first_free > p->nverts)
        return geo_err_set(err, -EINVAL, "first free vertex %u beyond the "
                           "%u vertices", first_free, p->nverts);
    geo_fill_stats st = {0};
    rc = fair(p, first_free, &o, &st, ctx);
    if (rc < 0)
        return work_failed(rc, err);
    if (stats)
        *stats = st;
    return 0;
}

int geo_fill_loops(geo_poly *p, const geo_fill_opts *opts, const geo_ctx *ctx,
                   geo_fill_stats *stats, geo_err *err)
{
    geo_fill_opts o;
    int rc = check_input(p, opts, &o, err);
    if (rc < 0)
        return rc;
    geo_fill_stats st = {0};
    filler F = {.p = p, .o = o};
    geo_topo *t = NULL;
    uint32_t *lstart = NULL, *lcorn = NULL, nloops = 0, *w = NULL, *cs = NULL;
    double(*en)[3] = NULL; /* per loop edge: the facet across it */
    geo_poly *q = NULL;
    uint8_t *in_region = NULL;
    t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
    if (geo_topo_boundary_loops(p, t, &lstart, &lcorn, &nloops) < 0 ||
        geo_edgemap_init(&F.edges, geo_poly_ncorners(p)) < 0)
        goto oom;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        if ((f & 65535) == 0 && geo_ctx_canceled(ctx)) {
            rc = -ECANCELED;
            goto fail;
        }
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        for (uint32_t i = 0; i < k; i++)
            if (geo_edgemap_put(&F.edges, geo_edge_ukey(fv[i], fv[(i + 1) % k]),
                                1) < 0)
                goto oom;
    }
    w = malloc(((size_t)t->nboundary_edges + 1) * sizeof *w);
    if (!(en = malloc(((size_t)t->nboundary_edges + 1) * sizeof *en)))
        goto oom;
    cs = malloc(((size_t)nloops + 2) * sizeof *cs);
    st.holes = calloc((size_t)nloops + 1, sizeof *st.holes);
    if (!w || !cs || !st.holes)
        goto oom;
    /* closed loops as vertex cycles, already reversed: a patch runs
     * against the loop's facets */
    uint32_t nclosed = 0, nw = 0;
    cs[0] = 0;
    for (uint32_t l = 0; l < nloops; l++) {
        uint32_t n = lstart[l + 1] - lstart[l];
        const uint32_t *lc = lcorn + lstart[l];
        bool closed = n >= 1;
        for (uint32_t k = 0; k < n && closed; k++) {
            uint32_t end = p->fidx[geo_topo_next(p, t, lc[k])];
            closed = end == p->fidx[lc[(k + 1) % n]];
        }
        for (uint32_t k = 0; k < n; k++)
            w[nw + k] = p->fidx[lc[n - 1 - k]];
        if (o.select_loop && !o.select_loop(o.select_user, w + nw, n))
            continue;
        if (!closed) {
            geo_hole_report *rep = &st.holes[st.nholes++];
            rep->nverts = n;
            rep->first_vertex = p->fidx[lc[0]];
            rep->status = GEO_HOLE_NOT_A_LOOP;
            st.nopen++;
            continue;
        }
        /* w's edge j runs against the loop corner lc[n − 2 − j mod n] */
        for (uint32_t j = 0; en && j < n; j++) {
            uint32_t f = t->corner_facet[lc[(2 * n - 2 - j) % n]];
            geo_poly_facet_area_vector(p, f, en[nw + j]);
            if (geo_vnormalize(en[nw + j]) == 0)
                memset(en[nw + j], 0, sizeof en[0]);
        }
        nw += n;
        cs[++nclosed] = nw;
    }
    for (uint32_t l = 0; l < nclosed; l++) {
        if ((l & 63) == 0 &&
            (rc = geo_ctx_progress(ctx, 0.5 * l / (nclosed + 1.0))) < 0)
            goto fail;
        geo_hole_report *rep = &st.holes[st.nholes++];
        uint32_t n = cs[l + 1] - cs[l];
        rep->nverts = n;
        rep->first_vertex = w[cs[l]];
        if ((rc = fill_loop(&F, w + cs[l], n, en ? en + cs[l] : NULL,
                            rep)) < 0)
            goto fail;
        if (rep->status == GEO_HOLE_FILLED)
            st.nfilled++;
        else
            st.nopen++;
    }
    /* everything below works on a copy, so p is untouched on failure */
    q = geo_poly_copy(p);
    if (!q || geo_poly_reserve(q, p->nverts, (size_t)p->nfacets + F.ntris,
                               geo_poly_ncorners(p) + 3 * F.ntris) < 0)
        goto oom;
    uint32_t nf0 = p->nfacets;
    for (size_t k = 0; k < F.ntris; k++) {
        int64_t nf = geo_poly_add_facet(q, F.tris[k], 3);
        if (nf < 0)
            goto oom;
        fit_plane(q, (uint32_t)nf, q->planes[nf]);
    }
    if ((rc = geo_ctx_progress(ctx, 0.5)) < 0)
        goto fail;
    in_region = calloc((size_t)q->nfacets + 1, 1);
    if (!in_region)
        goto oom;
    for (uint32_t f = 0; f < q->nfacets; f++)
        in_region[f] = f >= nf0 ? REGION_PATCH
                       : o.also_refine && o.also_refine[f] ? REGION_GIVEN
                                                           : 0;
    if ((rc = refine_and_fair(q, in_region, &o, &st, ctx)) < 0)
        goto fail;
    geo_poly tmp = *p;
    *p = *q;
    *q = tmp;
    rc = geo_ctx_progress(ctx, 1.0);
    goto done;
oom:
    rc = -ENOMEM;
fail:
    work_failed(rc, err);
done:
    geo_poly_free(q);
    geo_topo_free(t);
    free(lstart), free(lcorn), free(w), free(cs), free(in_region), free(en);
    free(F.tris), free(F.log);
    geo_edgemap_destroy(&F.edges);
    if (rc < 0 || !stats)
        geo_fill_stats_clear(&st);
    else
        *stats = st;
    return rc;
}
