/* predicates.h — orientation predicates whose sign is always right.
 *
 * Usage: call geo_orient3d / geo_orient2d / geo_plane_sign wherever a sign
 * decides topology (which side of a plane, does an edge cross a facet).
 * Each evaluates the determinant in double precision first and returns at
 * once when the result's magnitude exceeds a proven forward error bound
 * (Shewchuk's "A" bounds, Shewchuk 1997); otherwise it recomputes the
 * determinant exactly with floating-point expansion arithmetic. The answer
 * is the sign of the exact real-number determinant of the given doubles:
 * no epsilon, no tolerance. Inputs must be finite and not subnormal in
 * products (coordinates of scanned models in millimetres are far from that).
 *
 * Expansion arithmetic, not GMP: the fallback needs only a few hundred
 * doubles on the stack, allocates nothing, keeps lib/ free of dependencies
 * and is fast enough that the rare exact path never shows in a profile.
 *
 * All functions are pure, reentrant and thread-safe. They require IEEE-754
 * binary64 with round-to-nearest and no fused multiply-add contraction
 * (the Makefile builds with -ffp-contract=off). */
#ifndef GEO_PREDICATES_H
#define GEO_PREDICATES_H

/* Sign of (d − a) · ((b − a) × (c − a)): +1 when d lies on the side the
 * right-hand normal of the triangle a, b, c points to (for a facet listed
 * counter-clockwise seen from outside: d is outside), −1 on the other side,
 * 0 when the four points are exactly coplanar. This is seed 003's nf3. */
int geo_orient3d(const double a[3], const double b[3], const double c[3],
                 const double d[3]);

/* Sign of (b − a) × (c − a) in the plane: +1 when a, b, c turn
 * counter-clockwise (c left of the directed line a→b), −1 clockwise,
 * 0 when exactly collinear. Only [0] and [1] of each point are read. */
int geo_orient2d(const double a[2], const double b[2], const double c[2]);

/* orient2d of 3D points projected by dropping coordinate `drop` (0, 1 or
 * 2); the remaining axes keep their cyclic order (drop z: x,y; drop x:
 * y,z; drop y: z,x), so a counter-clockwise triangle seen from the +drop
 * axis gives +1. */
int geo_orient2d_proj(const double a[3], const double b[3], const double c[3],
                      int drop);

/* Exact sign of plane[0]·p[0] + plane[1]·p[1] + plane[2]·p[2] + plane[3]
 * for the given doubles (the plane's coefficients are taken as exact):
 * +1 outside (the side the normal points to), −1 inside, 0 exactly on it. */
int geo_plane_sign(const double plane[4], const double p[3]);

/* Exact comparison of coordinate k (0, 1 or 2) of two points X and Y that
 * lie on the plane (coefficients taken as exact). Each point is given as
 * x0, x1: when x1 is NULL, X is x0 itself (which the caller knows to lie
 * on the plane); otherwise X is the crossing of segment x0x1 with the
 * plane, and x0, x1 must lie strictly on opposite sides (geo_plane_sign
 * −1/+1). Likewise Y from y0, y1. Returns −1, 0, +1 as X[k] is less than,
 * equal to, greater than Y[k] for the exact real crossing points (no
 * rounding of the crossings is involved). Used to order the crossings of
 * a plane cut along a facet's section line. */
int geo_plane_crossing_cmp(const double plane[4], const double x0[3],
                           const double x1[3], const double y0[3],
                           const double y1[3], int k);

/* Exact sign of n · (p − p0) for the given doubles (seed 003's point +
 * normal form nfN): the differences p − p0 are formed exactly (two-term
 * expansions), so no rounding of an offset d = −n·p0 enters the answer.
 * +1 when p lies on the side n points to, −1 on the other side, 0 exactly
 * on the plane through p0 perpendicular to n. n = 0 gives 0. */
int geo_normal_sign(const double p0[3], const double n[3], const double p[3]);

#endif
