/* gem_check.h — shared checks of the F-rep triangulation tests on cut
 * gems (test_triangulate_gems.c, test_triangulate_random_gems.c). Each
 * fails the running cmocka test with a message naming what failed. */
#ifndef TEST_GEM_CHECK_H
#define TEST_GEM_CHECK_H

#include <jansson.h>
#include <stdint.h>

#include "frep.h"
#include "poly.h"
#include "triangulate.h"

/* The frep-object/1 in j (named "gem" in messages); fails the test on
 * error. */
geo_frep *gem_frep_from_json(json_t *j);

/* f triangulated at Q_LEV q and B_LEV q + 1, the report in *rep. */
geo_poly *gem_triangulate(const geo_frep *f, uint32_t q, geo_tri_report *rep);

/* Closed, manifold, outward, a sphere's topology, no self-intersections
 * (counted again, independently of the report), every vertex on the
 * surface, normals exact where the ring lies on one facet. */
void gem_assert_valid(const geo_poly *m, const geo_tri_report *rep,
                      const char *what);

/* The largest distance of the polytope's true edges (the half-spaces of
 * j) from the mesh (d[0]) and, away from the corners, the median and
 * 99th percentile (voxel: the mesh's voxel size). */
void gem_edge_distances(json_t *j, const geo_poly *m, double voxel,
                        double d[5]);

#endif
