/* fill.c — checked hole filling on any polygon mesh (see fill.h).
 *
 * Invariants: `out` is p's copy with the kept patches appended, so a
 * facet or vertex index below p's counts means the same in both and the
 * BVH of p's facets serves every check; a patch under test is always the
 * last facets (and vertices) of `out`, so taking it back is truncation;
 * `kept` lists the facet ranges of the patches kept so far. */
#include "fill.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grow.h"
#include "bvh.h"
#include "edgemap.h"
#include "orient.h"
#include "plane.h"
#include "polygon_triangulate.h"
#include "selfint.h"
#include "topo.h"
#include "vec.h"
#include "weld.h"

const char *geo_fill_attempt_name(enum geo_fill_attempt a)
{
    switch (a) {
    case GEO_ATTEMPT_PLANAR:
        return "planar";
    case GEO_ATTEMPT_AS_ASKED:
        return "as_asked";
    case GEO_ATTEMPT_ANGLE:
        return "angle";
    case GEO_ATTEMPT_NO_FAIR:
        return "no_fair";
    case GEO_ATTEMPT_PLAIN:
        return "plain";
    case GEO_ATTEMPT_AVOID_FAIRED:
        return "avoid_faired";
    case GEO_ATTEMPT_AVOID_REFINED:
        return "avoid_refined";
    case GEO_ATTEMPT_AVOID:
        return "avoid";
    case GEO_ATTEMPT_LIFT:
        return "lift";
    case GEO_ATTEMPT_LOWER:
        return "lower";
    case GEO_ATTEMPT_FAN:
        return "fan";
    }
    return "unknown";
}

void geo_mesh_fill_opts_default(geo_mesh_fill_opts *o)
{
    memset(o, 0, sizeof *o);
    geo_fill_opts_default(&o->fill);
    o->fill.max_dp_vertices = 96;
    o->planar = true;
    o->check = true;
    o->fallback = true;
    o->split_nonplanar = true;
}

void geo_mesh_fill_report_clear(geo_mesh_fill_report *rep)
{
    if (!rep)
        return;
    free(rep->holes);
    memset(rep, 0, sizeof *rep);
}

typedef struct kept_patch {
    uint32_t f0, f1; /* facet range in out */
    geo_bbox box;
} kept_patch;

typedef struct mfill {
    const geo_poly *p;
    const geo_topo *t;
    geo_poly *out;
    geo_bvh *bvh; /* p's facets */
    kept_patch *kept;
    size_t nkept, cap_kept;
    const geo_ctx *ctx;
    /* parts_overlap only (else shell is NULL): the shell of every facet
     * of out (a kept patch's is its hole's), the shell of the hole being
     * filled (GEO_NONE when its loop borders several), and the sorted
     * shell pairs (lo << 32 | hi) that cross each other in p */
    uint32_t *shell;
    size_t cap_shell;
    uint32_t hole_shell;
    uint64_t *crossed;
    size_t ncrossed;
} mfill;

/* ---- the check ---- */

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* Whether the hole's patch may cross facet g of out: only with
 * parts_overlap, when g lies on another shell that the hole's own shell
 * already crossed in p (the overlap of two parts, not a new one). */
static bool crossing_allowed(const mfill *M, uint32_t g)
{
    if (!M->shell || M->hole_shell == GEO_NONE)
        return false;
    uint32_t a = M->hole_shell, b = M->shell[g];
    if (a == b)
        return false;
    uint64_t key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
    return bsearch(&key, M->crossed, M->ncrossed, sizeof key, cmp_u64);
}

typedef struct pair_probe {
    const mfill *M;
    const geo_poly *out;
    uint32_t f;             /* the patch facet being tested */
    const geo_facet_shape *sf;
    int hit;                /* 1 intersecting, 0 not, < 0 error */
} pair_probe;

static bool probe_facet(void *user, uint32_t g)
{
    pair_probe *pp = user;
    if (crossing_allowed(pp->M, g))
        return true;
    geo_facet_shape sg;
    geo_facet_shape_of(pp->out, g, &sg);
    int r = geo_facets_intersect(pp->out, pp->f, g, pp->sf, &sg);
    if (r != 0) {
        pp->hit = r < 0 ? r : 1;
        return false;
    }
    return true;
}

typedef struct self_probe {
    const geo_poly *out;
    uint32_t f0;
    const geo_facet_shape *shapes;
    int hit;
    uint8_t *bad; /* when set: mark both facets of every pair, go on */
} self_probe;

static bool probe_pair(void *user, uint32_t a, uint32_t b)
{
    self_probe *sp = user;
    if (sp->bad && sp->bad[a] && sp->bad[b])
        return true;
    int r = geo_facets_intersect(sp->out, sp->f0 + a, sp->f0 + b,
                                 &sp->shapes[a], &sp->shapes[b]);
    if (r < 0) {
        sp->hit = r;
        return false;
    }
    if (r > 0) {
        sp->hit = 1;
        if (!sp->bad)
            return false;
        sp->bad[a] = sp->bad[b] = 1;
    }
    return true;
}

/* 1 when facets [f0, f1) of out are degenerate, not simple, or intersect
 * the mesh, a kept patch or each other; 0 when clean; -ENOMEM. With bad
 * (f1 − f0 bytes), every offending facet is marked, not just the first. */
static int patch_intersects(mfill *M, uint32_t f0, uint32_t f1, uint8_t *bad)
{
    uint32_t n = f1 - f0;
    geo_facet_shape *sh = malloc((size_t)n * sizeof *sh);
    geo_bbox *boxes = malloc((size_t)n * sizeof *boxes);
    geo_bvh *own = NULL;
    int hit = 0;
    if (!sh || !boxes) {
        hit = -ENOMEM;
        goto out;
    }
    geo_bbox all;
    geo_bbox_empty(&all);
    for (uint32_t k = 0; k < n && (!hit || bad); k++) {
        geo_facet_shape_of(M->out, f0 + k, &sh[k]);
        if (sh[k].degenerate || !sh[k].simple) {
            hit = 1;
            if (bad)
                bad[k] = 1;
        }
        geo_poly_facet_bbox(M->out, f0 + k, &boxes[k]);
        geo_bbox_union(&all, &boxes[k]);
    }
    for (uint32_t k = 0; k < n && (!hit || bad); k++) {
        if (bad && bad[k])
            continue;
        pair_probe pp = {M, M->out, f0 + k, &sh[k], 0};
        if (M->bvh)
            geo_bvh_query_box(M->bvh, &boxes[k], probe_facet, &pp);
        for (size_t q = 0; q < M->nkept && pp.hit == 0; q++) {
            const kept_patch *kp = &M->kept[q];
            if (!geo_bbox_overlap(&kp->box, &boxes[k]))
                continue;
            for (uint32_t g = kp->f0; g < kp->f1 && pp.hit == 0; g++) {
                geo_bbox gb;
                geo_poly_facet_bbox(M->out, g, &gb);
                if (geo_bbox_overlap(&gb, &boxes[k]))
                    probe_facet(&pp, g);
            }
        }
        if (pp.hit < 0) {
            hit = pp.hit;
            goto out;
        }
        if (pp.hit) {
            hit = 1;
            if (bad)
                bad[k] = 1;
        }
    }
    if ((!hit || bad) && n > 1) {
        own = geo_bvh_build(boxes, n, NULL);
        if (!own) {
            hit = -ENOMEM;
            goto out;
        }
        self_probe sp = {M->out, f0, sh, 0, bad};
        geo_bvh_pairs(own, 0, 0, probe_pair, &sp);
        if (sp.hit)
            hit = sp.hit;
    }
out:
    geo_bvh_free(own);
    free(sh), free(boxes);
    return hit;
}

static int keep_patch(mfill *M, uint32_t f0, uint32_t f1)
{
    if (geo_grow((void **)&M->kept, &M->cap_kept, M->nkept + 1,
                 sizeof *M->kept) < 0)
        return -ENOMEM;
    if (M->shell) {
        if (geo_grow((void **)&M->shell, &M->cap_shell, f1,
                     sizeof *M->shell) < 0)
            return -ENOMEM;
        for (uint32_t f = f0; f < f1; f++)
            M->shell[f] = M->hole_shell;
    }
    kept_patch *kp = &M->kept[M->nkept++];
    kp->f0 = f0;
    kp->f1 = f1;
    geo_bbox_empty(&kp->box);
    for (uint32_t f = f0; f < f1; f++) {
        geo_bbox b;
        geo_poly_facet_bbox(M->out, f, &b);
        geo_bbox_union(&kp->box, &b);
    }
    return 0;
}

