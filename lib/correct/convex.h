/* convex.h — correction of a convex scan by recovering the true facet
 * planes (docs/kernels/correct-convex.md).
 *
 * A shadow-profile scan (Palachev 2012, §1.2) of a convex stone is the
 * intersection of silhouette half-spaces: each plane contains its view's
 * direction and, to the silhouette noise, one true edge of the stone, so a
 * true facet comes out as a fan of slivers hinged on its own edges and
 * tilted by up to about a view step. Averaging the slivers (the merge of
 * Palachev 2012, §2.5) gives a plane tilted by a fraction of that step; the
 * hinges themselves lie on the true plane. So:
 *
 *  1. groups: the scan's facets are grouped into true facets, grown from
 *     the largest facet not yet in a group, each joining neighbour within
 *     the scan's own error (its surface noise and the roof its view step
 *     leaves) of the group's plane — the criterion of the merge's
 *     automatic groups (merge_groups.c), applied once to the raw scan;
 *  2. planes: each group's plane is its surface's least-squares plane
 *     (GEO_CONVEX_FIT_AREA, also the start of the silhouette adjustment
 *     that geo_correct uses), or fitted to the group's boundary — the
 *     edges it shares with other groups, where the slivers hinge on the
 *     true edges — by least squares over the boundary segments (each
 *     weighted by its length), with the segments that lie more than a few
 *     residual scales off rejected and the fit repeated (a boundary stretch
 *     no sliver hinges on lies outside the true plane);
 *  3. support: a group whose plane cuts the polytope of its neighbours'
 *     planes by no more than the scan's noise allows (a bevel strip along
 *     a true edge) is dropped;
 *  4. the result is the intersection of the kept half-spaces.
 *
 * Steps 1–3 are geo_convex_planes; geo_correct_convex runs them and step
 * 4 (with the silhouette fit adjusting the planes to every scan facet:
 * geo_convex_refine) and checks the result (see there). Conventions of
 * lib/core/poly.h; mm.
 * Reentrant; thread-safe on distinct models. */
#ifndef GEO_CONVEX_H
#define GEO_CONVEX_H

#include <stdint.h>

#include "ctx.h"
#include "poly.h"
#include "topo.h"

/* A group the support or narrow test took out, kept for the second look
 * of geo_correct_convex (a cut below the roofs of the neighbours' fitted
 * planes may still be a true facet's). */
typedef struct geo_convex_spare {
    double plane[4]; /* its fitted plane */
    double allow;    /* its allowance, as geo_convex_planes.allow */
    double roof;     /* the roof over it, mm */
    uint32_t group;
} geo_convex_spare;

typedef struct geo_convex_planes {
    uint32_t nplanes;     /* kept planes */
    double (*planes)[4];  /* nplanes unit outward planes */
    double *area;         /* nplanes: area of the scan facets of each */
    double *allow;        /* nplanes: how far the scan may lie outside the
                             plane over its group: the noise bound plus the
                             roof the view step leaves over a group that
                             wide and inclined, mm */
    double dev0;          /* the noise bound alone, mm */
    double step;          /* the view step, rad (0: views not known) */
    double (*span)[4];    /* ngroups: each group's horizontal direction
                             (x, y; unit, z × its fitted normal) and the
                             extent (lo, hi) of its scan vertices along
                             it, mm: the slivers over a facet rise with
                             the horizontal distance from where they
                             touch it (geo_convex_roof_at) */
    double hinge_noise;   /* the hinges' scatter about their planes, mm */
    double cut_min;       /* the deepest cut a dropped group made, mm */
    uint32_t ngroups;     /* groups found (kept or not) */
    uint32_t *group;      /* p->nfacets: group of each scan facet */
    uint32_t *kept;       /* ngroups: index into planes, or GEO_NONE */
    uint32_t dropped;     /* groups dropped as unsupported (step 3) */
    uint32_t nspare;          /* groups taken out, for a second look */
    geo_convex_spare *spare;  /* nspare */
} geo_convex_planes;

