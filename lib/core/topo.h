/* topo.h — the adjacency of a geo_poly, built once in O(n) with a hash of
 * edges (Palachev 2012, §3.2.2 "preprocessing"; a corner-based half-edge
 * structure, equivalent to Baumgart's winged edge in Nesterenko).
 *
 * Corner c (a position in poly->fidx) stands for the directed edge from
 * its vertex to the next vertex of its facet. For each corner the topology
 * stores its facet, its mate (the corner of the other facet on the same
 * undirected edge) and the kind of that edge. For each vertex it stores its
 * corners, ordered around the vertex (one fan per connected sheet), and
 * whether the vertex is manifold.
 *
 * A geo_topo describes the geo_poly it was built from as it was then; any
 * change to the facets invalidates it. Ownership: geo_topo_build allocates,
 * geo_topo_free releases. Read-only use is thread-safe. */
#ifndef GEO_TOPO_H
#define GEO_TOPO_H

#include <stdint.h>

#include "poly.h"

#define GEO_NONE UINT32_MAX

enum geo_edge_kind {
    GEO_EDGE_INTERIOR = 0,    /* exactly one mate, running the other way */
    GEO_EDGE_FLIPPED = 1,     /* exactly one mate, running the same way:
                                 the two facets disagree on orientation */
    GEO_EDGE_BOUNDARY = 2,    /* no mate: a free edge (a hole's border) */
    GEO_EDGE_NONMANIFOLD = 3, /* three or more corners on this edge */
};

enum geo_vertex_kind {
    GEO_VERTEX_INTERIOR = 0,    /* its facets form one closed fan */
    GEO_VERTEX_BOUNDARY = 1,    /* one open fan (on a hole's border) */
    GEO_VERTEX_NONMANIFOLD = 2, /* several fans, or a non-manifold edge */
    GEO_VERTEX_ISOLATED = 3,    /* in no facet */
};

typedef struct geo_topo {
    uint32_t nverts, nfacets, ncorners;
    uint32_t *corner_facet; /* ncorners: facet owning each corner; NULL
                               from geo_topo_build_lean on triangles,
                               where it is c / 3 (read geo_topo_facet) */
    uint32_t *mate;         /* ncorners: mate corner or GEO_NONE */
    uint8_t *edge_kind;     /* ncorners: enum geo_edge_kind */
    uint32_t *vstart;       /* nverts + 1 offsets into vcorners */
    uint32_t *vcorners;     /* ncorners: each vertex's corners, in fan
                               order (consecutive corners share an edge)
                               where the vertex is manifold */
    uint8_t *vertex_kind;   /* nverts: enum geo_vertex_kind */

    uint32_t nedges;             /* distinct undirected edges */
    uint32_t nboundary_edges;    /* edges with one corner */
    uint32_t nnonmanifold_edges; /* edges with three or more corners */
    uint32_t nflipped_edges;     /* two corners, same direction */
    uint32_t nnonmanifold_vertices;
} geo_topo;

/* Builds the topology of p in O(corners) expected time. Returns NULL on
 * out-of-memory (err set). Facets must have valid indices
 * (geo_poly_validate_indices). */
geo_topo *geo_topo_build(const geo_poly *p, geo_err *err);

/* geo_topo_build of a model whose indices are checked first
 * (geo_poly_validate_indices): NULL with *ret_rc -EINVAL (bad indices)
 * or -ENOMEM, and err set. */
geo_topo *geo_topo_build_checked(const geo_poly *p, int *ret_rc,
                                 geo_err *err);

/* geo_topo_build_checked, but on a model of triangles only (facet f's
 * corners are 3f, 3f + 1, 3f + 2) corner_facet is left NULL: 4 bytes a
 * corner less, for callers that read it through geo_topo_facet only
 * (geo_inspect). */
geo_topo *geo_topo_build_lean(const geo_poly *p, int *ret_rc, geo_err *err);

/* Releases t; accepts NULL; returns NULL. */
geo_topo *geo_topo_free(geo_topo *t);

/* The facet owning corner c. */
static inline uint32_t geo_topo_facet(const geo_topo *t, uint32_t c)
{
    return t->corner_facet ? t->corner_facet[c] : c / 3;
}

/* The corner after / before c in its facet (cyclically). */
static inline uint32_t geo_topo_next(const geo_poly *p, const geo_topo *t,
                                     uint32_t c)
{
    uint32_t f = geo_topo_facet(t, c);
    return c + 1 < p->fstart[f + 1] ? c + 1 : p->fstart[f];
}

static inline uint32_t geo_topo_prev(const geo_poly *p, const geo_topo *t,
                                     uint32_t c)
{
    uint32_t f = geo_topo_facet(t, c);
    return c > p->fstart[f] ? c - 1 : p->fstart[f + 1] - 1;
}

/* The facet across the edge of corner c, or GEO_NONE (boundary or
 * non-manifold edge). */
static inline uint32_t geo_topo_neighbor(const geo_topo *t, uint32_t c)
{
    uint32_t m = t->mate[c];
    return m == GEO_NONE ? GEO_NONE : geo_topo_facet(t, m);
}

/* True when every edge is interior and every vertex manifold (a closed,
 * consistently oriented 2-manifold surface). */
static inline int geo_topo_is_closed_manifold(const geo_topo *t)
{
    return t->nboundary_edges == 0 && t->nnonmanifold_edges == 0 &&
           t->nflipped_edges == 0 && t->nnonmanifold_vertices == 0;
}

/* The boundary loops of p: each loop is a cycle of boundary corners, each
 * corner's edge ending where the next one's begins. Loops are split at
 * non-manifold boundary vertices (two holes touching at a vertex give two
 * loops): the walk turns within the fan of the facet it arrives by and
 * never crosses to another fan, and a closed walk that still comes back
 * to a vertex (each fan of a pinch leads from one hole into the other) is
 * cut there, so every closed loop passes each vertex once. A walk that
 * ends at a non-manifold edge is returned as it is (an open chain). On success *ret_start (nloops + 1 offsets) and *ret_corners are
 * malloc'd for the caller to free, and *ret_nloops set; returns 0 or
 * -ENOMEM (outputs untouched). */
int geo_topo_boundary_loops(const geo_poly *p, const geo_topo *t,
                            uint32_t **ret_start, uint32_t **ret_corners,
                            uint32_t *ret_nloops);

#endif