/* Takes back everything appended to out after nv vertices, nf facets. */
static void truncate_out(geo_poly *out, uint32_t nv, uint32_t nf)
{
    out->nverts = nv;
    out->nfacets = nf;
}

/* ---- one hole ---- */

typedef struct loop_ref {
    const uint32_t *w;  /* the patch cycle: the loop reversed */
    const uint32_t *lc; /* the loop's corners in p (lc[k]'s edge runs
                           against w's edge n − 2 − k mod n) */
    uint32_t n;
} loop_ref;

/* Facet of p across w's edge j. */
static uint32_t facet_across(const mfill *M, const loop_ref *L, uint32_t j)
{
    return M->t->corner_facet[L->lc[(2 * L->n - 2 - j) % L->n]];
}

/* The loop's plane and its largest deviation (INFINITY when none). */
static double loop_planarity(const geo_poly *p, const loop_ref *L,
                             double plane[4])
{
    double *pts = malloc((size_t)L->n * 3 * sizeof *pts);
    if (!pts)
        return INFINITY;
    for (uint32_t k = 0; k < L->n; k++)
        memcpy(pts + 3 * k, p->verts[L->w[k]], 3 * sizeof *pts);
    double dev = INFINITY;
    if (geo_plane_fit(pts, NULL, L->n, NULL, plane) == 0) {
        dev = 0;
        for (uint32_t k = 0; k < L->n; k++) {
            double d = fabs(geo_plane_eval(plane, pts + 3 * k));
            if (d > dev)
                dev = d;
        }
    }
    free(pts);
    return dev;
}

/* Appends the loop as one facet when it is a valid planar facet. 1 kept,
 * 0 not (out unchanged), -ENOMEM. Not where two consecutive loop edges
 * belong to one facet of p: the new facet would share both with it and
 * leave the vertex between them in two facets only (a triangle left
 * standing in a hole in a flat region); a triangulation gives it more
 * (an ear there would lie on that facet: the search never repeats an
 * edge of p, and the check rejects an overlap). */
static int try_planar(mfill *M, const loop_ref *L, bool check)
{
    for (uint32_t j = 0; j < L->n; j++)
        if (facet_across(M, L, j) == facet_across(M, L, (j + 1) % L->n))
            return 0;
    geo_poly *out = M->out;
    uint32_t nf = out->nfacets;
    int64_t f = geo_poly_add_facet(out, L->w, L->n);
    if (f < 0)
        return (int)f;
    geo_poly_facet_fit_plane(out, nf, GEO_PLANE_UNWEIGHTED, out->planes[nf]);
    double eps = geo_poly_eps(M->p), worst = 0;
    for (uint32_t k = 0; k < L->n; k++) {
        double d = fabs(geo_plane_eval(out->planes[nf], out->verts[L->w[k]]));
        if (d > worst)
            worst = d;
    }
    int bad = !(worst <= eps);
    if (!bad) {
        geo_facet_shape s;
        geo_facet_shape_of(out, nf, &s);
        bad = s.degenerate || !s.simple;
    }
    if (!bad && check)
        bad = patch_intersects(M, nf, nf + 1, NULL);
    if (bad) {
        truncate_out(out, out->nverts, nf);
        return bad < 0 ? bad : 0;
    }
    return 1;
}

typedef struct edge_sel {
    uint32_t a, b; /* local indices of w[0], w[1] */
} edge_sel;

static bool select_edge(void *user, const uint32_t *cycle, uint32_t n)
{
    const edge_sel *e = user;
    for (uint32_t k = 0; k < n; k++)
        if (cycle[k] == e->a && cycle[(k + 1) % n] == e->b)
            return true;
    return false;
}

/* A triangle of out's vertices as a key of the forbidden set: exact
 * below 2²¹ vertices, else a hash (a collision only forbids one more
 * triangle). Never UINT64_MAX. */
static uint64_t tri_key(uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t t;
    if (a > b)
        t = a, a = b, b = t;
    if (b > c)
        t = b, b = c, c = t;
    if (a > b)
        t = a, a = b, b = t;
    if (c < (1u << 21))
        return (uint64_t)a | (uint64_t)b << 21 | (uint64_t)c << 42;
    uint64_t h = (uint64_t)a * 0x9e3779b97f4a7c15ull ^
                 (uint64_t)b * 0xc2b2ae3d27d4eb4full ^
                 (uint64_t)c * 0x165667b19e3779f9ull;
    return h | (uint64_t)1 << 63;
}

typedef struct admit_ctx {
    const uint32_t *glob;      /* sub's vertex → out's */
    const geo_edgemap *forbid; /* tri_key of the triangles not to use */
} admit_ctx;

static bool admit_tri(void *user, uint32_t a, uint32_t b, uint32_t c)
{
    const admit_ctx *ac = user;
    return geo_edgemap_get(ac->forbid, tri_key(ac->glob[a], ac->glob[b],
                                                ac->glob[c])) == UINT32_MAX;
}

/* Runs the hole filler on the facets around the loop and appends its
 * patch to out, avoiding the triangles in forbid (may be NULL). *status
 * gets the outcome; 0 or a negative errno. */
