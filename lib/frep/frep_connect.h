/* frep_connect.h — connectivity of the surface points (Vyatkin, second
 * stage): neighbours along the vertical and horizontal section contours,
 * and the quads A→B→C→D they close, two triangles each.
 *
 * Sections. The vertical section x = x_i is the binary image of column
 * samples (j, k) with column index i; the horizontal section y = y_j the
 * image (i, k) with row j. Inside pixels are 4-connected (two pixels that
 * touch only at a corner belong to different pieces), outside pixels
 * 8-connected — the convention under which all sections are slices of one
 * 2-manifold voxel surface. Every surface point is an edge of that image
 * between an outside and an inside pixel of its column; the contour of the
 * section is walked with the inside on the left (the wheel of fig. 6:
 * "turn left if the pixel ahead-left is outside, turn right if the pixel
 * ahead-right is inside, else go straight"), run by run rather than pixel
 * by pixel, and the next surface point met on the contour is the point's
 * successor. Walls (vertical stretches of the contour without surface
 * points) are crossed in one step. So each point has a successor and a
 * predecessor in its vertical section (V) and in its horizontal one (H).
 *
 * Quads. The four contour directions leave a point towards ∓x and ∓y in
 * an order fixed by its kind (entry or exit of its run), which gives a
 * rotation system: the V and H contours embed a 4-regular graph in the
 * voxel surface. Its faces, traced with the outside on the right, are the
 * cells the paper closes by walking "down, right, up, left": a face of
 * four distinct points is a quad A→B→C→D, split into two triangles along
 * its shorter diagonal (the other one when the shorter already is an
 * edge). Faces of other lengths — and quads that would repeat a directed
 * edge or a diagonal — are left open: they are the holes of fig. 8, to be
 * filled by lib/mesh/hole_fill.h. Every face is counter-clockwise seen from
 * outside, so the triangles are outward oriented by construction.
 *
 * Ownership: *ret_mesh (a geo_poly whose vertices are the grid's 2·nruns
 * points, in point order, some possibly unused) and *ret_flat (one byte
 * per facet: 1 when the triangle's three columns are collinear, i.e. it
 * projects onto the camera plane with zero area) are allocated here for
 * the caller to free. Deterministic; uses geo_ctx_parallel_for for the
 * contour successors. */
#ifndef GEO_FREP_CONNECT_H
#define GEO_FREP_CONNECT_H

#include <stdint.h>

#include "ctx.h"
#include "frep_grid.h"
#include "poly.h"

typedef struct geo_frep_connect_stats {
    uint32_t ncells;     /* faces of the contour graph */
    uint32_t nquads;     /* closed into two triangles each */
    uint32_t ncollapsed; /* two-point faces (no area to fill) */
    uint32_t nopen;      /* faces left as holes */
    uint32_t nflat;      /* triangles projecting with zero area */
} geo_frep_connect_stats;

/* Builds the quad mesh of grid g. Returns 0, -ENOMEM, -ECANCELED, or
 * -EINVAL when the contours are inconsistent (cannot happen for a grid
 * built by geo_frep_grid_build; checked rather than assumed). Outputs are
 * set only on success; st may be NULL. */
int geo_frep_connect(const geo_frep_grid *g, const geo_ctx *ctx,
                     geo_poly **ret_mesh, uint8_t **ret_flat,
                     geo_frep_connect_stats *st, geo_err *err);

#endif
