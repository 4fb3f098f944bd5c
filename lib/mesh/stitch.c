/* stitch.c — Nesterenko's stitching of two open meshes (see stitch.h).
 *
 * Invariants: a loop is kept as its vertex cycle in the direction of its
 * corners (its mesh's facets on the left seen from outside); the two
 * lines of the bridge always run the same way, line X along loop 1 and
 * line Y along loop 2 reversed, so a band facet uses X's edges backwards
 * and Y's forwards; P's entries are indices into the merged output. */
#include "stitch.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "halfspace.h"
#include "predicates.h"
#include "stats.h"
#include "stitch_trim.h"
#include "topo.h"
#include "vec.h"

void geo_stitch_opts_default(geo_stitch_opts *o)
{
    memset(o, 0, sizeof *o);
    geo_mesh_fill_opts_default(&o->fill);
}

const char *geo_stitch_method_name(enum geo_stitch_method m)
{
    return m == GEO_STITCH_PLANES ? "planes" : m == GEO_STITCH_WELD ? "weld"
                                                                    : "band";
}

void geo_stitch_report_clear(geo_stitch_report *rep)
{
    if (!rep)
        return;
    geo_mesh_fill_report_clear(&rep->fill);
    memset(rep, 0, sizeof *rep);
}

typedef struct loop {
    uint32_t *v; /* vertex cycle, along the corners */
    uint32_t *f; /* f[q]: the facet of edge v[q] → v[q + 1] */
    uint32_t n;
    double c[3];  /* centre: the vertex mean, (5) */
    double nw[3]; /* Newell normal (vector area) */
} loop;

typedef struct loops {
    loop *l;
    uint32_t n;
} loops;

static void loops_free(loops *L)
{
    for (uint32_t k = 0; k < L->n; k++)
        free(L->l[k].v), free(L->l[k].f);
    free(L->l);
    L->l = NULL;
    L->n = 0;
}

/* Algorithm 1 for every free-edge polyline of p: its closed loops. */
static int find_loops(const geo_poly *p, loops *ret, geo_err *err)
{
    geo_topo *t = geo_topo_build(p, err);
    uint32_t *ls = NULL, *lc = NULL, nl = 0;
    int rc = -ENOMEM;
    if (!t || geo_topo_boundary_loops(p, t, &ls, &lc, &nl) < 0)
        goto out;
    ret->l = calloc((size_t)nl + 1, sizeof *ret->l);
    if (!ret->l)
        goto out;
    for (uint32_t k = 0; k < nl; k++) {
        uint32_t n = ls[k + 1] - ls[k];
        const uint32_t *c = lc + ls[k];
        bool closed = n >= 3;
        for (uint32_t q = 0; q < n && closed; q++)
            closed = p->fidx[geo_topo_next(p, t, c[q])] ==
                     p->fidx[c[(q + 1) % n]];
        if (!closed)
            continue;
        loop *L = &ret->l[ret->n];
        L->v = malloc((size_t)n * sizeof *L->v);
        L->f = malloc((size_t)n * sizeof *L->f);
        ret->n++;
        if (!L->v || !L->f)
            goto out;
        L->n = n;
        memset(L->c, 0, sizeof L->c);
        memset(L->nw, 0, sizeof L->nw);
        for (uint32_t q = 0; q < n; q++) {
            L->v[q] = p->fidx[c[q]];
            L->f[q] = t->corner_facet[c[q]];
            geo_vadd(L->c, p->verts[L->v[q]], L->c);
        }
        geo_vscale(L->c, 1.0 / n, L->c);
        for (uint32_t q = 0; q < n; q++) {
            const double *a = p->verts[L->v[q]], *b = p->verts[L->v[(q + 1) % n]];
            L->nw[0] += (a[1] - b[1]) * (a[2] + b[2]);
            L->nw[1] += (a[2] - b[2]) * (a[0] + b[0]);
            L->nw[2] += (a[0] - b[0]) * (a[1] + b[1]);
        }
    }
    rc = 0;
out:
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory finding free edges");
    geo_topo_free(t);
    free(ls), free(lc);
    return rc;
}

/* The longest run of consecutive kept vertices of loop L (cyclically),
 * written to ret (in loop order); returns its length. */
static uint32_t longest_run(const loop *L, const uint8_t *keep, uint32_t *ret)
{
    uint32_t n = L->n, best = 0, bstart = 0, first_out = n;
    for (uint32_t k = 0; k < n; k++)
        if (!keep[k]) {
            first_out = k;
            break;
        }
    if (first_out == n) { /* all kept */
        memcpy(ret, L->v, (size_t)n * sizeof *ret);
        return n;
    }
    uint32_t run = 0, rs = 0;
    for (uint32_t q = 1; q <= n; q++) {
        uint32_t k = (first_out + q) % n;
        if (keep[k]) {
            if (run == 0)
                rs = k;
            run++;
            if (run > best) {
                best = run;
                bstart = rs;
            }
        } else {
            run = 0;
        }
    }
    for (uint32_t q = 0; q < best; q++)
        ret[q] = L->v[(bstart + q) % n];
    return best;
}

/* Algorithm 2 keeps whole half-loops; where a half-loop runs towards the
 * other mesh (along the rim of a surface cut in two) its vertices are not
 * facing anything and straight meridians from them would fold. The arc
 * is trimmed from both ends while the end vertex is more than twice as
 * far from the other arc as the arc's median vertex is (the paper's
 * intent: join the vertices spatially nearest each other). */
static void trim_arc(const geo_poly *pa, uint32_t *arc, uint32_t *n,
                     const geo_poly *pb, const uint32_t *other, uint32_t m)
{
    uint32_t k = *n;
    double *d = malloc((size_t)k * sizeof *d), *sorted = malloc((size_t)k * sizeof *d);
    if (!d || !sorted || k < 3) {
        free(d), free(sorted);
        return;
    }
    for (uint32_t i = 0; i < k; i++) {
        double best = INFINITY;
        for (uint32_t j = 0; j < m; j++) {
            double x = geo_vdist(pa->verts[arc[i]], pb->verts[other[j]]);
            best = x < best ? x : best;
        }
        d[i] = sorted[i] = best;
    }
    /* the median by partial selection sort is enough for loop sizes */
    for (uint32_t i = 0; i <= k / 2; i++)
        for (uint32_t j = i + 1; j < k; j++)
            if (sorted[j] < sorted[i]) {
                double t = sorted[i];
                sorted[i] = sorted[j];
                sorted[j] = t;
            }
    double lim = 2.0 * sorted[k / 2];
    uint32_t lo = 0, hi = k;
    while (hi - lo > 2 && d[lo] > lim)
        lo++;
    while (hi - lo > 2 && d[hi - 1] > lim)
        hi--;
    memmove(arc, arc + lo, (size_t)(hi - lo) * sizeof *arc);
    *n = hi - lo;
    free(d), free(sorted);
}