static int try_liepa(mfill *M, const loop_ref *L, const geo_fill_opts *fo,
                     const geo_edgemap *forbid, uint8_t *status,
                     geo_err *err)
{
    geo_poly *out = M->out;
    const geo_topo *t = M->t;
    geo_edgemap vmap = {0}, fset = {0};
    uint32_t *glob = NULL;
    size_t nglob = 0, cap_glob = 0;
    geo_poly *sub = geo_poly_new();
    geo_fill_stats st = {0};
    int rc = -ENOMEM;
    if (!sub || geo_edgemap_init(&vmap, 8 * (size_t)L->n) < 0 ||
        geo_edgemap_init(&fset, 8 * (size_t)L->n) < 0)
        goto done;
    /* the loop vertices' facets: p's (from the topology), then those of
     * kept patches near the loop */
    geo_bbox lbox;
    geo_bbox_empty(&lbox);
    for (uint32_t k = 0; k < L->n; k++) {
        geo_bbox_add(&lbox, out->verts[L->w[k]]);
        if (geo_edgemap_put(&vmap, L->w[k], UINT32_MAX - 1) < 0)
            goto done;
    }
    uint32_t *facets = NULL;
    size_t nfac = 0, cap_fac = 0;
#define PUSH_FACET(g)                                                         \
    do {                                                                      \
        if (geo_edgemap_get(&fset, (g)) == UINT32_MAX) {                      \
            if (nfac == cap_fac) {                                            \
                size_t nc_ = cap_fac ? 2 * cap_fac : 64;                      \
                uint32_t *nf_ = realloc(facets, nc_ * sizeof *nf_);           \
                if (!nf_)                                                     \
                    goto done_f;                                              \
                facets = nf_;                                                 \
                cap_fac = nc_;                                                \
            }                                                                 \
            if (geo_edgemap_put(&fset, (g), 1) < 0)                           \
                goto done_f;                                                  \
            facets[nfac++] = (g);                                             \
        }                                                                     \
    } while (0)
    for (uint32_t k = 0; k < L->n; k++) {
        uint32_t v = L->w[k];
        for (uint32_t c = t->vstart[v]; c < t->vstart[v + 1]; c++)
            PUSH_FACET(t->corner_facet[t->vcorners[c]]);
    }
    for (size_t q = 0; q < M->nkept; q++) {
        const kept_patch *kp = &M->kept[q];
        if (!geo_bbox_overlap(&kp->box, &lbox))
            continue;
        for (uint32_t g = kp->f0; g < kp->f1; g++) {
            const uint32_t *gv = geo_poly_facet(out, g);
            for (uint32_t i = 0; i < geo_poly_facet_size(out, g); i++)
                if (geo_edgemap_get(&vmap, gv[i]) != UINT32_MAX) {
                    PUSH_FACET(g);
                    break;
                }
        }
    }
#undef PUSH_FACET
    /* local numbering: every vertex of those facets */
    for (size_t q = 0; q < nfac; q++) {
        const uint32_t *gv = geo_poly_facet(out, facets[q]);
        uint32_t k = geo_poly_facet_size(out, facets[q]);
        for (uint32_t i = 0; i < k; i++) {
            uint32_t have = geo_edgemap_get(&vmap, gv[i]);
            if (have != UINT32_MAX && have != UINT32_MAX - 1)
                continue;
            if (nglob == cap_glob) {
                size_t nc = cap_glob ? 2 * cap_glob : 64;
                uint32_t *ng = realloc(glob, nc * sizeof *ng);
                if (!ng)
                    goto done_f;
                glob = ng;
                cap_glob = nc;
            }
            if (geo_edgemap_put(&vmap, gv[i], (uint32_t)nglob) < 0 ||
                geo_poly_add_vertex(sub, out->verts[gv[i]]) < 0)
                goto done_f;
            glob[nglob++] = gv[i];
        }
    }
    uint32_t *loc = NULL;
    for (size_t q = 0; q < nfac; q++) {
        const uint32_t *gv = geo_poly_facet(out, facets[q]);
        uint32_t k = geo_poly_facet_size(out, facets[q]);
        uint32_t *nl = realloc(loc, (size_t)k * sizeof *nl);
        if (!nl)
            goto done_l;
        loc = nl;
        for (uint32_t i = 0; i < k; i++)
            loc[i] = geo_edgemap_get(&vmap, gv[i]);
        int64_t nf = geo_poly_add_facet(sub, loc, k);
        if (nf < 0)
            goto done_l;
        memcpy(sub->planes[nf], out->planes[facets[q]], sizeof sub->planes[0]);
    }
    uint32_t nv_sub = sub->nverts, nf_sub = sub->nfacets;
    edge_sel es = {geo_edgemap_get(&vmap, L->w[0]),
                   geo_edgemap_get(&vmap, L->w[1])};
    geo_fill_opts o = *fo;
    o.select_loop = select_edge;
    o.select_user = &es;
    admit_ctx ac = {glob, forbid};
    if (forbid && forbid->n > 0) {
        o.admit = admit_tri;
        o.admit_user = &ac;
    }
    geo_ctx inner = {0};
    if (M->ctx) {
        inner.cancel = M->ctx->cancel;
        inner.seed = M->ctx->seed;
    }
    rc = geo_fill_loops(sub, &o, &inner, &st, err);
    if (rc < 0)
        goto done_l;
    *status = st.nholes == 1 ? st.holes[0].status : GEO_HOLE_NOT_A_LOOP;
    if (*status != GEO_HOLE_FILLED)
        goto done_l;
    /* the patch: sub's vertices and facets past the copied ones */
    uint32_t nv0 = out->nverts;
    rc = geo_poly_reserve(out, (size_t)nv0 + (sub->nverts - nv_sub),
                          (size_t)out->nfacets + (sub->nfacets - nf_sub),
                          (size_t)geo_poly_ncorners(out) +
                              (geo_poly_ncorners(sub) - sub->fstart[nf_sub]));
    if (rc < 0)
        goto done_l;
    for (uint32_t v = nv_sub; v < sub->nverts; v++)
        geo_poly_add_vertex(out, sub->verts[v]);
    for (uint32_t f = nf_sub; f < sub->nfacets; f++) {
        const uint32_t *sv = geo_poly_facet(sub, f);
        uint32_t k = geo_poly_facet_size(sub, f);
        uint32_t tri[3];
        uint32_t *g = k <= 3 ? tri : malloc((size_t)k * sizeof *g);
        if (!g) {
            rc = -ENOMEM;
            goto done_l;
        }
        for (uint32_t i = 0; i < k; i++)
            g[i] = sv[i] < nv_sub ? glob[sv[i]] : nv0 + (sv[i] - nv_sub);
        int64_t nf = geo_poly_add_facet(out, g, k);
        if (g != tri)
            free(g);
        if (nf < 0) {
            rc = (int)nf;
            goto done_l;
        }
        memcpy(out->planes[nf], sub->planes[f], sizeof out->planes[0]);
    }
    rc = 0;
done_l:
    free(loc);
done_f:
    free(facets);
done:
    geo_fill_stats_clear(&st);
    geo_poly_free(sub);
    free(glob);
    geo_edgemap_destroy(&vmap);
    geo_edgemap_destroy(&fset);
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory filling a hole");
    return rc;
}

/* Dihedral angles at the loop and edge-length ratio of the patch
 * [f0, f1) just kept. */
static int patch_metrics(const mfill *M, const loop_ref *L, uint32_t f0,
                         uint32_t f1, geo_mesh_hole *h)
{
    const geo_poly *out = M->out;
    geo_edgemap he;
    size_t nc = 0;
    for (uint32_t f = f0; f < f1; f++)
        nc += geo_poly_facet_size(out, f);
    if (geo_edgemap_init(&he, nc) < 0)
        return -ENOMEM;
    for (uint32_t f = f0; f < f1; f++) {
        const uint32_t *fv = geo_poly_facet(out, f);
        uint32_t k = geo_poly_facet_size(out, f);
        for (uint32_t i = 0; i < k; i++)
            if (geo_edgemap_put(&he, geo_edge_key(fv[i], fv[(i + 1) % k]), f) <
                0) {
                geo_edgemap_destroy(&he);
                return -ENOMEM;
            }
    }
    double worst = 0;
    for (uint32_t j = 0; j < L->n; j++) {
        uint32_t a = L->w[j], b = L->w[(j + 1) % L->n];
        uint32_t f = geo_edgemap_get(&he, geo_edge_key(a, b));
        if (f == UINT32_MAX)
            continue;
        double n1[3], n2[3], x[3];
        geo_poly_facet_area_vector(out, f, n1);
        geo_poly_facet_area_vector(out, facet_across(M, L, j), n2);
        geo_vcross(n1, n2, x);
        double ang = atan2(geo_vlen(x), geo_vdot(n1, n2)) * 180.0 / M_PI;
        if (ang > worst)
            worst = ang;
    }
    h->max_dihedral_deg = worst;
    /* inner edges of the patch (both directions in it), each once */
    double in_sum = 0;
    uint64_t in_n = 0;
    for (uint32_t f = f0; f < f1; f++) {
        const uint32_t *fv = geo_poly_facet(out, f);
        uint32_t k = geo_poly_facet_size(out, f);
        for (uint32_t i = 0; i < k; i++) {
            uint32_t a = fv[i], b = fv[(i + 1) % k];
            if (a < b &&
                geo_edgemap_get(&he, geo_edge_key(b, a)) != UINT32_MAX) {
                in_sum += geo_vdist(out->verts[a], out->verts[b]);
                in_n++;
            }
        }
    }
    geo_edgemap_destroy(&he);
    double around = 0;
    uint64_t an = 0;
    const geo_poly *p = M->p;
    for (uint32_t j = 0; j < L->n; j++) {
        uint32_t v = L->w[j];
        for (uint32_t c = M->t->vstart[v]; c < M->t->vstart[v + 1]; c++) {
            uint32_t cc = M->t->vcorners[c];
            uint32_t nx = p->fidx[geo_topo_next(p, M->t, cc)];
            uint32_t pv = p->fidx[geo_topo_prev(p, M->t, cc)];
            around += geo_vdist(p->verts[v], p->verts[nx]) +
                      geo_vdist(p->verts[v], p->verts[pv]);
            an += 2;
        }
    }
    h->edge_ratio = in_n && an && around > 0
                        ? (in_sum / (double)in_n) / (around / (double)an)
                        : 0.0;
    return 0;
}

/* The attempts for a hole, in order; returns how many. */
static int plan_attempts(const geo_mesh_fill_opts *mo, uint8_t kinds[4],
                         geo_fill_opts fo[4])
{
    int n = 0;
    kinds[n] = GEO_ATTEMPT_AS_ASKED;
    fo[n++] = mo->fill;
    if (!mo->check || !mo->fallback)
        return n;
    static const uint8_t more[3] = {GEO_ATTEMPT_ANGLE, GEO_ATTEMPT_NO_FAIR,
                                    GEO_ATTEMPT_PLAIN};
    for (int k = 0; k < 3; k++) {
        geo_fill_opts o = mo->fill;
        o.weight = GEO_FILL_ANGLE;
        if (more[k] >= GEO_ATTEMPT_NO_FAIR)
            o.fair = GEO_FAIR_NONE;
        if (more[k] == GEO_ATTEMPT_PLAIN)
            o.refine = false;
        o.refine = o.refine && mo->fill.refine;
        o.fair = mo->fill.fair == GEO_FAIR_NONE ? GEO_FAIR_NONE : o.fair;
        bool dup = false;
        for (int q = 0; q < n; q++)
            dup |= fo[q].weight == o.weight && fo[q].refine == o.refine &&
                   fo[q].fair == o.fair;
        if (!dup) {
            kinds[n] = more[k];
            fo[n++] = o;
        }
    }
    return n;
}

