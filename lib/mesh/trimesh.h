/* trimesh.h — a small dynamic triangle mesh for local refinement: split a
 * triangle at a point, split an edge at a point, flip an edge, with the
 * adjacency kept in a hash of directed edges.
 *
 * Triangles are vertex index triples, counter-clockwise seen from
 * outside; triangle t's corner k stands for the directed edge
 * t[k] → t[(k+1)%3] (half-edge id 3t + k). A directed edge is stored at
 * most once; an operation that would store one twice is refused, so the
 * mesh stays an oriented 2-manifold with boundary if it started as one.
 * Removed triangles stay in the array marked dead (ids are stable).
 *
 * Ownership: the mesh owns its arrays (geo_tmesh_init allocates,
 * geo_tmesh_destroy releases). Not thread-safe. */
#ifndef GEO_TRIMESH_H
#define GEO_TRIMESH_H

#include <stdbool.h>
#include <stdint.h>

#include "edgemap.h"
#include "poly.h"

typedef struct geo_tmesh {
    double (*v)[3];
    uint32_t nv, cap_v;
    uint32_t (*t)[3];
    uint8_t *dead;
    uint8_t *tag;   /* per triangle, the caller's; split pieces inherit */
    uint32_t nt, cap_t;
    geo_edgemap he; /* directed edge → half-edge id */
} geo_tmesh;

/* A mesh with nv vertices copied from xyz (3·nv doubles) and no
 * triangles. 0 or -ENOMEM. */
int geo_tmesh_init(geo_tmesh *m, const double *xyz, uint32_t nv);

/* Releases everything; m may be zeroed. */
void geo_tmesh_destroy(geo_tmesh *m);

/* Appends a vertex; returns its index or -ENOMEM. */
int64_t geo_tmesh_add_vertex(geo_tmesh *m, const double p[3]);

/* Appends triangle (a, b, c) with tag `tag`; returns its id, -EEXIST
 * when one of its directed edges is already stored (nothing changes), or
 * -ENOMEM. */
int64_t geo_tmesh_add(geo_tmesh *m, uint32_t a, uint32_t b, uint32_t c,
                      uint8_t tag);


/* Half-edge id of directed edge a → b, or UINT32_MAX. */
static inline uint32_t geo_tmesh_find(const geo_tmesh *m, uint32_t a,
                                      uint32_t b)
{
    return geo_edgemap_get(&m->he, geo_edge_key(a, b));
}

/* Splits live triangle t at new vertex x (already added) into three.
 * 0 or -ENOMEM (t unchanged). */
int geo_tmesh_split_tri(geo_tmesh *m, uint32_t t, uint32_t x);

/* Splits edge a–b at new vertex x: each live triangle on either side is
 * split in two. 0, -ENOENT (no such edge) or -ENOMEM. */
int geo_tmesh_split_edge(geo_tmesh *m, uint32_t a, uint32_t b, uint32_t x);

/* Flips the interior edge a–b (triangles (a,b,c) and (b,a,d) become
 * (a,d,c) and (b,c,d)). Returns 0, -ENOENT (not an interior edge),
 * -EEXIST (c–d already an edge) or -ENOMEM (unchanged on every error).
 * Geometric legality is the caller's business. */
int geo_tmesh_flip(geo_tmesh *m, uint32_t a, uint32_t b);

/* The vertex opposite half-edge h (in its triangle). */
static inline uint32_t geo_tmesh_opposite(const geo_tmesh *m, uint32_t h)
{
    return m->t[h / 3][(h % 3 + 2) % 3];
}

/* Unit normal of triangle t (zero for a degenerate one); returns twice
 * its area. */
double geo_tmesh_normal(const geo_tmesh *m, uint32_t t, double ret_n[3]);

/* Scratch of geo_tmesh_clashes, reusable across calls on one mesh:
 * zero-initialise, release with geo_tmesh_probe_destroy. */
typedef struct geo_tmesh_probe {
    uint32_t *vstamp, *vloc;  /* per mesh vertex: visit stamp, local id */
    uint32_t cap_v;
    uint32_t *tstamp;         /* per triangle: visit stamp */
    uint32_t cap_t;
    uint32_t stamp;
    uint32_t *queue, *tris, *gv; /* BFS vertices, triangles, local → mesh */
    uint32_t cap_q, cap_tris, cap_gv;
    geo_poly *p;              /* the neighbourhood as a polyhedron */
    double (*box)[6];         /* per facet of p: bounding box */
    struct geo_facet_shape *shape; /* per facet of p (lib/inspect/selfint.h) */
    uint8_t *has_shape;       /* whether shape[f] is computed */
    uint32_t cap_f;
} geo_tmesh_probe;

void geo_tmesh_probe_destroy(geo_tmesh_probe *pr);

/* Stands for the vertex at position x in geo_tmesh_clashes' new
 * triangles (not yet in the mesh). */
#define GEO_TMESH_NEWV (UINT32_MAX - 1)

/* Whether replacing the live triangles old[0..nold) by newt[0..nnew)
 * would make the surface touch or cross itself near them, decided
 * exactly with lib/inspect/selfint.h's definition (shared vertices and edges do
 * not count; a degenerate new triangle counts as a clash). Vertex ids in
 * newt are mesh vertices or GEO_TMESH_NEWV, which stands at x; when
 * moved is a mesh vertex, it is taken at x instead of its position (and
 * x is then not a new vertex). The neighbourhood is every live triangle
 * incident to a vertex within `rings` − 1 edges of old's vertices
 * (found by walking vertex fans, both ways around at a boundary);
 * triangles farther away are not looked at. Returns 1 (clash), 0 (none)
 * or -ENOMEM. The mesh is not changed. */
int geo_tmesh_clashes(const geo_tmesh *m, geo_tmesh_probe *pr,
                      const uint32_t *old, uint32_t nold,
                      const uint32_t (*newt)[3], uint32_t nnew,
                      uint32_t moved, const double x[3], uint32_t rings);

#endif