static double mean_edge(const geo_poly *p, uint64_t *count)
{
    double s = 0;
    uint64_t n = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        uint32_t k = geo_poly_facet_size(p, f);
        for (uint32_t i = 0; i < k; i++, n++)
            s += geo_vdist(p->verts[fv[i]], p->verts[fv[(i + 1) % k]]);
    }
    *count = n;
    return s;
}

/* The centre of loop l of p weighted by edge length (the edges'
 * midpoints); the vertex mean when the loop has no length. */
static void loop_centroid(const geo_poly *p, const loop *l, double ret[3])
{
    double sum = 0, c[3] = {0, 0, 0};
    for (uint32_t k = 0; k < l->n; k++) {
        const double *a = p->verts[l->v[k]], *b = p->verts[l->v[(k + 1) % l->n]];
        double w = geo_vdist(a, b);
        for (int d = 0; d < 3; d++)
            c[d] += w * 0.5 * (a[d] + b[d]);
        sum += w;
    }
    if (sum > 0)
        geo_vscale(c, 1.0 / sum, ret);
    else
        memcpy(ret, l->c, sizeof c);
}

/* Arc-length positions, 0 to 1, of the npts points L[(k + shift) % n] of
 * a line (a closed band's line repeats its first point last). */
static void line_arcs(const geo_poly *out, const uint32_t *L, uint32_t n,
                      uint32_t npts, uint32_t shift, double *s)
{
    s[0] = 0;
    for (uint32_t k = 1; k < npts; k++)
        s[k] = s[k - 1] + geo_vdist(out->verts[L[(k - 1 + shift) % n]],
                                    out->verts[L[(k + shift) % n]]);
    double total = npts > 1 ? s[npts - 1] : 0;
    for (uint32_t k = 1; k < npts; k++)
        s[k] = total > 0 ? s[k] / total : (double)k / (npts - 1);
}

/* H by arc length: the B end of each of the na meridians, j starting at
 * 0, ending at nb − 1, never falling and rising by at most one per
 * meridian (the band's facets need that), stepping when the next B
 * point lies nearer A_i's arc position or when the steps left require
 * it. Lines sampled unevenly (a cut through many small facets on one
 * side) are matched by where the points lie, not by their rank. */
static void meridians_arc(const double *sa, uint32_t na, const double *sb,
                          uint32_t nb, uint32_t *jof)
{
    uint32_t j = 0;
    jof[0] = 0;
    for (uint32_t i = 1; i < na; i++) {
        uint32_t need = nb - 1 - j, left = na - 1 - i;
        bool step = need > 0 &&
                    (need > left || fabs(sb[j + 1] - sa[i]) < fabs(sb[j] - sa[i]));
        j += step;
        jof[i] = j;
    }
}

/* Step 5a: lines of equal length whose meridians (one per vertex, the
 * identity when N = M) are all within tol long — the two halves of one
 * cut — are one curve: a band of zero width would be zero-area facets.
 * Appends the pairs (A_c, B_c) to (wa, wb, *nw) and returns true; returns
 * false, appending nothing, when any meridian is longer. */
static bool lines_coincide(const geo_poly *out, const uint32_t *A,
                           const uint32_t *B, uint32_t n, const uint32_t *jof,
                           uint32_t twist, double tol, uint32_t *wa,
                           uint32_t *wb, uint32_t *nw)
{
    for (uint32_t c = 0; c < n; c++)
        if (jof[c] != c ||
            geo_vdist(out->verts[A[c]], out->verts[B[(c + twist) % n]]) > tol)
            return false;
    for (uint32_t c = 0; c < n; c++) {
        wa[*nw] = A[c];
        wb[*nw] = B[(c + twist) % n];
        ++*nw;
    }
    return true;
}

/* Another pair of loops that coincide (a body cut by a plane into halves
 * with several loops each, such as a torus cut across its hole): loop a
 * of mesh 1 and loop b of mesh 2 (indices in out, b in the direction it
 * has as merged) of equal length, b running the other way along the same
 * points within tol. Appends the pairs as lines_coincide. */
static bool loops_coincide(const geo_poly *out, const uint32_t *a,
                           const uint32_t *b, uint32_t n, double tol,
                           uint32_t *wa, uint32_t *wb, uint32_t *nw)
{
    uint32_t s = 0;
    double best = INFINITY;
    for (uint32_t k = 0; k < n; k++) {
        double d = geo_vdist(out->verts[a[0]], out->verts[b[k]]);
        if (d < best) {
            best = d;
            s = k;
        }
    }
    for (uint32_t i = 0; i < n; i++)
        if (geo_vdist(out->verts[a[i]], out->verts[b[(s + n - i) % n]]) > tol)
            return false;
    for (uint32_t i = 0; i < n; i++) {
        wa[*nw] = a[i];
        wb[*nw] = b[(s + n - i) % n];
        ++*nw;
    }
    return true;
}

/* Welds the pairs: mesh 2's vertex wb[k] is replaced by mesh 1's wa[k] in
 * every facet (mesh 2's facets, from f2 on, get their planes refitted)
 * and dropped, the later vertices moving down in order. 0 or -ENOMEM
 * (out unchanged). */
static int weld(geo_poly *out, uint32_t f2, const uint32_t *wa,
                const uint32_t *wb, uint32_t nw)
{
    uint32_t *to = malloc((size_t)out->nverts * sizeof *to);
    uint8_t *gone = calloc(out->nverts, 1);
    if (!to || !gone) {
        free(to), free(gone);
        return -ENOMEM;
    }
    for (uint32_t k = 0; k < nw; k++)
        gone[wb[k]] = 1;
    uint32_t nv = 0;
    for (uint32_t v = 0; v < out->nverts; v++)
        if (!gone[v]) {
            memmove(out->verts[nv], out->verts[v], sizeof out->verts[0]);
            to[v] = nv++;
        }
    for (uint32_t k = 0; k < nw; k++)
        to[wb[k]] = to[wa[k]];
    out->nverts = nv;
    for (uint32_t f = 0; f < out->nfacets; f++) {
        uint32_t *fv = out->fidx + out->fstart[f];
        bool moved = false;
        for (uint32_t i = 0; i < geo_poly_facet_size(out, f); i++) {
            moved |= gone[fv[i]];
            fv[i] = to[fv[i]];
        }
        if (moved && f >= f2)
            geo_poly_facet_fit_plane(out, f, GEO_PLANE_UNWEIGHTED,
                                     out->planes[f]);
    }
    free(to), free(gone);
    return 0;
}

/* Step 5b: the gap rebuilt from the facet planes along the loops. */

/* A loop as merged into out: vertices, and the facet of each edge
 * v[q] → v[q + 1] (that facet's own edge). */
typedef struct rim {
    uint32_t *v, *f;
    uint32_t n;
} rim;

/* Planes of facets along the loops closer than this are one plane (with
 * the edge's ends on it): pieces of one facet on both sides of a cut. */
