/* stats.c — geo_inspect: one pass of each analysis over the topology,
 * then the self-intersection search (definitions in stats.h). Invariant:
 * the polyhedron is only read; every count is deterministic (independent
 * of the thread count). */
#include "stats.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "topo.h"
#include "uf.h"
#include "vec.h"

void geo_inspect_opts_default(geo_inspect_opts *o)
{
    memset(o, 0, sizeof *o);
    geo_selfint_opts_default(&o->selfint);
    o->coplanar_deg[0] = 0.5;
    o->coplanar_deg[1] = 1.0;
    o->coplanar_deg[2] = 2.0;
}

void geo_stats_clear(geo_stats *s)
{
    if (!s)
        return;
    geo_selfint_clear(&s->selfint);
    free(s->degree_count);
    memset(s, 0, sizeof *s);
}

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

/* Distinct values among nb[0..n): a quadratic scan for the short lists
 * of ordinary vertices (no call, no sort), a sort beyond. */
static uint32_t distinct(uint32_t *nb, uint32_t n)
{
    uint32_t d = 0;
    if (n <= 32) {
        for (uint32_t i = 0; i < n; i++) {
            uint32_t j = 0;
            while (j < i && nb[j] != nb[i])
                j++;
            d += j == i;
        }
        return d;
    }
    qsort(nb, n, sizeof *nb, cmp_u32);
    for (uint32_t i = 0; i < n; i++)
        d += i == 0 || nb[i] != nb[i - 1];
    return d;
}

/* Vertex degrees (distinct neighbours through the corners at each
 * vertex) into a histogram; also vertices in fewer than 3 facets. */
static int degrees(const geo_poly *p, const geo_topo *t, geo_stats *s)
{
    uint32_t maxc = 0;
    for (uint32_t v = 0; v < p->nverts; v++)
        if (t->vstart[v + 1] - t->vstart[v] > maxc)
            maxc = t->vstart[v + 1] - t->vstart[v];
    uint32_t *nb = malloc((2 * (size_t)maxc + 1) * sizeof *nb);
    uint32_t *deg = malloc(((size_t)p->nverts + 1) * sizeof *deg);
    if (!nb || !deg) {
        free(nb), free(deg);
        return -ENOMEM;
    }
    uint32_t maxd = 0;
    for (uint32_t v = 0; v < p->nverts; v++) {
        uint32_t k0 = t->vstart[v], k1 = t->vstart[v + 1];
        if (k1 - k0 < 3)
            s->low_degree_vertices++;
        /* an interior vertex's single closed fan crosses each of its
         * edges once, and each edge there has exactly two corners (else
         * it would be non-manifold, and so the vertex): as many distinct
         * edges, hence neighbours, as corners */
        if (t->vertex_kind[v] == GEO_VERTEX_INTERIOR) {
            deg[v] = k1 - k0;
            if (deg[v] > maxd)
                maxd = deg[v];
            continue;
        }
        uint32_t n = 0;
        for (uint32_t k = k0; k < k1; k++) {
            uint32_t c = t->vcorners[k];
            nb[n++] = p->fidx[geo_topo_next(p, t, c)];
            nb[n++] = p->fidx[geo_topo_prev(p, t, c)];
        }
        uint32_t d = distinct(nb, n);
        deg[v] = d;
        if (d > maxd)
            maxd = d;
    }
    s->degree_count = calloc((size_t)maxd + 1, sizeof *s->degree_count);
    if (!s->degree_count) {
        free(nb), free(deg);
        return -ENOMEM;
    }
    s->max_degree = maxd;
    for (uint32_t v = 0; v < p->nverts; v++)
        s->degree_count[deg[v]]++;
    free(nb), free(deg);
    return 0;
}

/* Whether the angle atan2(√yy, c) (degrees) of two unit normals is
 * surely at least tmax, without the arctangent or the root: c < 0 means
 * at least 90°, and yy > (c·tan(tmax))²·(1 + 1e-8) means a tangent above
 * tan(tmax) by far more than the rounding of the root, of atan2 and of
 * the conversion to degrees. Only for 1e-6 ≤ tmax ≤ 89 (tan_max = 0
 * otherwise: never sure). A NaN is never sure. Pairs not surely wider are
 * measured by atan2 as before. */
