/* model_cmp.c — comparing two polyhedra in tests. */
#include "model_cmp.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static bool same_number(double x, double y, double tol)
{
    if (tol == 0)
        return memcmp(&x, &y, sizeof x) == 0;
    return fabs(x - y) <= tol;
}

bool tu_poly_same(const geo_poly *a, const geo_poly *b, double vtol,
                  double ptol, char *why, size_t n)
{
    if (a->nverts != b->nverts || a->nfacets != b->nfacets) {
        snprintf(why, n, "counts %u/%u vs %u/%u", a->nverts, a->nfacets,
                 b->nverts, b->nfacets);
        return false;
    }
    for (uint32_t i = 0; i < a->nverts; i++)
        for (int k = 0; k < 3; k++)
            if (!same_number(a->verts[i][k], b->verts[i][k], vtol)) {
                snprintf(why, n, "vertices[%u][%d]: %.17g vs %.17g", i, k,
                         a->verts[i][k], b->verts[i][k]);
                return false;
            }
    for (uint32_t f = 0; f <= a->nfacets; f++)
        if (a->fstart[f] != b->fstart[f]) {
            snprintf(why, n, "facets[%u]: different sizes", f ? f - 1 : 0);
            return false;
        }
    for (uint32_t c = 0; c < geo_poly_ncorners(a); c++)
        if (a->fidx[c] != b->fidx[c]) {
            snprintf(why, n, "corner %u: index %u vs %u", c, a->fidx[c],
                     b->fidx[c]);
            return false;
        }
    if (ptol >= 0)
        for (uint32_t f = 0; f < a->nfacets; f++)
            for (int k = 0; k < 4; k++)
                if (!same_number(a->planes[f][k], b->planes[f][k], ptol)) {
                    snprintf(why, n, "facets[%u].plane[%d]: %.17g vs %.17g",
                             f, k, a->planes[f][k], b->planes[f][k]);
                    return false;
                }
    return true;
}
