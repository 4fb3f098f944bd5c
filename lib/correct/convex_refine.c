/* convex_refine.c — the recovered planes adjusted to the silhouettes
 * (convex.h, geo_convex_refine).
 *
 * Every facet j of a raw shadow-profile scan is one silhouette edge of
 * one view (Palachev 2012, §1.2): a plane (unit normal m_j, offset d_j)
 * through the projections of two stone vertices, each off by the
 * silhouette noise. So each scan facet measures the stone twice, at the
 * two vertices that span it:
 *
 *     m_j · x_a + d_j = noise,   m_j · x_b + d_j = noise.
 *
 * Two facets of one view that share a spanning vertex are the two edges
 * at one corner of its silhouette: they pass through the same noisy
 * point, so together they measure that vertex once in both directions
 * across the view (corner), not twice along their normals with
 * independent noise.
 *
 * The unknowns are the stone's planes (each a tilt in two directions and
 * an offset) and its vertices (three coordinates each), tied by the
 * incidences: a vertex lies on every plane of its facets, so where four
 * or eight facets meet the vertex stays one and every one of those planes
 * answers for its measurements. Vertices of the estimate closer than the
 * cluster radius are one vertex (the scan's noise splits a vertex of
 * degree > 3 into a cluster; the intersection of noisy planes does too).
 * The incidences enter as measurements of a weight far above the
 * silhouettes' (a penalty, as the bound of the test bench takes them);
 * the system is sparse (a plane with its vertices) and solved by
 * lib/core/spchol, Gauss–Newton, the two spanning vertices of each scan
 * facet chosen again at each iteration (span_of). Residuals are
 * Huber-weighted at twice their robust scale (a scan facet the estimate
 * explains by the wrong pair). A step after which that scale is larger
 * than before it is not taken: wrong pairs can make the iteration climb
 * (a heart's scan at K = 100 went 2.1 → 3.4 µm at 1 µm of noise, and the
 * larger noise it reported grouped the stone coarser).
 *
 * Why: the fits of convex_planes.c use the slivers that survived on one
 * true facet; this uses every silhouette plane of the scan where it
 * constrains the stone, at the stone's vertices, which is the
 * information the scan holds (its Cramér–Rao bound is the test bench's
 * scan_bound with the surviving planes only). */
#include "convex.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "ascent.h"
#include "select.h"
#include "spchol.h"
#include "topo.h"
#include "uf.h"
#include "vec.h"

#define REFINE_ITERS 3
#define HUBER 2.0
/* The incidences' weight relative to the largest measurement's. */
#define CONSTRAINT_WEIGHT 1e6
/* Damping relative to the incidences' weight: a plane or vertex no
 * silhouette sees stays where it was, and a direction the silhouettes
 * hardly see moves no more than they say (noise-free, without it the
 * solve wanders along them). */
#define DAMP_REL 1e-9
/* The damping of a held plane, relative to the incidences' weight. */
#define HOLD_REL 1e6
/* A step whose planes' Schur complement the rounding left indefinite
 * (a vertex where nearly parallel planes meet is held along their line by
 * the damping alone, and eliminating it cancels terms 10^15 times the
 * damping) is solved again with the damping DAMP_GROW times larger, up
 * to DAMP_RETRIES times: a shorter step, not a failed adjustment. */
#define DAMP_GROW 1e3
#define DAMP_RETRIES 3
/* A spanning vertex lies at most this many residual scales below the
 * highest (before the first residuals: the cluster radius). */
#define SPAN_SCALES 6.0
/* The least sine between a corner's two normals (corner): the residual
 * along the silhouette is the planes' residuals over it, 200 times at
 * this limit. */
#define CORNER_MIN_SIN 0.005

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* The normal equations as 3×3 blocks: block (i, j) of unknowns' triples
 * (planes first, then vertices). The pattern is fixed by the incidences
 * (a plane with its vertices) and the diagonal. */
typedef struct blocks {
    uint32_t n;          /* triples */
    uint32_t *rp, *ci;   /* CSR of the block pattern, both triangles */
    double (*v)[3][3];   /* values per block entry */
} blocks;

static double (*block_at(blocks *b, uint32_t i, uint32_t j))[3]
{
    uint32_t lo = b->rp[i], hi = b->rp[i + 1];
    while (lo < hi) {
        uint32_t mid = (lo + hi) / 2;
        if (b->ci[mid] < j)
            lo = mid + 1;
        else
            hi = mid;
    }
    return b->v[lo];
}

