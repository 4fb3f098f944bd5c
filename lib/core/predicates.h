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

#include <math.h>

/* Sign of (d − a) · ((b − a) × (c − a)): +1 when d lies on the side the
 * right-hand normal of the triangle a, b, c points to (for a facet listed
 * counter-clockwise seen from outside: d is outside), −1 on the other side,
 * 0 when the four points are exactly coplanar. This is nf3 of "Tests of graphic elements". */
int geo_orient3d(const double a[3], const double b[3], const double c[3],
                 const double d[3]);

/* geo_orient3d(a, b, c, d) for many d against one triangle a, b, c (the
 * sides of a polygon's vertices against another facet's reference plane):
 * n = (b − a) × (c − a) is formed once in doubles, and each query is one
 * dot product (d − a) · n with its own forward error bound. Each of the
 * six monomials ±(d − a)ᵢ(b − a)ⱼ(c − a)ₖ of the determinant passes at
 * most 8 roundings (three differences, the product and difference in n,
 * the product with d − a, two sums), so the computed value is within
 * γ₈·P of the exact one, P the sum of the monomials' magnitudes; P is
 * computed from the same rounded factors with 8 roundings of its own, so
 * 10u·P̂ (u = 2⁻⁵³) bounds the error. Above that bound (and above 2⁻⁹⁰⁰,
 * where products may underflow) the sign is exact; otherwise, and for
 * NaN or overflow, the answer comes from geo_orient3d. The answer is
 * always geo_orient3d(a, b, c, d). The struct points to a, b, c (not
 * copied: they must stay unchanged while it is used); read-only use is
 * thread-safe. */
typedef struct geo_orient3d_plane {
    const double *a, *b, *c;
    double n[3]; /* (b − a) × (c − a), rounded */
    double m[3]; /* |products| summed per component of n, rounded */
} geo_orient3d_plane;

/* Inline: the pair search forms two per candidate pair, and the call
 * and its loop cost more than the arithmetic. */
static inline void geo_orient3d_plane_init(geo_orient3d_plane *pl,
                                           const double a[3],
                                           const double b[3],
                                           const double c[3])
{
    pl->a = a, pl->b = b, pl->c = c;
    double ba0 = b[0] - a[0], ba1 = b[1] - a[1], ba2 = b[2] - a[2];
    double ca0 = c[0] - a[0], ca1 = c[1] - a[1], ca2 = c[2] - a[2];
    double p1 = ba1 * ca2, p2 = ba2 * ca1;
    pl->n[0] = p1 - p2;
    pl->m[0] = fabs(p1) + fabs(p2);
    p1 = ba2 * ca0, p2 = ba0 * ca2;
    pl->n[1] = p1 - p2;
    pl->m[1] = fabs(p1) + fabs(p2);
    p1 = ba0 * ca1, p2 = ba1 * ca0;
    pl->n[2] = p1 - p2;
    pl->m[2] = fabs(p1) + fabs(p2);
}

static inline int geo_orient3d_plane_sign(const geo_orient3d_plane *pl,
                                          const double d[3])
{
    const double *a = pl->a;
    double x0 = d[0] - a[0], x1 = d[1] - a[1], x2 = d[2] - a[2];
    double det = x0 * pl->n[0] + x1 * pl->n[1] + x2 * pl->n[2];
    double perm =
        fabs(x0) * pl->m[0] + fabs(x1) * pl->m[1] + fabs(x2) * pl->m[2];
    if (fabs(det) > 10.0 * 0x1.0p-53 * perm && fabs(det) > 0x1.0p-900)
        return det > 0 ? 1 : -1;
    return geo_orient3d(pl->a, pl->b, pl->c, d);
}

/* The exact path of geo_orient2d (expansion arithmetic), for its inline
 * filter below; callers use geo_orient2d. */
int geo_orient2d_exact(const double a[2], const double b[2],
                       const double c[2]);

/* Sign of (b − a) × (c − a) in the plane: +1 when a, b, c turn
 * counter-clockwise (c left of the directed line a→b), −1 clockwise,
 * 0 when exactly collinear. Only [0] and [1] of each point are read.
 * Inline: Shewchuk's filter (3 + 16u)u on the sum of the two products'
 * magnitudes; the exact path out of line. */
static inline int geo_orient2d(const double a[2], const double b[2],
                               const double c[2])
{
    double left = (a[0] - c[0]) * (b[1] - c[1]);
    double right = (a[1] - c[1]) * (b[0] - c[0]);
    double det = left - right;
    double bound = (3.0 + 16.0 * 0x1.0p-53) * 0x1.0p-53 *
                   (fabs(left) + fabs(right));
    if (fabs(det) > bound && fabs(det) > 0x1.0p-900)
        return det > 0 ? 1 : -1;
    return geo_orient2d_exact(a, b, c);
}

/* The exact path of geo_orient2d_proj (expansion arithmetic), for its
 * inline filter below; callers use geo_orient2d_proj. */
int geo_orient2d_proj_exact(const double a[3], const double b[3],
                            const double c[3], int drop);

