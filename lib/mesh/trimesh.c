/* trimesh.c — dynamic triangle mesh with a directed-edge hash (see
 * trimesh.h). Every operation first checks that it can succeed (edges
 * free, memory available), then applies, so a failure leaves the mesh
 * unchanged. */
#include "trimesh.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "selfint.h"
#include "vec.h"

int geo_tmesh_init(geo_tmesh *m, const double *xyz, uint32_t nv)
{
    memset(m, 0, sizeof *m);
    m->cap_v = nv + 64;
    m->v = malloc((size_t)m->cap_v * sizeof *m->v);
    if (!m->v || geo_edgemap_init(&m->he, 64) < 0) {
        geo_tmesh_destroy(m);
        return -ENOMEM;
    }
    if (nv)
        memcpy(m->v, xyz, (size_t)nv * sizeof *m->v);
    m->nv = nv;
    return 0;
}

void geo_tmesh_destroy(geo_tmesh *m)
{
    free(m->v);
    free(m->t);
    free(m->dead);
    free(m->tag);
    geo_edgemap_destroy(&m->he);
    memset(m, 0, sizeof *m);
}

int64_t geo_tmesh_add_vertex(geo_tmesh *m, const double p[3])
{
    if (m->nv == UINT32_MAX - 1)
        return -ENOMEM;
    if (m->nv == m->cap_v) {
        uint32_t nc = m->cap_v * 2 + 64;
        double(*nvv)[3] = realloc(m->v, (size_t)nc * sizeof *nvv);
        if (!nvv)
            return -ENOMEM;
        m->v = nvv;
        m->cap_v = nc;
    }
    memcpy(m->v[m->nv], p, sizeof m->v[0]);
    return m->nv++;
}

static int reserve_tris(geo_tmesh *m, uint32_t extra)
{
    if (m->nt + extra <= m->cap_t)
        return 0;
    uint32_t nc = m->cap_t * 2 + extra + 64;
    uint32_t(*nt)[3] = realloc(m->t, (size_t)nc * sizeof *nt);
    if (!nt)
        return -ENOMEM;
    m->t = nt;
    uint8_t *nd = realloc(m->dead, nc);
    if (!nd)
        return -ENOMEM;
    m->dead = nd;
    uint8_t *ng = realloc(m->tag, nc);
    if (!ng)
        return -ENOMEM;
    m->tag = ng;
    m->cap_t = nc;
    return 0;
}

/* Room in the edge hash for `extra` more keys, so later puts cannot
 * fail. */
static int reserve_edges(geo_tmesh *m, size_t extra)
{
    return geo_edgemap_reserve(&m->he, m->he.n + extra);
}

/* Stores triangle slot t = (a, b, c); edges must be free and room
 * reserved. */
static void put_tri(geo_tmesh *m, uint32_t t, uint32_t a, uint32_t b,
                    uint32_t c)
{
    m->t[t][0] = a;
    m->t[t][1] = b;
    m->t[t][2] = c;
    m->dead[t] = 0;
    /* reserve_edges guaranteed room: puts cannot fail */
    geo_edgemap_put(&m->he, geo_edge_key(a, b), 3 * t);
    geo_edgemap_put(&m->he, geo_edge_key(b, c), 3 * t + 1);
    geo_edgemap_put(&m->he, geo_edge_key(c, a), 3 * t + 2);
}

int64_t geo_tmesh_add(geo_tmesh *m, uint32_t a, uint32_t b, uint32_t c,
                      uint8_t tag)
{
    if (geo_tmesh_find(m, a, b) != UINT32_MAX ||
        geo_tmesh_find(m, b, c) != UINT32_MAX ||
        geo_tmesh_find(m, c, a) != UINT32_MAX)
        return -EEXIST;
    if (m->nt >= UINT32_MAX / 3 - 1 || reserve_tris(m, 1) < 0 ||
        reserve_edges(m, 3) < 0)
        return -ENOMEM;
    put_tri(m, m->nt, a, b, c);
    m->tag[m->nt] = tag;
    return m->nt++;
}

static void forget(geo_tmesh *m, uint32_t t)
{
    for (int k = 0; k < 3; k++)
        geo_edgemap_del(&m->he, geo_edge_key(m->t[t][k], m->t[t][(k + 1) % 3]));
}