/* Adds w · g gᵀ over the triples ti[0..nt) (g: 3 · nt entries). */
static void add_outer(blocks *b, const uint32_t *ti, const double *g,
                      uint32_t nt, double w)
{
    for (uint32_t a = 0; a < nt; a++)
        for (uint32_t c = 0; c < nt; c++) {
            double (*m)[3] = block_at(b, ti[a], ti[c]);
            for (int r = 0; r < 3; r++)
                for (int s = 0; s < 3; s++)
                    m[r][s] += w * g[3 * a + r] * g[3 * c + s];
        }
}

/* Two planes m1, m2 of one view through one spanning vertex x. A
 * silhouette edge joins two noisy projected vertices and the edges on
 * either side of a corner share it (Palachev 2012, §1.2: the silhouette
 * is the hull of the projected vertices), so the two planes measure one
 * noisy point: x's two components across the view direction d = m1 × m2,
 * each with the silhouette noise once — not two independent measurements
 * along m1 and m2, which count the noise along them twice and leave out
 * the component along the silhouette. Adds the corner's residual ρ (x's
 * offset from the planes' common line, across d), Huber-weighted at huber
 * on its length, to vertex block ti of b and to its right-hand side r.
 * False, nothing added (the caller takes the planes one by one), when the
 * normals are within CORNER_MIN_SIN of parallel or the line passes
 * farther than reject from x (not this vertex's corner: a pair the
 * estimate took wrongly). */
static bool corner(const double m1[4], const double m2[4], const double x[3],
                   double huber, double reject, blocks *b, uint32_t ti,
                   double (*r)[3])
{
    double d[3];
    geo_vcross(m1, m2, d);
    double sn = sqrt(geo_vdot(d, d));
    if (!(sn > CORNER_MIN_SIN))
        return false;
    geo_vscale(d, 1 / sn, d);
    double c = geo_vdot(m1, m2), den = 1 - c * c;
    double r1 = geo_vdot(m1, x) + m1[3], r2 = geo_vdot(m2, x) + m2[3];
    double al = (r1 - c * r2) / den, be = (r2 - c * r1) / den;
    double rho[3];
    for (int k = 0; k < 3; k++)
        rho[k] = al * m1[k] + be * m2[k];
    double len = sqrt(geo_vdot(rho, rho));
    if (len > reject)
        return false;
    double w = len <= huber ? 1 : huber / len;
    double (*blk)[3] = block_at(b, ti, ti);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            blk[i][k] += w * ((i == k) - d[i] * d[k]);
    for (int k = 0; k < 3; k++)
        r[k][0] -= w * rho[k];
    return true;
}

