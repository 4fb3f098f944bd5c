/* predicates.c — filtered exact orientation predicates.
 *
 * Fast path: the determinant in doubles and Shewchuk's error bound on it
 * (J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast
 * Robust Geometric Predicates", 1997, bounds errboundA). If |det| exceeds
 * the bound its sign is the exact sign. Otherwise the determinant is
 * rebuilt exactly as a nonoverlapping expansion: every difference of inputs
 * is a two-term expansion (Two_Diff), products are formed with
 * Scale-Expansion, sums with Grow-Expansion, and the sign of an expansion
 * is the sign of its largest (last) component. */
#include "predicates.h"

#include <math.h>

#define EPS 0x1.0p-53 /* half an ulp of 1: the unit roundoff */
#define O3D_BOUND ((7.0 + 56.0 * EPS) * EPS)
/* a·x+b·y+c·z+d: three products and three sums, γ4 with slack */
#define PLANE_BOUND ((5.0 + 64.0 * EPS) * EPS)
/* Below this magnitude products may underflow and the bounds stop holding:
 * always take the exact path there. */
#define TINY 0x1.0p-900

/* Splits a into hi + lo with 26 significant bits each (Dekker). */
static inline void split(double a, double *hi, double *lo)
{
    const double splitter = 134217729.0; /* 2^27 + 1 */
    double c = splitter * a;
    double abig = c - a;
    *hi = c - abig;
    *lo = a - *hi;
}

static inline void two_product(double a, double b, double *x, double *y)
{
    double ahi, alo, bhi, blo;
    *x = a * b;
    split(a, &ahi, &alo);
    split(b, &bhi, &blo);
    double err1 = *x - ahi * bhi;
    double err2 = err1 - alo * bhi;
    double err3 = err2 - ahi * blo;
    *y = alo * blo - err3;
}

static inline void two_sum(double a, double b, double *x, double *y)
{
    *x = a + b;
    double bv = *x - a;
    double av = *x - bv;
    *y = (a - av) + (b - bv);
}

static inline void fast_two_sum(double a, double b, double *x, double *y)
{
    *x = a + b;
    *y = b - (*x - a);
}

static inline void two_diff(double a, double b, double *x, double *y)
{
    *x = a - b;
    double bv = a - *x;
    double av = *x + bv;
    *y = (a - av) + (bv - b);
}

/* h = e + b; e has elen components in increasing magnitude; h has room
 * for elen + 1. Returns h's length (zero components dropped, at least 1). */
static int grow_expansion(int elen, const double *e, double b, double *h)
{
    double q = b;
    int hn = 0;
    for (int i = 0; i < elen; i++) {
        double qnew, hh;
        two_sum(q, e[i], &qnew, &hh);
        q = qnew;
        if (hh != 0.0)
            h[hn++] = hh;
    }
    if (q != 0.0 || hn == 0)
        h[hn++] = q;
    return hn;
}

/* h = e + f, via one grow per component of f; h has room for elen+flen.
 * tmp has room for elen+flen too. */
static int expansion_sum(int elen, const double *e, int flen, const double *f,
                         double *h, double *tmp)
{
    int n = elen;
    for (int i = 0; i < elen; i++)
        h[i] = e[i];
    for (int j = 0; j < flen; j++) {
        n = grow_expansion(n, h, f[j], tmp);
        for (int i = 0; i < n; i++)
            h[i] = tmp[i];
    }
    return n;
}

/* h = e · b; h has room for 2·elen. */
static int scale_expansion(int elen, const double *e, double b, double *h)
{
    double q, hh, p1, p0, sum;
    int hn = 0;
    two_product(e[0], b, &q, &hh);
    if (hh != 0.0)
        h[hn++] = hh;
    for (int i = 1; i < elen; i++) {
        two_product(e[i], b, &p1, &p0);
        two_sum(q, p0, &sum, &hh);
        if (hh != 0.0)
            h[hn++] = hh;
        fast_two_sum(p1, sum, &q, &hh);
        if (hh != 0.0)
            h[hn++] = hh;
    }
    if (q != 0.0 || hn == 0)
        h[hn++] = q;
    return hn;
}

/* h = e · f; h has room for 2·elen·flen. */
static int expansion_product(int elen, const double *e, int flen,
                             const double *f, double *h)
{
    double part[64], acc[256], tmp[256];
    int n = 0;
    for (int j = 0; j < flen; j++) {
        int pn = scale_expansion(elen, e, f[j], part);
        if (n == 0) {
            for (int i = 0; i < pn; i++)
                acc[i] = part[i];
            n = pn;
        } else {
            n = expansion_sum(n, acc, pn, part, acc, tmp);
        }
    }
    for (int i = 0; i < n; i++)
        h[i] = acc[i];
    return n;
}

