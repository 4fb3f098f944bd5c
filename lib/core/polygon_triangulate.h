/* polygon_triangulate.h — splitting one planar (or nearly planar) simple
 * polygon into triangles, for formats that store only triangles (STL,
 * ASE) and for kernels that need triangles.
 *
 * Method: the polygon is projected onto the coordinate plane most nearly
 * parallel to it (dropping the axis of the largest component of its
 * Newell normal), then clipped ear by ear; every decision (is a corner
 * convex, does a point lie in a candidate ear) is an exact orientation
 * sign (geo_orient2d_proj), never an epsilon comparison. A strictly
 * convex polygon is fanned from its first vertex without any search.
 * Cost: O(n) for a convex polygon, O(n·r) per clipped ear otherwise
 * (r reflex corners), O(n²·r) worst case for one polygon.
 *
 * Thread-safe and reentrant; allocates scratch memory only for polygons
 * of more than 64 vertices. */
#ifndef GEO_POLYGON_TRIANGULATE_H
#define GEO_POLYGON_TRIANGULATE_H

#include <stdint.h>

/* Triangulates the polygon whose corner i is the point at xyz + 3·idx[i]
 * (xyz: x, y, z of every vertex in turn, as &geo_poly.verts[0][0];
 * n ≥ 3, coordinates finite). Writes n − 2 triangles into ret_tris (caller
 * allocated, n − 2 entries) as positions 0 … n−1 into idx (not vertex
 * numbers), each listed in the polygon's own turning direction, so
 * their right-hand normals agree with the polygon's Newell normal.
 *
 * For a simple polygon the triangles cover it exactly, none has zero
 * area unless the polygon has three consecutive collinear corners left
 * at the end, and every edge used is a polygon edge or an inner
 * diagonal. For a polygon that is not simple, or has a zero Newell
 * normal, the result is still n − 2 triangles over the polygon's corners
 * (some may overlap or be degenerate) — never a failure or a hang.
 *
 * Returns 0, -EINVAL for n < 3, or -ENOMEM (ret_tris then undefined). */
int geo_polygon_triangulate(const double *xyz, const uint32_t *idx,
                            uint32_t n, uint32_t (*ret_tris)[3]);

#endif
