/* hausdorff.c — the Hausdorff distance estimate of hausdorff.h: the
 * samples of one surface queried against the other (surface.h). */
#include "hausdorff.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "edgemap.h"
#include "surface.h"
#include "vec.h"

/* The larger of worst and p's distance² to s (compared, not fmax: a
 * libm call per sample). */
static double above(const geo_surface *s, const double p[3], double worst,
                    uint32_t *hint)
{
    double d = geo_surface_dist2_above(s, p, worst, hint);
    return d > worst ? d : worst;
}

static int directed(const geo_poly *a, const geo_poly *b, const geo_ctx *ctx,
                    double *ret, geo_err *err)
{
    if (b->nfacets == 0)
        return geo_err_set(err, -EINVAL, "hausdorff: the second surface has "
                           "no facets");
    geo_surface *s;
    int rc = geo_surface_new(b, &s, err);
    if (rc < 0)
        return rc;
    double worst = 0;
    uint32_t hint = UINT32_MAX;
    uint8_t *seen = calloc((size_t)a->nverts + 1, 1);
    /* an edge of two facets is sampled once: the same midpoint queried
     * again cannot raise the maximum (the result does not depend on the
     * order or the repeats of the samples) */
    geo_edgemap edges = {0};
    if (!seen || geo_edgemap_init(&edges, geo_poly_ncorners(a) / 2 + 1) < 0) {
        free(seen);
        geo_surface_free(s);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    for (uint32_t f = 0; f < a->nfacets; f++) {
        /* a sample near a large non-convex facet costs O(its size) */
        if ((f & 255) == 255 && geo_ctx_canceled(ctx)) {
            rc = geo_err_set(err, -ECANCELED, "hausdorff: canceled");
            break;
        }
        uint32_t n = geo_poly_facet_size(a, f);
        const uint32_t *vs = geo_poly_facet(a, f);
        double c[3] = {0, 0, 0};
        for (uint32_t i = 0, j = n - 1; i < n; j = i++) {
            double m[3];
            uint32_t u = vs[i], w = vs[j];
            geo_vadd(c, a->verts[u], c);
            if (!seen[u]) {
                seen[u] = 1;
                worst = above(s, a->verts[u], worst, &hint);
            }
            uint64_t key = geo_edge_ukey(u, w);
            if (geo_edgemap_get(&edges, key) != UINT32_MAX)
                continue;
            if (geo_edgemap_put(&edges, key, 1) < 0) {
                rc = geo_err_set(err, -ENOMEM, "out of memory");
                break;
            }
            geo_vadd(a->verts[u], a->verts[w], m);
            geo_vscale(m, 0.5, m);
            worst = above(s, m, worst, &hint);
        }
        if (rc < 0)
            break;
        if (n) {
            geo_vscale(c, 1.0 / n, c);
            worst = above(s, c, worst, &hint);
        }
    }
    free(seen);
    geo_edgemap_destroy(&edges);
    geo_surface_free(s);
    *ret = sqrt(worst);
    return rc;
}

int geo_hausdorff_directed(const geo_poly *a, const geo_poly *b, double *ret,
                           geo_err *err)
{
    return directed(a, b, NULL, ret, err);
}

int geo_hausdorff_ctx(const geo_poly *a, const geo_poly *b,
                      const geo_ctx *ctx, double *ret, geo_err *err)
{
    double ab, ba;
    int r = directed(a, b, ctx, &ab, err);
    if (r == 0)
        r = directed(b, a, ctx, &ba, err);
    if (r == 0)
        *ret = fmax(ab, ba);
    return r;
}

int geo_hausdorff(const geo_poly *a, const geo_poly *b, double *ret,
                  geo_err *err)
{
    return geo_hausdorff_ctx(a, b, NULL, ret, err);
}
