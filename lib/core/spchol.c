/* spchol.c — sparse Cholesky with a nested-dissection or a
 * minimum-degree ordering (see spchol.h).
 *
 * Invariants: perm is a permutation of 0 … n−1 (perm[k] is the unknown
 * eliminated k-th); column j of L holds its diagonal first, then its
 * rows below in increasing order, in Li/Lx[Lp[j] .. Lp[j+1]). */
#include "spchol.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX
#define LEAF 64

struct geo_spchol {
    uint32_t n;
    uint32_t *perm;
    uint64_t *Lp;
    uint32_t *Li;
    double *Lx;
    /* the symbolic part, kept for geo_spchol_refactor: C = P·A·P''s
     * upper triangle by columns (Cp, Ci; cmap: each entry's index in A's
     * values), the elimination tree, and A's own pattern to check a
     * refactored matrix against */
    uint64_t *Cp;
    uint32_t *Ci, *cmap, *parent;
    uint32_t *arp, *aci;
};

/* ---- ordering ---- */

typedef struct nd_task {
    uint32_t start, count;
    bool emit; /* append as they are (a separator, or a set too small) */
} nd_task;

typedef struct nd_work {
    const uint32_t *rp, *ci;
    uint32_t *set;   /* per unknown: id of the set it is in now */
    uint32_t *level; /* per unknown: its level in the last search */
    uint32_t *queue; /* search order */
    uint32_t *cnt;   /* per level: unknowns */
    uint32_t *tmp;
} nd_work;

/* Breadth-first search from root within the unknowns of set id; fills
 * queue and level; returns the number reached, *ret_h the last level. */
static uint32_t bfs(nd_work *W, uint32_t id, uint32_t root, uint32_t stamp,
                    uint32_t *ret_h)
{
    /* set[v] == id: in the set, not reached; stamp: reached */
    uint32_t head = 0, tail = 0;
    W->queue[tail++] = root;
    W->set[root] = stamp;
    W->level[root] = 0;
    while (head < tail) {
        uint32_t v = W->queue[head++];
        for (uint32_t q = W->rp[v]; q < W->rp[v + 1]; q++) {
            uint32_t u = W->ci[q];
            if (W->set[u] != id)
                continue;
            W->set[u] = stamp;
            W->level[u] = W->level[v] + 1;
            W->queue[tail++] = u;
        }
    }
    *ret_h = W->level[W->queue[tail - 1]];
    return tail;
}

static uint32_t degree(const nd_work *W, uint32_t v)
{
    return W->rp[v + 1] - W->rp[v];
}

/* Splits the set work[start .. start+count) (all marked id): pushes the
 * tasks that order it onto the stack. *next_id supplies fresh set ids. */
