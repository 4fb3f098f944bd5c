/* merge_impl.h — internals shared by the facet-merging files (merge.c,
 * merge_contour.c, merge_lift.c, merge_cut.c, merge_check.c,
 * merge_groups.c); not part of the library's interface.
 *
 * One merge workspace (geo_mw) holds the editable model, the tolerance,
 * the "world" of the local validity checks (a facet BVH built once per
 * round whose boxes only ever grow, plus the facets created since) and
 * scratch arrays indexed by vertex or facet id with generation stamps, so
 * that merging one group costs time in proportion to its neighbourhood,
 * never to the model. */
#ifndef GEO_MERGE_IMPL_H
#define GEO_MERGE_IMPL_H

#include <stdbool.h>
#include <stdint.h>

#include "bvh.h"
#include "edit.h"
#include "merge.h"

typedef struct geo_mw {
    geo_edit *e;
    double eps;            /* planarity tolerance of the model */
    double max_cut;        /* the deepest a vertex may lie above the
                              merged plane and be cut off, mm: the
                              deviation bound (geo_merge_max_deviation) */
    double origin[3];      /* reference point of volume sums */
    enum geo_merge_plane plane_mode;
    enum geo_lift_order lift_order;
    /* area moments of the current group's surface (GEO_MERGE_PLANE_AREA),
     * about the point mo */
    double mo[3], ma, ms[3], mss[3][3], mn[3];
    bool check;            /* local validity check + rollback */

    /* world: BVH over the facets that existed when it was built (boxes
     * enlarged as facets change), facets created since in extra */
    geo_bvh *bvh;
    uint32_t nbase;        /* facets covered by bvh */
    uint32_t *slot_of;     /* nbase: facet → position in bvh->items */
    uint32_t *leaf_of;     /* bvh->nitems: item position → leaf node */
    uint32_t *parent;      /* bvh->nnodes: node → parent (root: GEO_NONE) */
    uint32_t *extra;
    uint32_t nextra, capextra;

    /* stamps by facet and vertex id (grown with the edit) */
    uint32_t *fmark, *vmark, *vmark2;
    uint32_t capf, capv;
    uint32_t gen;          /* current stamp; bumped by geo_mw_stamp */
    const geo_ctx *ctx;    /* the run's, while a round merges (NULL
                              otherwise): geo_mw_check asks it */
    /* sides of vertices against the current plane, valid where
     * vside_at[v] == sgen (bumped by geo_mw_side_reset) */
    uint32_t *vside_at;
    int8_t *vside;
    uint32_t sgen;

    /* scratch lists */
    uint32_t *buf_a, *buf_b, *buf_c;
    uint32_t cap_a, cap_b, cap_c;

    /* vertices moved by lifting since the report was last read:
     * (vertex id, displacement) */
    uint32_t *moved_id;
    double (*moved_by)[3];
    uint32_t nmoved, capmoved;

    uint32_t statement_violations;

    /* when set, the merged facet gets this plane instead of a fitted one
     * (the bevel pass: a strip joins its neighbour in the neighbour's
     * plane) */
    const double *fixed_plane;
} geo_mw;

/* A new workspace over e (borrowed; the caller frees it after the
 * workspace). NULL on out-of-memory. */
geo_mw *geo_mw_new(geo_edit *e, const geo_merge_opts *opts, geo_err *err);
geo_mw *geo_mw_free(geo_mw *w);

/* Makes the stamp arrays cover every current vertex and facet id; bumps
 * the generation (all marks become stale). 0 or -ENOMEM. */
int geo_mw_stamp(geo_mw *w);

/* Grows scratch list *buf to need entries. 0 or -ENOMEM. */
int geo_mw_grow(uint32_t **buf, uint32_t *cap, size_t need);

/* (Re)builds the world BVH over the live facets of the edit. 0 or
 * -ENOMEM. */
int geo_mw_world_build(geo_mw *w, geo_err *err);

/* After a committed change: enlarge the boxes of the touched facets
 * (ids from geo_edit_touched_facets, copied before the commit) and list
 * the new ones as extra. 0 or -ENOMEM. */
int geo_mw_world_update(geo_mw *w, const uint32_t *touched, uint32_t n);

/* The local validity check of the running transaction (see merge.c):
 * the touched facets and vertices are planar, closed, manifold, not
 * inverted, not degenerate and intersect nothing. 0 when valid, else
 * -EINVAL with err saying what is wrong, or -ENOMEM. */
int geo_mw_check(geo_mw *w, geo_err *err);

/* Steps of one merge (merge_contour.c, merge_lift.c, merge_cut.c), all
 * inside the caller's transaction; each returns 0, -EINVAL with err
 * saying why the group cannot be merged, or -ENOMEM. */

/* §2.4: validates the group, walks its enclosing contour, replaces the
 * group by one facet (*ret_main) on that contour and removes the
 * hanging vertices. Fills rep->contour, rep->hanging_removed and
 * rep->dev_before is left to the caller. The group's distinct vertices
 * are left in w->buf_c[0 .. *ret_nverts) (for the deviation figures). */
int geo_mw_contour(geo_mw *w, const uint32_t *group, uint32_t n,
                   uint32_t *ret_main, uint32_t *ret_nverts,
                   geo_merge_group *rep, geo_err *err);

/* §2.5: the plane of the merged facet as w->plane_mode says (normal
 * along the facet's Newell vector), or w->fixed_plane when set. */
int geo_mw_plane(geo_mw *w, uint32_t main, double ret_plane[4],
                 geo_err *err);

