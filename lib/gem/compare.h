/* compare.h — two models of the same stone side by side: the rigid
 * motion that lays model B onto model A, and how far apart they are then
 * (docs/kernels/compare.md). A scan, its corrected model and the design
 * can be compared whatever their orientation and position.
 *
 * Alignment. Each model's main axis is its table's normal. The table is
 * the largest group of nearly parallel facets (normals within 1°, so a
 * scan's table split into slivers counts whole) when that group has at
 * least 1.5 times the area of any other; otherwise the largest facet
 * whose normal lies within 10° of the axis guess (+z, or the caller's
 * axis) as in geo_report. With an axis given and no table near it, the
 * axis itself is used. The rotation takes B's axis onto A's, then turns
 * B about A's axis by the best correlation of the area-weighted
 * (inclination, azimuth) histograms of the facet normals (0.5° steps),
 * then is refined by least squares (Horn's quaternion) on each model's
 * normals matched to the other's nearest (both ways, weighted by the
 * smaller area; 2° down to 0.1°), axis included.
 * Every promising turn is refined; the one whose normals cover the most
 * of both surfaces wins, and among those within 1 % of it (the equal
 * turns of a symmetric stone, set apart by noise) the smallest rotation.
 * The translation solves, by least squares over the matched facets, for
 * B's planes passing through A's facet centres,
 * twice rejecting pairs beyond 3 robust deviations (from the volume
 * centroids when fewer than three independent normals are matched).
 *
 * Facets are matched one to one: B facets within 1° of an A facet's
 * normal whose plane stays within 2 % of A's size of A's facet, nearest
 * (largest distance of B's plane from A's facet's vertices) first, each
 * facet used once; models of different facet counts (a scan and its
 * design) leave facets unmatched.
 *
 * Measures after alignment: the symmetric Hausdorff estimate of
 * hausdorff.h, the area-weighted mean distance of samples of both
 * surfaces to the other (surface.h; about 4,000 samples per surface, one
 * at least per triangle of each facet), and the relative volume
 * difference. Lengths in mm. Reentrant; thread-safe on unchanging
 * models. */
#ifndef GEO_COMPARE_H
#define GEO_COMPARE_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"

typedef struct geo_compare_opts {
    const double *axis;  /* axis guess for both models; NULL: +z */
    const char *name_a;  /* how messages name A and B (a path); NULL: */
    const char *name_b;  /* "A", "B" */
} geo_compare_opts;

typedef struct geo_compare_pair {
    uint32_t a, b;       /* facet indices */
    double angle_deg;    /* between the normals after alignment */
    double offset_mm;    /* B's plane minus A's along A's normal, at A's
                            facet centre: > 0 when B lies outside */
} geo_compare_pair;

typedef struct geo_compare_result {
    bool aligned;            /* a rigid motion was found; false: B is
                                measured where it lies */
    double rotation[3][3];   /* applied to B: x' = R x + t */
    double translation[3];   /* t, mm */
    double rotation_deg;     /* angle of R */
    double rotation_axis[3]; /* unit axis of R (A's axis when R = I) */
    double axis[3];          /* A's main axis */
    double coverage;         /* 0–1: area share of both surfaces whose
                                normal finds the other's within 1° */
    double hausdorff_mm, mean_distance_mm;
    double volume_difference_relative; /* (vol B − vol A) / vol A */
    uint32_t matched, unmatched_a, unmatched_b;
    geo_compare_pair *pairs; /* matched, by A's facet index */
} geo_compare_result;

/* p's main axis as geo_compare finds it (axis: the guess, may be NULL;
 * name: the model in messages): 0 with ret_axis and *ret_table (a facet,
 * or UINT32_MAX when the given axis is used), or -EINVAL ("NAME: no
 * table: ...; give an axis", "NAME: an empty model ...") / -ENOMEM. */
int geo_compare_axis(const geo_poly *p, const double *axis, const char *name,
                     double ret_axis[3], uint32_t *ret_table, geo_err *err);

/* Aligns b onto a and measures; both with valid indices and planes.
 * o may be NULL. 0 with *ret filled (free with geo_compare_free), or
 * -EINVAL (an empty model, no table and no axis: named), -ENOMEM,
 * -ECANCELED. */
int geo_compare(const geo_poly *a, const geo_poly *b,
                const geo_compare_opts *o, const geo_ctx *ctx,
                geo_compare_result *ret, geo_err *err);

void geo_compare_free(geo_compare_result *r);

#endif