#define PLANE_MERGE_DEG 0.05

/* The plane of the rn vertices rv of pr (Newell normal through their
 * mean), signed so that the other loop (ov of po) lies on its negative
 * side: the slab's wall at the first loop. False when that loop is off
 * the plane by more than tol, or the other is not wholly
 * on the negative side (exact signs) and farther than tol from it (no
 * gap between the loops, or one too thin to close). */
static bool cap_plane(const geo_poly *pr, const uint32_t *rv, uint32_t rn,
                      const geo_poly *po, const uint32_t *ov, uint32_t on,
                      double tol, double pl[4])
{
    double oc[3] = {0, 0, 0};
    for (uint32_t q = 0; q < on; q++)
        geo_vmadd(oc, 1.0 / on, po->verts[ov[q]], oc);
    if (!geo_loop_plane(pr, rv, rn, pl))
        return false;
    if (geo_plane_eval(pl, oc) > 0)
        for (int k = 0; k < 4; k++)
            pl[k] = -pl[k];
    for (uint32_t q = 0; q < rn; q++)
        if (fabs(geo_plane_eval(pl, pr->verts[rv[q]])) > tol)
            return false;
    for (uint32_t q = 0; q < on; q++) {
        const double *x = po->verts[ov[q]];
        if (geo_plane_sign(pl, x) >= 0 || !(fabs(geo_plane_eval(pl, x)) > tol))
            return false;
    }
    return true;
}

/* Appends to pl (*n planes of 4) the plane of each of r's edge facets
 * unless one there agrees (normals within PLANE_MERGE_DEG and the edge's
 * ends within eps of it). False when an edge is off its own facet's
 * plane by more than eps (a facet whose plane does not continue it). */
static bool rim_planes(const geo_poly *out, const rim *r, double eps,
                       double *pl, uint32_t *n)
{
    double cosmax = cos(PLANE_MERGE_DEG * M_PI / 180);
    for (uint32_t q = 0; q < r->n; q++) {
        const double *a = out->verts[r->v[q]], *b = out->verts[r->v[(q + 1) % r->n]];
        const double *fp = out->planes[r->f[q]];
        if (!(fabs(geo_plane_eval(fp, a)) <= eps && fabs(geo_plane_eval(fp, b)) <= eps))
            return false;
        bool have = false;
        for (uint32_t k = 0; k < *n && !have; k++) {
            const double *e = pl + 4 * (size_t)k;
            have = geo_vdot(e, fp) >= cosmax &&
                   fabs(geo_plane_eval(e, a)) <= eps &&
                   fabs(geo_plane_eval(e, b)) <= eps;
        }
        if (!have)
            memcpy(pl + 4 * (size_t)(*n)++, fp, 4 * sizeof *fp);
    }
    return true;
}

static double seg_dist(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], x[3];
    geo_vsub(b, a, ab);
    geo_vsub(p, a, ap);
    double l2 = geo_vdot(ab, ab), t = l2 > 0 ? geo_vdot(ap, ab) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    geo_vmadd(a, t, ab, x);
    return geo_vdist(p, x);
}

/* Matches the cap facet C of g to rim r: every corner within tol of a
 * rim vertex (pos[corner] its position on r), each edge a → b of C the
 * run of r forwards from a's vertex to b's (C, seen from outside g, runs
 * like the half's facets along the loop), every vertex of the run within
 * tol of the segment ab, the runs covering r exactly once. */
static bool match_cap(const geo_poly *out, const geo_poly *g, uint32_t C,
                      const rim *r, double tol, uint32_t *pos)
{
    const uint32_t *cv = geo_poly_facet(g, C);
    uint32_t k = geo_poly_facet_size(g, C);
    for (uint32_t i = 0; i < k; i++) {
        double best = INFINITY;
        for (uint32_t q = 0; q < r->n; q++) {
            double d = geo_vdist(g->verts[cv[i]], out->verts[r->v[q]]);
            if (d < best) {
                best = d;
                pos[cv[i]] = q;
            }
        }
        if (!(best <= tol))
            return false;
    }
    uint64_t covered = 0;
    for (uint32_t i = 0; i < k; i++) {
        uint32_t pa = pos[cv[i]], pb = pos[cv[(i + 1) % k]];
        uint32_t steps = (pb + r->n - pa) % r->n;
        if (steps == 0)
            return false;
        covered += steps;
        for (uint32_t s = 1; s < steps; s++)
            if (!(seg_dist(out->verts[r->v[(pa + s) % r->n]], g->verts[cv[i]],
                           g->verts[cv[(i + 1) % k]]) <= tol))
                return false;
    }
    return covered == r->n;
}

/* The gap between rims r[0] and r[1] as the intersection of the slab
 * between them with the half-spaces of the facet planes along both, its
 * walls dropped and its side facets joined to the loops (each wall
 * corner replaced by its loop vertex, each wall edge by its run of loop
 * vertices). Appended to p: new vertices and facets. Returns 1 when
 * built, 0 when the construction does not apply (p unchanged: loops not
 * planar, no gap, an edge off its facet's plane, walls that are not the
 * loops — a pair not convex about the gap), -ENOMEM. */
