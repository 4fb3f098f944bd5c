/* merge_check.c — the local validity check of an edit (one merged group,
 * one collapsed cluster), and the facet BVH it searches.
 *
 * What a change can break is confined to the facets it touched (changed,
 * created, or holding a moved vertex) and the facets near them, so only
 * those are checked, with the same rules as geo_inspect's "valid":
 *  - every touched facet has ≥ 3 distinct vertices, its vertices within
 *    eps of its plane, its polygon winding with its plane (not inverted);
 *  - every vertex of a touched facet lies in ≥ 3 facets that form one
 *    closed fan, each of its edges shared by exactly one other facet
 *    running the other way (closed, manifold, consistently oriented);
 *  - no touched facet intersects itself or any facet whose bounding box
 *    overlaps its own, by the exact tests of lib/inspect/selfint.h (run on a small
 *    polyhedron holding just those facets, vertex identity kept).
 * Pairs of untouched facets are as they were. The BVH is built once per
 * round over the live facets; a changed facet's box is enlarged in place
 * (leaf and ancestors) and never shrunk, so every query still finds it;
 * facets created since the build are searched linearly (w->extra). */
#include "merge_impl.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "selfint.h"
#include "vec.h"

static void edit_facet_box(const geo_edit *e, uint32_t f, geo_bbox *b)
{
    geo_bbox_empty(b);
    const uint32_t *vs = geo_edit_fv(e, f);
    for (uint32_t i = 0; i < geo_edit_fn(e, f); i++)
        geo_bbox_add(b, e->verts[vs[i]]);
}

int geo_mw_world_build(geo_mw *w, geo_err *err)
{
    geo_edit *e = w->e;
    w->bvh = geo_bvh_free(w->bvh);
    free(w->slot_of), free(w->leaf_of), free(w->parent);
    w->slot_of = w->leaf_of = w->parent = NULL;
    w->nextra = 0;
    uint32_t nf = e->nfacets, nlive = 0;
    geo_bbox *boxes = malloc(((size_t)nf + 1) * sizeof *boxes);
    uint32_t *fid = malloc(((size_t)nf + 1) * sizeof *fid);
    w->slot_of = malloc(((size_t)nf + 1) * sizeof *w->slot_of);
    if (!boxes || !fid || !w->slot_of)
        goto oom;
    for (uint32_t f = 0; f < nf; f++) {
        w->slot_of[f] = GEO_NONE;
        if (!e->falive[f])
            continue;
        edit_facet_box(e, f, &boxes[nlive]);
        fid[nlive++] = f;
    }
    w->bvh = geo_bvh_build(boxes, nlive, err);
    if (!w->bvh)
        goto oom;
    /* items are positions in boxes[]; translate them to facet ids so the
     * queries report facet ids */
    geo_bvh *h = w->bvh;
    w->leaf_of = malloc(((size_t)h->nitems + 1) * sizeof *w->leaf_of);
    w->parent = malloc(((size_t)h->nnodes + 1) * sizeof *w->parent);
    if (!w->leaf_of || !w->parent)
        goto oom;
    for (uint32_t k = 0; k < h->nitems; k++) {
        h->items[k] = fid[h->items[k]];
        w->slot_of[h->items[k]] = k;
    }
    for (uint32_t n = 0; n < h->nnodes; n++)
        w->parent[n] = GEO_NONE;
    for (uint32_t n = 0; n < h->nnodes; n++) {
        const geo_bvh_node *nd = &h->nodes[n];
        if (nd->count) {
            for (uint32_t k = nd->child; k < nd->child + nd->count; k++)
                w->leaf_of[k] = n;
        } else {
            w->parent[nd->child] = n;
            w->parent[nd->child + 1] = n;
        }
    }
    w->nbase = nf;
    free(boxes), free(fid);
    return 0;
oom:
    free(boxes), free(fid);
    return geo_err_set(err, -ENOMEM, "out of memory");
}

static bool box_contains(const geo_bbox *outer, const geo_bbox *in)
{
    for (int k = 0; k < 3; k++)
        if (in->lo[k] < outer->lo[k] || in->hi[k] > outer->hi[k])
            return false;
    return true;
}

