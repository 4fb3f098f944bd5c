/* rim_split.c — see rim_split.h. */
#include "rim_split.h"

#include <string.h>

#include "topo.h"

geo_poly *rim_split(const geo_poly *p)
{
    geo_topo *t = geo_topo_build(p, NULL);
    geo_poly *q = geo_poly_new();
    for (uint32_t v = 0; v < p->nverts; v++)
        geo_poly_add_vertex(q, p->verts[v]);
    uint32_t fv[256];
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t k = geo_poly_facet_size(p, f), m = 0, free_edges = 0, at = 0;
        const uint32_t *src = geo_poly_facet(p, f);
        for (uint32_t c = 0; c < k; c++)
            free_edges += t->mate[p->fstart[f] + c] == GEO_NONE;
        for (uint32_t c = 0; c < k && m + 2 < 256; c++) {
            fv[m++] = src[c];
            if (t->mate[p->fstart[f] + c] == GEO_NONE) {
                double x[3];
                for (int d = 0; d < 3; d++)
                    x[d] = 0.5 * (p->verts[src[c]][d] + p->verts[src[(c + 1) % k]][d]);
                at = m;
                fv[m++] = (uint32_t)geo_poly_add_vertex(q, x);
            }
        }
        if (free_edges != 1 || m < 4) {
            int64_t nf = geo_poly_add_facet(q, fv, m);
            memcpy(q->planes[nf], p->planes[f], sizeof q->planes[0]);
            continue;
        }
        /* the chord from m (position at) to the vertex opposite */
        uint32_t h = (at + m / 2) % m, a[256], b[256], na = 0, nb = 0;
        for (uint32_t i = at;; i = (i + 1) % m) {
            a[na++] = fv[i];
            if (i == h)
                break;
        }
        for (uint32_t i = h;; i = (i + 1) % m) {
            b[nb++] = fv[i];
            if (i == at)
                break;
        }
        int64_t nf = geo_poly_add_facet(q, a, na);
        memcpy(q->planes[nf], p->planes[f], sizeof q->planes[0]);
        nf = geo_poly_add_facet(q, b, nb);
        memcpy(q->planes[nf], p->planes[f], sizeof q->planes[0]);
    }
    geo_topo_free(t);
    return q;
}
