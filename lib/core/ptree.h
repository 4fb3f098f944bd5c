/* ptree.h — a tree of balls over a point set, for "which points may lie
 * above this plane" (the convex correction's check of a scan's vertices
 * against a result's planes: most pairs are far below the bound) and
 * "how far do the points reach above these planes" (its check of the
 * result's vertices against the scan's planes, where an ascent along the
 * result's edges cannot be used).
 *
 * The points are split at the median of their box's longest side down
 * to a few a leaf; each node keeps the ball about its box's centre that
 * holds its points. A query skips a node whose ball stays below the
 * level, so a plane near few points costs about their number times the
 * depth. The answer is a superset: every point where the plane's value
 * (geo_plane_eval) exceeds the level is listed, whatever the rounding.
 *
 * Ownership: the tree copies what it needs (the points are read only
 * during geo_ptree_build). A tree may be queried by several threads. */
#ifndef GEO_PTREE_H
#define GEO_PTREE_H

#include <stdint.h>

typedef struct geo_ptree geo_ptree;

/* The tree of pts[0 .. n). 0 with *ret, or -ENOMEM (*ret NULL). */
int geo_ptree_build(const double (*pts)[3], uint32_t n, geo_ptree **ret);

/* Writes to out (room for n indices) the points x that may have
 * plane[0..2]·x + plane[3] > level, and returns their count: every point
 * where it holds, and points near it. Points with a coordinate that is
 * not finite are always listed. */
uint32_t geo_ptree_above(const geo_ptree *t, const double plane[4],
                         double level, uint32_t *out);

/* The largest value n·x + d of any of the planes at any of the points
 * (pts: those the tree was built from), and at least 0: how far the
 * points reach outside the intersection of the planes' negative
 * half-spaces, bit for bit the value the evaluation of every pair would
 * give. Most pairs are skipped: at each node the planes that may still
 * be the highest at one of its points go on to its halves (a plane's
 * value in a ball of radius r is within |n|·r of its value at the
 * centre, so one lower there than the highest by more than 2·|n|·r, or
 * below −|n|·r, goes no further; the margin covers the rounding). 0 with
 * *ret, or -ENOMEM (*ret then only a lower bound). */
int geo_ptree_reach(const geo_ptree *t, const double (*pts)[3],
                    const double (*planes)[4], uint32_t nplanes,
                    double *ret);

/* Releases t; accepts NULL; returns NULL. */
geo_ptree *geo_ptree_free(geo_ptree *t);

#endif
