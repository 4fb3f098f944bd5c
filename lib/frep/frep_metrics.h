/* frep_metrics.h — how well a triangle mesh approximates an F-rep surface
 * (Vyatkin's two metrics plus uniformity) and whether it is a valid
 * closed surface.
 *
 *  - Vertex deviation: |F(v)| / |∇F(v)| at every vertex, the first-order
 *    distance to the surface (model units): max, mean, RMS.
 *  - Normal deviation: the angle between the mesh's vertex normal (the
 *    angle-weighted mean of its triangles' normals) and the surface's
 *    outward normal −∇F/|∇F| (degrees): max, mean, 95th percentile, over
 *    all vertices and over "smooth" vertices only — those whose one-ring
 *    lies in a single smooth piece of F (lib/frep/frep.h, geo_frep_run_piece),
 *    i.e. away from the creases of unions and intersections, where the
 *    surface normal is undefined.
 *  - Uniformity: coefficient of variation (standard deviation / mean) of
 *    edge lengths and of triangle areas.
 *  - Topology (lib/core/topo.h): boundary, non-manifold and flipped edges,
 *    non-manifold vertices, Euler characteristic; signed volume and area.
 * Self-intersections are not measured here (see the triangulator).
 *
 * Read-only on its inputs; reentrant. */
#ifndef GEO_FREP_METRICS_H
#define GEO_FREP_METRICS_H

#include <stdint.h>

#include "ctx.h"
#include "frep.h"
#include "poly.h"

typedef struct geo_frep_metrics {
    uint32_t nverts, nfacets;
    double dev_max, dev_mean, dev_rms;       /* model units */
    double ndev_max, ndev_mean, ndev_p95;    /* degrees, all vertices */
    uint32_t nsmooth;                        /* vertices away from creases */
    double sdev_max, sdev_mean, sdev_p95;    /* degrees, smooth vertices */
    double edge_mean, edge_cv;               /* edge lengths */
    double area_mean, area_cv;               /* facet areas */
    uint32_t boundary_edges, nonmanifold_edges, flipped_edges;
    uint32_t nonmanifold_vertices;
    int64_t euler;                           /* V − E + F */
    double volume, area;
} geo_frep_metrics;

/* Measures mesh m (facets of any size; normals use their fan triangles)
 * against f. 0, -ENOMEM or -ECANCELED (ctx, checked every 65536 vertices
 * or facets; may be NULL) with err set. */
int geo_frep_mesh_metrics(const geo_frep *f, const geo_poly *m,
                          const geo_ctx *ctx, geo_frep_metrics *ret,
                          geo_err *err);

#endif
