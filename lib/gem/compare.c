/* compare.c — aligning two models of a stone and measuring them
 * (compare.h).
 *
 * Normals are looked up in a uniform grid over [-1, 1]³ whose cell is
 * twice the chord of 2°, so every normal within 2° of a query lies in
 * the 2×2×2 cells nearest it. Rotations are found from normals alone (the facet
 * normals weighted by area determine a convex stone up to translation),
 * the translation afterwards from the plane offsets. */
#include "compare.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "polygon_triangulate.h"
#include "surface.h"
#include "vec.h"

#define DEG (M_PI / 180.0)

enum {
    NI = 90,          /* inclination bins of 2° */
    NZ = 720,         /* azimuth bins of 0.5° */
    SUB_MAX = 256,    /* largest facets used while choosing the rotation */
    MAX_PEAKS = 16,   /* turns refined per axis pair */
    MAX_TURNS = 6 * MAX_PEAKS, /* per comparison: 2 + 2 × 2 axis pairs */
    STANDOUT_TRIES = 64, /* largest facets whose groups are measured */
    MEAN_SAMPLES = 2000, /* per surface, for the mean distance */
};

/* ---- small linear algebra ---- */

static void mat_mul(double a[3][3], double b[3][3],
                    double r[3][3])
{
    double t[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            t[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] +
                      a[i][2] * b[2][j];
    memcpy(r, t, sizeof t);
}

static void mat_vec(double m[3][3], const double v[3], double r[3])
{
    double t[3];
    for (int i = 0; i < 3; i++)
        t[i] = m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2];
    memcpy(r, t, sizeof t);
}

static void mat_tvec(double m[3][3], const double v[3], double r[3])
{
    double t[3];
    for (int i = 0; i < 3; i++)
        t[i] = m[0][i] * v[0] + m[1][i] * v[1] + m[2][i] * v[2];
    memcpy(r, t, sizeof t);
}

static void mat_identity(double m[3][3])
{
    memset(m, 0, 9 * sizeof(double));
    m[0][0] = m[1][1] = m[2][2] = 1;
}

/* Rotation by angle about unit axis k (Rodrigues). */
static void mat_axis_angle(const double k[3], double angle, double r[3][3])
{
    double s = sin(angle), c = cos(angle), v = 1 - c;
    r[0][0] = c + k[0] * k[0] * v;
    r[0][1] = k[0] * k[1] * v - k[2] * s;
    r[0][2] = k[0] * k[2] * v + k[1] * s;
    r[1][0] = k[1] * k[0] * v + k[2] * s;
    r[1][1] = c + k[1] * k[1] * v;
    r[1][2] = k[1] * k[2] * v - k[0] * s;
    r[2][0] = k[2] * k[0] * v - k[1] * s;
    r[2][1] = k[2] * k[1] * v + k[0] * s;
    r[2][2] = c + k[2] * k[2] * v;
}

/* A unit vector perpendicular to unit a. */
static void perpendicular(const double a[3], double r[3])
{
    double e[3] = {0, 0, 0};
    int k = fabs(a[0]) < fabs(a[1]) ? (fabs(a[0]) < fabs(a[2]) ? 0 : 2)
                                    : (fabs(a[1]) < fabs(a[2]) ? 1 : 2);
    e[k] = 1;
    geo_vcross(a, e, r);
    geo_vnormalize(r);
}

/* The smallest rotation taking unit b onto unit a. */
static void mat_onto(const double b[3], const double a[3], double r[3][3])
{
    double k[3];
    geo_vcross(b, a, k);
    double s = geo_vlen(k), c = geo_vdot(a, b);
    if (s < 1e-300) {
        if (c > 0) {
            mat_identity(r);
            return;
        }
        perpendicular(b, k);
        mat_axis_angle(k, M_PI, r);
        return;
    }
    geo_vscale(k, 1 / s, k);
    mat_axis_angle(k, atan2(s, c), r);
}

/* Angle of rotation r (accurate near 0 and π) and its unit axis (def
 * when the angle is 0). */
static double mat_angle(double r[3][3], const double def[3],
                        double axis[3])
{
    double v[3] = {(r[2][1] - r[1][2]) / 2, (r[0][2] - r[2][0]) / 2,
                   (r[1][0] - r[0][1]) / 2};
    double s = geo_vlen(v), c = (r[0][0] + r[1][1] + r[2][2] - 1) / 2;
    double angle = atan2(s, c);
    if (s > 1e-9) {
        geo_vscale(v, 1 / s, axis);
    } else if (c > 0) {
        memcpy(axis, def, 3 * sizeof(double));
    } else { /* a half turn: the axis is the longest column of R + I */
        double len = -1;
        for (int j = 0; j < 3; j++) {
            double col[3] = {r[0][j], r[1][j], r[2][j]};
            col[j] += 1;
            if (geo_vlen(col) > len) {
                len = geo_vlen(col);
                memcpy(axis, col, sizeof col);
            }
        }
        geo_vnormalize(axis);
    }
    return angle;
}

/* Eigen-decomposition of a symmetric n×n matrix (n ≤ 4) by cyclic
 * Jacobi rotations: a is destroyed, its diagonal left as the
 * eigenvalues; column k of v is the eigenvector of a[k][k]. */
