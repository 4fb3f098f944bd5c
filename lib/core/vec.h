/* vec.h — small inline 3-vector helpers (double[3]); no allocation. */
#ifndef GEO_VEC_H
#define GEO_VEC_H

#include <math.h>

static inline void geo_vsub(const double a[3], const double b[3], double r[3])
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}

static inline void geo_vadd(const double a[3], const double b[3], double r[3])
{
    r[0] = a[0] + b[0];
    r[1] = a[1] + b[1];
    r[2] = a[2] + b[2];
}

static inline void geo_vscale(const double a[3], double s, double r[3])
{
    r[0] = a[0] * s;
    r[1] = a[1] * s;
    r[2] = a[2] * s;
}

/* A running box along one axis: lo = fmin(lo, x), hi = fmax(hi, x) for
 * lo and hi not NaN (a NaN x leaves both), compared inline: at -O2 fmin
 * and fmax are library calls, in loops over every vertex. */
static inline void geo_minmax(double x, double *lo, double *hi)
{
    if (x < *lo)
        *lo = x;
    if (x > *hi)
        *hi = x;
}

/* r = a + s·b */
static inline void geo_vmadd(const double a[3], double s, const double b[3],
                             double r[3])
{
    r[0] = a[0] + s * b[0];
    r[1] = a[1] + s * b[1];
    r[2] = a[2] + s * b[2];
}

static inline double geo_vdot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline void geo_vcross(const double a[3], const double b[3], double r[3])
{
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    r[0] = x;
    r[1] = y;
    r[2] = z;
}

static inline double geo_vlen(const double a[3])
{
    return sqrt(geo_vdot(a, a));
}

/* The angle between a and b (radians, 0..π; accurate near 0 and π,
 * where acos of the dot product is not). */
static inline double geo_vangle(const double a[3], const double b[3])
{
    double c[3];
    geo_vcross(a, b, c);
    return atan2(geo_vlen(c), geo_vdot(a, b));
}

/* |a| without overflow or underflow of the squares (gradients of F-rep
 * functions range from 1e-300 to 1e300): scaled by the largest
 * component first. 0 for a zero vector, NaN/inf propagate. */
static inline double geo_vlen_scaled(const double a[3])
{
    double m = fmax(fabs(a[0]), fmax(fabs(a[1]), fabs(a[2])));
    if (!(m > 0) || !isfinite(m))
        return m;
    double x = a[0] / m, y = a[1] / m, z = a[2] / m;
    return m * sqrt(x * x + y * y + z * z);
}

static inline double geo_vdist(const double a[3], const double b[3])
{
    double d[3];
    geo_vsub(a, b, d);
    return geo_vlen(d);
}

/* Normalises a in place; returns its former length (0 leaves a as is). */
static inline double geo_vnormalize(double a[3])
{
    double l = geo_vlen(a);
    if (l > 0.0) {
        a[0] /= l;
        a[1] /= l;
        a[2] /= l;
    }
    return l;
}

/* Two unit vectors completing the unit vector u to an orthonormal basis
 * (u, e1, e2), e1 ⟂ the axis along which u is shortest. */
static inline void geo_vbasis(const double u[3], double e1[3], double e2[3])
{
    double t[3] = {0, 0, 0};
    int k = fabs(u[0]) <= fabs(u[1]) ? (fabs(u[0]) <= fabs(u[2]) ? 0 : 2)
                                     : (fabs(u[1]) <= fabs(u[2]) ? 1 : 2);
    t[k] = 1;
    geo_vcross(u, t, e1);
    geo_vnormalize(e1);
    geo_vcross(u, e1, e2);
}

/* Signed distance-like value of p to plane (a,b,c,d): a·x+b·y+c·z+d. */
static inline double geo_plane_eval(const double plane[4], const double p[3])
{
    return plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3];
}

#endif
