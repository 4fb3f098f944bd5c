/* gem_check.h — shared checks of the F-rep triangulation tests on cut
 * gems (test_triangulate_gems.c, test_triangulate_random_gems.c). They
 * return errors and problems for the test to fail with (the support
 * objects do not depend on cmocka). */
#ifndef TEST_GEM_CHECK_H
#define TEST_GEM_CHECK_H

#include <jansson.h>
#include <stdint.h>

#include "frep.h"
#include "poly.h"
#include "triangulate.h"

/* The frep-object/1 in j (named "gem" in messages), or NULL with err. */
geo_frep *gem_frep_from_json(json_t *j, geo_err *err);

/* f triangulated at Q_LEV q and B_LEV q + 1 (the report in *rep), or
 * NULL with err. */
geo_poly *gem_triangulate(const geo_frep *f, uint32_t q, geo_tri_report *rep,
                          geo_err *err);

/* NULL when m is closed, manifold, outward, of a sphere's topology,
 * without self-intersections (counted again, independently of the
 * report), every vertex on the surface, normals exact where the ring
 * lies on one facet; else a static message starting with `what`. */
const char *gem_problem(const geo_poly *m, const geo_tri_report *rep,
                        const char *what);

/* The largest distance of the polytope's true edges (the half-spaces of
 * j) from the mesh (d[0]) and, away from the corners, the median and
 * 99th percentile (voxel: the mesh's voxel size). 0, or -1 when j has no
 * half-spaces or edges. */
int gem_edge_distances(json_t *j, const geo_poly *m, double voxel,
                       double d[5]);

#endif
