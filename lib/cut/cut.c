/* cut.c — plane cut of an arbitrary polyhedron (Palachev 2012, §3).
 *
 * Stages (the paper's, with the topology of lib/core/topo.h as preprocessing):
 *  1. the side of every vertex, decided once: on the plane when
 *     |plane(v)| ≤ geo_poly_eps(p)·|n| (the tolerance of lib/core/poly.h),
 *     else the exact sign (geo_plane_sign). Without the tolerance a
 *     plane put through a vertex in floating point (d = −n·v rounded)
 *     leaves the vertex a rounding error off it, and the crossings on
 *     its edges round onto the vertex itself: zero-length edges and
 *     facets touching themselves. Beyond the tolerance a crossing lies
 *     at least that far from both ends of its edge;
 *  2. one new vertex per crossed edge, shared by the edge's two facets
 *     through the mate corner;
 *  3.–4. per cut facet, the events on its section line l = facet ∩ plane
 *     sorted exactly (ENTRY, EXIT, PASS, DOUBLE; convex on-plane vertices
 *     hanging), the direction sweep, and its kept pieces by the paper's
 *     cycles B and A, each segment of l walked by cycle A being, reversed,
 *     an edge of a new facet: lib/cut/cut_facet.c, the one implementation the
 *     merge's local §3.4 cut (lib/correct/merge_cut.c) calls too; here it gets
 *     the exact sides of stage 1 and the crossing vertices of stage 2,
 *     and its pieces become facets of the output with the facet's plane;
 *  5. the section components: the edges of the new facets chained at their
 *     shared vertices. A crossed edge's vertex is shared by exactly the two
 *     facets of that edge, so following the chain is the paper's transition
 *     F(facet, edge) = (next facet, next edge); edges of the model lying in
 *     the plane join the chain when only one of their two facets is kept
 *     there; a component with holes, or passing a vertex twice, is split
 *     into simple coplanar facets (lib/cut/region_split.h) with every
 *     crossing's rounding bound, so the split holds for the exact
 *     section too;
 *  6. dropping the removed side, the hanging on-plane vertices, and
 *     renumbering (geo_poly_compact).
 *
 * What differs in the §3.4 variant (opts.main_facet) is only checked
 * here: the main facet on or above the plane, one component, one new
 * facet.
 *
 * Invariants: side[] is never recomputed; every crossing point is computed
 * once; the kept pieces of a facet and the new facets use the same vertex
 * ids along every shared edge, so the result is closed by construction. */
#include "cut.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cut_facet.h"
#include "predicates.h"
#include "region_split.h"
#include "selfint.h"
#include "vec.h"

typedef struct cutter {
    const geo_poly *p;
    const geo_topo *t;
    const double *plane; /* as given: decides every side */
    bool drop_hanging;   /* opts.drop_hanging */
    double unit[4];      /* normalised: the new facets' plane */
    int8_t *side;
    uint32_t *xv;        /* per corner: crossing vertex id or GEO_NONE */
    double *xerr;        /* per crossing vertex (id − p->nverts): bound on
                            its distance from the exact crossing */
    double on_tol;       /* |plane(v)| up to which v lies on the plane */
    size_t capxerr;
    geo_poly *out;
    geo_err *err;

    /* the per-facet stages; cf.sec: edges of the new facets (src, dst),
     * output vertex ids */
    geo_cutf cf;
    int8_t *fside;       /* sides of one facet's vertices, in its order */
    size_t capfside;
    /* corners of kept in-plane edges (candidates for the section) */
    uint32_t *kin;
    size_t nkin, capkin;
    uint8_t *kept_inplane; /* per corner: its edge lies in the plane and
                              its facet is kept along it */

    uint32_t pieces, split_facets, removed_facets, new_vertices;
} cutter;

/* plane(x) in floating point, for the tolerance of "lies on the plane"
 * (its sign, where it matters, comes from geo_plane_sign). */
static double plane_value(const double plane[4], const double x[3])
{
    return plane[0] * x[0] + plane[1] * x[1] + plane[2] * x[2] + plane[3];
}

/* A bound on the distance of on-plane vertex v from the plane (within
 * the tolerance, it need not lie on it exactly), with room for the
 * rounding of its computation. */
static double onplane_bound(const cutter *k, uint32_t v)
{
    const double *x = k->p->verts[v];
    double mag = fabs(k->plane[0] * x[0]) + fabs(k->plane[1] * x[1]) +
                 fabs(k->plane[2] * x[2]) + fabs(k->plane[3]);
    double d = fabs(plane_value(k->plane, x)) + 8 * DBL_EPSILON * mag;
    return d / geo_vlen(k->plane) * (1 + 8 * DBL_EPSILON);
}

