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