int geo_tmesh_split_tri(geo_tmesh *m, uint32_t t, uint32_t x)
{
    if (reserve_tris(m, 2) < 0 || reserve_edges(m, 6) < 0)
        return -ENOMEM;
    uint32_t a = m->t[t][0], b = m->t[t][1], c = m->t[t][2];
    forget(m, t);
    put_tri(m, t, a, b, x);
    m->tag[m->nt] = m->tag[m->nt + 1] = m->tag[t];
    put_tri(m, m->nt++, b, c, x);
    put_tri(m, m->nt++, c, a, x);
    return 0;
}

int geo_tmesh_split_edge(geo_tmesh *m, uint32_t a, uint32_t b, uint32_t x)
{
    uint32_t h1 = geo_tmesh_find(m, a, b), h2 = geo_tmesh_find(m, b, a);
    if (h1 == UINT32_MAX && h2 == UINT32_MAX)
        return -ENOENT;
    if (reserve_tris(m, 2) < 0 || reserve_edges(m, 6) < 0)
        return -ENOMEM;
    uint32_t hs[2] = {h1, h2};
    for (int s = 0; s < 2; s++) {
        uint32_t h = hs[s];
        if (h == UINT32_MAX)
            continue;
        uint32_t t = h / 3, k = h % 3;
        uint32_t p = m->t[t][k], q = m->t[t][(k + 1) % 3],
                 r = m->t[t][(k + 2) % 3];
        forget(m, t);
        put_tri(m, t, p, x, r);
        m->tag[m->nt] = m->tag[t];
        put_tri(m, m->nt++, x, q, r);
    }
    return 0;
}

int geo_tmesh_flip(geo_tmesh *m, uint32_t a, uint32_t b)
{
    uint32_t h1 = geo_tmesh_find(m, a, b), h2 = geo_tmesh_find(m, b, a);
    if (h1 == UINT32_MAX || h2 == UINT32_MAX)
        return -ENOENT;
    uint32_t c = geo_tmesh_opposite(m, h1), d = geo_tmesh_opposite(m, h2);
    if (c == d || geo_tmesh_find(m, c, d) != UINT32_MAX ||
        geo_tmesh_find(m, d, c) != UINT32_MAX)
        return -EEXIST;
    if (reserve_edges(m, 2) < 0)
        return -ENOMEM;
    uint32_t t1 = h1 / 3, t2 = h2 / 3;
    forget(m, t1);
    forget(m, t2);
    put_tri(m, t1, a, d, c);
    put_tri(m, t2, b, c, d);
    return 0;
}

double geo_tmesh_normal(const geo_tmesh *m, uint32_t t, double ret_n[3])
{
    double e1[3], e2[3];
    geo_vsub(m->v[m->t[t][1]], m->v[m->t[t][0]], e1);
    geo_vsub(m->v[m->t[t][2]], m->v[m->t[t][0]], e2);
    geo_vcross(e1, e2, ret_n);
    return geo_vnormalize(ret_n);
}

void geo_tmesh_probe_destroy(geo_tmesh_probe *pr)
{
    free(pr->vstamp), free(pr->vloc), free(pr->tstamp);
    free(pr->queue), free(pr->tris), free(pr->gv);
    free(pr->box), free(pr->shape), free(pr->has_shape);
    geo_poly_free(pr->p);
    memset(pr, 0, sizeof *pr);
}

static int grow_u32(uint32_t **a, uint32_t *cap, uint32_t need, bool zero)
{
    if (need <= *cap)
        return 0;
    uint32_t nc = *cap * 2 + 64;
    if (nc < need)
        nc = need;
    uint32_t *n = realloc(*a, (size_t)nc * sizeof *n);
    if (!n)
        return -ENOMEM;
    if (zero)
        memset(n + *cap, 0, (size_t)(nc - *cap) * sizeof *n);
    *a = n;
    *cap = nc;
    return 0;
}

/* Marks triangle t as part of the neighbourhood once. */
static int probe_tri(geo_tmesh_probe *pr, uint32_t t, uint32_t *ntris)
{
    if (pr->tstamp[t] == pr->stamp)
        return 0;
    pr->tstamp[t] = pr->stamp;
    uint32_t c = pr->cap_tris;
    if (grow_u32(&pr->tris, &c, *ntris + 1, false) < 0)
        return -ENOMEM;
    pr->cap_tris = c;
    pr->tris[(*ntris)++] = t;
    return 0;
}