static int push_kin(cutter *k, uint32_t corner)
{
    if (k->kept_inplane[corner])
        return 0;
    if (geo_grow((void **)&k->kin, &k->capkin, k->nkin + 1, sizeof *k->kin) < 0)
        return -ENOMEM;
    k->kept_inplane[corner] = 1;
    k->kin[k->nkin++] = corner;
    return 0;
}

/* ---- one cut facet ---------------------------------------------------- */

static int facet_error(cutter *k, uint32_t f, const char *what)
{
    return geo_err_set(k->err, -EINVAL,
                       "facets[%u]: %s (a self-intersecting or strongly "
                       "non-planar facet)", f, what);
}

/* Facet f by the shared stages (lib/cut/cut_facet.h): its kept pieces become
 * facets of the output with f's plane; the in-plane edges cycle B walked
 * become section candidates. */
static int cut_facet(cutter *k, uint32_t f)
{
    const geo_poly *p = k->p;
    uint32_t n = geo_poly_facet_size(p, f), c0 = p->fstart[f];
    const uint32_t *vs = geo_poly_facet(p, f);

    double nf[3];
    geo_poly_facet_area_vector(p, f, nf);
    if (geo_cutf_frame(&k->cf, nf) < 0)
        return facet_error(k, f, k->cf.why);
    if (geo_grow((void **)&k->fside, &k->capfside, n, 1) < 0)
        return -ENOMEM;
    for (uint32_t j = 0; j < n; j++)
        k->fside[j] = k->side[vs[j]];
    int np = geo_cutf_facet(&k->cf, (const double(*)[3])p->verts, vs, k->fside,
                            k->xv + c0, n);
    if (np == -EINVAL)
        return facet_error(k, f, k->cf.why);
    if (np < 0)
        return np;
    for (size_t j = 0; j < k->cf.ninplane; j++) {
        int r = push_kin(k, c0 + k->cf.inplane[j]);
        if (r < 0)
            return r;
    }
    for (int q = 0; q < np; q++) {
        uint32_t b = k->cf.pstart[q];
        int64_t nf_out = geo_poly_add_facet(k->out, k->cf.piece + b,
                                            k->cf.pstart[q + 1] - b);
        if (nf_out < 0)
            return (int)nf_out;
        memcpy(k->out->planes[nf_out], p->planes[f], sizeof p->planes[f]);
    }
    k->pieces += (uint32_t)np;
    k->split_facets++;
    return 0;
}

/* ---- the section: chaining the new facets' edges ------------------------ */

/* Among the edges leaving v (at least two: the section touches itself at
 * v), the one that follows the edge arriving from u: the first clockwise
 * from the direction v→u, so each new facet keeps its inside on the left
 * and the loops split at v instead of crossing there. */
static uint32_t pick_out(const cutter *k, const uint32_t *head,
                         const uint32_t *nextedge, uint32_t u, uint32_t v,
                         int drop, int osign)
{
    const double(*P)[3] = (const double(*)[3])k->out->verts;
    uint32_t best = GEO_NONE;
    int best_half = 0;
    for (uint32_t e = head[v]; e != GEO_NONE; e = nextedge[e]) {
        uint32_t w = k->cf.sec[e][1];
        /* half 1: clockwise of v→u within (0, π]; half 2: (π, 2π] */
        int o = osign * geo_orient2d_proj(P[v], P[u], P[w], drop);
        int half;
        if (o < 0)
            half = 1;
        else if (o > 0)
            half = 2;
        else {
            double du[3], dw[3];
            geo_vsub(P[u], P[v], du);
            geo_vsub(P[w], P[v], dw);
            half = geo_vdot(du, dw) < 0 ? 1 : 3; /* straight on / back */
        }
        if (best == GEO_NONE || half < best_half) {
            best = e;
            best_half = half;
            continue;
        }
        if (half == best_half && half < 3) {
            uint32_t bw = k->cf.sec[best][1];
            /* w before bw when w is counter-clockwise of bw, i.e. less
             * far clockwise from v→u */
            if (osign * geo_orient2d_proj(P[v], P[bw], P[w], drop) > 0)
                best = e;
        }
    }
    return best;
}

/* The plane's projection: 2D coordinates of output vertex v, mirrored
 * when the normal points to −drop, so that every new facet turns
 * counter-clockwise (exact copies of the coordinates, no rounding). */
static void plane_xy(const cutter *k, uint32_t v, int drop, int osign,
                     double ret[2])
{
    const double *x = k->out->verts[v];
    int u = (drop + 1) % 3, w = (drop + 2) % 3;
    ret[0] = osign > 0 ? x[u] : x[w];
    ret[1] = osign > 0 ? x[w] : x[u];
}

/* lidx without the on-plane old vertices that lie in exactly one kept
 * facet: on the section's boundary they sit on a straight line between
 * that facet and the new facet, and drop_hanging removes them from the
 * old facet; leaving them out of the region keeps diagonals off them. */
