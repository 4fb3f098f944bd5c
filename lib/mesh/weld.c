/* weld.c — coincident boundary vertices made one (weld.h). */
#include "weld.h"

#include <errno.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* Orders vertex indices by their coordinates, then by index. */
static int cmp_position(const void *a, const void *b, void *user)
{
    const geo_poly *p = user;
    uint32_t u = *(const uint32_t *)a, v = *(const uint32_t *)b;
    for (int k = 0; k < 3; k++)
        if (p->verts[u][k] != p->verts[v][k])
            return p->verts[u][k] < p->verts[v][k] ? -1 : 1;
    return (u > v) - (u < v);
}

static bool same_position(const geo_poly *p, uint32_t u, uint32_t v)
{
    return p->verts[u][0] == p->verts[v][0] &&
           p->verts[u][1] == p->verts[v][1] &&
           p->verts[u][2] == p->verts[v][2];
}

/* Does some facet of p list one vertex twice? */
static bool has_repeated_vertex(const geo_poly *p)
{
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = i + 1; j < n; j++)
                if (fv[i] == fv[j])
                    return true;
    }
    return false;
}

int geo_weld_boundary(geo_poly *p, const geo_topo *t, uint32_t *ret_welded,
                      geo_err *err)
{
    *ret_welded = 0;
    uint32_t nv = p->nverts, nc = geo_poly_ncorners(p), nb = 0;
    uint32_t *bv = malloc(((size_t)nv + 1) * sizeof *bv);
    uint32_t *to = malloc(((size_t)nv + 1) * sizeof *to);
    bool *on = calloc((size_t)nv + 1, sizeof *on);
    geo_poly *q = NULL;
    geo_topo *tq = NULL;
    int rc = -ENOMEM;
    if (!bv || !to || !on)
        goto done;
    /* a boundary corner's edge starts at its vertex and ends at the next
     * corner's: both ends are on the boundary */
    for (uint32_t c = 0; c < nc; c++)
        if (t->edge_kind[c] == GEO_EDGE_BOUNDARY) {
            on[p->fidx[c]] = true;
            on[p->fidx[geo_topo_next(p, t, c)]] = true;
        }
    for (uint32_t v = 0; v < nv; v++) {
        to[v] = v;
        if (on[v])
            bv[nb++] = v;
    }
    qsort_r(bv, nb, sizeof *bv, cmp_position, p);
    bool any = false;
    for (uint32_t i = 1; i < nb; i++)
        if (same_position(p, bv[i - 1], bv[i])) {
            to[bv[i]] = to[bv[i - 1]]; /* the lowest of its run */
            any = true;
        }
    rc = 0;
    if (!any)
        goto done;
    rc = -ENOMEM;
    if (!(q = geo_poly_copy(p)))
        goto done;
    for (uint32_t c = 0; c < nc; c++)
        q->fidx[c] = to[q->fidx[c]];
    rc = 0;
    if (has_repeated_vertex(q))
        goto done; /* a facet with two coincident vertices of its own */
    rc = -ENOMEM;
    if (!(tq = geo_topo_build(q, err)))
        goto done;
    rc = 0;
    if (tq->nboundary_edges >= t->nboundary_edges ||
        tq->nnonmanifold_edges > t->nnonmanifold_edges ||
        tq->nnonmanifold_vertices > t->nnonmanifold_vertices ||
        tq->nflipped_edges > t->nflipped_edges)
        goto done;
    rc = -ENOMEM;
    if (geo_poly_compact(q, NULL, NULL, NULL) < 0)
        goto done;
    *ret_welded = nv - q->nverts;
    geo_poly tmp = *p;
    *p = *q;
    *q = tmp;
    rc = 0;
done:
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory");
    geo_topo_free(tq);
    geo_poly_free(q);
    free(bv), free(to), free(on);
    return rc;
}
