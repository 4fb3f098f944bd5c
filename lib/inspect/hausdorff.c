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

/* The largest distance from a's samples to s (b's surface), visiting a's
 * facets in order (NULL: index order). */
static int directed_to(const geo_poly *a, const uint32_t *order,
                       const geo_surface *s, const geo_ctx *ctx, double *ret,
                       geo_err *err)
{
    int rc = 0;
    double worst = 0;
    uint32_t hint = UINT32_MAX;
    uint8_t *seen = calloc((size_t)a->nverts + 1, 1);
    /* an edge of two facets is sampled once: the same midpoint queried
     * again cannot raise the maximum (the result does not depend on the
     * order or the repeats of the samples) */
    geo_edgemap edges = {0};
    if (!seen || geo_edgemap_init(&edges, geo_poly_ncorners(a) / 2 + 1) < 0) {
        free(seen);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    for (uint32_t k = 0; k < a->nfacets; k++) {
        uint32_t f = order ? order[k] : k;
        /* a sample near a large non-convex facet costs O(its size) */
        if ((k & 255) == 255 && geo_ctx_canceled(ctx)) {
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
    *ret = sqrt(worst);
    return rc;
}

static int no_facets(const char *which, geo_err *err)
{
    return geo_err_set(err, -EINVAL, "hausdorff: the %s surface has no "
                       "facets", which);
}

int geo_hausdorff_directed(const geo_poly *a, const geo_poly *b, double *ret,
                           geo_err *err)
{
    if (b->nfacets == 0)
        return no_facets("second", err);
    geo_surface *s;
    int r = geo_surface_new(b, &s, err);
    if (r == 0)
        r = directed_to(a, NULL, s, NULL, ret, err);
    geo_surface_free(s);
    return r;
}

/* Both surfaces are indexed first: each one's leaf order is the order its
 * samples are queried in against the other (the samples of one scan
 * facet after another in file order jump across the stone, and a hint
 * from far away prunes nothing). */
int geo_hausdorff_ctx(const geo_poly *a, const geo_poly *b,
                      const geo_ctx *ctx, double *ret, geo_err *err)
{
    if (a->nfacets == 0 || b->nfacets == 0)
        return no_facets(a->nfacets == 0 ? "first" : "second", err);
    geo_surface *sa = NULL, *sb = NULL;
    uint32_t *oa = malloc(((size_t)a->nfacets + 1) * sizeof *oa);
    uint32_t *ob = malloc(((size_t)b->nfacets + 1) * sizeof *ob);
    int r = oa && ob ? 0 : geo_err_set(err, -ENOMEM, "out of memory");
    if (r == 0)
        r = geo_surface_new(b, &sb, err);
    if (r == 0)
        r = geo_surface_new(a, &sa, err);
    double ab, ba;
    if (r == 0) {
        geo_surface_facet_order(sa, oa);
        geo_surface_facet_order(sb, ob);
        r = directed_to(a, oa, sb, ctx, &ab, err);
    }
    if (r == 0)
        r = directed_to(b, ob, sa, ctx, &ba, err);
    if (r == 0)
        *ret = fmax(ab, ba);
    geo_surface_free(sa);
    geo_surface_free(sb);
    free(oa), free(ob);
    return r;
}

int geo_hausdorff(const geo_poly *a, const geo_poly *b, double *ret,
                  geo_err *err)
{
    return geo_hausdorff_ctx(a, b, NULL, ret, err);
}
