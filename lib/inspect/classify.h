/* classify.h — the tests of graphic elements in space ("Tests of graphic elements"): the side of
 * a point relative to a plane in the paper's four forms, the plane ×
 * polyhedron test cross3, and the convexity tests conv3 (polyhedron) and
 * of each facet polygon.
 *
 * Sign convention ("Tests of graphic elements", "positive half-space"): every form is > 0 on
 * the side the plane's normal points to — outside, for a facet listed
 * counter-clockwise seen from outside — < 0 on the other side, 0 on the
 * plane.
 *
 * Values and signs: each form has a value function (the paper's formula
 * in doubles, for measuring) and a sign function. The sign functions are
 * exact: they return the sign of the real-number expression evaluated on
 * the given doubles, through lib/core/predicates.h. Which expression that is
 * for each form:
 *   implicit     A·x+B·y+C·z+D with the coefficients taken as exact;
 *   point+normal N·(p − p0) with p − p0 formed exactly — never through a
 *                rounded offset D = −N·p0 (geo_normal_sign);
 *   three points (p − a)·((b − a) × (c − b)) = orient3d(a, b, c, p);
 *   facet        the three-point form on the facet's reference corner
 *                (geo_facet_ref), i.e. the plane through three of its
 *                vertices. A facet whose vertices are not exactly coplanar
 *                (scanned models: within geo_poly_eps, not exactly) has no
 *                single exact plane; the reference corner's plane is the
 *                one used, and it contains at least three of its vertices.
 *
 * All functions are pure, reentrant and thread-safe on an unchanging
 * geo_poly. Nothing allocates except where stated. */
#ifndef GEO_CLASSIFY_H
#define GEO_CLASSIFY_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"

/* nfF(p) = A·p.x + B·p.y + C·p.z + D for plane = {A, B, C, D}; units of
 * the coefficients times millimetres (a distance in mm when (A,B,C) is a
 * unit vector). */
double geo_nf_implicit(const double plane[4], const double p[3]);
/* Exact sign of nfF(p): +1, −1 or 0. */
int geo_nf_implicit_sign(const double plane[4], const double p[3]);

/* nfN(p0, N, p) = N·(p − p0): the plane through p0 with normal N. */
double geo_nf_normal(const double p0[3], const double n[3], const double p[3]);
/* Exact sign of nfN (N·(p − p0) with exact differences). */
int geo_nf_normal_sign(const double p0[3], const double n[3],
                       const double p[3]);

/* nf3(a, b, c, p) = (p − a)·((b − a) × (c − b)): the plane through a, b, c
 * with the right-hand normal of a → b → c; mm³ (twice the triangle's area
 * times the distance). 0 for collinear a, b, c. */
double geo_nf3(const double a[3], const double b[3], const double c[3],
               const double p[3]);
/* Exact sign of nf3 (geo_orient3d). */
int geo_nf3_sign(const double a[3], const double b[3], const double c[3],
                 const double p[3]);

/* The reference corner of facet f: three vertex indices (previous, corner,
 * next) of a corner whose triangle has the orientation of the whole
 * polygon. The paper's nfG takes the first three vertices, but the first
 * corner of a non-convex facet may be reflex (its normal then points
 * inward) and its vertices may be collinear; this picks the vertex that is
 * lexicographically smallest in the projection along the facet's dominant
 * normal axis — a convex corner of any simple polygon — and, if its
 * neighbours are collinear with it, the non-collinear corner with the
 * polygon's orientation and the largest projected area. A facet with no
 * such corner (zero area) gets its first three vertices. O(facet size). */
void geo_facet_ref(const geo_poly *p, uint32_t f, uint32_t ret[3]);

/* nfG(facet f, p) = (p − p1)·((p2 − p1) × (p3 − p2)) with p1, p2, p3 the
 * reference corner (geo_facet_ref); mm³. */
double geo_nf_facet(const geo_poly *p, uint32_t f, const double q[3]);
/* Exact sign of nfG (orient3d on the reference corner). */
int geo_nf_facet_sign(const geo_poly *p, uint32_t f, const double q[3]);

/* True when every vertex of facet f lies exactly (orient3d = 0) in the
 * plane of its reference corner. Hand-built models with integer
 * coordinates are; scanned models with rounded vertices rarely are. */
bool geo_facet_is_planar_exact(const geo_poly *p, uint32_t f);

/* A plane in any of the paper's forms, for functions that accept each. */
enum geo_plane_form {
    GEO_PLANE_IMPLICIT = 0,     /* coef = {A, B, C, D} */
    GEO_PLANE_POINT_NORMAL = 1, /* point p0, normal N */
    GEO_PLANE_THREE_POINTS = 2, /* pts[0..2] = a, b, c */
};
typedef struct geo_plane_spec {
    enum geo_plane_form form;
    double coef[4];
    double point[3], normal[3];
    double pts[3][3];
} geo_plane_spec;

/* Fills a THREE_POINTS spec with facet f's reference corner (nfG). */
void geo_plane_spec_facet(const geo_poly *p, uint32_t f, geo_plane_spec *ret);
/* The form's value and exact sign at q (see above). */
double geo_plane_spec_value(const geo_plane_spec *pl, const double q[3]);
int geo_plane_spec_sign(const geo_plane_spec *pl, const double q[3]);

/* cross3(f, P): +1 when the plane has vertices of p strictly on both sides
 * (it crosses the polyhedron), −1 when every vertex is strictly on one
 * side (it misses), 0 when it touches: some vertices lie exactly on the
 * plane and none lie across it (a vertex, an edge or a facet on the
 * plane). Every vertex of p counts, used by a facet or not; an empty
 * model gives −1. Exact signs, each vertex's side decided once; stops at
 * the first pair across. O(nverts). */
int geo_cross3(const geo_plane_spec *pl, const geo_poly *p);

/* The outcome of conv3 (the polyhedron's convexity test). */
typedef struct geo_conv3_result {
    bool convex;        /* no facet has vertices strictly on both sides */
    uint32_t facet;     /* !convex: the first such facet */
    uint32_t v_above;   /* !convex: a vertex with nfG > 0 for it */
    uint32_t v_below;   /* !convex: a vertex with nfG < 0 for it */
    uint32_t nabove;    /* facets with some vertex strictly above and none
                           below: 0 for a convex model listed outward,
                           nfacets when inverted */
} geo_conv3_result;

/* conv3(P, G) ("Tests of graphic elements"): for each facet, the exact side (geo_nf_facet_
 * sign) of every vertex not in that facet, with the paper's two flags
 * (l: some vertex below, r: some vertex above); the facet is settled as
 * soon as both are raised and the test stops at the first such facet.
 * Vertices exactly on a facet's plane raise neither flag. O(nfacets ·
 * nverts) in the worst (convex) case: the test is inherently per facet ×
 * vertex. Reports progress and checks cancellation through ctx (may be
 * NULL). Returns 0 with *ret filled, -ECANCELED or -ENOMEM (one
 * nverts-sized scratch array); ret is untouched on error. */
int geo_conv3(const geo_poly *p, const geo_ctx *ctx, geo_conv3_result *ret);

/* Convexity of facet f's polygon, exact: in the projection along the
 * facet's dominant normal axis, every corner turns the polygon's way or
 * is straight (orient2d ≥ 0 relative to the polygon's orientation), at
 * least one turns strictly, and the boundary winds around once (the edge
 * directions change sign along the other axes at most twice), which rules
 * out star-shaped self-overlapping cycles. For a facet that is not exactly
 * planar, this is the convexity of its projection. */
bool geo_facet_is_convex(const geo_poly *p, uint32_t f);

#endif
