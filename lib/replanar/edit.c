/* edit.c — the editable polyhedron with undo (edit.h).
 * Invariants: for every live facet f and every v in f's cycle, f is in v's
 * facet list exactly once, and a vertex's list holds only live facets
 * containing it; inside a transaction every changed list lives in arena
 * space at or beyond txn_alen, so the saved slices are never written. */
#include "edit.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "vec.h"

static int grow_arena(geo_edit *e, size_t need)
{
    if (need <= e->acap)
        return 0;
    size_t c = e->acap ? e->acap : 1024;
    while (c < need)
        c += c / 2 + 1024;
    uint32_t *a = realloc(e->arena, c * sizeof *a);
    if (!a)
        return -ENOMEM;
    e->arena = a;
    e->acap = c;
    return 0;
}

/* A fresh slice of room cap at the arena's end. */
static int alloc_slice(geo_edit *e, uint32_t cap, geo_slice *ret)
{
    if (grow_arena(e, e->alen + cap) < 0)
        return -ENOMEM;
    ret->off = (uint32_t)e->alen;
    ret->n = 0;
    ret->cap = cap;
    e->alen += cap;
    return 0;
}

/* Makes s writable with room for need entries: moves it to fresh arena
 * space when it is too small or (inside a transaction) older than the
 * transaction. */
static int writable(geo_edit *e, geo_slice *s, uint32_t need)
{
    bool old = e->in_txn && s->off < e->txn_alen;
    if (!old && need <= s->cap)
        return 0;
    uint32_t cap = need > s->cap ? need + need / 2 + 2 : s->cap;
    geo_slice t;
    if (alloc_slice(e, cap, &t) < 0)
        return -ENOMEM;
    memcpy(e->arena + t.off, e->arena + s->off, s->n * sizeof *e->arena);
    t.n = s->n;
    *s = t;
    return 0;
}

static int save_facet(geo_edit *e, uint32_t f)
{
    if (!e->in_txn || f >= e->txn_nfacets || e->fstamp[f] == e->txn)
        return 0;
    if (e->nfsaved == e->capfsaved) {
        size_t c = e->capfsaved ? 2 * e->capfsaved : 64;
        void *b = realloc(e->fsaved, c * sizeof *e->fsaved);
        if (!b)
            return -ENOMEM;
        e->fsaved = b;
        e->capfsaved = c;
    }
    geo_edit_fsave *s = &e->fsaved[e->nfsaved++];
    s->id = f;
    s->s = e->fv[f];
    memcpy(s->plane, e->planes[f], sizeof s->plane);
    s->alive = e->falive[f];
    e->fstamp[f] = e->txn;
    return 0;
}

static int save_vertex(geo_edit *e, uint32_t v)
{
    if (!e->in_txn || v >= e->txn_nverts || e->vstamp[v] == e->txn)
        return 0;
    if (e->nvsaved == e->capvsaved) {
        size_t c = e->capvsaved ? 2 * e->capvsaved : 64;
        void *b = realloc(e->vsaved, c * sizeof *e->vsaved);
        if (!b)
            return -ENOMEM;
        e->vsaved = b;
        e->capvsaved = c;
    }
    geo_edit_vsave *s = &e->vsaved[e->nvsaved++];
    s->id = v;
    s->s = e->vf[v];
    memcpy(s->pos, e->verts[v], sizeof s->pos);
    e->vstamp[v] = e->txn;
    return 0;
}

static int vf_add(geo_edit *e, uint32_t v, uint32_t f)
{
    if (save_vertex(e, v) < 0 || writable(e, &e->vf[v], e->vf[v].n + 1) < 0)
        return -ENOMEM;
    e->arena[e->vf[v].off + e->vf[v].n++] = f;
    return 0;
}

static int vf_del(geo_edit *e, uint32_t v, uint32_t f)
{
    if (save_vertex(e, v) < 0 || writable(e, &e->vf[v], e->vf[v].n) < 0)
        return -ENOMEM;
    uint32_t *l = e->arena + e->vf[v].off, n = e->vf[v].n;
    for (uint32_t i = 0; i < n; i++)
        if (l[i] == f) {
            l[i] = l[n - 1];
            e->vf[v].n--;
            break;
        }
    return 0;
}