static bool surely_wider(double yy, double c, double tan_max)
{
    if (tan_max == 0)
        return false;
    double lim = c * tan_max;
    return c < 0 || yy > lim * lim * (1 + 1e-8);
}

/* Whether that angle is surely below t (tan_t = tan(t), 0 when never
 * sure, as above): c > 0 and yy < (c·tan(t))²·(1 − 1e-8), a tangent
 * below tan(t) by 5e-9 relative, which moves the angle by at least
 * 5.6e-11 relative over 1e-6° ≤ t ≤ 89° — far beyond the few units in
 * the last place of the root, atan2 and the conversion to degrees. */
static bool surely_narrower(double yy, double c, double tan_t)
{
    if (tan_t == 0 || !(c > 0))
        return false;
    double lim = c * tan_t;
    return yy < lim * lim * (1 - 1e-8);
}

/* The unit Newell normal of facet f, and its length. */
static double unit_normal(const geo_poly *p, uint32_t f, double ret[3])
{
    geo_poly_facet_area_vector(p, f, ret);
    return geo_vnormalize(ret);
}

/* The last unit normals computed, by facet modulo their number: a facet's
 * neighbours above it are, in a mesh's usual orders, a few hundred facets
 * further on, and each is asked for up to three times as a neighbour and
 * once as itself. A hit gives the same bits; a miss computes them. */
enum { NORMAL_CACHE = 2048 };
typedef struct normal_cache {
    uint32_t f[NORMAL_CACHE];
    double n[NORMAL_CACHE][4]; /* unit normal, length */
} normal_cache;

static double cached_normal(const geo_poly *p, normal_cache *c, uint32_t f,
                            double ret[3])
{
    uint32_t k = f % NORMAL_CACHE;
    if (c->f[k] != f) {
        c->n[k][3] = unit_normal(p, f, c->n[k]);
        c->f[k] = f;
    }
    memcpy(ret, c->n[k], 3 * sizeof *ret);
    return c->n[k][3];
}

/* Facet f's largest distance from its plane (geo_poly_max_nonplanarity's
 * term), given its unit Newell normal nrm of length len. A triangle
 * without a stored plane is on the plane geo_poly_facet_plane would fit:
 * nrm itself through the centroid (the zero plane when len is not
 * positive), the same operations, so the same bits, without forming the
 * normal again. */
static double facet_nonplanarity(const geo_poly *p, uint32_t f,
                                 const double nrm[3], double len)
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double pl[4] = {0, 0, 0, 0};
    if (p->planes || n != 3) {
        geo_poly_facet_plane(p, f, pl);
    } else if (len > 0) {
        /* each term + 0.0, as geo_poly_facet_plane returns it; held in
         * scalars, not written piecewise into pl and read back whole (a
         * store the processor cannot forward) */
        double c[3];
        geo_poly_facet_center(p, f, c);
        double a = nrm[0] + 0.0, b = nrm[1] + 0.0, e = nrm[2] + 0.0,
               d = -geo_vdot(nrm, c) + 0.0, m = 0;
        for (uint32_t i = 0; i < 3; i++) {
            const double *x = p->verts[v[i]];
            double r = fabs(a * x[0] + b * x[1] + e * x[2] + d);
            if (r > m)
                m = r;
        }
        return m;
    }
    double m = 0;
    for (uint32_t i = 0; i < n; i++) {
        double d = fabs(geo_plane_eval(pl, p->verts[v[i]]));
        if (d > m)
            m = d;
    }
    return m;
}

/* One pass over the facets, in order: the total area, the volume (about
 * o, as geo_poly_volume sums it) and the largest nonplanarity, from the
 * Newell vectors the pass forms anyway; facets winding against their
 * plane; adjacent facet pairs (each once) whose normals are within each
 * threshold. Each facet's neighbours above it are gathered through its
 * corners with a stamp per facet, so a pair sharing several edges counts
 * once (as agreeing when any of its edges agrees). A neighbour's normal
 * is computed again where it is needed (the same bits; cached_normal
 * keeps the last ones) rather than kept for every facet: 24 bytes per
 * facet. */
