/* scan_bound.c — the Cramér–Rao bound of a simulated scan (scan_bound.h).
 *
 * Unknowns: each facet's plane n·x + d = 0 (a tilt a·t1 + b·t2 of its
 * normal and a shift c of its offset) and each vertex's position. A view
 * with projection basis (e1, e2) measures P x, P = e1 e1ᵀ + e2 e2ᵀ, of
 * every vertex x on its silhouette; summed over those views that is the
 * information Q_x / σ² on x. The stone's incidences are constraints: a
 * vertex stays on each of its facets' planes, linearised
 * s_f · (a, b, c) + n_f · δx = 0 with s_f = (t1·x, t2·x, 1) — so a vertex
 * where four planes meet stays one vertex, as on the stone. The
 * constrained bound is taken as the limit of the information with each
 * constraint added as a measurement of weight CONSTRAINT_WEIGHT times the
 * largest vertex information; the information is sparse (a facet with
 * its vertices), factored by lib/core/spchol, and each facet's block of
 * the inverse solved for. */
#include "scan_bound.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "convex.h"
#include "spchol.h"
#include "stone_sim.h"
#include "vec.h"

/* Regularisation relative to the largest diagonal entry: a plane no
 * silhouette sees keeps a huge variance instead of making the
 * information singular. */
#define BOUND_REG 1e-10
/* The incidence constraints' weight, relative to the largest vertex
 * information: large enough that they hold to 1e-6 of the noise. */
#define CONSTRAINT_WEIGHT 1e6

static void tangents(const double n[3], double t1[3], double t2[3])
{
    double e[3] = {0, 0, 0};
    e[fabs(n[0]) < 0.6 ? 0 : 1] = 1;
    geo_vcross(n, e, t1);
    geo_vnormalize(t1);
    geo_vcross(n, t1, t2);
}