/* Visits vertex v (reached along an edge to w): its triangles join the
 * neighbourhood, its unvisited neighbours the queue at depth + 1. */
static int probe_fan(const geo_tmesh *m, geo_tmesh_probe *pr, uint32_t v,
                     uint32_t w, uint32_t *ntris, uint32_t *nq, bool expand)
{
    for (int dir = 0; dir < 2; dir++) {
        uint32_t u = w;
        for (uint32_t guard = 0; guard < 1024; guard++) {
            /* CCW: triangle (v, u, c) has half-edge v→u; CW: (u, v, c) */
            uint32_t h = dir ? geo_tmesh_find(m, u, v) : geo_tmesh_find(m, v, u);
            if (h == UINT32_MAX)
                break;
            if (probe_tri(pr, h / 3, ntris) < 0)
                return -ENOMEM;
            uint32_t c = geo_tmesh_opposite(m, h);
            if (expand && pr->vstamp[c] != pr->stamp) {
                pr->vstamp[c] = pr->stamp;
                uint32_t cap = pr->cap_q;
                if (grow_u32(&pr->queue, &cap, 2 * (*nq + 1), false) < 0)
                    return -ENOMEM;
                pr->cap_q = cap;
                pr->queue[2 * *nq] = c;
                pr->queue[2 * *nq + 1] = v;
                (*nq)++;
            }
            u = c;
            if (u == w)
                return 0; /* closed fan: no need to go the other way */
        }
    }
    return 0;
}

/* Local index of mesh vertex g (or GEO_TMESH_NEWV) in the probe's
 * polyhedron, adding it on first use. */
static int64_t probe_vertex(const geo_tmesh *m, geo_tmesh_probe *pr,
                            uint32_t g, uint32_t moved, const double x[3],
                            int64_t *newv)
{
    if (g == GEO_TMESH_NEWV && *newv >= 0)
        return *newv;
    if (g != GEO_TMESH_NEWV && pr->vstamp[g] == pr->stamp + 1)
        return pr->vloc[g];
    const double *pos = g == GEO_TMESH_NEWV || g == moved ? x : m->v[g];
    int64_t l = geo_poly_add_vertex(pr->p, pos);
    if (l < 0)
        return l;
    if (g != GEO_TMESH_NEWV) {
        pr->vstamp[g] = pr->stamp + 1;
        pr->vloc[g] = (uint32_t)l;
    } else {
        *newv = l;
    }
    return l;
}

/* Bounding box of triangle tv of p: lo in b[0..3), hi in b[3..6). */
static void tri_box(const geo_poly *p, const uint32_t *tv, double b[6])
{
    for (int k = 0; k < 3; k++) {
        double lo = p->verts[tv[0]][k], hi = lo;
        for (int i = 1; i < 3; i++) {
            lo = fmin(lo, p->verts[tv[i]][k]);
            hi = fmax(hi, p->verts[tv[i]][k]);
        }
        b[k] = lo;
        b[k + 3] = hi;
    }
}

static bool boxes_apart(const double a[6], const double b[6])
{
    for (int k = 0; k < 3; k++)
        if (a[k + 3] < b[k] || b[k + 3] < a[k])
            return true;
    return false;
}

