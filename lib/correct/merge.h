/* merge.h — merging groups of adjacent, nearly coplanar facets into one
 * facet (Palachev 2012, §2): the correction that removes the edges a
 * shadow-profile scanner adds when it splits one true facet into slivers.
 *
 * One group is merged by the paper's four steps:
 *  1. the contour enclosing the group (§2.4), the group replaced by one
 *     facet on it, and the hanging vertices (left in two facets) removed;
 *  2. the least-squares plane (§2.5): by default of the group's whole
 *     surface (area centroid, axis of least inertia: §2.5.2's area and
 *     inertia ways), so that heaps of close points do not pull it; the
 *     contour's points, plain (§2.5.1) or weighted by incident edge length
 *     (§2.5.2), are options;
 *  3. the contour points below the plane lifted, lowest event first, along
 *     the intersection of their neighbour facets, joining with a neighbour
 *     where their paths meet first, creating vertices where a point lies in
 *     more than three facets (§2.6, all eight cases of §2.6.4);
 *  4. the cut by that plane in the §3.4 form: the (non-planar) merged facet
 *     is replaced by the section, which must be one component.
 * The merged facet lies in the new plane; every other facet keeps its
 * plane. Conventions of lib/core/poly.h (mm, counter-clockwise from outside,
 * unit outward planes); a vertex within geo_poly_eps of the plane counts as
 * lying on it, decided once per step.
 *
 * Nothing invalid is ever returned: each merge is followed by a local
 * validity check of everything it touched and its neighbourhood (closed,
 * manifold, every vertex in ≥ 3 facets, planar within eps, not inverted,
 * not degenerate, and no self-intersection, tested exactly against every
 * facet whose box overlaps — lib/inspect/selfint.h), and a group that fails any
 * step is rolled back and reported with the reason. The input must be a
 * valid polyhedron (geo_inspect) for that guarantee to mean the result is.
 *
 * Groups found automatically (geo_merge_auto): connected groups of facets
 * sharing edges, each facet's normal within max_angle_deg of the group's
 * common plane and every vertex of the group within max_deviation of that
 * plane, and — the scan's own error — each facet that joins within
 * a few times the scan's surface noise plus a view step's roof of the
 * plane the group had before it; grown greedily from the largest facet
 * not yet in a group. The deviation bound widens, on wide inclined
 * groups, by the roof the scanner's view step leaves. Only simply
 * connected groups (one enclosing contour, §2.1) are merged. Rounds
 * repeat until a round merges nothing (merged facets can merge again);
 * then the bevel strips the scanner leaves along sharp edges (narrow
 * facets within three times the deviation bound of both neighbours'
 * planes, lib/correct/merge_bevel.c) are merged into a neighbour in its plane,
 * once, and the rounds resume if any was.
 *
 * Complexity: one group costs O(k log n) for a neighbourhood of k facets
 * (the facet BVH is built once per round and its boxes enlarged in place);
 * a round O(n log n). Not thread-safe on one model; reentrant. */
#ifndef GEO_MERGE_H
#define GEO_MERGE_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"
#include "topo.h"

/* The order in which contour points are lifted (§2.6.2). */
enum geo_lift_order {
    /* the event lowest along the plane's normal first: the join or the
     * arrival on the plane whose point v has the smallest n·v (default) */
    GEO_LIFT_EVENT_HEIGHT = 0,
    /* the paper's: the smallest lift d = n·(v − A_i) first */
    GEO_LIFT_PAPER = 1,
};

/* How the merged facet's plane is fitted (§2.5). */
enum geo_merge_plane {
    /* least squares over the contour's points (§2.5.1) */
    GEO_MERGE_PLANE_CONTOUR = 0,
    /* the same, each point weighted by half its two contour edges
     * (§2.5.2, first way) */
    GEO_MERGE_PLANE_CONTOUR_WEIGHTED = 1,
    /* least squares over the group's whole surface: the plane through its
     * area centroid normal to its axis of least inertia (§2.5.2, the
     * area and inertia ways) */
    GEO_MERGE_PLANE_AREA = 2,
};

typedef struct geo_merge_opts {
    /* Plane fit [see geo_merge_opts_default and README]. */
    enum geo_merge_plane plane;
    /* Lifting order [GEO_LIFT_EVENT_HEIGHT]; see README for why. */
    enum geo_lift_order lift_order;
    /* Local validity check with rollback [true]. Turning it off is for
     * measurements only: an invalid group is then kept. */
    bool check;
    /* Automatic groups: largest angle between a facet's normal and the
     * group's plane, degrees, in (0, 90) [see geo_merge_opts_default]. */
    double max_angle_deg;
    /* Automatic groups: largest distance of a group vertex from the
     * group's plane, mm; 0 means rel_deviation × the model's size
     * (bounding-box diagonal). Every group, given or found: the deepest
     * a vertex may lie above the merged plane and be cut off (a group
     * whose cut would go deeper is refused). */
    double max_deviation;
    double rel_deviation;
    /* Automatic groups on a scan (see merge_groups.c, README): the
     * scanner's views over 180° (K), 0 to read them off the model
     * (geo_merge_view_grid; none found: no view-step term) [0]; the
     * scan's surface noise, mm (area RMS distance of one true facet's
     * slivers from its plane), 0 to measure it on the model, negative to
     * leave the noise test out [0]. */
    uint32_t views;
    double noise;
    /* Automatic groups: remove bevel strips after the rounds [true]. */
    bool bevels;
    /* Automatic groups: rounds at most [16]. */
    uint32_t max_rounds;
} geo_merge_opts;

/* Fills the defaults (see README "Automatic correction" for why). */
void geo_merge_opts_default(geo_merge_opts *o);

