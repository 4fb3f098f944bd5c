/* plane.h — planes a·x+b·y+c·z+d = 0 with (a,b,c) a unit normal: least
 * squares fits (Palachev 2012, §2.5), three-plane intersection, and the
 * symmetric 3×3 eigen-solver behind the fit, the area moments of a
 * polygon behind the area-weighted fits. Pure functions, thread-safe. */
#ifndef GEO_PLANE_H
#define GEO_PLANE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Least-squares plane of n points (pts: 3·n doubles x,y,z,…) (Palachev 2012, §2.5.1): minimises
 * Σ wᵢ (a·xᵢ+b·yᵢ+c·zᵢ+d)² with |(a,b,c)| = 1, i.e. the eigenvector of the
 * smallest eigenvalue of the weighted covariance, through the weighted
 * centroid. w may be NULL (all weights 1). If orient is non-NULL the
 * normal is turned to have a non-negative dot product with it. Returns 0,
 * or -EINVAL when n < 3, weights sum to 0, or the points are collinear
 * within rounding (ret is then left unchanged). */
int geo_plane_fit(const double *pts, const double *w, size_t n,
                  const double orient[3], double ret[4]);

/* Plane through p with unit normal n (n need not be unit: it is
 * normalised). Returns -EINVAL for a zero normal. */
int geo_plane_from_point_normal(const double p[3], const double n[3],
                                double ret[4]);


/* The common point of three planes. Returns false (ret unchanged) when the
 * normals are linearly dependent: |det| ≤ 1e-12 · |n1|·|n2|·|n3|. */
bool geo_plane_intersect3(const double p1[4], const double p2[4],
                          const double p3[4], double ret[3]);

/* The meets of many triples of k planes (the vertices of their
 * arrangement, searched by the convex correction): each pair's cross
 * product and each plane's length taken once, so a meet costs a
 * determinant and a solve. geo_plane_triples_meet(t, a, b, c) gives
 * geo_plane_intersect3(pl[a], pl[b], pl[c]) bit for bit (the same
 * operations; cross(c, a) is −cross(a, c) exactly). The planes must
 * stay in place while t is used; t's arrays are reused by the next
 * geo_plane_triples_set. */
typedef struct geo_plane_triples {
    const double (*pl)[4];
    uint32_t k, cap;
    double *len;     /* |normal| of each plane */
    double (*cr)[3]; /* cross(pl[a], pl[b]) at a·k + b, a < b */
} geo_plane_triples;

/* 0, or -ENOMEM (t then holds no planes). */
int geo_plane_triples_set(geo_plane_triples *t, const double (*pl)[4],
                          uint32_t k);

/* For a < b < c < k: as geo_plane_intersect3 of the three planes. */
bool geo_plane_triples_meet(const geo_plane_triples *t, uint32_t a,
                            uint32_t b, uint32_t c, double ret[3]);

void geo_plane_triples_free(geo_plane_triples *t);

/* Eigen-decomposition of the symmetric 3×3 matrix m (row-major, only the
 * upper triangle read, m not modified): ret_values ascending,
 * ret_vectors[k] the unit eigenvector of ret_values[k]. The closed form
 * (eigenvalues from the characteristic cubic, the isolated one's vector
 * as a null vector, the other two by one exact 2×2 rotation), accurate to
 * a few ulps of the largest eigenvalue over the gaps; a nearly scalar
 * matrix goes to Jacobi. For the moment fits that run once per facet a
 * group takes in. */
void geo_sym3_eigen(double m[3][3], double ret_values[3],
                    double ret_vectors[3][3]);

/* The same by cyclic Jacobi rotations (the upper triangle read): four times
 * slower, and what geo_plane_fit uses, so that the planes fitted to the
 * facets of a model read without them — and every statistic from them —
 * stay as they were. */
void geo_sym3_eigen_jacobi(const double m[3][3], double ret_values[3],
                           double ret_vectors[3][3]);

/* Adds the area moments of polygon fv[0..n) of verts about the point o, as
 * the fan from fv[0] (exact for a convex planar polygon): its area to *a,
 * ∫(x − o) dA to s, ∫(x − o)(x − o)ᵀ dA to ss (upper triangle). */
void geo_fan_moments(const double (*verts)[3], const uint32_t *fv, uint32_t n,
                     const double o[3], double *a, double s[3],
                     double ss[3][3]);

/* Solves the symmetric positive-definite 3×3 system m x = b by Cholesky.
 * m is not modified. Returns false when m is not positive definite (x unchanged). */
bool geo_spd3_solve(double m[3][3], const double b[3], double x[3]);

#endif
