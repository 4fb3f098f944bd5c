/* convex_refine.c — the recovered planes adjusted to the silhouettes
 * (convex.h, geo_convex_refine).
 *
 * Every facet of a raw shadow-profile scan is one silhouette plane
 * (Palachev 2012, §1.2): a plane tangent to the true stone, its offset
 * off by the silhouette noise. So for each scan facet j (unit normal m_j,
 * offset d_j) the true stone's support in direction m_j is −d_j:
 *
 *     max over the stone's vertices v of  m_j · v  =  −d_j  (+ noise),
 *
 * and the stone's vertices are the meets of its facet planes. The planes
 * are adjusted (Gauss–Newton, each plane by a tilt in two directions and
 * an offset) so that these supports match in the least-squares sense:
 * the estimator that uses every silhouette, where a group fit uses only
 * the slivers that survived on one facet. A scan facet whose support is
 * shared by two vertices within the noise (a sliver hinged on a true
 * edge) constrains both. Residuals are Huber-weighted at twice their
 * robust scale (a scan facet tangent where the estimate has a cluster of
 * vertices instead of one); a small damping keeps the planes no
 * silhouette sees where they were.
 *
 * Each vertex keeps, through the iterations, the three planes of its
 * facets that meet best (largest |det|); the caller intersects the
 * adjusted planes again for the topology. Cost per iteration: O(F·V)
 * for the supports (F scan facets, V vertices) plus O(P³) for the
 * normal equations of P planes (dense Cholesky). */
#include "convex.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "topo.h"
#include "vec.h"

#define REFINE_ITERS 4
/* Two vertices support a scan facet together when within this many
 * residual scales of each other. */
#define TIE_SCALE 1.0
#define HUBER 2.0
/* Damping: relative to the largest diagonal entry, and absolute (per mm²
 * of the offset's scale). */
#define DAMP_REL 1e-6

typedef struct vtx {
    uint32_t pl[3];   /* its three planes */
    double x[3];      /* position */
    double w[3][3];   /* columns of N⁻¹ (w[r] = N⁻¹ e_r) */
} vtx;

/* Solves the meet of planes a, b, c; fills v->x and v->w. false when the
 * normals are dependent. */
static bool vtx_solve(vtx *v, const double (*pl)[4])
{
    const double *a = pl[v->pl[0]], *b = pl[v->pl[1]], *c = pl[v->pl[2]];
    double bc[3], ca[3], ab[3];
    geo_vcross(b, c, bc);
    geo_vcross(c, a, ca);
    geo_vcross(a, b, ab);
    double det = geo_vdot(a, bc);
    if (fabs(det) < 1e-12)
        return false;
    /* N⁻¹ = [bc ca ab] / det (columns) */
    for (int k = 0; k < 3; k++) {
        v->w[0][k] = bc[k] / det;
        v->w[1][k] = ca[k] / det;
        v->w[2][k] = ab[k] / det;
        v->x[k] = -(a[3] * bc[k] + b[3] * ca[k] + c[3] * ab[k]) / det;
    }
    return true;
}

/* Dense Cholesky solve of the n×n SPD matrix a (row-major, overwritten)
 * with right-hand side b (overwritten by x). false when not SPD. */
static bool chol_solve(double *a, double *b, uint32_t n)
{
    for (uint32_t j = 0; j < n; j++) {
        double s = a[(size_t)j * n + j];
        for (uint32_t k = 0; k < j; k++)
            s -= a[(size_t)j * n + k] * a[(size_t)j * n + k];
        if (!(s > 0))
            return false;
        double l = sqrt(s);
        a[(size_t)j * n + j] = l;
        for (uint32_t i = j + 1; i < n; i++) {
            double t = a[(size_t)i * n + j];
            for (uint32_t k = 0; k < j; k++)
                t -= a[(size_t)i * n + k] * a[(size_t)j * n + k];
            a[(size_t)i * n + j] = t / l;
        }
    }
    for (uint32_t i = 0; i < n; i++) {
        double t = b[i];
        for (uint32_t k = 0; k < i; k++)
            t -= a[(size_t)i * n + k] * b[k];
        b[i] = t / a[(size_t)i * n + i];
    }
    for (uint32_t i = n; i-- > 0;) {
        double t = b[i];
        for (uint32_t k = i + 1; k < n; k++)
            t -= a[(size_t)k * n + i] * b[k];
        b[i] = t / a[(size_t)i * n + i];
    }
    return true;
}

