/* topo.c — adjacency by bucketing corners by their edges' lower vertex;
 * vertex fans by walking across edges without assuming consistent
 * orientation (so a flipped facet still has neighbours, which orientation
 * repair needs). */
#include "topo.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

geo_topo *geo_topo_free(geo_topo *t)
{
    if (!t)
        return NULL;
    free(t->corner_facet);
    free(t->mate);
    free(t->edge_kind);
    free(t->vstart);
    free(t->vcorners);
    free(t->vertex_kind);
    free(t);
    return NULL;
}

/* Pairs corners sharing an undirected edge; fills mate, edge_kind and the
 * edge counters. The corners are bucketed by their edge's lower vertex
 * (a counting sort: two sequential passes, no hashing), and each bucket —
 * a few corners — is grouped by the edge's upper vertex. The buckets are
 * kept in vcorners (order_fans fills it after) and each corner's upper
 * vertex in its mate until its edge is grouped: no scratch of 8 bytes a
 * corner. */
static int pair_edges(const geo_poly *p, geo_topo *t)
{
    uint32_t nc = t->ncorners, nv = t->nverts;
    uint32_t *start = calloc((size_t)nv + 2, sizeof *start);
    uint32_t *order = t->vcorners, *upper = t->mate;
    if (!start)
        return -ENOMEM;
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++) {
            uint32_t a = p->fidx[c];
            uint32_t b = p->fidx[c + 1 < p->fstart[f + 1] ? c + 1
                                                          : p->fstart[f]];
            upper[c] = a < b ? b : a;
            start[(a < b ? a : b) + 2]++;
        }
    for (uint32_t v = 0; v < nv; v++)
        start[v + 2] += start[v + 1];
    /* start[v + 1] is now where bucket v begins; filling advances it to
     * where bucket v ends, which is start[v + 2]'s old value */
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++) {
            uint32_t a = p->fidx[c];
            uint32_t b = p->fidx[c + 1 < p->fstart[f + 1] ? c + 1
                                                          : p->fstart[f]];
            order[start[(a < b ? a : b) + 1]++] = c;
        }
    for (uint32_t c = 0; c < nc; c++)
        t->edge_kind[c] = UINT8_MAX; /* not yet grouped */
    for (uint32_t v = 0; v < nv; v++) {
        uint32_t lo = start[v], hi = start[v + 1];
        for (uint32_t i = lo; i < hi; i++) {
            uint32_t c0 = order[i];
            if (t->edge_kind[c0] != UINT8_MAX)
                continue;
            /* the corners of edge {v, upper[c0]}: c0, and c1, c2 ...;
             * all still ungrouped (an edge is grouped whole), so the
             * grouped ones, whose upper was overwritten by their mate,
             * are passed over */
            uint32_t n = 1, c1 = GEO_NONE, u0 = upper[c0];
            for (uint32_t j = i + 1; j < hi; j++)
                if (t->edge_kind[order[j]] == UINT8_MAX &&
                    upper[order[j]] == u0) {
                    if (n == 1)
                        c1 = order[j];
                    n++;
                }
            t->nedges++;
            if (n == 1) {
                t->mate[c0] = GEO_NONE;
                t->edge_kind[c0] = GEO_EDGE_BOUNDARY;
                t->nboundary_edges++;
            } else if (n == 2) {
                bool same = p->fidx[c0] == p->fidx[c1];
                uint8_t kind = same ? GEO_EDGE_FLIPPED : GEO_EDGE_INTERIOR;
                t->mate[c0] = c1;
                t->mate[c1] = c0;
                t->edge_kind[c0] = t->edge_kind[c1] = kind;
                if (same)
                    t->nflipped_edges++;
            } else {
                for (uint32_t j = i; j < hi; j++)
                    if (t->edge_kind[order[j]] == UINT8_MAX &&
                        upper[order[j]] == u0) {
                        t->mate[order[j]] = GEO_NONE;
                        t->edge_kind[order[j]] = GEO_EDGE_NONMANIFOLD;
                    }
                t->nnonmanifold_edges++;
            }
        }
    }
    free(start);
    return 0;
}