static int reserve_verts(geo_edit *e, uint32_t need)
{
    if (need <= e->cap_verts)
        return 0;
    uint32_t c = e->cap_verts ? e->cap_verts : 64;
    while (c < need)
        c += c / 2 + 64;
    void *a = realloc(e->verts, c * sizeof *e->verts);
    if (a)
        e->verts = a;
    void *b = realloc(e->vf, c * sizeof *e->vf);
    if (b)
        e->vf = b;
    void *s = realloc(e->vstamp, c * sizeof *e->vstamp);
    if (s)
        e->vstamp = s;
    if (!a || !b || !s)
        return -ENOMEM;
    e->cap_verts = c;
    return 0;
}

static int reserve_facets(geo_edit *e, uint32_t need)
{
    if (need <= e->cap_facets)
        return 0;
    uint32_t c = e->cap_facets ? e->cap_facets : 64;
    while (c < need)
        c += c / 2 + 64;
    void *a = realloc(e->fv, c * sizeof *e->fv);
    if (a)
        e->fv = a;
    void *b = realloc(e->planes, c * sizeof *e->planes);
    if (b)
        e->planes = b;
    void *d = realloc(e->falive, c);
    if (d)
        e->falive = d;
    void *s = realloc(e->fstamp, c * sizeof *e->fstamp);
    if (s)
        e->fstamp = s;
    if (!a || !b || !d || !s)
        return -ENOMEM;
    e->cap_facets = c;
    return 0;
}

geo_edit *geo_edit_free(geo_edit *e)
{
    if (!e)
        return NULL;
    free(e->verts), free(e->vf), free(e->fv), free(e->planes);
    free(e->falive), free(e->arena), free(e->fstamp), free(e->vstamp);
    free(e->fsaved), free(e->vsaved);
    free(e);
    return NULL;
}

geo_edit *geo_edit_from_poly(const geo_poly *p, geo_err *err)
{
    geo_edit *e = calloc(1, sizeof *e);
    uint32_t nc = geo_poly_ncorners(p);
    if (!e || reserve_verts(e, p->nverts + 1) < 0 ||
        reserve_facets(e, p->nfacets + 1) < 0 ||
        grow_arena(e, 2 * (size_t)nc + 2 * (size_t)p->nfacets +
                          2 * (size_t)p->nverts + 16) < 0) {
        geo_edit_free(e);
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    e->nverts = p->nverts;
    e->nfacets = p->nfacets;
    memcpy(e->verts, p->verts, (size_t)p->nverts * sizeof *p->verts);
    memcpy(e->planes, p->planes, (size_t)p->nfacets * sizeof *p->planes);
    memset(e->falive, 1, p->nfacets);
    memset(e->fstamp, 0, (size_t)p->nfacets * sizeof *e->fstamp);
    memset(e->vstamp, 0, (size_t)p->nverts * sizeof *e->vstamp);
    /* facet cycles with one spare slot each, then vertex lists sized by
     * count with one spare */
    size_t a = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        e->fv[f].off = (uint32_t)a;
        e->fv[f].n = n;
        e->fv[f].cap = n + 1;
        memcpy(e->arena + a, geo_poly_facet(p, f), n * sizeof *e->arena);
        a += n + 1;
    }
    for (uint32_t v = 0; v < p->nverts; v++)
        e->vf[v].n = 0;
    for (uint32_t c = 0; c < nc; c++)
        e->vf[p->fidx[c]].n++;
    for (uint32_t v = 0; v < p->nverts; v++) {
        e->vf[v].off = (uint32_t)a;
        e->vf[v].cap = e->vf[v].n + 1;
        a += e->vf[v].cap;
        e->vf[v].n = 0;
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *vs = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < geo_poly_facet_size(p, f); i++) {
            geo_slice *s = &e->vf[vs[i]];
            /* a facet listing a vertex twice is kept once in its list */
            uint32_t *l = e->arena + s->off;
            bool have = s->n > 0 && l[s->n - 1] == f;
            if (!have)
                l[s->n++] = f;
        }
    }
    e->alen = a;
    return e;
}

