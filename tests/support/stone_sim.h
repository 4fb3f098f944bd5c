/* stone_sim.h — a shadow-profile scanner simulator for tests and
 * benchmarks.
 *
 * A stone is the intersection of the half-spaces of its facet planes
 * (brilliant, princess and emerald cuts with seeded random proportions).
 * A scan is what a shadow-profile scanner (Palachev 2012, §1.2) reconstructs:
 * for K views over 180° about the holder axis (z), the silhouette — the
 * convex hull of the stone's vertices projected along the view direction,
 * with optional noise — gives one half-space per silhouette edge, its plane
 * parallel to the view direction; a top view (along z) bounds the model.
 * The scanned model is the intersection of all of them, so true facets
 * come out split into slivers of nearly coplanar facets and vertices of
 * degree > 3 split into clusters, as in the paper.
 *
 * Test tooling, not product code: the clipper snaps vertices within a
 * tolerance of a plane onto it, which is adequate for generating convex
 * models and nothing else. */
#ifndef FACET_STONE_SIM_H
#define FACET_STONE_SIM_H

#include <stdint.h>

#include "poly.h"

/* Cuts: a round brilliant (121 facets), princess, emerald, a 16-fold
 * brilliant with twice the facets ("jubilee", 241: its 128 girdle facets
 * are 2.8° apart and 0.16 mm wide), and the same crown and pavilion on a
 * 96-facet girdle ("jubilee96", 209 facets; girdle facets 3.75° apart,
 * 0.21 mm wide). */
enum sim_cut { SIM_BRILLIANT, SIM_PRINCESS, SIM_EMERALD, SIM_JUBILEE,
               SIM_JUBILEE96 };

/* The true stone of the given cut, about 6.5 mm across, with proportions
 * drawn from seed. NULL on out-of-memory. Valid convex polyhedron. */
geo_poly *sim_stone(enum sim_cut cut, uint64_t seed);

/* The intersection of n half-spaces plane(p) ≤ 0 (planes: 4·n doubles,
 * normals of any length), clipped from the box [−r, r]³. Redundant planes
 * leave no facet. NULL when the intersection is empty or on OOM. */
geo_poly *sim_halfspace_intersection(const double *planes, uint32_t n,
                                     double r);

/* Clips convex p by plane(x) ≤ 0, snapping vertices within tol of the
 * plane onto it; returns a new polyhedron (p unchanged), or NULL when
 * nothing remains or on OOM. *ret_changed tells whether the plane cut. */
geo_poly *sim_clip_convex(const geo_poly *p, const double plane[4], double tol,
                          int *ret_changed);

/* The least silhouette noise a scan is made with, mm. Without noise, a
 * stone edge that stays on the silhouette over a run of views gives one
 * plane per view through that edge, and the clipping in doubles cannot
 * resolve planes that meet along one line (at 1e-7 mm 2 of 36 scans came
 * out open; at 1e-6 mm none of those 36 nor of 60 random designs). A
 * thousandth of the 1 µm of the sample models. */
#define SIM_NOISE_FLOOR 1e-6

/* A scan of stone with k views over 180° about z plus one top view;
 * noise is the standard deviation of the silhouette noise in mm (the
 * sample models use 0.001), raised to SIM_NOISE_FLOOR. NULL on failure. */
geo_poly *sim_scan(const geo_poly *stone, uint32_t k, double noise,
                   uint64_t seed);

/* The same with the views turned by phase (radians): view i looks along
 * azimuth phase + 180° · i / k. */
geo_poly *sim_scan_phase(const geo_poly *stone, uint32_t k, double noise,
                         double phase, uint64_t seed);

/* The projection basis of view i of sim_scan_phase's k + 1: for i < k
 * the view along azimuth phase + 180° · i / k (e1 horizontal, e2 = z),
 * for i = k the top view (e1 = x, e2 = y). */
void sim_view_basis(uint32_t k, double phase, uint32_t i, double e1[3],
                    double e2[3]);

/* The stone's vertices on the noise-free silhouette seen along e1 × e2
 * (projected onto (e1, e2)), counter-clockwise, into ids (room for
 * stone->nverts); returns how many (0 on out-of-memory). Vertices in the
 * middle of a silhouette edge are not on it. */
uint32_t sim_silhouette(const geo_poly *stone, const double e1[3],
                        const double e2[3], uint32_t *ids);

/* Turns p about z by angle (radians), vertices and planes. */
void sim_rotate_z(geo_poly *p, double angle);

/* Squared distance from point x to facet f of g (a planar polygon). */
double sim_facet_dist2(const geo_poly *g, uint32_t f, const double x[3]);

/* Symmetric Hausdorff distance estimate between two closed polyhedra:
 * the largest distance from sample points of either surface (every
 * vertex, facet centroids and samples per facet proportional to area) to
 * the other surface. */
double sim_hausdorff(const geo_poly *a, const geo_poly *b, uint32_t samples);

/* One-sided: largest distance from samples of a's surface to b's. */
double sim_hausdorff_directed(const geo_poly *a, const geo_poly *b,
                              uint32_t samples);

#endif