/* P(|δ| < t) for δ Gaussian in the plane with covariance c (2×2). */
static double within(double c00, double c01, double c11, double t)
{
    double tr = c00 + c11, dt = sqrt(fmax(0, (c00 - c11) * (c00 - c11) / 4 + c01 * c01));
    double l1 = fmax(tr / 2 + dt, 1e-300), l2 = fmax(tr / 2 - dt, 1e-300);
    /* polar integral: ∫ (1 − exp(−t² a(θ) / 2)) / a(θ) dθ / (2π √(l1 l2)),
     * a(θ) = cos²θ / l1 + sin²θ / l2 */
    const int steps = 720;
    double s = 0;
    for (int i = 0; i < steps; i++) {
        double th = (i + 0.5) * 2 * M_PI / steps, c = cos(th), sn = sin(th);
        double a = c * c / l1 + sn * sn / l2;
        s += -expm1(-t * t * a / 2) / a;
    }
    double p = s * (2 * M_PI / steps) / (2 * M_PI * sqrt(l1 * l2));
    return p > 1 ? 1 : p;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The bound from q[v], the sum over v's measurements of the projector
 * each measures (times σ², which is divided out here); q is not read
 * when sigma is 0 (every facet attainable). */
static int bound_of(const geo_poly *stone, const double (*q)[3][3],
                    double sigma, double tol_deg, double *facet_sd_deg,
                    sim_scan_bound *ret)
{
    uint32_t nf = stone->nfacets, nv = stone->nverts;
    uint32_t n = 3 * nf + 3 * nv;
    memset(ret, 0, sizeof *ret);
    ret->truth = nf;
    if (!(sigma > 0)) {
        ret->attainable = nf;
        if (facet_sd_deg)
            memset(facet_sd_deg, 0, nf * sizeof *facet_sd_deg);
        return 0;
    }
    int r = -ENOMEM;
    double *info = calloc((size_t)n * n + 1, sizeof *info);
    double (*t1)[3] = malloc(((size_t)nf + 1) * sizeof *t1);
    double (*t2)[3] = malloc(((size_t)nf + 1) * sizeof *t2);
    uint32_t *rp = NULL, *ci = NULL;
    double *val = NULL, (*b)[3] = NULL, *sd = NULL;
    geo_spchol *fac = NULL;
    if (!info || !t1 || !t2)
        goto done;
#define INFO(i, j) info[(size_t)(i) * n + (j)]
    double qmax = 0;
    for (uint32_t v = 0; v < nv; v++)
        for (int a = 0; a < 3; a++) {
            for (int c = 0; c < 3; c++)
                INFO(3 * nf + 3 * v + a, 3 * nf + 3 * v + c) = q[v][a][c] / (sigma * sigma);
            qmax = fmax(qmax, q[v][a][a] / (sigma * sigma));
        }
    for (uint32_t i = 0; i < n; i++)
        INFO(i, i) += BOUND_REG * qmax + 1e-300;
    /* the incidences */
    double w = CONSTRAINT_WEIGHT * qmax;
    for (uint32_t f = 0; f < nf; f++) {
        const double *nn = stone->planes[f];
        tangents(nn, t1[f], t2[f]);
        for (uint32_t c = stone->fstart[f]; c < stone->fstart[f + 1]; c++) {
            uint32_t v = stone->fidx[c];
            const double *x = stone->verts[v];
            uint32_t idx[6] = {3 * f, 3 * f + 1, 3 * f + 2, 3 * nf + 3 * v,
                               3 * nf + 3 * v + 1, 3 * nf + 3 * v + 2};
            double g[6] = {geo_vdot(t1[f], x), geo_vdot(t2[f], x), 1,
                           nn[0], nn[1], nn[2]};
            for (int i = 0; i < 6; i++)
                for (int j = 0; j < 6; j++)
                    INFO(idx[i], idx[j]) += w * g[i] * g[j];
        }
    }
    /* compressed rows of the nonzero pattern */
    size_t nnz = 0;
    for (size_t i = 0; i < (size_t)n * n; i++)
        nnz += info[i] != 0;
    rp = malloc(((size_t)n + 1) * sizeof *rp);
    ci = malloc((nnz + 1) * sizeof *ci);
    val = malloc((nnz + 1) * sizeof *val);
    b = malloc(((size_t)n + 1) * sizeof *b);
    sd = malloc(((size_t)nf + 1) * sizeof *sd);
    if (!rp || !ci || !val || !b || !sd)
        goto done;
    nnz = 0;
    for (uint32_t i = 0; i < n; i++) {
        rp[i] = (uint32_t)nnz;
        for (uint32_t j = 0; j < n; j++)
            if (INFO(i, j) != 0) {
                ci[nnz] = j;
                val[nnz++] = INFO(i, j);
            }
    }
    rp[n] = (uint32_t)nnz;
#undef INFO
    free(info);
    info = NULL;
    r = geo_spchol_factor(n, rp, ci, val, GEO_SPCHOL_DISSECTION, 0, NULL, &fac);
    if (r < 0)
        goto done;
    double tol = tol_deg * M_PI / 180, sum = 0;
    for (uint32_t f = 0; f < nf; f++) {
        memset(b, 0, (size_t)n * sizeof *b);
        for (int j = 0; j < 3; j++)
            b[3 * f + j][j] = 1;
        if ((r = geo_spchol_solve3(fac, b)) < 0)
            goto done;
        double c00 = b[3 * f][0], c01 = b[3 * f][1], c11 = b[3 * f + 1][1];
        sum += within(c00, c01, c11, tol);
        sd[f] = sqrt(fmax(0, c00 + c11)) * 180 / M_PI;
        if (facet_sd_deg)
            facet_sd_deg[f] = sd[f];
    }
    qsort(sd, nf, sizeof *sd, cmp_double);
    ret->attainable = sum;
    ret->sd_median_deg = nf ? sd[nf / 2] : 0;
    r = 0;
done:
    geo_spchol_free(fac);
    free(info), free(t1), free(t2);
    free(rp), free(ci), free(val), free(b), free(sd);
    return r;
}

int sim_scan_bound_measure(const geo_poly *stone, uint32_t k, double sigma,
                           double phase, double tol_deg, double *facet_sd_deg,
                           sim_scan_bound *ret)
{
    if (!(sigma > 0)) /* every facet: no silhouette to look at */
        return bound_of(stone, NULL, sigma, tol_deg, facet_sd_deg, ret);
    uint32_t nv = stone->nverts;
    double (*q)[3][3] = calloc((size_t)nv + 1, sizeof *q);
    uint32_t *ids = malloc(((size_t)nv + 1) * sizeof *ids);
    int r = -ENOMEM;
    if (!q || !ids)
        goto done;
    /* Q_x over the views that have x on their silhouette */
    for (uint32_t i = 0; i <= k; i++) {
        double e1[3], e2[3];
        sim_view_basis(k, phase, i, e1, e2);
        uint32_t h = sim_silhouette(stone, e1, e2, ids);
        if (h == 0 && nv > 0)
            goto done;
        for (uint32_t j = 0; j < h; j++)
            for (int a = 0; a < 3; a++)
                for (int c = 0; c < 3; c++)
                    q[ids[j]][a][c] += e1[a] * e1[c] + e2[a] * e2[c];
    }
    r = bound_of(stone, (const double(*)[3][3])q, sigma, tol_deg,
                 facet_sd_deg, ret);
done:
    free(q), free(ids);
    return r;
}

/* One measurement of the scan: stone vertex v measured along the normal
 * of scan facet j, from the view keyed key. */
typedef struct span_rec {
    int64_t key;
    uint32_t v, j;
} span_rec;

static int cmp_span_rec(const void *x, const void *y)
{
    const span_rec *a = x, *b = y;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    if (a->v != b->v)
        return a->v < b->v ? -1 : 1;
    return (a->j > b->j) - (a->j < b->j);
}

int sim_scan_bound_of_scan(const geo_poly *stone, const geo_poly *scan,
                           double sigma, double tol_deg, double *facet_sd_deg,
                           sim_scan_bound *ret)
{
    if (!(sigma > 0))
        return bound_of(stone, NULL, sigma, tol_deg, facet_sd_deg, ret);
    uint32_t nv = stone->nverts, nj = scan->nfacets;
    double (*q)[3][3] = calloc((size_t)nv + 1, sizeof *q);
    span_rec *rec = malloc((2 * (size_t)nj + 1) * sizeof *rec);
    int64_t *key = malloc(((size_t)nj + 1) * sizeof *key);
    if (!q || !rec || !key || geo_convex_view_keys(scan, key) < 0) {
        free(q), free(rec), free(key);
        return -ENOMEM;
    }
    /* each scan facet measures, along its normal, the two stone vertices
     * that span it: the two highest in its direction */
    size_t nr = 0;
    for (uint32_t j = 0; j < nj; j++) {
        const double *m = scan->planes[j];
        uint32_t top[2] = {UINT32_MAX, UINT32_MAX};
        double s1 = -INFINITY, s2 = -INFINITY;
        for (uint32_t v = 0; v < nv; v++) {
            double s = geo_vdot(m, stone->verts[v]);
            if (s > s1) {
                s2 = s1, top[1] = top[0];
                s1 = s, top[0] = v;
            } else if (s > s2) {
                s2 = s, top[1] = v;
            }
        }
        for (int e = 0; e < 2; e++)
            if (top[e] != UINT32_MAX)
                rec[nr++] = (span_rec){key[j], top[e], j};
    }
    /* The planes of one view through one vertex measure the same noisy
     * projected point (consecutive edges of a silhouette share their
     * corner): together they observe its components along their normals,
     * with one noise, so the information is the projection onto the span
     * of those normals (both image directions once two of them differ),
     * not the sum of one term per plane. */
    qsort(rec, nr, sizeof *rec, cmp_span_rec);
    for (size_t a = 0, b; a < nr; a = b) {
        for (b = a + 1;
             b < nr && rec[b].key == rec[a].key && rec[b].v == rec[a].v;)
            b++;
        const double *m1 = scan->planes[rec[a].j];
        double d[3] = {0, 0, 0}, dl = 0;
        for (size_t i = a + 1; i < b && !(dl > 1e-9); i++) {
            geo_vcross(m1, scan->planes[rec[i].j], d);
            dl = sqrt(geo_vdot(d, d));
        }
        double (*qv)[3] = q[rec[a].v];
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                qv[r][c] += dl > 1e-9 ? (r == c) - d[r] * d[c] / (dl * dl)
                                      : m1[r] * m1[c];
    }
    int r = bound_of(stone, (const double(*)[3][3])q, sigma, tol_deg,
                     facet_sd_deg, ret);
    free(q), free(rec), free(key);
    return r;
}
