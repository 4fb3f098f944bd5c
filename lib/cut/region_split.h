/* region_split.h — a planar region bounded by closed loops, split into
 * simple polygons along diagonals between its own points (no point is
 * added). Used for the new facets of a plane cut (lib/cut/cut.h): a facet of
 * facet-model/1 is a simple polygon without holes, so a section component
 * with holes, or one whose boundary touches itself at a point, becomes
 * several facets lying side by side in the plane.
 *
 * Input model. Points are 2D doubles taken as exact. The region lies to
 * the left of every loop: a counter-clockwise loop bounds a part of the
 * region from outside, a clockwise loop bounds a hole. Loops do not cross;
 * they may touch at points they share (same index): a hole touching the
 * outer loop or another hole, a part touching another part, a loop
 * visiting a point twice. Parts may be nested (an island inside a hole is
 * a part of its own). Two different indices at the same position are not
 * allowed (they would be a contact between different points).
 *
 * Output. Every part that has no hole and visits no point twice is
 * returned as it is (its loop, unchanged). Every other part is split:
 * each piece is a simple polygon (no point twice, edges meeting only at
 * consecutive points), counter-clockwise, and the pieces of a part tile
 * it exactly, two neighbouring pieces sharing one whole diagonal (same
 * two indices, opposite directions). A part with h holes gives at least
 * two pieces when h > 0; the split aims at few pieces (see
 * region_split.c for the method and why).
 *
 * Exactness: every decision is a sign of geo_orient2d or a comparison of
 * the given coordinates; no tolerance (with bounds, see geo_region_split).
 * Complexity: O(m log m) for the m points plus, per split part of n
 * points, O(n) ear tests in the usual case, each visiting the non-convex
 * corners in its triangle's box through a grid (O(n²) visits at worst,
 * for long thin fans), O(n) per hole for its bridge, O(n) for the merge;
 * classification of the holes O(Σ hole × part) over the pairs whose
 * boxes nest.
 *
 * Thread safety: reentrant; allocates its own scratch. */
#ifndef GEO_REGION_SPLIT_H
#define GEO_REGION_SPLIT_H

#include <stdint.h>

#include "ctx.h"

typedef struct geo_region_pieces {
    uint32_t nparts;     /* counter-clockwise loops: connected parts */
    uint32_t nholes;     /* clockwise loops */
    uint32_t nsplit;     /* parts that were split into several pieces */
    uint32_t nfallback;  /* split parts decided on the given positions
                            alone (see geo_region_split) */
    uint32_t npieces;
    uint32_t *start;     /* npieces + 1 offsets into idx */
    uint32_t *idx;       /* point indices of the pieces, counter-clockwise */
    uint32_t *part;      /* per piece: its part, 0 … nparts − 1, parts
                            numbered in the order of their loops */
} geo_region_pieces;

/* Splits the region bounded by nloops loops (loop l is points
 * loop_idx[loop_start[l] … loop_start[l + 1]), each of ≥ 3 points, indices
 * < npts) into simple pieces, stored in *ret (malloc'd arrays, release
 * with geo_region_pieces_clear; previous contents are not freed).
 *
 * perr (may be NULL): per point, a bound on how far (in each coordinate)
 * the point's true position may lie from pts[i] — the points of a plane
 * section are rounded crossings. With bounds, every choice that makes
 * geometry (bridge, ear, diagonal) is taken only when it holds for all
 * positions within them, so no diagonal passes within a bound of a point
 * (a straight run of the boundary stays straight, with no sliver across
 * it); only when that leaves no choice for a part is the part decided on
 * pts alone (counted in nfallback). Classification (loop orientation,
 * which hole lies in which part) is always exact on pts.
 *
 * Returns 0, or with err set and *ret zeroed:
 *  -EINVAL the loops do not bound a region as described above: a loop of
 *          fewer than 3 points or zero area, an index out of range, two
 *          indices at one position, a hole not inside any part, or a part
 *          for which no bridge or no ear exists (its boundary crosses
 *          itself); the message names the loop;
 *  -ENOMEM. */
int geo_region_split(const double (*pts)[2], const double *perr,
                     uint32_t npts, const uint32_t *loop_start,
                     const uint32_t *loop_idx, uint32_t nloops,
                     geo_region_pieces *ret, geo_err *err);

/* 1 when geo_region_split would change something (a loop is clockwise
 * or of zero area, passes a point twice, is shorter than 3 points or has
 * an index out of range), 0 when every loop is a simple part returned as
 * it is, -ENOMEM. O(m) for the m loop points plus O(npts) to allocate. */
int geo_region_needs_split(const double (*pts)[2], uint32_t npts,
                           const uint32_t *loop_start, const uint32_t *loop_idx,
                           uint32_t nloops);

/* Frees the arrays of r and zeroes it; accepts NULL. */
void geo_region_pieces_clear(geo_region_pieces *r);

#endif