/* The bare triangulation steered around the mesh: each round forbids the
 * loop triangles that crossed something (the mesh, a kept patch, the
 * patch itself) and searches again, so the programme picks other
 * diagonals — the hole is split into other sub-holes — until a patch
 * crosses nothing or no triangulation is left. Then the same search is
 * refined and faired, and the first variant that still crosses nothing
 * is kept. 1 kept (h->attempt says which), 0 none (out unchanged), or a
 * negative errno. */
static int try_avoid(mfill *M, const geo_mesh_fill_opts *mo, const loop_ref *L,
                     geo_mesh_hole *h, geo_mesh_fill_report *rep,
                     geo_err *err)
{
    geo_poly *out = M->out;
    uint32_t nv0 = out->nverts, nf0 = out->nfacets;
    geo_edgemap forbid = {0};
    uint8_t *bad = NULL;
    int rc = -ENOMEM;
    if (geo_edgemap_init(&forbid, 64) < 0)
        goto done;
    geo_fill_opts bare = mo->fill;
    bare.weight = GEO_FILL_ANGLE;
    bare.refine = false;
    bare.fair = GEO_FAIR_NONE;
    /* each round costs one O(n³) search; big holes get fewer rounds */
    uint32_t rounds = L->n <= 64 ? 200 : L->n <= 200 ? 60 : 16;
    bool found = false;
    for (uint32_t r = 0; r < rounds && !found; r++) {
        uint8_t st = GEO_HOLE_NO_TRIANGULATION;
        rc = try_liepa(M, L, &bare, &forbid, &st, err);
        if (rc < 0)
            goto done;
        if (st != GEO_HOLE_FILLED)
            break;
        uint32_t np = out->nfacets - nf0;
        uint8_t *nb = realloc(bad, np ? np : 1);
        if (!nb) {
            rc = -ENOMEM;
            goto done;
        }
        bad = nb;
        memset(bad, 0, np);
        rc = patch_intersects(M, nf0, out->nfacets, bad);
        if (rc < 0)
            goto done;
        if (rc == 0) {
            found = true;
            break;
        }
        rep->nrejected++;
        size_t added = 0;
        for (uint32_t k = 0; k < np; k++) {
            if (!bad[k] || geo_poly_facet_size(out, nf0 + k) != 3)
                continue;
            const uint32_t *tv = geo_poly_facet(out, nf0 + k);
            uint64_t key = tri_key(tv[0], tv[1], tv[2]);
            if (geo_edgemap_get(&forbid, key) == UINT32_MAX) {
                if (geo_edgemap_put(&forbid, key, 1) < 0) {
                    rc = -ENOMEM;
                    goto done;
                }
                added++;
            }
        }
        truncate_out(out, nv0, nf0);
        if (added == 0)
            break; /* nothing left to steer by */
    }
    rc = 0;
    if (!found)
        goto done;
    /* the steered triangulation passes: try it refined and faired */
    static const uint8_t kinds[2] = {GEO_ATTEMPT_AVOID_FAIRED,
                                     GEO_ATTEMPT_AVOID_REFINED};
    for (int a = 0; a < 2 && mo->fill.refine; a++) {
        if (kinds[a] == GEO_ATTEMPT_AVOID_FAIRED &&
            mo->fill.fair == GEO_FAIR_NONE)
            continue;
        truncate_out(out, nv0, nf0);
        geo_fill_opts o = mo->fill;
        o.weight = GEO_FILL_ANGLE;
        if (kinds[a] == GEO_ATTEMPT_AVOID_REFINED)
            o.fair = GEO_FAIR_NONE;
        uint8_t st = GEO_HOLE_NO_TRIANGULATION;
        rc = try_liepa(M, L, &o, &forbid, &st, err);
        if (rc < 0)
            goto done;
        if (st != GEO_HOLE_FILLED)
            continue;
        rc = patch_intersects(M, nf0, out->nfacets, NULL);
        if (rc < 0)
            goto done;
        if (rc == 0) {
            h->attempt = kinds[a];
            rc = 1;
            goto done;
        }
        rep->nrejected++;
    }
    /* the bare steered patch, searched once more (it passed before) */
    truncate_out(out, nv0, nf0);
    uint8_t st = GEO_HOLE_NO_TRIANGULATION;
    rc = try_liepa(M, L, &bare, &forbid, &st, err);
    if (rc < 0)
        goto done;
    h->attempt = GEO_ATTEMPT_AVOID;
    rc = st == GEO_HOLE_FILLED ? 1 : 0;
    if (rc == 0)
        truncate_out(out, nv0, nf0);
done:
    if (rc < 0)
        truncate_out(out, nv0, nf0);
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory steering a patch");
    geo_edgemap_destroy(&forbid);
    free(bad);
    return rc;
}

/* Unit Newell normal of the patch cycle (zero when it has none). */
static void cycle_normal(const geo_poly *out, const loop_ref *L, double n[3])
{
    n[0] = n[1] = n[2] = 0;
    for (uint32_t k = 0; k < L->n; k++) {
        const double *a = out->verts[L->w[k]];
        const double *b = out->verts[L->w[(k + 1) % L->n]];
        n[0] += (a[1] - b[1]) * (a[2] + b[2]);
        n[1] += (a[2] - b[2]) * (a[0] + b[0]);
        n[2] += (a[0] - b[0]) * (a[1] + b[1]);
    }
    if (geo_vnormalize(n) == 0)
        n[0] = n[1] = n[2] = 0;
}

/* Appends a fan from the loop's centroid: the patch the lift bends when
 * refinement added no vertex to bend. */
static int append_fan(geo_poly *out, const loop_ref *L)
{
    double c[3] = {0, 0, 0};
    for (uint32_t k = 0; k < L->n; k++)
        for (int d = 0; d < 3; d++)
            c[d] += out->verts[L->w[k]][d] / L->n;
    int64_t v = geo_poly_add_vertex(out, c);
    if (v < 0)
        return (int)v;
    for (uint32_t k = 0; k < L->n; k++) {
        uint32_t t[3] = {L->w[k], L->w[(k + 1) % L->n], (uint32_t)v};
        int64_t f = geo_poly_add_facet(out, t, 3);
        if (f < 0)
            return (int)f;
    }
    return 0;
}

/* The patch lifted or lowered along the loop's normal: the vertices the
 * patch added move by amp × (the loop's mean radius) × (their distance in
 * edges from the loop, over the largest), a dome instead of a lid, which clears a sheet the lid
 * would lie on (an open sheet, a hole in a flat region whose only
 * triangulation overlaps it) or a thin wall next to the hole. Amplitudes
 * are tried from small to large, lifting first; the first patch that
 * crosses nothing is kept. 1 kept, 0 none (out unchanged), -ENOMEM. */