static int leave_out_hanging(const cutter *k, const uint32_t *ids,
                             const uint32_t *loc, uint32_t nl,
                             uint32_t *lstart, uint32_t *lidx, uint32_t nloops)
{
    const geo_poly *o = k->out;
    uint32_t nold = k->p->nverts;
    uint8_t *cnt = calloc((size_t)nl + 1, 1);
    if (!cnt)
        return -ENOMEM;
    uint32_t nc = geo_poly_ncorners(o);
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t v = o->fidx[c];
        if (v < nold && k->side[v] == 0 && loc[v] < nl && ids[loc[v]] == v &&
            cnt[loc[v]] < 2)
            cnt[loc[v]]++;
    }
    uint32_t w = 0;
    for (uint32_t l = 0, b = 0; l < nloops; l++) {
        uint32_t e = lstart[l + 1], s = w, keep = 0;
        for (uint32_t j = b; j < e; j++) {
            uint32_t v = ids[lidx[j]];
            keep += !(v < nold && k->side[v] == 0 && cnt[lidx[j]] == 1);
        }
        for (uint32_t j = b; j < e; j++) {
            uint32_t v = ids[lidx[j]];
            if (keep < 3 || !(v < nold && k->side[v] == 0 && cnt[lidx[j]] == 1))
                lidx[w++] = lidx[j];
        }
        lstart[l] = s;
        b = e;
    }
    lstart[nloops] = w;
    free(cnt);
    return 0;
}

/* Adds the new facets for the traced section loops (lv, lstart): each
 * counter-clockwise loop that passes each point once is one facet; when
 * there is a hole or a loop touching itself, the region is split into
 * simple coplanar facets (lib/cut/region_split.h), decided in the plane's
 * projection with exact orientation signs on the computed vertex
 * positions, and each resulting facet is checked again for simplicity in
 * 3D (lib/inspect/selfint.h). loc: scratch of out->nverts entries. */
static int place_section(cutter *k, const uint32_t *lv, uint32_t *lstart,
                         uint32_t nloops, uint32_t *loc, uint32_t *ret_parts)
{
    uint32_t nlv = lstart[nloops], nl = 0;
    int drop = geo_cutf_dominant_axis(k->unit);
    int osign = k->unit[drop] > 0 ? 1 : -1;
    uint32_t *ids = malloc(((size_t)nlv + 1) * sizeof *ids);
    uint32_t *lidx = malloc(((size_t)nlv + 1) * sizeof *lidx);
    double(*xy)[2] = malloc(((size_t)nlv + 1) * sizeof *xy);
    double *perr = malloc(((size_t)nlv + 1) * sizeof *perr);
    geo_region_pieces pc;
    memset(&pc, 0, sizeof pc);
    int r = 0;
    if (!ids || !lidx || !xy || !perr) {
        r = geo_err_set(k->err, -ENOMEM, "out of memory");
        goto done;
    }
    for (uint32_t i = 0; i < nlv; i++)
        loc[lv[i]] = GEO_NONE;
    for (uint32_t i = 0; i < nlv; i++) {
        uint32_t v = lv[i];
        if (loc[v] == GEO_NONE) {
            loc[v] = nl;
            ids[nl] = v;
            plane_xy(k, v, drop, osign, xy[nl]);
            perr[nl] = v < k->p->nverts ? onplane_bound(k, v)
                                        : k->xerr[v - k->p->nverts];
            nl++;
        }
        lidx[i] = loc[v];
    }
    int need = geo_region_needs_split((const double(*)[2])xy, nl, lstart,
                                      lidx, nloops);
    if (need < 0) {
        r = geo_err_set(k->err, -ENOMEM, "out of memory");
        goto done;
    }
    if (!need) {
        for (uint32_t l = 0; l < nloops; l++) {
            int64_t f = geo_poly_add_facet(k->out, lv + lstart[l],
                                           lstart[l + 1] - lstart[l]);
            if (f < 0) {
                r = geo_err_set(k->err, (int)f, "out of memory adding a facet");
                goto done;
            }
            memcpy(k->out->planes[f], k->unit, sizeof k->unit);
        }
        *ret_parts = nloops;
        goto done;
    }
    if (k->drop_hanging &&
        leave_out_hanging(k, ids, loc, nl, lstart, lidx, nloops) < 0) {
        r = geo_err_set(k->err, -ENOMEM, "out of memory");
        goto done;
    }
    r = geo_region_split((const double(*)[2])xy, perr, nl, lstart, lidx,
                         nloops, &pc, k->err);
    if (r < 0) {
        geo_err_prefix(k->err, "section");
        goto done;
    }
    for (uint32_t q = 0; q < pc.npieces; q++) {
        uint32_t n = pc.start[q + 1] - pc.start[q];
        uint32_t *v = pc.idx + pc.start[q];
        for (uint32_t j = 0; j < n; j++)
            v[j] = ids[v[j]];
        int64_t f = geo_poly_add_facet(k->out, v, n);
        if (f < 0) {
            r = geo_err_set(k->err, (int)f, "out of memory adding a facet");
            goto done;
        }
        memcpy(k->out->planes[f], k->unit, sizeof k->unit);
        geo_facet_shape sh;
        geo_facet_shape_of(k->out, (uint32_t)f, &sh);
        double area[3];
        geo_poly_facet_area_vector(k->out, (uint32_t)f, area);
        if (sh.degenerate || geo_facet_self_intersects(k->out, (uint32_t)f, &sh) ||
            !(geo_vdot(area, k->unit) > 0)) {
            r = geo_err_set(k->err, -ENOTSUP,
                            "section: component %u, split because of a hole "
                            "or a point it touches itself at, gives a facet "
                            "that is not a simple polygon once its vertices "
                            "are rounded; move the plane a little (change "
                            "plane[3] by 1e-6 of the model's size)", pc.part[q]);
            goto done;
        }
    }
    *ret_parts = pc.nparts;
done:
    geo_region_pieces_clear(&pc);
    free(ids), free(lidx), free(xy), free(perr);
    return r;
}