int geo_edit_to_poly(const geo_edit *e, geo_poly *out, uint32_t *ret_vmap,
                     uint32_t *ret_fmap)
{
    geo_poly_clear(out);
    uint32_t nf = 0;
    size_t nc = 0;
    for (uint32_t f = 0; f < e->nfacets; f++)
        if (e->falive[f]) {
            nf++;
            nc += e->fv[f].n;
        }
    uint32_t *vmap = malloc(((size_t)e->nverts + 1) * sizeof *vmap);
    if (!vmap)
        return -ENOMEM;
    for (uint32_t v = 0; v < e->nverts; v++)
        vmap[v] = GEO_NONE;
    for (uint32_t f = 0; f < e->nfacets; f++) {
        if (!e->falive[f])
            continue;
        const uint32_t *vs = geo_edit_fv(e, f);
        for (uint32_t i = 0; i < e->fv[f].n; i++)
            vmap[vs[i]] = 0;
    }
    uint32_t nv = 0;
    for (uint32_t v = 0; v < e->nverts; v++)
        if (vmap[v] == 0)
            vmap[v] = nv++;
    if (geo_poly_reserve(out, nv, nf, nc) < 0) {
        free(vmap);
        return -ENOMEM;
    }
    for (uint32_t v = 0; v < e->nverts; v++)
        if (vmap[v] != GEO_NONE)
            memcpy(out->verts[vmap[v]], e->verts[v], sizeof e->verts[v]);
    out->nverts = nv;
    uint32_t k = 0, c = 0;
    for (uint32_t f = 0; f < e->nfacets; f++) {
        if (ret_fmap)
            ret_fmap[f] = e->falive[f] ? k : GEO_NONE;
        if (!e->falive[f])
            continue;
        const uint32_t *vs = geo_edit_fv(e, f);
        out->fstart[k] = c;
        for (uint32_t i = 0; i < e->fv[f].n; i++)
            out->fidx[c++] = vmap[vs[i]];
        memcpy(out->planes[k], e->planes[f], sizeof e->planes[f]);
        k++;
    }
    out->fstart[k] = c;
    out->nfacets = k;
    if (ret_vmap)
        memcpy(ret_vmap, vmap, (size_t)e->nverts * sizeof *vmap);
    free(vmap);
    return 0;
}

int geo_edit_gc(geo_edit *e)
{
    size_t need = 0;
    for (uint32_t f = 0; f < e->nfacets; f++)
        need += e->falive[f] ? e->fv[f].n + 1 : 0;
    for (uint32_t v = 0; v < e->nverts; v++)
        need += e->vf[v].n + 1;
    uint32_t *a = malloc((need + 1024) * sizeof *a);
    if (!a)
        return -ENOMEM;
    size_t k = 0;
    for (uint32_t f = 0; f < e->nfacets; f++) {
        geo_slice *s = &e->fv[f];
        if (!e->falive[f]) {
            s->off = s->n = s->cap = 0;
            continue;
        }
        memcpy(a + k, e->arena + s->off, s->n * sizeof *a);
        s->off = (uint32_t)k;
        s->cap = s->n + 1;
        k += s->cap;
    }
    for (uint32_t v = 0; v < e->nverts; v++) {
        geo_slice *s = &e->vf[v];
        memcpy(a + k, e->arena + s->off, s->n * sizeof *a);
        s->off = (uint32_t)k;
        s->cap = s->n + 1;
        k += s->cap;
    }
    free(e->arena);
    e->arena = a;
    e->alen = k;
    e->acap = need + 1024;
    return 0;
}

void geo_edit_begin(geo_edit *e)
{
    e->in_txn = true;
    e->txn++;
    e->nfsaved = e->nvsaved = 0;
    e->txn_nverts = e->nverts;
    e->txn_nfacets = e->nfacets;
    e->txn_alen = e->alen;
}

void geo_edit_commit(geo_edit *e)
{
    e->in_txn = false;
}