int geo_mw_world_update(geo_mw *w, const uint32_t *touched, uint32_t n)
{
    geo_edit *e = w->e;
    geo_bvh *h = w->bvh;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t f = touched[i];
        if (f >= e->nfacets || !e->falive[f])
            continue;
        if (f >= w->nbase || w->slot_of[f] == GEO_NONE) {
            bool have = false;
            for (uint32_t j = 0; j < w->nextra && !have; j++)
                have = w->extra[j] == f;
            if (have)
                continue;
            if (geo_mw_grow(&w->extra, &w->capextra, (size_t)w->nextra + 1) < 0)
                return -ENOMEM;
            w->extra[w->nextra++] = f;
            continue;
        }
        if (!h)
            continue;
        geo_bbox b;
        edit_facet_box(e, f, &b);
        uint32_t k = w->slot_of[f];
        geo_bbox_union(&h->boxes[k], &b);
        for (uint32_t nd = w->leaf_of[k]; nd != GEO_NONE; nd = w->parent[nd]) {
            if (box_contains(&h->nodes[nd].box, &b))
                break;
            geo_bbox_union(&h->nodes[nd].box, &b);
        }
    }
    return 0;
}

/* ---- the check ------------------------------------------------------- */

typedef struct checker {
    geo_mw *w;
    geo_edit *e;
    uint32_t *tf;            /* touched live facets */
    uint32_t ntf;
    uint32_t *cand;          /* facets of the mini model: touched first */
    uint32_t ncand, capcand;
    geo_bbox *tbox;          /* boxes of the touched facets */
} checker;

static int add_cand(checker *c, uint32_t f)
{
    if (c->w->fmark[f] == c->w->gen)
        return 0;
    c->w->fmark[f] = c->w->gen;
    if (geo_mw_grow(&c->cand, &c->capcand, (size_t)c->ncand + 1) < 0)
        return -ENOMEM;
    c->cand[c->ncand++] = f;
    return 0;
}

static bool cand_visit(void *user, uint32_t f)
{
    checker *c = user;
    if (f < c->e->nfacets && c->e->falive[f] && add_cand(c, f) < 0)
        return false;
    return true;
}

/* One closed fan about v, every edge matched exactly once. */
static int check_fan(const geo_edit *e, uint32_t v, geo_err *err)
{
    uint32_t n = geo_edit_vn(e, v);
    const uint32_t *l = geo_edit_vf(e, v);
    if (n < 3)
        return geo_err_set(err, -EINVAL, "vertices[%u]: in %u facets", v, n);
    enum { MAXFAN = 64 };
    uint32_t prev[MAXFAN], next[MAXFAN];
    if (n > MAXFAN)
        return geo_err_set(err, -EINVAL, "vertices[%u]: in %u facets (more "
                           "than %d)", v, n, MAXFAN);
    for (uint32_t i = 0; i < n; i++) {
        uint32_t g = l[i], m = geo_edit_fn(e, g), p = geo_edit_find(e, g, v);
        if (p == GEO_NONE)
            return geo_err_set(err, -EINVAL, "vertices[%u]: facet list out of "
                               "date", v);
        const uint32_t *vs = geo_edit_fv(e, g);
        prev[i] = vs[p ? p - 1 : m - 1];
        next[i] = vs[p + 1 < m ? p + 1 : 0];
    }
    uint32_t cur = 0, steps = 0;
    do {
        uint32_t found = GEO_NONE;
        for (uint32_t j = 0; j < n; j++)
            if (prev[j] == next[cur]) {
                if (found != GEO_NONE)
                    return geo_err_set(err, -EINVAL, "edge %u-%u: in more than "
                                       "two facets", v, next[cur]);
                found = j;
            }
        if (found == GEO_NONE)
            return geo_err_set(err, -EINVAL, "edge %u-%u: no facet across (or "
                               "one running the same way)", v, next[cur]);
        cur = found;
        steps++;
    } while (cur != 0 && steps <= n);
    if (steps != n)
        return geo_err_set(err, -EINVAL, "vertices[%u]: its facets form more "
                           "than one fan", v);
    return 0;
}

