/* fidelity.h — how faithfully a corrected scan gives back the true stone,
 * facet by facet.
 *
 * A true facet is recovered when one facet of the corrected model, each
 * used once, has its normal within tol_deg of the true normal and passes
 * within tol_mm of the true facet's area centroid (distance to the facet
 * polygon). Pairs are taken in order of increasing angle (greedy one to
 * one). The angle error of a true facet is the angle to the corrected
 * facet nearest its centroid, matched or not. */
#ifndef FACET_FIDELITY_H
#define FACET_FIDELITY_H

#include <stdint.h>

#include "poly.h"

typedef struct sim_fidelity {
    uint32_t truth, recovered;
    double angle_median, angle_p95, angle_max; /* degrees */
    uint32_t worst_facet;   /* true facet of the largest angle error */
    uint32_t spurious;      /* corrected facets over 1 % of the surface
                               matching no true facet */
} sim_fidelity;

/* Fills ret comparing corrected with truth (both closed, outward).
 * Returns 0 or -ENOMEM. */
int sim_fidelity_measure(const geo_poly *truth, const geo_poly *corrected,
                         double tol_deg, double tol_mm, sim_fidelity *ret);

#endif