static void jacobi(int n, double a[4][4], double v[4][4])
{
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            v[i][j] = i == j;
    for (int sweep = 0; sweep < 60; sweep++) {
        double off = 0, diag = 0;
        for (int i = 0; i < n; i++) {
            diag += fabs(a[i][i]);
            for (int j = i + 1; j < n; j++)
                off += fabs(a[i][j]);
        }
        if (!(off > 1e-300) || off < 1e-18 * diag)
            return;
        for (int p = 0; p < n; p++)
            for (int q = p + 1; q < n; q++) {
                if (a[p][q] == 0)
                    continue;
                double th = (a[q][q] - a[p][p]) / (2 * a[p][q]);
                double t = (th >= 0 ? 1 : -1) /
                           (fabs(th) + sqrt(th * th + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < n; k++) {
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < n; k++) {
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < n; k++) {
                    double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq;
                    v[k][q] = s * vkp + c * vkq;
                }
            }
    }
}

/* The rotation R maximising Σ w (R b)·a from S = Σ w b aᵀ (Horn 1987,
 * closed form with unit quaternions). */
static void horn(double S[3][3], double r[3][3])
{
    double sxx = S[0][0], sxy = S[0][1], sxz = S[0][2], syx = S[1][0],
           syy = S[1][1], syz = S[1][2], szx = S[2][0], szy = S[2][1],
           szz = S[2][2];
    double n[4][4] = {
        {sxx + syy + szz, syz - szy, szx - sxz, sxy - syx},
        {syz - szy, sxx - syy - szz, sxy + syx, szx + sxz},
        {szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy},
        {sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz},
    };
    double v[4][4];
    jacobi(4, n, v);
    int k = 0;
    for (int i = 1; i < 4; i++)
        if (n[i][i] > n[k][k])
            k = i;
    double w = v[0][k], x = v[1][k], y = v[2][k], z = v[3][k];
    double l = sqrt(w * w + x * x + y * y + z * z);
    w /= l, x /= l, y /= l, z /= l;
    r[0][0] = 1 - 2 * (y * y + z * z);
    r[0][1] = 2 * (x * y - w * z);
    r[0][2] = 2 * (x * z + w * y);
    r[1][0] = 2 * (x * y + w * z);
    r[1][1] = 1 - 2 * (x * x + z * z);
    r[1][2] = 2 * (y * z - w * x);
    r[2][0] = 2 * (x * z - w * y);
    r[2][1] = 2 * (y * z + w * x);
    r[2][2] = 1 - 2 * (x * x + y * y);
}

/* ---- a model's facets, normals and their grid ---- */

typedef struct model {
    const geo_poly *p;
    const char *name;
    uint32_t n;          /* facets with an area and a normal */
    uint32_t *fac;       /* their indices in p */
    double (*nrm)[3];
    double *area;
    double total;
    uint32_t *order;     /* positions by area, largest first */
    uint32_t nsub;       /* the first nsub of order */
    int res;             /* grid cells per side */
    double h;            /* cell side */
    uint32_t *start;     /* res³ + 1 offsets into cell */
    uint32_t *cell;      /* positions, grouped by cell */
    double centroid[3];  /* volume centroid (area centroid if flat) */
    double volume;
} model;

static void model_free(model *m)
{
    free(m->fac);
    free(m->nrm);
    free(m->area);
    free(m->order);
    free(m->start);
    free(m->cell);
    memset(m, 0, sizeof *m);
}

static int cell_coord(const model *m, double x)
{
    int c = (int)floor((x + 1) / m->h);
    return c < 0 ? 0 : c >= m->res ? m->res - 1 : c;
}

static uint32_t cell_of(const model *m, const double v[3])
{
    return ((uint32_t)cell_coord(m, v[0]) * (uint32_t)m->res +
            (uint32_t)cell_coord(m, v[1])) * (uint32_t)m->res +
           (uint32_t)cell_coord(m, v[2]);
}

/* The lower of the two cells along an axis nearest x. */
static int cell_low(const model *m, double x)
{
    int c = (int)floor((x + 1) / m->h - 0.5);
    return c < 0 ? 0 : c > m->res - 2 ? m->res - 2 : c;
}

/* Cell o (bits: +1 along x, y, z) of the 2×2×2 block at lo. */
static uint32_t cell_index(const model *m, const int lo[3], int o)
{
    uint32_t r = (uint32_t)m->res;
    return ((uint32_t)(lo[0] + (o & 1)) * r + (uint32_t)(lo[1] + (o >> 1 & 1))) *
               r + (uint32_t)(lo[2] + (o >> 2 & 1));
}

static int by_area_desc(const void *x, const void *y, void *keys)
{
    const double *k = keys;
    double a = k[*(const uint32_t *)x], b = k[*(const uint32_t *)y];
    if (a != b)
        return a > b ? -1 : 1;
    return (*(const uint32_t *)x > *(const uint32_t *)y) -
           (*(const uint32_t *)x < *(const uint32_t *)y);
}

/* Volume centroid: the signed tetrahedra of every facet's fan about the
 * first vertex; the area centroid of the facets when the volume is 0. */
static void centroid_of(model *m)
{
    const geo_poly *p = m->p;
    const double *o = p->verts[0];
    double c[3] = {0, 0, 0}, v6 = 0, ca[3] = {0, 0, 0}, at = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *ix = geo_poly_facet(p, f);
        const double *a = p->verts[ix[0]];
        for (uint32_t k = 1; k + 1 < n; k++) {
            const double *b = p->verts[ix[k]], *d = p->verts[ix[k + 1]];
            double ao[3], bo[3], dO[3], x[3];
            geo_vsub(a, o, ao);
            geo_vsub(b, o, bo);
            geo_vsub(d, o, dO);
            geo_vcross(bo, dO, x);
            double t = geo_vdot(ao, x);
            v6 += t;
            double ab[3], ad[3], y[3];
            geo_vsub(b, a, ab);
            geo_vsub(d, a, ad);
            geo_vcross(ab, ad, y);
            double tri = geo_vlen(y) / 2;
            at += tri;
            for (int q = 0; q < 3; q++) {
                c[q] += t * (o[q] + a[q] + b[q] + d[q]) / 4;
                ca[q] += tri * (a[q] + b[q] + d[q]) / 3;
            }
        }
    }
    m->volume = v6 / 6;
    double scale = geo_poly_size(p);
    if (fabs(v6) > 1e-12 * scale * scale * scale) {
        geo_vscale(c, 1 / v6, m->centroid);
    } else if (at > 0) {
        geo_vscale(ca, 1 / at, m->centroid);
    } else {
        memcpy(m->centroid, o, sizeof m->centroid);
    }
}