static void nd_split(nd_work *W, uint32_t *work, nd_task *stack,
                     uint32_t *top, nd_task t, uint32_t *next_id)
{
    uint32_t *S = work + t.start, m = t.count;
    uint32_t id = (*next_id)++;
    for (uint32_t k = 0; k < m; k++)
        W->set[S[k]] = id;
    /* a pseudo-peripheral root: restart from a least-degree vertex of
     * the last level while that makes the search deeper */
    uint32_t root = S[0], h = 0, reached = 0;
    for (int round = 0; round < 5; round++) {
        uint32_t stamp = (*next_id)++, hh;
        reached = bfs(W, id, root, stamp, &hh);
        for (uint32_t k = 0; k < reached; k++)
            W->set[W->queue[k]] = id;
        if (round > 0 && hh <= h)
            break;
        h = hh;
        uint32_t best = NONE;
        for (uint32_t k = reached; k-- > 0 && W->level[W->queue[k]] == hh;)
            if (best == NONE || degree(W, W->queue[k]) < degree(W, best))
                best = W->queue[k];
        root = best;
    }
    /* the levels of the last search from root */
    uint32_t stamp = (*next_id)++;
    reached = bfs(W, id, root, stamp, &h);
    if (reached < m) {
        /* not connected: the component reached, then the rest */
        uint32_t a = 0, b = reached;
        for (uint32_t k = 0; k < m; k++)
            W->tmp[W->set[S[k]] == stamp ? a++ : b++] = S[k];
        memcpy(S, W->tmp, (size_t)m * sizeof *S);
        stack[(*top)++] = (nd_task){t.start + reached, m - reached, false};
        stack[(*top)++] = (nd_task){t.start, reached, false};
        return;
    }
    if (h < 2) {
        stack[(*top)++] = (nd_task){t.start, m, true};
        return;
    }
    memset(W->cnt, 0, ((size_t)h + 1) * sizeof *W->cnt);
    for (uint32_t k = 0; k < m; k++)
        W->cnt[W->level[S[k]]]++;
    /* the separator: the smallest level leaving at most 2/3 on either
     * side, else the median level */
    uint32_t sep = NONE, before = 0, median = NONE;
    for (uint32_t l = 0; l <= h; l++) {
        uint32_t after = m - before - W->cnt[l];
        if (l >= 1 && l < h && 3 * (uint64_t)before <= 2 * (uint64_t)m &&
            3 * (uint64_t)after <= 2 * (uint64_t)m &&
            (sep == NONE || W->cnt[l] < W->cnt[sep]))
            sep = l;
        if (median == NONE && 2 * (uint64_t)(before + W->cnt[l]) >= m)
            median = l;
        before += W->cnt[l];
    }
    if (sep == NONE)
        sep = median < 1 ? 1 : median >= h ? h - 1 : median;
    uint32_t na = 0, nb = 0, nc = 0;
    for (uint32_t k = 0; k < m; k++) {
        uint32_t l = W->level[S[k]];
        na += l < sep;
        nb += l > sep;
    }
    nc = m - na - nb;
    uint32_t ia = 0, ib = na, ic = na + nb;
    for (uint32_t k = 0; k < m; k++) {
        uint32_t l = W->level[S[k]];
        W->tmp[l < sep ? ia++ : l > sep ? ib++ : ic++] = S[k];
    }
    memcpy(S, W->tmp, (size_t)m * sizeof *S);
    stack[(*top)++] = (nd_task){t.start + na + nb, nc, true};
    stack[(*top)++] = (nd_task){t.start + na, nb, false};
    stack[(*top)++] = (nd_task){t.start, na, false};
}

/* perm: the elimination order. 0 or -ENOMEM. */
static int nd_order(uint32_t n, const uint32_t *rp, const uint32_t *ci,
                    uint32_t *perm)
{
    nd_work W = {rp, ci, NULL, NULL, NULL, NULL, NULL};
    uint32_t *work = malloc(((size_t)n + 1) * sizeof *work);
    /* each split pushes at most three tasks and pops one; the depth of
     * the recursion is O(log n) for balanced splits and at most n */
    nd_task *stack = malloc((2 * (size_t)n + 4) * sizeof *stack);
    W.set = calloc((size_t)n + 1, sizeof *W.set);
    W.level = malloc(((size_t)n + 1) * sizeof *W.level);
    W.queue = malloc(((size_t)n + 1) * sizeof *W.queue);
    W.cnt = malloc(((size_t)n + 1) * sizeof *W.cnt);
    W.tmp = malloc(((size_t)n + 1) * sizeof *W.tmp);
    int rc = -ENOMEM;
    if (!work || !stack || !W.set || !W.level || !W.queue || !W.cnt || !W.tmp)
        goto out;
    for (uint32_t v = 0; v < n; v++)
        work[v] = v;
    uint32_t top = 0, pos = 0, next_id = 1;
    if (n > 0)
        stack[top++] = (nd_task){0, n, false};
    while (top > 0) {
        nd_task t = stack[--top];
        if (t.count == 0)
            continue;
        if (t.emit || t.count <= LEAF) {
            memcpy(perm + pos, work + t.start, (size_t)t.count * sizeof *perm);
            pos += t.count;
            continue;
        }
        nd_split(&W, work, stack, &top, t, &next_id);
    }
    rc = 0;
out:
    free(work), free(stack), free(W.set), free(W.level), free(W.queue);
    free(W.cnt), free(W.tmp);
    return rc;
}

/* ---- minimum degree ---- */

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Approximate minimum degree (Amestoy, Davis and Duff 1996) on the
 * quotient graph, over supervariables: unknowns with the same closed
 * neighbourhood in A (the three of a plane in convex_refine) are one
 * node of their count's weight and are eliminated together. An
 * eliminated node becomes an element: the clique of its neighbours,
 * kept as a list rather than as the clique's edges, and it absorbs the
 * elements it was adjacent to (and any other whose variables all lie in
 * its clique). The next pivot is a node of least approximate external
 * degree — the variables it is joined to, bounded above by those of its
 * variables outside the new element, the new element and |L_e \ L_p| of
 * its other elements; bucket lists give it in O(1), ties to the node
 * whose degree changed last. The pivot's clique is exact, so the count
 * of L's entries, checked against max_nnz as it goes, is the factor's.
 * The work is about the entries of A plus those of the elements' lists
 * as they are built. */