/* orient2d of 3D points projected by dropping coordinate `drop` (0, 1 or
 * 2); the remaining axes keep their cyclic order (drop z: x,y; drop x:
 * y,z; drop y: z,x), so a counter-clockwise triangle seen from the +drop
 * axis gives +1. Inline: the filter of geo_orient2d (Shewchuk's bound
 * (3 + 16u)u on the sum of the two products' magnitudes) on the
 * projected coordinates in place; the exact path out of line. */
static inline int geo_orient2d_proj(const double a[3], const double b[3],
                                    const double c[3], int drop)
{
    int u = drop == 2 ? 0 : drop + 1, v = drop == 0 ? 2 : drop - 1;
    double left = (a[u] - c[u]) * (b[v] - c[v]);
    double right = (a[v] - c[v]) * (b[u] - c[u]);
    double det = left - right;
    double bound = (3.0 + 16.0 * 0x1.0p-53) * 0x1.0p-53 *
                   (fabs(left) + fabs(right));
    if (fabs(det) > bound && fabs(det) > 0x1.0p-900)
        return det > 0 ? 1 : -1;
    return geo_orient2d_proj_exact(a, b, c, drop);
}

/* geo_orient2d_proj(a, b, c, drop) for many c against one line a → b
 * (the vertices of a facet against a shared edge): b − a is formed once,
 * each query is (b − a) × (c − a) in the projection. Each of its two
 * monomials passes at most 4 roundings (two differences, the product, the
 * difference), so the computed value is within γ₄·P of the exact one, P
 * the sum of the monomials' magnitudes; P is computed from the same
 * rounded factors with 4 roundings of its own, so 6u·P̂ bounds the error.
 * Above that bound (and above 2⁻⁹⁰⁰) the sign is exact; otherwise, and
 * for NaN or overflow, the answer comes from geo_orient2d_proj. The
 * answer is always geo_orient2d_proj(a, b, c, drop). The struct points to
 * a and b (not copied); read-only use is thread-safe. */
typedef struct geo_orient2d_line {
    const double *a, *b;
    int drop, u, v;  /* dropped axis; the kept ones in cyclic order */
    double du, dv;   /* b − a in the kept axes, rounded */
} geo_orient2d_line;

static inline void geo_orient2d_line_init(geo_orient2d_line *l,
                                          const double a[3],
                                          const double b[3], int drop)
{
    l->a = a, l->b = b, l->drop = drop;
    l->u = drop == 2 ? 0 : drop + 1;
    l->v = drop == 0 ? 2 : drop - 1;
    l->du = b[l->u] - a[l->u];
    l->dv = b[l->v] - a[l->v];
}

static inline int geo_orient2d_line_sign(const geo_orient2d_line *l,
                                         const double c[3])
{
    double xu = c[l->u] - l->a[l->u], xv = c[l->v] - l->a[l->v];
    double left = l->du * xv, right = l->dv * xu;
    double det = left - right;
    if (fabs(det) > 6.0 * 0x1.0p-53 * (fabs(left) + fabs(right)) &&
        fabs(det) > 0x1.0p-900)
        return det > 0 ? 1 : -1;
    return geo_orient2d_proj(l->a, l->b, c, l->drop);
}

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

/* Exact sign of n · (p − p0) for the given doubles (the point + normal
 * form nfN of "Tests of graphic elements"): the differences p − p0 are formed exactly (two-term
 * expansions), so no rounding of an offset d = −n·p0 enters the answer.
 * +1 when p lies on the side n points to, −1 on the other side, 0 exactly
 * on the plane through p0 perpendicular to n. n = 0 gives 0. */
int geo_normal_sign(const double p0[3], const double n[3], const double p[3]);

/* The exact side of plane q of the point where planes a, b and c meet
 * (each plane a·x+b·y+c·z+d as four doubles taken as exact; normals of
 * any length): +1 when that point lies on the side q's normal points to,
 * −1 on the other side, 0 exactly on q; also 0 when the normals of a, b,
 * c are linearly dependent (they meet in no single point). The point is
 * never rounded: the answer is sign(det[a; b; c; q]) · sign(det of the
 * three normals), the first by expansion arithmetic when its filter
 * fails. Used to decide vertex-plane incidences of half-space
 * intersections (lib/core/halfspace.h). */
int geo_plane_meet_sign(const double a[4], const double b[4],
                        const double c[4], const double q[4]);

/* The point where planes a, b and c meet, prepared for many sides
 * (geo_meet_side) against other planes: det[a; b; c; q] is linear in q,
 * so its cofactors along q's row and their error bounds are taken once,
 * and the sign of the normals' determinant is decided once, exactly. a, b
 * and c must stay in place while m is used. */
typedef struct geo_meet {
    const double *a, *b, *c;
    double cof[4]; /* det[a; b; c; q] = Σ q[j] · cof[j] */
    double per[4]; /* the permanents bounding each cofactor's error */
    int s3;        /* sign of det of the normals of a, b, c */
} geo_meet;

void geo_meet_prepare(const double a[4], const double b[4],
                      const double c[4], geo_meet *m);

/* geo_plane_meet_sign(m->a, m->b, m->c, q), always the same answer: a
 * filtered sum of four products, the full predicate when the filter
 * cannot decide. */
int geo_meet_side(const geo_meet *m, const double q[4]);

#endif