/* The corner of vertex v in the facet across the edge owned by corner e,
 * or GEO_NONE when that edge has no single mate. *ret_via receives the
 * mate (the neighbour's owner of the crossed edge). */
static uint32_t cross_edge(const geo_poly *p, const geo_topo *t, uint32_t v,
                           uint32_t e, uint32_t *ret_via)
{
    uint32_t m = t->mate[e];
    if (m == GEO_NONE)
        return GEO_NONE;
    *ret_via = m;
    return p->fidx[m] == v ? m : geo_topo_next(p, t, m);
}

/* Walks from corner k0 of vertex v, leaving first through the edge that is
 * not `via`, appending corners to out; stops at a free edge, at k0 (sets
 * *ret_closed) or at a corner already taken. Returns the count appended. */
static uint32_t walk_fan(const geo_poly *p, const geo_topo *t, uint32_t v,
                         uint32_t k0, uint32_t via, uint8_t *taken,
                         uint32_t *out, bool *ret_closed)
{
    uint32_t n = 0, k = k0;
    *ret_closed = false;
    for (;;) {
        uint32_t exit = via == k ? geo_topo_prev(p, t, k) : k;
        uint32_t next_via;
        uint32_t k1 = cross_edge(p, t, v, exit, &next_via);
        if (k1 == GEO_NONE)
            return n;
        if (k1 == k0) {
            *ret_closed = true;
            return n;
        }
        if (taken[k1])
            return n;
        taken[k1] = 1;
        out[n++] = k1;
        k = k1;
        via = next_via;
    }
}

/* Each vertex's corners in fan order into vcorners: bucketed there by
 * vertex first, then each bucket copied out (raw, as long as the largest
 * bucket) and written back fan by fan. */
static int order_fans(const geo_poly *p, geo_topo *t)
{
    uint32_t nv = t->nverts, nc = t->ncorners;
    uint32_t *fill = calloc((size_t)nv + 1, sizeof *fill);
    uint8_t *taken = calloc((size_t)nc + 1, 1);
    if (!fill || !taken) {
        free(fill), free(taken);
        return -ENOMEM;
    }
    for (uint32_t c = 0; c < nc; c++)
        t->vstart[p->fidx[c] + 1]++;
    uint32_t maxdeg = 0;
    for (uint32_t v = 0; v < nv; v++) {
        if (t->vstart[v + 1] > maxdeg)
            maxdeg = t->vstart[v + 1];
        t->vstart[v + 1] += t->vstart[v];
    }
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t v = p->fidx[c];
        t->vcorners[t->vstart[v] + fill[v]++] = c;
    }
    free(fill);
    /* a fan of v holds at most its corners */
    uint32_t *raw = malloc(((size_t)maxdeg + 1) * sizeof *raw);
    uint32_t *bufa = malloc(((size_t)maxdeg + 1) * sizeof *bufa);
    uint32_t *bufb = malloc(((size_t)maxdeg + 1) * sizeof *bufb);
    if (!raw || !bufa || !bufb) {
        free(raw), free(taken), free(bufa), free(bufb);
        return -ENOMEM;
    }

    for (uint32_t v = 0; v < nv; v++) {
        uint32_t lo = t->vstart[v], hi = t->vstart[v + 1], out = lo;
        if (lo == hi) {
            t->vertex_kind[v] = GEO_VERTEX_ISOLATED;
            continue;
        }
        memcpy(raw, t->vcorners + lo, (size_t)(hi - lo) * sizeof *raw);
        uint32_t fans = 0;
        bool closed_all = true, bad_edge = false;
        for (uint32_t i = 0; i < hi - lo; i++) {
            uint32_t k0 = raw[i];
            uint8_t kin = t->edge_kind[geo_topo_prev(p, t, k0)];
            uint8_t kout = t->edge_kind[k0];
            if (kin == GEO_EDGE_NONMANIFOLD || kout == GEO_EDGE_NONMANIFOLD)
                bad_edge = true;
            if (taken[k0])
                continue;
            taken[k0] = 1;
            fans++;
            bool closed;
            /* leave through the in-edge first */
            uint32_t na = walk_fan(p, t, v, k0, k0, taken, bufa, &closed);
            if (closed) {
                t->vcorners[out++] = k0;
                memcpy(t->vcorners + out, bufa, na * sizeof *bufa);
                out += na;
                continue;
            }
            closed_all = false;
            bool dummy;
            uint32_t nb = walk_fan(p, t, v, k0, geo_topo_prev(p, t, k0),
                                   taken, bufb, &dummy);
            for (uint32_t j = nb; j-- > 0;)
                t->vcorners[out++] = bufb[j];
            t->vcorners[out++] = k0;
            memcpy(t->vcorners + out, bufa, na * sizeof *bufa);
            out += na;
        }
        if (fans > 1 || bad_edge) {
            t->vertex_kind[v] = GEO_VERTEX_NONMANIFOLD;
            t->nnonmanifold_vertices++;
        } else {
            t->vertex_kind[v] =
                closed_all ? GEO_VERTEX_INTERIOR : GEO_VERTEX_BOUNDARY;
        }
    }
    free(raw), free(taken), free(bufa), free(bufb);
    return 0;
}