enum { MD_VARIABLE, MD_ELEMENT, MD_ABSORBED };

typedef struct md_work {
    uint32_t **adj, *len, *cap;
    uint32_t *head, *next, *prev, *deg;
    uint32_t *w;     /* per node: its unknowns */
    uint32_t *first; /* per node: its first unknown */
    uint32_t *buf;
    uint32_t **el, *elen, *ecap; /* per variable: its elements */
    uint32_t *ext;   /* per variable: its approximate external degree */
    uint32_t *lw;    /* per element: the weight of its variables */
    uint32_t *wv, *wmark; /* per element: |L_e \ L_p|, set in round */
    uint32_t *mark;  /* per node: in the pivot's clique (its round) */
    uint8_t *state;
} md_work;

static void md_unlink(md_work *M, uint32_t v)
{
    if (M->prev[v] != NONE)
        M->next[M->prev[v]] = M->next[v];
    else
        M->head[M->deg[v]] = M->next[v];
    if (M->next[v] != NONE)
        M->prev[M->next[v]] = M->prev[v];
}

static void md_link(md_work *M, uint32_t v)
{
    uint32_t d = M->deg[v];
    M->prev[v] = NONE;
    M->next[v] = M->head[d];
    if (M->head[d] != NONE)
        M->prev[M->head[d]] = v;
    M->head[d] = v;
}

/* Appends the variables of node s's list not yet marked with stamp to
 * M->buf (*m of them, their weight added to *deg). */
static void md_gather(md_work *M, uint32_t s, uint32_t stamp, uint32_t *m,
                      uint32_t *deg)
{
    for (uint32_t q = 0; q < M->len[s]; q++) {
        uint32_t v = M->adj[s][q];
        if (M->state[v] == MD_VARIABLE && M->mark[v] != stamp) {
            M->mark[v] = stamp;
            M->buf[(*m)++] = v;
            *deg += M->w[v];
        }
    }
}

/* Element e is covered by another: its list is no longer read. */
static void md_absorb(md_work *M, uint32_t e)
{
    M->state[e] = MD_ABSORBED;
    free(M->adj[e]);
    M->adj[e] = NULL;
    M->len[e] = 0;
}

/* The graph of A + A' without the diagonal, each row sorted: the
 * transpose of the transpose sorts A's rows, the transpose adds the
 * entries of a pattern given with one triangle missing. 0 or -ENOMEM. */
static int md_graph(uint32_t n, const uint32_t *rp, const uint32_t *ci,
                    uint32_t **ret_p, uint32_t **ret_i)
{
    size_t nz = n ? rp[n] : 0;
    uint32_t *tp = calloc((size_t)n + 2, sizeof *tp);
    uint32_t *ti = malloc((nz + 1) * sizeof *ti);
    uint32_t *sp = calloc((size_t)n + 2, sizeof *sp);
    uint32_t *si = malloc((nz + 1) * sizeof *si);
    uint32_t *gp = calloc((size_t)n + 1, sizeof *gp);
    uint32_t *gi = malloc((2 * nz + 1) * sizeof *gi);
    int rc = -ENOMEM;
    if (!tp || !ti || !sp || !si || !gp || !gi)
        goto out;
    for (uint32_t v = 0; v < n; v++)
        for (uint32_t q = rp[v]; q < rp[v + 1]; q++)
            if (ci[q] != v)
                tp[ci[q] + 2]++;
    for (uint32_t v = 0; v < n; v++)
        tp[v + 2] += tp[v + 1];
    for (uint32_t v = 0; v < n; v++)
        for (uint32_t q = rp[v]; q < rp[v + 1]; q++)
            if (ci[q] != v)
                ti[tp[ci[q] + 1]++] = v;
    /* tp[u] .. tp[u+1]: the rows holding u, ascending */
    for (uint32_t u = 0; u < n; u++)
        for (uint32_t q = tp[u]; q < tp[u + 1]; q++)
            sp[ti[q] + 2]++;
    for (uint32_t v = 0; v < n; v++)
        sp[v + 2] += sp[v + 1];
    for (uint32_t u = 0; u < n; u++)
        for (uint32_t q = tp[u]; q < tp[u + 1]; q++)
            si[sp[ti[q] + 1]++] = u;
    /* sp[v] .. sp[v+1]: row v ascending; the union with its column */
    uint32_t m = 0;
    for (uint32_t v = 0; v < n; v++) {
        gp[v] = m;
        uint32_t i = sp[v], j = tp[v], ie = sp[v + 1], je = tp[v + 1];
        while (i < ie || j < je) {
            uint32_t x = j >= je || (i < ie && si[i] < ti[j]) ? si[i++]
                         : i < ie && si[i] == ti[j]          ? (j++, si[i++])
                                                             : ti[j++];
            if (m == gp[v] || gi[m - 1] != x) /* repeated in a row */
                gi[m++] = x;
        }
    }
    gp[n] = m;
    *ret_p = gp, *ret_i = gi;
    gp = gi = NULL;
    rc = 0;
out:
    free(tp), free(ti), free(sp), free(si), free(gp), free(gi);
    return rc;
}