static int gap_from_planes(geo_poly *p, const rim r[2], uint32_t *ret_planes,
                           uint32_t *ret_nv, uint32_t *ret_nf)
{
    double eps = geo_poly_eps(p), near = 1e3 * eps;
    uint32_t np = 0, nmax = r[0].n + r[1].n + 2;
    double *pl = malloc((size_t)nmax * 4 * sizeof *pl);
    geo_poly *g = NULL;
    uint32_t *src = NULL, *pos = NULL, *map = NULL, *fv = NULL;
    uint8_t *wall = NULL; /* the rim a gap vertex lies on: 1, 2, or 0 */
    int rc = -ENOMEM;
    if (!pl)
        goto out;
    rc = 0;
    if (!rim_planes(p, &r[0], eps, pl, &np) || !rim_planes(p, &r[1], eps, pl, &np))
        goto out;
    uint32_t nside = np;
    if (!cap_plane(p, r[0].v, r[0].n, p, r[1].v, r[1].n, near, pl + 4 * (size_t)np++) ||
        !cap_plane(p, r[1].v, r[1].n, p, r[0].v, r[0].n, near, pl + 4 * (size_t)np++))
        goto out;
    enum geo_halfspace_status st;
    geo_err herr = {{0}};
    int h = geo_halfspace_intersect(pl, np, 0.5 * eps, &g, &src, &st, &herr);
    if (h == -ENOMEM)
        rc = -ENOMEM;
    if (h < 0)
        goto out;
    rc = -ENOMEM;
    pos = malloc((size_t)g->nverts * sizeof *pos);
    map = malloc((size_t)g->nverts * sizeof *map);
    wall = calloc(g->nverts, 1);
    if (!pos || !map || !wall)
        goto out;
    rc = 0;
    uint32_t caps[2] = {GEO_NONE, GEO_NONE};
    for (uint32_t f = 0; f < g->nfacets; f++)
        if (src[f] >= nside)
            caps[src[f] - nside] = f;
    if (caps[0] == GEO_NONE || caps[1] == GEO_NONE)
        goto out;
    bool ok = true;
    for (int w = 0; w < 2 && ok; w++) {
        ok = match_cap(p, g, caps[w], &r[w], near, pos);
        const uint32_t *cv = geo_poly_facet(g, caps[w]);
        for (uint32_t i = 0; i < geo_poly_facet_size(g, caps[w]) && ok; i++) {
            ok = wall[cv[i]] == 0; /* a corner on both walls: no gap */
            wall[cv[i]] = (uint8_t)(w + 1);
            map[cv[i]] = r[w].v[pos[cv[i]]];
        }
    }
    if (!ok)
        goto out;
    /* fits: append the gap's own vertices, then its side facets */
    rc = -ENOMEM;
    size_t ncorner = geo_poly_ncorners(g) + r[0].n + r[1].n;
    if (!(fv = malloc(ncorner * sizeof *fv)) ||
        geo_poly_reserve(p, (size_t)p->nverts + g->nverts,
                         (size_t)p->nfacets + g->nfacets,
                         geo_poly_ncorners(p) + ncorner) < 0)
        goto out;
    uint32_t nv = 0, nf = 0;
    for (uint32_t v = 0; v < g->nverts; v++)
        if (!wall[v]) {
            map[v] = (uint32_t)geo_poly_add_vertex(p, g->verts[v]);
            nv++;
        }
    for (uint32_t f = 0; f < g->nfacets; f++) {
        if (f == caps[0] || f == caps[1])
            continue;
        const uint32_t *gv = geo_poly_facet(g, f);
        uint32_t k = geo_poly_facet_size(g, f), m = 0;
        for (uint32_t i = 0; i < k; i++) {
            uint32_t a = gv[i], b = gv[(i + 1) % k];
            fv[m++] = map[a];
            if (wall[a] && wall[a] == wall[b]) {
                /* the wall's edge b → a runs forwards along the loop:
                 * this facet takes the run backwards */
                const rim *w = &r[wall[a] - 1];
                uint32_t steps = (pos[a] + w->n - pos[b]) % w->n;
                for (uint32_t s = 1; s < steps; s++)
                    fv[m++] = w->v[(pos[a] + w->n - s) % w->n];
            }
        }
        int64_t nfi = geo_poly_add_facet(p, fv, m);
        memcpy(p->planes[nfi], g->planes[f], sizeof p->planes[0]);
        nf++;
    }
    *ret_planes = nside;
    *ret_nv = nv;
    *ret_nf = nf;
    rc = 1;
out:
    free(pl), free(src), free(pos), free(map), free(fv), free(wall);
    geo_poly_free(g);
    return rc;
}

/* Step 5a for loops on one polyline sampled differently. */

typedef struct insert {
    uint32_t facet, after; /* the facet, and its corner before the edge */
    double t;              /* position along the edge, 0 to 1 */
    uint32_t v;            /* the vertex put there */
} insert;

static int insert_cmp(const void *a, const void *b)
{
    const insert *x = a, *y = b;
    if (x->facet != y->facet)
        return x->facet < y->facet ? -1 : 1;
    if (x->after != y->after)
        return x->after < y->after ? -1 : 1;
    return (x->t > y->t) - (x->t < y->t);
}

/* Each vertex of rim a either within tol of a vertex of rim b (paired:
 * appended to pa, pb when a is mesh 2's rim, as pb → pa) or within tol
 * of the inside of one of b's edges (an insert into that edge's facet).
 * False when a vertex is off b's polyline. */
static bool seam_side(const geo_poly *out, const rim *a, const rim *b,
                      bool a_is_2, double tol, uint32_t *wa, uint32_t *wb,
                      uint32_t *nw, uint8_t *paired, insert *ins, uint32_t *nins)
{
    for (uint32_t i = 0; i < a->n; i++) {
        const double *x = out->verts[a->v[i]];
        uint32_t near_v = GEO_NONE, near_e = GEO_NONE;
        for (uint32_t j = 0; j < b->n && near_v == GEO_NONE; j++)
            if (geo_vdist(x, out->verts[b->v[j]]) <= tol)
                near_v = j;
        if (near_v != GEO_NONE) {
            /* mesh 1's vertex stays; each pair once */
            uint32_t v1 = a_is_2 ? b->v[near_v] : a->v[i],
                     v2 = a_is_2 ? a->v[i] : b->v[near_v];
            if (!paired[a_is_2 ? near_v : i]) {
                paired[a_is_2 ? near_v : i] = 1;
                wa[*nw] = v1;
                wb[*nw] = v2;
                ++*nw;
            }
            continue;
        }
        for (uint32_t j = 0; j < b->n && near_e == GEO_NONE; j++)
            if (seg_dist(x, out->verts[b->v[j]], out->verts[b->v[(j + 1) % b->n]]) <= tol)
                near_e = j;
        if (near_e == GEO_NONE)
            return false;
        const double *p = out->verts[b->v[near_e]],
                     *q = out->verts[b->v[(near_e + 1) % b->n]];
        uint32_t f = b->f[near_e], k = geo_poly_facet_size(out, f);
        const uint32_t *fv = geo_poly_facet(out, f);
        uint32_t after = GEO_NONE;
        for (uint32_t c = 0; c < k; c++)
            if (fv[c] == b->v[near_e] && fv[(c + 1) % k] == b->v[(near_e + 1) % b->n])
                after = c;
        if (after == GEO_NONE)
            return false;
        double pq[3], px[3];
        geo_vsub(q, p, pq);
        geo_vsub(x, p, px);
        ins[*nins] = (insert){f, after, geo_vdot(px, pq) / geo_vdot(pq, pq), a->v[i]};
        ++*nins;
    }
    return true;
}

/* Loops facing with no gap, every vertex of each on the other's polyline
 * (within tol) but not vertex for vertex — one cut, its halves sampled
 * differently: each loop's vertices are put into the other's edges (the
 * edges' facets take them), the vertices that coincide are welded, and
 * the seam is closed with no band. Appends the pairs to (wa, wb, *nw),
 * rewrites out's facets and returns 1 (*ret_inserted the vertices put
 * into edges), 0 when the loops are not on one polyline (out and the
 * pairs unchanged), -ENOMEM. */
