/* design.h — GemCad designs as truths for tests, benchmarks and the stone
 * simulator: loading the collection in tests/data/designs/, and writing
 * round brilliants whose proportions are known exactly.
 *
 * A design read here is the exact intersection of its facet half-spaces
 * (proto/model_asc.c), scaled to a given outline width and standing on
 * the simulator's holder axis z with its table up, so that
 * sim_scan(design_load(...), k, noise, seed) scans any design. */
#ifndef FACET_DESIGN_H
#define FACET_DESIGN_H

#include <stdbool.h>
#include <stdint.h>

#include "poly.h"

/* The simulator's stones are about this wide (mm). */
#define DESIGN_WIDTH_MM 6.5

/* Directory of the designs: $FACET_DESIGNS, else tests/data/designs. */
const char *design_dir(void);

/* Path of design NAME (static buffer, overwritten by the next call). */
const char *design_path(const char *name);

/* Reads the GemCad design at path and scales it so that its outline's
 * largest caliper width is width_mm (≤ 0: the file's own units). NULL
 * with err set on any error. The caller frees the model. */
geo_poly *design_load(const char *path, double width_mm, geo_err *err);

/* The facet planes of the GemCad file at path, computed from the
 * definitions of docs/formats-asc.md alone (its own parse and standard
 * sin/cos, sharing no code with the reader), for checking the reader:
 * planes[4i..4i+3] (unit normal, plane(x) ≤ 0 inside) and angle[i] (the
 * tier's signed angle; −0 for a culet) of every listed index, at most
 * max. Returns the count; the caller's test fails on an unreadable file. */
uint32_t design_file_planes(const char *path, double *planes, double *angle,
                            uint32_t max);

/* A round brilliant by its proportions; angles in degrees, percentages of
 * the mean diameter (outline perimeter / π) unless said otherwise. */
typedef struct design_brilliant {
    double crown_deg;       /* the 8 bezels (crown mains) */
    double pavilion_deg;    /* the 8 pavilion mains */
    double table_percent;   /* 100 × table perimeter / outline perimeter */
    double girdle_percent;  /* thinnest girdle, at the mains */
    double star_below_deg;  /* star angle = crown − this */
    double upper_girdle_above_deg; /* upper girdle = crown + this */
    double lower_girdle_above_deg; /* lower girdle = pavilion + this */
    double culet_percent;   /* culet caliper width; 0: pointed */
    uint32_t girdle_facets; /* a multiple of 16, 64..128 */
} design_brilliant;

/* Proportions drawn from seed within the ranges cutters use (crown
 * 31–37°, pavilion 39.8–42°, table 52–62 %, girdle 2–4.5 %, half of them
 * with a culet of 0.5–2 %, 64, 80, 96 or 112 girdle facets). */
void design_brilliant_random(uint64_t seed, design_brilliant *ret);

/* The design as GemCad .asc text (malloc'd, NUL-terminated; the caller
 * frees it), or NULL on out-of-memory. Units: the girdle's apothem is 1.
 * Tiers are named P (pavilion mains), L (lower girdles), K (culet),
 * R (girdle), B (bezels), S (stars), U (upper girdles), T (table). */
char *design_brilliant_asc(const design_brilliant *b);

/* Designs of every shape as lists of planes: each facet an inclination
 * (GemCad's signed angle: + crown, − pavilion, 90 girdle, 0 table, −0
 * culet), a distance from the origin and the azimuth of its normal
 * (degrees from +y towards +x, the index × 3.75 of a "g -96 48" gear),
 * with the tier it belongs to and whether it is a main. The stone is the
 * exact intersection of the planes; a built design has only facets that
 * appear in it (each with an area above 1e-6 of the stone's surface), and
 * its mains are found on the built stone by exact incidence: a crown
 * facet sharing a vertex with the table and one with a girdle facet, a
 * pavilion facet sharing one with a girdle facet and one with the culet
 * (without a culet: the lowest vertex). */
