/* cut.h — cutting a polyhedron by a plane (Palachev 2012, §3): keep the part
 * where plane(p) = a·x+b·y+c·z+d ≤ 0, close it with new facets lying on
 * the plane whose outward normal is the plane's normal.
 *
 * The input is any closed, consistently oriented, manifold polyhedron
 * (convex or not, facets convex or not). The section may have several
 * components (each becomes one new facet, or several coplanar simple
 * facets when it has holes or its boundary passes a vertex twice: a
 * facet cannot have holes; see lib/cut/region_split.h), an old facet may fall into
 * several pieces, vertices and edges may lie exactly on the plane, and
 * whole facets may lie in it (a facet in the plane whose outward normal is
 * the plane's normal ends up inside a new facet; one facing the other way
 * is dropped with the removed part; when nothing is cut every facet stays
 * as it is). A plane that misses the solid, or only touches it at a
 * vertex, an edge or a facet, gives an unchanged or an empty result,
 * reported as such.
 *
 * Exactness: the side of every vertex is decided once by geo_plane_sign on
 * the plane's coefficients as given (not normalised), and every facet and
 * the new facets reuse that decision. The order of the crossings along a
 * facet's section line is decided exactly (geo_plane_crossing_cmp), so it
 * never contradicts the sides. Only the positions of the new vertices are
 * rounded (each edge's crossing is computed once and shared by both of
 * its facets).
 *
 * The split of a section is decided so that it holds for the exact
 * crossing points as well as for their rounded positions (each crossing
 * carries a bound on its rounding), so no diagonal grazes a vertex.
 *
 * Kept parts that no valid polyhedron represents are refused with
 * -ENOTSUP and a message, never returned: the plane touching from inside
 * a reflex edge lying in it (two pieces sharing only that edge), the apex
 * of a cavity (the cavity meeting the new facet in one point), or a
 * vertex on the plane left with two separate fans of facets (two parts
 * meeting in one point); two vertices at one position would count as a
 * contact, so duplicating does not help. The message says why and that
 * moving the plane a little either way (plane[3] larger: apart, smaller:
 * joined) gives a valid cut.
 *
 * Thread safety: geo_cut is reentrant; the input is only read. */
#ifndef GEO_CUT_H
#define GEO_CUT_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"
#include "topo.h"

typedef struct geo_cut_opts {
    /* Palachev 2012, §3.4 (facet merging): index of the "main" facet, which may
     * be non-planar; all its vertices must lie on the plane or on the
     * removed side (≥ 0), it is removed and replaced by the new facet,
     * and the section must have exactly one component. GEO_NONE (the
     * default from geo_cut_opts_default) for an ordinary cut. The
     * section must also be one facet: one with a hole is refused. */
    uint32_t main_facet;
    /* Optional topology of the input (geo_topo_build of the same poly) to
     * save rebuilding it; NULL builds it. Not modified. */
    const geo_topo *topo;
    /* Remove on-plane vertices that end up in exactly two facets (they lie
     * on the straight edge between those facets; the validity rules want
     * every vertex in ≥ 3 facets). Default true. */
    bool drop_hanging;
} geo_cut_opts;

typedef struct geo_cut_report {
    bool unchanged;             /* no vertex on the removed side */
    bool empty;                 /* no vertex on the kept side */
    uint32_t components;        /* section components (connected parts) */
    uint32_t new_facets;        /* facets created on the plane: one per
                                   component, more for one with holes */
    uint32_t first_new_facet;   /* index of the first of them in the
                                   output (they come last), or GEO_NONE */
    uint32_t split_facets;      /* old facets that were cut */
    uint32_t pieces;            /* facets those became (≥ split_facets) */
    uint32_t removed_facets;    /* old facets dropped whole */
    uint32_t new_vertices;      /* crossing points created (before the
                                   hanging ones are dropped) */
    uint32_t removed_vertices;  /* old vertices not in the result */
    uint32_t hanging_dropped;   /* vertices dropped as hanging */
    double volume_before, volume_after;
} geo_cut_report;

/* Fills the defaults: main_facet GEO_NONE, topo NULL, drop_hanging true. */
void geo_cut_opts_default(geo_cut_opts *opts);

/* Cuts p by plane (a, b, c, d; (a, b, c) non-zero, need not be unit) and
 * stores the kept part in out (which must not be p; its previous contents
 * are replaced). Kept facets keep their planes; cut facets' pieces keep
 * the old facet's plane; the new facets get the plane normalised. Output
 * order: the kept old facets and pieces in the order of the old facets,
 * then the new facets; vertices renumbered densely, old ones first in
 * their old order.
 *
 * opts NULL means the defaults; ctx may be NULL (progress and
 * cancellation); rep may be NULL; err may be NULL.
 *
 * Returns 0 (also for an unchanged or empty result: see rep), or
 *  -EINVAL  bad input: plane not finite or zero normal, indices invalid,
 *           the model not a closed oriented manifold, a facet whose
 *           section is inconsistent (a self-intersecting facet, or a
 *           section whose boundaries cross), a main facet with a vertex
 *           on the kept side, or a §3.4 cut whose section is not one
 *           component of one facet;
 *  -ENOTSUP the result cannot be represented (see above), or a split
 *           facet that is not simple once rounded (move the plane);
 *  -ENOMEM, -ECANCELED;
 * with err naming the place ("facets[12]: ..."). On error out is left
 * empty. Complexity: O(n) for the classification plus O(k log k) for the
 * k crossings, plus the split of a section with holes (README "Plane
 * cut"); memory O(n). */
int geo_cut(const geo_poly *p, const double plane[4],
            const geo_cut_opts *opts, const geo_ctx *ctx, geo_poly *out,
            geo_cut_report *rep, geo_err *err);

#endif