int geo_tmesh_clashes(const geo_tmesh *m, geo_tmesh_probe *pr,
                      const uint32_t *old, uint32_t nold,
                      const uint32_t (*newt)[3], uint32_t nnew,
                      uint32_t moved, const double x[3], uint32_t rings)
{
    uint32_t cv = pr->cap_v;
    if (grow_u32(&pr->vstamp, &cv, m->nv, true) < 0)
        return -ENOMEM;
    if (cv != pr->cap_v) {
        uint32_t *n = realloc(pr->vloc, (size_t)cv * sizeof *n);
        if (!n)
            return -ENOMEM;
        pr->vloc = n;
        pr->cap_v = cv;
    }
    if (grow_u32(&pr->tstamp, &pr->cap_t, m->nt, true) < 0)
        return -ENOMEM;
    if (!pr->p && !(pr->p = geo_poly_new()))
        return -ENOMEM;
    /* two stamps per call: stamp marks visited, stamp + 1 mapped */
    if (pr->stamp >= UINT32_MAX - 4) {
        memset(pr->vstamp, 0, (size_t)pr->cap_v * sizeof *pr->vstamp);
        memset(pr->tstamp, 0, (size_t)pr->cap_t * sizeof *pr->tstamp);
        pr->stamp = 0;
    }
    pr->stamp += 2;
    uint32_t ntris = 0, nq = 0;
    /* old triangles are marked so that they are never collected */
    for (uint32_t i = 0; i < nold; i++)
        pr->tstamp[old[i]] = pr->stamp;
    for (uint32_t i = 0; i < nold; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t v = m->t[old[i]][k];
            if (pr->vstamp[v] == pr->stamp)
                continue;
            pr->vstamp[v] = pr->stamp;
            uint32_t cap = pr->cap_q;
            if (grow_u32(&pr->queue, &cap, 2 * (nq + 1), false) < 0)
                return -ENOMEM;
            pr->cap_q = cap;
            pr->queue[2 * nq] = v;
            pr->queue[2 * nq + 1] = m->t[old[i]][(k + 1) % 3];
            nq++;
        }
    /* breadth first: depth of queue[lo .. hi) is d */
    uint32_t lo = 0;
    for (uint32_t d = 0; d < rings && lo < nq; d++) {
        uint32_t hi = nq;
        for (uint32_t q = lo; q < hi; q++)
            if (probe_fan(m, pr, pr->queue[2 * q], pr->queue[2 * q + 1],
                          &ntris, &nq, d + 1 < rings) < 0)
                return -ENOMEM;
        lo = hi;
    }
    /* the polyhedron: neighbourhood triangles, then the new ones */
    geo_poly_clear(pr->p);
    int64_t newv = -1;
    for (uint32_t i = 0; i < ntris + nnew; i++) {
        const uint32_t *tv = i < ntris ? m->t[pr->tris[i]] : newt[i - ntris];
        uint32_t loc[3];
        for (int k = 0; k < 3; k++) {
            int64_t l = probe_vertex(m, pr, tv[k], moved, x, &newv);
            if (l < 0)
                return -ENOMEM;
            loc[k] = (uint32_t)l;
        }
        if (geo_poly_add_facet(pr->p, loc, 3) < 0)
            return -ENOMEM;
    }
    /* boxes of every facet, shapes when first needed (a facet near
     * several new triangles is looked at once) */
    uint32_t nf = ntris + nnew;
    if (nf > pr->cap_f) {
        uint32_t nc = 2 * nf + 64;
        double(*nb)[6] = realloc(pr->box, (size_t)nc * sizeof *nb);
        if (!nb)
            return -ENOMEM;
        pr->box = nb;
        geo_facet_shape *ns = realloc(pr->shape, (size_t)nc * sizeof *ns);
        if (!ns)
            return -ENOMEM;
        pr->shape = ns;
        uint8_t *nh = realloc(pr->has_shape, nc);
        if (!nh)
            return -ENOMEM;
        pr->has_shape = nh;
        pr->cap_f = nc;
    }
    memset(pr->has_shape, 0, nf);
    for (uint32_t f = 0; f < nf; f++)
        tri_box(pr->p, geo_poly_facet(pr->p, f), pr->box[f]);
    for (uint32_t i = 0; i < nnew; i++) {
        uint32_t f = ntris + i;
        geo_facet_shape_of(pr->p, f, &pr->shape[f]);
        pr->has_shape[f] = 1;
        if (pr->shape[f].degenerate)
            return 1;
        for (uint32_t g = 0; g < f; g++) {
            if (boxes_apart(pr->box[f], pr->box[g]))
                continue;
            if (!pr->has_shape[g]) {
                geo_facet_shape_of(pr->p, g, &pr->shape[g]);
                pr->has_shape[g] = 1;
            }
            int hit = geo_facets_intersect(pr->p, f, g, &pr->shape[f],
                                           &pr->shape[g]);
            if (hit != 0)
                return hit < 0 ? -ENOMEM : 1;
        }
    }
    return 0;
}