static int check_facet(const geo_mw *w, uint32_t f, geo_err *err)
{
    const geo_edit *e = w->e;
    uint32_t n = geo_edit_fn(e, f);
    const uint32_t *vs = geo_edit_fv(e, f);
    if (n < 3)
        return geo_err_set(err, -EINVAL, "facets[%u]: %u vertices", f, n);
    for (uint32_t i = 0; i < n; i++) {
        if (vs[i] == vs[(i + 1) % n])
            return geo_err_set(err, -EINVAL, "facets[%u]: vertex %u repeated",
                               f, vs[i]);
        double d = fabs(geo_plane_eval(e->planes[f], e->verts[vs[i]]));
        if (!(d <= w->eps))
            return geo_err_set(err, -EINVAL, "facets[%u]: vertex %u is %.3g mm "
                               "off its plane", f, vs[i], d);
    }
    double a[3];
    geo_edit_area_vector(e, f, a);
    if (!(geo_vdot(a, e->planes[f]) > 0))
        return geo_err_set(err, -EINVAL, "facets[%u]: winds against its plane "
                           "(inverted or degenerate)", f);
    return 0;
}

int geo_mw_check(geo_mw *w, geo_err *err)
{
    geo_edit *e = w->e;
    if (geo_mw_stamp(w) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    checker c;
    memset(&c, 0, sizeof c);
    c.w = w;
    c.e = e;
    int r = 0;
    geo_poly *mini = NULL;
    geo_facet_shape *shapes = NULL;
    uint32_t *vid = NULL;
    geo_bbox *cbox = NULL;
    uint8_t *shaped = NULL;

    /* touched facets: changed or new, or holding a touched vertex */
    uint32_t nt = geo_edit_ntouched_facets(e), nv = geo_edit_ntouched_verts(e);
    uint32_t *tmp = malloc(((size_t)nt + nv + 1) * sizeof *tmp);
    if (!tmp)
        return geo_err_set(err, -ENOMEM, "out of memory");
    nt = geo_edit_touched_facets(e, tmp);
    for (uint32_t i = 0; i < nt && r == 0; i++)
        if (tmp[i] < e->nfacets && e->falive[tmp[i]])
            r = add_cand(&c, tmp[i]);
    nv = geo_edit_touched_verts(e, tmp);
    for (uint32_t i = 0; i < nv && r == 0; i++)
        for (uint32_t j = 0; j < geo_edit_vn(e, tmp[i]) && r == 0; j++)
            r = add_cand(&c, geo_edit_vf(e, tmp[i])[j]);
    free(tmp);
    if (r < 0)
        goto oom;
    c.ntf = c.ncand;

    for (uint32_t i = 0; i < c.ntf; i++)
        if ((r = check_facet(w, c.cand[i], err)) < 0)
            goto done;
    for (uint32_t i = 0; i < c.ntf; i++) {
        uint32_t f = c.cand[i];
        for (uint32_t j = 0; j < geo_edit_fn(e, f); j++) {
            uint32_t v = geo_edit_fv(e, f)[j];
            if (w->vmark[v] == w->gen)
                continue;
            w->vmark[v] = w->gen;
            if ((r = check_fan(e, v, err)) < 0)
                goto done;
        }
    }

    /* neighbours by box: one query with the union of the touched boxes,
     * then the pairs whose own boxes overlap */
    c.tbox = malloc(((size_t)c.ntf + 1) * sizeof *c.tbox);
    if (!c.tbox)
        goto oom;
    geo_bbox all;
    geo_bbox_empty(&all);
    for (uint32_t i = 0; i < c.ntf; i++) {
        edit_facet_box(e, c.cand[i], &c.tbox[i]);
        geo_bbox_union(&all, &c.tbox[i]);
    }
    if (w->bvh && !geo_bvh_query_box(w->bvh, &all, cand_visit, &c))
        goto oom;
    for (uint32_t j = 0; j < w->nextra; j++) {
        uint32_t g = w->extra[j];
        geo_bbox b;
        if (!e->falive[g] || w->fmark[g] == w->gen)
            continue;
        edit_facet_box(e, g, &b);
        if (geo_bbox_overlap(&b, &all) && add_cand(&c, g) < 0)
            goto oom;
    }

    /* the small model: the candidates with their vertices renumbered */
    mini = geo_poly_new();
    vid = malloc(((size_t)e->nverts + 1) * sizeof *vid);
    if (!mini || !vid)
        goto oom;
    uint32_t gen2 = w->gen + 1; /* vmark2 holds "numbered in mini" */
    for (uint32_t i = 0; i < c.ncand; i++) {
        uint32_t f = c.cand[i];
        uint32_t n = geo_edit_fn(e, f);
        uint32_t loc[64], *lv = n <= 64 ? loc : malloc(n * sizeof *lv);
        if (!lv)
            goto oom;
        for (uint32_t j = 0; j < n; j++) {
            uint32_t v = geo_edit_fv(e, f)[j];
            if (w->vmark2[v] != gen2) {
                w->vmark2[v] = gen2;
                int64_t id = geo_poly_add_vertex(mini, e->verts[v]);
                if (id < 0) {
                    if (lv != loc)
                        free(lv);
                    goto oom;
                }
                vid[v] = (uint32_t)id;
            }
            lv[j] = vid[v];
        }
        int64_t g = geo_poly_add_facet(mini, lv, n);
        if (lv != loc)
            free(lv);
        if (g < 0)
            goto oom;
        memcpy(mini->planes[g], e->planes[f], sizeof e->planes[f]);
    }
    w->gen = gen2; /* vmark2 entries of this check are stale from now on */
    shapes = malloc(((size_t)c.ncand + 1) * sizeof *shapes);
    if (!shapes)
        goto oom;
    shaped = calloc((size_t)c.ncand + 1, 1);
    if (!shaped)
        goto oom;
    for (uint32_t i = 0; i < c.ntf; i++) {
        geo_facet_shape_of(mini, i, &shapes[i]);
        shaped[i] = 1;
    }
    for (uint32_t i = 0; i < c.ntf; i++) {
        if (shapes[i].degenerate) {
            r = geo_err_set(err, -EINVAL, "facets[%u]: degenerate", c.cand[i]);
            goto done;
        }
        if (!shapes[i].simple) {
            r = geo_err_set(err, -EINVAL, "facets[%u]: its polygon intersects "
                            "itself", c.cand[i]);
            goto done;
        }
    }
    cbox = malloc(((size_t)c.ncand + 1) * sizeof *cbox);
    if (!cbox)
        goto oom;
    for (uint32_t j = 0; j < c.ncand; j++)
        if (j < c.ntf)
            cbox[j] = c.tbox[j];
        else
            geo_poly_facet_bbox(mini, j, &cbox[j]);
    uint64_t work = 0; /* vertices tested since the last cancel check */
    for (uint32_t i = 0; i < c.ntf; i++) {
        for (uint32_t j = 0; j < c.ncand; j++) {
            if (j == i || (j < c.ntf && j < i))
                continue;
            if (!geo_bbox_overlap(&c.tbox[i], &cbox[j]))
                continue;
            /* a pair with a facet of 10,000s of vertices costs as much */
            work += geo_poly_facet_size(mini, i) + geo_poly_facet_size(mini, j);
            if (work >= (1u << 18)) {
                work = 0;
                if (geo_ctx_canceled(w->ctx)) {
                    r = geo_err_set(err, -ECANCELED, "canceled");
                    goto done;
                }
            }
            if (!shaped[j]) {
                geo_facet_shape_of(mini, j, &shapes[j]);
                shaped[j] = 1;
            }
            int x = geo_facets_intersect(mini, i, j, &shapes[i], &shapes[j]);
            if (x < 0)
                goto oom;
            if (x) {
                r = geo_err_set(err, -EINVAL, "facets[%u] and facets[%u] "
                                "intersect", c.cand[i], c.cand[j]);
                goto done;
            }
        }
    }
    r = 0;
    goto done;
oom:
    r = geo_err_set(err, -ENOMEM, "out of memory");
done:
    geo_poly_free(mini);
    free(shapes), free(vid), free(c.cand), free(c.tbox), free(cbox), free(shaped);
    return r;
}
