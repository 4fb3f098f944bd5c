/* halfspace.c — exact half-space intersection by incremental clipping.
 *
 * The region starts as a box far larger than the planes' offsets (six
 * extra planes after the n given ones) and is clipped by one plane after
 * another. The state is purely combinatorial: a vertex is a triple of
 * plane indices, a face is the cycle of its vertices with, for each edge,
 * the face across it (its label). Clipping by plane l decides the side of
 * the vertices of the faces l reaches exactly (geo_plane_meet_sign,
 * through the vertex's prepared cofactors: geo_meet_side; the faces are
 * found from one vertex outside, see clip), keeps the vertices on the
 * inner side or on l, creates one vertex (f, g, l) on each edge between
 * faces f and g whose ends lie strictly on opposite sides, and builds l's
 * face from the edges on l of the faces that survive. Invariant after
 * each plane: the faces form a closed convex polyhedron whose vertices
 * are distinct points; no vertex is ever created where one exists, so
 * coincident vertices cannot arise. Coordinates are computed once at the
 * end. */
#include "halfspace.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "predicates.h"
#include "uf.h"

#define HS_NONE UINT32_MAX

typedef struct hs_face {
    uint32_t *v;   /* vertex ids, counter-clockwise seen from outside */
    uint32_t *lab; /* lab[k]: the face across edge v[k] → v[k+1] */
    uint32_t n, cap;
    bool alive;
} hs_face;

typedef struct hs {
    const double (*pl)[4]; /* n + 6 planes: the given ones, then the box */
    uint32_t np;
    hs_face *face;          /* np faces, indexed by plane */
    uint32_t (*vert)[3];    /* vertex id → its three planes */
    geo_meet *meet;         /* vertex id → its point, for the sides */
    uint32_t nv, cap_v;
    int8_t *sign;           /* per vertex: side of the current plane */
    uint32_t *stamp;        /* per vertex: the round sign was set in */
    uint32_t *chain;        /* per vertex: edge of the new face from it */
    uint32_t round;         /* the current plane's round, from 1 */
    uint32_t *alive;        /* ids of the live faces */
    uint32_t nalive;
    uint32_t *apos;         /* per face: its index in alive */
    uint32_t *fmark;        /* per face: the round it was reached in */
    uint32_t *vis;          /* the faces a round clips, in alive order */
    double (*unit)[3];      /* per plane: its unit normal */
    /* crossing vertices of the current round, by edge (open addressing) */
    uint64_t *hkey;
    uint32_t *hval;
    uint32_t *hused; /* the slots filled this round, to empty them */
    uint32_t hcap, nused;
    /* scratch for the new face's edges: from, to, label */
    uint32_t (*edges)[3];
    uint32_t nedges, cap_edges;
} hs;

static int grow(void **p, uint32_t *cap, uint32_t need, size_t elem)
{
    if (need <= *cap)
        return 0;
    uint32_t c = *cap ? *cap : 16;
    while (c < need) {
        if (c > UINT32_MAX / 2)
            return -ENOMEM;
        c *= 2;
    }
    void *q = realloc(*p, (size_t)c * elem);
    if (!q)
        return -ENOMEM;
    *p = q;
    *cap = c;
    return 0;
}

static int add_vertex(hs *h, uint32_t a, uint32_t b, uint32_t c,
                      uint32_t *ret)
{
    if (h->nv == UINT32_MAX - 1)
        return -ENOMEM;
    if (h->nv == h->cap_v) {
        uint32_t old = h->cap_v, cap = old;
        void *v = h->vert;
        if (grow(&v, &cap, h->nv + 1, sizeof *h->vert) < 0)
            return -ENOMEM;
        h->vert = v;
        int8_t *s = realloc(h->sign, cap);
        if (!s)
            return -ENOMEM;
        h->sign = s;
        uint32_t *st = realloc(h->stamp, (size_t)cap * sizeof *st);
        if (!st)
            return -ENOMEM;
        h->stamp = st;
        uint32_t *ch = realloc(h->chain, (size_t)cap * sizeof *ch);
        if (!ch)
            return -ENOMEM;
        h->chain = ch;
        geo_meet *mt = realloc(h->meet, (size_t)cap * sizeof *mt);
        if (!mt)
            return -ENOMEM;
        h->meet = mt;
        memset(h->stamp + old, 0, (size_t)(cap - old) * sizeof *h->stamp);
        h->cap_v = cap;
    }
    uint32_t id = h->nv++;
    h->vert[id][0] = a, h->vert[id][1] = b, h->vert[id][2] = c;
    geo_meet_prepare(h->pl[a], h->pl[b], h->pl[c], &h->meet[id]);
    *ret = id;
    return 0;
}