void geo_edit_rollback(geo_edit *e)
{
    for (size_t i = e->nfsaved; i-- > 0;) {
        const geo_edit_fsave *s = &e->fsaved[i];
        e->fv[s->id] = s->s;
        memcpy(e->planes[s->id], s->plane, sizeof s->plane);
        e->falive[s->id] = s->alive;
    }
    for (size_t i = e->nvsaved; i-- > 0;) {
        const geo_edit_vsave *s = &e->vsaved[i];
        e->vf[s->id] = s->s;
        memcpy(e->verts[s->id], s->pos, sizeof s->pos);
    }
    e->nverts = e->txn_nverts;
    e->nfacets = e->txn_nfacets;
    e->alen = e->txn_alen;
    e->in_txn = false;
}

uint32_t geo_edit_ntouched_facets(const geo_edit *e)
{
    return (uint32_t)e->nfsaved + (e->nfacets - e->txn_nfacets);
}

uint32_t geo_edit_touched_facets(const geo_edit *e, uint32_t *ret)
{
    uint32_t k = 0;
    for (size_t i = 0; i < e->nfsaved; i++)
        ret[k++] = e->fsaved[i].id;
    for (uint32_t f = e->txn_nfacets; f < e->nfacets; f++)
        ret[k++] = f;
    return k;
}

uint32_t geo_edit_ntouched_verts(const geo_edit *e)
{
    return (uint32_t)e->nvsaved + (e->nverts - e->txn_nverts);
}

uint32_t geo_edit_touched_verts(const geo_edit *e, uint32_t *ret)
{
    uint32_t k = 0;
    for (size_t i = 0; i < e->nvsaved; i++)
        ret[k++] = e->vsaved[i].id;
    for (uint32_t v = e->txn_nverts; v < e->nverts; v++)
        ret[k++] = v;
    return k;
}

uint32_t geo_edit_find(const geo_edit *e, uint32_t f, uint32_t v)
{
    const uint32_t *vs = geo_edit_fv(e, f);
    for (uint32_t i = 0; i < e->fv[f].n; i++)
        if (vs[i] == v)
            return i;
    return GEO_NONE;
}

uint32_t geo_edit_across(const geo_edit *e, uint32_t f, uint32_t a,
                         uint32_t b)
{
    const uint32_t *l = geo_edit_vf(e, a);
    uint32_t found = GEO_NONE;
    for (uint32_t i = 0; i < e->vf[a].n; i++) {
        uint32_t g = l[i];
        if (g == f || !e->falive[g])
            continue;
        const uint32_t *vs = geo_edit_fv(e, g);
        uint32_t n = e->fv[g].n;
        for (uint32_t j = 0; j < n; j++)
            if (vs[j] == b && vs[j + 1 < n ? j + 1 : 0] == a) {
                if (found != GEO_NONE)
                    return GEO_NONE;
                found = g;
                break;
            }
    }
    return found;
}

int64_t geo_edit_add_vertex(geo_edit *e, const double xyz[3])
{
    if (e->nverts >= GEO_POLY_MAX_VERTS)
        return -ERANGE;
    if (reserve_verts(e, e->nverts + 1) < 0)
        return -ENOMEM;
    geo_slice s;
    if (alloc_slice(e, 6, &s) < 0)
        return -ENOMEM;
    uint32_t v = e->nverts++;
    memcpy(e->verts[v], xyz, sizeof e->verts[v]);
    e->vf[v] = s;
    e->vstamp[v] = 0;
    return v;
}

int geo_edit_move_vertex(geo_edit *e, uint32_t v, const double xyz[3])
{
    if (save_vertex(e, v) < 0)
        return -ENOMEM;
    memcpy(e->verts[v], xyz, sizeof e->verts[v]);
    return 0;
}

int64_t geo_edit_add_facet(geo_edit *e, const uint32_t *vs, uint32_t n,
                           const double plane[4])
{
    if (reserve_facets(e, e->nfacets + 1) < 0)
        return -ENOMEM;
    geo_slice s;
    if (alloc_slice(e, n + 2, &s) < 0)
        return -ENOMEM;
    uint32_t f = e->nfacets;
    memcpy(e->arena + s.off, vs, n * sizeof *vs);
    s.n = n;
    e->fv[f] = s;
    memcpy(e->planes[f], plane, sizeof e->planes[f]);
    e->falive[f] = 1;
    e->fstamp[f] = 0;
    e->nfacets++;
    for (uint32_t i = 0; i < n; i++)
        if (vf_add(e, vs[i], f) < 0)
            return -ENOMEM;
    return f;
}