/* Releases the arrays and zeroes r; accepts NULL. */
void geo_convex_planes_clear(geo_convex_planes *r);

/* How high the scan may rise above the true plane n (unit outward) of
 * group g at x, by the view step alone (mm): a sliver of view k contains
 * d_k, so it is the facet turned about a line of steepest descent by
 * β · sin a (β its azimuth off the edge-on view, a the facet's
 * inclination) and rises in proportion to the horizontal distance from
 * where it touches; the two views around the edge-on one, touching at
 * the group's two horizontal ends, meet under
 *     step · sin a · u₁ u₂ / (u₁ + u₂)
 * (u₁, u₂ the horizontal distances of x from those ends): 0 at the ends,
 * step · sin a · w / 4 in the middle of a group w wide. 0 outside the
 * group's extent. */
double geo_convex_roof_at(const geo_convex_planes *cp, uint32_t g,
                          const double n[3], const double x[3]);

/* The plane each group gets (step 2). */
enum geo_convex_fit {
    /* the least-squares plane of the group's surface (Palachev 2012, §2.5.2,
     * the area and inertia ways), over the slivers of the whole true
     * facet */
    GEO_CONVEX_FIT_AREA = 0,
    /* the trimmed fit of the group's boundary (step 2 above): better
     * noise-free, worse once the noise is a micrometre */
    GEO_CONVEX_FIT_HINGE = 1,
    /* the area planes, then adjusted to every silhouette plane of the
     * scan at the vertices that span it (geo_convex_refine), kept when
     * their intersection passes the checks: the most faithful with 0–3 µm
     * of noise (docs), geo_correct's */
    GEO_CONVEX_FIT_SILHOUETTE = 2,
};

/* Steps 1–3 above on p, which must be a closed, outward, manifold model
 * (a raw convex scan; other models give planes too, meaningless ones).
 * views: the scanner's views over 180° (geo_merge_view_grid), 0 when not
 * known (no roof term); noise: the scan's surface noise in mm
 * (geo_merge_surface_noise), 0 for none. ret is filled (arrays malloc'd,
 * free with geo_convex_planes_clear). Returns 0, -EINVAL (p not closed
 * and manifold; err says so), -ENOMEM or -ECANCELED (ctx, which may be
 * NULL; ret zeroed). */
int geo_convex_planes_find(const geo_poly *p, uint32_t views, double noise,
                           enum geo_convex_fit fit, const geo_ctx *ctx,
                           geo_convex_planes *ret, geo_err *err);

/* The same with p's topology t (geo_topo_build) given, for a caller that
 * has it already. */
int geo_convex_planes_find_topo(const geo_poly *p, const geo_topo *t,
                                uint32_t views, double noise,
                                enum geo_convex_fit fit, const geo_ctx *ctx,
                                geo_convex_planes *ret, geo_err *err);

/* Adjusts planes[0..nplanes) (unit outward, in place) to every
 * silhouette plane of scan: each scan facet measures the two vertices
 * of the stone that span it (convex_refine.c says how and why). est is
 * their intersection (geo_halfspace_intersect) and src its facets'
 * planes; vertices of est closer than cluster (mm) are one vertex.
 * held (may be NULL): per plane, nonzero for one that stays where it is
 * while the others and all vertices move. *ret_scale gets the robust
 * scale of the residuals at the planes returned: the silhouettes' own
 * noise, mm. A Gauss–Newton step that raises that scale is not taken
 * (the planes before it are returned). Returns 0, -EINVAL (the normal
 * equations not positive definite: planes unchanged), -ENOMEM. */
/* The cluster radius geo_correct_convex passes, in noise bounds (the
 * larger of geo_convex_planes' dev0 and hinge_noise). */
#define GEO_CONVEX_REFINE_CLUSTER 3.0

