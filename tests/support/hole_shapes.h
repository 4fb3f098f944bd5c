/* hole_shapes.h — polyhedra whose plane sections have holes, islands or
 * points where a hole touches the outer boundary, for the plane-cut tests
 * and benchmark. All constructors return NULL on failure; the caller
 * frees. */
#ifndef FACET_HOLE_SHAPES_H
#define FACET_HOLE_SHAPES_H

#include <stdint.h>

#include "poly.h"

/* The prism of height h over the cells marked '#' in an ASCII map (rows
 * from the top, nrows rows of equal length; cell (row r, column c) is the
 * unit square [c, c+1] × [nrows−1−r, nrows−r]). Top and bottom are one
 * square facet per cell, walls one quad per cell side bordering an empty
 * cell or the outside, all outward. Cells must not touch only at a
 * corner (the solid would pinch there). Volume: cells × h. */
geo_poly *hs_grid_prism(const char *const *rows, uint32_t nrows, double h);

/* The box [lo, hi] with the box [ilo, ihi] (strictly inside) hollowed
 * out: two shells, the cavity's facing inward. */
geo_poly *hs_hollow_box(const double lo[3], const double hi[3],
                        const double ilo[3], const double ihi[3]);

/* A square ring (outer [0,10]², hole [3,7]², z in [0, 4]) whose south
 * bar has a saddle on top: its top rises to the corners (z = 4) along x
 * and dips to z = 1 at the middle of both bar edges, around the centre
 * s = (5, 1.5, 2). The plane z = 2 passes through s: the section kept
 * below is the ring's annulus with the hole touching the outer boundary
 * at s; above, the two humps beside s meet only at s. s is vertex
 * HS_SADDLE. */
geo_poly *hs_saddle_ring(void);
#define HS_SADDLE 16u

/* A torus around the z axis (radii R > r > 0) triangulated on an nu × nv
 * grid (2·nu·nv triangles; nu ≥ 3, nv ≥ 3), outward. Its section by the
 * plane z = c, |c| < r, is an annulus. */
geo_poly *hs_torus(uint32_t nu, uint32_t nv, double R, double r);

#endif