static int face_push(hs_face *f, uint32_t v, uint32_t lab)
{
    if (f->n == f->cap) {
        uint32_t cap = f->cap ? f->cap * 2 : 8;
        uint32_t *a = realloc(f->v, (size_t)cap * sizeof *a);
        if (!a)
            return -ENOMEM;
        f->v = a;
        uint32_t *b = realloc(f->lab, (size_t)cap * sizeof *b);
        if (!b)
            return -ENOMEM;
        f->lab = b;
        f->cap = cap;
    }
    f->v[f->n] = v;
    f->lab[f->n] = lab;
    f->n++;
    return 0;
}

static void face_free(hs_face *f)
{
    free(f->v);
    free(f->lab);
    memset(f, 0, sizeof *f);
}

/* The box as planes np−6 .. np−1 (+x, −x, +y, −y, +z, −z): 8 vertices
 * (bit 0, 1, 2 of a vertex's number: the + side in x, y, z) and 6 faces;
 * the face across each edge is found by its reversed edge. */
static int init_box(hs *h)
{
    uint32_t b = h->np - 6;
    for (uint32_t i = 0; i < 8; i++) {
        uint32_t id;
        if (add_vertex(h, b + ((i & 1) ? 0 : 1), b + ((i & 2) ? 2 : 3),
                       b + ((i & 4) ? 4 : 5), &id) < 0)
            return -ENOMEM;
    }
    static const uint32_t cyc[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2},
                                       {2, 6, 7, 3}, {0, 1, 5, 4},
                                       {4, 5, 7, 6}, {0, 2, 3, 1}};
    for (uint32_t f = 0; f < 6; f++) {
        for (uint32_t k = 0; k < 4; k++) {
            uint32_t a = cyc[f][k], c = cyc[f][(k + 1) % 4], across = 0;
            for (uint32_t g = 0; g < 6; g++)
                for (uint32_t j = 0; j < 4; j++)
                    if (cyc[g][j] == c && cyc[g][(j + 1) % 4] == a)
                        across = g;
            if (face_push(&h->face[b + f], a, b + across) < 0)
                return -ENOMEM;
        }
        h->face[b + f].alive = true;
        h->apos[b + f] = h->nalive;
        h->alive[h->nalive++] = b + f;
    }
    return 0;
}

static int vertex_side(const hs *h, uint32_t v, uint32_t l)
{
    return geo_meet_side(&h->meet[v], h->pl[l]);
}

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a);
}

/* The crossing vertex on edge a–b (between faces f and g) for plane l:
 * found if the face across made it already, else created. */
static int crossing(hs *h, uint32_t a, uint32_t b, uint32_t f, uint32_t g,
                    uint32_t l, uint32_t *ret)
{
    uint64_t key = edge_key(a, b) + 1; /* 0 marks an empty slot */
    uint32_t m = h->hcap - 1;
    uint32_t i = (uint32_t)((key * 0x9e3779b97f4a7c15ull) >> 32) & m;
    while (h->hkey[i] && h->hkey[i] != key)
        i = (i + 1) & m;
    if (h->hkey[i]) {
        *ret = h->hval[i];
        return 0;
    }
    if (add_vertex(h, f, g, l, ret) < 0)
        return -ENOMEM;
    h->sign[*ret] = 0; /* it lies on l by construction */
    h->stamp[*ret] = h->round;
    h->hkey[i] = key;
    h->hval[i] = *ret;
    h->hused[h->nused++] = i;
    return 0;
}

/* Face f clipped by plane l into out (labels as in hs_face; an edge both
 * of whose ends lie on l gets label l). Its edges on l are appended,
 * reversed, to h->edges for l's face. */