int geo_edit_kill_facet(geo_edit *e, uint32_t f)
{
    if (!e->falive[f])
        return 0;
    if (save_facet(e, f) < 0)
        return -ENOMEM;
    uint32_t n = e->fv[f].n;
    for (uint32_t i = 0; i < n; i++)
        if (vf_del(e, geo_edit_fv(e, f)[i], f) < 0)
            return -ENOMEM;
    e->falive[f] = 0;
    return 0;
}

int geo_edit_set_facet(geo_edit *e, uint32_t f, const uint32_t *vs,
                       uint32_t n)
{
    if (save_facet(e, f) < 0)
        return -ENOMEM;
    uint32_t old = e->fv[f].n;
    for (uint32_t i = 0; i < old; i++)
        if (vf_del(e, geo_edit_fv(e, f)[i], f) < 0)
            return -ENOMEM;
    e->fv[f].n = 0;
    if (writable(e, &e->fv[f], n) < 0)
        return -ENOMEM;
    memcpy(geo_edit_fv(e, f), vs, n * sizeof *vs);
    e->fv[f].n = n;
    for (uint32_t i = 0; i < n; i++)
        if (vf_add(e, vs[i], f) < 0)
            return -ENOMEM;
    return 0;
}

int geo_edit_set_plane(geo_edit *e, uint32_t f, const double plane[4])
{
    if (save_facet(e, f) < 0)
        return -ENOMEM;
    memcpy(e->planes[f], plane, sizeof e->planes[f]);
    return 0;
}

int geo_edit_insert(geo_edit *e, uint32_t f, uint32_t pos, uint32_t v)
{
    if (save_facet(e, f) < 0 || writable(e, &e->fv[f], e->fv[f].n + 1) < 0)
        return -ENOMEM;
    uint32_t *l = geo_edit_fv(e, f);
    memmove(l + pos + 1, l + pos, (e->fv[f].n - pos) * sizeof *l);
    l[pos] = v;
    e->fv[f].n++;
    return vf_add(e, v, f);
}

int geo_edit_remove(geo_edit *e, uint32_t f, uint32_t pos)
{
    if (save_facet(e, f) < 0 || writable(e, &e->fv[f], e->fv[f].n) < 0)
        return -ENOMEM;
    uint32_t *l = geo_edit_fv(e, f);
    uint32_t v = l[pos];
    memmove(l + pos, l + pos + 1, (e->fv[f].n - pos - 1) * sizeof *l);
    e->fv[f].n--;
    return vf_del(e, v, f);
}

int geo_edit_replace(geo_edit *e, uint32_t f, uint32_t pos, uint32_t v)
{
    if (save_facet(e, f) < 0 || writable(e, &e->fv[f], e->fv[f].n) < 0)
        return -ENOMEM;
    uint32_t *l = geo_edit_fv(e, f);
    uint32_t old = l[pos];
    l[pos] = v;
    if (vf_del(e, old, f) < 0)
        return -ENOMEM;
    return vf_add(e, v, f);
}

void geo_edit_area_vector(const geo_edit *e, uint32_t f, double ret[3])
{
    uint32_t n = e->fv[f].n;
    const uint32_t *v = geo_edit_fv(e, f);
    double s[3] = {0, 0, 0};
    if (n > 0) {
        const double *o = e->verts[v[0]];
        for (uint32_t i = 1; i + 1 < n; i++) {
            double a[3], b[3], c[3];
            geo_vsub(e->verts[v[i]], o, a);
            geo_vsub(e->verts[v[i + 1]], o, b);
            geo_vcross(a, b, c);
            geo_vadd(s, c, s);
        }
    }
    memcpy(ret, s, sizeof s);
}

double geo_edit_facet_volume(const geo_edit *e, uint32_t f, const double o[3])
{
    return geo_fan_volume6(0, (const double(*)[3])e->verts, geo_edit_fv(e, f),
                           e->fv[f].n, o) / 6.0;
}