/* c = a · b (3×3). */
static void mul3(double a[3][3], double b[3][3], double c[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
}

/* ret = a⁻¹ (3×3, by cofactors); false when a is singular. */
static bool inv3(double a[3][3], double ret[3][3])
{
    double c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1];
    double c01 = a[1][2] * a[2][0] - a[1][0] * a[2][2];
    double c02 = a[1][0] * a[2][1] - a[1][1] * a[2][0];
    double det = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02;
    if (!(fabs(det) > 0) || !isfinite(det))
        return false;
    ret[0][0] = c00 / det;
    ret[1][0] = c01 / det;
    ret[2][0] = c02 / det;
    ret[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) / det;
    ret[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / det;
    ret[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) / det;
    ret[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / det;
    ret[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) / det;
    ret[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / det;
    return true;
}

/* The two vertices (of x[0..n)) that span scan facet j, its silhouette
 * edge's ends, into ret (GEO_NONE where none). Along the edge's
 * direction e (in the facet's plane, across the view), the two ends lie
 * one at or before the facet's extent and one at or beyond it (the facet
 * is what the other views left of the strip between them): each end is
 * the highest vertex on its side within tau of the highest of all
 * (slack: how far inside the extent an end may seem). A vertical plane
 * may be of a side view or of the top view: both are tried and the pair
 * lying higher kept. When no pair qualifies, the two highest. */
static void span_of(const geo_poly *scan, uint32_t j, const double (*x)[3],
                    const uint32_t *adj_start, const uint32_t *adj,
                    uint32_t *stamp, uint32_t mark, uint32_t hint,
                    double tau, double slack,
                    uint32_t *cand, double *ch, uint32_t ret[2])
{
    const double *m = scan->planes[j];
    double s1;
    uint32_t top = geo_ascent_top(adj_start, adj, x, m, hint, &s1);
    /* those within tau of it: the vertices above a plane form a
     * connected part of the graph, grown from the top */
    uint32_t nc = 0, second = GEO_NONE;
    double s2 = -INFINITY;
    cand[nc] = top;
    ch[nc++] = s1;
    stamp[top] = mark;
    for (uint32_t i = 0; i < nc; i++)
        for (uint32_t a = adj_start[cand[i]]; a < adj_start[cand[i] + 1]; a++) {
            uint32_t u = adj[a];
            if (stamp[u] == mark)
                continue;
            stamp[u] = mark;
            double s = geo_vdot(m, x[u]);
            if (s > s2) {
                s2 = s;
                second = u;
            }
            if (s >= s1 - tau) {
                cand[nc] = u;
                ch[nc++] = s;
            }
        }
    ret[0] = top;
    ret[1] = second;
    /* the view directions the plane contains: the horizontal one, and z
     * for a vertical plane */
    double views[2][3];
    int nviews = 0;
    double h = sqrt(m[0] * m[0] + m[1] * m[1]);
    if (h > 1e-9) {
        views[nviews][0] = m[1] / h;
        views[nviews][1] = -m[0] / h;
        views[nviews++][2] = 0;
    }
    if (fabs(m[2]) < 1e-6) {
        views[nviews][0] = views[nviews][1] = 0;
        views[nviews++][2] = 1;
    }
    uint32_t fn = geo_poly_facet_size(scan, j);
    const uint32_t *fv = geo_poly_facet(scan, j);
    double best = INFINITY;
    for (int k = 0; k < nviews; k++) {
        double e[3];
        geo_vcross(m, views[k], e);
        double tmin = INFINITY, tmax = -INFINITY;
        for (uint32_t i = 0; i < fn; i++) {
            double t = geo_vdot(e, scan->verts[fv[i]]);
            tmin = t < tmin ? t : tmin;
            tmax = t > tmax ? t : tmax;
        }
        double da = INFINITY, db = INFINITY;
        uint32_t ca = GEO_NONE, cb = GEO_NONE;
        for (uint32_t i = 0; i < nc; i++) {
            uint32_t u = cand[i];
            double drop = s1 - ch[i];
            if (drop > tau)
                continue;
            double t = geo_vdot(e, x[u]);
            if (t <= tmin + slack && drop < da) {
                da = drop;
                ca = u;
            }
            if (t >= tmax - slack && drop < db) {
                db = drop;
                cb = u;
            }
        }
        if (ca != GEO_NONE && cb != GEO_NONE && ca != cb && da + db < best) {
            best = da + db;
            ret[0] = ca;
            ret[1] = cb;
        }
    }
}

/* Adds to B's diagonal: hold on the planes held (their vertices follow
 * them: damped far above the incidences), damp everywhere else. */
static void add_damping(blocks *B, uint32_t nplanes, const uint8_t *held,
                        double hold, double damp)
{
    for (uint32_t i = 0; i < B->n; i++) {
        double (*d)[3] = block_at(B, i, i);
        double di = i < nplanes && held && held[i] ? hold : damp;
        for (int k = 0; k < 3; k++)
            d[k][k] += di;
    }
}

/* One step's system B (planes first, then the ncl vertices) reduced to
 * the planes: each vertex couples only to its planes, so it is eliminated
 * (its inverse block kept in vinv for the back-substitution), leaving the
 * planes' Schur complement in S and the planes' rows of rhs, which is
 * factored into *fac (its analysis reused while the pattern holds; rp,
 * ci and val are S in scalars). 0, -EDOM when the rounding left a vertex
 * block or S not positive definite, -ENOMEM. */
static int schur_factor(blocks *B, blocks *S, uint32_t nplanes, uint32_t ncl,
                        double (*vinv)[3][3], double (*rhs)[3], uint32_t *rp,
                        uint32_t *ci, double *val, geo_spchol **fac)
{
    memset(S->v, 0, (size_t)S->rp[S->n] * sizeof *S->v);
    for (uint32_t p = 0; p < nplanes; p++)
        memcpy(block_at(S, p, p), block_at(B, p, p), sizeof S->v[0]);
    for (uint32_t cv = 0; cv < ncl; cv++) {
        uint32_t row = nplanes + cv;
        double mi[3][3];
        if (!inv3(block_at(B, row, row), mi))
            return -EDOM;
        memcpy(vinv[cv], mi, sizeof mi);
        for (uint32_t ia = B->rp[row]; ia < B->rp[row + 1]; ia++) {
            uint32_t p = B->ci[ia];
            if (p >= nplanes)
                continue;
            double g[3][3]; /* A_pc · A_cc⁻¹ */
            mul3(block_at(B, p, row), mi, g);
            for (int k = 0; k < 3; k++)
                for (int l = 0; l < 3; l++)
                    rhs[3 * p + k][0] -= g[k][l] * rhs[3 * row + l][0];
            for (uint32_t ib = B->rp[row]; ib < B->rp[row + 1]; ib++) {
                uint32_t q = B->ci[ib];
                if (q >= nplanes)
                    continue;
                double h[3][3];
                mul3(g, B->v[ib], h);
                double (*s)[3] = block_at(S, p, q);
                for (int k = 0; k < 3; k++)
                    for (int l = 0; l < 3; l++)
                        s[k][l] -= h[k][l];
            }
        }
    }
    uint32_t z = 0, np3 = 3 * nplanes;
    for (uint32_t i = 0; i < nplanes; i++)
        for (int rI = 0; rI < 3; rI++) {
            rp[3 * i + rI] = z;
            for (uint32_t a = S->rp[i]; a < S->rp[i + 1]; a++)
                for (int k = 0; k < 3; k++) {
                    ci[z] = 3 * S->ci[a] + k;
                    val[z++] = S->v[a][rI][k];
                }
        }
    rp[np3] = z;
    int r = *fac ? geo_spchol_refactor(*fac, np3, rp, ci, val, NULL) : -EINVAL;
    if (r == -EINVAL) {
        *fac = geo_spchol_free(*fac);
        r = geo_spchol_factor(np3, rp, ci, val, GEO_SPCHOL_MIN_DEGREE, 0,
                              NULL, fac);
    }
    return r == -ENOMEM ? r : r < 0 ? -EDOM : 0;
}

/* One measurement: vertex c (of x) by scan facet j, j's view keyed key. */
typedef struct meas {
    int64_t key;
    uint32_t c, j;
} meas;

/* The order within one vertex's measurements: by view, then facet. */
static int cmp_meas(const meas *a, const meas *b)
{
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return (a->j > b->j) - (a->j < b->j);
}

static int cmp_i64(const void *x, const void *y)
{
    int64_t a = *(const int64_t *)x, b = *(const int64_t *)y;
    return (a > b) - (a < b);
}

/* A side view's key for plane m (convex.h, geo_convex_view_keys): views
 * lie far more than 1e-9 rad apart (K = 2400: 1.3e-3 rad) and a plane's
 * rounding moves the azimuth by about 1e-15, so units of 1e-9 rad part
 * them. */
static int64_t side_key(const double m[3], uint32_t j)
{
    double h = hypot(m[0], m[1]);
    if (!(h > 1e-12))
        return -2 - (int64_t)j;
    double a = atan2(m[0], -m[1]);
    if (a < 0)
        a += M_PI;
    if (a >= M_PI - 5e-10)
        a = 0;
    return (int64_t)llround(a * 1e9);
}

int geo_convex_view_keys(const geo_poly *scan, int64_t *key)
{
    uint32_t n = scan->nfacets;
    int64_t *side = malloc(((size_t)n + 1) * sizeof *side);
    if (!side)
        return -ENOMEM;
    size_t ns = 0;
    for (uint32_t j = 0; j < n; j++) {
        key[j] = side_key(scan->planes[j], j);
        if (fabs(scan->planes[j][2]) > 1e-12)
            side[ns++] = key[j];
    }
    qsort(side, ns, sizeof *side, cmp_i64);
    for (uint32_t j = 0; j < n; j++)
        if (fabs(scan->planes[j][2]) <= 1e-12 && key[j] >= 0 &&
            !bsearch(&key[j], side, ns, sizeof *side, cmp_i64))
            key[j] = -1;
    free(side);
    return 0;
}

int geo_convex_refine(const geo_poly *scan, const geo_poly *est,
                      const uint32_t *src, double cluster,
                      double (*planes)[4], uint32_t nplanes,
                      const uint8_t *held, double *ret_scale)
{
    uint32_t nv = est->nverts, nc = geo_poly_ncorners(est);
    *ret_scale = 0;
    int r = -ENOMEM;
    uint32_t *par = malloc(((size_t)nv + 1) * sizeof *par);
    uint32_t *cl = malloc(((size_t)nv + 1) * sizeof *cl);
    double (*x)[3] = calloc((size_t)nv + 1, sizeof *x);
    uint32_t *cand = malloc(((size_t)nv + 1) * sizeof *cand);
    double *ch = malloc(((size_t)nv + 1) * sizeof *ch);
    uint64_t *inc = malloc(((size_t)nc + 1) * sizeof *inc);
    double (*t1)[3] = malloc(((size_t)nplanes + 1) * sizeof *t1);
    double (*t2)[3] = malloc(((size_t)nplanes + 1) * sizeof *t2);
    double *res = malloc((2 * (size_t)scan->nfacets + 1) * sizeof *res);
    uint32_t (*pair)[2] = malloc(((size_t)scan->nfacets + 1) * sizeof *pair);
    int64_t *vkey = malloc(((size_t)scan->nfacets + 1) * sizeof *vkey);
    double (*pl_prev)[4] = malloc(((size_t)nplanes + 1) * sizeof *pl_prev);
    double (*x_prev)[3] = malloc(((size_t)nv + 1) * sizeof *x_prev);
    meas *ms = malloc((2 * (size_t)scan->nfacets + 1) * sizeof *ms);
    double (*pl)[4] = malloc(((size_t)nplanes + 1) * sizeof *pl);
    blocks B = {0}, S = {0};
    double (*vinv)[3][3] = NULL;
    uint32_t *adj_start = NULL, *adj = NULL, *stamp = NULL, *mstart = NULL;
    uint32_t *rp = NULL, *ci = NULL;
    double *val = NULL, (*rhs)[3] = NULL, (*rhs0)[3] = NULL;
    geo_spchol *fac = NULL;
    if (!par || !cl || !x || !cand || !ch || !inc || !t1 || !t2 || !res ||
        !pair || !pl || !vkey || !ms || !pl_prev || !x_prev ||
        geo_convex_view_keys(scan, vkey) < 0)
        goto done;
    memcpy(pl, planes, nplanes * sizeof *pl);

    /* the vertices: the estimate's, those closer than cluster one */
    for (uint32_t v = 0; v < nv; v++)
        par[v] = v;
    for (uint32_t f = 0; f < est->nfacets; f++)
        for (uint32_t k = est->fstart[f]; k < est->fstart[f + 1]; k++) {
            uint32_t a = est->fidx[k];
            uint32_t b = est->fidx[k + 1 < est->fstart[f + 1] ? k + 1
                                                              : est->fstart[f]];
            if (geo_vdist(est->verts[a], est->verts[b]) < cluster)
                par[geo_uf_find(par, a)] = geo_uf_find(par, b);
        }
    uint32_t ncl = 0;
    for (uint32_t v = 0; v < nv; v++)
        if (geo_uf_find(par, v) == v)
            cl[v] = ncl++;
    uint32_t *cnt = calloc((size_t)ncl + 1, sizeof *cnt);
    if (!cnt)
        goto done;
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t c = cl[geo_uf_find(par, v)];
        cl[v] = c;
        cnt[c]++;
        for (int k = 0; k < 3; k++)
            x[c][k] += est->verts[v][k];
    }
    for (uint32_t c = 0; c < ncl; c++)
        for (int k = 0; k < 3; k++)
            x[c][k] /= cnt[c];
    free(cnt);

    /* the vertices' neighbours across the estimate's edges */
    adj_start = calloc((size_t)ncl + 2, sizeof *adj_start);
    mstart = malloc(((size_t)ncl + 2) * sizeof *mstart);
    adj = malloc(((size_t)nc + 1) * sizeof *adj);
    stamp = calloc((size_t)ncl + 1, sizeof *stamp);
    if (!adj_start || !adj || !stamp || !mstart)
        goto done;
    /* each facet edge once per side: its corner's vertex to the next */
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t f = 0; f < est->nfacets; f++)
            for (uint32_t k = est->fstart[f]; k < est->fstart[f + 1]; k++) {
                uint32_t a = cl[est->fidx[k]];
                uint32_t b = cl[est->fidx[k + 1 < est->fstart[f + 1]
                                            ? k + 1 : est->fstart[f]]];
                if (a == b)
                    continue;
                if (pass == 0)
                    adj_start[a + 2]++;
                else
                    adj[adj_start[a + 1]++] = b;
            }
        if (pass == 0)
            for (uint32_t i = 0; i < ncl; i++)
                adj_start[i + 2] += adj_start[i + 1];
    }
    /* the incidences (plane, vertex), each once */
    uint32_t ninc = 0;
    for (uint32_t f = 0; f < est->nfacets; f++)
        for (uint32_t k = est->fstart[f]; k < est->fstart[f + 1]; k++)
            inc[ninc++] = (uint64_t)src[f] << 32 | cl[est->fidx[k]];
    qsort(inc, ninc, sizeof *inc, cmp_u64);
    uint32_t m = 0;
    for (uint32_t i = 0; i < ninc; i++)
        if (m == 0 || inc[i] != inc[m - 1])
            inc[m++] = inc[i];
    ninc = m;

    /* the block pattern: the diagonal and each incidence both ways */
    B.n = nplanes + ncl;
    B.rp = calloc((size_t)B.n + 2, sizeof *B.rp);
    B.ci = malloc(((size_t)B.n + 2 * (size_t)ninc + 1) * sizeof *B.ci);
    if (!B.rp || !B.ci)
        goto done;
    for (uint32_t i = 0; i < B.n; i++)
        B.rp[i + 2]++;
    for (uint32_t i = 0; i < ninc; i++) {
        B.rp[(inc[i] >> 32) + 2]++;
        B.rp[nplanes + (uint32_t)inc[i] + 2]++;
    }
    for (uint32_t i = 0; i < B.n; i++)
        B.rp[i + 2] += B.rp[i + 1];
    for (uint32_t i = 0; i < B.n; i++)
        B.ci[B.rp[i + 1]++] = i;
    for (uint32_t i = 0; i < ninc; i++) {
        uint32_t p = (uint32_t)(inc[i] >> 32), c = nplanes + (uint32_t)inc[i];
        B.ci[B.rp[p + 1]++] = c;
        B.ci[B.rp[c + 1]++] = p;
    }
    for (uint32_t i = 0; i < B.n; i++) /* rows sorted for block_at */
        for (uint32_t a = B.rp[i] + 1; a < B.rp[i + 1]; a++)
            for (uint32_t b = a; b > B.rp[i] && B.ci[b - 1] > B.ci[b]; b--) {
                uint32_t t = B.ci[b];
                B.ci[b] = B.ci[b - 1];
                B.ci[b - 1] = t;
            }
    uint32_t nb = B.rp[B.n], n = 3 * B.n;
    B.v = malloc(((size_t)nb + 1) * sizeof *B.v);
    rhs = malloc(((size_t)n + 1) * sizeof *rhs);
    rhs0 = malloc(((size_t)n + 1) * sizeof *rhs0);
    if (!B.v || !rhs || !rhs0)
        goto done;

    /* the planes' Schur complement: planes meeting at a vertex */
    {
        size_t npair = 0;
        for (uint32_t cv = 0; cv < ncl; cv++) {
            uint32_t row = nplanes + cv, d = B.rp[row + 1] - B.rp[row];
            npair += (size_t)d * d;
        }
        uint64_t *pq = malloc((npair + nplanes + 1) * sizeof *pq);
        if (!pq)
            goto done;
        size_t k = 0;
        for (uint32_t p = 0; p < nplanes; p++)
            pq[k++] = (uint64_t)p << 32 | p;
        for (uint32_t cv = 0; cv < ncl; cv++) {
            uint32_t row = nplanes + cv;
            for (uint32_t ia = B.rp[row]; ia < B.rp[row + 1]; ia++)
                for (uint32_t ib = B.rp[row]; ib < B.rp[row + 1]; ib++)
                    if (B.ci[ia] < nplanes && B.ci[ib] < nplanes)
                        pq[k++] = (uint64_t)B.ci[ia] << 32 | B.ci[ib];
        }
        qsort(pq, k, sizeof *pq, cmp_u64);
        size_t u = 0;
        for (size_t i = 0; i < k; i++)
            if (u == 0 || pq[i] != pq[u - 1])
                pq[u++] = pq[i];
        S.n = nplanes;
        S.rp = calloc((size_t)nplanes + 1, sizeof *S.rp);
        S.ci = malloc((u + 1) * sizeof *S.ci);
        S.v = malloc((u + 1) * sizeof *S.v);
        vinv = malloc(((size_t)ncl + 1) * sizeof *vinv);
        if (!S.rp || !S.ci || !S.v || !vinv) {
            free(pq);
            goto done;
        }
        for (size_t i = 0; i < u; i++) {
            S.rp[(pq[i] >> 32) + 1]++;
            S.ci[i] = (uint32_t)pq[i];
        }
        for (uint32_t p = 0; p < nplanes; p++)
            S.rp[p + 1] += S.rp[p];
        free(pq);
        /* S in scalars: 9 entries a block */
        rp = malloc((3 * (size_t)nplanes + 1) * sizeof *rp);
        ci = malloc((9 * u + 1) * sizeof *ci);
        val = malloc((9 * u + 1) * sizeof *val);
        if (!rp || !ci || !val)
            goto done;
    }
    double scale = 0, scale_prev = cluster;
    uint32_t mark = 0;
    for (int it = 0; it <= REFINE_ITERS; it++) {
        if (it > 0)
            scale_prev = scale;
        for (uint32_t i = 0; i < nplanes; i++)
            geo_vbasis(pl[i], t1[i], t2[i]);
        memset(B.v, 0, (size_t)nb * sizeof *B.v);
        memset(rhs, 0, (size_t)n * sizeof *rhs);
        /* each scan facet's spanning vertices, and the residual scale */
        uint32_t nr = 0;
        for (uint32_t j = 0; j < scan->nfacets; j++) {
            const double *mj = scan->planes[j];
            /* consecutive scan facets are mostly neighbours */
            uint32_t hint = j > 0 ? pair[j - 1][0] : 0;
            span_of(scan, j, (const double(*)[3])x, adj_start, adj, stamp,
                    ++mark, hint, SPAN_SCALES * scale_prev, cluster, cand, ch,
                    pair[j]);
            for (int e = 0; e < 2; e++)
                if (pair[j][e] != GEO_NONE)
                    res[nr++] = fabs(geo_vdot(mj, x[pair[j][e]]) + mj[3]);
        }
        scale = fmax(nr ? 1.4826 * geo_select_kth(res, nr, nr / 2) : 0, 1e-7);
        /* a step that raised the residuals' robust scale is not taken:
         * the estimate before it stands */
        if (it > 0 && scale > scale_prev) {
            memcpy(pl, pl_prev, nplanes * sizeof *pl);
            memcpy(x, x_prev, ncl * sizeof *x);
            break;
        }
        *ret_scale = scale;
        if (it == REFINE_ITERS)
            break;
        double dmax = 0;
        /* the measurements by vertex (counting), each vertex's by view
         * and facet (insertion: a vertex has a few dozen at most) */
        size_t nm = 0;
        memset(mstart, 0, ((size_t)ncl + 2) * sizeof *mstart);
        for (uint32_t j = 0; j < scan->nfacets; j++)
            for (int e = 0; e < 2; e++)
                if (pair[j][e] != GEO_NONE)
                    mstart[pair[j][e] + 2]++, nm++;
        for (uint32_t c = 0; c < ncl; c++)
            mstart[c + 2] += mstart[c + 1];
        for (uint32_t j = 0; j < scan->nfacets; j++)
            for (int e = 0; e < 2; e++)
                if (pair[j][e] != GEO_NONE)
                    ms[mstart[pair[j][e] + 1]++] =
                        (meas){vkey[j], pair[j][e], j};
        for (uint32_t c = 0; c < ncl; c++)
            for (uint32_t i = mstart[c] + 1; i < mstart[c + 1]; i++)
                for (uint32_t k = i;
                     k > mstart[c] && cmp_meas(&ms[k - 1], &ms[k]) > 0; k--) {
                    meas t = ms[k];
                    ms[k] = ms[k - 1];
                    ms[k - 1] = t;
                }
        for (size_t a = 0, b; a < nm; a = b) {
            for (b = a + 1;
                 b < nm && ms[b].key == ms[a].key && ms[b].c == ms[a].c;)
                b++;
            uint32_t c = ms[a].c, ti = nplanes + c;
            if (b - a == 2 && corner(scan->planes[ms[a].j],
                                     scan->planes[ms[a + 1].j], x[c],
                                     HUBER * scale, SPAN_SCALES * scale, &B,
                                     ti, &rhs[3 * ti]))
                continue;
            for (size_t i = a; i < b; i++) {
                const double *mj = scan->planes[ms[i].j];
                double rr = geo_vdot(mj, x[c]) + mj[3];
                double w = fabs(rr) <= HUBER * scale ? 1
                                                      : HUBER * scale / fabs(rr);
                add_outer(&B, &ti, mj, 1, w);
                for (int k = 0; k < 3; k++)
                    rhs[3 * ti + k][0] -= w * mj[k] * rr;
            }
        }
        for (uint32_t i = 0; i < B.n; i++) {
            double (*d)[3] = block_at(&B, i, i);
            for (int k = 0; k < 3; k++)
                dmax = fmax(dmax, d[k][k]);
        }
        double W = CONSTRAINT_WEIGHT * fmax(dmax, 1);
        for (uint32_t i = 0; i < ninc; i++) {
            uint32_t p = (uint32_t)(inc[i] >> 32), c = (uint32_t)inc[i];
            uint32_t ti[2] = {p, nplanes + c};
            double g[6] = {geo_vdot(t1[p], x[c]), geo_vdot(t2[p], x[c]), 1,
                           pl[p][0], pl[p][1], pl[p][2]};
            double rr = geo_vdot(pl[p], x[c]) + pl[p][3];
            add_outer(&B, ti, g, 2, W);
            for (int k = 0; k < 3; k++) {
                rhs[3 * p + k][0] -= W * g[k] * rr;
                rhs[3 * (nplanes + c) + k][0] -= W * g[3 + k] * rr;
            }
        }
        double damp = DAMP_REL * W + 1e-12, added = 0;
        memcpy(rhs0, rhs, (size_t)n * sizeof *rhs);
        for (int attempt = 0;; attempt++) {
            add_damping(&B, nplanes, held, attempt ? 0 : HOLD_REL * W,
                        damp - added);
            added = damp;
            memcpy(rhs, rhs0, (size_t)n * sizeof *rhs);
            r = schur_factor(&B, &S, nplanes, ncl, vinv, rhs, rp, ci, val,
                             &fac);
            if (r != -EDOM || attempt == DAMP_RETRIES)
                break;
            damp *= DAMP_GROW;
        }
        if (r < 0) {
            r = r == -ENOMEM ? r : -EINVAL;
            goto done;
        }
        if ((r = geo_spchol_solve3(fac, rhs)) < 0)
            goto done;
        memcpy(pl_prev, pl, nplanes * sizeof *pl);
        memcpy(x_prev, x, ncl * sizeof *x);
        for (uint32_t cv = 0; cv < ncl; cv++) {
            uint32_t row = nplanes + cv;
            double bv[3] = {rhs[3 * row][0], rhs[3 * row + 1][0],
                            rhs[3 * row + 2][0]};
            for (uint32_t ia = B.rp[row]; ia < B.rp[row + 1]; ia++) {
                uint32_t p = B.ci[ia];
                if (p >= nplanes)
                    continue;
                for (int k = 0; k < 3; k++)
                    for (int l = 0; l < 3; l++)
                        bv[k] -= B.v[ia][k][l] * rhs[3 * p + l][0];
            }
            for (int k = 0; k < 3; k++)
                rhs[3 * row + k][0] = vinv[cv][k][0] * bv[0] +
                                      vinv[cv][k][1] * bv[1] +
                                      vinv[cv][k][2] * bv[2];
        }
        for (uint32_t i = 0; i < nplanes; i++) {
            double nn[3];
            for (int k = 0; k < 3; k++)
                nn[k] = pl[i][k] + rhs[3 * i][0] * t1[i][k] +
                        rhs[3 * i + 1][0] * t2[i][k];
            double len = sqrt(geo_vdot(nn, nn));
            for (int k = 0; k < 3; k++)
                pl[i][k] = nn[k] / len;
            pl[i][3] = (pl[i][3] + rhs[3 * i + 2][0]) / len;
        }
        for (uint32_t c = 0; c < ncl; c++)
            for (int k = 0; k < 3; k++)
                x[c][k] += rhs[3 * (nplanes + c) + k][0];
    }
    memcpy(planes, pl, nplanes * sizeof *pl);
    r = 0;
done:
    geo_spchol_free(fac);
    free(par), free(cl), free(x), free(cand), free(ch), free(inc);
    free(t1), free(t2), free(res);
    free(pair), free(pl), free(B.rp), free(B.ci), free(B.v);
    free(vkey), free(ms), free(mstart), free(pl_prev), free(x_prev);
    free(S.rp), free(S.ci), free(S.v), free(vinv);
    free(adj_start), free(adj), free(stamp);
    free(rp), free(ci), free(val), free(rhs), free(rhs0);
    return r;
}
