/* stats.h — the inspection statistics of a polyhedron (spec algorithms.md
 * §2), computed in one call: topology counts, orientation, measures,
 * facet shape defects, self-intersections, near-coplanar neighbours,
 * vertex degrees and clusters of short edges.
 *
 * Definitions (each field below refers to these):
 * - edges: distinct undirected edges. boundary edge: one corner (a hole's
 *   border); non-manifold edge: three or more corners; holes: boundary
 *   loops (geo_topo_boundary_loops). closed: every edge has exactly two
 *   corners. Non-manifold vertex: its facets form several fans or it is on
 *   a non-manifold edge.
 * - orientation, inconsistent_facets, shells: lib/inspect/orient.h.
 * - inverted facet: its polygon winds against its own stored plane (the
 *   Newell normal of its vertex cycle and the plane's normal have a
 *   negative dot product) — a facet turned over, e.g. by a vertex moved
 *   across it during re-planarization (Palachev 2012, §4.3.4–4.3.5), or a model
 *   whose planes were not negated with their facets.
 * - degenerate facet: fewer than three distinct points, or all its points
 *   on one line (exact); zero area follows. Degenerate edge: its two
 *   vertices (distinct indices) at the same position.
 * - non-convex facet: a non-degenerate facet whose polygon has a reflex
 *   corner or touches itself (flat corners allowed), exact in its 2D
 *   projection (lib/inspect/selfint.h).
 * - self-intersections: lib/inspect/selfint.h (pairs of facets plus facets whose
 *   own polygon intersects itself); self_intersecting_facets: facets in
 *   any of those.
 * - near-coplanar pair: two facets sharing an edge whose unit Newell
 *   normals differ by less than the threshold angle (across a disagreeing
 *   edge one normal is negated first): a scanner's split facets.
 * - vertex degree: the number of distinct edges at the vertex.
 * - short-edge cluster: a connected group of ≥ 2 vertices joined by edges
 *   shorter than the radius — the "heaps" of Palachev 2012, §4.1, where a
 *   scanner splits one true vertex of degree > 3. Default radius 1e-3 of
 *   the model's bounding-box diagonal (10 µm on a 10 mm stone): ten times
 *   a scanner's silhouette noise, far below a cut's ordinary edges, and
 *   fixed by the model's size, so it does not shrink as a scan fragments
 *   (a fraction of the median edge length would: the median falls from
 *   0.27 mm on a true brilliant to 0.05 mm on its K=400 scan, hiding the
 *   very clusters it should count).
 * - valid: closed, no non-manifold vertex, every vertex in ≥ 3 facets,
 *   outward, no inverted facet, max_nonplanarity ≤ eps, no
 *   self-intersection, no degenerate facet.
 *
 * Complexity: O(n log n) overall (topology O(corners), BVH O(n log n),
 * degree and near-coplanar counts O(corners log)), the self-intersection
 * search dominating. Ownership: geo_stats holds malloc'd arrays released
 * by geo_stats_clear. Reentrant. */
#ifndef GEO_STATS_H
#define GEO_STATS_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "orient.h"
#include "poly.h"
#include "selfint.h"

#define GEO_STATS_NCOPLANAR 3

typedef struct geo_inspect_opts {
    geo_selfint_opts selfint;  /* pair cap (default 1000), tasks */
    double eps;                /* planarity tolerance, mm; 0 means
                                  geo_poly_eps(p) */
    double coplanar_deg[GEO_STATS_NCOPLANAR]; /* default 0.5, 1, 2 */
    double short_edge_radius;  /* mm; 0 means 1e-3 × model size */
} geo_inspect_opts;

/* Fills the defaults. */
void geo_inspect_opts_default(geo_inspect_opts *o);

typedef struct geo_stats {
    uint32_t vertices, edges, facets;
    bool closed;
    uint32_t boundary_edges, holes;
    uint32_t nonmanifold_edges, nonmanifold_vertices;
    uint32_t low_degree_vertices; /* in fewer than 3 facets (isolated too) */
    enum geo_orientation orientation;
    uint32_t inconsistent_facets;
    uint32_t inverted_facets; /* winding against their own plane */
    uint32_t shells;
    bool orientable;
    double volume;           /* signed, mm³ (geo_poly_volume) */
    double area;             /* mm² */
    double max_nonplanarity; /* mm (geo_poly_max_nonplanarity) */
    double eps;              /* the planarity tolerance used, mm */
    uint32_t nonconvex_facets, degenerate_facets, degenerate_edges;
    geo_selfint selfint;     /* count, capped sorted pairs, facet flags */
    uint32_t self_intersecting_facets;
    double coplanar_deg[GEO_STATS_NCOPLANAR];
    uint32_t near_coplanar[GEO_STATS_NCOPLANAR];
    uint32_t max_degree;
    uint32_t *degree_count;  /* max_degree + 1 entries: vertices per degree */
    double short_edge_radius;
    uint32_t short_edge_clusters;
    uint32_t short_edge_cluster_vertices; /* vertices in those clusters */
    bool valid;
} geo_stats;

/* Computes every statistic of p. opts NULL means defaults. ctx as for
 * geo_selfint_find (parallel loop, progress, cancel). On success 0 and
 * *ret owns its arrays (geo_stats_clear); on error (-EINVAL invalid
 * indices, -ENOMEM, -ECANCELED) *ret is zeroed and err set. */
int geo_inspect(const geo_poly *p, const geo_inspect_opts *opts,
                const geo_ctx *ctx, geo_stats *ret, geo_err *err);

/* Of geo_inspect's statistics only the counts, the topology (closed,
 * boundary and non-manifold edges and vertices) and the orientation
 * (orientation, inconsistent facets, shells, orientable); the rest zero.
 * For a caller that decides on these alone: it costs a topology build
 * (none when t, p's topology, is given), where geo_inspect adds the
 * self-intersection search. Errors as geo_inspect's (*ret zeroed). */
int geo_inspect_topology(const geo_poly *p, const geo_topo *t,
                         geo_stats *ret, geo_err *err);

/* Releases the arrays of s and zeroes it; accepts NULL. */
void geo_stats_clear(geo_stats *s);

#endif
