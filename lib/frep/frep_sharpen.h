/* frep_sharpen.h — recovering the hard edges of an F-rep object in a
 * triangle mesh of its surface.
 *
 * Where a union or an intersection switches from one smooth piece of F to
 * another (lib/frep/frep.h, geo_frep_run_piece) the surface has a crease. A
 * mesh whose vertices all lie on the surface but never on a crease cuts
 * every crease off with a chamfer about one edge wide. Here every edge
 * whose two ends lie on different pieces G₁, G₂ (a hard edge of the
 * mesh in Vyatkin's sense: it spans a crease) gets a point X on the
 * crease {G₁ = 0, G₂ = 0} — the least-norm Gauss–Newton solution from the
 * point S = (s(P)·Q + s(Q)·P)/(s(P)+s(Q)) of the paper, s being the mean
 * length of the edges at P and Q — which must also lie on the surface
 * (F(X) = 0: no third piece cuts the crease there) and near the edge. The
 * edge is then split at X, each of its triangles into two (fig. 12), or,
 * when X is within a quarter of the edge from an end that lies on one
 * piece only, that end is moved onto X if none of its triangles turns over.
 * When the two pieces have no crease there — the edge jumps over a third
 * piece the rays never hit, as a wall parallel to the rays does over a
 * vertical facet — S is moved onto F = 0 along ∇F instead; landing on a
 * piece neither end lies on, it splits the edge into two that each span a
 * real crease, recovered in the next round (Vyatkin's faces
 * perpendicular to the camera plane: without this they stay chamfered,
 * and refining them folds the mesh).
 * A triangle whose corners lie on three pieces pairwise sharing a crease
 * spans a corner of the object: it is split at the point where the three
 * pieces meet (Newton on three equations), under the same checks; each
 * corner gets one vertex (four or more pieces may meet at one point), a
 * later triangle spanning the same corner being flipped onto it. Every
 * operation is checked exactly before it is applied: its new triangles
 * must not touch or cross any triangle within two rings of it
 * (geo_tmesh_clashes, lib/inspect/selfint.h's definition), so recovery never
 * folds the mesh onto itself; refused operations are counted. Rounds
 * repeat (at most 4) until no edge spans two pieces. Edges along a
 * recovered crease join points on it, so the crease is represented by
 * mesh edges lying on it exactly (to rounding) instead of a chamfer.
 *
 * Ownership: m is modified in place (vertices appended or moved, facets
 * rewritten as triangles in a new order); it must be a triangle mesh. 0,
 * -EINVAL (a non-triangle facet), -ENOMEM or -ECANCELED (m unchanged on
 * error). Progress runs 0 → 1 over the rounds; cancellation is checked
 * every few thousand triangles. Not thread-safe for one m. */
#ifndef GEO_FREP_SHARPEN_H
#define GEO_FREP_SHARPEN_H

#include <stdint.h>

#include "ctx.h"
#include "frep.h"
#include "poly.h"

typedef struct geo_sharpen_stats {
    uint32_t nedge_splits;  /* edges split at a crease point */
    uint32_t nsnaps;        /* vertices moved onto a crease */
    uint32_t ncorners;      /* triangles split at a corner point */
    uint32_t nmiddle_splits; /* edges split at a piece between their ends */
    uint32_t ncorner_flips; /* edges flipped onto an existing corner */
    uint32_t nrejected;     /* operations refused by the checks */
    uint32_t nrounds;
} geo_sharpen_stats;

/* Recovers the creases of f in mesh m (see above). tags, when not NULL
 * and *tags not NULL, is a malloc'd array of one byte per facet that is
 * carried along: on success it is replaced by a new malloc'd array for
 * the new facets (a split facet's pieces keep its byte). st may be
 * NULL. */
int geo_frep_sharpen(const geo_frep *f, geo_poly *m, uint8_t **tags,
                     const geo_ctx *ctx, geo_sharpen_stats *st, geo_err *err);

#endif
