/* select.h — the k-th smallest of n doubles (a median, for the robust
 * scales of the plane fits) without sorting them: O(n) expected where a
 * sort is O(n log n), the same value a sort would put at k. */
#ifndef GEO_SELECT_H
#define GEO_SELECT_H

#include <stdint.h>

/* Reorders a[0..n) and returns its k-th smallest element (k < n, no NaN
 * among them): the value a[k] would hold were a sorted ascending. */
double geo_select_kth(double *a, uint32_t n, uint32_t k);

#endif