static int build_section(cutter *k, uint32_t *ret_components)
{
    uint32_t nv = k->out->nverts;
    size_t m = k->cf.nsec;
    uint32_t *head = malloc(((size_t)nv + 1) * sizeof *head);
    uint32_t *nextedge = malloc((m + 1) * sizeof *nextedge);
    uint32_t *outdeg = calloc((size_t)nv + 1, sizeof *outdeg);
    uint8_t *used = calloc(m + 1, 1);
    uint32_t *lv = malloc((m + 1) * sizeof *lv);
    uint32_t *lstart = malloc((m + 2) * sizeof *lstart);
    int r = 0;
    if (!head || !nextedge || !outdeg || !used || !lv || !lstart) {
        r = geo_err_set(k->err, -ENOMEM, "out of memory building the section");
        goto done;
    }
    if (m > UINT32_MAX / 2) {
        r = geo_err_set(k->err, -EINVAL, "section: too many edges");
        goto done;
    }
    for (uint32_t v = 0; v < nv; v++)
        head[v] = GEO_NONE;
    for (size_t e = m; e-- > 0;) {
        uint32_t a = k->cf.sec[e][0];
        nextedge[e] = head[a];
        head[a] = (uint32_t)e;
        outdeg[a]++;
    }
    int drop = geo_cutf_dominant_axis(k->unit);
    int osign = k->unit[drop] > 0 ? 1 : -1;
    uint32_t nloops = 0, nlv = 0;
    lstart[0] = 0;
    for (size_t e0 = 0; e0 < m; e0++) {
        if (used[e0])
            continue;
        uint32_t len = 0;
        size_t e = e0;
        for (;;) {
            used[e] = 1;
            lv[nlv + len++] = k->cf.sec[e][0];
            uint32_t u = k->cf.sec[e][0], v = k->cf.sec[e][1];
            uint32_t nx = outdeg[v] == 1 ? head[v]
                        : outdeg[v] == 0 ? GEO_NONE
                        : pick_out(k, head, nextedge, u, v, drop, osign);
            if (nx == GEO_NONE) {
                r = geo_err_set(k->err, -EINVAL,
                                "section: the boundary of a new facet does "
                                "not close at vertex %u", v);
                goto done;
            }
            if (nx == e0)
                break;
            if (used[nx]) {
                r = geo_err_set(k->err, -EINVAL,
                                "section: the boundary of a new facet runs "
                                "into itself at vertex %u", v);
                goto done;
            }
            e = nx;
        }
        if (len < 3) {
            r = geo_err_set(k->err, -EINVAL,
                            "section: a component with %u vertices", len);
            goto done;
        }
        nlv += len;
        lstart[++nloops] = nlv;
    }
    /* head is free now: it serves as the vertex → local index map */
    r = place_section(k, lv, lstart, nloops, head, ret_components);
done:
    free(head), free(nextedge), free(outdeg), free(used), free(lv), free(lstart);
    return r;
}

/* Edges of the model lying in the plane whose facet is kept along them
 * become edges of the section unless the facet across is kept there too
 * (then the edge stays between those two facets; when that edge is reflex
 * the kept solid would pinch along it: refused). */