static void tangents(const double n[3], double t1[3], double t2[3])
{
    double e[3] = {0, 0, 0};
    int k = fabs(n[0]) < fabs(n[1]) ? (fabs(n[0]) < fabs(n[2]) ? 0 : 2)
                                    : (fabs(n[1]) < fabs(n[2]) ? 1 : 2);
    e[k] = 1;
    geo_vcross(n, e, t1);
    geo_vnormalize(t1);
    geo_vcross(n, t1, t2);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One row of the normal equations: residual r, weight wt, for vertex v
 * along direction m. */
static void add_row(double *A, double *g, uint32_t np3, const vtx *v,
                    const double m[3], double r, double wt,
                    const double (*t1)[3], const double (*t2)[3])
{
    uint32_t idx[9];
    double jac[9];
    for (int s = 0; s < 3; s++) {
        uint32_t i = v->pl[s];
        double mw = -geo_vdot(m, v->w[s]);
        jac[3 * s] = mw * geo_vdot(t1[i], v->x);
        jac[3 * s + 1] = mw * geo_vdot(t2[i], v->x);
        jac[3 * s + 2] = mw;
        idx[3 * s] = 3 * i;
        idx[3 * s + 1] = 3 * i + 1;
        idx[3 * s + 2] = 3 * i + 2;
    }
    for (int a = 0; a < 9; a++) {
        g[idx[a]] += wt * jac[a] * r;
        for (int b = 0; b < 9; b++)
            A[(size_t)idx[a] * np3 + idx[b]] += wt * jac[a] * jac[b];
    }
}

int geo_convex_refine(const geo_poly *scan, const geo_poly *est,
                      const uint32_t *src, double (*planes)[4],
                      uint32_t nplanes, double *ret_scale)
{
    uint32_t nv = est->nverts, np3 = 3 * nplanes;
    *ret_scale = 0;
    if ((size_t)np3 * np3 > (size_t)64 << 20)
        return -E2BIG; /* beyond what a dense solve should take */
    vtx *vs = malloc(((size_t)nv + 1) * sizeof *vs);
    uint32_t *vf = malloc(((size_t)geo_poly_ncorners(est) + 1) * sizeof *vf);
    uint32_t *vstart = calloc((size_t)nv + 2, sizeof *vstart);
    double *A = malloc((size_t)np3 * np3 * sizeof *A);
    double *g = malloc(((size_t)np3 + 1) * sizeof *g);
    double (*t1)[3] = malloc(((size_t)nplanes + 1) * sizeof *t1);
    double (*t2)[3] = malloc(((size_t)nplanes + 1) * sizeof *t2);
    double *res = malloc((2 * (size_t)scan->nfacets + 1) * sizeof *res);
    double (*pl)[4] = malloc(((size_t)nplanes + 1) * sizeof *pl);
    int r = -ENOMEM;
    if (!vs || !vf || !vstart || !A || !g || !t1 || !t2 || !res || !pl)
        goto done;
    memcpy(pl, planes, nplanes * sizeof *pl);
    /* each vertex's facets, then its best-meeting triple of planes */
    for (uint32_t f = 0; f < est->nfacets; f++)
        for (uint32_t k = est->fstart[f]; k < est->fstart[f + 1]; k++)
            vstart[est->fidx[k] + 2]++;
    for (uint32_t v = 0; v < nv; v++)
        vstart[v + 2] += vstart[v + 1];
    for (uint32_t f = 0; f < est->nfacets; f++)
        for (uint32_t k = est->fstart[f]; k < est->fstart[f + 1]; k++)
            vf[vstart[est->fidx[k] + 1]++] = src[f];
    for (uint32_t v = 0; v < nv; v++) {
        double best = -1;
        const uint32_t *fs = vf + vstart[v];
        uint32_t n = vstart[v + 1] - vstart[v];
        for (uint32_t a = 0; a < n; a++)
            for (uint32_t b = a + 1; b < n; b++)
                for (uint32_t c = b + 1; c < n; c++) {
                    double bc[3];
                    geo_vcross(pl[fs[b]], pl[fs[c]], bc);
                    double det = fabs(geo_vdot(pl[fs[a]], bc));
                    if (det > best) {
                        best = det;
                        vs[v].pl[0] = fs[a];
                        vs[v].pl[1] = fs[b];
                        vs[v].pl[2] = fs[c];
                    }
                }
        if (best <= 0) {
            r = -EINVAL;
            goto done;
        }
    }
    double scale = 0;
    for (int it = 0; it < REFINE_ITERS; it++) {
        for (uint32_t v = 0; v < nv; v++)
            if (!vtx_solve(&vs[v], (const double(*)[4])pl)) {
                r = -EINVAL;
                goto done;
            }
        for (uint32_t i = 0; i < nplanes; i++)
            tangents(pl[i], t1[i], t2[i]);
        /* the supports: the best vertex per scan facet, and its tie */
        uint32_t nr = 0;
        memset(A, 0, (size_t)np3 * np3 * sizeof *A);
        memset(g, 0, np3 * sizeof *g);
        for (int pass = 0; pass < 2; pass++) {
            nr = 0;
            for (uint32_t j = 0; j < scan->nfacets; j++) {
                const double *m = scan->planes[j];
                uint32_t b1 = 0, b2 = GEO_NONE;
                double s1 = -INFINITY, s2 = -INFINITY;
                for (uint32_t v = 0; v < nv; v++) {
                    double s = geo_vdot(m, vs[v].x);
                    if (s > s1) {
                        s2 = s1, b2 = b1;
                        s1 = s, b1 = v;
                    } else if (s > s2) {
                        s2 = s, b2 = v;
                    }
                }
                double r1 = s1 + m[3];
                if (pass == 0) {
                    res[nr++] = fabs(r1);
                    continue;
                }
                double wt = fabs(r1) <= HUBER * scale ? 1 : HUBER * scale / fabs(r1);
                add_row(A, g, np3, &vs[b1], m, r1, wt, (const double(*)[3])t1,
                        (const double(*)[3])t2);
                if (b2 != GEO_NONE && s1 - s2 <= TIE_SCALE * scale) {
                    double r2 = s2 + m[3];
                    double w2 = fabs(r2) <= HUBER * scale ? 1 : HUBER * scale / fabs(r2);
                    add_row(A, g, np3, &vs[b2], m, r2, w2, (const double(*)[3])t1,
                            (const double(*)[3])t2);
                }
            }
            if (pass == 0) {
                qsort(res, nr, sizeof *res, cmp_double);
                scale = fmax(1.4826 * res[nr / 2], 1e-7);
                if (it == 0)
                    *ret_scale = scale;
            }
        }
        double dmax = 0;
        for (uint32_t i = 0; i < np3; i++)
            dmax = fmax(dmax, A[(size_t)i * np3 + i]);
        for (uint32_t i = 0; i < np3; i++) {
            A[(size_t)i * np3 + i] += DAMP_REL * dmax + 1e-12;
            g[i] = -g[i];
        }
        if (!chol_solve(A, g, np3)) {
            r = -EINVAL;
            goto done;
        }
        for (uint32_t i = 0; i < nplanes; i++) {
            double n[3];
            for (int k = 0; k < 3; k++)
                n[k] = pl[i][k] + g[3 * i] * t1[i][k] + g[3 * i + 1] * t2[i][k];
            geo_vnormalize(n);
            memcpy(pl[i], n, sizeof n);
            pl[i][3] += g[3 * i + 2];
        }
    }
    memcpy(planes, pl, nplanes * sizeof *pl);
    r = 0;
done:
    free(vs), free(vf), free(vstart), free(A), free(g), free(t1), free(t2);
    free(res), free(pl);
    return r;
}