static int facet_pass(const geo_poly *p, const geo_topo *t,
                      const double o[3], geo_stats *s)
{
    uint32_t nf = p->nfacets;
    uint32_t *stamp = malloc(((size_t)nf + 1) * sizeof *stamp);
    uint8_t *agree = malloc((size_t)nf + 1);
    uint32_t maxn = 1;
    for (uint32_t f = 0; f < nf; f++)
        if (geo_poly_facet_size(p, f) > maxn)
            maxn = geo_poly_facet_size(p, f);
    uint32_t *list = malloc((size_t)maxn * sizeof *list);
    normal_cache *nc = malloc(sizeof *nc);
    if (!stamp || !agree || !list || !nc) {
        free(stamp), free(agree), free(list), free(nc);
        return -ENOMEM;
    }
    for (uint32_t f = 0; f < nf; f++)
        stamp[f] = GEO_NONE;
    /* the total area from the same Newell vectors, summed in facet order
     * as geo_poly_area does */
    s->area = 0;
    double tmax = s->coplanar_deg[0];
    for (int k = 1; k < GEO_STATS_NCOPLANAR; k++)
        if (s->coplanar_deg[k] > tmax)
            tmax = s->coplanar_deg[k];
    double tan_max = tmax >= 1e-6 && tmax <= 89 ? tan(tmax * M_PI / 180.0)
                                                : 0;
    double tan_k[GEO_STATS_NCOPLANAR];
    for (int k = 0; k < GEO_STATS_NCOPLANAR; k++) {
        double deg = s->coplanar_deg[k];
        tan_k[k] = deg >= 1e-6 && deg <= 89 ? tan(deg * M_PI / 180.0) : 0;
    }
    for (uint32_t k = 0; k < NORMAL_CACHE; k++)
        nc->f[k] = GEO_NONE;
    double vol = 0;
    s->max_nonplanarity = 0;
    for (uint32_t f = 0; f < nf; f++) {
        double nrm[3], len = cached_normal(p, nc, f, nrm);
        s->area += 0.5 * len;
        vol = geo_fan_volume6(vol, (const double(*)[3])p->verts,
                              geo_poly_facet(p, f), geo_poly_facet_size(p, f),
                              o);
        double np = facet_nonplanarity(p, f, nrm, len);
        if (np > s->max_nonplanarity)
            s->max_nonplanarity = np;
        /* an implicit plane's normal is nrm itself, bit for bit (the
         * same Newell vector normalised by the same geo_vnormalize), and
         * a dot product of a vector with itself is never negative: no
         * facet of implicit planes is inverted */
        if (p->planes && geo_vdot(nrm, p->planes[f]) < 0)
            s->inverted_facets++;
        uint32_t nl = 0;
        for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++) {
            uint32_t m = t->mate[c];
            if (m == GEO_NONE)
                continue;
            uint32_t g = geo_topo_facet(t, m);
            if (g <= f)
                continue;
            uint8_t ag = t->edge_kind[c] != GEO_EDGE_FLIPPED;
            if (stamp[g] != f) {
                stamp[g] = f;
                agree[g] = ag;
                list[nl++] = g;
            } else {
                agree[g] |= ag;
            }
        }
        for (uint32_t i = 0; i < nl; i++) {
            uint32_t g = list[i];
            double n2[3], x[3];
            cached_normal(p, nc, g, n2);
            geo_vscale(n2, agree[g] ? 1.0 : -1.0, n2);
            geo_vcross(nrm, n2, x);
            double yy = geo_vdot(x, x), dot = geo_vdot(nrm, n2);
            if (surely_wider(yy, dot, tan_max))
                continue;
            /* each threshold decided by the tangent where it surely can
             * be (a smooth mesh's neighbours: all of them), else by the
             * angle itself */
            unsigned below = 0;
            int k = 0;
            for (; k < GEO_STATS_NCOPLANAR; k++) {
                if (surely_narrower(yy, dot, tan_k[k]))
                    below |= 1u << k;
                else if (!surely_wider(yy, dot, tan_k[k]))
                    break;
            }
            if (k == GEO_STATS_NCOPLANAR) {
                for (k = 0; k < GEO_STATS_NCOPLANAR; k++)
                    s->near_coplanar[k] += below >> k & 1;
                continue;
            }
            double ang = atan2(sqrt(yy), dot) * 180.0 / M_PI;
            for (k = 0; k < GEO_STATS_NCOPLANAR; k++)
                if (ang < s->coplanar_deg[k])
                    s->near_coplanar[k]++;
        }
    }
    s->volume = vol / 6.0;
    free(stamp), free(agree), free(list), free(nc);
    return 0;
}