static int inplane_edges(cutter *k)
{
    const geo_poly *p = k->p;
    for (size_t i = 0; i < k->nkin; i++) {
        uint32_t c = k->kin[i], m = k->t->mate[c];
        uint32_t a = p->fidx[c], b = p->fidx[geo_topo_next(p, k->t, c)];
        if (!k->kept_inplane[m]) {
            int r = geo_cutf_push_section(&k->cf, b, a);
            if (r < 0)
                return r;
            continue;
        }
        if (c > m)
            continue;
        /* the lowest vertex of each facet: on its inner side of the edge */
        const double *lowest[2] = {NULL, NULL};
        uint32_t fs[2] = {k->t->corner_facet[c], k->t->corner_facet[m]};
        for (int s = 0; s < 2; s++) {
            double best = 0;
            uint32_t nv = geo_poly_facet_size(p, fs[s]);
            const uint32_t *vs = geo_poly_facet(p, fs[s]);
            for (uint32_t j = 0; j < nv; j++) {
                double h = geo_plane_eval(k->plane, p->verts[vs[j]]);
                if (k->side[vs[j]] < 0 && (!lowest[s] || h < best)) {
                    lowest[s] = p->verts[vs[j]];
                    best = h;
                }
            }
        }
        if (lowest[0] && lowest[1] &&
            geo_orient3d(p->verts[a], p->verts[b], lowest[0], lowest[1]) > 0)
            return geo_err_set(k->err, -ENOTSUP,
                               "facets[%u]: the plane touches the reflex "
                               "edge %u-%u from inside: the kept part would "
                               "be two pieces meeting only along that edge, "
                               "which no valid polyhedron represents; move "
                               "the plane a little, e.g. by 1e-6 of the "
                               "model's size (a larger plane[3] separates "
                               "the pieces, a smaller one keeps them "
                               "joined)", fs[0], a, b);
    }
    return 0;
}

/* A vertex on the plane whose neighbours all lie on the kept side is the
 * apex of a cone below the plane: of the solid (a peak: the new facets
 * keep away from it) or of a cavity (the solid lies above it, and a new
 * facet would pass over the apex, touching it). The latter is refused.
 * Inside is decided by the winding number of each new facet around the
 * apex in the plane's projection, with exact orientation signs. */
static int check_cavity_apexes(cutter *k, uint32_t first_new)
{
    const geo_poly *p = k->p;
    const geo_topo *t = k->t;
    const geo_poly *o = k->out;
    int drop = geo_cutf_dominant_axis(k->unit);
    int u = (drop + 1) % 3, w = (drop + 2) % 3;
    for (uint32_t v = 0; v < p->nverts; v++) {
        if (k->side[v] != 0 || t->vstart[v] == t->vstart[v + 1])
            continue;
        bool apex = true;
        for (uint32_t i = t->vstart[v]; i < t->vstart[v + 1] && apex; i++) {
            uint32_t c = t->vcorners[i];
            apex = k->side[p->fidx[geo_topo_next(p, t, c)]] < 0 &&
                   k->side[p->fidx[geo_topo_prev(p, t, c)]] < 0;
        }
        if (!apex)
            continue;
        const double *q = p->verts[v];
        for (uint32_t f = first_new; f < o->nfacets; f++) {
            uint32_t n = geo_poly_facet_size(o, f);
            const uint32_t *vs = geo_poly_facet(o, f);
            bool vertex_of_f = false;
            for (uint32_t j = 0; j < n; j++)
                vertex_of_f |= vs[j] == v;
            if (vertex_of_f)
                continue;
            int wn = 0;
            bool on = false;
            for (uint32_t j = 0; j < n && !on; j++) {
                const double *a = o->verts[vs[j]];
                const double *b = o->verts[vs[j + 1 < n ? j + 1 : 0]];
                int s = geo_orient2d_proj(a, b, q, drop);
                if (s == 0 && fmin(a[u], b[u]) <= q[u] && q[u] <= fmax(a[u], b[u]) &&
                    fmin(a[w], b[w]) <= q[w] && q[w] <= fmax(a[w], b[w]))
                    on = true;
                else if (a[w] <= q[w] && b[w] > q[w] && s > 0)
                    wn++;
                else if (a[w] > q[w] && b[w] <= q[w] && s < 0)
                    wn--;
            }
            if (on || wn != 0)
                return geo_err_set(k->err, -ENOTSUP,
                                   "vertices[%u]: the plane touches the apex "
                                   "of a cavity from inside: the cavity would "
                                   "meet the new facet in that one point, "
                                   "which no valid polyhedron represents; "
                                   "move the plane a little, e.g. by 1e-6 of "
                                   "the model's size (a larger plane[3] opens "
                                   "the cavity into a hole of the section, a "
                                   "smaller one keeps it closed)", v);
        }
    }
    return 0;
}

/* Removes on-plane vertices left in exactly two facets (they lie on the
 * straight edge between those two), or in one (left out of a split
 * section by leave_out_hanging: they lie on the edge that facet shares
 * with a new facet). Returns the count or -EINVAL. */