/* Closed neighbourhoods of v and u equal (v ≠ u, each in the other's
 * row): the rows are equal but for v in u's and u in v's. */
static bool md_twins(const uint32_t *gp, const uint32_t *gi, uint32_t u,
                     uint32_t v)
{
    uint32_t i = gp[u], j = gp[v];
    while (i < gp[u + 1] || j < gp[v + 1]) {
        if (i < gp[u + 1] && gi[i] == v) {
            i++;
            continue;
        }
        if (j < gp[v + 1] && gi[j] == u) {
            j++;
            continue;
        }
        if (i == gp[u + 1] || j == gp[v + 1] || gi[i] != gi[j])
            return false;
        i++, j++;
    }
    return true;
}

/* perm: the elimination order. 0, -ERANGE (L would exceed max_nnz
 * entries, max_nnz > 0), -ENOMEM or -ECANCELED. */
static int md_order(uint32_t n, const uint32_t *rp, const uint32_t *ci,
                    uint64_t max_nnz, const geo_ctx *ctx, uint32_t *perm)
{
    md_work M = {0};
    uint32_t *gp = NULL, *gi = NULL, *node = NULL, *nextu = NULL;
    uint64_t *hk = NULL;
    uint32_t nn = 0; /* nodes */
    size_t sz = (size_t)n + 1;
    int rc = md_graph(n, rp, ci, &gp, &gi);
    if (rc < 0)
        return rc;
    rc = -ENOMEM;
    node = malloc(sz * sizeof *node);   /* unknown → its node */
    nextu = malloc(sz * sizeof *nextu); /* next unknown of its node */
    hk = malloc(sz * sizeof *hk);
    if (!node || !nextu || !hk)
        goto out;
    /* supervariables: equal closed rows, found among equal hashes */
    for (uint32_t v = 0; v < n; v++) {
        uint32_t h = v * 2654435761u;
        for (uint32_t q = gp[v]; q < gp[v + 1]; q++)
            h += gi[q] * 2654435761u;
        hk[v] = (uint64_t)h << 32 | v;
        node[v] = NONE;
    }
    qsort(hk, n, sizeof *hk, cmp_u64);
    for (uint32_t a = 0, b; a < n; a = b) {
        for (b = a + 1; b < n && hk[b] >> 32 == hk[a] >> 32; b++)
            ;
        for (uint32_t i = a; i < b; i++) {
            uint32_t u = (uint32_t)hk[i];
            if (node[u] != NONE)
                continue;
            node[u] = nn++;
            for (uint32_t j = i + 1; j < b; j++) {
                uint32_t v = (uint32_t)hk[j];
                if (node[v] == NONE &&
                    gp[u + 1] - gp[u] == gp[v + 1] - gp[v] &&
                    md_twins(gp, gi, u, v))
                    node[v] = node[u];
            }
        }
    }
    M.adj = calloc((size_t)nn + 1, sizeof *M.adj);
    M.len = calloc((size_t)nn + 1, sizeof *M.len);
    M.cap = calloc((size_t)nn + 1, sizeof *M.cap);
    M.head = malloc(sz * sizeof *M.head);
    M.next = malloc(((size_t)nn + 1) * sizeof *M.next);
    M.prev = malloc(((size_t)nn + 1) * sizeof *M.prev);
    M.deg = malloc(((size_t)nn + 1) * sizeof *M.deg);
    M.w = calloc((size_t)nn + 1, sizeof *M.w);
    M.first = malloc(((size_t)nn + 1) * sizeof *M.first);
    M.buf = malloc(((size_t)nn + 1) * sizeof *M.buf);
    if (!M.adj || !M.len || !M.cap || !M.head || !M.next || !M.prev ||
        !M.deg || !M.w || !M.first || !M.buf)
        goto out;
    for (uint32_t v = n; v-- > 0;) { /* members ascending */
        uint32_t s = node[v];
        nextu[v] = M.w[s] ? M.first[s] : NONE;
        M.first[s] = v;
        M.w[s]++;
    }
    /* a node's neighbours: its first unknown's, as nodes, ascending
     * (nodes taken in order, each appended to its neighbours' lists) */
    for (uint32_t s = 0; s < nn; s++) {
        uint32_t u = M.first[s];
        for (uint32_t q = gp[u]; q < gp[u + 1]; q++)
            if (node[gi[q]] != s)
                M.cap[node[gi[q]]]++;
    }
    for (uint32_t s = 0; s < nn; s++)
        if (!(M.adj[s] = malloc(((size_t)M.cap[s] + 1) * sizeof **M.adj)))
            goto out;
    for (uint32_t s = 0; s < nn; s++) {
        uint32_t u = M.first[s];
        for (uint32_t q = gp[u]; q < gp[u + 1]; q++) {
            uint32_t t = node[gi[q]];
            if (t != s && (M.len[t] == 0 || M.adj[t][M.len[t] - 1] != s))
                M.adj[t][M.len[t]++] = s;
        }
    }
    for (uint32_t d = 0; d <= n; d++)
        M.head[d] = NONE;
    for (uint32_t s = nn; s-- > 0;) {
        uint32_t d = M.w[s] - 1;
        for (uint32_t i = 0; i < M.len[s]; i++)
            d += M.w[M.adj[s][i]];
        M.deg[s] = d;
        md_link(&M, s);
    }
    /* the quotient graph: a node is a variable (its variables in adj,
     * its elements in el), an element (an eliminated node: the
     * variables of its clique in adj, their weight in lw) or absorbed */
    M.el = calloc((size_t)nn + 1, sizeof *M.el);
    M.elen = calloc((size_t)nn + 1, sizeof *M.elen);
    M.ecap = calloc((size_t)nn + 1, sizeof *M.ecap);
    M.ext = malloc(((size_t)nn + 1) * sizeof *M.ext);
    M.lw = calloc((size_t)nn + 1, sizeof *M.lw);
    M.wv = calloc((size_t)nn + 1, sizeof *M.wv);
    M.mark = calloc((size_t)nn + 1, sizeof *M.mark);
    M.wmark = calloc((size_t)nn + 1, sizeof *M.wmark);
    M.state = calloc((size_t)nn + 1, 1);
    if (!M.el || !M.elen || !M.ecap || !M.ext || !M.lw || !M.wv ||
        !M.mark || !M.wmark || !M.state)
        goto out;
    for (uint32_t s = 0; s < nn; s++)
        M.ext[s] = M.deg[s] + 1 - M.w[s];
    uint64_t nnz = 0;
    uint32_t mindeg = 0, k = 0, stamp = 0;
    for (uint32_t it = 0; it < nn; it++) {
        if ((it & 4095) == 4095 && geo_ctx_canceled(ctx)) {
            rc = -ECANCELED;
            goto out;
        }
        while (M.head[mindeg] == NONE)
            mindeg++;
        uint32_t p = M.head[mindeg];
        md_unlink(&M, p);
        stamp++;
        /* its clique: its variables and those of its elements, which
         * it absorbs */
        M.mark[p] = stamp;
        uint32_t m = 0, degp = 0;
        for (uint32_t a = 0; a < M.elen[p]; a++) {
            uint32_t e = M.el[p][a];
            if (M.state[e] != MD_ELEMENT)
                continue;
            md_gather(&M, e, stamp, &m, &degp);
            md_absorb(&M, e);
        }
        md_gather(&M, p, stamp, &m, &degp);
        free(M.el[p]);
        M.el[p] = NULL;
        M.elen[p] = 0;
        if (m > M.cap[p]) {
            uint32_t *t = realloc(M.adj[p], (size_t)m * sizeof *t);
            if (!t)
                goto out;
            M.adj[p] = t;
            M.cap[p] = m;
        }
        memcpy(M.adj[p], M.buf, (size_t)m * sizeof *M.buf);
        M.len[p] = m;
        M.lw[p] = degp;
        M.state[p] = MD_ELEMENT;
        /* its unknowns' columns: the later ones of p and the clique */
        uint64_t wp = M.w[p];
        nnz += wp * degp + wp * (wp + 1) / 2;
        if (max_nnz && nnz > max_nnz) {
            rc = -ERANGE;
            goto out;
        }
        for (uint32_t u = M.first[p]; u != NONE; u = nextu[u])
            perm[k++] = u;
        uint32_t left = n - k;
        /* |L_e \ L_p| for the other elements of the clique's variables */
        for (uint32_t a = 0; a < m; a++) {
            uint32_t i = M.adj[p][a];
            for (uint32_t q = 0; q < M.elen[i]; q++) {
                uint32_t e = M.el[i][q];
                if (M.state[e] != MD_ELEMENT)
                    continue;
                if (M.wmark[e] != stamp) {
                    M.wmark[e] = stamp;
                    M.wv[e] = M.lw[e];
                }
                M.wv[e] -= M.w[i];
            }
        }
        /* each variable of the clique: its elements (those wholly in the
         * clique absorbed) and p, its variables outside the clique, and
         * its approximate external degree (Amestoy, Davis and Duff) */
        for (uint32_t a = 0; a < m; a++) {
            uint32_t i = M.adj[p][a], ne = 0, na = 0;
            uint64_t d = 0;
            for (uint32_t q = 0; q < M.elen[i]; q++) {
                uint32_t e = M.el[i][q];
                if (M.state[e] != MD_ELEMENT)
                    continue;
                if (M.wv[e] == 0) { /* L_e ⊆ L_p */
                    md_absorb(&M, e);
                    continue;
                }
                d += M.wv[e];
                M.el[i][ne++] = e;
            }
            if (ne == M.ecap[i]) {
                uint32_t c = ne + ne / 2 + 4;
                uint32_t *t = realloc(M.el[i], (size_t)c * sizeof *t);
                if (!t)
                    goto out;
                M.el[i] = t;
                M.ecap[i] = c;
            }
            M.el[i][ne++] = p;
            M.elen[i] = ne;
            for (uint32_t q = 0; q < M.len[i]; q++) {
                uint32_t v = M.adj[i][q];
                if (M.state[v] == MD_VARIABLE && M.mark[v] != stamp &&
                    v != i) {
                    M.adj[i][na++] = v;
                    d += M.w[v];
                }
            }
            M.len[i] = na;
            d += degp - M.w[i];
            uint64_t bound = (uint64_t)M.ext[i] + degp - M.w[i];
            if (bound < d)
                d = bound;
            if (left - M.w[i] < d)
                d = left - M.w[i];
            M.ext[i] = (uint32_t)d;
            md_unlink(&M, i);
            M.deg[i] = (uint32_t)d + M.w[i] - 1;
            md_link(&M, i);
            if (M.deg[i] < mindeg)
                mindeg = M.deg[i];
        }
    }
    rc = 0;
out:
    if (M.adj)
        for (uint32_t s = 0; s < nn; s++)
            free(M.adj[s]);
    if (M.el)
        for (uint32_t s = 0; s < nn; s++)
            free(M.el[s]);
    free(M.adj), free(M.len), free(M.cap), free(M.head), free(M.next);
    free(M.prev), free(M.deg), free(M.w), free(M.first), free(M.buf);
    free(M.el), free(M.elen), free(M.ecap), free(M.ext), free(M.lw);
    free(M.wv), free(M.wmark), free(M.mark), free(M.state);
    free(gp), free(gi), free(node), free(nextu), free(hk);
    return rc;
}

