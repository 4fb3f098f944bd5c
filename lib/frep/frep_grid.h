/* frep_grid.h — the surface points of an F-rep object (Vyatkin, first
 * stage of the triangulation): a quadtree over the projection plane (x, y)
 * and, through every cell it keeps, a ray along z split by binary
 * subdivision that finds every crossing.
 *
 * Sampling model. The sampling cube is centred on the object's bounds box
 * with side L = the box's largest side. Its projection is divided into
 * n × n columns (n = 2^qlev) and each column into m samples along z
 * (m = 2^blev): voxels of L/n × L/n × L/m. Column (i, j) is the ray
 * x = x_i, y = y_j through the column centre, sample k sits at z_k:
 *   x_i = ox + (i + ½)·L/n,  y_j = oy + (j + ½)·L/n,  z_k = oz + (k + ½)·L/m.
 * A sample is inside when F ≥ 0 there. Each sample's side is decided
 * exactly once — by an interval bound that proves a whole block of the
 * ray empty or full, or by evaluating F at the sample — and stored as
 * runs: maximal blocks [s, e] of consecutive inside samples of one
 * column. Everything after this stage (the section contours, the quads)
 * reads only the runs, so it sees one consistent digital object.
 *
 * Surface points. A run [s, e] has two crossings: its entry between
 * z_{s−1} and z_s and its exit between z_e and z_{e+1}. Each is solved on
 * the column's ray to full precision (bracketed regula falsi, Illinois
 * variant), so a point keeps its column's x, y exactly and |F| at it is at
 * rounding level. Point 2r is run r's entry (outward normal towards −z),
 * point 2r + 1 its exit (towards +z).
 *
 * The object must stay strictly inside the sampling cube: a run touching
 * the cube's first or last sample, or any inside sample in the outermost
 * columns, is reported as -EINVAL ("the object reaches the boundary of the
 * sampling cube ..."), never clipped silently.
 *
 * Parallelism: the quadtree below level min(qlev, 4) and the root solving
 * are split into independent chunks run with geo_ctx_parallel_for; the
 * result does not depend on the number of threads or their scheduling.
 * Cancellation is checked in every chunk; progress is reported between
 * batches of chunks from the calling thread.
 *
 * Ownership: geo_frep_grid_build allocates *ret; geo_frep_grid_free
 * releases it. A built grid is read-only. */
#ifndef GEO_FREP_GRID_H
#define GEO_FREP_GRID_H

#include <stdint.h>

#include "ctx.h"
#include "frep.h"

#define GEO_FREP_MAX_QLEV 11u
#define GEO_FREP_MAX_BLEV 20u
/* The smallest sample spacing relative to the largest coordinate of the
 * sampling cube (2^-32: about a million units in the last place per
 * sample); a finer sampling is refused with -EINVAL. */
#define GEO_FREP_MIN_RESOLUTION 0x1p-32

typedef struct geo_frep_grid {
    uint32_t qlev, blev;
    uint32_t n;          /* columns per side, 2^qlev */
    uint32_t m;          /* samples per column, 2^blev */
    double origin[3];    /* the sampling cube's lower corner */
    double side;         /* L */
    double hx, hz;       /* L/n and L/m */
    uint32_t *col_start; /* n·n + 1 offsets into runs; column id j·n + i */
    uint32_t nruns;
    int32_t (*runs)[2];  /* [s, e] of each run, increasing within a column */
    uint32_t *run_col;   /* column id of each run */
    double (*pts)[3];    /* 2·nruns surface points */
    uint64_t nevals;     /* point evaluations of F spent (statistics) */
    uint64_t nboxes;     /* interval bounds evaluated (statistics) */
    uint32_t nregularised; /* runs removed or merged as one column thick */
} geo_frep_grid;

/* Samples f (finished) at levels qlev ∈ [1, GEO_FREP_MAX_QLEV],
 * blev ∈ [1, GEO_FREP_MAX_BLEV] and solves the surface points. Returns 0,
 * -EINVAL (levels out of range, bounds too far from the origin for their
 * size — see GEO_FREP_MIN_RESOLUTION —, or the object reaches the cube's
 * boundary; err says where), -ENOMEM, or -ECANCELED. *ret is set only on
 * success. progress fractions run from p0 to p1. */
int geo_frep_grid_build(const geo_frep *f, uint32_t qlev, uint32_t blev,
                        const geo_ctx *ctx, double p0, double p1,
                        geo_frep_grid **ret, geo_err *err);

/* Releases g; accepts NULL; returns NULL. */
geo_frep_grid *geo_frep_grid_free(geo_frep_grid *g);

/* Sample coordinates of the grid. */
static inline double geo_frep_grid_x(const geo_frep_grid *g, uint32_t i)
{
    return g->origin[0] + ((double)i + 0.5) * g->hx;
}
static inline double geo_frep_grid_y(const geo_frep_grid *g, uint32_t j)
{
    return g->origin[1] + ((double)j + 0.5) * g->hx;
}
static inline double geo_frep_grid_z(const geo_frep_grid *g, int64_t k)
{
    return g->origin[2] + ((double)k + 0.5) * g->hz;
}

#endif
