/* correct.h — the automatic post-scan correction (Palachev 2012, §2, §4.1): the
 * correction every scan gets before anything else is done with it.
 *
 *   inspect → re-orient if needed → repeat { merge the groups of nearly
 *   coplanar facets (merge.h, until a round merges nothing); collapse the
 *   clusters of vertices joined by very short edges (clusters.h) } until
 *   neither changes anything → re-orient if needed → inspect,
 * then the Hausdorff estimate between input and result (hausdorff.h).
 *
 * Why merging comes before collapsing: on a raw scan the clusters sit in
 * fans of slivers meeting at angles of hundredths of a degree; holding
 * the collapsed vertex while re-planarizing such slivers turns some of
 * them over, so most clusters are rolled back (measured: README
 * "Automatic correction"), and the merge removes the slivers and most of
 * the heaps anyway. The clusters left after merging (a true vertex where
 * four or more merged planes nearly meet) collapse cleanly; a collapse can
 * make new groups, hence the repeat.
 *
 * The result is valid whenever the input is (each step checks what it
 * touched and rolls back what would break validity); an input that is not
 * a closed manifold is refused. Conventions of lib/core/poly.h; mm.
 * Reentrant; p changes in place only on success. */
#ifndef GEO_CORRECT_H
#define GEO_CORRECT_H

#include <stdbool.h>
#include <stdint.h>

#include "clusters.h"
#include "convex.h"
#include "ctx.h"
#include "merge.h"
#include "poly.h"
#include "stats.h"

typedef struct geo_correct_opts {
    geo_merge_opts merge;       /* geo_merge_opts_default */
    geo_collapse_opts collapse; /* geo_collapse_opts_default */
    bool collapse_clusters;     /* run the collapse [true] */
    bool convex;                /* a convex scan: its recovered planes
                                   intersected (convex.h) instead of the
                                   merge rounds, which stay the fallback
                                   and the path of a non-convex scan
                                   [true: on the fixed suite it recovers
                                   more facets, see
                                   docs/kernels/correct-convex.md] */
    enum geo_convex_fit convex_fit; /* its planes
                                       [GEO_CONVEX_FIT_SILHOUETTE] */
    uint32_t max_rounds;        /* merge + collapse rounds [4] */
    bool input_stats;           /* report.before holds every statistic of
                                   the input [true]; false: only what the
                                   correction needs of it (closed,
                                   manifold, orientation), the rest zero
                                   — the self-intersection search of the
                                   input is most of geo_inspect's time,
                                   and a caller that writes no report
                                   has no use for it */
} geo_correct_opts;

/* Fills the defaults. */
void geo_correct_opts_default(geo_correct_opts *o);

typedef struct geo_correct_report {
    geo_stats before, after;    /* geo_inspect of the input (but see
                                   input_stats) and of the result */
    geo_merge_report merge;     /* every group of every round; facet ids
                                   as in merge.h, numbered per merge pass:
                                   pass k's ids refer to the model that
                                   pass started from */
    uint32_t merge_passes;
    uint32_t clusters_found, clusters_collapsed, clusters_rolled_back;
    double cluster_max_displacement; /* mm */
    uint32_t reoriented_facets; /* facets flipped by geo_orient_repair */
    uint32_t views;             /* the scanner's views used by the
                                   automatic groups (0: none known) */
    double noise;               /* the scan's surface noise they used, mm
                                   (0: no noise test) */
    uint32_t rounds;
    bool convex_tried;          /* the convex path was asked for */
    bool convex;                /* the convex path gave the result */
    geo_convex_report convex_report; /* what it did, or why not */
    uint32_t vertices_before, facets_before, vertices_after, facets_after;
    double volume_before, volume_after; /* mm³ */
    double hausdorff;           /* estimate between input and result, mm */
    /* Input vertices that survive with a new position: their index in the
     * result and displacement (mm). */
    geo_moved_vertex *moved;
    uint32_t nmoved;
} geo_correct_report;

/* Releases the report's arrays and zeroes it; accepts NULL. */
void geo_correct_report_clear(geo_correct_report *r);

/* Corrects p in place (see above). opts NULL means defaults; report may
 * be NULL. Returns 0, -EINVAL (p not a closed manifold, not orientable,
 * or invalid indices; err says which), -ENOMEM, -ECANCELED (p unchanged
 * on error). */
int geo_correct(geo_poly *p, const geo_correct_opts *opts,
                     const geo_ctx *ctx, geo_correct_report *report,
                     geo_err *err);

#endif