static int seam_insert(geo_poly *out, const rim r[2], double tol,
                       uint32_t *wa, uint32_t *wb, uint32_t *nw,
                       uint32_t *ret_inserted)
{
    uint32_t n = r[0].n + r[1].n, nw0 = *nw, nins = 0;
    insert *ins = malloc((size_t)n * sizeof *ins);
    uint8_t *paired = calloc(n, 1);
    geo_poly *q = geo_poly_new();
    int rc = -ENOMEM;
    if (!ins || !paired || !q)
        goto out;
    rc = 0;
    if (!seam_side(out, &r[0], &r[1], false, tol, wa, wb, nw, paired, ins, &nins) ||
        !seam_side(out, &r[1], &r[0], true, tol, wa, wb, nw, paired, ins, &nins) ||
        nins == 0) {
        *nw = nw0;
        goto out;
    }
    qsort(ins, nins, sizeof *ins, insert_cmp);
    rc = -ENOMEM;
    if (geo_poly_reserve(q, out->nverts, out->nfacets,
                         (size_t)geo_poly_ncorners(out) + nins) < 0)
        goto out;
    for (uint32_t v = 0; v < out->nverts; v++)
        geo_poly_add_vertex(q, out->verts[v]);
    uint32_t *fv = malloc(((size_t)geo_poly_ncorners(out) + nins) * sizeof *fv);
    if (!fv)
        goto out;
    uint32_t s = 0;
    for (uint32_t f = 0; f < out->nfacets; f++) {
        const uint32_t *src = geo_poly_facet(out, f);
        uint32_t k = geo_poly_facet_size(out, f), m = 0;
        for (uint32_t c = 0; c < k; c++) {
            fv[m++] = src[c];
            while (s < nins && ins[s].facet == f && ins[s].after == c)
                fv[m++] = ins[s++].v;
        }
        int64_t nf = geo_poly_add_facet(q, fv, m);
        memcpy(q->planes[nf], out->planes[f], sizeof q->planes[0]);
    }
    free(fv);
    rc = geo_poly_assign(out, q);
    if (rc == 0) {
        *ret_inserted = nins;
        rc = 1;
    }
out:
    free(ins), free(paired);
    geo_poly_free(q);
    return rc;
}

/* Step 5b for loops l1, l2 facing across a gap: out (mesh 1, mesh 2 as
 * merged) with the gap rebuilt from the facet planes, the other
 * coinciding loops welded (wa, wb, nw), the openings left filled, and
 * kept only when geo_inspect finds the whole valid. 1 when out holds
 * that, 0 when the construction did not apply or gave no valid solid
 * (out unchanged), -ENOMEM or -ECANCELED. */
static int stitch_by_planes(geo_poly *out, const geo_poly *m1, const rim r[2],
                            const uint32_t *wa, const uint32_t *wb, uint32_t nw,
                            const geo_stitch_opts *o, const geo_ctx *ctx,
                            geo_stitch_report *R, geo_err *err)
{
    geo_poly *cand = geo_poly_copy(out);
    geo_mesh_fill_report fr = {0};
    int rc = -ENOMEM;
    if (!cand)
        goto out;
    uint32_t planes = 0, nv = 0, nf = 0;
    if ((rc = gap_from_planes(cand, r, &planes, &nv, &nf)) <= 0)
        goto out;
    rc = -ENOMEM;
    if (nw && weld(cand, m1->nfacets, wa, wb, nw) < 0)
        goto out;
    geo_err ferr = {{0}};
    rc = geo_fill(cand, &o->fill, NULL, &fr, &ferr);
    if (rc == -ENOMEM || rc == -ECANCELED) {
        *err = ferr;
        goto out;
    }
    if (rc < 0) {
        rc = 0;
        goto out;
    }
    geo_stats st;
    if ((rc = geo_inspect(cand, NULL, ctx, &st, err)) < 0)
        goto out;
    bool valid = st.valid;
    geo_stats_clear(&st);
    rc = 0;
    if (!valid)
        goto out;
    if ((rc = geo_poly_assign(out, cand)) < 0)
        goto out;
    R->method = GEO_STITCH_PLANES;
    R->planes = planes;
    R->band_vertices = nv;
    R->band_facets = nf;
    R->welded = nw;
    R->meridians = R->rows = R->twist = 0;
    R->meridian_length = 0;
    R->fill = fr;
    memset(&fr, 0, sizeof fr);
    rc = 1;
out:
    if (rc == -ENOMEM)
        geo_err_set(err, rc, "out of memory stitching");
    geo_mesh_fill_report_clear(&fr);
    geo_poly_free(cand);
    return rc;
}

/* The chosen loops as merged into out (mesh 2 after mesh 1, turned over
 * when flipped2): r[1]'s arrays are malloc'd. 0 or -ENOMEM. */
static int make_rims(const geo_poly *m1, const loop *l1, const loop *l2,
                     bool flipped2, rim r[2])
{
    uint32_t n = l2->n, off2 = m1->nverts;
    r[0] = (rim){l1->v, l1->f, l1->n};
    r[1] = (rim){malloc((size_t)n * sizeof *r[1].v),
                 malloc((size_t)n * sizeof *r[1].f), n};
    if (!r[1].v || !r[1].f) {
        free(r[1].v), free(r[1].f);
        r[1].v = r[1].f = NULL;
        return -ENOMEM;
    }
    for (uint32_t k = 0; k < n; k++) {
        /* turned over, edge v[k] → v[k + 1] is mesh 2's v[n−2−k] → v[n−1−k] */
        r[1].v[k] = off2 + (flipped2 ? l2->v[n - 1 - k] : l2->v[k]);
        r[1].f[k] = m1->nfacets + (flipped2 ? l2->f[(2 * n - 2 - k) % n] : l2->f[k]);
    }
    return 0;
}

