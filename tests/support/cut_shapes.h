/* cut_shapes.h — polyhedra built in code for the plane-cut tests and
 * benchmark (prisms of simple polygons, a square ring, bumpy triangulated
 * spheres, convex polyhedra from half-spaces) and a validity check of a
 * result. All constructors return NULL on failure; the caller frees. */
#ifndef FACET_CUT_SHAPES_H
#define FACET_CUT_SHAPES_H

#include <stdint.h>

#include "poly.h"

/* The prism over a simple polygon xy[0..n) (counter-clockwise seen from +z)
 * between z0 < z1: bottom, top and n side quads, outward. */
geo_poly *cs_prism(const double (*xy)[2], uint32_t n, double z0, double z1);

/* A prism over a star with `points` tips (radius r_out) and inner corners
 * (radius r_in), centred at the origin, z in [0, h]. */
geo_poly *cs_star_prism(uint32_t points, double r_in, double r_out, double h);

/* A prism over a comb: a base bar [0, w]×[0, 2] with `prongs` prongs of
 * width 1 and length 6 pointing +y, spaced 2 apart; z in [0, 3]. */
geo_poly *cs_comb_prism(uint32_t prongs);

/* A square ring (picture frame): outer [0,10]², inner [3,7]², z in [0, 4];
 * top and bottom each made of four trapezoids. Volume 336. */
geo_poly *cs_frame(void);

/* A 10-cube with a square pyramid on its bottom face [3,7]², apex
 * (5, 5, apex_z): dug into the cube (apex_z > 0) or standing out of it
 * (apex_z < 0). */
geo_poly *cs_dented_box(double apex_z);

/* A closed triangulated sphere-like surface: nlat rings × nlon segments
 * (2·nlon·(nlat − 1) triangles), radius 1 + bump·sin(5θ)·sin(4φ) around
 * the origin (star-shaped; convex when bump = 0). */
geo_poly *cs_sphere(uint32_t nlat, uint32_t nlon, double bump);

/* The convex polyhedron ∩ {plane_i(x) ≤ 0} of m planes (a,b,c unit) by
 * enumerating triple intersections; NULL when it is unbounded, empty or
 * has a vertex where more than three planes meet (within tol). */
geo_poly *cs_convex(const double (*planes)[4], uint32_t m, double tol);

/* m random planes tangent to the unit sphere plus four bounding ones
 * (planes receives m + 4 rows). */
void cs_random_planes(uint64_t *seed, uint32_t m, double (*planes)[4]);

/* Checks that p is a valid polyhedron: indices, closed oriented manifold,
 * every vertex in ≥ 3 facets, planes unit and agreeing with the facets'
 * orientation, every vertex within tol of its facets' planes, positive
 * volume. Returns NULL or a static message naming what failed. */
const char *cs_check_valid(const geo_poly *p, double tol);

#endif