/* What happened to one group. */
typedef struct geo_merge_group {
    uint32_t first, count; /* its facets: report.facets[first, +count) */
    int32_t status;        /* 0 merged; -EINVAL not merged (reason) */
    char reason[160];      /* why not, naming the place; "" when merged */
    uint32_t facet;        /* id of the merged facet (see report.facets),
                              GEO_NONE when not merged */
    uint32_t out_facet;    /* its index in the output model, or GEO_NONE
                              (not merged, or merged again later) */
    double plane[4];       /* the merged facet's plane */
    uint32_t contour;      /* contour vertices (§2.4) */
    uint32_t hanging;      /* hanging vertices removed (§2.4 step 8) */
    uint32_t lifts;        /* lift steps (§2.6.1) */
    uint32_t joins;        /* of them, joins with a neighbour (§2.6.4) */
    uint32_t new_vertices; /* vertices created by lifting */
    uint32_t moved;        /* vertices moved by lifting */
    double max_lift;       /* largest displacement of a vertex, mm */
    double dev_before;     /* largest distance of the group's vertices
                              from the new plane, mm */
    double dev_after;      /* largest distance of the merged facet's
                              vertices from its plane, mm (≤ eps) */
    double volume_change;  /* mm³, + when material was added */
} geo_merge_group;

/* A vertex moved by lifting: its index in the output and how far. */
typedef struct geo_moved_vertex {
    uint32_t vertex;
    double by[3]; /* mm, displacement from its input position */
} geo_moved_vertex;

typedef struct geo_merge_report {
    uint32_t ngroups, merged, failed, rounds;
    geo_merge_group *groups;
    /* Facet ids of the groups. Ids below the input's facet count are the
     * input's facets; larger ids are facets created by earlier groups of
     * the same run (the group whose .facet it is). */
    uint32_t *facets;
    uint32_t nfacets_listed;
    geo_moved_vertex *moved;
    uint32_t nmoved;
    /* vertices_before entries: each input vertex's index in the output, or
     * GEO_NONE (UINT32_MAX) when it is gone */
    uint32_t *vmap;
    uint32_t statement_violations; /* §2.7 statements 1–3 found false
                                      (groups rolled back); 0 expected */
    uint32_t views;       /* automatic groups: the views used (0: none) */
    double noise;         /* automatic groups: the surface noise used, mm
                             (0: no noise test) */
    double max_dev;       /* automatic groups: the deviation bound used
                             (before the roof term), mm */
    uint32_t bevels;      /* of the groups merged, bevel strips */
    uint32_t vertices_before, facets_before, vertices_after, facets_after;
    double volume_before, volume_after;
} geo_merge_report;

/* Releases the report's arrays and zeroes it; accepts NULL. The merge
 * functions below take their report as an output (it may be
 * uninitialised; what it held is not freed): clear a report before
 * handing it in again. */
void geo_merge_report_clear(geo_merge_report *r);

/* The deviation bound opts gives for p: max_deviation, or rel_deviation ×
 * geo_poly_size(p) when max_deviation is 0. */
double geo_merge_max_deviation(const geo_merge_opts *o, const geo_poly *p);

/* The scanner's views over 180° as the facet normals of a raw scan show
 * them (see lib/correct/merge_scale.c): K when at least half of the facets that
 * are not horizontal have normal azimuths, modulo 180°, on a grid of step
 * 180°/K, else 0. *ret_fraction (may be NULL) gets the fraction on the
 * grid. O(n log n). Returns 0 or -ENOMEM. Thread-safe (reads p only). */
int geo_merge_view_grid(const geo_poly *p, uint32_t *ret_views,
                        double *ret_fraction);

/* The surface noise geo_merge_auto measures when opts->noise is 0 (see
 * lib/correct/merge_scale.c), mm, 0 when p has no group of nearly coplanar
 * facets; opts NULL means defaults; t is p's topology, or NULL to build
 * it. Returns 0, -EINVAL (p not closed and manifold), -ENOMEM, -ECANCELED
 * (ctx may be NULL). */
int geo_merge_surface_noise(const geo_poly *p, const geo_topo *t,
                            const geo_merge_opts *opts, const geo_ctx *ctx,
                            double *ret, geo_err *err);

/* Merges the group of n facets of p (indices into p) in place. Returns 0
 * when merged; -EINVAL when the group cannot be merged or the result
 * would be invalid (p unchanged; err and the report's group say why);
 * -ENOMEM, -ECANCELED (p unchanged). report may be NULL; on success and
 * on -EINVAL it has one group. opts NULL means defaults. */
int geo_merge(geo_poly *p, const uint32_t *group, uint32_t n,
                     const geo_merge_opts *opts, const geo_ctx *ctx,
                     geo_merge_report *report, geo_err *err);

/* Merges ngroups groups given as CSR (gstart: ngroups + 1 offsets into
 * gfacets, indices into the input p) one after another. A group that
 * cannot be merged (or that shares a facet with an earlier merged group)
 * is reported and skipped. Returns 0 (see the report for each group),
 * -EINVAL for an index out of range, -ENOMEM, -ECANCELED (p unchanged on
 * error). */
int geo_merge_groups(geo_poly *p, uint32_t ngroups, const uint32_t *gstart,
                     const uint32_t *gfacets, const geo_merge_opts *opts,
                     const geo_ctx *ctx, geo_merge_report *report,
                     geo_err *err);

/* Finds groups automatically (see above) and merges them, round after
 * round until a round changes nothing (at most opts.max_rounds). Returns 0
 * (p changed in place), -EINVAL (p not closed and manifold), -ENOMEM,
 * -ECANCELED (p unchanged on error). */
int geo_merge_auto(geo_poly *p, const geo_merge_opts *opts,
                   const geo_ctx *ctx, geo_merge_report *report,
                   geo_err *err);

#endif