static int stitch_pair(const geo_poly *m1, const geo_poly *m2,
                       const geo_stitch_opts *opts, const geo_ctx *ctx,
                       geo_poly *out, geo_stitch_report *rep, geo_err *err,
                       bool may_trim)
{
    geo_stitch_opts o;
    if (opts)
        o = *opts;
    else
        geo_stitch_opts_default(&o);
    if (!(o.segment >= 0) || !isfinite(o.segment))
        return geo_err_set(err, -EINVAL, "segment: must be ≥ 0");
    int rc = geo_poly_validate_indices(m1, err);
    if (rc < 0) {
        geo_err_prefix(err, "mesh 1");
        return rc;
    }
    if ((rc = geo_poly_validate_indices(m2, err)) < 0) {
        geo_err_prefix(err, "mesh 2");
        return rc;
    }
    geo_stitch_report R = {0};
    loops L1 = {0}, L2 = {0};
    uint32_t *X = NULL, *Y = NULL, *jof = NULL, *P = NULL;
    uint32_t *wa = NULL, *wb = NULL, *lb2 = NULL, nw = 0;
    uint8_t *keep = NULL, *used2 = NULL;
    rim rims[2] = {{0}, {0}};
    geo_poly_clear(out);
    if ((rc = find_loops(m1, &L1, err)) < 0 ||
        (rc = find_loops(m2, &L2, err)) < 0)
        goto fail;
    R.loops1 = L1.n;
    R.loops2 = L2.n;
    if (L1.n == 0 || L2.n == 0) {
        rc = geo_err_set(err, -EINVAL, "mesh %d has no free-edge loop "
                         "(nothing to stitch)", L1.n == 0 ? 1 : 2);
        goto fail;
    }
    /* the pair of loops with the closest centres */
    double best = INFINITY;
    for (uint32_t a = 0; a < L1.n; a++)
        for (uint32_t b = 0; b < L2.n; b++) {
            double d = geo_vdist(L1.l[a].c, L2.l[b].c);
            if (d < best) {
                best = d;
                R.loop1 = a;
                R.loop2 = b;
            }
        }
    const loop *l1 = &L1.l[R.loop1], *l2 = &L2.l[R.loop2];
    R.nloop1 = l1->n;
    R.nloop2 = l2->n;
    double wtol = 1e3 * geo_eps_of_size(geo_poly_size(m1) +
                                        geo_poly_size(m2));
    if (may_trim) {
        /* step 5c: halves that overlap are cut back to one plane first */
        geo_poly *t1, *t2;
        double mid[4];
        rc = geo_stitch_trim(m1, l1->v, l1->n, m2, l2->v, l2->n, wtol, &t1,
                             &t2, mid);
        if (rc < 0)
            goto oom;
        if (rc == 1) {
            geo_stitch_report T;
            rc = stitch_pair(t1, t2, &o, ctx, out, &T, err, false);
            geo_poly_free(t1);
            geo_poly_free(t2);
            if (rc < 0)
                goto fail;
            T.trimmed = true;
            T.loops1 = R.loops1;
            T.loops2 = R.loops2;
            T.nloop1 = R.nloop1;
            T.nloop2 = R.nloop2;
            R = T;
            goto done;
        }
    }
    double a1[3], g1[3], g2[3];
    geo_vsub(l2->c, l1->c, a1);
    /* the offset test uses the loops' length-weighted centres: a cut
     * through many small facets on one side crowds its loop's vertices
     * there and pulls the vertex mean sideways */
    loop_centroid(m1, l1, g1);
    loop_centroid(m2, l2, g2);
    double a1g[3];
    geo_vsub(g2, g1, a1g);
    /* across a gap: mean planes within 45° of parallel, and each centre
     * off the other's axis by less than half the smaller loop radius */
    double n1 = geo_vlen(l1->nw), n2 = geo_vlen(l2->nw), r1 = 0, r2 = 0;
    for (uint32_t k = 0; k < l1->n; k++)
        r1 += geo_vdist(m1->verts[l1->v[k]], l1->c) / l1->n;
    for (uint32_t k = 0; k < l2->n; k++)
        r2 += geo_vdist(m2->verts[l2->v[k]], l2->c) / l2->n;
    double lat[3], ax[3];
    geo_vscale(l1->nw, n1 > 0 ? 1.0 / n1 : 0.0, ax);
    geo_vmadd(a1g, -geo_vdot(a1g, ax), ax, lat);
    bool parallel = n1 > 0 && n2 > 0 &&
                    fabs(geo_vdot(l1->nw, l2->nw)) >= sqrt(0.5) * n1 * n2;
    R.band = parallel && geo_vlen(lat) < 0.5 * fmin(r1, r2);
    /* or: planar loops, each wholly beyond the other's plane — the walls
     * of a slab (step 5b), however far off-axis a small loop sits */
    double wall[4];
    if (!R.band && parallel)
        R.band = cap_plane(m1, l1->v, l1->n, m2, l2->v, l2->n, wtol, wall) &&
                 cap_plane(m2, l2->v, l2->n, m1, l1->v, l1->n, wtol, wall);
    /* facing loops of consistently oriented meshes run opposite ways */
    double agree = geo_vdot(l1->nw, l2->nw);
    R.flipped2 = R.band ? agree > 0 : agree < 0;
    uint32_t nl2 = l2->n;
    X = malloc((size_t)(l1->n + 1) * sizeof *X);
    Y = malloc((size_t)(nl2 + 1) * sizeof *Y);
    keep = calloc((size_t)(l1->n > nl2 ? l1->n : nl2) + 1, 1);
    if (!X || !Y || !keep)
        goto oom;
    /* loop 2 in the direction it has once mesh 2 is as it will be merged,
     * then backwards: Y runs like X */
    uint32_t *l2v = malloc((size_t)nl2 * sizeof *l2v);
    if (!l2v)
        goto oom;
    for (uint32_t k = 0; k < nl2; k++)
        l2v[k] = R.flipped2 ? l2->v[nl2 - 1 - k] : l2->v[k];
    loop l2o = *l2;
    l2o.v = l2v;
    uint32_t nx, ny;
    if (R.band) {
        memcpy(X, l1->v, (size_t)l1->n * sizeof *X);
        nx = l1->n;
        for (uint32_t k = 0; k < nl2; k++)
            Y[k] = l2v[nl2 - 1 - k];
        ny = nl2;
    } else {
        /* algorithm 2: the vertices on the side facing the other loop */
        for (uint32_t k = 0; k < l1->n; k++) {
            double d[3];
            geo_vsub(m1->verts[l1->v[k]], l1->c, d);
            keep[k] = geo_vdot(d, a1) > 0;
        }
        nx = longest_run(l1, keep, X);
        for (uint32_t k = 0; k < nl2; k++) {
            double d[3];
            geo_vsub(m2->verts[l2v[k]], l2->c, d);
            keep[k] = geo_vdot(d, a1) < 0;
        }
        uint32_t *tmp = malloc((size_t)nl2 * sizeof *tmp);
        if (!tmp) {
            free(l2v);
            goto oom;
        }
        ny = longest_run(&l2o, keep, tmp);
        for (uint32_t k = 0; k < ny; k++)
            Y[k] = tmp[ny - 1 - k];
        free(tmp);
    }
    free(l2v);
    if (!R.band) {
        trim_arc(m1, X, &nx, m2, Y, ny);
        trim_arc(m2, Y, &ny, m1, X, nx);
    }
    R.chosen1 = nx;
    R.chosen2 = ny;
    if (nx < 2 || ny < 2) {
        rc = geo_err_set(err, -EINVAL, "algorithm 2 chose %u vertices on loop "
                         "1 and %u on loop 2: need at least 2 on each", nx, ny);
        goto fail;
    }
    /* merged output: mesh 1, mesh 2 (turned over if needed), the band */
    uint32_t off2 = m1->nverts;
    size_t nc1 = geo_poly_ncorners(m1), nc2 = geo_poly_ncorners(m2);
    if (geo_poly_reserve(out, (size_t)m1->nverts + m2->nverts,
                         (size_t)m1->nfacets + m2->nfacets, nc1 + nc2) < 0)
        goto oom;
    for (uint32_t v = 0; v < m1->nverts; v++)
        geo_poly_add_vertex(out, m1->verts[v]);
    for (uint32_t v = 0; v < m2->nverts; v++)
        geo_poly_add_vertex(out, m2->verts[v]);
    for (uint32_t f = 0; f < m1->nfacets; f++) {
        int64_t nf = geo_poly_add_facet(out, geo_poly_facet(m1, f),
                                        geo_poly_facet_size(m1, f));
        memcpy(out->planes[nf], m1->planes[f], sizeof out->planes[0]);
    }
    for (uint32_t f = 0; f < m2->nfacets; f++) {
        uint32_t k = geo_poly_facet_size(m2, f);
        const uint32_t *fv = geo_poly_facet(m2, f);
        int64_t nf = geo_poly_add_facet(out, fv, k);
        uint32_t *dst = out->fidx + out->fstart[nf];
        for (uint32_t i = 0; i < k; i++)
            dst[i] = off2 + (R.flipped2 ? fv[k - 1 - i] : fv[i]);
        memcpy(out->planes[nf], m2->planes[f], sizeof out->planes[0]);
        if (R.flipped2)
            for (int q = 0; q < 4; q++)
                out->planes[nf][q] = -out->planes[nf][q];
    }
    for (uint32_t k = 0; k < ny; k++)
        Y[k] += off2;
    /* A: the longer line (N ≥ M), B the other */
    R.swapped = ny > nx;
    const uint32_t *A = R.swapped ? Y : X, *B = R.swapped ? X : Y;
    uint32_t N = R.swapped ? ny : nx, M = R.swapped ? nx : ny;
    /* columns: N meridians; a band's lines are closed by their first
     * point (N + 1 and M + 1 points, the last meridian the first) */
    uint32_t ncol = N, na = R.band ? N + 1 : N, nb = R.band ? M + 1 : M;
    jof = malloc(((size_t)na + 1) * sizeof *jof);
    if (!jof)
        goto oom;
    double *sa = malloc((size_t)na * sizeof *sa);
    double *sb = malloc((size_t)nb * sizeof *sb);
    uint32_t *jt = malloc(((size_t)na + 1) * sizeof *jt);
    if (!sa || !sb || !jt) {
        free(sa), free(sb), free(jt);
        goto oom;
    }
    line_arcs(out, A, N, na, 0, sa);
    uint32_t twist = 0;
    double total = INFINITY;
    for (uint32_t s = 0; s < (R.band ? M : 1); s++) {
        line_arcs(out, B, M, nb, s, sb);
        meridians_arc(sa, na, sb, nb, jt);
        double sum = 0;
        for (uint32_t i = 0; i < ncol && sum < total; i++)
            sum += geo_vdist(out->verts[A[i]],
                             out->verts[B[(jt[i] + s) % M]]);
        if (sum < total) {
            total = sum;
            twist = s;
            memcpy(jof, jt, (size_t)na * sizeof *jof);
        }
        if ((s & 255) == 255 && geo_ctx_canceled(ctx)) {
            free(sa), free(sb), free(jt);
            rc = geo_err_set(err, -ECANCELED, "canceled");
            goto fail;
        }
    }
    free(sa), free(sb), free(jt);
    R.twist = twist;
    R.meridians = ncol;
    R.meridian_length = total;
    /* pairs to weld: the chosen lines if they coincide, and any other
     * pair of loops that does (mesh 1's vertices first in out, so A is
     * X, mesh 1's line, whenever N = M) */
    uint32_t nl1 = 0, maxl2 = 0;
    for (uint32_t a = 0; a < L1.n; a++)
        nl1 += L1.l[a].n;
    for (uint32_t b = 0; b < L2.n; b++)
        maxl2 = L2.l[b].n > maxl2 ? L2.l[b].n : maxl2;
    double tol = geo_poly_eps(out);
    wa = malloc(((size_t)nl1 + 1) * sizeof *wa);
    wb = malloc(((size_t)nl1 + 1) * sizeof *wb);
    lb2 = malloc(((size_t)maxl2 + 1) * sizeof *lb2);
    used2 = calloc((size_t)L2.n + 1, 1);
    if (!wa || !wb || !lb2 || !used2)
        goto oom;
    bool welded = N == M && lines_coincide(out, A, B, N, jof, twist, tol, wa,
                                           wb, &nw);
    used2[R.loop2] = 1;
    for (uint32_t a = 0; a < L1.n; a++) {
        const loop *la = &L1.l[a];
        for (uint32_t b = 0; b < L2.n && a != R.loop1; b++) {
            const loop *lb = &L2.l[b];
            if (used2[b] || la->n != lb->n)
                continue;
            for (uint32_t k = 0; k < lb->n; k++)
                lb2[k] = off2 + (R.flipped2 ? lb->v[lb->n - 1 - k] : lb->v[k]);
            if (loops_coincide(out, la->v, lb2, la->n, tol, wa, wb, &nw)) {
                used2[b] = 1;
                R.welded_loops++;
                break;
            }
        }
    }
    if (welded) {
        R.rows = 1;
        R.method = GEO_STITCH_WELD;
        goto openings;
    }
    if (R.band) {
        if (make_rims(m1, l1, l2, R.flipped2, rims) < 0)
            goto oom;
        rc = seam_insert(out, rims, tol, wa, wb, &nw, &R.inserted);
        if (rc < 0)
            goto oom;
        if (rc == 1) {
            R.rows = 1;
            R.method = GEO_STITCH_WELD;
            goto openings;
        }
        rc = stitch_by_planes(out, m1, rims, wa, wb, nw, &o, ctx, &R, err);
        if (rc < 0)
            goto fail;
        if (rc == 1) {
            rc = geo_ctx_progress(ctx, 1.0);
            if (rc < 0) {
                geo_err_set(err, rc, "canceled");
                goto fail;
            }
            goto done;
        }
    }
    R.method = GEO_STITCH_BAND;
    uint64_t e1, e2;
    double s1 = mean_edge(m1, &e1), s2 = mean_edge(m2, &e2);
    R.segment = o.segment > 0 ? o.segment
                              : (e1 + e2 ? (s1 + s2) / (double)(e1 + e2) : 0);
    double mean_len = total / ncol;
    uint32_t segs = 1;
    if (R.segment > 0 && mean_len / R.segment > 1.5)
        segs = (uint32_t)lround(fmin(mean_len / R.segment, 10000.0));

    uint32_t rows = segs + 1;
    R.rows = rows;
    /* P, rows × ncol; intermediate points appended as new vertices */
    P = malloc((size_t)rows * ncol * sizeof *P);
    if (!P)
        goto oom;
    for (uint32_t c = 0; c < ncol; c++) {
        uint32_t a = A[c], b = B[(jof[c] + twist) % M];
        P[c] = a;
        P[(size_t)(rows - 1) * ncol + c] = b;
        for (uint32_t r = 1; r + 1 < rows; r++) {
            double t = (double)r / (rows - 1), x[3];
            for (int k = 0; k < 3; k++)
                x[k] = out->verts[a][k] +
                       t * (out->verts[b][k] - out->verts[a][k]);
            int64_t nv = geo_poly_add_vertex(out, x);
            if (nv < 0)
                goto oom;
            P[(size_t)r * ncol + c] = (uint32_t)nv;
            R.band_vertices++;
        }
    }
    /* facets: X's edges backwards, Y's forwards */
    uint32_t nf0 = out->nfacets;
    for (uint32_t c = 0; c + (R.band ? 0 : 1) < ncol; c++) {
        uint32_t c2 = (c + 1) % ncol;
        for (uint32_t r = 0; r + 1 < rows; r++) {
            uint32_t a = P[(size_t)r * ncol + c], b = P[(size_t)r * ncol + c2];
            uint32_t d = P[(size_t)(r + 1) * ncol + c];
            uint32_t e = P[(size_t)(r + 1) * ncol + c2];
            /* quad (b, a, d, e) runs X's edge backwards when A is X */
            uint32_t tri[2][3];
            int nt = 0;
            if (d == e) {
                tri[nt][0] = b, tri[nt][1] = a, tri[nt][2] = d, nt++;
            } else if (geo_vdist(out->verts[a], out->verts[e]) <=
                       geo_vdist(out->verts[b], out->verts[d])) {
                tri[nt][0] = b, tri[nt][1] = a, tri[nt][2] = e, nt++;
                tri[nt][0] = a, tri[nt][1] = d, tri[nt][2] = e, nt++;
            } else {
                tri[nt][0] = b, tri[nt][1] = a, tri[nt][2] = d, nt++;
                tri[nt][0] = b, tri[nt][1] = d, tri[nt][2] = e, nt++;
            }
            for (int q = 0; q < nt; q++) {
                if (R.swapped) {
                    uint32_t tmp = tri[q][0];
                    tri[q][0] = tri[q][2];
                    tri[q][2] = tmp;
                }
                int64_t nf = geo_poly_add_facet(out, tri[q], 3);
                if (nf < 0)
                    goto oom;
                geo_poly_facet_fit_plane(out, (uint32_t)nf,
                                         GEO_PLANE_UNWEIGHTED, out->planes[nf]);
            }
        }
    }
    R.band_facets = out->nfacets - nf0;
    /* straight meridians between jagged lines fold where a line steps
     * along the meridians' direction: the band's own points are faired
     * (U² = 0, both meshes fixed), which spreads them evenly and carries
     * the meshes' curvature across the gap */
    if (R.band_vertices && o.fill.fill.fair != GEO_FAIR_NONE &&
        (rc = geo_fair_vertices(out, out->nverts - R.band_vertices,
                                &o.fill.fill, ctx, NULL, err)) < 0)
        goto fail;
    if ((rc = geo_ctx_progress(ctx, 0.5)) < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }
openings:
    if (nw && weld(out, m1->nfacets, wa, wb, nw) < 0)
        goto oom;
    R.welded = nw;
    /* the openings left: the loop vertices not bridged, other loops */
    if ((rc = geo_fill(out, &o.fill, NULL, &R.fill, err)) < 0) {
        geo_err_prefix(err, "closing the openings");
        goto fail;
    }
    rc = geo_ctx_progress(ctx, 1.0);
    if (rc < 0) {
        geo_err_set(err, rc, "canceled");
        goto fail;
    }
    goto done;
oom:
    rc = geo_err_set(err, -ENOMEM, "out of memory stitching");
fail:
    geo_poly_clear(out);
    geo_stitch_report_clear(&R);
done:
    loops_free(&L1);
    loops_free(&L2);
    free(X), free(Y), free(jof), free(P), free(keep);
    free(wa), free(wb), free(lb2), free(used2);
    free(rims[1].v), free(rims[1].f);
    if (rep)
        *rep = R;
    else
        geo_stitch_report_clear(&R);
    return rc;
}