static int clip_face(hs *h, uint32_t f, uint32_t l, hs_face *out)
{
    hs_face *src = &h->face[f];
    out->n = 0;
    for (uint32_t k = 0; k < src->n; k++) {
        uint32_t a = src->v[k], b = src->v[(k + 1) % src->n];
        int sa = h->sign[a], sb = h->sign[b];
        if (sa <= 0 && face_push(out, a, src->lab[k]) < 0)
            return -ENOMEM;
        if (sa * sb < 0) {
            uint32_t x;
            if (crossing(h, a, b, f, src->lab[k], l, &x) < 0 ||
                face_push(out, x, src->lab[k]) < 0)
                return -ENOMEM;
        }
    }
    /* a vertex is on l when its sign is 0 or it was made this round */
    for (uint32_t k = 0; k < out->n; k++) {
        uint32_t a = out->v[k], b = out->v[(k + 1) % out->n];
        if (h->sign[a] != 0 || h->sign[b] != 0)
            continue;
        out->lab[k] = l;
        void *e = h->edges;
        if (grow(&e, &h->cap_edges, h->nedges + 1, sizeof *h->edges) < 0)
            return -ENOMEM;
        h->edges = e;
        h->edges[h->nedges][0] = b;
        h->edges[h->nedges][1] = a;
        h->edges[h->nedges][2] = f;
        h->nedges++;
    }
    return 0;
}

/* Plane l's approximate value at vertex v: det[a; b; c; q] = Σ q_j cof_j
 * vanishes for q through the point, so cof is the point in homogeneous
 * coordinates. It only guides the walk; every side is the exact one. */
static double approx_value(const hs *h, uint32_t v, const double *q)
{
    const double *c = h->meet[v].cof;
    return (q[0] * c[0] + q[1] * c[1] + q[2] * c[2] + q[3] * c[3]) / c[3];
}

/* The corner of face f where q is highest, approximately, and its value. */
static void highest_corner(const hs *h, uint32_t f, const double *q,
                           uint32_t *ret_k, double *ret_val)
{
    const hs_face *F = &h->face[f];
    uint32_t bk = 0;
    double bv = -INFINITY;
    for (uint32_t k = 0; k < F->n; k++) {
        double v = approx_value(h, F->v[k], q);
        if (v > bv)
            bv = v, bk = k;
    }
    *ret_k = bk;
    *ret_val = bv;
}

static void set_sign(hs *h, uint32_t v, uint32_t l)
{
    if (h->stamp[v] != h->round) {
        h->stamp[v] = h->round;
        h->sign[v] = (int8_t)vertex_side(h, v, l);
    }
}

/* A face through a vertex strictly outside l, or NONE: from the live
 * face whose normal is nearest l's, up the faces across the edges at the
 * highest corner while that corner rises (a linear function on a convex
 * polyhedron has no other local maximum). NONE sends the caller to the
 * full search, so a walk misled by rounding costs time, never a vertex. */
static uint32_t walk_outside(hs *h, uint32_t l)
{
    const double *q = h->pl[l], *u = h->unit[l];
    uint32_t F = HS_NONE;
    double near = -INFINITY;
    for (uint32_t i = 0; i < h->nalive; i++) {
        const double *w = h->unit[h->alive[i]];
        double c = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
        if (c > near)
            near = c, F = h->alive[i];
    }
    if (F == HS_NONE)
        return HS_NONE;
    uint32_t bk;
    double bv;
    highest_corner(h, F, q, &bk, &bv);
    for (uint32_t step = 0; step < h->nalive; step++) {
        const hs_face *f = &h->face[F];
        uint32_t across[2] = {f->lab[bk], f->lab[(bk + f->n - 1) % f->n]};
        uint32_t G = HS_NONE, gk = 0;
        double gv = bv;
        for (int s = 0; s < 2; s++) {
            uint32_t k;
            double v;
            highest_corner(h, across[s], q, &k, &v);
            if (v > gv)
                gv = v, gk = k, G = across[s];
        }
        if (G == HS_NONE)
            break;
        F = G, bk = gk, bv = gv;
    }
    uint32_t b = h->face[F].v[bk];
    set_sign(h, b, l);
    return h->sign[b] > 0 ? F : HS_NONE;
}