int geo_convex_refine(const geo_poly *scan, const geo_poly *est,
                      const uint32_t *src, double cluster,
                      double (*planes)[4], uint32_t nplanes,
                      const uint8_t *held, double *ret_scale);

/* The view that cut each facet of a raw scan, as an integer key (the
 * facets of one view share it), into key (room for scan->nfacets; scan
 * must have planes). A side view looks along a horizontal direction,
 * which lies in the facet's plane: z × its normal, keyed by azimuth
 * modulo 180°. A vertical facet's plane contains z as well: the top
 * view's (key −1) unless a facet that is not vertical has its side key.
 * A horizontal facet does not say its azimuth: a key of its own
 * (−2 − its index). Returns 0 or -ENOMEM. */
int geo_convex_view_keys(const geo_poly *scan, int64_t *key);

/* What geo_correct_convex did. */
typedef struct geo_convex_report {
    uint32_t groups, planes, dropped; /* see geo_convex_planes */
    uint32_t redundant;  /* kept planes that bound no facet of the result */
    uint32_t narrow;     /* planes removed for a facet narrower than the
                            scan resolves */
    uint32_t unneeded;   /* planes removed as the scan does not need
                            them */
    uint32_t clipped;    /* silhouette planes added where the result
                            reached outside the scan */
    uint32_t readmitted; /* dropped groups given back by the second
                            look, on the adjusted planes or, when those
                            were declined, the fitted ones: the scan's
                            need of them beyond the noise (convex.c,
                            readmit) */
    uint32_t held;       /* planes the adjustment pushed into the scan,
                            held at their fitted place while the others
                            were adjusted again (convex.c, rescue) */
    uint32_t turned;     /* planes the adjustment turned out of their
                            slivers' cone (a wrong spanning pair), held
                            at their fitted place while the others were
                            adjusted again (convex.c, turned_out) */
    bool adjusted;       /* the planes are the ones adjusted to the
                            silhouettes (else the fitted ones: the
                            adjusted did not pass the checks) */
    double concavity;  /* the scan's deepest local concavity, mm */
    double bound;      /* the deviation the result may have from the
                          scan, mm */
    double deviation;  /* the result's Hausdorff distance to the scan, mm */
    double silhouette_scale; /* the robust scale (1.4826 × median) of the
                          silhouettes' residuals at the adjusted stone's
                          vertices, mm: the scanner's noise as the
                          adjustment measures it, also when its planes
                          were declined; 0 when none ran */
    bool regrouped;    /* the groups were found again with the noise unit
                          that scale gives (geo_correct: the scan's surface
                          estimate was short of it) */
    char reason[200];  /* why the convex path was not taken ("" if it was) */
} geo_convex_report;

/* The convex path of the correction: when p (closed, outward, manifold)
 * is convex to within the scan's deviation bound max_dev (mm; every edge's
 * dihedral convex or concave by no more than that), its true planes are
 * found (geo_convex_planes_find with views, noise) and *ret becomes their
 * exact intersection (lib/core/halfspace.h: closed, outward, convex, no
 * self-intersection by construction), provided it lies within the bound
 * the scan's noise and view step allow (rep->bound) of p: no result
 * vertex farther outside p than the hinges' noise moves them, no vertex
 * of p farther outside the result than its group's roof allows. Returns 0 (*ret a new
 * model, the caller frees it), 1 when the path does not apply or a check
 * fails (*ret NULL, rep->reason says which), -ENOMEM or -ECANCELED (err
 * set). p is never modified. rep may be NULL; t is p's topology, or NULL
 * to build it. */
int geo_correct_convex(const geo_poly *p, const geo_topo *t,
                       uint32_t views, double noise,
                       double max_dev, enum geo_convex_fit fit,
                       const geo_ctx *ctx, geo_poly **ret,
                       geo_convex_report *rep, geo_err *err);

#endif