static int try_lift(mfill *M, const geo_mesh_fill_opts *mo, const loop_ref *L,
                    geo_mesh_hole *h, geo_mesh_fill_report *rep, geo_err *err)
{
    geo_poly *out = M->out;
    uint32_t nv0 = out->nverts, nf0 = out->nfacets;
    double nrm[3];
    cycle_normal(out, L, nrm);
    if (geo_vdot(nrm, nrm) == 0)
        return 0;
    geo_fill_opts o = mo->fill;
    o.weight = GEO_FILL_ANGLE;
    uint8_t st = GEO_HOLE_NO_TRIANGULATION;
    int rc = try_liepa(M, L, &o, NULL, &st, err);
    if (rc < 0)
        return rc;
    /* a facet with every corner on the loop cannot be lifted: it would
     * stay where the lid crossed; the fan has none */
    bool rim_only = st != GEO_HOLE_FILLED || out->nverts == nv0;
    for (uint32_t f = nf0; f < out->nfacets && !rim_only; f++) {
        const uint32_t *fv = geo_poly_facet(out, f);
        uint32_t k = geo_poly_facet_size(out, f), on = 0;
        for (uint32_t i = 0; i < k; i++)
            on += fv[i] < nv0;
        rim_only = on == k;
    }
    if (rim_only) {
        truncate_out(out, nv0, nf0);
        if ((rc = append_fan(out, L)) < 0) {
            truncate_out(out, nv0, nf0);
            return geo_err_set(err, rc, "out of memory lifting a patch");
        }
    }
    uint32_t nnew = out->nverts - nv0;
    uint32_t *depth = malloc((size_t)nnew * sizeof *depth);
    double(*base)[3] = malloc((size_t)nnew * sizeof *base);
    if (!depth || !base) {
        free(depth), free(base);
        truncate_out(out, nv0, nf0);
        return geo_err_set(err, -ENOMEM, "out of memory lifting a patch");
    }
    memcpy(base, out->verts + nv0, (size_t)nnew * sizeof *base);
    for (uint32_t v = 0; v < nnew; v++)
        depth[v] = UINT32_MAX;
    /* distances in edges from the loop: relax over the patch's edges */
    double elen = 0;
    uint64_t ne = 0;
    for (bool changed = true; changed;) {
        changed = false;
        for (uint32_t f = nf0; f < out->nfacets; f++) {
            const uint32_t *fv = geo_poly_facet(out, f);
            uint32_t k = geo_poly_facet_size(out, f);
            for (uint32_t i = 0; i < k; i++) {
                uint32_t a = fv[i], b = fv[(i + 1) % k];
                for (int dir = 0; dir < 2; dir++) {
                    uint32_t x = dir ? b : a, y = dir ? a : b;
                    if (y < nv0)
                        continue;
                    uint32_t dx = x < nv0 ? 0 : depth[x - nv0];
                    if (dx != UINT32_MAX && dx + 1 < depth[y - nv0]) {
                        depth[y - nv0] = dx + 1;
                        changed = true;
                    }
                }
            }
        }
    }
    for (uint32_t f = nf0; f < out->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(out, f);
        uint32_t k = geo_poly_facet_size(out, f);
        for (uint32_t i = 0; i < k; i++, ne++)
            elen += geo_vdist(out->verts[fv[i]], out->verts[fv[(i + 1) % k]]);
    }
    elen = ne ? elen / (double)ne : 0;
    /* heights relative to the loop's radius, the profile a cone over
     * the distances in edges: a fan's apex and a refined patch's middle
     * rise alike */
    double ctr[3] = {0, 0, 0}, rad = 0;
    uint32_t maxd = 1;
    for (uint32_t k = 0; k < L->n; k++)
        geo_vadd(ctr, out->verts[L->w[k]], ctr);
    geo_vscale(ctr, 1.0 / L->n, ctr);
    for (uint32_t k = 0; k < L->n; k++)
        rad += geo_vdist(ctr, out->verts[L->w[k]]) / L->n;
    for (uint32_t v = 0; v < nnew; v++)
        if (depth[v] != UINT32_MAX && depth[v] > maxd)
            maxd = depth[v];
    static const double amps[] = {0.0, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0,
                                  -0.1, -0.25, -0.5, -1.0, -2.0, -4.0};
    rc = 0;
    for (size_t a = 0; a < sizeof amps / sizeof amps[0] && elen > 0; a++) {
        for (uint32_t v = 0; v < nnew; v++) {
            double d = depth[v] == UINT32_MAX ? 1 : depth[v];
            for (int c = 0; c < 3; c++)
                out->verts[nv0 + v][c] =
                    base[v][c] + amps[a] * rad * (d / maxd) * nrm[c];
        }
        for (uint32_t f = nf0; f < out->nfacets; f++)
            geo_poly_facet_fit_plane(out, f, GEO_PLANE_UNWEIGHTED,
                                     out->planes[f]);
        int r = patch_intersects(M, nf0, out->nfacets, NULL);
        if (r < 0) {
            rc = geo_err_set(err, r, "out of memory checking a patch");
            break;
        }
        if (r == 0) {
            h->attempt = amps[a] > 0   ? GEO_ATTEMPT_LIFT
                         : amps[a] < 0 ? GEO_ATTEMPT_LOWER
                         : rim_only    ? GEO_ATTEMPT_FAN
                                       : GEO_ATTEMPT_AS_ASKED;
            rc = 1;
            break;
        }
        rep->nrejected++;
    }
    free(depth), free(base);
    if (rc != 1)
        truncate_out(out, nv0, nf0);
    return rc;
}

