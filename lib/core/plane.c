/* plane.c — plane fitting and intersection (Palachev 2012, §2.5, §2.6.3). */
#include "plane.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec.h"

/* The eigenpairs val[k], vec[k] in ascending order of value, each vector
 * made unit: both solvers' answer. */
static void sorted_out(const double val[3], const double vec[3][3],
                       double ret_values[3], double ret_vectors[3][3])
{
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (val[order[j]] < val[order[i]]) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    for (int i = 0; i < 3; i++) {
        ret_values[i] = val[order[i]];
        memcpy(ret_vectors[i], vec[order[i]], sizeof vec[0]);
        geo_vnormalize(ret_vectors[i]);
    }
}

void geo_sym3_eigen_jacobi(const double a0[3][3], double ret_values[3],
                           double ret_vectors[3][3])
{
    double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            a[i][j] = i <= j ? a0[i][j] : a0[j][i];

    for (int sweep = 0; sweep < 50; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (off == 0.0 || off <= 1e-300 || off < 1e-18 * diag)
            break;
        for (int p = 0; p < 2; p++) {
            for (int q = p + 1; q < 3; q++) {
                if (a[p][q] == 0.0)
                    continue;
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) /
                           (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int k = 0; k < 3; k++) { /* A = Jᵀ A J */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 3; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    double val[3], vec[3][3];
    for (int k = 0; k < 3; k++) {
        val[k] = a[k][k];
        for (int i = 0; i < 3; i++)
            vec[k][i] = v[i][k];
    }
    sorted_out(val, (const double(*)[3])vec, ret_values, ret_vectors);
}

/* Unit x perpendicular to the rows of m, from the largest of the rows'
 * pairwise cross products; its squared length, relative to the scale of
 * m, in *ret_q. */
static void null_vector(const double m[3][3], double x[3], double *ret_q)
{
    double c[3][3], best = -1;
    int k = 0;
    geo_vcross(m[0], m[1], c[0]);
    geo_vcross(m[0], m[2], c[1]);
    geo_vcross(m[1], m[2], c[2]);
    for (int i = 0; i < 3; i++) {
        double q = geo_vdot(c[i], c[i]);
        if (q > best) {
            best = q;
            k = i;
        }
    }
    double f = geo_vdot(m[0], m[0]) + geo_vdot(m[1], m[1]) +
               geo_vdot(m[2], m[2]);
    *ret_q = f > 0 ? best / (f * f) : 0;
    memcpy(x, c[k], sizeof c[k]);
    geo_vnormalize(x);
}

static double quad(const double a[3][3], const double u[3], const double v[3])
{
    double r = 0;
    for (int i = 0; i < 3; i++)
        r += u[i] * (a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2]);
    return r;
}

/* The closed form (Smith 1961) gives the three eigenvalues at the cost of
 * one acos and two cos. The one farthest from the other two is
 * well-conditioned: its eigenvector is the null vector of A − λI, and
 * the other two are the exact 2×2 problem in the plane perpendicular to
 * it (one Jacobi rotation). The plane fits call this for every facet a
 * group takes in, and four Jacobi sweeps cost four times as much.
 * Nearly scalar matrices (spread below 1e-6 of the mean, where the
 * eigenvalues' rounding approaches their gaps) go to Jacobi. */
void geo_sym3_eigen(double m[3][3], double ret_values[3],
                    double ret_vectors[3][3])
{
    double a[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            a[i][j] = i <= j ? m[i][j] : m[j][i];
    const double(*ca)[3] = (const double(*)[3])a;
    double q = (a[0][0] + a[1][1] + a[2][2]) / 3;
    double p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    double p2 = (a[0][0] - q) * (a[0][0] - q) + (a[1][1] - q) * (a[1][1] - q) +
                (a[2][2] - q) * (a[2][2] - q) + 2 * p1;
    double pp = sqrt(p2 / 6);
    if (!(pp > 1e-6 * fabs(q)) || !isfinite(pp)) {
        geo_sym3_eigen_jacobi(ca, ret_values, ret_vectors);
        return;
    }
    double b[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            b[i][j] = (a[i][j] - (i == j ? q : 0)) / pp;
    double r = (b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) -
                b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0])) / 2;
    double phi = acos(fmin(fmax(r, -1), 1)) / 3;
    double hi = q + 2 * pp * cos(phi);
    double lo = q + 2 * pp * cos(phi + 2 * M_PI / 3);
    double mid = 3 * q - hi - lo;
    /* the isolated one: lo unless lo and mid are the closer pair */
    double lam = mid - lo >= hi - mid ? lo : hi;
    double mm[3][3], x[3], qual;
    memcpy(mm, a, sizeof mm);
    for (int i = 0; i < 3; i++)
        mm[i][i] -= lam;
    null_vector((const double(*)[3])mm, x, &qual);
    /* exactly, qual is at least 1/20 (the isolated one's gaps are at
     * least half the spread); far below it, λ was not accurate */
    if (!(qual > 1e-3)) {
        geo_sym3_eigen_jacobi(ca, ret_values, ret_vectors);
        return;
    }
    /* u, w: an orthonormal basis of the plane perpendicular to x */
    int k = fabs(x[0]) <= fabs(x[1]) && fabs(x[0]) <= fabs(x[2]) ? 0
            : fabs(x[1]) <= fabs(x[2])                           ? 1
                                                                 : 2;
    double e[3] = {0, 0, 0}, u[3], w[3];
    e[k] = 1;
    geo_vcross(x, e, u);
    geo_vnormalize(u);
    geo_vcross(x, u, w);
    double uu = quad(ca, u, u), uw = quad(ca, u, w), ww = quad(ca, w, w);
    double val[3] = {quad(ca, x, x), uu, ww}, vec[3][3];
    memcpy(vec[0], x, sizeof x);
    memcpy(vec[1], u, sizeof u);
    memcpy(vec[2], w, sizeof w);
    if (uw != 0) {
        double theta = (ww - uu) / (2 * uw);
        double t = (theta >= 0 ? 1.0 : -1.0) /
                   (fabs(theta) + sqrt(theta * theta + 1));
        double c = 1 / sqrt(t * t + 1), sn = t * c;
        val[1] = uu - t * uw;
        val[2] = ww + t * uw;
        for (int i = 0; i < 3; i++) {
            vec[1][i] = c * u[i] - sn * w[i];
            vec[2][i] = sn * u[i] + c * w[i];
        }
    }
    sorted_out(val, (const double(*)[3])vec, ret_values, ret_vectors);
}

int geo_plane_fit(const double *pts, const double *w, size_t n,
                  const double orient[3], double ret[4])
{
    if (n < 3)
        return -EINVAL;
    double wsum = 0, c[3] = {0, 0, 0};
    for (size_t i = 0; i < n; i++) {
        double wi = w ? w[i] : 1.0;
        wsum += wi;
        geo_vmadd(c, wi, pts + 3 * i, c);
    }
    if (!(wsum > 0))
        return -EINVAL;
    geo_vscale(c, 1.0 / wsum, c);

    double cov[3][3] = {{0}};
    for (size_t i = 0; i < n; i++) {
        double wi = w ? w[i] : 1.0, d[3];
        geo_vsub(pts + 3 * i, c, d);
        for (int r = 0; r < 3; r++)
            for (int s = r; s < 3; s++)
                cov[r][s] += wi * d[r] * d[s];
    }
    double values[3], vectors[3][3];
    geo_sym3_eigen_jacobi((const double(*)[3])cov, values, vectors);
    /* collinear (or coincident) points: two vanishing eigenvalues */
    if (!(values[1] > 1e-24 * (values[2] > 0 ? values[2] : 1.0)) ||
        !(values[2] > 0))
        return -EINVAL;
    double nrm[3] = {vectors[0][0], vectors[0][1], vectors[0][2]};
    if (orient && geo_vdot(nrm, orient) < 0)
        geo_vscale(nrm, -1.0, nrm);
    ret[0] = nrm[0];
    ret[1] = nrm[1];
    ret[2] = nrm[2];
    ret[3] = -geo_vdot(nrm, c);
    return 0;
}

int geo_plane_from_point_normal(const double p[3], const double n[3],
                                double ret[4])
{
    double u[3] = {n[0], n[1], n[2]};
    if (!(geo_vnormalize(u) > 0))
        return -EINVAL;
    ret[0] = u[0];
    ret[1] = u[1];
    ret[2] = u[2];
    ret[3] = -geo_vdot(u, p);
    return 0;
}

bool geo_plane_intersect3(const double p1[4], const double p2[4],
                          const double p3[4], double ret[3])
{
    double n23[3], n31[3], n12[3];
    geo_vcross(p2, p3, n23);
    geo_vcross(p3, p1, n31);
    geo_vcross(p1, p2, n12);
    double det = geo_vdot(p1, n23);
    double scale = geo_vlen(p1) * geo_vlen(p2) * geo_vlen(p3);
    if (!(fabs(det) > 1e-12 * scale))
        return false;
    for (int k = 0; k < 3; k++)
        ret[k] = -(p1[3] * n23[k] + p2[3] * n31[k] + p3[3] * n12[k]) / det;
    return true;
}

int geo_plane_triples_set(geo_plane_triples *t, const double (*pl)[4],
                          uint32_t k)
{
    if (k > t->cap) {
        free(t->len), free(t->cr);
        t->len = malloc((size_t)k * sizeof *t->len);
        t->cr = malloc((size_t)k * k * sizeof *t->cr);
        t->cap = t->len && t->cr ? k : 0;
        if (!t->cap) {
            free(t->len), free(t->cr);
            t->len = NULL, t->cr = NULL, t->k = 0;
            return -ENOMEM;
        }
    }
    t->pl = pl;
    t->k = k;
    for (uint32_t a = 0; a < k; a++) {
        t->len[a] = geo_vlen(pl[a]);
        for (uint32_t b = a + 1; b < k; b++)
            geo_vcross(pl[a], pl[b], t->cr[(size_t)a * k + b]);
    }
    return 0;
}

bool geo_plane_triples_meet(const geo_plane_triples *t, uint32_t a,
                            uint32_t b, uint32_t c, double ret[3])
{
    /* geo_plane_intersect3(p1, p2, p3) with p1, p2, p3 = a, b, c */
    const double *p1 = t->pl[a], *p2 = t->pl[b], *p3 = t->pl[c];
    const double *n23 = t->cr[(size_t)b * t->k + c];
    const double *n12 = t->cr[(size_t)a * t->k + b];
    const double *n13 = t->cr[(size_t)a * t->k + c];
    double n31[3] = {-n13[0], -n13[1], -n13[2]};
    double det = geo_vdot(p1, n23);
    double scale = t->len[a] * t->len[b] * t->len[c];
    if (!(fabs(det) > 1e-12 * scale))
        return false;
    for (int k = 0; k < 3; k++)
        ret[k] = -(p1[3] * n23[k] + p2[3] * n31[k] + p3[3] * n12[k]) / det;
    return true;
}

void geo_plane_triples_free(geo_plane_triples *t)
{
    free(t->len), free(t->cr);
    memset(t, 0, sizeof *t);
}

bool geo_spd3_solve(double m[3][3], const double b[3], double x[3])
{
    double l[3][3] = {{0}};
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j <= i; j++) {
            double s = i <= j ? m[i][j] : m[j][i];
            for (int k = 0; k < j; k++)
                s -= l[i][k] * l[j][k];
            if (i == j) {
                if (!(s > 0))
                    return false;
                l[i][i] = sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    double y[3];
    for (int i = 0; i < 3; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++)
            s -= l[i][k] * y[k];
        y[i] = s / l[i][i];
    }
    for (int i = 2; i >= 0; i--) {
        double s = y[i];
        for (int k = i + 1; k < 3; k++)
            s -= l[k][i] * x[k];
        x[i] = s / l[i][i];
    }
    return true;
}

void geo_fan_moments(const double (*verts)[3], const uint32_t *fv, uint32_t n,
                     const double o[3], double *a, double s[3],
                     double ss[3][3])
{
    double p0[3];
    geo_vsub(verts[fv[0]], o, p0);
    for (uint32_t i = 1; i + 1 < n; i++) {
        double p1[3], p2[3], u[3], v[3], c[3], m[3];
        geo_vsub(verts[fv[i]], o, p1);
        geo_vsub(verts[fv[i + 1]], o, p2);
        geo_vsub(p1, p0, u);
        geo_vsub(p2, p0, v);
        geo_vcross(u, v, c);
        double ar = 0.5 * geo_vlen(c);
        for (int k = 0; k < 3; k++)
            m[k] = (p0[k] + p1[k] + p2[k]) / 3;
        *a += ar;
        /* ∫ x xᵀ over a triangle = A/12 (Σ pᵢ pᵢᵀ + 9 m mᵀ) */
        for (int k = 0; k < 3; k++) {
            s[k] += ar * m[k];
            for (int l = k; l < 3; l++)
                ss[k][l] += ar / 12 * (p0[k] * p0[l] + p1[k] * p1[l] +
                                       p2[k] * p2[l] + 9 * m[k] * m[l]);
        }
    }
}
