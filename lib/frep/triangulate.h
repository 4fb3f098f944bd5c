/* triangulate.h — triangulation of a functionally defined object (seed
 * 001; spec algorithms.md §6): the whole pipeline from a finished
 * geo_frep to a closed, outward-oriented triangle mesh with its quality
 * report.
 *
 * Stages (each timed):
 *  1. sample   surface points: quadtree over the projection plane and
 *              binary subdivision of every ray, all crossings solved onto
 *              F = 0 (lib/frep/frep_grid.h);
 *  2. connect  vertical/horizontal section contours and the quads
 *              A→B→C→D, two triangles each (lib/frep/frep_connect.h);
 *  3. fill     holes: Liepa's minimum-weight triangulation
 *              (lib/mesh/hole_fill.h);
 *  4. sharpen  creases of unions/intersections recovered
 *              (lib/frep/frep_sharpen.h), when the object has any, including
 *              those of faces parallel to the rays (walls);
 *  5. refine   the patches together with the triangles that project with
 *              zero area (walls) and every triangle sharing a vertex with
 *              them, so that flips can turn a wall's slivers into fair
 *              triangles: centroid splits, hard-edge splits, fairing
 *              (lib/mesh/hole_fill.h, geo_refine_region; its time is counted
 *              in t_fill). A new or moved vertex stays on what its sources
 *              share: Newton steps along ∇F for a smooth object; on an
 *              object with creases, onto the smooth piece (or the crease)
 *              all its sources lie on, a triangle spanning a crease not
 *              being split at all, so refinement never cuts a crease;
 *              hard edges are the edges lying on a crease;
 *  6. metrics  vertex and normal deviation, uniformity, topology
 *              (lib/frep/frep_metrics.h), exact self-intersections
 *              (lib/inspect/selfint.h).
 *
 * Complexity: sampling visits O(n_s·(Q_LEV + B_LEV)) boxes for n_s
 * surface columns, each costing the length of the program specialised to
 * it (a few terms deep in the tree); connecting is O(p log r) for p points
 * and r runs per column; filling is O(Σ h·min(h, 128)²) over holes of h
 * vertices; the rest is linear in the mesh size.
 *
 * Determinism: the mesh depends only on the object and the options, not
 * on the number of threads behind ctx->parallel_for.
 *
 * Ownership: *ret_mesh is allocated here (geo_poly_free); report->fill
 * owns a malloc'd array (geo_tri_report_clear). An object with no
 * inside sample left (empty, or thinner than a column everywhere) gives
 * 0 with an empty mesh and report->empty set. Errors: -EINVAL (bad
 * levels, bounds too far from the origin for their size, an object
 * reaching the sampling cube's boundary), -ENOMEM, -ECANCELED, with err
 * set; outputs untouched then. */
#ifndef GEO_TRIANGULATE_H
#define GEO_TRIANGULATE_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "frep.h"
#include "frep_connect.h"
#include "frep_metrics.h"
#include "frep_sharpen.h"
#include "hole_fill.h"
#include "poly.h"

typedef struct geo_tri_opts {
    uint32_t quad_levels;        /* Q_LEV [9] */
    uint32_t binary_levels;      /* B_LEV [10] */
    enum geo_fill_weight fill;   /* [GEO_FILL_AREA] */
    bool refine;                 /* [true] */
    enum geo_fill_fair fair;     /* [GEO_FAIR_UNIFORM] */
    bool sharpen;                /* [true] */
    double hard_angle_deg;       /* [45] */
    double density;              /* refinement density [1.0] */
} geo_tri_opts;

/* Fills the defaults above. */
void geo_tri_opts_default(geo_tri_opts *o);

typedef struct geo_tri_report {
    geo_frep_metrics quality;
    geo_frep_connect_stats connect;
    geo_fill_stats fill;        /* owns fill.holes */
    geo_sharpen_stats sharpen;
    bool empty;                 /* no inside sample survived: the mesh has
                                   no vertices and no facets (an empty
                                   object, or one thinner than a column
                                   everywhere at these levels) */
    uint32_t npoints;           /* surface points found by sampling */
    uint32_t npinched;          /* pinched points removed before filling */
    uint32_t ndropped;          /* facets of closed pieces enclosing less
                                   than 1/1000 of a voxel, removed after
                                   filling */
    uint64_t nevals, nboxes;    /* point and interval evaluations */
    double voxel[3];            /* voxel size (x, y, z) */
    int64_t self_intersections; /* pairs of facets meeting other than along
                                   shared edges/vertices (lib/inspect/selfint.h) */
    uint32_t ndegenerate;       /* facets without a plane (zero area) */
    double t_sample, t_connect, t_fill, t_sharpen, t_metrics, t_total;
} geo_tri_report;

/* Frees what a report owns and zeroes it; accepts NULL. */
void geo_tri_report_clear(geo_tri_report *r);

/* Triangulates f (finished). opts NULL means defaults; report may be
 * NULL. Progress runs 0 → 1 over the stages. */
int geo_triangulate(const geo_frep *f, const geo_tri_opts *opts,
                         const geo_ctx *ctx, geo_poly **ret_mesh,
                         geo_tri_report *report, geo_err *err);

#endif
