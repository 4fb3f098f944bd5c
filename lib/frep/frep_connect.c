/* frep_connect.c — section contours over the runs of a geo_frep_grid,
 * the rotation system they define, face tracing, quads.
 *
 * Notation: a section has a column coordinate c (j for vertical sections,
 * i for horizontal ones) and the sample index k. With the inside on the
 * left, a run's exit point (top, outward +z) is left moving towards −c,
 * its entry point (bottom, outward −z) towards +c. Point p's four
 * neighbours are stored as nb[4p + slot]. */
#include "frep_connect.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "edgemap.h"
#include "vec.h"

enum { NV = 0, PV = 1, NH = 2, PH = 3 }; /* next/prev in V and H */
enum { BLOCK = 4096 };

/* Directions around a point, counter-clockwise seen from outside. An exit
 * point (outward +z): nextV −y, nextH −x, so CCW from above: +x (prevH),
 * +y (prevV), −x (nextH), −y (nextV). An entry point (outward −z): nextV
 * +y, nextH +x; CCW seen from below: +x (nextH), −y (prevV), −x (prevH),
 * +y (nextV). */
static const uint8_t ROT[2][4] = {{NH, PV, PH, NV}, {PH, PV, NH, NV}};
static const uint8_t POS[2][4] = {
    /* slot → position in ROT, entry */ {3, 1, 0, 2},
    /* exit */ {3, 1, 2, 0}};
static const uint8_t OPP[4] = {PV, NV, PH, NH};

/* Last run of [a, b) whose start is ≤ k, or a − 1 when none. */
static int64_t last_le(const int32_t (*runs)[2], uint32_t a, uint32_t b,
                       int32_t k)
{
    int64_t lo = a, hi = (int64_t)b - 1, ans = (int64_t)a - 1;
    while (lo <= hi) {
        int64_t mid = lo + (hi - lo) / 2;
        if (runs[mid][0] <= k) {
            ans = mid;
            lo = mid + 1;
        } else {
            hi = mid - 1;
        }
    }
    return ans;
}

/* The successor of point pt on its section contour; step is the column-id
 * distance of a +c move (1 for horizontal sections, n for vertical). */
static uint32_t sec_next(const geo_frep_grid *g, uint32_t pt, uint32_t step)
{
    const int32_t(*runs)[2] = (const int32_t(*)[2])g->runs;
    uint32_t r = pt >> 1, col = g->run_col[r];
    int32_t s = runs[r][0], e = runs[r][1];
    uint32_t ca = g->col_start[col], cb = g->col_start[col + 1];
    if (pt & 1) {
        /* exit: moving −c along the top of the run, at height e + ½ */
        uint32_t nc = col - step, a = g->col_start[nc],
                 b = g->col_start[nc + 1];
        int64_t R = last_le(runs, a, b, e);
        if (R >= a && runs[R][1] >= e) {
            if (runs[R][1] == e)
                return (uint32_t)(2 * R + 1); /* straight on */
            /* turn right: up the wall of column c−1 */
            if (r + 1 < cb && runs[r + 1][0] <= runs[R][1])
                return 2 * (r + 1);
            return (uint32_t)(2 * R + 1);
        }
        /* turn left: down the wall of our own run */
        if (R >= a && runs[R][1] >= s)
            return (uint32_t)(2 * R + 1);
        return 2 * r;
    }
    /* entry: moving +c along the bottom of the run, at height s − ½ */
    uint32_t nc = col + step, a = g->col_start[nc], b = g->col_start[nc + 1];
    int64_t R = last_le(runs, a, b, s);
    if (R >= a && runs[R][1] >= s) {
        if (runs[R][0] == s)
            return (uint32_t)(2 * R);
        /* turn right: down the wall of column c+1 */
        if (r > ca && runs[r - 1][1] >= runs[R][0])
            return 2 * (r - 1) + 1;
        return (uint32_t)(2 * R);
    }
    /* turn left: up the wall of our own run */
    if (R + 1 < b && runs[R + 1][0] <= e)
        return (uint32_t)(2 * (R + 1));
    return 2 * r + 1;
}

typedef struct succ_job {
    const geo_frep_grid *g;
    uint32_t *nb;
    uint32_t npts;
} succ_job;