int geo_stitch(const geo_poly *m1, const geo_poly *m2,
               const geo_stitch_opts *opts, const geo_ctx *ctx, geo_poly *out,
               geo_stitch_report *rep, geo_err *err)
{
    return stitch_pair(m1, m2, opts, ctx, out, rep, err, true);
}

/* Union-find root with path halving. */
static uint32_t root(uint32_t *up, uint32_t x)
{
    while (up[x] != x) {
        up[x] = up[up[x]];
        x = up[x];
    }
    return x;
}

int geo_stitch_pieces(const geo_poly *p, const geo_stitch_opts *opts,
                      const geo_ctx *ctx, geo_poly *out,
                      geo_stitch_report *rep, geo_err *err)
{
    geo_poly_clear(out);
    int rc = geo_poly_validate_indices(p, err);
    if (rc < 0)
        return rc;
    uint32_t *up = malloc(((size_t)p->nverts + 1) * sizeof *up);
    bool *keep = malloc(((size_t)p->nfacets + 1) * sizeof *keep);
    geo_poly *a = NULL, *b = NULL;
    if (!up || !keep) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    for (uint32_t v = 0; v < p->nverts; v++)
        up[v] = v;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        const uint32_t *fv = geo_poly_facet(p, f);
        for (uint32_t i = 1; i < geo_poly_facet_size(p, f); i++) {
            uint32_t x = root(up, fv[0]), y = root(up, fv[i]);
            if (x != y)
                up[x < y ? y : x] = x < y ? x : y;
        }
    }
    /* pieces in order of their first facet */
    uint32_t r0 = UINT32_MAX, r1 = UINT32_MAX, more = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t r = root(up, geo_poly_facet(p, f)[0]);
        if (r0 == UINT32_MAX || r == r0)
            r0 = r;
        else if (r1 == UINT32_MAX || r == r1)
            r1 = r;
        else
            more = 1;
    }
    if (r1 == UINT32_MAX || more) {
        rc = geo_err_set(err, -EINVAL, "stitch needs a model of exactly two "
                         "pieces (the two open meshes); this one has %s",
                         r0 == UINT32_MAX ? "no facets"
                         : r1 == UINT32_MAX ? "one piece" : "more than two");
        goto out;
    }
    a = geo_poly_copy(p);
    b = geo_poly_copy(p);
    if (!a || !b) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    for (uint32_t f = 0; f < p->nfacets; f++)
        keep[f] = root(up, geo_poly_facet(p, f)[0]) == r0;
    if ((rc = geo_poly_compact(a, keep, NULL, NULL)) < 0)
        goto oom;
    for (uint32_t f = 0; f < p->nfacets; f++)
        keep[f] = !keep[f];
    if ((rc = geo_poly_compact(b, keep, NULL, NULL)) < 0)
        goto oom;
    rc = geo_stitch(a, b, opts, ctx, out, rep, err);
    goto out;
oom:
    rc = geo_err_set(err, -ENOMEM, "out of memory");
out:
    geo_poly_free(a);
    geo_poly_free(b);
    free(up), free(keep);
    return rc;
}
