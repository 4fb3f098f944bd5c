/* clusters.h — collapsing clusters of vertices joined by very short edges
 * (Palachev 2012, §4.1 and the paper's open §4.3.6): a scanner splits a vertex
 * where four or more facets meet into a heap of degree-3 vertices joined
 * by edges of a few µm; each heap becomes one vertex, and the planarity of
 * the facets around it is restored by the re-planarization of
 * lib/replanar/replanar.h.
 *
 * Steps: clusters are the connected groups (≥ 2 vertices) of the graph of
 * edges shorter than the radius; each becomes one vertex placed at the
 * point nearest, in the least-squares sense, to the planes of the facets
 * around the cluster (Σ (n·x + d)² + λ|x − c|², c the cluster's centroid,
 * λ = 1e-3 per facet: a pull that only matters along directions the
 * nearly parallel planes of slivers leave undetermined); facets lose the
 * repeated vertices, and facets left with fewer than three vertices go.
 * The new vertices are then held fixed at those points while every other
 * vertex and every plane is re-planarized (schedule `scaled`, §4.3.2):
 * the point already fits its planes best, and holding it keeps the
 * re-planarization's moves at the size of the planes' residuals there.
 * The result is inspected (geo_inspect); a cluster whose collapse leaves
 * the model invalid (not manifold, a facet intersecting another, not
 * planar, inverted) or moves a vertex farther than max_move is rolled
 * back and the rest redone, so nothing
 * invalid is ever returned: in the worst case the model comes back
 * unchanged with every cluster reported rolled back.
 *
 * Conventions of lib/core/poly.h; lengths in mm. Complexity: O(n) to find the
 * clusters, one re-planarization (O(steps × active corners)) and one
 * inspection (O(n log n)) per attempt, at most max_attempts attempts.
 * Reentrant; p is changed in place only on success. */
#ifndef GEO_CLUSTERS_H
#define GEO_CLUSTERS_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"

typedef struct geo_collapse_opts {
    /* Edges shorter than this join a cluster, mm; 0 means rel_radius ×
     * the model's size (bounding-box diagonal). */
    double radius;
    double rel_radius;     /* [see geo_collapse_opts_default] */
    /* Largest move of any vertex the collapse and re-planarization may
     * cause, mm; 0 means 2 × the radius. A vertex between facets at a
     * small angle moves by the planes' residual divided by that angle
     * (lib/replanar/replanar.h), so holding a collapsed vertex can push it far;
     * the clusters near such a vertex are rolled back. */
    double max_move;
    uint32_t max_attempts; /* collapse + check rounds [4] */
    uint32_t max_steps;    /* re-planarization step budget [400] */
} geo_collapse_opts;

/* Fills the defaults. */
void geo_collapse_opts_default(geo_collapse_opts *o);

typedef struct geo_collapse_report {
    double radius;             /* the radius used, mm */
    uint32_t clusters;         /* found */
    uint32_t collapsed;        /* kept in the result */
    uint32_t rolled_back;      /* undone: the result was invalid with them */
    uint32_t attempts;
    uint32_t vertices_before, vertices_after;
    uint32_t facets_before, facets_after;
    double max_displacement;   /* largest move of a surviving vertex, mm */
    uint32_t replanar_steps;   /* of the final re-planarization */
    /* The clusters: cluster c has input vertices
     * cverts[cstart[c] .. cstart[c+1]) and became output vertex cnew[c]
     * (GEO_NONE when rolled back). */
    uint32_t *cstart, *cverts, *cnew;
    /* vertices_before entries: each input vertex's index in the result
     * (a collapsed cluster's vertices all map to its new vertex), or
     * GEO_NONE when it is gone */
    uint32_t *vmap;
} geo_collapse_report;

/* Releases the report's arrays and zeroes it; accepts NULL. */
void geo_collapse_report_clear(geo_collapse_report *r);

/* Collapses the clusters of p (see above). opts NULL means defaults;
 * report may be NULL; *report is overwritten, never read (release an
 * earlier one with geo_collapse_report_clear first). Returns 0 (p changed in place, or left as it was
 * when nothing could be collapsed), -EINVAL when p is not a closed
 * manifold with valid indices, -ENOMEM, -ECANCELED (p unchanged). */
int geo_collapse(geo_poly *p, const geo_collapse_opts *opts,
                          const geo_ctx *ctx, geo_collapse_report *report,
                          geo_err *err);

#endif