static int fill_one(mfill *M, const geo_mesh_fill_opts *mo, const loop_ref *L,
                    geo_mesh_hole *h, geo_mesh_fill_report *rep, geo_err *err)
{
    geo_poly *out = M->out;
    double plane[4];
    h->planarity = loop_planarity(out, L, plane);
    uint32_t nv0 = out->nverts, nf0 = out->nfacets;
    if (mo->planar && h->planarity <= geo_poly_eps(M->p)) {
        h->attempt = GEO_ATTEMPT_PLANAR;
        int r = try_planar(M, L, mo->check);
        if (r < 0)
            return geo_err_set(err, r, "out of memory filling a hole");
        if (r == 1) {
            h->status = GEO_HOLE_FILLED_PLANAR;
            goto kept;
        }
    }
    uint8_t kinds[4];
    geo_fill_opts fo[4];
    int na = plan_attempts(mo, kinds, fo);
    h->status = GEO_HOLE_NO_TRIANGULATION;
    for (int a = 0; a < na; a++) {
        h->attempt = kinds[a];
        /* refined patches are built first without the per-split checks
         * (the whole patch is checked below, which is much cheaper), and
         * only when that patch crosses, again with them */
        bool fast = mo->check && fo[a].refine && fo[a].check_each;
        for (int pass = fast ? 0 : 1; pass < 2; pass++) {
            geo_fill_opts o = fo[a];
            o.check_each = pass == 1 && fo[a].check_each;
            uint8_t st = GEO_HOLE_NO_TRIANGULATION;
            int r = try_liepa(M, L, &o, NULL, &st, err);
            if (r < 0)
                return r;
            h->status = st;
            if (st == GEO_HOLE_NO_TRIANGULATION && mo->check &&
                mo->fallback)
                goto dome; /* a new vertex repeats no edge of the mesh */
            if (st != GEO_HOLE_FILLED)
                return 0; /* nothing another weight could change */
            if (!mo->check)
                goto kept;
            r = patch_intersects(M, nf0, out->nfacets, NULL);
            if (r < 0)
                return geo_err_set(err, r, "out of memory checking a patch");
            if (r == 0)
                goto kept;
            rep->nrejected++;
            truncate_out(out, nv0, nf0);
            h->status = GEO_HOLE_INTERSECTS;
        }
    }
    if (h->status == GEO_HOLE_INTERSECTS && mo->fallback) {
        int r = try_avoid(M, mo, L, h, rep, err);
        if (r < 0)
            return r;
        if (r == 1) {
            h->status = GEO_HOLE_FILLED;
            goto kept;
        }
dome:;
        uint8_t before = h->status;
        r = try_lift(M, mo, L, h, rep, err);
        if (r < 0)
            return r;
        if (r == 1) {
            h->status = GEO_HOLE_FILLED;
            goto kept;
        }
        h->status = before;
        h->attempt = GEO_ATTEMPT_LOWER;
    }
    return 0;
kept:
    h->facets_added = out->nfacets - nf0;
    h->verts_added = out->nverts - nv0;
    if (keep_patch(M, nf0, out->nfacets) < 0 ||
        patch_metrics(M, L, nf0, out->nfacets, h) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    return 0;
}

/* parts_overlap: the shells of p (components across two-corner edges,
 * as lib/inspect/orient.h counts them) and the pairs of shells that
 * cross each other (every intersecting facet pair of p, exact). */
static int find_overlaps(mfill *M, const geo_ctx *ctx, geo_err *err)
{
    const geo_poly *p = M->p;
    const geo_topo *t = M->t;
    uint32_t n = p->nfacets;
    M->cap_shell = n ? n : 1;
    if (!(M->shell = malloc(M->cap_shell * sizeof *M->shell)))
        return geo_err_set(err, -ENOMEM, "out of memory");
    for (uint32_t f = 0; f < n; f++)
        M->shell[f] = f;
    uint32_t *u = M->shell; /* union-find, roots the smallest facet */
    for (uint32_t c = 0; c < t->ncorners; c++) {
        if (t->mate[c] == GEO_NONE)
            continue;
        uint32_t a = t->corner_facet[c], b = t->corner_facet[t->mate[c]];
        while (u[a] != a)
            a = u[a] = u[u[a]];
        while (u[b] != b)
            b = u[b] = u[u[b]];
        if (a != b)
            u[a > b ? a : b] = a < b ? a : b;
    }
    for (uint32_t f = 0; f < n; f++)
        u[f] = u[u[f]]; /* roots are smaller: one pass flattens */
    geo_selfint_opts so;
    geo_selfint_opts_default(&so);
    /* a pair of shells missed past the cap only allows less (32 MB of
     * pairs at most, whatever a hostile mesh holds) */
    so.max_pairs = 1u << 22;
    geo_selfint si;
    int rc = geo_selfint_find(p, M->bvh, &so, ctx, &si, err);
    if (rc < 0)
        return rc;
    M->crossed = malloc(((size_t)si.npairs + 1) * sizeof *M->crossed);
    if (!M->crossed) {
        geo_selfint_clear(&si);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    size_t m = 0;
    for (uint32_t k = 0; k < si.npairs; k++) {
        uint32_t a = u[si.pairs[k][0]], b = u[si.pairs[k][1]];
        if (a != b)
            M->crossed[m++] = a < b ? (uint64_t)a << 32 | b
                                    : (uint64_t)b << 32 | a;
    }
    geo_selfint_clear(&si);
    qsort(M->crossed, m, sizeof *M->crossed, cmp_u64);
    size_t k = 0;
    for (size_t i = 0; i < m; i++)
        if (k == 0 || M->crossed[i] != M->crossed[k - 1])
            M->crossed[k++] = M->crossed[i];
    M->ncrossed = k;
    return 0;
}

/* The shell every edge of the loop borders, or GEO_NONE. */
static uint32_t loop_shell(const mfill *M, const uint32_t *lc, uint32_t n)
{
    uint32_t s = M->shell[M->t->corner_facet[lc[0]]];
    for (uint32_t k = 1; k < n; k++)
        if (M->shell[M->t->corner_facet[lc[k]]] != s)
            return GEO_NONE;
    return s;
}

/* An open mesh has no inside: once every hole is closed, a shell that
 * came out turned inside out (consistent, negative volume) has all its
 * facets reversed. A shell with inconsistent facets is left as it is
 * (that is a defect of the input, for `orient` to repair). */
static int turn_outward(geo_poly *p, geo_mesh_fill_report *R, geo_err *err)
{
    geo_topo *t = geo_topo_build(p, err);
    uint8_t *flip = malloc(p->nfacets ? p->nfacets : 1);
    geo_orient_report orep;
    int rc = -ENOMEM;
    if (t && flip && geo_orient_analyze(p, t, flip, &orep, err) == 0) {
        rc = 0;
        if (orep.ninconsistent == 0 && orep.orientable)
            for (uint32_t f = 0; f < p->nfacets; f++)
                if (flip[f]) {
                    geo_poly_flip_facet(p, f);
                    R->nreversed++;
                }
    }
    if (rc < 0)
        geo_err_set(err, rc, "out of memory orienting the result");
    geo_topo_free(t);
    free(flip);
    return rc;
}

/* remove_crossing removes at most this part of the facets (see
 * fill_removing) */
#define REMOVE_MAX_FRACTION 0.05

/* A facet that may be removed: the pairs it is in, its area. */
typedef struct cand {
    uint32_t f, pairs;
    double area;
} cand;

static int cmp_cand(const void *a, const void *b)
{
    const cand *x = a, *y = b;
    if (x->pairs != y->pairs)
        return x->pairs > y->pairs ? -1 : 1;
    if (x->area != y->area)
        return x->area < y->area ? -1 : 1;
    return (x->f > y->f) - (x->f < y->f);
}

/* remove_crossing: which facets go. Of the intersecting pairs with a
 * facet on a rim (a vertex on a hole's border), enough facets that touch
 * a rim to leave none of those pairs whole: greedily, the facet in the
 * most such pairs first (ties: the smaller area, then the lower index) —
 * a flap folded over an opening crosses what it lies across, so it goes
 * and the wall it pierces stays. keep[f] false for each; the count. */
static int choose_removed(const geo_poly *p, const uint8_t *rim,
                          const geo_selfint *si, bool *keep,
                          uint32_t *ret_n)
{
    uint32_t nf = p->nfacets, *deg = calloc((size_t)nf + 1, sizeof *deg);
    uint8_t *onrim = calloc((size_t)nf + 1, 1);
    uint32_t *start = NULL, *adj = NULL;
    cand *c = NULL;
    int rc = -ENOMEM;
    *ret_n = 0;
    if (!deg || !onrim)
        goto done;
    for (uint32_t f = 0; f < nf; f++) {
        keep[f] = true;
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 0; i < geo_poly_facet_size(p, f) && !onrim[f]; i++)
            onrim[f] = rim[fv[i]];
    }
    /* the pairs that matter: a distinct pair with a facet on a rim */
#define COUNTS(a, b) ((a) != (b) && (onrim[a] || onrim[b]))
    for (uint32_t k = 0; k < si->npairs; k++) {
        uint32_t a = si->pairs[k][0], b = si->pairs[k][1];
        if (COUNTS(a, b))
            deg[a]++, deg[b]++;
    }
    start = malloc(((size_t)nf + 1) * sizeof *start);
    if (!start)
        goto done;
    start[0] = 0;
    for (uint32_t f = 0; f < nf; f++)
        start[f + 1] = start[f] + deg[f];
    adj = malloc(((size_t)start[nf] + 1) * sizeof *adj);
    c = malloc(((size_t)nf + 1) * sizeof *c);
    if (!adj || !c)
        goto done;
    memset(deg, 0, (size_t)nf * sizeof *deg);
    for (uint32_t k = 0; k < si->npairs; k++) {
        uint32_t a = si->pairs[k][0], b = si->pairs[k][1];
        if (COUNTS(a, b)) {
            adj[start[a] + deg[a]++] = b;
            adj[start[b] + deg[b]++] = a;
        }
    }
#undef COUNTS
    uint32_t nc = 0;
    for (uint32_t f = 0; f < nf; f++)
        if (onrim[f] && deg[f] > 0) {
            double av[3];
            geo_poly_facet_area_vector(p, f, av);
            c[nc++] = (cand){f, deg[f], geo_vlen(av)};
        }
    qsort(c, nc, sizeof *c, cmp_cand);
    for (uint32_t i = 0; i < nc; i++) {
        uint32_t f = c[i].f;
        bool whole = false; /* a pair of f with both facets still kept */
        for (uint32_t k = start[f]; k < start[f + 1] && !whole; k++)
            whole = keep[adj[k]];
        if (whole) {
            keep[f] = false;
            ++*ret_n;
        }
    }
    rc = 0;
done:
    free(deg), free(onrim), free(start), free(adj), free(c);
    return rc;
}

/* remove_crossing past the flaps: rings of facets grown around the
 * crossings that remain and around the holes left open (each ring: every
 * facet with a vertex of a removed one or on such a hole), tried in turn
 * until the holes close */
#define REMOVE_RINGS 3

/* Marks in open[] (p->nverts bytes, cleared first) the vertices of p on
 * the loops of q that rep left open; vnew: q's vertex of each of p's. */
static int mark_open_loops(const geo_poly *p, const geo_poly *q,
                           const geo_topo *tq, const uint32_t *vnew,
                           const geo_mesh_fill_report *rep, uint8_t *open)
{
    memset(open, 0, p->nverts);
    uint32_t *lstart = NULL, *lcorn = NULL, nloops = 0;
    uint8_t *qopen = calloc((size_t)q->nverts + 1, 1);
    if (!qopen || geo_topo_boundary_loops(q, tq, &lstart, &lcorn, &nloops) < 0) {
        free(qopen);
        return -ENOMEM;
    }
    for (uint32_t h = 0; h < rep->nloops; h++) {
        uint8_t st = rep->holes[h].status;
        if (st != GEO_HOLE_FILLED && st != GEO_HOLE_FILLED_PLANAR &&
            rep->holes[h].first_vertex < q->nverts)
            qopen[rep->holes[h].first_vertex] = 1;
    }
    /* every loop through a vertex that starts a hole left open (two
     * loops touching at it are both taken) */
    for (uint32_t l = 0; l < nloops; l++) {
        bool hit = false;
        for (uint32_t k = lstart[l]; k < lstart[l + 1] && !hit; k++)
            hit = qopen[q->fidx[lcorn[k]]] & 1;
        for (uint32_t k = lstart[l]; k < lstart[l + 1] && hit; k++)
            qopen[q->fidx[lcorn[k]]] |= 2;
    }
    for (uint32_t v = 0; v < p->nverts; v++)
        open[v] = vnew[v] != UINT32_MAX && (qopen[vnew[v]] & 2);
    free(qopen), free(lstart), free(lcorn);
    return 0;
}

/* Removes from a copy of p the facets keep[] clears and fills it; swaps
 * it into p when every hole closes (1), else leaves p as it was and marks
 * in open[] p's vertices on the holes left open (0), or a negative
 * errno. */
static int fill_without(geo_poly *p, const bool *keep, uint32_t nrem,
                        const geo_mesh_fill_opts *mo, const geo_ctx *ctx,
                        uint8_t *open, geo_mesh_fill_report *rep,
                        geo_err *err)
{
    geo_poly *q = geo_poly_copy(p);
    uint32_t *vnew = malloc(((size_t)p->nverts + 1) * sizeof *vnew);
    geo_topo *tq = NULL;
    int rc = -ENOMEM;
    if (!q || !vnew || geo_poly_compact(q, keep, vnew, NULL) < 0 ||
        !(tq = geo_topo_build(q, err)))
        goto done;
    geo_mesh_fill_opts m2 = *mo;
    m2.remove_crossing = false;
    geo_mesh_fill_report r2 = {0};
    rc = geo_fill(q, &m2, ctx, &r2, err);
    if (rc == 0 && r2.nopen == 0) {
        geo_poly tmp = *p;
        *p = *q;
        *q = tmp;
        r2.nremoved = nrem;
        *rep = r2;
        rc = 1;
    } else {
        if (rc == 0)
            rc = mark_open_loops(p, q, tq, vnew, &r2, open);
        geo_mesh_fill_report_clear(&r2);
    }
done:
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory");
    geo_topo_free(tq);
    geo_poly_free(q);
    free(vnew);
    return rc;
}

/* Clears keep[] of every facet with a vertex of a facet already cleared
 * or marked in open[] (mark: nverts bytes of scratch); returns how many
 * facets are cleared in all. */
static uint32_t grow_ring(const geo_poly *p, bool *keep, const uint8_t *open,
                          uint8_t *mark)
{
    memcpy(mark, open, p->nverts);
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (!keep[f])
            for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++)
                mark[p->fidx[c]] = 1;
    uint32_t n = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1] && keep[f]; c++)
            keep[f] = !mark[p->fidx[c]];
        n += !keep[f];
    }
    return n;
}