static int model_init(model *m, const geo_poly *p, const char *name,
                      geo_err *err)
{
    memset(m, 0, sizeof *m);
    m->p = p;
    m->name = name;
    if (p->nfacets == 0 || p->nverts < 4)
        return geo_err_set(err, -EINVAL, "%s: an empty model has nothing "
                           "to compare", name);
    m->fac = malloc((size_t)p->nfacets * sizeof *m->fac);
    m->nrm = malloc((size_t)p->nfacets * sizeof *m->nrm);
    m->area = malloc((size_t)p->nfacets * sizeof *m->area);
    m->order = malloc((size_t)p->nfacets * sizeof *m->order);
    m->h = 4 * sin(1 * DEG);
    m->res = (int)ceil(2 / m->h) + 2;
    size_t ncell = (size_t)m->res * m->res * m->res;
    m->start = calloc(ncell + 1, sizeof *m->start);
    m->cell = malloc((size_t)p->nfacets * sizeof *m->cell);
    if (!m->fac || !m->nrm || !m->area || !m->order || !m->start ||
        !m->cell) {
        model_free(m);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double a = geo_poly_facet_area(p, f);
        const double *q = p->planes[f];
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        if (!(a > 0) || !(len > 0.5) || !isfinite(len))
            continue; /* a degenerate facet: no direction */
        m->fac[m->n] = f;
        for (int k = 0; k < 3; k++)
            m->nrm[m->n][k] = q[k] / len;
        m->area[m->n] = a;
        m->total += a;
        m->order[m->n] = m->n;
        m->n++;
    }
    if (m->n < 4) {
        model_free(m);
        return geo_err_set(err, -EINVAL, "%s: fewer than 4 facets with an "
                           "area: nothing to compare", name);
    }
    qsort_r(m->order, m->n, sizeof *m->order, by_area_desc, m->area);
    m->nsub = m->n < SUB_MAX ? m->n : SUB_MAX;
    for (uint32_t i = 0; i < m->n; i++)
        m->start[cell_of(m, m->nrm[i]) + 1]++;
    for (size_t c = 0; c < ncell; c++)
        m->start[c + 1] += m->start[c];
    uint32_t *fill = malloc(ncell * sizeof *fill);
    if (!fill) {
        model_free(m);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    memcpy(fill, m->start, ncell * sizeof *fill);
    for (uint32_t i = 0; i < m->n; i++)
        m->cell[fill[cell_of(m, m->nrm[i])]++] = i;
    free(fill);
    centroid_of(m);
    return 0;
}

/* The 8 cells nearest v (2 per axis: its own and the neighbour on its
 * nearer side): with a cell twice the chord of 2°, they hold every
 * normal within 2° of v. i runs over the positions there. */
#define FOR_NEAR_CELLS(m, v, i)                                             \
    for (int o_ = 0, lo_[3] = {cell_low(m, (v)[0]), cell_low(m, (v)[1]),    \
                               cell_low(m, (v)[2])};                        \
         o_ < 8; o_++)                                                      \
        for (uint32_t c_ = cell_index(m, lo_, o_), k_ = (m)->start[c_];     \
             k_ < (m)->start[c_ + 1]; k_++)                                 \
            for (uint32_t i = (m)->cell[k_], once_ = 1; once_; once_ = 0)

/* The position of m's normal nearest to v with a cosine ≥ cos_tol
 * (tolerance ≤ 2°), or UINT32_MAX. */
static uint32_t nearest_normal(const model *m, const double v[3],
                               double cos_tol)
{
    uint32_t best = UINT32_MAX;
    double bd = cos_tol;
    FOR_NEAR_CELLS(m, v, i) {
        double d = geo_vdot(m->nrm[i], v);
        if (d >= bd) {
            bd = d;
            best = i;
        }
    }
    return best;
}

/* ---- main axis ---- */

/* Largest facet within 10° of unit g, or UINT32_MAX. */
static uint32_t table_near(const model *m, const double g[3])
{
    for (uint32_t k = 0; k < m->n; k++) {
        uint32_t i = m->order[k];
        if (geo_vdot(m->nrm[i], g) >= cos(10 * DEG))
            return i;
    }
    return UINT32_MAX;
}

/* The area of the facets within 1° of v, and their area-weighted mean
 * normal. */
static double group_area(const model *m, const double v[3], double mean[3])
{
    double s = 0, c1 = cos(1 * DEG);
    double acc[3] = {0, 0, 0};
    FOR_NEAR_CELLS(m, v, i) {
        if (geo_vdot(m->nrm[i], v) >= c1) {
            s += m->area[i];
            geo_vmadd(acc, m->area[i], m->nrm[i], acc);
        }
    }
    if (mean) {
        memcpy(mean, acc, sizeof acc);
        geo_vnormalize(mean);
    }
    return s;
}

/* The table that stands out: the largest facet's group (facets within
 * 1°) when it has 1.5 times the area of any other group among the
 * largest facets'. UINT32_MAX when none does. */
static uint32_t table_standout(const model *m, double axis[3])
{
    uint32_t tries = m->n < STANDOUT_TRIES ? m->n : STANDOUT_TRIES;
    uint32_t best = UINT32_MAX;
    double ba = 0, bmean[3] = {0, 0, 1};
    for (uint32_t k = 0; k < tries; k++) {
        uint32_t i = m->order[k];
        double mean[3], a = group_area(m, m->nrm[i], mean);
        if (a > ba) {
            ba = a;
            best = i;
            memcpy(bmean, mean, sizeof mean);
        }
    }
    double second = 0;
    for (uint32_t k = 0; k < tries; k++) {
        uint32_t i = m->order[k];
        if (geo_vdot(m->nrm[i], bmean) >= cos(2 * DEG))
            continue;
        second = fmax(second, group_area(m, m->nrm[i], NULL));
    }
    if (best == UINT32_MAX || ba < 1.5 * second)
        return UINT32_MAX;
    memcpy(axis, bmean, 3 * sizeof(double));
    return best;
}

typedef struct axis_cand {
    double axis[3];
    uint32_t table; /* facet of p, UINT32_MAX: the given axis */
} axis_cand;

/* The candidates for m's main axis, most likely first: the table that
 * stands out, then the table near the guess; with a given axis, the
 * table near it or the axis itself. 0 with *ncand ≥ 1, or -EINVAL. */
static int axis_cands(const model *m, const double *given, axis_cand c[2],
                      int *ncand, geo_err *err)
{
    *ncand = 0;
    double g[3] = {0, 0, 1};
    if (given) {
        double len = sqrt(geo_vdot(given, given));
        if (!(len > 0) || !isfinite(len))
            return geo_err_set(err, -EINVAL, "axis: not a direction");
        geo_vscale(given, 1 / len, g);
        uint32_t t = table_near(m, g);
        if (t != UINT32_MAX)
            memcpy(c[0].axis, m->nrm[t], sizeof c[0].axis);
        else
            memcpy(c[0].axis, g, sizeof g);
        c[0].table = t == UINT32_MAX ? UINT32_MAX : m->fac[t];
        *ncand = 1;
        return 0;
    }
    uint32_t s = table_standout(m, c[0].axis);
    if (s != UINT32_MAX)
        c[(*ncand)++].table = m->fac[s];
    uint32_t t = table_near(m, g);
    if (t != UINT32_MAX &&
        (s == UINT32_MAX || geo_vdot(m->nrm[t], c[0].axis) < cos(2 * DEG))) {
        memcpy(c[*ncand].axis, m->nrm[t], sizeof c[0].axis);
        c[(*ncand)++].table = m->fac[t];
    }
    if (*ncand == 0)
        return geo_err_set(err, -EINVAL, "%s: no table: no facet's normal "
                           "lies within 10 degrees of the axis (0, 0, 1) and "
                           "no group of parallel facets stands out as the "
                           "largest (a rough or a sphere?); give an axis",
                           m->name);
    return 0;
}

int geo_compare_axis(const geo_poly *p, const double *axis, const char *name,
                     double ret_axis[3], uint32_t *ret_table, geo_err *err)
{
    model m;
    int r = model_init(&m, p, name ? name : "model", err);
    if (r < 0)
        return r;
    axis_cand c[2];
    int nc;
    r = axis_cands(&m, axis, c, &nc, err);
    if (r == 0) {
        memcpy(ret_axis, c[0].axis, sizeof c[0].axis);
        *ret_table = c[0].table;
    }
    model_free(&m);
    return r;
}

/* ---- the rotation ---- */

/* Inclination and azimuth bins of unit v in the frame (ex, ey, a);
 * false near the poles, where the azimuth means nothing. */
static bool bins(const double v[3], const double ex[3], const double ey[3],
                 const double a[3], int *ii, int *iz)
{
    double x = geo_vdot(v, ex), y = geo_vdot(v, ey), z = geo_vdot(v, a);
    double inc = atan2(hypot(x, y), z);
    if (inc < 3 * DEG || inc > 177 * DEG)
        return false;
    double az = atan2(y, x);
    if (az < 0)
        az += 2 * M_PI;
    *ii = (int)(inc / (2 * DEG));
    if (*ii >= NI)
        *ii = NI - 1;
    *iz = (int)(az / (0.5 * DEG)) % NZ;
    return true;
}

/* A's area by (inclination, azimuth) about axis a, smoothed over ±1
 * inclination and ±2 azimuth bins. */
static void histogram(const model *A, const double a[3], const double ex[3],
                      const double ey[3], double *H)
{
    memset(H, 0, (size_t)NI * NZ * sizeof *H);
    for (uint32_t i = 0; i < A->n; i++) {
        int ii, iz;
        if (!bins(A->nrm[i], ex, ey, a, &ii, &iz))
            continue;
        for (int di = -1; di <= 1; di++) {
            if (ii + di < 0 || ii + di >= NI)
                continue;
            for (int dz = -2; dz <= 2; dz++) {
                double w = A->area[i] * (1 - abs(di) / 2.0) *
                           (1 - abs(dz) / 3.0);
                H[(ii + di) * NZ + (iz + dz + NZ) % NZ] += w;
            }
        }
    }
}

/* Adds the pairs of one direction to S: each normal of `from` (its
 * subsample unless all) with its nearest normal of `to` under R (Rᵀ when
 * from is A), weighted by the smaller area so that a sliver cannot pull
 * a large facet. Returns how many matched. */
static uint32_t pair_up(const model *from, const model *to, bool from_is_a,
                        bool all, double R[3][3], double ct, double S[3][3])
{
    uint32_t n = all ? from->n : from->nsub, matched = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t j = all ? k : from->order[k];
        double v[3];
        if (from_is_a)
            mat_tvec(R, from->nrm[j], v);
        else
            mat_vec(R, from->nrm[j], v);
        uint32_t i = nearest_normal(to, v, ct);
        if (i == UINT32_MAX)
            continue;
        matched++;
        const double *b = from_is_a ? to->nrm[i] : from->nrm[j];
        const double *a = from_is_a ? from->nrm[j] : to->nrm[i];
        double w = fmin(from->area[j], to->area[i]);
        for (int p = 0; p < 3; p++)
            for (int q = 0; q < 3; q++)
                S[p][q] += w * b[p] * a[q];
    }
    return matched;
}

