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

#endif
