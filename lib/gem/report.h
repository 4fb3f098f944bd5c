/* report.h — a stone as a cutter reads it: tiers, proportions and the
 * facet table (docs/kernels/report.md).
 *
 * The table is the largest facet whose outward normal lies within 10° of
 * the main axis (+z, the holder axis of a scan and the top of a design,
 * unless the caller gives one); the axis is then the table's normal.
 * Tiers: girdle = facets within 5° of parallel to the axis; crown = the
 * other facets with normal·axis > 0, pavilion = normal·axis < 0; culet =
 * a pavilion facet within 5° of parallel to the table. Lengths in mm,
 * angles in degrees, percentages of the mean diameter (outline perimeter
 * / π) unless said otherwise. The model must be a closed, outward
 * polyhedron with valid planes (convexity is not required but the
 * proportions assume it).
 *
 * Thread-safe for concurrent calls on distinct or unchanging models. */
#ifndef GEO_REPORT_H
#define GEO_REPORT_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"

enum geo_tier { GEO_TIER_TABLE, GEO_TIER_CROWN, GEO_TIER_GIRDLE,
                GEO_TIER_PAVILION, GEO_TIER_CULET };

/* "table", "crown", "girdle", "pavilion", "culet". */
const char *geo_tier_name(enum geo_tier t);

typedef struct geo_report_facet {
    enum geo_tier tier;
    double inclination_deg; /* angle between its plane and the table's, 0–90 */
    double azimuth_deg;     /* of its normal projected on the table plane,
                               0–360, from the reference direction towards
                               the right seen from above */
    double index;           /* azimuth on the gear, fractional */
    double distance_mm;     /* its plane's distance from the axis point */
    double area_mm2;
} geo_report_facet;

typedef struct geo_range {
    double min, max, mean;
} geo_range;

typedef struct geo_report {
    bool has_table;
    uint32_t table_facet;   /* UINT32_MAX without a table */
    double axis[3];         /* unit, towards the table */
    double ref[3];          /* azimuth 0 direction in the table plane */
    double center[3];       /* the axis point: outline centroid at girdle
                               mid-height */
    double table_percent;   /* 100 × table perimeter / outline perimeter */
    geo_range diameter_mm;  /* outline caliper widths; mean = perimeter/π */
    double length_mm, width_mm, length_to_width;
    double total_depth_percent, crown_height_percent,
        pavilion_depth_percent, culet_percent;
    geo_range girdle_thickness_percent; /* zeros without girdle facets */
    geo_range crown_angle_deg, pavilion_angle_deg; /* of the mains */
    uint32_t crown_mains, pavilion_mains;
    uint32_t tier_count[5];
    uint32_t nfacets;
    geo_report_facet *facets; /* nfacets, in the model's facet order */
    struct geo_scan_deviation *scan; /* nfacets, or NULL: see below */
} geo_report;

/* How far a raw scan's surface lies from each facet of the model, µm:
 * the scan's surface is sampled at every facet's vertices, edge midpoints
 * and area centroid (the centroid standing for half of the facet's area,
 * the corners and midpoints for a quarter, shared equally), each sample is
 * assigned to the model facet nearest to it (lib/inspect/surface.h), and
 * each model facet gets the largest distance of its samples and their
 * area-weighted root mean square. A facet no sample is nearest to has
 * samples 0 (and max, rms 0). */
typedef struct geo_scan_deviation {
    uint32_t samples;
    double max_um, rms_um;
} geo_scan_deviation;

/* Fills *ret for model p. axis: the main axis (NULL: +z); when given, a
 * model without a table is still reported (has_table false, table and
 * culet figures 0). gear: teeth for the facets' index (> 0). Returns 0;
 * -EINVAL with err ("no table: ...; give an axis") for a model without a
 * table and no axis, or for an empty or flat model; -ENOMEM. The caller
 * releases ret with geo_report_free. */
int geo_report_compute(const geo_poly *p, const double *axis, uint32_t gear,
                       geo_report *ret, geo_err *err);

/* Fills r->scan (r computed for model; its previous deviations freed)
 * with the deviation of scan from model's facets (above). scan: any
 * polyhedron with valid indices (open, non-convex, many facets: a raw
 * scan), in the model's frame and units (mm). 0, or -EINVAL (an empty
 * model or scan) / -ENOMEM with err set and r->scan NULL. */
int geo_report_scan_deviation(geo_report *r, const geo_poly *model,
                              const geo_poly *scan, geo_err *err);

void geo_report_free(geo_report *r);

#endif
