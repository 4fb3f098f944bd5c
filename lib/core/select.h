/* select.h — the k-th smallest of n doubles (a median, for the robust
 * scales of the plane fits) without sorting them: O(n) expected where a
 * sort is O(n log n), the same value a sort would put at k; and the
 * median split of point indices along an axis (the bounding-volume and
 * ball trees of bvh.c and ptree.c). */
#ifndef GEO_SELECT_H
#define GEO_SELECT_H

#include <stdint.h>

/* Reorders a[0..n) and returns its k-th smallest element (k < n, no NaN
 * among them): the value a[k] would hold were a sorted ascending. */
double geo_select_kth(double *a, uint32_t n, uint32_t k);

/* Reorders idx[lo .. hi) so that pts[idx[k]][axis] is the value a sort
 * by that coordinate would put at k, none before it larger and none
 * after it smaller (lo ≤ k < hi; no NaN among the keys): quickselect
 * with median-of-three pivots and a three-way partition (runs of equal
 * keys always make progress); after 2·log2(n) + 8 rounds that have not
 * found k (an adversarial order) the rest is sorted, so the worst case
 * stays O(n log n). */
void geo_select_axis(const double (*pts)[3], uint32_t *idx, uint32_t lo,
                     uint32_t hi, uint32_t k, int axis);

#endif