/* Clips the polyhedron by plane l. *ret_status is set to EMPTY when
 * nothing of the interior is left.
 *
 * The faces l changes are found from one vertex outside it: the vertices
 * strictly outside a plane span a connected part of a convex
 * polyhedron's edge graph, and every vertex on l is next to one of them,
 * so crossing every edge with an end not strictly inside reaches each
 * face with a vertex outside or an edge on l; the others stay as they
 * are. The faces reached are clipped in the order of the live list, as a
 * search of every face would, so the result is the same, vertex
 * numbering and cycles included. When the walk finds no vertex outside,
 * every vertex is tested. */
static int clip(hs *h, uint32_t l, enum geo_halfspace_status *ret_status)
{
    h->round++;
    uint32_t start = walk_outside(h, l), nvis = 0, ncorners = 0;
    bool pos = false, neg = false;
    if (start != HS_NONE) {
        pos = true;
        h->fmark[start] = h->round;
        h->vis[nvis++] = start;
        for (uint32_t i = 0; i < nvis; i++) {
            const hs_face *f = &h->face[h->vis[i]];
            ncorners += f->n;
            for (uint32_t k = 0; k < f->n; k++) {
                set_sign(h, f->v[k], l);
                neg |= h->sign[f->v[k]] < 0;
            }
            for (uint32_t k = 0; k < f->n; k++) {
                uint32_t g = f->lab[k];
                if (h->fmark[g] == h->round ||
                    (h->sign[f->v[k]] < 0 &&
                     h->sign[f->v[(k + 1) % f->n]] < 0))
                    continue;
                h->fmark[g] = h->round;
                h->vis[nvis++] = g;
            }
        }
        /* an edge stopped the search: both its ends lie inside */
        neg |= nvis < h->nalive;
        /* in the order of the live list (few faces: insertion) */
        for (uint32_t i = 1; i < nvis; i++) {
            uint32_t f = h->vis[i], j = i;
            for (; j > 0 && h->apos[h->vis[j - 1]] > h->apos[f]; j--)
                h->vis[j] = h->vis[j - 1];
            h->vis[j] = f;
        }
    } else {
        for (uint32_t i = 0; i < h->nalive; i++) {
            const hs_face *f = &h->face[h->alive[i]];
            ncorners += f->n;
            for (uint32_t k = 0; k < f->n; k++) {
                set_sign(h, f->v[k], l);
                pos |= h->sign[f->v[k]] > 0;
                neg |= h->sign[f->v[k]] < 0;
            }
            h->vis[nvis++] = h->alive[i];
        }
    }
    if (!pos)
        return 0; /* l cuts nothing off: redundant, touching or a duplicate */
    if (!neg) {
        *ret_status = GEO_HALFSPACE_EMPTY;
        return -EINVAL;
    }
    uint32_t need = 1;
    while (need < 2 * ncorners)
        need *= 2;
    if (need > h->hcap) {
        uint64_t *k = realloc(h->hkey, (size_t)need * sizeof *k);
        if (!k)
            return -ENOMEM;
        h->hkey = k;
        uint32_t *v = realloc(h->hval, (size_t)need * sizeof *v);
        if (!v)
            return -ENOMEM;
        h->hval = v;
        uint32_t *u = realloc(h->hused, (size_t)need * sizeof *u);
        if (!u)
            return -ENOMEM;
        h->hused = u;
        h->hcap = need;
        memset(h->hkey, 0, (size_t)h->hcap * sizeof *h->hkey);
        h->nused = 0;
    }
    /* the table holds a round's few crossings: only their slots are
     * emptied, not the whole table for every plane */
    for (uint32_t i = 0; i < h->nused; i++)
        h->hkey[h->hused[i]] = 0;
    h->nused = 0;
    h->nedges = 0;

    hs_face tmp = {0};
    bool dropped = false;
    for (uint32_t i = 0; i < nvis; i++) {
        uint32_t fi = h->vis[i];
        hs_face *f = &h->face[fi];
        bool any_neg = false, all_neg = true;
        for (uint32_t k = 0; k < f->n; k++) {
            bool ng = h->sign[f->v[k]] < 0;
            any_neg |= ng;
            all_neg &= ng;
        }
        if (!any_neg) { /* what is left of f is at most an edge */
            face_free(f);
            dropped = true;
            continue;
        }
        if (all_neg) /* l does not touch f: clip_face would copy it */
            continue;
        if (clip_face(h, fi, l, &tmp) < 0) {
            face_free(&tmp);
            return -ENOMEM;
        }
        hs_face swap = *f;
        *f = tmp;
        f->alive = true;
        tmp = swap;
    }
    face_free(&tmp);
    uint32_t kept = h->nalive;
    if (dropped) {
        kept = 0;
        for (uint32_t i = 0; i < h->nalive; i++)
            if (h->face[h->alive[i]].alive) {
                h->apos[h->alive[i]] = kept;
                h->alive[kept++] = h->alive[i];
            }
    }

    /* l's face: the reversed edges on l, chained by their start vertex;
     * they form one cycle because the section of a convex polyhedron by a
     * plane through its interior is a convex polygon */
    for (uint32_t e = 0; e < h->nedges; e++)
        h->chain[h->edges[e][0]] = e;
    hs_face *nf = &h->face[l];
    uint32_t e = 0;
    for (uint32_t step = 0; step < h->nedges; step++) {
        if (face_push(nf, h->edges[e][0], h->edges[e][2]) < 0)
            return -ENOMEM;
        e = h->chain[h->edges[e][1]];
    }
    nf->alive = true;
    h->apos[l] = kept;
    h->alive[kept++] = l;
    h->nalive = kept;
    return 0;
}