static void succ_task(void *arg, size_t blk)
{
    succ_job *sj = arg;
    size_t p0 = blk * BLOCK, p1 = p0 + BLOCK;
    if (p1 > sj->npts)
        p1 = sj->npts;
    for (size_t p = p0; p < p1; p++) {
        sj->nb[4 * p + NV] = sec_next(sj->g, (uint32_t)p, sj->g->n);
        sj->nb[4 * p + NH] = sec_next(sj->g, (uint32_t)p, 1);
    }
}

static int64_t icross(const geo_frep_grid *g, uint32_t a, uint32_t b,
                      uint32_t c)
{
    uint32_t ca = g->run_col[a >> 1], cb = g->run_col[b >> 1],
             cc = g->run_col[c >> 1];
    int64_t ai = ca % g->n, aj = ca / g->n, bi = cb % g->n, bj = cb / g->n,
            ci = cc % g->n, cj = cc / g->n;
    return (bi - ai) * (cj - aj) - (bj - aj) * (ci - ai);
}

int geo_frep_connect(const geo_frep_grid *g, const geo_ctx *ctx,
                     geo_poly **ret_mesh, uint8_t **ret_flat,
                     geo_frep_connect_stats *st, geo_err *err)
{
    geo_frep_connect_stats stats = {0};
    uint32_t npts = 2 * g->nruns;
    uint32_t *nb = malloc(4 * (size_t)npts * sizeof *nb + 1);
    uint8_t *seen = calloc((size_t)npts * 4 + 1, 1);
    uint32_t *cyc = NULL;
    uint8_t *flat = NULL;
    size_t flat_cap = 0;
    geo_poly *mesh = geo_poly_new();
    geo_edgemap used = {0}, undirected = {0};
    int rc = 0;
    if (!nb || !seen || !mesh) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
    succ_job sj = {g, nb, npts};
    geo_ctx_parallel_for(ctx, (npts + (size_t)BLOCK - 1) / BLOCK, succ_task,
                         &sj);
    if (geo_ctx_canceled(ctx)) {
        rc = geo_err_set(err, -ECANCELED, "canceled");
        goto done;
    }
    for (size_t p = 0; p < npts; p++)
        nb[4 * p + PV] = nb[4 * p + PH] = UINT32_MAX;
    for (uint32_t p = 0; p < npts; p++)
        for (int sec = 0; sec < 2; sec++) {
            uint32_t q = nb[4 * (size_t)p + (sec ? NH : NV)];
            uint32_t *back = &nb[4 * (size_t)q + (sec ? PH : PV)];
            if (*back != UINT32_MAX) {
                rc = geo_err_set(err, -EINVAL,
                                 "section contours are inconsistent at "
                                 "point %u", q);
                goto done;
            }
            *back = p;
        }
    if (geo_poly_reserve(mesh, npts, (size_t)npts * 2 + 16,
                         (size_t)npts * 6 + 48) < 0 ||
        geo_edgemap_init(&used, (size_t)npts * 6) < 0 ||
        geo_edgemap_init(&undirected, (size_t)npts * 3) < 0) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
    for (uint32_t p = 0; p < npts; p++) {
        if (geo_poly_add_vertex(mesh, g->pts[p]) < 0) {
            rc = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        for (int sec = 0; sec < 2; sec++)
            if (geo_edgemap_put(&undirected,
                                geo_edge_ukey(p, nb[4 * (size_t)p +
                                                    (sec ? NH : NV)]),
                                1) < 0) {
                rc = geo_err_set(err, -ENOMEM, "out of memory");
                goto done;
            }
    }
    size_t cyc_cap = 64;
    cyc = malloc(cyc_cap * sizeof *cyc);
    if (!cyc) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
    for (size_t h0 = 0; h0 < 4 * (size_t)npts; h0++) {
        if (seen[h0])
            continue;
        if ((h0 & 0xffff) == 0 && geo_ctx_canceled(ctx)) {
            rc = geo_err_set(err, -ECANCELED, "canceled");
            goto done;
        }
        /* trace the face to the left of half-edge h0 */
        size_t len = 0, h = h0;
        do {
            seen[h] = 1;
            uint32_t p = (uint32_t)(h >> 2), s = (uint32_t)(h & 3);
            if (len == cyc_cap) {
                uint32_t *nc = realloc(cyc, 2 * cyc_cap * sizeof *nc);
                if (!nc) {
                    rc = geo_err_set(err, -ENOMEM, "out of memory");
                    goto done;
                }
                cyc = nc;
                cyc_cap *= 2;
            }
            cyc[len++] = p;
            uint32_t q = nb[h], t = OPP[s], kind = q & 1;
            uint32_t s2 = ROT[kind][(POS[kind][t] + 3) & 3];
            h = 4 * (size_t)q + s2;
        } while (h != h0 && len <= 4 * (size_t)npts);
        stats.ncells++;
        if (len == 2) {
            stats.ncollapsed++;
            continue;
        }
        bool quad = len == 4 && cyc[0] != cyc[1] && cyc[0] != cyc[2] &&
                    cyc[0] != cyc[3] && cyc[1] != cyc[2] &&
                    cyc[1] != cyc[3] && cyc[2] != cyc[3];
        for (size_t k = 0; quad && k < 4; k++)
            if (geo_edgemap_get(&used, geo_edge_key(cyc[k],
                                                    cyc[(k + 1) & 3])) !=
                UINT32_MAX)
                quad = false;
        int shift = 0;
        if (quad) {
            const double *a = g->pts[cyc[0]], *b = g->pts[cyc[1]],
                         *c = g->pts[cyc[2]], *d = g->pts[cyc[3]];
            bool ac_free = geo_edgemap_get(&undirected,
                                           geo_edge_ukey(cyc[0], cyc[2])) ==
                           UINT32_MAX;
            bool bd_free = geo_edgemap_get(&undirected,
                                           geo_edge_ukey(cyc[1], cyc[3])) ==
                           UINT32_MAX;
            bool prefer_ac = geo_vdist(a, c) <= geo_vdist(b, d);
            if (ac_free && (prefer_ac || !bd_free))
                shift = 0;
            else if (bd_free)
                shift = 1;
            else
                quad = false;
        }
        if (!quad) {
            stats.nopen++;
            continue;
        }
        uint32_t A = cyc[shift], B = cyc[shift + 1], C = cyc[shift + 2],
                 D = cyc[(shift + 3) & 3];
        uint32_t t1[3] = {A, B, C}, t2[3] = {A, C, D};
        if (geo_poly_add_facet(mesh, t1, 3) < 0 ||
            geo_poly_add_facet(mesh, t2, 3) < 0 ||
            geo_edgemap_put(&undirected, geo_edge_ukey(A, C), 1) < 0) {
            rc = geo_err_set(err, -ENOMEM, "out of memory");
            goto done;
        }
        for (size_t k = 0; k < 4; k++)
            if (geo_edgemap_put(&used,
                                geo_edge_key(cyc[k], cyc[(k + 1) & 3]),
                                1) < 0) {
                rc = geo_err_set(err, -ENOMEM, "out of memory");
                goto done;
            }
        if (mesh->nfacets > flat_cap) {
            size_t nc = flat_cap ? 2 * flat_cap : 4096;
            uint8_t *nf = realloc(flat, nc);
            if (!nf) {
                rc = geo_err_set(err, -ENOMEM, "out of memory");
                goto done;
            }
            flat = nf;
            flat_cap = nc;
        }
        flat[mesh->nfacets - 2] = icross(g, A, B, C) == 0;
        flat[mesh->nfacets - 1] = icross(g, A, C, D) == 0;
        stats.nflat += flat[mesh->nfacets - 2] + flat[mesh->nfacets - 1];
        stats.nquads++;
    }
    if (!flat && !(flat = calloc(1, 1))) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
done:
    free(nb);
    free(seen);
    free(cyc);
    geo_edgemap_destroy(&used);
    geo_edgemap_destroy(&undirected);
    if (rc < 0) {
        geo_poly_free(mesh);
        free(flat);
        return rc;
    }
    *ret_mesh = mesh;
    *ret_flat = flat;
    if (st)
        *st = stats;
    return 0;
}