/* Union-find over edges shorter than the radius, each edge once (from
 * its lower corner; the union of the two lower roots keeps every root the
 * smallest vertex of its set, so the order of the unions does not
 * matter); in the same pass, the zero-length edges. */
static int clusters(const geo_poly *p, const geo_topo *t, geo_stats *s)
{
    uint32_t nv = p->nverts;
    uint32_t *parent = malloc(((size_t)nv + 1) * sizeof *parent);
    uint32_t *size = calloc((size_t)nv + 1, sizeof *size);
    if (!parent || !size) {
        free(parent), free(size);
        return -ENOMEM;
    }
    for (uint32_t v = 0; v < nv; v++)
        parent[v] = v;
    double r = s->short_edge_radius;
    /* an edge whose squared length is above r²·(1 + 1e-9) is surely not
     * shorter than r (far beyond the rounding of r², of the sum and of
     * the square root), so the square root is taken only near r */
    double r2 = r * r * (1 + 1e-9);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t m = t->mate[p->fstart[f] + i];
            if (m != GEO_NONE && m < p->fstart[f] + i)
                continue;
            uint32_t a = fv[i], b = i + 1 < n ? fv[i + 1] : fv[0];
            const double *x = p->verts[a], *y = p->verts[b];
            if (x[0] == y[0] && x[1] == y[1] && x[2] == y[2])
                s->degenerate_edges++;
            double d[3];
            geo_vsub(x, y, d);
            if (geo_vdot(d, d) > r2)
                continue;
            if (geo_vdist(p->verts[a], p->verts[b]) < r) {
                a = geo_uf_find(parent, a);
                b = geo_uf_find(parent, b);
                if (a != b)
                    parent[a < b ? b : a] = a < b ? a : b;
            }
        }
    }
    for (uint32_t v = 0; v < nv; v++)
        size[geo_uf_find(parent, v)]++;
    for (uint32_t v = 0; v < nv; v++)
        if (size[v] >= 2) {
            s->short_edge_clusters++;
            s->short_edge_cluster_vertices += size[v];
        }
    free(parent), free(size);
    return 0;
}

/* Progress of the self-intersection search mapped into [lo, 1]. */
typedef struct sub_progress {
    const geo_ctx *outer;
    double lo;
} sub_progress;

static int sub_report(void *user, double fraction)
{
    const sub_progress *sp = user;
    return geo_ctx_progress(sp->outer, sp->lo + (1.0 - sp->lo) * fraction);
}

/* The counts of p and of its topology t, and its orientation. 0, or
 * geo_orient_analyze's error. */
static int topology_stats(const geo_poly *p, const geo_topo *t,
                          geo_stats *ret, geo_err *err)
{
    ret->vertices = p->nverts;
    ret->facets = p->nfacets;
    ret->edges = t->nedges;
    ret->boundary_edges = t->nboundary_edges;
    ret->nonmanifold_edges = t->nnonmanifold_edges;
    ret->nonmanifold_vertices = t->nnonmanifold_vertices;
    ret->closed = t->nboundary_edges == 0 && t->nnonmanifold_edges == 0;
    geo_orient_report orep;
    int rc = geo_orient_analyze(p, t, NULL, &orep, err);
    if (rc < 0)
        return rc;
    ret->orientation = orep.orientation;
    ret->inconsistent_facets = orep.ninconsistent;
    ret->shells = orep.nshells;
    ret->orientable = orep.orientable;
    return 0;
}