/* remove_crossing: first the flaps choose_removed picks; when crossings
 * remain between facets that stay (two sheets through each other inside
 * the mesh, away from any hole), both facets of each such pair go as
 * well, and then rings around them and around the holes the choice
 * before left open (REMOVE_RINGS): a patch over the bare opening of one
 * crossing facet would cross the other again, and a wider hole lets the
 * patch pass. Each choice is filled in a copy, the
 * first whose holes all close swapped into p: it then crosses nothing
 * (every crossing facet is gone and every patch is checked). 1 kept, 0
 * not (nothing to remove, more crossings than are listed, past
 * REMOVE_MAX_FRACTION of the facets, or a hole left open: p unchanged),
 * or a negative errno. */
static int fill_removing(geo_poly *p, const geo_mesh_fill_opts *mo,
                         const geo_ctx *ctx, geo_mesh_fill_report *rep,
                         geo_err *err)
{
    geo_topo *t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
    geo_selfint_opts so;
    geo_selfint_opts_default(&so);
    so.max_pairs = 1u << 22; /* 32 MB of pairs at most; past it, no removal */
    geo_selfint si;
    int rc = geo_selfint_find(p, NULL, &so, ctx, &si, err);
    if (rc < 0) {
        geo_topo_free(t);
        return rc;
    }
    uint32_t nf = p->nfacets;
    uint8_t *rim = calloc((size_t)p->nverts + 1, 1);
    uint8_t *open = calloc((size_t)p->nverts + 1, 1);
    bool *keep = malloc(((size_t)nf + 1) * sizeof *keep);
    uint32_t nrem = 0, left = 0;
    rc = -ENOMEM;
    if (!rim || !open || !keep)
        goto done;
    rc = 0;
    if (si.count > si.npairs)
        goto done;
    for (uint32_t c = 0; c < t->ncorners; c++)
        if (t->edge_kind[c] == GEO_EDGE_BOUNDARY) {
            rim[p->fidx[c]] = 1;
            rim[p->fidx[geo_topo_next(p, t, c)]] = 1;
        }
    if ((rc = choose_removed(p, rim, &si, keep, &nrem)) < 0)
        goto done;
    for (uint32_t k = 0; k < si.npairs; k++) {
        uint32_t a = si.pairs[k][0], b = si.pairs[k][1];
        if (keep[a] && keep[b]) {
            left++;
            keep[a] = keep[b] = false;
        }
    }
    /* a flap or a fold is a local defect: a choice past
     * REMOVE_MAX_FRACTION of the facets would remesh the model rather
     * than repair it (an assembly of crossing parts would lose most of
     * itself: parts_overlap is the rule there) */
    if (left == 0 && nrem > 0 && nrem <= REMOVE_MAX_FRACTION * nf &&
        (rc = fill_without(p, keep, nrem, mo, ctx, open, rep, err)) != 0)
        goto done;
    if (nrem == 0 && left == 0)
        goto done;
    /* the flaps alone left a hole open: rings around them as around any
     * other crossing */
    nrem = 0;
    for (uint32_t f = 0; f < nf; f++)
        nrem += !keep[f];
    for (int ring = left == 0; ring <= REMOVE_RINGS && rc == 0; ring++) {
        if (ring > 0)
            nrem = grow_ring(p, keep, open, rim);
        if (nrem > REMOVE_MAX_FRACTION * nf)
            break;
        rc = fill_without(p, keep, nrem, mo, ctx, open, rep, err);
    }
done:
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory");
    free(rim), free(open), free(keep);
    geo_selfint_clear(&si);
    geo_topo_free(t);
    return rc;
}

/* A facet of more than three vertices with one farther than eps from its
 * plane (implicit planes read as stored: geo_poly_facet_plane). */
static bool nonplanar(const geo_poly *p, uint32_t f, double eps)
{
    uint32_t n = geo_poly_facet_size(p, f);
    if (n <= 3)
        return false;
    const uint32_t *v = geo_poly_facet(p, f);
    double pl[4];
    geo_poly_facet_plane(p, f, pl);
    for (uint32_t i = 0; i < n; i++)
        if (!(fabs(geo_plane_eval(pl, p->verts[v[i]])) <= eps))
            return true;
    return false;
}

/* Splits every facet of p with a vertex farther than geo_poly_eps(p)
 * from its plane into triangles on its own vertices: the facet keeps its
 * index as the first triangle, the others are appended, each with its
 * own plane. *ret_split gets how many were split. 0 or -ENOMEM (p
 * unchanged). */
static int split_nonplanar(geo_poly *p, uint32_t *ret_split)
{
    double eps = geo_poly_eps(p);
    uint8_t *split = malloc((size_t)p->nfacets + 1);
    if (!split)
        return -ENOMEM;
    uint32_t nsplit = 0, ntri = 0, maxn = 3;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        split[f] = nonplanar(p, f, eps);
        if (split[f]) {
            nsplit++, ntri += n - 2;
            maxn = n > maxn ? n : maxn;
        }
    }
    *ret_split = nsplit;
    if (nsplit == 0) {
        free(split);
        return 0;
    }
    geo_poly *q = geo_poly_new();
    uint32_t (*tri)[3] = malloc((size_t)maxn * sizeof *tri);
    uint32_t (*rest)[3] = malloc(((size_t)ntri + 1) * sizeof *rest);
    int rc = -ENOMEM;
    if (!q || !tri || !rest ||
        geo_poly_reserve(q, p->nverts, p->nfacets + ntri - nsplit,
                         geo_poly_ncorners(p) + 3 * (size_t)ntri) < 0)
        goto out;
    for (uint32_t v = 0; v < p->nverts; v++)
        if (geo_poly_add_vertex(q, p->verts[v]) < 0)
            goto out;
    uint32_t nrest = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        int64_t id;
        if (!split[f]) {
            if ((id = geo_poly_add_facet(q, v, n)) < 0)
                goto out;
            geo_poly_facet_plane(p, f, q->planes[id]);
            continue;
        }
        if (geo_polygon_triangulate(&p->verts[0][0], v, n, tri) < 0)
            goto out;
        for (uint32_t k = 0; k < n - 2; k++) {
            uint32_t t3[3] = {v[tri[k][0]], v[tri[k][1]], v[tri[k][2]]};
            if (k == 0) {
                if ((id = geo_poly_add_facet(q, t3, 3)) < 0)
                    goto out;
                geo_poly_facet_fit_plane(q, (uint32_t)id, GEO_PLANE_UNWEIGHTED,
                                         q->planes[id]);
            } else {
                memcpy(rest[nrest++], t3, sizeof t3);
            }
        }
    }
    for (uint32_t k = 0; k < nrest; k++) {
        int64_t id = geo_poly_add_facet(q, rest[k], 3);
        if (id < 0)
            goto out;
        geo_poly_facet_fit_plane(q, (uint32_t)id, GEO_PLANE_UNWEIGHTED,
                                 q->planes[id]);
    }
    geo_poly tmp = *p;
    *p = *q;
    *q = tmp;
    rc = 0;