/* Refines R from the normals of each model matched to their nearest
 * normals of the other, the tolerance shrinking through tols and then
 * kept until R settles (at most iters rounds). Over the subsamples
 * unless all. false when fewer than 3 pairs matched (R unchanged). */
static bool refine(const model *A, const model *B, bool all,
                   const double *tols, int ntols, int iters, double R[3][3])
{
    for (int it = 0; it < iters; it++) {
        double ct = cos(tols[it < ntols ? it : ntols - 1]);
        double S[3][3] = {{0}};
        uint32_t matched = pair_up(B, A, false, all, R, ct, S) +
                           pair_up(A, B, true, all, R, ct, S);
        if (matched < 3)
            return it > 0;
        double Rn[3][3], change = 0;
        horn(S, Rn);
        for (int p = 0; p < 3; p++)
            for (int q = 0; q < 3; q++)
                change = fmax(change, fabs(Rn[p][q] - R[p][q]));
        memcpy(R, Rn, sizeof Rn);
        if (it >= ntols && change < 1e-15)
            break;
    }
    return true;
}

/* Area share of from's subsample (all of it when all) whose normal,
 * turned by R (or by its transpose when back), finds one of to's within
 * cos_tol. */
static double covered(const model *from, const model *to, double R[3][3],
                      bool back, bool all, double cos_tol)
{
    double covered_area = 0, total = 0;
    uint32_t n = all ? from->n : from->nsub;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t j = all ? k : from->order[k];
        double v[3];
        if (back)
            mat_tvec(R, from->nrm[j], v);
        else
            mat_vec(R, from->nrm[j], v);
        total += from->area[j];
        if (nearest_normal(to, v, cos_tol) != UINT32_MAX)
            covered_area += from->area[j];
    }
    return covered_area / total;
}