static void unit_plane(const double in[4], double out[4])
{
    double len = sqrt(in[0] * in[0] + in[1] * in[1] + in[2] * in[2]);
    for (int k = 0; k < 4; k++)
        out[k] = in[k] / len;
}

/* The point where the three unit planes meet (Cramer's rule in long
 * double) and the magnitude of their determinant. */
static double meet(const double a[4], const double b[4], const double c[4],
                   double ret[3])
{
    long double bc[3] = {
        (long double)b[1] * c[2] - (long double)b[2] * c[1],
        (long double)b[2] * c[0] - (long double)b[0] * c[2],
        (long double)b[0] * c[1] - (long double)b[1] * c[0]};
    long double ca[3] = {
        (long double)c[1] * a[2] - (long double)c[2] * a[1],
        (long double)c[2] * a[0] - (long double)c[0] * a[2],
        (long double)c[0] * a[1] - (long double)c[1] * a[0]};
    long double ab[3] = {
        (long double)a[1] * b[2] - (long double)a[2] * b[1],
        (long double)a[2] * b[0] - (long double)a[0] * b[2],
        (long double)a[0] * b[1] - (long double)a[1] * b[0]};
    long double det = a[0] * bc[0] + a[1] * bc[1] + a[2] * bc[2];
    if (det == 0)
        return 0.0;
    for (int k = 0; k < 3; k++)
        ret[k] = (double)(-(a[3] * bc[k] + b[3] * ca[k] + c[3] * ab[k]) / det);
    return (double)fabsl(det);
}

/* The output in plain arrays: faces in plane order as CSR cycles of
 * dense vertex numbers. */
typedef struct hs_out {
    uint32_t nf, nv;
    uint32_t *src;    /* nf: input plane of each face */
    uint32_t *start;  /* nf + 1 */
    uint32_t *idx;    /* start[nf] vertex numbers */
    double (*x)[3];   /* nv positions */
} hs_out;

static void out_free(hs_out *o)
{
    free(o->src);
    free(o->start);
    free(o->idx);
    free(o->x);
    memset(o, 0, sizeof *o);
}

/* Places every vertex of o from the best conditioned triple of the unit
 * planes of the faces through it. */