static int expansion_sign(int n, const double *e)
{
    double top = e[n - 1];
    return (top > 0.0) - (top < 0.0);
}

static int negate(int n, double *e)
{
    for (int i = 0; i < n; i++)
        e[i] = -e[i];
    return n;
}

/* Exact a·b − c·d for two-term expansions; h has room for 16. */
static int minor2(const double a[2], const double b[2], const double c[2],
                  const double d[2], double *h)
{
    double ab[8], cd[8], tmp[16];
    int abn = expansion_product(2, a, 2, b, ab);
    int cdn = expansion_product(2, c, 2, d, cd);
    negate(cdn, cd);
    return expansion_sum(abn, ab, cdn, cd, h, tmp);
}

static int sign_of(double v)
{
    return (v > 0.0) - (v < 0.0);
}

static int orient2d_exact(const double a[2], const double b[2],
                          const double c[2])
{
    double acx[2], acy[2], bcx[2], bcy[2], det[16];
    two_diff(a[0], c[0], &acx[1], &acx[0]);
    two_diff(a[1], c[1], &acy[1], &acy[0]);
    two_diff(b[0], c[0], &bcx[1], &bcx[0]);
    two_diff(b[1], c[1], &bcy[1], &bcy[0]);
    int n = minor2(acx, bcy, acy, bcx, det);
    return expansion_sign(n, det);
}

int geo_orient2d_exact(const double a[2], const double b[2],
                       const double c[2])
{
    return orient2d_exact(a, b, c);
}

int geo_orient2d_proj_exact(const double a[3], const double b[3],
                            const double c[3], int drop)
{
    int u = (drop + 1) % 3, v = (drop + 2) % 3;
    double pa[2] = {a[u], a[v]}, pb[2] = {b[u], b[v]}, pc[2] = {c[u], c[v]};
    return orient2d_exact(pa, pb, pc);
}

/* Shewchuk's orient3d(a,b,c,d) = det[a−d; b−d; c−d], positive when d is
 * below; ours is its negation (positive when d is on the normal's side). */
static int orient3d_exact(const double a[3], const double b[3],
                          const double c[3], const double d[3])
{
    double ad[3][2], bd[3][2], cd[3][2];
    for (int k = 0; k < 3; k++) {
        two_diff(a[k], d[k], &ad[k][1], &ad[k][0]);
        two_diff(b[k], d[k], &bd[k][1], &bd[k][0]);
        two_diff(c[k], d[k], &cd[k][1], &cd[k][0]);
    }
    double m1[16], m2[16], m3[16];
    int n1 = minor2(bd[1], cd[2], bd[2], cd[1], m1); /* bdy·cdz − bdz·cdy */
    int n2 = minor2(cd[1], ad[2], cd[2], ad[1], m2); /* cdy·adz − cdz·ady */
    int n3 = minor2(ad[1], bd[2], ad[2], bd[1], m3); /* ady·bdz − adz·bdy */
    double t1[64], t2[64], t3[64], s[128], det[192], tmp[192];
    int k1 = expansion_product(n1, m1, 2, ad[0], t1);
    int k2 = expansion_product(n2, m2, 2, bd[0], t2);
    int k3 = expansion_product(n3, m3, 2, cd[0], t3);
    int sn = expansion_sum(k1, t1, k2, t2, s, tmp);
    int dn = expansion_sum(sn, s, k3, t3, det, tmp);
    return -expansion_sign(dn, det);
}

int geo_orient3d(const double a[3], const double b[3], const double c[3],
                 const double d[3])
{
    double adx = a[0] - d[0], ady = a[1] - d[1], adz = a[2] - d[2];
    double bdx = b[0] - d[0], bdy = b[1] - d[1], bdz = b[2] - d[2];
    double cdx = c[0] - d[0], cdy = c[1] - d[1], cdz = c[2] - d[2];

    double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
    double cdxady = cdx * ady, adxcdy = adx * cdy;
    double adxbdy = adx * bdy, bdxady = bdx * ady;

    double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) +
                 cdz * (adxbdy - bdxady);
    double permanent = (fabs(bdxcdy) + fabs(cdxbdy)) * fabs(adz) +
                       (fabs(cdxady) + fabs(adxcdy)) * fabs(bdz) +
                       (fabs(adxbdy) + fabs(bdxady)) * fabs(cdz);
    if (fabs(det) > O3D_BOUND * permanent && fabs(det) > TINY)
        return -sign_of(det);
    return orient3d_exact(a, b, c, d);
}