/* The topology of p; without corner_facet when lean and every facet
 * is a triangle (facets of at least 3 corners, 3 per facet on average). */
static geo_topo *build(const geo_poly *p, bool lean, geo_err *err)
{
    geo_topo *t = calloc(1, sizeof *t);
    if (!t)
        goto oom;
    uint32_t nc = geo_poly_ncorners(p);
    t->nverts = p->nverts;
    t->nfacets = p->nfacets;
    t->ncorners = nc;
    if (!lean || nc != 3 * (uint64_t)p->nfacets) {
        t->corner_facet = malloc(((size_t)nc + 1) * sizeof *t->corner_facet);
        if (!t->corner_facet)
            goto oom;
        for (uint32_t f = 0; f < p->nfacets; f++)
            for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++)
                t->corner_facet[c] = f;
    }
    t->mate = malloc(((size_t)nc + 1) * sizeof *t->mate);
    t->edge_kind = malloc((size_t)nc + 1);
    t->vstart = calloc((size_t)p->nverts + 1, sizeof *t->vstart);
    t->vcorners = malloc(((size_t)nc + 1) * sizeof *t->vcorners);
    t->vertex_kind = malloc((size_t)p->nverts + 1);
    if (!t->mate || !t->edge_kind || !t->vstart || !t->vcorners ||
        !t->vertex_kind)
        goto oom;
    if (pair_edges(p, t) < 0 || order_fans(p, t) < 0)
        goto oom;
    return t;
oom:
    geo_err_set(err, -ENOMEM, "out of memory building the topology");
    return geo_topo_free(t);
}

geo_topo *geo_topo_build(const geo_poly *p, geo_err *err)
{
    return build(p, false, err);
}

static geo_topo *build_checked(const geo_poly *p, bool lean, int *ret_rc,
                               geo_err *err)
{
    int rc = geo_poly_validate_indices(p, err);
    geo_topo *t = rc < 0 ? NULL : build(p, lean, err);
    if (!t)
        *ret_rc = rc < 0 ? rc : -ENOMEM;
    return t;
}

geo_topo *geo_topo_build_checked(const geo_poly *p, int *ret_rc,
                                 geo_err *err)
{
    return build_checked(p, false, ret_rc, err);
}

geo_topo *geo_topo_build_lean(const geo_poly *p, int *ret_rc, geo_err *err)
{
    return build_checked(p, true, ret_rc, err);
}