/* ---- factorisation ---- */

/* Pattern of row k of L (columns < k) in s[top .. n), topologically
 * ordered; w marks visited columns with stamp. Returns top. */
static uint32_t ereach(const uint64_t *Cp, const uint32_t *Ci, uint32_t k,
                       const uint32_t *parent, uint32_t *s, uint32_t *w,
                       uint32_t stamp, uint32_t n)
{
    uint32_t top = n;
    w[k] = stamp;
    for (uint64_t p = Cp[k]; p < Cp[k + 1]; p++) {
        uint32_t i = Ci[p], len = 0;
        if (i > k)
            continue;
        for (; w[i] != stamp; i = parent[i]) {
            s[len++] = i;
            w[i] = stamp;
        }
        while (len > 0)
            s[--top] = s[--len];
    }
    return top;
}

geo_spchol *geo_spchol_free(geo_spchol *f)
{
    if (f) {
        free(f->perm), free(f->Lp), free(f->Li), free(f->Lx);
        free(f->Cp), free(f->Ci), free(f->cmap), free(f->parent);
        free(f->arp), free(f->aci);
        free(f);
    }
    return NULL;
}

uint64_t geo_spchol_nnz(const geo_spchol *f)
{
    return f->Lp[f->n];
}

/* The numeric factorisation of f's symbolic part with A's values v:
 * 0, -EDOM (not positive definite), -ENOMEM or -ECANCELED. */