/* plane(p) exactly as an expansion; acc has room for 8. */
static int plane_value_exact(const double plane[4], const double p[3],
                             double *acc)
{
    double tmp[8], prod[2];
    int n = 1;
    acc[0] = plane[3];
    for (int k = 0; k < 3; k++) {
        two_product(plane[k], p[k], &prod[1], &prod[0]);
        n = expansion_sum(n, acc, 2, prod, acc, tmp);
    }
    return n;
}

static int plane_sign_exact(const double plane[4], const double p[3])
{
    double acc[8];
    int n = plane_value_exact(plane, p, acc);
    return expansion_sign(n, acc);
}

int geo_plane_sign(const double plane[4], const double p[3])
{
    double t0 = plane[0] * p[0], t1 = plane[1] * p[1], t2 = plane[2] * p[2];
    double v = ((t0 + t1) + t2) + plane[3];
    double mag = fabs(t0) + fabs(t1) + fabs(t2) + fabs(plane[3]);
    if (fabs(v) > PLANE_BOUND * mag && fabs(v) > TINY)
        return sign_of(v);
    return plane_sign_exact(plane, p);
}

/* Coordinate k of a crossing point as the exact fraction num/den: a point
 * on the plane is x0[k]/1; the crossing of x0x1 is
 * (s0·x1[k] − s1·x0[k]) / (s0 − s1) with s = plane(·) exact.
 * num has room for 28, den for 14. */
static void crossing_fraction(const double plane[4], const double x0[3],
                              const double x1[3], int k, double *num,
                              int *nnum, double *den, int *nden)
{
    if (!x1) {
        num[0] = x0[k];
        den[0] = 1.0;
        *nnum = *nden = 1;
        return;
    }
    double s0[8], s1[8], a[16], b[16], tmp[32];
    int n0 = plane_value_exact(plane, x0, s0);
    int n1 = plane_value_exact(plane, x1, s1);
    int an = scale_expansion(n0, s0, x1[k], a);
    int bn = scale_expansion(n1, s1, -x0[k], b);
    *nnum = expansion_sum(an, a, bn, b, num, tmp);
    negate(n1, s1);
    *nden = expansion_sum(n0, s0, n1, s1, den, tmp);
}

/* h = e · f for expansions longer than expansion_product's buffers allow:
 * h and tmp have room for 2·elen·flen, part for 2·elen. */
static int long_product(int elen, const double *e, int flen, const double *f,
                        double *h, double *tmp, double *part)
{
    int n = 0;
    for (int j = 0; j < flen; j++) {
        int pn = scale_expansion(elen, e, f[j], part);
        if (n == 0) {
            for (int i = 0; i < pn; i++)
                h[i] = part[i];
            n = pn;
        } else {
            n = expansion_sum(n, h, pn, part, h, tmp);
        }
    }
    return n;
}

static int crossing_cmp_exact(const double plane[4], const double x0[3],
                              const double x1[3], const double y0[3],
                              const double y1[3], int k)
{
    double nx[28], dx[14], ny[28], dy[14];
    int nnx, ndx, nny, ndy;
    crossing_fraction(plane, x0, x1, k, nx, &nnx, dx, &ndx);
    crossing_fraction(plane, y0, y1, k, ny, &nny, dy, &ndy);
    /* X − Y = (nx·dy − ny·dx) / (dx·dy) */
    double p1[2 * 28 * 14], p2[2 * 28 * 14], tmp[4 * 28 * 14], part[56];
    double diff[4 * 28 * 14];
    int n1 = long_product(nnx, nx, ndy, dy, p1, tmp, part);
    int n2 = long_product(nny, ny, ndx, dx, p2, tmp, part);
    negate(n2, p2);
    int nd = expansion_sum(n1, p1, n2, p2, diff, tmp);
    return expansion_sign(nd, diff) * expansion_sign(ndx, dx) *
           expansion_sign(ndy, dy);
}

/* Floating-point coordinate k of a crossing with a bound on its error;
 * false when no useful bound is available. */