/* §2.6: lifts the main facet's vertices below the plane until none is
 * left (statements 1–3 of §2.7 checked on the way). */
int geo_mw_lift(geo_mw *w, uint32_t main, const double plane[4],
                geo_merge_group *rep, geo_err *err);

/* §2.8 / §3.4: cuts the model by the plane, the main facet (all its
 * vertices on or above the plane) replaced by the section, which must be
 * one component; the main facet keeps its id and gets the plane. */
int geo_mw_cut(geo_mw *w, uint32_t main, const double plane[4],
               geo_merge_group *rep, geo_err *err);

/* Merges one group (all of the above plus the check) in its own
 * transaction; on failure the edit is rolled back, rep->status and
 * rep->reason say why, and -EINVAL is returned (-ENOMEM, -ECANCELED
 * pass through, also with the edit rolled back). */
int geo_mw_merge(geo_mw *w, const uint32_t *group, uint32_t n,
                 geo_merge_group *rep, geo_err *err);

/* Appends a group of n facets to rep (facets copied) and returns it in
 * *ret. 0 or -ENOMEM. */
int geo_merge_report_add(geo_merge_report *rep, const uint32_t *facets,
                         uint32_t n, geo_merge_group **ret);

/* Writes the edit into out (geo_edit_to_poly) and completes rep: merged
 * and failed counts, each merged group's out_facet, the moved input
 * vertices (in_verts: the nin input positions), the after-figures.
 * 0 or -ENOMEM. */
int geo_merge_report_finish(geo_merge_report *rep, const geo_edit *e,
                            const double (*in_verts)[3], uint32_t nin,
                            geo_poly *out);

/* The criterion of automatic groups (merge_groups.c, README "Automatic
 * correction"): every member's normal within acos(cosmax) of the group's
 * least-squares plane and every vertex within max(max_dev,
 * roof_factor·sin(inclination)·width·step) of it, width being the
 * group's extent along its plane's middle axis of inertia, the
 * inclination the plane's angle with the horizontal and step the
 * scanner's view step (radians, 0 when unknown); when noise > 0, also
 * each facet that joins within rms_factor·noise +
 * step_factor·extent·step (area RMS distance, mm) of the plane the group
 * had before it, extent being the diagonal of the grown group's box. */
/* The factors (README "Automatic correction" says how they were chosen). */
#define GEO_GROUP_RMS_FACTOR 3.0
#define GEO_GROUP_STEP_FACTOR 0.1
#define GEO_GROUP_ROOF_FACTOR 0.25

typedef struct geo_group_crit {
    double cosmax;
    double max_dev;
    double noise;
    double step;
} geo_group_crit;

/* Automatic groups of the current edit (merge_groups.c): CSR lists
 * (*ret_start: *ret_n + 1 offsets; *ret_facets) malloc'd for the caller,
 * largest seed first. 0, -ENOMEM or -ECANCELED (ctx, may be NULL, is
 * asked as the groups grow: growing one is quadratic in its candidates). */
int geo_mw_find_groups(geo_mw *w, const geo_group_crit *c, const geo_ctx *ctx,
                       uint32_t **ret_start, uint32_t **ret_facets,
                       uint32_t *ret_n);

/* One round of automatic merging: finds the groups and merges each
 * (members merged away meanwhile are dropped from it, and a group whose
 * facets an earlier group changed is merged only if it still meets the
 * angle and deviation bounds); groups go into rep. *ret_merged counts the
 * groups merged. 0, -ENOMEM or -ECANCELED (ctx is asked between groups;
 * frac0..frac1 is this round's share of the progress). */
int geo_mw_auto_round(geo_mw *w, const geo_group_crit *c, const geo_ctx *ctx,
                      double frac0, double frac1, geo_merge_report *rep,
                      uint32_t *ret_merged, geo_err *err);

/* Area moments of facet f about the point o (fan triangles): area,
 * first moment Σ∫(x − o) dA and second moment Σ∫(x − o)(x − o)ᵀ dA
 * (added to *a, s and ss). */
void geo_mw_facet_moments(const geo_edit *e, uint32_t f, const double o[3],
                          double *a, double s[3], double ss[3][3]);

/* The surface noise of the scan (merge_scale.c): the median, over the
 * groups of at least two facets the criterion c finds (with c->noise
 * ignored), of the area RMS distance of the group's surface from its
 * area least-squares plane; 0 when there is no such group. 0, -ENOMEM or
 * -ECANCELED. */
int geo_mw_surface_noise(geo_mw *w, const geo_group_crit *c,
                         const geo_ctx *ctx, double *ret);

/* One pass removing bevel strips (merge_bevel.c): each facet that is a
 * strip along the edge of two larger neighbours, within a few times
 * c->max_dev of both their planes, is merged into one of them with that neighbour's plane
 * kept. Groups go into rep; *ret_merged counts them. 0, -ENOMEM or
 * -ECANCELED. */
int geo_mw_bevel_pass(geo_mw *w, const geo_group_crit *c, const geo_ctx *ctx,
                      geo_merge_report *rep, uint32_t *ret_merged,
                      geo_err *err);

/* Side of v against plane with the tolerance: 0 when |plane(v)| ≤ eps,
 * else the sign; decided once and cached until geo_mw_side_reset (which
 * must be called whenever the plane or a position changes). */
int geo_mw_side(geo_mw *w, uint32_t v, const double plane[4]);
void geo_mw_side_reset(geo_mw *w);

#endif