static int64_t drop_hanging(cutter *k)
{
    geo_poly *o = k->out;
    uint32_t nold = k->p->nverts;
    uint8_t *cnt = calloc((size_t)nold + 1, 1);
    if (!cnt)
        return -ENOMEM;
    uint32_t nc = geo_poly_ncorners(o);
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t v = o->fidx[c];
        if (v < nold && k->side[v] == 0 && cnt[v] < 3)
            cnt[v]++;
    }
    int64_t dropped = 0;
    for (uint32_t v = 0; v < nold; v++)
        if (cnt[v] == 1 || cnt[v] == 2)
            dropped++;
    if (dropped == 0) {
        free(cnt);
        return 0;
    }
    uint32_t w = 0;
    for (uint32_t f = 0; f < o->nfacets; f++) {
        uint32_t s = o->fstart[f], e = o->fstart[f + 1], start = w;
        for (uint32_t c = s; c < e; c++) {
            uint32_t v = o->fidx[c];
            if (v < nold && (cnt[v] == 1 || cnt[v] == 2))
                continue;
            o->fidx[w++] = v;
        }
        o->fstart[f] = start;
        if (w - start < 3) {
            free(cnt);
            return geo_err_set(k->err, -EINVAL,
                               "result facet %u degenerates when its "
                               "hanging vertices are removed", f);
        }
    }
    o->fstart[o->nfacets] = w;
    free(cnt);
    return dropped;
}

typedef struct wedge {
    uint32_t v, prev, next; /* a facet's corner at v and its neighbours */
} wedge;

static int cmp_wedge(const void *a, const void *b)
{
    const wedge *x = a, *y = b;
    if (x->v != y->v)
        return x->v < y->v ? -1 : 1;
    if (x->prev != y->prev)
        return x->prev < y->prev ? -1 : 1;
    return (x->next > y->next) - (x->next < y->next);
}

/* Only vertices on the plane can lose part of their fan; each must still
 * have its facets in one closed fan (the facet after the one with edge
 * v→n is the one with edge n→v). Two fans mean the kept part touches
 * itself at the vertex (e.g. a saddle vertex on the plane): refused. */
static int check_plane_fans(cutter *k)
{
    const geo_poly *o = k->out;
    uint32_t nold = k->p->nverts;
    size_t n = 0, cap = 0;
    wedge *w = NULL;
    for (uint32_t f = 0; f < o->nfacets; f++) {
        uint32_t s = o->fstart[f], e = o->fstart[f + 1];
        for (uint32_t c = s; c < e; c++) {
            uint32_t v = o->fidx[c];
            if (v >= nold || k->side[v] != 0)
                continue;
            if (geo_grow((void **)&w, &cap, n + 1, sizeof *w) < 0) {
                free(w);
                return geo_err_set(k->err, -ENOMEM, "out of memory");
            }
            w[n].v = v;
            w[n].prev = o->fidx[c > s ? c - 1 : e - 1];
            w[n].next = o->fidx[c + 1 < e ? c + 1 : s];
            n++;
        }
    }
    if (n == 0)
        return 0;
    qsort(w, n, sizeof *w, cmp_wedge);
    int r = 0;
    for (size_t a = 0; a < n && r == 0;) {
        size_t b = a;
        while (b < n && w[b].v == w[a].v)
            b++;
        /* walk the fan from the first wedge; it must visit all b − a */
        size_t steps = 0;
        uint32_t want = w[a].next;
        do {
            size_t x = a;
            while (x < b && w[x].prev != want)
                x++;
            if (x == b)
                break;
            want = w[x].next;
            steps++;
        } while (want != w[a].next && steps <= b - a);
        if (steps != b - a || want != w[a].next)
            r = geo_err_set(k->err, -ENOTSUP,
                            "vertices[%u]: the kept part would touch itself "
                            "at this vertex on the plane (two parts meeting "
                            "in one point), which no valid polyhedron "
                            "represents; move the plane a little, e.g. by "
                            "1e-6 of the model's size (a larger plane[3] "
                            "separates the parts, a smaller one joins them)", w[a].v);
        a = b;
    }
    free(w);
    return r;
}

void geo_cut_opts_default(geo_cut_opts *opts)
{
    opts->main_facet = GEO_NONE;
    opts->topo = NULL;
    opts->drop_hanging = true;
}

static int check_input(const geo_poly *p, const double plane[4],
                       const geo_cut_opts *o, geo_err *err)
{
    for (int j = 0; j < 4; j++)
        if (!isfinite(plane[j]))
            return geo_err_set(err, -EINVAL, "plane[%d]: not a finite number", j);
    if (plane[0] == 0 && plane[1] == 0 && plane[2] == 0)
        return geo_err_set(err, -EINVAL, "plane: the normal (a, b, c) is zero");
    if (!isfinite(geo_vlen(plane)) || !(geo_vlen(plane) > 0))
        return geo_err_set(err, -EINVAL, "plane: the normal cannot be normalised");
    if (o->main_facet != GEO_NONE && o->main_facet >= p->nfacets)
        return geo_err_set(err, -EINVAL, "main facet %u out of range (%u facets)",
                           o->main_facet, p->nfacets);
    return geo_poly_validate_indices(p, err);
}