/* Area share of both subsamples whose normal finds the other model's
 * within 1° under R. */
static double coverage(const model *A, const model *B, double R[3][3],
                       bool all)
{
    double c1 = cos(1 * DEG);
    return (covered(A, B, R, true, all, c1) + covered(B, A, R, false, all, c1)) / 2;
}

/* A symmetric stone's equal turns cover the same share of the surfaces
 * but for the noise of a few small facets at the 1° test: on a K = 800
 * scan against its design, 0.22 % apart for the turns of 0° and 45°. A
 * wrong turn of an asymmetric stone leaves most facets unmatched. */
#define COVER_TIE 0.01

/* The refined turns and their coverage; the winner is picked when all
 * are in (pick_turn), so that it does not depend on their order. */
typedef struct best_rot {
    bool found;
    double R[3][3], score, angle;
    uint32_t n;
    struct {
        double R[3][3], score, angle;
    } turn[MAX_TURNS];
} best_rot;

static void consider(best_rot *b, double R[3][3], double score)
{
    if (b->n == MAX_TURNS)
        return;
    double axis[3], def[3] = {0, 0, 1};
    memcpy(b->turn[b->n].R, R, sizeof b->turn[b->n].R);
    b->turn[b->n].score = score;
    b->turn[b->n].angle = mat_angle(R, def, axis);
    if (!b->found || score > b->score)
        b->score = score;
    b->found = true;
    b->n++;
}

/* Of the turns within COVER_TIE of the best coverage, the smallest
 * rotation (the equal turns of a symmetric stone: two models in one
 * frame stay as they are); b->score stays the best coverage. */
static void pick_turn(best_rot *b)
{
    uint32_t k = UINT32_MAX;
    for (uint32_t i = 0; i < b->n; i++)
        if (b->turn[i].score >= b->score - COVER_TIE &&
            (k == UINT32_MAX || b->turn[i].angle < b->turn[k].angle - 1e-9))
            k = i;
    if (k == UINT32_MAX)
        return;
    memcpy(b->R, b->turn[k].R, sizeof b->R);
    b->angle = b->turn[k].angle;
}

/* Every turn about A's axis the histograms suggest (peaks at least
 * floor × the highest), refined and scored. */
static int try_axes(const model *A, const model *B, const axis_cand *ca,
                    const axis_cand *cb, double floor, double *H,
                    double *corr, const geo_ctx *ctx, best_rot *best)
{
    const double *a = ca->axis;
    double ex[3], ey[3];
    perpendicular(a, ex);
    geo_vcross(a, ex, ey);
    histogram(A, a, ex, ey, H);
    double R0[3][3];
    mat_onto(cb->axis, a, R0);
    /* B's subsample in A's frame */
    int ii[SUB_MAX], iz[SUB_MAX];
    double w[SUB_MAX];
    uint32_t nb = 0;
    for (uint32_t k = 0; k < B->nsub; k++) {
        uint32_t j = B->order[k];
        double v[3];
        mat_vec(R0, B->nrm[j], v);
        if (bins(v, ex, ey, a, &ii[nb], &iz[nb]))
            w[nb++] = B->area[j];
    }
    double cmax = 0;
    for (int s = 0; s < NZ; s++) {
        double c = 0;
        for (uint32_t k = 0; k < nb; k++)
            c += w[k] * H[ii[k] * NZ + (iz[k] + s) % NZ];
        corr[s] = c;
        cmax = fmax(cmax, c);
    }
    int peaks[MAX_PEAKS], np = 0;
    for (int s = 0; s < NZ; s++) {
        double c = corr[s];
        if (!(c > 0) || c < floor * cmax || !(c > corr[(s + NZ - 1) % NZ]) ||
            c < corr[(s + 1) % NZ])
            continue;
        /* keep the MAX_PEAKS highest, in decreasing order */
        int at = np < MAX_PEAKS ? np++ : MAX_PEAKS;
        while (at > 0 && corr[peaks[at - 1]] < c) {
            if (at < MAX_PEAKS)
                peaks[at] = peaks[at - 1];
            at--;
        }
        if (at < MAX_PEAKS)
            peaks[at] = s;
    }
    if (nb == 0) /* nothing but the table and culet: no turn to find */
        peaks[np++] = 0;
    static const double tols[] = {2 * DEG, 1 * DEG, 0.5 * DEG};
    for (int k = 0; k < np; k++) {
        if (geo_ctx_canceled(ctx))
            return -ECANCELED;
        double Rz[3][3], R[3][3];
        mat_axis_angle(a, peaks[k] * 0.5 * DEG, Rz);
        mat_mul(Rz, R0, R);
        if (!refine(A, B, false, tols, 2, 2, R))
            continue;
        consider(best, R, coverage(A, B, R, false));
    }
    return 0;
}

/* ---- the translation and the facet pairs ---- */

typedef struct cand_pair {
    uint32_t a, b; /* positions in A and B */
    double cost;   /* largest distance of B's plane from A's facet */
} cand_pair;

