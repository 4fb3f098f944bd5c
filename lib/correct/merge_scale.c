/* merge_scale.c — what a scan tells of its own error, for the automatic
 * groups (merge_groups.c): the scanner's view step, read off the facet
 * normals, and the surface noise, measured on the groups of nearly
 * coplanar facets.
 *
 * The view step. A shadow-profile scanner (Palachev 2012, §1.2) turns the stone
 * about the holder axis z in K equal steps over 180°; every silhouette
 * plane of view k contains that view's direction d_k = (cos θ_k, sin θ_k,
 * 0), so the normal n of every facet it leaves satisfies n·d_k = 0: the
 * normals' azimuths, taken modulo 180°, sit on a grid of step 180°/K (to
 * rounding). The grid shows as the most frequent gap between the distinct
 * azimuths (each view gives many facets of one azimuth, so nearly every
 * grid point is occupied and the gaps are the step itself); it is
 * accepted when at least half of the facets lie on it. A model that is
 * not a raw scan (already corrected, or designed) has no such grid.
 *
 * The surface noise: the median, over the groups the deviation and angle
 * bounds find, of the area RMS distance of the group's surface from its
 * least-squares plane. A group of one true facet's slivers lies within
 * the silhouette noise plus the roof its view step leaves; the median is
 * robust to the groups that join two true facets.
 *
 * Both cost O(n log n) (sorts), the noise one grouping pass more. */
#include "merge_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "vec.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* How many of the n sorted values lie in [lo, hi]. */
static uint32_t count_within(const double *v, uint32_t n, double lo,
                             double hi)
{
    uint32_t a = 0, b = n; /* first ≥ lo */
    while (a < b) {
        uint32_t m = a + (b - a) / 2;
        if (v[m] < lo)
            a = m + 1;
        else
            b = m;
    }
    uint32_t c = a, d = n; /* first > hi */
    while (c < d) {
        uint32_t m = c + (d - c) / 2;
        if (v[m] <= hi)
            c = m + 1;
        else
            d = m;
    }
    return c - a;
}

/* Azimuths closer than this (radians) are one grid value: far above the
 * rounding of unit normals (1e-16 / their horizontal length, which is at
 * least 1e-3 here) and far below any view step (π/100000). */
#define AZ_TOL 1e-9

int geo_merge_view_grid(const geo_poly *p, uint32_t *ret_views,
                        double *ret_fraction)
{
    *ret_views = 0;
    if (ret_fraction)
        *ret_fraction = 0;
    uint32_t n = 0;
    double *az = malloc(((size_t)p->nfacets + 1) * sizeof *az);
    double *gap = malloc(((size_t)p->nfacets + 1) * sizeof *gap);
    if (!az || !gap) {
        free(az), free(gap);
        return -ENOMEM;
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const double *nr = p->planes[f];
        /* a horizontal facet's azimuth says nothing */
        if (hypot(nr[0], nr[1]) < 1e-3)
            continue;
        double a = atan2(nr[1], nr[0]);
        a = fmod(a + 2 * M_PI, M_PI);
        az[n++] = a;
    }
    qsort(az, n, sizeof *az, cmp_double);
    uint32_t ng = 0;
    for (uint32_t i = 1; i < n; i++)
        if (az[i] - az[i - 1] > AZ_TOL)
            gap[ng++] = az[i] - az[i - 1];
    qsort(gap, ng, sizeof *gap, cmp_double);
    /* the most frequent gap: the longest run of gaps equal within the
     * tolerance */
    uint32_t best = 0, bi = 0;
    for (uint32_t i = 0, j = 0; i < ng; i++) {
        if (j < i)
            j = i;
        while (j + 1 < ng && gap[j + 1] - gap[i] <= 2 * AZ_TOL)
            j++;
        if (j - i + 1 > best) {
            best = j - i + 1;
            bi = i;
        }
    }
    if (best >= 3) {
        double s = gap[bi + best / 2];
        double k = round(M_PI / s);
        if (k >= 2 && k <= 1e5 && fabs(M_PI / k - s) <= 4 * AZ_TOL) {
            double step = M_PI / k;
            /* the facets on the grid, its offset tried at the residues
             * of up to 64 facets (the grid need not start at 0): a facet
             * is on it when its residue is within AZ_TOL of the offset,
             * round the step — counted in the sorted residues (gap's
             * storage, no longer needed), not by a remainder per pair */
            double *res = gap;
            for (uint32_t j = 0; j < n; j++)
                res[j] = fmod(az[j], step);
            double *sorted = az; /* the azimuths are not read again */
            memcpy(sorted, res, (size_t)n * sizeof *sorted);
            qsort(sorted, n, sizeof *sorted, cmp_double);
            uint32_t bon = 0;
            for (uint32_t i = 0; i < n; i += 1 + n / 64) {
                double o = res[i];
                uint32_t on = count_within(sorted, n, o - AZ_TOL, o + AZ_TOL);
                if (o - AZ_TOL < 0)
                    on += count_within(sorted, n, o - AZ_TOL + step, step);
                if (o + AZ_TOL >= step)
                    on += count_within(sorted, n, 0, o + AZ_TOL - step);
                if (on > bon)
                    bon = on;
            }
            if (ret_fraction)
                *ret_fraction = (double)bon / n;
            if (2 * bon >= n)
                *ret_views = (uint32_t)k;
        }
    }
    free(az), free(gap);
    return 0;
}

int geo_mw_surface_noise(geo_mw *w, const geo_group_crit *c,
                         const geo_ctx *ctx, double *ret)
{
    geo_group_crit c0 = *c;
    c0.noise = 0;
    uint32_t *start = NULL, *facets = NULL, ng = 0;
    *ret = 0;
    int r = geo_mw_find_groups(w, &c0, ctx, &start, &facets, &ng);
    if (r < 0)
        return r;
    double *rms = malloc(((size_t)ng + 1) * sizeof *rms);
    if (!rms) {
        free(start), free(facets);
        return -ENOMEM;
    }
    const geo_edit *e = w->e;
    uint32_t nr = 0;
    for (uint32_t g = 0; g < ng; g++) {
        if (start[g + 1] - start[g] < 2)
            continue;
        double o[3], a = 0, s[3] = {0, 0, 0}, ss[3][3] = {{0}};
        memcpy(o, e->verts[geo_edit_fv(e, facets[start[g]])[0]], sizeof o);
        for (uint32_t k = start[g]; k < start[g + 1]; k++)
            geo_mw_facet_moments(e, facets[k], o, &a, s, ss);
        if (!(a > 0))
            continue;
        double mu[3], cv[3][3], val[3], vec[3][3];
        for (int i = 0; i < 3; i++)
            mu[i] = s[i] / a;
        for (int i = 0; i < 3; i++)
            for (int j = i; j < 3; j++)
                cv[i][j] = ss[i][j] / a - mu[i] * mu[j];
        geo_sym3_eigen(cv, val, vec);
        rms[nr++] = sqrt(fmax(val[0], 0));
    }
    if (nr) {
        qsort(rms, nr, sizeof *rms, cmp_double);
        *ret = nr % 2 ? rms[nr / 2] : 0.5 * (rms[nr / 2 - 1] + rms[nr / 2]);
    }
    free(rms), free(start), free(facets);
    return 0;
}