static int place(hs_out *o, const double (*unit)[4])
{
    uint32_t nc = o->start[o->nf];
    uint32_t *deg = calloc((size_t)o->nv + 1, sizeof *deg);
    uint32_t *inc = malloc((size_t)(nc ? nc : 1) * sizeof *inc);
    double (*x)[3] = malloc((size_t)(o->nv ? o->nv : 1) * sizeof *x);
    if (!deg || !inc || !x) {
        free(deg), free(inc), free(x);
        return -ENOMEM;
    }
    for (uint32_t c = 0; c < nc; c++)
        deg[o->idx[c] + 1]++;
    for (uint32_t v = 0; v < o->nv; v++)
        deg[v + 1] += deg[v];
    for (uint32_t f = 0; f < o->nf; f++)
        for (uint32_t c = o->start[f]; c < o->start[f + 1]; c++)
            inc[deg[o->idx[c]]++] = o->src[f];
    /* deg[v] now ends v's incidences; they start at deg[v − 1] */
    for (uint32_t v = 0; v < o->nv; v++) {
        uint32_t lo = v ? deg[v - 1] : 0, hi = deg[v];
        double best = -1.0;
        x[v][0] = x[v][1] = x[v][2] = 0.0;
        for (uint32_t i = lo; i < hi; i++)
            for (uint32_t j = i + 1; j < hi; j++)
                for (uint32_t k = j + 1; k < hi; k++) {
                    double y[3];
                    double d = meet(unit[inc[i]], unit[inc[j]], unit[inc[k]],
                                    y);
                    if (d > best)
                        best = d, x[v][0] = y[0], x[v][1] = y[1],
                        x[v][2] = y[2];
                }
    }
    free(deg);
    free(inc);
    free(o->x);
    o->x = x;
    return 0;
}

/* Contracts the edges of o shorter than tol: the rounding of the input
 * planes (trigonometric normals of a symmetric design) turns a point where
 * four planes meet in exact geometry into two vertices some 1e-16 mm
 * apart, and those are one vertex to every user. Faces left with fewer
 * than three vertices vanish. When a contraction would make a face pass
 * twice through one vertex, nothing is merged. 1 when it merged, 0 when
 * not, or -ENOMEM. */
static int contract(hs_out *o, double tol)
{
    uint32_t nc = o->start[o->nf];
    uint32_t *up = malloc((size_t)(o->nv ? o->nv : 1) * sizeof *up);
    uint32_t *idx = malloc((size_t)(nc ? nc : 1) * sizeof *idx);
    uint32_t *start = malloc(((size_t)o->nf + 1) * sizeof *start);
    uint32_t *src = malloc((size_t)(o->nf ? o->nf : 1) * sizeof *src);
    uint32_t *seen = calloc((size_t)o->nv + 1, sizeof *seen);
    int rc = -ENOMEM;
    if (!up || !idx || !start || !src || !seen)
        goto out;
    bool any = false;
    for (uint32_t v = 0; v < o->nv; v++)
        up[v] = v;
    for (uint32_t f = 0; f < o->nf; f++) {
        uint32_t a0 = o->start[f], n = o->start[f + 1] - a0;
        for (uint32_t k = 0; k < n; k++) {
            uint32_t a = o->idx[a0 + k], b = o->idx[a0 + (k + 1) % n];
            double d2 = 0;
            for (int q = 0; q < 3; q++)
                d2 += (o->x[a][q] - o->x[b][q]) * (o->x[a][q] - o->x[b][q]);
            if (d2 <= tol * tol) {
                uint32_t ra = geo_uf_find(up, a), rb = geo_uf_find(up, b);
                if (ra != rb)
                    up[ra < rb ? rb : ra] = ra < rb ? ra : rb, any = true;
            }
        }
    }
    rc = 0;
    if (!any)
        goto out;
    uint32_t nf = 0, m = 0;
    start[0] = 0;
    for (uint32_t f = 0; f < o->nf; f++) {
        uint32_t a0 = o->start[f], n = o->start[f + 1] - a0, first = m;
        for (uint32_t k = 0; k < n; k++) {
            uint32_t r = geo_uf_find(up, o->idx[a0 + k]);
            if (m > first && idx[m - 1] == r)
                continue;
            idx[m++] = r;
        }
        while (m - first > 1 && idx[m - 1] == idx[first])
            m--;
        if (m - first < 3) {
            m = first;
            continue;
        }
        for (uint32_t c = first; c < m; c++) {
            if (seen[idx[c]] == f + 1)
                goto out; /* a face through one vertex twice: keep all */
            seen[idx[c]] = f + 1;
        }
        src[nf] = o->src[f];
        start[++nf] = m;
    }
    /* renumber the surviving roots densely by first use */
    for (uint32_t v = 0; v < o->nv; v++)
        seen[v] = UINT32_MAX;
    uint32_t nv = 0;
    for (uint32_t c = 0; c < m; c++) {
        if (seen[idx[c]] == UINT32_MAX)
            seen[idx[c]] = nv++;
        idx[c] = seen[idx[c]];
    }
    free(o->idx), free(o->start), free(o->src);
    o->idx = idx, o->start = start, o->src = src;
    idx = start = src = NULL;
    o->nf = nf, o->nv = nv;
    rc = 1;
out:
    free(up);
    free(idx);
    free(start);
    free(src);
    free(seen);
    return rc;
}