static int numeric(geo_spchol *f, const double *v, const geo_ctx *ctx)
{
    uint32_t n = f->n;
    uint32_t *s = malloc(((size_t)n + 1) * sizeof *s);
    uint32_t *w = calloc((size_t)n + 1, sizeof *w);
    uint64_t *next = malloc(((size_t)n + 1) * sizeof *next);
    double *x = calloc((size_t)n + 1, sizeof *x);
    int rc = -ENOMEM;
    if (!s || !w || !next || !x)
        goto out;
    for (uint32_t k = 0; k < n; k++)
        next[k] = f->Lp[k];
    for (uint32_t k = 0; k < n; k++) {
        if ((k & 4095) == 4095 && geo_ctx_canceled(ctx)) {
            rc = -ECANCELED;
            goto out;
        }
        uint32_t top = ereach(f->Cp, f->Ci, k, f->parent, s, w, k + 1, n);
        for (uint64_t p = f->Cp[k]; p < f->Cp[k + 1]; p++)
            x[f->Ci[p]] = v[f->cmap[p]];
        double d = x[k];
        x[k] = 0;
        for (; top < n; top++) {
            uint32_t i = s[top];
            double lki = x[i] / f->Lx[f->Lp[i]];
            x[i] = 0;
            for (uint64_t p = f->Lp[i] + 1; p < next[i]; p++)
                x[f->Li[p]] -= f->Lx[p] * lki;
            d -= lki * lki;
            uint64_t p = next[i]++;
            f->Li[p] = k;
            f->Lx[p] = lki;
        }
        if (!(d > 0)) {
            rc = -EDOM;
            goto out;
        }
        uint64_t p = next[k]++;
        f->Li[p] = k;
        f->Lx[p] = sqrt(d);
    }
    rc = 0;
out:
    free(s), free(w), free(next), free(x);
    return rc;
}