static int by_cost(const void *x, const void *y)
{
    const cand_pair *p = x, *q = y;
    if (p->cost != q->cost)
        return p->cost < q->cost ? -1 : 1;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    return (p->b > q->b) - (p->b < q->b);
}

/* B's plane j moved by (R, t): normal n, offset d. */
static void moved_plane(const model *B, uint32_t j, double R[3][3],
                        const double t[3], double n[3], double *d)
{
    mat_vec(R, B->nrm[j], n);
    *d = B->p->planes[B->fac[j]][3] - geo_vdot(n, t);
}

/* Matches facets one to one under (R, t) into pairs (positions, room
 * for min(A->n, B->n)); returns how many. */
static int match_pairs(const model *A, const model *B, double R[3][3],
                       const double t[3], double delta, cand_pair **pairs,
                       uint32_t *ret_n)
{
    size_t cap = 1024, n = 0;
    cand_pair *c = malloc(cap * sizeof *c);
    if (!c)
        return -ENOMEM;
    double c1 = cos(1 * DEG);
    for (uint32_t j = 0; j < B->n; j++) {
        double nv[3], d;
        moved_plane(B, j, R, t, nv, &d);
        FOR_NEAR_CELLS(A, nv, i) {
            if (geo_vdot(A->nrm[i], nv) < c1)
                continue;
            const geo_poly *p = A->p;
            uint32_t f = A->fac[i], sz = geo_poly_facet_size(p, f);
            const uint32_t *ix = geo_poly_facet(p, f);
            double cost = 0;
            for (uint32_t k = 0; k < sz; k++)
                cost = fmax(cost, fabs(geo_vdot(nv, p->verts[ix[k]]) + d));
            if (!(cost <= delta))
                continue;
            if (n == cap) {
                cand_pair *g = realloc(c, 2 * cap * sizeof *c);
                if (!g) {
                    free(c);
                    return -ENOMEM;
                }
                c = g;
                cap *= 2;
            }
            c[n++] = (cand_pair){i, j, cost};
        }
    }
    qsort(c, n, sizeof *c, by_cost);
    uint8_t *used_a = calloc(A->n, 1), *used_b = calloc(B->n, 1);
    if (!used_a || !used_b) {
        free(used_a), free(used_b), free(c);
        return -ENOMEM;
    }
    size_t m = 0;
    for (size_t k = 0; k < n; k++)
        if (!used_a[c[k].a] && !used_b[c[k].b]) {
            used_a[c[k].a] = used_b[c[k].b] = 1;
            c[m++] = c[k];
        }
    free(used_a), free(used_b);
    *pairs = c;
    *ret_n = (uint32_t)m;
    return 0;
}