/* The boundary corner that follows boundary corner c around its hole:
 * walk the fan of c's end vertex from c's facet to the next free edge. */
static uint32_t next_boundary(const geo_poly *p, const geo_topo *t,
                              uint32_t c)
{
    uint32_t k = geo_topo_next(p, t, c), v = p->fidx[k], via = c;
    for (uint32_t guard = 0; guard <= t->ncorners; guard++) {
        uint32_t exit = via == k ? geo_topo_prev(p, t, k) : k;
        uint8_t kind = t->edge_kind[exit];
        if (kind == GEO_EDGE_BOUNDARY)
            return exit;
        if (kind == GEO_EDGE_NONMANIFOLD)
            return GEO_NONE;
        uint32_t nv;
        uint32_t k1 = cross_edge(p, t, v, exit, &nv);
        if (k1 == GEO_NONE)
            return GEO_NONE;
        k = k1;
        via = nv;
    }
    return GEO_NONE;
}

int geo_topo_boundary_loops(const geo_poly *p, const geo_topo *t,
                            uint32_t **ret_start, uint32_t **ret_corners,
                            uint32_t *ret_nloops)
{
    uint32_t nb = t->nboundary_edges;
    uint32_t *start = malloc(((size_t)nb + 2) * sizeof *start);
    uint32_t *corners = malloc(((size_t)nb + 1) * sizeof *corners);
    uint8_t *used = calloc((size_t)t->ncorners + 1, 1);
    if (!start || !corners || !used) {
        free(start), free(corners), free(used);
        return -ENOMEM;
    }
    /* pos[v]: 1 + the stack slot of the corner leaving v in the walk
     * being split; walk, stack: scratch for that walk */
    bool split = t->nnonmanifold_vertices > 0;
    uint32_t *pos = split ? calloc((size_t)p->nverts + 1, sizeof *pos) : NULL;
    uint32_t *walk = split ? malloc(((size_t)nb + 1) * sizeof *walk) : NULL;
    uint32_t *stack = split ? malloc(((size_t)nb + 1) * sizeof *stack) : NULL;
    if (split && (!pos || !walk || !stack)) {
        free(start), free(corners), free(used), free(pos), free(walk),
            free(stack);
        return -ENOMEM;
    }
    uint32_t nloops = 0, n = 0;
    start[0] = 0;
    for (uint32_t c0 = 0; c0 < t->ncorners; c0++) {
        if (t->edge_kind[c0] != GEO_EDGE_BOUNDARY || used[c0])
            continue;
        uint32_t c = c0, first = n;
        while (c != GEO_NONE && !used[c]) {
            used[c] = 1;
            corners[n++] = c;
            c = next_boundary(p, t, c);
        }
        if (c != c0 || !split) {
            start[++nloops] = n;
            continue;
        }
        /* A closed walk that comes back to a vertex it left before (two
         * holes touching at a pinch vertex: each fan there leads from one
         * hole into the other) is split into simple loops: the stretch
         * since the walk left that vertex is a loop of its own. Loops are
         * written in the order they close. */
        uint32_t len = n - first, top = 0, o = first;
        memcpy(walk, corners + first, (size_t)len * sizeof *walk);
        for (uint32_t k = 0; k <= len; k++) {
            uint32_t v = k < len ? p->fidx[walk[k]] : GEO_NONE;
            uint32_t from = k < len ? (pos[v] ? pos[v] - 1 : GEO_NONE) : 0;
            if (from != GEO_NONE) {
                for (uint32_t q = from; q < top; q++) {
                    pos[p->fidx[stack[q]]] = 0;
                    corners[o++] = stack[q];
                }
                start[++nloops] = o;
                top = from;
            }
            if (k < len) {
                stack[top] = walk[k];
                pos[v] = ++top;
            }
        }
    }
    free(pos), free(walk), free(stack);
    free(used);
    *ret_start = start;
    *ret_corners = corners;
    *ret_nloops = nloops;
    return 0;
}