static int crossing_approx(const double plane[4], const double x0[3],
                           const double x1[3], int k, double *ret_val,
                           double *ret_err)
{
    if (!x1) {
        *ret_val = x0[k];
        *ret_err = 0.0;
        return 1;
    }
    const double *pt[2] = {x0, x1};
    double a[2], bnd[2];
    for (int i = 0; i < 2; i++) {
        double t0 = plane[0] * pt[i][0], t1 = plane[1] * pt[i][1];
        double t2 = plane[2] * pt[i][2];
        double v = ((t0 + t1) + t2) + plane[3];
        double mag = fabs(t0) + fabs(t1) + fabs(t2) + fabs(plane[3]);
        /* |fl(v)| is within the bound of |v| whatever the signs */
        a[i] = fabs(v);
        bnd[i] = PLANE_BOUND * mag;
    }
    double den = a[0] + a[1] - bnd[0] - bnd[1];
    if (!(den > TINY))
        return 0;
    double t = a[0] / (a[0] + a[1]);
    double dt = (bnd[0] + bnd[1]) / den + 8.0 * EPS;
    double d = x1[k] - x0[k];
    double val = x0[k] + t * d;
    *ret_val = val;
    *ret_err = dt * fabs(d) * (1.0 + 8.0 * EPS) +
               4.0 * EPS * (fabs(val) + fabs(x0[k]));
    return 1;
}

int geo_plane_crossing_cmp(const double plane[4], const double x0[3],
                           const double x1[3], const double y0[3],
                           const double y1[3], int k)
{
    double vx, ex, vy, ey;
    if (crossing_approx(plane, x0, x1, k, &vx, &ex) &&
        crossing_approx(plane, y0, y1, k, &vy, &ey)) {
        double diff = vx - vy;
        double bound = (ex + ey) * (1.0 + 8.0 * EPS);
        if (!x1 && !y1)
            return sign_of(diff);
        if (fabs(diff) > bound && fabs(diff) > TINY)
            return sign_of(diff);
    }
    return crossing_cmp_exact(plane, x0, x1, y0, y1, k);
}

static int normal_sign_exact(const double p0[3], const double n[3],
                             const double p[3])
{
    double acc[16], tmp[16], diff[2], prod[4];
    int len = 1;
    acc[0] = 0.0;
    for (int k = 0; k < 3; k++) {
        two_diff(p[k], p0[k], &diff[1], &diff[0]);
        int pn = scale_expansion(2, diff, n[k], prod);
        len = expansion_sum(len, acc, pn, prod, acc, tmp);
    }
    return expansion_sign(len, acc);
}

int geo_normal_sign(const double p0[3], const double n[3], const double p[3])
{
    double t0 = n[0] * (p[0] - p0[0]), t1 = n[1] * (p[1] - p0[1]),
           t2 = n[2] * (p[2] - p0[2]);
    double v = (t0 + t1) + t2;
    /* each term carries a difference, a product and two sums: γ4 with
     * slack, as for the plane */
    double mag = fabs(t0) + fabs(t1) + fabs(t2);
    if (fabs(v) > PLANE_BOUND * mag && fabs(v) > TINY)
        return sign_of(v);
    return normal_sign_exact(p0, n, p);
}

/* Exact a·b − c·d of doubles; h has room for 4. */
static int minor2_double(double a, double b, double c, double d, double *h)
{
    double ab[2], cd[2], tmp[4];
    two_product(a, b, &ab[1], &ab[0]);
    two_product(c, d, &cd[1], &cd[0]);
    cd[0] = -cd[0], cd[1] = -cd[1];
    return expansion_sum(2, ab, 2, cd, h, tmp);
}

/* The 4 × 4 determinant of the rows r[0..3] exactly, by Laplace expansion
 * along the first two rows: Σ ± m(r0,r1; i,j) · m(r2,r3; k,l). */
static int det4_exact(const double *const r[4])
{
    static const int pair[6][2] = {{0, 1}, {0, 2}, {0, 3},
                                   {1, 2}, {1, 3}, {2, 3}};
    static const int sgn[6] = {1, -1, 1, 1, -1, 1};
    double acc[6 * 32], tmp[6 * 32], prod[32];
    int n = 0;
    for (int t = 0; t < 6; t++) {
        int i = pair[t][0], j = pair[t][1];
        int k = pair[5 - t][0], l = pair[5 - t][1];
        double m[4], w[4];
        int mn = minor2_double(r[0][i], r[1][j], r[0][j], r[1][i], m);
        int wn = minor2_double(r[2][k], r[3][l], r[2][l], r[3][k], w);
        int pn = expansion_product(mn, m, wn, w, prod);
        if (sgn[t] < 0)
            negate(pn, prod);
        if (n == 0) {
            for (int q = 0; q < pn; q++)
                acc[q] = prod[q];
            n = pn;
        } else {
            n = expansion_sum(n, acc, pn, prod, acc, tmp);
        }
    }
    return expansion_sign(n, acc);
}