/* The output model: live faces in plane order, vertices numbered by first
 * use, each placed from the best conditioned triple of its faces; edges
 * shorter than merge_tol contracted. */
static int build(hs *h, uint32_t n, double merge_tol, geo_poly **ret,
                 uint32_t **ret_source)
{
    int rc = -ENOMEM;
    hs_out o = {0};
    uint32_t nc = 0;
    for (uint32_t f = 0; f < n; f++)
        if (h->face[f].alive)
            o.nf++, nc += h->face[f].n;
    uint32_t *map = malloc((size_t)h->nv * sizeof *map);
    double (*unit)[4] = malloc((size_t)(n ? n : 1) * sizeof *unit);
    o.src = malloc((size_t)(o.nf ? o.nf : 1) * sizeof *o.src);
    o.start = malloc(((size_t)o.nf + 1) * sizeof *o.start);
    o.idx = malloc((size_t)(nc ? nc : 1) * sizeof *o.idx);
    geo_poly *p = NULL;
    if (!map || !unit || !o.src || !o.start || !o.idx)
        goto out;
    for (uint32_t f = 0; f < n; f++)
        unit_plane(h->pl[f], unit[f]);
    for (uint32_t i = 0; i < h->nv; i++)
        map[i] = UINT32_MAX;
    uint32_t fi = 0, c = 0;
    o.start[0] = 0;
    for (uint32_t f = 0; f < n; f++) {
        const hs_face *F = &h->face[f];
        if (!F->alive)
            continue;
        for (uint32_t k = 0; k < F->n; k++) {
            if (map[F->v[k]] == UINT32_MAX)
                map[F->v[k]] = o.nv++;
            o.idx[c++] = map[F->v[k]];
        }
        o.src[fi] = f;
        o.start[++fi] = c;
    }
    if (place(&o, (const double (*)[4])unit) < 0)
        goto out;
    double lo[3] = {INFINITY, INFINITY, INFINITY};
    double hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; v < o.nv; v++)
        for (int k = 0; k < 3; k++)
            lo[k] = fmin(lo[k], o.x[v][k]), hi[k] = fmax(hi[k], o.x[v][k]);
    double size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) +
                       (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    double tol = merge_tol < 0 ? GEO_HALFSPACE_MERGE * (1.0 + size)
                               : merge_tol;
    int merged = tol > 0 ? contract(&o, tol) : 0;
    if (merged < 0 || (merged && place(&o, (const double (*)[4])unit) < 0))
        goto out;
    p = geo_poly_new();
    if (!p || geo_poly_reserve(p, o.nv, o.nf, o.start[o.nf]) < 0)
        goto out;
    for (uint32_t v = 0; v < o.nv; v++)
        if (geo_poly_add_vertex(p, o.x[v]) < 0)
            goto out;
    for (uint32_t f = 0; f < o.nf; f++) {
        int64_t id = geo_poly_add_facet(p, o.idx + o.start[f],
                                        o.start[f + 1] - o.start[f]);
        if (id < 0)
            goto out;
        memcpy(p->planes[id], unit[o.src[f]], sizeof p->planes[id]);
    }
    *ret = p;
    p = NULL;
    if (ret_source) {
        *ret_source = o.src;
        o.src = NULL;
    }
    rc = 0;
out:
    geo_poly_free(p);
    out_free(&o);
    free(map);
    free(unit);
    return rc;
}