int geo_inspect_topology(const geo_poly *p, const geo_topo *t,
                         geo_stats *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    int rc;
    geo_topo *own = NULL;
    if (!t && !(t = own = geo_topo_build_lean(p, &rc, err)))
        return rc;
    rc = topology_stats(p, t, ret, err);
    geo_topo_free(own);
    if (rc < 0)
        memset(ret, 0, sizeof *ret);
    return rc;
}

int geo_inspect(const geo_poly *p, const geo_inspect_opts *opts,
                const geo_ctx *ctx, geo_stats *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    geo_inspect_opts o;
    if (opts)
        o = *opts;
    else
        geo_inspect_opts_default(&o);
    int rc;
    uint8_t *fans = NULL;
    geo_topo *t = geo_topo_build_lean(p, &rc, err);
    if (!t)
        return rc;

    if ((rc = topology_stats(p, t, ret, err)) < 0)
        goto fail;
    uint32_t *lstart = NULL, *lcorners = NULL, nloops = 0;
    rc = geo_topo_boundary_loops(p, t, &lstart, &lcorners, &nloops);
    free(lstart), free(lcorners);
    if (rc < 0)
        goto oom;
    ret->holes = nloops;

    /* the box once: geo_poly_size (geo_poly_eps's and the radius'
     * common size) and geo_poly_volume's centre */
    double lo[3], hi[3], d[3], mid[3];
    geo_poly_bbox(p, lo, hi);
    geo_vsub(hi, lo, d);
    double size = geo_vlen(d);
    geo_vadd(lo, hi, mid);
    geo_vscale(mid, 0.5, mid);
    ret->eps = o.eps > 0 ? o.eps : geo_eps_of_size(size);
    memcpy(ret->coplanar_deg, o.coplanar_deg, sizeof ret->coplanar_deg);
    ret->short_edge_radius =
        o.short_edge_radius > 0 ? o.short_edge_radius : 1e-3 * size;
    if (degrees(p, t, ret) < 0 || facet_pass(p, t, mid, ret) < 0 ||
        clusters(p, t, ret) < 0)
        goto oom;
    /* a mesh of triangles: the vertices whose fans need no pair test
     * (a byte a vertex, while the topology is at hand) */
    if (p->nverts > 0 && geo_poly_ncorners(p) == 3 * (size_t)p->nfacets &&
        !o.selfint.simple_fans) {
        if (!(fans = malloc(p->nverts)))
            goto oom;
        geo_selfint_simple_fans(p, t, fans);
        o.selfint.simple_fans = fans;
    }
    geo_topo_free(t);
    t = NULL;
    /* the topology's build checked them */
    o.selfint.indices_checked = true;
    if ((rc = geo_ctx_progress(ctx, 0.1)) < 0)
        goto fail;

    geo_ctx sub = {0};
    sub_progress sp = {ctx, 0.1};
    if (ctx)
        sub = *ctx;
    sub.progress = sub_report;
    sub.user = &sp;
    rc = geo_selfint_find(p, NULL, &o.selfint, &sub, &ret->selfint, err);
    free(fans);
    fans = NULL;
    if (rc < 0)
        goto fail;
    ret->self_intersecting_facets = ret->selfint.nflagged;
    ret->degenerate_facets = ret->selfint.ndegenerate;
    for (uint32_t f = 0; f < p->nfacets; f++)
        ret->nonconvex_facets +=
            (ret->selfint.facet_flags[f] & GEO_SI_NONCONVEX) != 0;
    ret->valid = ret->closed && ret->nonmanifold_vertices == 0 &&
                 ret->low_degree_vertices == 0 && ret->inverted_facets == 0 &&
                 ret->orientation == GEO_ORIENT_OUTWARD &&
                 ret->max_nonplanarity <= ret->eps &&
                 ret->selfint.count == 0 && ret->degenerate_facets == 0;
    return 0;
oom:
    rc = geo_err_set(err, -ENOMEM, "inspect: out of memory");
fail:
    geo_topo_free(t);
    free(fans);
    geo_stats_clear(ret);
    return rc;
}
