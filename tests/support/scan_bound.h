/* scan_bound.h — how well any correction could give a stone's facets back
 * from a shadow-profile scan: the Cramér–Rao bound on each true facet's
 * normal.
 *
 * The simulator's scan (stone_sim.h) measures, in each of its k + 1
 * views, every stone vertex on the silhouette, projected, with Gaussian
 * noise of standard deviation sigma in both coordinates, independently
 * per view and vertex. Taking the stone's facet planes as the unknowns
 * (each a tilt in two directions and an offset; a vertex is the
 * least-squares meet of its facets' planes), the Fisher information of
 * all those measurements bounds the covariance of any unbiased estimate
 * of the planes from below. The scanned model is a function of the
 * silhouettes (their half-spaces, intersected: most silhouette edges are
 * cut away), so it carries at most that information: no correction of
 * the scan can do better on average.
 *
 * From each facet's 2×2 bound on its normal, the probability that an
 * estimate at the bound lies within tol_deg of the true normal; the sum
 * over the facets is the number a correction could recover by the angle
 * criterion of fidelity.h (the 5 µm centroid criterion is not modelled:
 * at these noise levels it binds far less). Test tooling, not product
 * code. */
#ifndef FACET_SCAN_BOUND_H
#define FACET_SCAN_BOUND_H

#include <stdint.h>

#include "poly.h"

typedef struct sim_scan_bound {
    uint32_t truth;       /* true facets */
    double attainable;    /* expected facets within tol_deg at the bound */
    double sd_median_deg; /* median over facets of the bound's angular
                             standard deviation, √(trace of the 2×2), ° */
} sim_scan_bound;

/* The bound for stone scanned as sim_scan_phase(stone, k, sigma, phase)
 * does (sigma in mm; 0 gives every facet). facet_sd_deg: NULL, or room
 * for stone->nfacets angular standard deviations (°, each facet's).
 * Returns 0, -ENOMEM, or -EDOM (the information is not positive definite
 * even regularised). */
int sim_scan_bound_measure(const geo_poly *stone, uint32_t k, double sigma,
                           double phase, double tol_deg, double *facet_sd_deg,
                           sim_scan_bound *ret);

/* The same bound with only what the scanned model keeps: each facet of
 * scan (sim_scan_phase of stone, noise sigma in mm) is one silhouette
 * edge, and measures the two stone vertices that span it along its
 * normal — but two facets of one view (geo_convex_view_keys) through one
 * vertex are the edges at one corner of its silhouette, one noisy point:
 * together they measure the vertex in both directions across the view,
 * once. The silhouette planes the intersection cut away measure
 * nothing. A correction sees the scan, not the silhouettes, so this is
 * its bound (still optimistic: the surviving planes are the innermost,
 * a bias the bound does not model). */
int sim_scan_bound_of_scan(const geo_poly *stone, const geo_poly *scan,
                           double sigma, double tol_deg, double *facet_sd_deg,
                           sim_scan_bound *ret);

#endif