int geo_spchol_factor(uint32_t n, const uint32_t *rp, const uint32_t *ci,
                      const double *v, geo_spchol_order order,
                      uint64_t max_nnz, const geo_ctx *ctx, geo_spchol **ret)
{
    *ret = NULL;
    for (uint64_t q = 0; q < (n ? rp[n] : 0); q++)
        if (ci[q] >= n)
            return -EINVAL;
    geo_spchol *f = calloc(1, sizeof *f);
    uint32_t *pinv = malloc(((size_t)n + 1) * sizeof *pinv);
    uint32_t *s = NULL, *w = NULL;
    uint64_t *next = NULL;
    int rc = -ENOMEM;
    if (!f || !pinv)
        goto out;
    f->n = n;
    f->perm = malloc(((size_t)n + 1) * sizeof *f->perm);
    f->Lp = malloc(((size_t)n + 1) * sizeof *f->Lp);
    f->Cp = malloc(((size_t)n + 2) * sizeof *f->Cp);
    f->arp = malloc(((size_t)n + 1) * sizeof *f->arp);
    f->aci = malloc(((size_t)(n ? rp[n] : 0) + 1) * sizeof *f->aci);
    if (!f->perm || !f->Lp || !f->Cp || !f->arp || !f->aci)
        goto out;
    if ((rc = order == GEO_SPCHOL_MIN_DEGREE
                  ? md_order(n, rp, ci, max_nnz, ctx, f->perm)
                  : nd_order(n, rp, ci, f->perm)) < 0)
        goto out;
    rc = -ENOMEM;
    memcpy(f->arp, rp, ((size_t)n + 1) * sizeof *rp);
    memcpy(f->aci, ci, (size_t)(n ? rp[n] : 0) * sizeof *ci);
    for (uint32_t k = 0; k < n; k++)
        pinv[f->perm[k]] = k;
    /* C = P·A·P', its upper triangle by columns */
    uint64_t *Cp = f->Cp;
    Cp[0] = 0;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t r = f->perm[k], c = 0;
        for (uint32_t q = rp[r]; q < rp[r + 1]; q++)
            c += pinv[ci[q]] <= k;
        Cp[k + 1] = Cp[k] + c;
    }
    f->Ci = malloc((Cp[n] + 1) * sizeof *f->Ci);
    f->cmap = malloc((Cp[n] + 1) * sizeof *f->cmap);
    f->parent = malloc(((size_t)n + 1) * sizeof *f->parent);
    s = malloc(((size_t)n + 1) * sizeof *s);
    w = calloc((size_t)n + 1, sizeof *w);
    next = malloc(((size_t)n + 1) * sizeof *next);
    if (!f->Ci || !f->cmap || !f->parent || !s || !w || !next)
        goto out;
    uint32_t *Ci = f->Ci, *parent = f->parent;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t r = f->perm[k];
        uint64_t p = Cp[k];
        for (uint32_t q = rp[r]; q < rp[r + 1]; q++)
            if (pinv[ci[q]] <= k) {
                Ci[p] = pinv[ci[q]];
                f->cmap[p++] = q;
            }
    }
    /* elimination tree (with path compression through next[]) */
    for (uint32_t k = 0; k < n; k++) {
        parent[k] = NONE;
        next[k] = NONE;
        for (uint64_t p = Cp[k]; p < Cp[k + 1]; p++)
            for (uint32_t i = Ci[p]; i != NONE && i < k;) {
                uint32_t inext = (uint32_t)next[i];
                next[i] = k;
                if (inext == NONE)
                    parent[i] = k;
                i = inext;
            }
    }
    /* column counts: row k of L has the pattern ereach finds */
    memset(next, 0, ((size_t)n + 1) * sizeof *next);
    for (uint32_t k = 0; k < n; k++) {
        uint32_t top = ereach(Cp, Ci, k, parent, s, w, k + 1, n);
        for (uint32_t q = top; q < n; q++)
            next[s[q]]++;
        next[k]++;
    }
    f->Lp[0] = 0;
    for (uint32_t k = 0; k < n; k++)
        f->Lp[k + 1] = f->Lp[k] + next[k];
    if (max_nnz && f->Lp[n] > max_nnz) {
        rc = -ERANGE;
        goto out;
    }
    f->Li = malloc((f->Lp[n] + 1) * sizeof *f->Li);
    f->Lx = malloc((f->Lp[n] + 1) * sizeof *f->Lx);
    if (!f->Li || !f->Lx)
        goto out;
    if ((rc = numeric(f, v, ctx)) < 0)
        goto out;
    *ret = f;
    f = NULL;
    rc = 0;
