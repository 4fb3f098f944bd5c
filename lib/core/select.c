/* select.c — quickselect with a median-of-three pivot (select.h); after
 * 2·log2(n) + 8 rounds that have not narrowed the range (an adversarial
 * order) the rest is sorted, so the worst case stays O(n log n). */
#include "select.h"

#include <stdlib.h>

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void swap(double *a, uint32_t i, uint32_t j)
{
    double t = a[i];
    a[i] = a[j];
    a[j] = t;
}

double geo_select_kth(double *a, uint32_t n, uint32_t k)
{
    uint32_t lo = 0, hi = n; /* a[k] lies in [lo, hi) */
    int budget = 8;
    for (uint32_t m = n; m > 1; m >>= 1)
        budget += 2;
    while (hi - lo > 16) {
        if (budget-- == 0) {
            qsort(a + lo, hi - lo, sizeof *a, cmp_double);
            return a[k];
        }
        uint32_t mid = lo + (hi - lo) / 2;
        if (a[mid] < a[lo])
            swap(a, mid, lo);
        if (a[hi - 1] < a[lo])
            swap(a, hi - 1, lo);
        if (a[hi - 1] < a[mid])
            swap(a, hi - 1, mid);
        double pivot = a[mid];
        /* three ways: < pivot, == pivot, > pivot (many equal values, as
         * residuals of zero, end the search at once) */
        uint32_t lt = lo, i = lo, gt = hi;
        while (i < gt) {
            if (a[i] < pivot)
                swap(a, lt++, i++);
            else if (a[i] > pivot)
                swap(a, i, --gt);
            else
                i++;
        }
        if (k < lt)
            hi = lt;
        else if (k >= gt)
            lo = gt;
        else
            return pivot;
    }
    /* a short range: insertion sort */
    for (uint32_t i = lo + 1; i < hi; i++) {
        double v = a[i];
        uint32_t j = i;
        for (; j > lo && a[j - 1] > v; j--)
            a[j] = a[j - 1];
        a[j] = v;
    }
    return a[k];
}

typedef struct axis_key {
    const double (*pts)[3];
    int axis;
} axis_key;

static int cmp_axis(const void *a, const void *b, void *arg)
{
    const axis_key *k = arg;
    double x = k->pts[*(const uint32_t *)a][k->axis];
    double y = k->pts[*(const uint32_t *)b][k->axis];
    return (x > y) - (x < y);
}

void geo_select_axis(const double (*pts)[3], uint32_t *idx, uint32_t lo,
                     uint32_t hi, uint32_t k, int axis)
{
    int budget = 8;
    for (uint32_t m = hi - lo; m > 1; m >>= 1)
        budget += 2;
    while (hi - lo > 1) {
        if (budget-- == 0) {
            axis_key key = {pts, axis};
            qsort_r(idx + lo, hi - lo, sizeof *idx, cmp_axis, &key);
            return;
        }
        uint32_t mid = lo + (hi - lo) / 2;
        double a = pts[idx[lo]][axis], m = pts[idx[mid]][axis],
               z = pts[idx[hi - 1]][axis];
        double pivot = a < m ? (m < z ? m : (a < z ? z : a))
                             : (a < z ? a : (m < z ? z : m));
        /* [lo, lt) < pivot, [lt, i) == pivot, (gt, hi) > pivot */
        uint32_t lt = lo, i = lo, gt = hi;
        while (i < gt) {
            double c = pts[idx[i]][axis];
            uint32_t t = idx[i];
            if (c < pivot) {
                idx[i++] = idx[lt];
                idx[lt++] = t;
            } else if (c > pivot) {
                idx[i] = idx[--gt];
                idx[gt] = t;
            } else {
                i++;
            }
        }
        if (k < lt)
            hi = lt;
        else if (k >= gt)
            lo = gt;
        else
            return;
    }
}