int geo_cut(const geo_poly *p, const double plane[4],
            const geo_cut_opts *opts, const geo_ctx *ctx, geo_poly *out,
            geo_cut_report *rep, geo_err *err)
{
    geo_cut_opts o;
    if (opts)
        o = *opts;
    else
        geo_cut_opts_default(&o);
    geo_cut_report rp;
    memset(&rp, 0, sizeof rp);
    rp.first_new_facet = GEO_NONE;
    geo_poly_clear(out);
    int r = check_input(p, plane, &o, err);
    if (r < 0)
        return r;

    cutter k;
    memset(&k, 0, sizeof k);
    k.p = p;
    k.plane = plane;
    k.drop_hanging = o.drop_hanging;
    k.out = out;
    k.err = err;
    double len = geo_vlen(plane);
    for (int j = 0; j < 4; j++)
        k.unit[j] = plane[j] / len;
    k.cf.plane = plane;
    k.cf.frame = k.unit;

    geo_topo *own = NULL;
    k.t = o.topo;
    if (!k.t) {
        own = geo_topo_build(p, err);
        if (!own)
            return -ENOMEM;
        k.t = own;
    } else if (k.t->nverts != p->nverts || k.t->ncorners != geo_poly_ncorners(p)) {
        return geo_err_set(err, -EINVAL, "topology does not match the model");
    }
    if (!geo_topo_is_closed_manifold(k.t)) {
        r = geo_err_set(err, -EINVAL,
                        "model is not a closed oriented manifold (%u boundary, "
                        "%u non-manifold, %u flipped edges, %u non-manifold "
                        "vertices)", k.t->nboundary_edges, k.t->nnonmanifold_edges,
                        k.t->nflipped_edges, k.t->nnonmanifold_vertices);
        goto done;
    }

    k.side = malloc((size_t)p->nverts + 1);
    if (!k.side)
        goto oom;
    uint32_t nneg = 0, npos = 0;
    k.on_tol = geo_poly_eps(p) * geo_vlen(plane);
    for (uint32_t v = 0; v < p->nverts; v++) {
        k.side[v] = (int8_t)(fabs(plane_value(plane, p->verts[v])) <= k.on_tol
                                 ? 0
                                 : geo_plane_sign(plane, p->verts[v]));
        if (k.t->vertex_kind[v] == GEO_VERTEX_ISOLATED)
            continue;
        nneg += k.side[v] < 0;
        npos += k.side[v] > 0;
    }
    if (o.main_facet != GEO_NONE) {
        const uint32_t *vs = geo_poly_facet(p, o.main_facet);
        for (uint32_t j = 0; j < geo_poly_facet_size(p, o.main_facet); j++)
            if (k.side[vs[j]] < 0) {
                r = geo_err_set(err, -EINVAL,
                                "facets[%u].vertices[%u]: the main facet has "
                                "a vertex on the kept side of the plane",
                                o.main_facet, j);
                goto done;
            }
    }
    rp.volume_before = geo_poly_volume(p);
    if ((r = geo_ctx_progress(ctx, 0.1)) < 0)
        goto canceled;
    if (npos == 0) {
        rp.unchanged = true;
        if (geo_poly_assign(out, p) < 0)
            goto oom;
        rp.volume_after = rp.volume_before;
        goto done;
    }
    if (nneg == 0) {
        rp.empty = true;
        rp.removed_vertices = p->nverts;
        rp.removed_facets = p->nfacets;
        if (o.main_facet != GEO_NONE) {
            r = geo_err_set(err, -EINVAL, "main facet: the whole model lies "
                            "on the removed side, no section to merge into");
            goto done;
        }
        goto done;
    }

    uint32_t nc = geo_poly_ncorners(p);
    k.xv = malloc(((size_t)nc + 1) * sizeof *k.xv);
    k.kept_inplane = calloc((size_t)nc + 1, 1);
    if (!k.xv || !k.kept_inplane)
        goto oom;
    if (geo_poly_reserve(out, p->nverts, p->nfacets, nc) < 0)
        goto oom;
    memcpy(out->verts, p->verts, (size_t)p->nverts * sizeof *p->verts);
    out->nverts = p->nverts;

    /* one vertex per crossed edge, shared with the mate corner */
    for (uint32_t c = 0; c < nc; c++)
        k.xv[c] = GEO_NONE;
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t a = p->fidx[c], b = p->fidx[geo_topo_next(p, k.t, c)];
        if (k.side[a] * k.side[b] >= 0 || k.xv[c] != GEO_NONE)
            continue;
        double x[3];
        double xe = geo_cutf_crossing_point(k.unit, p->verts[a], p->verts[b], x);
        int64_t id = geo_poly_add_vertex(out, x);
        if (id < 0 || geo_grow((void **)&k.xerr, &k.capxerr, k.new_vertices + 1,
                           sizeof *k.xerr) < 0)
            goto oom;
        k.xerr[k.new_vertices] = xe;
        k.xv[c] = (uint32_t)id;
        k.xv[k.t->mate[c]] = (uint32_t)id;
        k.new_vertices++;
    }
    if ((r = geo_ctx_progress(ctx, 0.3)) < 0)
        goto canceled;

    for (uint32_t f = 0; f < p->nfacets; f++) {
        if ((f & 4095) == 4095 &&
            (r = geo_ctx_progress(ctx, 0.3 + 0.4 * f / p->nfacets)) < 0)
            goto canceled;
        uint32_t n = geo_poly_facet_size(p, f), c0 = p->fstart[f];
        const uint32_t *vs = geo_poly_facet(p, f);
        bool neg = false, pos = false;
        for (uint32_t j = 0; j < n; j++) {
            neg |= k.side[vs[j]] < 0;
            pos |= k.side[vs[j]] > 0;
        }
        if (neg && pos) {
            if ((r = cut_facet(&k, f)) < 0)
                goto done;
        } else if (neg) {
            int64_t g = geo_poly_add_facet(out, vs, n);
            if (g < 0)
                goto oom;
            memcpy(out->planes[g], p->planes[f], sizeof p->planes[f]);
            for (uint32_t j = 0; j < n; j++)
                if (k.side[vs[j]] == 0 && k.side[vs[j + 1 < n ? j + 1 : 0]] == 0 &&
                    push_kin(&k, c0 + j) < 0)
                    goto oom;
        } else {
            /* on the removed side or in the plane: the new facets cover
             * an in-plane facet facing along the normal, and one facing
             * against it bounds only the removed part */
            k.removed_facets++;
        }
    }
    if ((r = inplane_edges(&k)) < 0)
        goto done;
    if ((r = geo_ctx_progress(ctx, 0.75)) < 0)
        goto canceled;

    uint32_t first_new = out->nfacets;
    if ((r = build_section(&k, &rp.components)) < 0)
        goto done;
    rp.new_facets = out->nfacets - first_new;
    if ((r = check_cavity_apexes(&k, first_new)) < 0)
        goto done;
    if (o.main_facet != GEO_NONE && rp.components != 1) {
        r = geo_err_set(err, -EINVAL,
                        "main facet: the section has %u components, the "
                        "merge needs exactly one", rp.components);
        goto done;
    }
    if (o.main_facet != GEO_NONE && rp.new_facets != 1) {
        r = geo_err_set(err, -EINVAL,
                        "main facet: the section has a hole or touches "
                        "itself at a point, so it takes %u facets; the "
                        "merge needs exactly one", rp.new_facets);
        goto done;
    }
    if (o.drop_hanging) {
        int64_t d = drop_hanging(&k);
        if (d < 0) {
            r = (int)d;
            goto done;
        }
        rp.hanging_dropped = (uint32_t)d;
    }
    if ((r = check_plane_fans(&k)) < 0)
        goto done;
    uint32_t *vmap = malloc(((size_t)out->nverts + 1) * sizeof *vmap);
    if (!vmap || geo_poly_compact(out, NULL, vmap, NULL) < 0) {
        free(vmap);
        goto oom;
    }
    for (uint32_t v = 0; v < p->nverts; v++)
        rp.removed_vertices += vmap[v] == GEO_NONE;
    free(vmap);
    rp.first_new_facet = rp.new_facets ? first_new : GEO_NONE;
    rp.split_facets = k.split_facets;
    rp.pieces = k.pieces;
    rp.removed_facets = k.removed_facets;
    rp.new_vertices = k.new_vertices;
    rp.volume_after = geo_poly_volume(out);
    r = geo_ctx_progress(ctx, 1.0);
    if (r < 0)
        goto canceled;
    goto done;

canceled:
    r = geo_err_set(err, -ECANCELED, "cut canceled");
    goto done;
oom:
    r = geo_err_set(err, -ENOMEM, "out of memory");
done:
    if (r < 0) {
        geo_poly_clear(out);
    } else if (rep) {
        *rep = rp;
    }
    free(k.side), free(k.xv), free(k.xerr), free(k.kept_inplane);
    free(k.kin), free(k.fside);
    geo_cutf_free(&k.cf);
    geo_topo_free(own);
    return r;
}