/* Sign of the 4 × 4 determinant of the rows, filtered: each of its 24
 * monomials passes at most 8 roundings (two products, a difference, the
 * product of the minors, four sums), the permanent as many, so 12u·P̂
 * bounds the error with slack. */
static int det4_sign(const double *const r[4])
{
    static const int pair[6][2] = {{0, 1}, {0, 2}, {0, 3},
                                   {1, 2}, {1, 3}, {2, 3}};
    static const int sgn[6] = {1, -1, 1, 1, -1, 1};
    double det = 0.0, perm = 0.0;
    for (int t = 0; t < 6; t++) {
        int i = pair[t][0], j = pair[t][1];
        int k = pair[5 - t][0], l = pair[5 - t][1];
        double a = r[0][i] * r[1][j], b = r[0][j] * r[1][i];
        double c = r[2][k] * r[3][l], d = r[2][l] * r[3][k];
        double term = (a - b) * (c - d);
        det += sgn[t] > 0 ? term : -term;
        perm += (fabs(a) + fabs(b)) * (fabs(c) + fabs(d));
    }
    if (fabs(det) > 12.0 * EPS * perm && fabs(det) > TINY)
        return sign_of(det);
    return det4_exact(r);
}

int geo_plane_meet_sign(const double a[4], const double b[4],
                        const double c[4], const double q[4])
{
    static const double zero[3] = {0.0, 0.0, 0.0};
    /* geo_orient3d(0, a, b, c) = c · (a × b) = det[a; b; c] of the normals */
    int s3 = geo_orient3d(zero, a, b, c);
    if (s3 == 0)
        return 0;
    const double *rows[4] = {a, b, c, q};
    return s3 * det4_sign(rows);
}

/* The 3 × 3 determinant of rows a, b, c on columns p, q, r, and its
 * permanent (the sum of its monomials' magnitudes). */
static double det3_cols(const double *a, const double *b, const double *c,
                        int p, int q, int r, double *per)
{
    double m0 = b[q] * c[r] - b[r] * c[q];
    double m1 = b[p] * c[r] - b[r] * c[p];
    double m2 = b[p] * c[q] - b[q] * c[p];
    *per = fabs(a[p]) * (fabs(b[q] * c[r]) + fabs(b[r] * c[q])) +
           fabs(a[q]) * (fabs(b[p] * c[r]) + fabs(b[r] * c[p])) +
           fabs(a[r]) * (fabs(b[p] * c[q]) + fabs(b[q] * c[p]));
    return a[p] * m0 - a[q] * m1 + a[r] * m2;
}

void geo_meet_prepare(const double a[4], const double b[4],
                      const double c[4], geo_meet *m)
{
    static const double zero[3] = {0.0, 0.0, 0.0};
    m->a = a, m->b = b, m->c = c;
    m->s3 = geo_orient3d(zero, a, b, c);
    /* expansion along the last row: det = Σ q[j] (−1)^(3+j) M_j, M_j
     * the minor of a, b, c without column j */
    m->cof[0] = -det3_cols(a, b, c, 1, 2, 3, &m->per[0]);
    m->cof[1] = det3_cols(a, b, c, 0, 2, 3, &m->per[1]);
    m->cof[2] = -det3_cols(a, b, c, 0, 1, 3, &m->per[2]);
    m->cof[3] = det3_cols(a, b, c, 0, 1, 2, &m->per[3]);
}

int geo_meet_side(const geo_meet *m, const double q[4])
{
    if (m->s3 == 0)
        return 0;
    /* each cofactor is off by at most 6u of its permanent (five
     * roundings a monomial), the sum of the four products by 5u of the
     * terms, which the permanents bound: 16u of Σ |q_j| · per_j covers
     * both and the rounding of the bound itself */
    double det = q[0] * m->cof[0] + q[1] * m->cof[1] + q[2] * m->cof[2] +
                 q[3] * m->cof[3];
    double bound = fabs(q[0]) * m->per[0] + fabs(q[1]) * m->per[1] +
                   fabs(q[2]) * m->per[2] + fabs(q[3]) * m->per[3];
    if (fabs(det) > 16.0 * EPS * bound && fabs(det) > TINY)
        return m->s3 * sign_of(det);
    return geo_plane_meet_sign(m->a, m->b, m->c, q);
}