out:
    geo_spchol_free(f);
    free(pinv), free(s), free(w), free(next);
    return rc;
}

int geo_spchol_refactor(geo_spchol *f, uint32_t n, const uint32_t *rp,
                        const uint32_t *ci, const double *v,
                        const geo_ctx *ctx)
{
    if (n != f->n ||
        memcmp(rp, f->arp, ((size_t)n + 1) * sizeof *rp) != 0 ||
        memcmp(ci, f->aci, (size_t)(n ? rp[n] : 0) * sizeof *ci) != 0)
        return -EINVAL;
    return numeric(f, v, ctx);
}

int geo_spchol_solve3(const geo_spchol *f, double (*b)[3])
{
    uint32_t n = f->n;
    double(*y)[3] = malloc(((size_t)n + 1) * sizeof *y);
    if (!y)
        return -ENOMEM;
    for (uint32_t k = 0; k < n; k++)
        memcpy(y[k], b[f->perm[k]], sizeof y[k]);
    for (uint32_t j = 0; j < n; j++) {
        double dj = f->Lx[f->Lp[j]];
        for (int c = 0; c < 3; c++)
            y[j][c] /= dj;
        for (uint64_t p = f->Lp[j] + 1; p < f->Lp[j + 1]; p++) {
            double l = f->Lx[p];
            double *yi = y[f->Li[p]];
            for (int c = 0; c < 3; c++)
                yi[c] -= l * y[j][c];
        }
    }
    for (uint32_t j = n; j-- > 0;) {
        for (uint64_t p = f->Lp[j] + 1; p < f->Lp[j + 1]; p++) {
            double l = f->Lx[p];
            const double *yi = y[f->Li[p]];
            for (int c = 0; c < 3; c++)
                y[j][c] -= l * yi[c];
        }
        double dj = f->Lx[f->Lp[j]];
        for (int c = 0; c < 3; c++)
            y[j][c] /= dj;
    }
    for (uint32_t k = 0; k < n; k++)
        memcpy(b[f->perm[k]], y[k], sizeof y[k]);
    free(y);
    return 0;
}
