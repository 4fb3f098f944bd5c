/* ptree.c — the tree of balls over points (ptree.h).
 *
 * Invariants: node 0 is the root; a node that is not a leaf has its
 * halves at index + 1 and at right; idx[lo .. hi) are its points, and
 * every one lies within r of c (r computed, then widened by 1e-9 of
 * itself for the rounding of the distances). */
#include "ptree.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "select.h"
#include "vec.h"

#define LEAF_SIZE 4 /* points a leaf holds, at most (but equal ones) */
#define LEAF UINT32_MAX

typedef struct node {
    double c[3], r;         /* the ball */
    uint32_t lo, hi, right; /* idx[lo .. hi); right half, or LEAF */
} node;

struct geo_ptree {
    uint32_t n, nfin; /* points; the finite ones come first in idx */
    uint32_t *idx;
    node *node;
    uint32_t nnodes, depth;
    double scale; /* the largest |x| + |y| + |z| of a finite point */
};

/* The node of idx[lo .. hi) at depth, then its halves' (preorder). */
static void build(geo_ptree *t, const double (*pts)[3], uint32_t lo,
                  uint32_t hi, uint32_t depth)
{
    uint32_t id = t->nnodes++;
    node *nd = &t->node[id];
    if (depth > t->depth)
        t->depth = depth;
    double blo[3] = {INFINITY, INFINITY, INFINITY};
    double bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = lo; i < hi; i++) /* finite points: no NaN here */
        for (int k = 0; k < 3; k++) {
            double x = pts[t->idx[i]][k];
            blo[k] = x < blo[k] ? x : blo[k];
            bhi[k] = x > bhi[k] ? x : bhi[k];
        }
    double r2 = 0;
    for (int k = 0; k < 3; k++)
        nd->c[k] = blo[k] + (bhi[k] - blo[k]) / 2;
    for (uint32_t i = lo; i < hi; i++) {
        double d[3];
        geo_vsub(pts[t->idx[i]], nd->c, d);
        double d2 = geo_vdot(d, d);
        r2 = d2 > r2 ? d2 : r2;
    }
    nd->r = sqrt(r2) * (1 + 1e-9);
    nd->lo = lo, nd->hi = hi, nd->right = LEAF;
    int axis = 0;
    for (int k = 1; k < 3; k++)
        if (bhi[k] - blo[k] > bhi[axis] - blo[axis])
            axis = k;
    if (hi - lo <= LEAF_SIZE || !(bhi[axis] > blo[axis]))
        return;
    uint32_t mid = lo + (hi - lo) / 2;
    geo_select_axis(pts, t->idx, lo, hi, mid, axis);
    build(t, pts, lo, mid, depth + 1);
    t->node[id].right = t->nnodes;
    build(t, pts, mid, hi, depth + 1);
}

int geo_ptree_build(const double (*pts)[3], uint32_t n, geo_ptree **ret)
{
    *ret = NULL;
    geo_ptree *t = calloc(1, sizeof *t);
    if (!t)
        return -ENOMEM;
    t->idx = malloc(((size_t)n + 1) * sizeof *t->idx);
    /* median splits: at most 2n − 1 nodes */
    t->node = malloc((2 * (size_t)n + 1) * sizeof *t->node);
    if (!t->idx || !t->node) {
        geo_ptree_free(t);
        return -ENOMEM;
    }
    t->n = n;
    uint32_t a = 0, b = n;
    for (uint32_t v = 0; v < n; v++) {
        const double *x = pts[v];
        if (isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2])) {
            t->scale = fmax(t->scale, fabs(x[0]) + fabs(x[1]) + fabs(x[2]));
            t->idx[a++] = v;
        } else {
            t->idx[--b] = v;
        }
    }
    t->nfin = a;
    if (a > 0)
        build(t, pts, 0, a, 1);
    *ret = t;
    return 0;
}

/* The rounding margin of a plane's bounds, and its normal's length
 * (widened by 1e-9 of itself) in *ret_len. */
static double slack_of(const geo_ptree *t, const double plane[4],
                       double *ret_len)
{
    double len = sqrt(plane[0] * plane[0] + plane[1] * plane[1] +
                      plane[2] * plane[2]);
    *ret_len = len * (1 + 1e-9);
    /* far above an evaluation's rounding, at a point or a centre */
    return 1e-12 * (len * t->scale + fabs(plane[3]) + 1);
}