enum design_shape {
    DESIGN_OVAL,       /* 2-fold, mirror; faceted girdle */
    DESIGN_PEAR,       /* 1-fold, mirror; faceted girdle */
    DESIGN_MARQUISE,   /* 2-fold, mirror; faceted girdle */
    DESIGN_HEART,      /* 1-fold, mirror; faceted girdle; convex (the
                          cleft between the lobes is flattened) */
    DESIGN_TRILLIANT,  /* 3-fold, mirror; 3 sides and 3 cut corners */
    DESIGN_PRINCESS,   /* 4-fold, mirror; 4 sides and 4 small corners */
    DESIGN_CUSHION,    /* 4-fold, mirror; faceted girdle */
    DESIGN_EMERALD,    /* 2-fold, mirror; step cut, 4 sides and 4 corners */
    DESIGN_RADIANT,    /* 2-fold, mirror; 4 sides and 4 corners */
    DESIGN_ASYMMETRIC, /* 1-fold, no mirror; faceted girdle */
    DESIGN_NSHAPES
};

/* "oval", "pear", ... (the file names of the collection). */
const char *design_shape_name(enum design_shape s);

typedef struct design_facet {
    double angle_deg, dist, azimuth_deg;
    int tier;  /* enum geo_tier (report.h) */
    bool main;
} design_facet;

typedef struct design_cut {
    char title[200];
    uint32_t fold;
    bool mirror;
    uint32_t n;
    design_facet *f;
    uint32_t dropped; /* facets that did not appear and were left out */
} design_cut;

/* The proportions of a fancy design. The outline of a faceted girdle is
 * the curve of support function h(ψ) = 1 + Σ a[k] cos kψ + b[k] sin kψ
 * (ψ the azimuth), convex where h + h'' > 0; a polygonal outline is its
 * sides and cut corners (length_to_width, corner). */
typedef struct design_fancy {
    enum design_shape shape;
    double a[8], b[8];        /* harmonics of a faceted girdle's outline */
    double length_to_width;   /* polygonal outlines */
    double corner;            /* corner cut, fraction of the half width */
    double crown_deg;         /* crown mains (all equal) */
    double pavilion_deg;      /* the steepest pavilion main (the others
                                 meet it at the point) */
    double table_inset;       /* table edge inside the girdle, fraction of
                                 the smallest support distance */
    double girdle_percent;
    double star_below_deg, upper_girdle_above_deg, lower_girdle_above_deg;
    double culet_percent;     /* 0: pointed */
    uint32_t girdle_facets;   /* faceted girdles: a multiple of 8, 64..120 */
    uint32_t steps;           /* step cut: steps of crown and pavilion */
} design_fancy;

/* The shape's reference proportions, and a variant drawn from seed (its
 * outline's harmonics scaled by 0.7–1.3 and drawn back towards a round
 * until the smallest radius of curvature is 0.3 of the mean: pointed
 * ends sharper than that make stars that reach the girdle). */
void design_fancy_default(enum design_shape s, design_fancy *ret);
void design_fancy_random(enum design_shape s, uint64_t seed,
                         design_fancy *ret);

/* Builds the design (see above): 0, or -1 on out-of-memory or when the
 * planes bound no stone. The caller frees it with design_free. */
int design_fancy_build(const design_fancy *d, design_cut *ret);

void design_free(design_cut *d);

/* The planes of d (4 doubles each, plane(x) ≤ 0 inside) from its facets'
 * angles, distances and azimuths; malloc'd, NULL on out-of-memory. */
double *design_planes(const design_cut *d);

/* d as GemCad .asc text (malloc'd; NULL on out-of-memory): consecutive
 * facets of equal angle and distance share a tier line, in d's order, so
 * the stone read back has d's facets in d's order. */
char *design_asc(const design_cut *d);

#endif