static int by_value(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* Least squares t with B's matched planes through A's facet centres,
 * pairs beyond 3 robust deviations dropped twice. false (t unchanged)
 * when the normals do not span space. */
static bool solve_translation(const model *A, const model *B,
                              double R[3][3], const cand_pair *pr,
                              uint32_t n, double t[3])
{
    if (n < 3)
        return false;
    double *res = malloc((size_t)n * sizeof *res);
    uint8_t *out = calloc(n, 1);
    if (!res || !out) {
        free(res), free(out);
        return false;
    }
    double eps = geo_poly_eps(A->p);
    bool ok = false;
    for (int round = 0; round < 3; round++) {
        double M[4][4] = {{0}}, rhs[3] = {0, 0, 0};
        uint32_t used = 0;
        for (uint32_t k = 0; k < n; k++) {
            if (out[k])
                continue;
            double nv[3], c[3];
            mat_vec(R, B->nrm[pr[k].b], nv);
            geo_poly_facet_center(A->p, A->fac[pr[k].a], c);
            double r = geo_vdot(nv, c) + B->p->planes[B->fac[pr[k].b]][3];
            double w = fmin(A->area[pr[k].a], B->area[pr[k].b]);
            for (int p = 0; p < 3; p++) {
                rhs[p] += w * nv[p] * r;
                for (int q = 0; q < 3; q++)
                    M[p][q] += w * nv[p] * nv[q];
            }
            used++;
        }
        double V[4][4];
        jacobi(3, M, V);
        double lmax = fmax(M[0][0], fmax(M[1][1], M[2][2]));
        double lmin = fmin(M[0][0], fmin(M[1][1], M[2][2]));
        if (used < 3 || !(lmin > 1e-4 * lmax))
            break;
        double tn[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++) {
            double u[3] = {V[0][k], V[1][k], V[2][k]};
            geo_vmadd(tn, geo_vdot(u, rhs) / M[k][k], u, tn);
        }
        memcpy(t, tn, sizeof tn);
        ok = true;
        if (round == 2)
            break;
        /* residuals, their median absolute deviation, and the cut */
        uint32_t m = 0;
        for (uint32_t k = 0; k < n; k++) {
            if (out[k])
                continue;
            double nv[3], c[3];
            mat_vec(R, B->nrm[pr[k].b], nv);
            geo_poly_facet_center(A->p, A->fac[pr[k].a], c);
            res[m++] = fabs(geo_vdot(nv, c) +
                            B->p->planes[B->fac[pr[k].b]][3] -
                            geo_vdot(nv, t));
        }
        double *sorted = malloc((size_t)m * sizeof *sorted);
        if (!sorted)
            break;
        memcpy(sorted, res, (size_t)m * sizeof *sorted);
        qsort(sorted, m, sizeof *sorted, by_value);
        double cut = fmax(3 * 1.4826 * sorted[m / 2], 100 * eps);
        free(sorted);
        uint32_t q = 0;
        for (uint32_t k = 0; k < n; k++) {
            if (out[k])
                continue;
            if (res[q++] > cut)
                out[k] = 1;
        }
    }
    free(res), free(out);
    return ok;
}

/* ---- measuring ---- */

/* b moved by (R, t): vertices and planes. */
static geo_poly *moved_copy(const geo_poly *b, double R[3][3],
                            const double t[3])
{
    geo_poly *q = geo_poly_copy(b);
    if (!q)
        return NULL;
    for (uint32_t v = 0; v < q->nverts; v++) {
        double x[3];
        mat_vec(R, b->verts[v], x);
        geo_vadd(x, t, q->verts[v]);
    }
    for (uint32_t f = 0; f < q->nfacets; f++) {
        double n[3];
        mat_vec(R, b->planes[f], n);
        memcpy(q->planes[f], n, sizeof n);
        q->planes[f][3] = b->planes[f][3] - geo_vdot(n, t);
    }
    return q;
}

/* One direction of the measures: from the surface of p to s. */
typedef struct direction {
    const geo_poly *p, *to;
    const geo_ctx *ctx;
    double max2;      /* over the Hausdorff samples (hausdorff.h) */
    double sum, area; /* Σ area × distance over the area samples */
    int rc;
} direction;

static bool tick(uint32_t *count, const geo_ctx *ctx)
{
    return (++*count & GEO_CTX_CHECK_MASK) == 0 && geo_ctx_canceled(ctx);
}

/* The samples of hausdorff.h — every vertex, every edge's midpoint
 * (once: from the facet that lists it rising, so a closed model's twin
 * edge is not measured again) and every facet's vertex centroid — give
 * the same estimate as geo_hausdorff; the mean takes about MEAN_SAMPLES
 * area samples: triangles larger than the share of one are split in k²,
 * smaller ones pool their area into one sample at the centroid of the
 * last. */
static int measure(direction *d)
{
    const geo_poly *p = d->p;
    geo_surface *s;
    int r = geo_surface_new(d->to, &s, NULL);
    if (r < 0)
        return r;
    uint32_t maxn = 3;
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (geo_poly_facet_size(p, f) > maxn)
            maxn = geo_poly_facet_size(p, f);
    uint32_t (*tris)[3] = malloc((size_t)(maxn - 2) * sizeof *tris);
    uint8_t *seen = calloc((size_t)p->nverts + 1, 1);
    if (!tris || !seen) {
        r = -ENOMEM;
        goto out;
    }
    double target = geo_poly_area(p) / MEAN_SAMPLES, carry = 0;
    uint32_t hint = UINT32_MAX, count = 0;
    d->max2 = d->sum = d->area = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *ix = geo_poly_facet(p, f);
        double c[3] = {0, 0, 0};
        for (uint32_t i = 0; i < n; i++) {
            uint32_t u = ix[i], v = ix[(i + 1) % n];
            geo_vadd(c, p->verts[u], c);
            if (!seen[u]) {
                seen[u] = 1;
                d->max2 = fmax(d->max2, geo_surface_dist2_above(
                                            s, p->verts[u], d->max2, &hint));
            }
            if (u < v) {
                double m[3];
                geo_vadd(p->verts[u], p->verts[v], m);
                geo_vscale(m, 0.5, m);
                d->max2 = fmax(d->max2,
                               geo_surface_dist2_above(s, m, d->max2, &hint));
            }
            if (tick(&count, d->ctx)) {
                r = -ECANCELED;
                goto out;
            }
        }
        geo_vscale(c, 1.0 / n, c);
        d->max2 = fmax(d->max2, geo_surface_dist2_above(s, c, d->max2, &hint));
        if ((r = geo_polygon_triangulate(&p->verts[0][0], ix, n, tris)) < 0)
            goto out;
        for (uint32_t t = 0; t + 2 < n; t++) {
            const double *P0 = p->verts[ix[tris[t][0]]],
                         *P1 = p->verts[ix[tris[t][1]]],
                         *P2 = p->verts[ix[tris[t][2]]];
            double e1[3], e2[3], x[3];
            geo_vsub(P1, P0, e1);
            geo_vsub(P2, P0, e2);
            geo_vcross(e1, e2, x);
            double ta = geo_vlen(x) / 2;
            if (!(ta > 0))
                continue;
            int k = 1;
            double w = ta;
            if (ta < target) {
                carry += ta;
                if (carry < target)
                    continue;
                w = carry;
                carry = 0;
            } else {
                k = (int)floor(sqrt(ta / target));
                k = k < 1 ? 1 : k > 64 ? 64 : k;
                w = ta / ((double)k * k);
            }
            for (int i = 0; i < k; i++)
                for (int j = 0; i + j < k; j++)
                    for (int up = 0; up < 2; up++) {
                        if (up && i + j >= k - 1)
                            continue;
                        double a = (i + (up ? 2.0 : 1.0) / 3) / k;
                        double b = (j + (up ? 2.0 : 1.0) / 3) / k;
                        double q[3];
                        for (int e = 0; e < 3; e++)
                            q[e] = P0[e] + a * e1[e] + b * e2[e];
                        d->sum += w * sqrt(geo_surface_dist2(s, q, &hint,
                                                             NULL));
                        d->area += w;
                        if (tick(&count, d->ctx)) {
                            r = -ECANCELED;
                            goto out;
                        }
                    }
        }
    }
    if (carry > 0 && p->nfacets) { /* the last small triangles' area */
        double c[3];
        geo_poly_facet_center(p, p->nfacets - 1, c);
        d->sum += carry * sqrt(geo_surface_dist2(s, c, &hint, NULL));
        d->area += carry;
    }
out:
    free(tris);
    free(seen);
    geo_surface_free(s);
    return r;
}

static void measure_task(void *arg, size_t i)
{
    direction *d = (direction *)arg + i;
    d->rc = measure(d);
}

/* Hausdorff estimate and mean distance between a and b, both directions
 * at once when the caller gives a parallel loop. */
static int measures(const geo_poly *a, const geo_poly *b, const geo_ctx *ctx,
                    double *hausdorff, double *mean, geo_err *err)
{
    direction d[2] = {{.p = a, .to = b, .ctx = ctx},
                      {.p = b, .to = a, .ctx = ctx}};
    geo_ctx_parallel_for(ctx, 2, measure_task, d);
    for (int i = 0; i < 2; i++) {
        if (d[i].rc == -ECANCELED)
            return geo_err_set(err, -ECANCELED, "compare: canceled");
        if (d[i].rc < 0)
            return geo_err_set(err, d[i].rc, "out of memory");
    }
    *hausdorff = sqrt(fmax(d[0].max2, d[1].max2));
    double area = d[0].area + d[1].area;
    *mean = area > 0 ? (d[0].sum + d[1].sum) / area : 0;
    return 0;
}