uint32_t geo_ptree_above(const geo_ptree *t, const double plane[4],
                         double level, uint32_t *out)
{
    uint32_t m = 0;
    for (uint32_t i = t->nfin; i < t->n; i++)
        out[m++] = t->idx[i];
    if (t->nfin == 0)
        return m;
    double len, slack = slack_of(t, plane, &len);
    /* the pending right halves; the depth bounds them */
    uint32_t stack[64], top = 0, id = 0;
    for (;;) {
        const node *nd = &t->node[id];
        double bound = geo_plane_eval(plane, nd->c) + len * nd->r + slack;
        if (!(bound <= level)) {
            if (nd->right == LEAF) {
                for (uint32_t i = nd->lo; i < nd->hi; i++)
                    out[m++] = t->idx[i];
            } else {
                stack[top++] = nd->right;
                id++;
                continue;
            }
        }
        if (top == 0)
            break;
        id = stack[--top];
    }
    return m;
}

/* The planes cand[depth − 1][0 .. nc) against the points of node id:
 * those that may be the highest at one of them go on to its halves. */
static void reach_node(const geo_ptree *t, const double (*pts)[3],
                       const double (*planes)[4], uint32_t **cand,
                       double *val, uint32_t id, uint32_t depth, uint32_t nc,
                       double nmax, double slack, double *out)
{
    const node *nd = &t->node[id];
    const uint32_t *in = cand[depth - 1];
    double best = -INFINITY, r = nd->r * nmax;
    for (uint32_t q = 0; q < nc; q++) {
        double v = geo_plane_eval(planes[in[q]], nd->c);
        val[q] = v;
        if (v > best)
            best = v;
    }
    /* at a point within r of c, a plane is within r of its value at c:
     * one below best − 2r there is below the plane of best; one below −r
     * is below 0 */
    double lim = fmax(best - 2 * r, -r) - slack;
    uint32_t *kept = cand[depth], nk = 0;
    for (uint32_t q = 0; q < nc; q++)
        if (!(val[q] < lim))
            kept[nk++] = in[q];
    if (nd->right != LEAF) {
        reach_node(t, pts, planes, cand, val, id + 1, depth + 1, nk, nmax,
                   slack, out);
        reach_node(t, pts, planes, cand, val, nd->right, depth + 1, nk, nmax,
                   slack, out);
        return;
    }
    double m = *out;
    for (uint32_t i = nd->lo; i < nd->hi; i++) {
        const double *x = pts[t->idx[i]];
        for (uint32_t q = 0; q < nk; q++) {
            double d = geo_plane_eval(planes[kept[q]], x);
            if (d > m)
                m = d;
        }
    }
    *out = m;
}

int geo_ptree_reach(const geo_ptree *t, const double (*pts)[3],
                    const double (*planes)[4], uint32_t nplanes,
                    double *ret)
{
    double out = 0;
    /* the points that are not finite against every plane */
    for (uint32_t i = t->nfin; i < t->n; i++)
        for (uint32_t j = 0; j < nplanes; j++) {
            double d = geo_plane_eval(planes[j], pts[t->idx[i]]);
            if (d > out)
                out = d;
        }
    *ret = out;
    if (t->nfin == 0 || nplanes == 0)
        return 0;
    uint32_t **cand = calloc((size_t)t->depth + 1, sizeof *cand);
    double *val = malloc((size_t)nplanes * sizeof *val);
    int rc = -ENOMEM;
    if (!cand || !val)
        goto out;
    for (uint32_t d = 0; d <= t->depth; d++)
        if (!(cand[d] = malloc((size_t)nplanes * sizeof **cand)))
            goto out;
    double nmax = 0, slack = 0;
    for (uint32_t j = 0; j < nplanes; j++) {
        double len, s = slack_of(t, planes[j], &len);
        nmax = fmax(nmax, len);
        slack = fmax(slack, s);
        cand[0][j] = j;
    }
    reach_node(t, pts, planes, cand, val, 0, 1, nplanes, nmax, slack, &out);
    *ret = out;
    rc = 0;
out:
    if (cand)
        for (uint32_t d = 0; d <= t->depth; d++)
            free(cand[d]);
    free(cand);
    free(val);
    return rc;
}

geo_ptree *geo_ptree_free(geo_ptree *t)
{
    if (t) {
        free(t->idx);
        free(t->node);
        free(t);
    }
    return NULL;
}