out:
    geo_poly_free(q);
    free(split), free(tri), free(rest);
    return rc;
}

/* 1 when some vertex of p is in no facet, 0 when none, -ENOMEM. */
static int has_unused_vertex(const geo_poly *p)
{
    bool *used = calloc((size_t)p->nverts + 1, sizeof *used);
    if (!used)
        return -ENOMEM;
    uint32_t nc = geo_poly_ncorners(p), nused = 0;
    for (uint32_t c = 0; c < nc; c++)
        if (!used[p->fidx[c]]) {
            used[p->fidx[c]] = true;
            nused++;
        }
    free(used);
    return nused < p->nverts;
}

/* Before the holes of an open mesh (a closed one is left alone): vertices
 * no facet uses are removed, seams welded (lib/mesh/weld.h), facets
 * inconsistent with their neighbours are reversed where the shell is
 * orientable (a mesh from another tool often mixes both windings; no
 * patch could make it a solid, and the loops would split at every flipped
 * edge), and, with split, non-planar facets are split. */
static int prepare_open(geo_poly *p, bool split, uint32_t *ret_split,
                        uint32_t *ret_reversed, uint32_t *ret_unused,
                        uint32_t *ret_welded, geo_err *err)
{
    *ret_split = *ret_reversed = *ret_unused = *ret_welded = 0;
    geo_topo *t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
    int rc = 0;
    bool open = t->nboundary_edges > 0;
    /* a vertex no facet uses is no part of any surface, yet a solid with
     * one is not valid (every vertex in three facets or more) */
    uint32_t nv = p->nverts;
    int unused = open ? has_unused_vertex(p) : 0;
    if (unused < 0) {
        geo_topo_free(t);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    if (unused) {
        geo_topo_free(t);
        if (geo_poly_compact(p, NULL, NULL, NULL) < 0)
            return geo_err_set(err, -ENOMEM, "out of memory");
        *ret_unused = nv - p->nverts;
        if (!(t = geo_topo_build(p, err)))
            return -ENOMEM;
    }
    /* a seam whose sides repeat their vertices reads as a hole that no
     * patch fills (its sides coincide): weld it first */
    if (open) {
        if (geo_weld_boundary(p, t, ret_welded, err) < 0) {
            geo_topo_free(t);
            return -ENOMEM;
        }
        if (*ret_welded) {
            geo_topo_free(t);
            if (!(t = geo_topo_build(p, err)))
                return -ENOMEM;
            open = t->nboundary_edges > 0;
        }
    }
    if (open && t->nflipped_edges > 0) {
        uint8_t *flip = malloc((size_t)p->nfacets + 1);
        geo_orient_report orep;
        if (!flip || geo_orient_analyze(p, t, flip, &orep, err) < 0)
            rc = -ENOMEM;
        else if (orep.orientable)
            for (uint32_t f = 0; f < p->nfacets; f++)
                if (flip[f]) {
                    geo_poly_flip_facet(p, f);
                    ++*ret_reversed;
                }
        free(flip);
    }
    geo_topo_free(t);
    if (rc == 0 && open && split &&
        geo_poly_max_nonplanarity(p) > geo_poly_eps(p) &&
        split_nonplanar(p, ret_split) < 0)
        rc = -ENOMEM;
    if (rc < 0)
        geo_err_set(err, rc, "out of memory");
    return rc;
}

int geo_fill(geo_poly *p, const geo_mesh_fill_opts *opts,
                  const geo_ctx *ctx, geo_mesh_fill_report *rep, geo_err *err)
{
    geo_mesh_fill_opts mo;
    if (opts)
        mo = *opts;
    else
        geo_mesh_fill_opts_default(&mo);
    mo.fill.select_loop = NULL;
    mo.fill.select_user = NULL;
    if (mo.fill.weight != GEO_FILL_AREA && mo.fill.weight != GEO_FILL_EDGES &&
        mo.fill.weight != GEO_FILL_ANGLE)
        return geo_err_set(err, -EINVAL, "weight: unknown");
    int rc = geo_poly_validate_indices(p, err);
    if (rc < 0)
        return rc;
    uint32_t nsplit = 0, nrev = 0, nunused = 0, nwelded = 0;
    if ((rc = prepare_open(p, mo.split_nonplanar, &nsplit, &nrev, &nunused,
                           &nwelded, err)) < 0)
        return rc;
    if (mo.remove_crossing) {
        geo_mesh_fill_report RR = {0};
        rc = fill_removing(p, &mo, ctx, &RR, err);
        if (rc < 0)
            return rc;
        if (rc == 1) {
            RR.nsplit = nsplit;
            RR.nunused = nunused;
            RR.nwelded = nwelded;
            RR.nreversed += nrev;
            if (rep)
                *rep = RR;
            else
                geo_mesh_fill_report_clear(&RR);
            return 0;
        }
        mo.remove_crossing = false;
    }
    geo_mesh_fill_report R = {
        .nsplit = nsplit, .nreversed = nrev, .nunused = nunused,
        .nwelded = nwelded};
    mfill M = {.p = p, .ctx = ctx};
    uint32_t *lstart = NULL, *lcorn = NULL, nloops = 0, *w = NULL;
    geo_topo *t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
    M.t = t;
    rc = -ENOMEM;
    if (geo_topo_boundary_loops(p, t, &lstart, &lcorn, &nloops) < 0)
        goto fail;
    R.nloops = nloops;
    R.holes = calloc((size_t)nloops + 1, sizeof *R.holes);
    w = malloc(((size_t)t->nboundary_edges + 1) * sizeof *w);
    M.out = geo_poly_copy(p);
    if (!R.holes || !w || !M.out)
        goto fail;
    if (nloops > 0 && mo.check && p->nfacets > 0 &&
        !(M.bvh = geo_bvh_build_facets(p, err)))
        goto fail;
    if (nloops > 0 && mo.check && mo.parts_overlap && p->nfacets > 0 &&
        (rc = find_overlaps(&M, ctx, err)) < 0)
        goto fail;
    rc = -ENOMEM;
    for (uint32_t l = 0; l < nloops; l++) {
        geo_mesh_hole *h = &R.holes[l];
        uint32_t n = lstart[l + 1] - lstart[l];
        const uint32_t *lc = lcorn + lstart[l];
        h->nverts = n;
        h->first_vertex = p->fidx[lc[0]];
        h->planarity = INFINITY;
        bool closed = n >= 1;
        for (uint32_t k = 0; k < n && closed; k++)
            closed = p->fidx[geo_topo_next(p, t, lc[k])] ==
                     p->fidx[lc[(k + 1) % n]];
        if (!closed)
            h->status = GEO_HOLE_NOT_A_LOOP;
        else if (n < 3)
            h->status = GEO_HOLE_DEGENERATE;
        else if (n > mo.fill.max_hole_vertices)
            h->status = GEO_HOLE_TOO_LARGE;
        else {
            for (uint32_t k = 0; k < n; k++)
                w[k] = p->fidx[lc[n - 1 - k]];
            loop_ref L = {w, lc, n};
            M.hole_shell = M.shell ? loop_shell(&M, lc, n) : GEO_NONE;
            if ((rc = fill_one(&M, &mo, &L, h, &R, err)) < 0)
                goto fail;
        }
        if (h->status == GEO_HOLE_FILLED || h->status == GEO_HOLE_FILLED_PLANAR) {
            R.nfilled++;
            R.nplanar += h->status == GEO_HOLE_FILLED_PLANAR;
            R.verts_added += h->verts_added;
            R.facets_added += h->facets_added;
            if (h->max_dihedral_deg > R.max_dihedral_deg)
                R.max_dihedral_deg = h->max_dihedral_deg;
        } else {
            R.nopen++;
        }
        if ((rc = geo_ctx_progress(ctx, (l + 1.0) / nloops)) < 0) {
            geo_err_set(err, rc, "canceled");
            goto fail;
        }
    }
    geo_poly tmp = *p;
    *p = *M.out;
    *M.out = tmp;
    rc = 0;
    if (R.nfilled > 0 && R.nopen == 0 && (rc = turn_outward(p, &R, err)) < 0)
        goto fail;
    goto done;
fail:
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory");
done:
    geo_poly_free(M.out);
    geo_bvh_free(M.bvh);
    geo_topo_free(t);
    free(M.kept);
    free(M.shell), free(M.crossed);
    free(lstart), free(lcorn), free(w);
    if (rc < 0 || !rep)
        geo_mesh_fill_report_clear(&R);
    else
        *rep = R;
    return rc;
}