static int by_a(const void *x, const void *y)
{
    const geo_compare_pair *p = x, *q = y;
    return (p->a > q->a) - (p->a < q->a);
}

void geo_compare_free(geo_compare_result *r)
{
    if (r) {
        free(r->pairs);
        r->pairs = NULL;
    }
}

int geo_compare(const geo_poly *a, const geo_poly *b,
                const geo_compare_opts *o, const geo_ctx *ctx,
                geo_compare_result *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    geo_compare_opts def = {0};
    if (!o)
        o = &def;
    model A, B;
    int r = model_init(&A, a, o->name_a ? o->name_a : "A", err);
    if (r < 0)
        return r;
    r = model_init(&B, b, o->name_b ? o->name_b : "B", err);
    if (r < 0) {
        model_free(&A);
        return r;
    }
    axis_cand ca[2], cb[2];
    int nca = 0, ncb = 0;
    r = axis_cands(&A, o->axis, ca, &nca, err);
    if (r == 0 && axis_cands(&B, o->axis, cb, &ncb, NULL) < 0) {
        /* B without a table: taken along A's axis as it lies */
        memcpy(cb[0].axis, ca[0].axis, sizeof cb[0].axis);
        cb[0].table = UINT32_MAX;
        ncb = 1;
    }
    double *H = r == 0 ? malloc((size_t)NI * NZ * sizeof *H) : NULL;
    double *corr = H ? malloc(NZ * sizeof *corr) : NULL;
    cand_pair *pairs = NULL;
    geo_poly *moved = NULL;
    uint32_t npairs = 0;
    if (r == 0 && !corr) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    if (r < 0)
        goto out;
    /* the likeliest axes and turns first; everything else when they do
     * not fit well */
    best_rot best = {0};
    for (int j = 0; j < ncb && r == 0; j++)
        r = try_axes(&A, &B, &ca[0], &cb[j], 0.8, H, corr, ctx, &best);
    if (r == 0 && (!best.found || best.score < 0.9)) {
        for (int i = 0; i < nca && r == 0; i++)
            for (int j = 0; j < ncb && r == 0; j++)
                r = try_axes(&A, &B, &ca[i], &cb[j], 0.3, H, corr, ctx,
                             &best);
    }
    if (r == -ECANCELED) {
        geo_err_set(err, r, "compare: canceled");
        goto out;
    }
    pick_turn(&best);
    double R[3][3], t[3] = {0, 0, 0};
    mat_identity(R);
    ret->aligned = best.found && best.score >= 0.5;
    if (ret->aligned) {
        static const double fine[] = {1 * DEG, 0.5 * DEG, 0.25 * DEG,
                                      0.1 * DEG};
        memcpy(R, best.R, sizeof R);
        refine(&A, &B, true, fine, 4, 7, R);
        /* from the centroids, then the planes, matched again each time */
        double c[3];
        mat_vec(R, B.centroid, c);
        geo_vsub(A.centroid, c, t);
        double delta = 0.02 * geo_poly_size(a);
        for (int round = 0; round < 2; round++) {
            free(pairs);
            pairs = NULL;
            if ((r = match_pairs(&A, &B, R, t, delta, &pairs, &npairs)) < 0)
                break;
            if (!solve_translation(&A, &B, R, pairs, npairs, t))
                break;
        }
        if (r == 0) {
            free(pairs);
            pairs = NULL;
            r = match_pairs(&A, &B, R, t, delta, &pairs, &npairs);
        }
        ret->coverage = coverage(&A, &B, R, true);
    } else {
        ret->coverage = best.found ? best.score : 0;
        r = match_pairs(&A, &B, R, t, 0.02 * geo_poly_size(a), &pairs,
                        &npairs);
    }
    if (r < 0) {
        geo_err_set(err, r, "out of memory");
        goto out;
    }
    memcpy(ret->rotation, R, sizeof R);
    memcpy(ret->translation, t, sizeof t);
    memcpy(ret->axis, ca[0].axis, sizeof ret->axis);
    ret->rotation_deg = mat_angle(R, ca[0].axis, ret->rotation_axis) / DEG;
    ret->pairs = malloc(((size_t)npairs + 1) * sizeof *ret->pairs);
    if (!ret->pairs) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    for (uint32_t k = 0; k < npairs; k++) {
        uint32_t i = pairs[k].a, j = pairs[k].b;
        double nv[3], d, c[3], x[3];
        moved_plane(&B, j, R, t, nv, &d);
        geo_poly_facet_center(a, A.fac[i], c);
        geo_vcross(nv, A.nrm[i], x);
        double cs = geo_vdot(nv, A.nrm[i]);
        ret->pairs[k] = (geo_compare_pair){
            .a = A.fac[i], .b = B.fac[j],
            .angle_deg = atan2(geo_vlen(x), cs) / DEG,
            .offset_mm = -(geo_vdot(nv, c) + d) / cs,
        };
    }
    qsort(ret->pairs, npairs, sizeof *ret->pairs, by_a);
    ret->matched = npairs;
    ret->unmatched_a = a->nfacets - npairs;
    ret->unmatched_b = b->nfacets - npairs;
    moved = moved_copy(b, R, t);
    if (!moved) {
        r = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    r = measures(a, moved, ctx, &ret->hausdorff_mm, &ret->mean_distance_mm,
                 err);
    if (r == 0)
        ret->volume_difference_relative =
            A.volume != 0 ? (B.volume - A.volume) / A.volume : 0;
out:
    free(H);
    free(corr);
    free(pairs);
    geo_poly_free(moved);
    model_free(&A);
    model_free(&B);
    if (r < 0)
        geo_compare_free(ret);
    return r;
}
