/* trimesh.c — dynamic triangle mesh with a directed-edge hash (see
 * trimesh.h). Every operation first checks that it can succeed (edges
 * free, memory available), then applies, so a failure leaves the mesh
 * unchanged. */
#include "trimesh.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

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

void geo_tmesh_remove(geo_tmesh *m, uint32_t t)
{
    if (m->dead[t])
        return;
    forget(m, t);
    m->dead[t] = 1;
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