static const char *const BOX_SIDE[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};

int geo_halfspace_intersect(const double *planes, uint32_t n,
                            double merge_tol, geo_poly **ret,
                            uint32_t **ret_source,
                            enum geo_halfspace_status *ret_status,
                            geo_err *err)
{
    enum geo_halfspace_status st = GEO_HALFSPACE_OK;
    if (n > UINT32_MAX - 6)
        return geo_err_set(err, -ENOMEM, "%u planes are too many", n);
    double reach = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        const double *q = planes + 4 * (size_t)i;
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        bool finite = isfinite(q[0]) && isfinite(q[1]) && isfinite(q[2]) &&
                      isfinite(q[3]);
        if (!finite || !(len > 0.0) || !isfinite(len)) {
            if (ret_status)
                *ret_status = GEO_HALFSPACE_BAD_PLANE;
            return geo_err_set(err, -EINVAL, "planes[%u]: %s", i,
                               finite ? "zero normal" : "not finite");
        }
        reach = fmax(reach, fabs(q[3]) / len);
    }
    /* the box: a power of two, so that its planes are exact and their
     * products with the given coefficients stay far from overflow */
    double r = ldexp(1.0, ilogb(1e6 * (1.0 + reach)) + 1);
    hs h = {0};
    h.np = n + 6;
    double (*pl)[4] = malloc((size_t)h.np * sizeof *pl);
    h.face = calloc(h.np, sizeof *h.face);
    h.alive = malloc((size_t)h.np * sizeof *h.alive);
    h.apos = malloc((size_t)h.np * sizeof *h.apos);
    h.fmark = calloc(h.np, sizeof *h.fmark);
    h.vis = malloc((size_t)h.np * sizeof *h.vis);
    h.unit = malloc((size_t)h.np * sizeof *h.unit);
    int rc = -ENOMEM;
    if (!pl || !h.face || !h.alive || !h.apos || !h.fmark || !h.vis ||
        !h.unit)
        goto out;
    memcpy(pl, planes, (size_t)n * sizeof *pl);
    for (uint32_t k = 0; k < 6; k++) {
        double *q = pl[n + k];
        q[0] = q[1] = q[2] = 0.0;
        q[k / 2] = (k % 2) ? -1.0 : 1.0;
        q[3] = -r;
    }
    h.pl = (const double (*)[4])pl;
    for (uint32_t i = 0; i < h.np; i++) {
        double len = sqrt(pl[i][0] * pl[i][0] + pl[i][1] * pl[i][1] +
                          pl[i][2] * pl[i][2]);
        for (int k = 0; k < 3; k++)
            h.unit[i][k] = pl[i][k] / len;
    }
    if (init_box(&h) < 0)
        goto out;
    for (uint32_t l = 0; l < n; l++) {
        rc = clip(&h, l, &st);
        if (rc == -EINVAL) {
            geo_err_set(err, rc, "the planes bound nothing: planes[%u] "
                        "leaves no interior of the region of planes[0..%u]",
                        l, l ? l - 1 : 0);
            goto out;
        }
        if (rc < 0)
            goto out;
    }
    for (uint32_t k = 0; k < 6; k++)
        if (h.face[n + k].alive) {
            st = GEO_HALFSPACE_UNBOUNDED;
            rc = geo_err_set(err, -EINVAL, "the planes do not bound the "
                             "region: it is unbounded towards %s",
                             BOX_SIDE[k]);
            goto out;
        }
    rc = build(&h, n, merge_tol, ret, ret_source);
out:
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory");
    if (rc < 0 && ret_status)
        *ret_status = st;
    for (uint32_t f = 0; h.face && f < h.np; f++)
        face_free(&h.face[f]);
    free(h.face);
    free(h.alive);
    free(h.apos);
    free(h.fmark);
    free(h.vis);
    free(h.unit);
    free(h.vert);
    free(h.sign);
    free(h.stamp);
    free(h.chain);
    free(h.meet);
    free(h.hkey);
    free(h.hval);
    free(h.hused);
    free(h.edges);
    free(pl);
    return rc;
}
