/* stone_sim.c — stones as half-space intersections, their shadow-profile
 * scans, and a Hausdorff distance estimate (see stone_sim.h). */
#include "stone_sim.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "plane.h"
#include "vec.h"

/* ---- convex clipping ------------------------------------------------ */

typedef struct edge_slot {
    uint64_t key;
    uint32_t vertex; /* new vertex on that edge, UINT32_MAX = empty slot */
} edge_slot;

typedef struct edge_map {
    edge_slot *slots;
    size_t cap;
} edge_map;

static uint64_t ekey(uint32_t a, uint32_t b)
{
    return a < b ? ((uint64_t)a << 32) | b : ((uint64_t)b << 32) | a;
}

static edge_slot *edge_find(edge_map *m, uint64_t key)
{
    size_t h = (key * 0x9e3779b97f4a7c15ULL) >> 20;
    for (size_t i = h & (m->cap - 1);; i = (i + 1) & (m->cap - 1))
        if (m->slots[i].vertex == UINT32_MAX || m->slots[i].key == key)
            return &m->slots[i];
}

geo_poly *sim_clip_convex(const geo_poly *p, const double plane[4], double tol,
                          int *ret_changed)
{
    uint32_t nv = p->nverts;
    signed char *side = malloc(nv + 1);
    double *val = malloc((nv + 1) * sizeof *val);
    int any_pos = 0, any_neg = 0;
    for (uint32_t i = 0; i < nv; i++) {
        val[i] = geo_plane_eval(plane, p->verts[i]);
        side[i] = val[i] > tol ? 1 : (val[i] < -tol ? -1 : 0);
        any_pos |= side[i] > 0;
        any_neg |= side[i] < 0;
    }
    *ret_changed = any_pos;
    if (!any_pos) {
        free(side), free(val);
        return geo_poly_copy(p);
    }
    if (!any_neg) {
        free(side), free(val);
        return NULL;
    }
    geo_poly *q = geo_poly_new();
    uint32_t *vmap = malloc((nv + 1) * sizeof *vmap);
    for (uint32_t i = 0; i < nv; i++)
        vmap[i] = side[i] <= 0 ? (uint32_t)geo_poly_add_vertex(q, p->verts[i])
                               : UINT32_MAX;
    edge_map em = {NULL, 64};
    while (em.cap < 4 * (size_t)geo_poly_ncorners(p))
        em.cap <<= 1;
    em.slots = malloc(em.cap * sizeof *em.slots);
    for (size_t i = 0; i < em.cap; i++)
        em.slots[i].vertex = UINT32_MAX;

    /* cap_next[a] = b: the cap face has an edge a→b */
    uint32_t cap_cap = nv + geo_poly_ncorners(p) + 16;
    uint32_t *cap_next = malloc(cap_cap * sizeof *cap_next);
    for (uint32_t i = 0; i < cap_cap; i++)
        cap_next[i] = UINT32_MAX;
    uint32_t *loop = malloc((2 * (size_t)geo_poly_ncorners(p) + 8) * sizeof *loop);
    bool coplanar_face = false;

    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        uint32_t m = 0, leave = UINT32_MAX, enter = UINT32_MAX;
        bool all_on = true;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = v[i], b = v[(i + 1) % n];
            if (side[a] != 0)
                all_on = false;
            if (side[a] <= 0)
                loop[m++] = vmap[a];
            if ((side[a] < 0 && side[b] > 0) || (side[a] > 0 && side[b] < 0)) {
                edge_slot *s = edge_find(&em, ekey(a, b));
                if (s->vertex == UINT32_MAX) {
                    double t = val[a] / (val[a] - val[b]), x[3];
                    double d[3];
                    geo_vsub(p->verts[b], p->verts[a], d);
                    geo_vmadd(p->verts[a], t, d, x);
                    s->key = ekey(a, b);
                    s->vertex = (uint32_t)geo_poly_add_vertex(q, x);
                }
                loop[m++] = s->vertex;
                if (side[a] < 0)
                    leave = s->vertex;
                else
                    enter = s->vertex;
            } else if (side[a] == 0 && side[b] > 0) {
                leave = vmap[a];
            } else if (side[a] > 0 && side[b] == 0) {
                enter = vmap[b];
            }
        }
        if (all_on) {
            coplanar_face = true;
            if (geo_vdot(p->planes[f], plane) < 0)
                continue; /* an opposite face in the plane: degenerate */
        }
        if (m < 3)
            continue;
        /* drop consecutive duplicates produced by snapping */
        uint32_t k = 0;
        for (uint32_t i = 0; i < m; i++)
            if (k == 0 || loop[k - 1] != loop[i])
                loop[k++] = loop[i];
        while (k > 1 && loop[k - 1] == loop[0])
            k--;
        if (k < 3)
            continue;
        int64_t nf = geo_poly_add_facet(q, loop, k);
        memcpy(q->planes[nf], p->planes[f], sizeof q->planes[0]);
        if (leave != UINT32_MAX && enter != UINT32_MAX && leave != enter)
            cap_next[enter] = leave;
    }
    if (!coplanar_face) {
        uint32_t start = UINT32_MAX;
        for (uint32_t i = 0; i < q->nverts && start == UINT32_MAX; i++)
            if (cap_next[i] != UINT32_MAX)
                start = i;
        if (start != UINT32_MAX) {
            uint32_t k = 0, c = start;
            do {
                loop[k++] = c;
                c = cap_next[c];
            } while (c != UINT32_MAX && c != start && k < q->nverts);
            if (c == start && k >= 3) {
                int64_t nf = geo_poly_add_facet(q, loop, k);
                double nrm[3] = {plane[0], plane[1], plane[2]};
                double l = geo_vlen(nrm);
                for (int j = 0; j < 3; j++)
                    q->planes[nf][j] = plane[j] / l;
                q->planes[nf][3] = plane[3] / l;
            }
        }
    }
    free(side), free(val), free(vmap), free(em.slots), free(cap_next),
        free(loop);
    if (q->nfacets < 4)
        return geo_poly_free(q);
    geo_poly_compact(q, NULL, NULL, NULL);
    return q;
}

geo_poly *sim_halfspace_intersection(const double *planes, uint32_t n,
                                     double r)
{
    double lo[3] = {-r, -r, -r}, hi[3] = {r, r, r};
    double v[8][3];
    for (int i = 0; i < 8; i++) {
        v[i][0] = (i & 1) ? hi[0] : lo[0];
        v[i][1] = (i & 2) ? hi[1] : lo[1];
        v[i][2] = (i & 4) ? hi[2] : lo[2];
    }
    static const uint32_t idx[] = {0, 2, 3, 1, 4, 5, 7, 6, 0, 1, 5, 4,
                                   2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5};
    static const uint32_t start[] = {0, 4, 8, 12, 16, 20, 24};
    geo_poly *p = geo_poly_from_arrays(8, &v[0][0], 6, start, idx, NULL, NULL);
    double tol = 1e-12 * r;
    for (uint32_t i = 0; p && i < n; i++) {
        int changed;
        geo_poly *q = sim_clip_convex(p, planes + 4 * i, tol, &changed);
        geo_poly_free(p);
        p = q;
    }
    return p;
}

/* ---- stones ------------------------------------------------------- */

typedef struct plane_list {
    double *v;
    uint32_t n, cap;
} plane_list;

static void add_plane(plane_list *l, const double nrm[3], const double p0[3])
{
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 64;
        l->v = realloc(l->v, 4 * (size_t)l->cap * sizeof *l->v);
    }
    double pl[4];
    geo_plane_from_point_normal(p0, nrm, pl);
    memcpy(l->v + 4 * l->n++, pl, sizeof pl);
}

static double jitter(uint64_t *rng, double amp)
{
    return (2 * geo_rand_unit(rng) - 1) * amp;
}

/* A facet plane at azimuth phi inclined by alpha (radians, from the
 * horizontal) through point (r cos phi, r sin phi, z); up = +1 for crown
 * facets (normal upward), −1 for pavilion facets. */
static void add_inclined(plane_list *l, double phi, double alpha, double r,
                         double z, int up)
{
    double n[3] = {sin(alpha) * cos(phi), sin(alpha) * sin(phi),
                   up * cos(alpha)};
    double p0[3] = {r * cos(phi), r * sin(phi), z};
    add_plane(l, n, p0);
}

/* A round brilliant with `fold` mains and a girdle of `ngirdle` facets
 * (8, 64: the classic 57-facet crown and pavilion pattern with a 64-facet
 * girdle; 16, 128: a "jubilee" with twice the facets, for large scans;
 * 16, 96: the jubilee's crown and pavilion on a 96-facet girdle). */
static void brilliant(plane_list *l, uint64_t *rng, int fold, int ngirdle)
{
    const double R = 3.25, deg = M_PI / 180;
    double girdle = 0.03 * 2 * R * (1 + jitter(rng, 0.2));
    double zt = girdle / 2, zb = -girdle / 2;
    double crown = (34.5 + jitter(rng, 1.5)) * deg;
    double pav = (40.75 + jitter(rng, 0.6)) * deg;
    double table_h = zt + (R * (1 - (0.56 + jitter(rng, 0.02)))) * tan(crown);
    double rot = jitter(rng, M_PI);
    for (int k = 0; k < ngirdle; k++) {
        double phi = rot + k * 2 * M_PI / ngirdle, n[3] = {cos(phi), sin(phi), 0};
        double p0[3] = {R * n[0], R * n[1], 0};
        add_plane(l, n, p0);
    }
    double up[3] = {0, 0, 1}, top[3] = {0, 0, table_h};
    add_plane(l, up, top);
    double w = M_PI / fold; /* half the angle between mains */
    for (int k = 0; k < fold; k++) {
        double phi = rot + k * 2 * w;
        add_inclined(l, phi, crown, R, zt, 1); /* bezel */
        /* star: shallower, between bezels, reaching the table edge */
        double star = crown * (0.62 + jitter(rng, 0.03));
        double rs = R * (0.56 + 0.5 * (1 - 0.56)) * cos(w);
        double zs = zt + (R - rs) * tan(crown) * 0.98;
        add_inclined(l, phi + w, star, rs, zs, 1);
        /* upper girdle halves: steeper, either side of the bezel corner */
        double ug = crown * (1.12 + jitter(rng, 0.02));
        add_inclined(l, phi + w - w / 4, ug, R, zt, 1);
        add_inclined(l, phi + w + w / 4, ug, R, zt, 1);
        /* pavilion main and lower girdle halves */
        add_inclined(l, phi, pav, R, zb, -1);
        double lg = pav * (1.03 + jitter(rng, 0.005));
        add_inclined(l, phi + w - w / 4, lg, R, zb, -1);
        add_inclined(l, phi + w + w / 4, lg, R, zb, -1);
    }
}

/* A step cut: a rectangular (princess) or octagonal (emerald) girdle,
 * tiers of crown and pavilion facets at increasing angles. */
static void step_cut(plane_list *l, uint64_t *rng, bool octagon)
{
    const double deg = M_PI / 180;
    double a = 3.25, b = octagon ? 3.25 * (0.7 + jitter(rng, 0.05)) : 3.25;
    double girdle = 0.1 * (1 + jitter(rng, 0.2));
    double zt = girdle / 2, zb = -girdle / 2;
    double rot = jitter(rng, 0.3);
    int sides = octagon ? 8 : 4;
    /* girdle outline: rectangle, or rectangle with cut corners */
    double outline_phi[8], outline_r[8];
    for (int s = 0; s < sides; s++) {
        double phi = s * 2 * M_PI / sides;
        double c = cos(phi), sn = sin(phi);
        double r = octagon && (s % 2)
                       ? 0.82 * (a + b) / 2 * (1 + jitter(rng, 0.03))
                       : (fabs(c) > fabs(sn) ? a : b);
        outline_phi[s] = rot + phi;
        outline_r[s] = r;
        double n[3] = {cos(rot + phi), sin(rot + phi), 0};
        double p0[3] = {r * n[0], r * n[1], 0};
        add_plane(l, n, p0);
    }
    int tiers = octagon ? 3 : 2;
    double crown0 = (octagon ? 40 : 35 + jitter(rng, 3)) * deg;
    double pav0 = (octagon ? 50 : 42 + jitter(rng, 2)) * deg;
    for (int s = 0; s < sides; s++) {
        double phi = outline_phi[s], r = outline_r[s];
        double zc = zt, zp = zb, rc = r, rp = r;
        for (int t = 0; t < tiers; t++) {
            double ca = crown0 - t * (octagon ? 8 : 10) * deg + jitter(rng, 0.5 * deg);
            double pa = pav0 - t * (octagon ? 8 : 6) * deg + jitter(rng, 0.5 * deg);
            add_inclined(l, phi, ca, rc, zc, 1);
            add_inclined(l, phi, pa, rp, zp, -1);
            double step = r * (octagon ? 0.1 : 0.14);
            zc += step * tan(ca);
            rc -= step;
            zp -= 1.6 * step * tan(pa);
            rp -= 1.6 * step;
        }
        if (!octagon) { /* princess chevrons */
            double pa = (pav0 + 3 * deg) + jitter(rng, 0.5 * deg);
            add_inclined(l, phi + M_PI / 8, pa, r * 0.95, zb, -1);
            add_inclined(l, phi - M_PI / 8, pa, r * 0.95, zb, -1);
        }
    }
    double up[3] = {0, 0, 1}, top[3] = {0, 0, zt + 0.35 * a * (1 + jitter(rng, 0.1))};
    add_plane(l, up, top);
    double dn[3] = {0, 0, -1}, bot[3] = {0, 0, zb - (octagon ? 2.2 : 2.8) * a * 0.5};
    add_plane(l, dn, bot);
}

geo_poly *sim_stone(enum sim_cut cut, uint64_t seed)
{
    uint64_t rng = seed * 0x9e3779b97f4a7c15ULL + 1;
    plane_list l = {0};
    if (cut == SIM_BRILLIANT)
        brilliant(&l, &rng, 8, 64);
    else if (cut == SIM_JUBILEE)
        brilliant(&l, &rng, 16, 128);
    else if (cut == SIM_JUBILEE96)
        brilliant(&l, &rng, 16, 96);
    else
        step_cut(&l, &rng, cut == SIM_EMERALD);
    geo_poly *p = sim_halfspace_intersection(l.v, l.n, 10.0);
    free(l.v);
    return p;
}

/* ---- scanning ---------------------------------------------------- */

typedef struct pt2 {
    double x, y;
    uint32_t id; /* the stone's vertex it is the projection of */
} pt2;

static int cmp_pt2(const void *a, const void *b)
{
    const pt2 *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    return (p->y > q->y) - (p->y < q->y);
}

static double cross2(pt2 o, pt2 a, pt2 b)
{
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
}

/* Andrew's monotone chain; returns the hull counter-clockwise in h. */
static uint32_t hull2(pt2 *p, uint32_t n, pt2 *h)
{
    qsort(p, n, sizeof *p, cmp_pt2);
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++) {
        while (k >= 2 && cross2(h[k - 2], h[k - 1], p[i]) <= 0)
            k--;
        h[k++] = p[i];
    }
    for (uint32_t i = n - 1, t = k + 1; i-- > 0;) {
        while (k >= t && cross2(h[k - 2], h[k - 1], p[i]) <= 0)
            k--;
        h[k++] = p[i];
    }
    return k > 1 ? k - 1 : k;
}

static double gauss(uint64_t *rng)
{
    double u = geo_rand_unit(rng) + 1e-300, v = geo_rand_unit(rng);
    return sqrt(-2 * log(u)) * cos(2 * M_PI * v);
}

/* Adds the half-spaces of the silhouette seen along e1 × e2, projected
 * onto (e1, e2). */
static void add_silhouette(plane_list *l, const geo_poly *stone,
                           const double e1[3],
                           const double e2[3], double noise, uint64_t *rng)
{
    uint32_t n = stone->nverts;
    pt2 *p = malloc((n + 1) * sizeof *p), *h = malloc((2 * n + 2) * sizeof *h);
    for (uint32_t i = 0; i < n; i++) {
        p[i].x = geo_vdot(stone->verts[i], e1) + noise * gauss(rng);
        p[i].y = geo_vdot(stone->verts[i], e2) + noise * gauss(rng);
        p[i].id = i;
    }
    uint32_t k = hull2(p, n, h);
    for (uint32_t i = 0; i < k; i++) {
        pt2 a = h[i], b = h[(i + 1) % k];
        /* outward 2D normal of the ccw edge a→b is (dy, −dx) */
        double nx = b.y - a.y, ny = -(b.x - a.x);
        double nrm[3], p0[3];
        for (int j = 0; j < 3; j++) {
            nrm[j] = nx * e1[j] + ny * e2[j];
            p0[j] = a.x * e1[j] + a.y * e2[j];
        }
        add_plane(l, nrm, p0);
    }
    free(p);
    free(h);
}

uint32_t sim_silhouette(const geo_poly *stone, const double e1[3],
                        const double e2[3], uint32_t *ids)
{
    uint32_t n = stone->nverts;
    pt2 *p = malloc((n + 1) * sizeof *p), *h = malloc((2 * n + 2) * sizeof *h);
    uint32_t k = 0;
    if (p && h) {
        for (uint32_t i = 0; i < n; i++)
            p[i] = (pt2){geo_vdot(stone->verts[i], e1),
                         geo_vdot(stone->verts[i], e2), i};
        k = hull2(p, n, h);
        for (uint32_t i = 0; i < k; i++)
            ids[i] = h[i].id;
    }
    free(p);
    free(h);
    return k;
}

geo_poly *sim_scan(const geo_poly *stone, uint32_t k, double noise,
                   uint64_t seed)
{
    return sim_scan_phase(stone, k, noise, 0, seed);
}

void sim_rotate_z(geo_poly *p, double angle)
{
    double c = cos(angle), s = sin(angle);
    for (uint32_t i = 0; i < p->nverts; i++) {
        double x = p->verts[i][0], y = p->verts[i][1];
        p->verts[i][0] = c * x - s * y;
        p->verts[i][1] = s * x + c * y;
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double x = p->planes[f][0], y = p->planes[f][1];
        p->planes[f][0] = c * x - s * y;
        p->planes[f][1] = s * x + c * y;
    }
}

void sim_view_basis(uint32_t k, double phase, uint32_t i, double e1[3],
                    double e2[3])
{
    if (i >= k) { /* the top view, along z */
        memcpy(e1, (double[3]){1, 0, 0}, 3 * sizeof *e1);
        memcpy(e2, (double[3]){0, 1, 0}, 3 * sizeof *e2);
        return;
    }
    double th = phase + M_PI * i / k;
    memcpy(e1, (double[3]){-sin(th), cos(th), 0}, 3 * sizeof *e1);
    memcpy(e2, (double[3]){0, 0, 1}, 3 * sizeof *e2);
}

geo_poly *sim_scan_phase(const geo_poly *stone, uint32_t k, double noise,
                         double phase, uint64_t seed)
{
    uint64_t rng = seed * 0xd1b54a32d192ed03ULL + 7;
    noise = fmax(noise, SIM_NOISE_FLOOR);
    plane_list l = {0};
    for (uint32_t i = 0; i <= k; i++) {
        double e1[3], e2[3];
        sim_view_basis(k, phase, i, e1, e2);
        add_silhouette(&l, stone, e1, e2, noise, &rng);
    }
    geo_poly *p = sim_halfspace_intersection(l.v, l.n, 10.0);
    free(l.v);
    return p;
}

/* ---- Hausdorff ---------------------------------------------------- */

static double seg_dist2(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3];
    geo_vsub(b, a, ab);
    geo_vsub(p, a, ap);
    double l2 = geo_vdot(ab, ab);
    double t = l2 > 0 ? geo_vdot(ap, ab) / l2 : 0;
    t = t < 0 ? 0 : (t > 1 ? 1 : t);
    double c[3], d[3];
    geo_vmadd(a, t, ab, c);
    geo_vsub(p, c, d);
    return geo_vdot(d, d);
}

/* Squared distance from p to facet f (a planar polygon). */
double sim_facet_dist2(const geo_poly *g, uint32_t f, const double p[3])
{
    uint32_t n = geo_poly_facet_size(g, f);
    const uint32_t *v = geo_poly_facet(g, f);
    const double *pl = g->planes[f];
    double s = geo_plane_eval(pl, p), q[3];
    geo_vmadd(p, -s, pl, q);
    /* winding of the projected point around the polygon, in the plane */
    double wind = 0;
    for (uint32_t i = 0; i < n; i++) {
        double a[3], b[3], c[3];
        geo_vsub(g->verts[v[i]], q, a);
        geo_vsub(g->verts[v[(i + 1) % n]], q, b);
        geo_vcross(a, b, c);
        wind += atan2(geo_vdot(c, pl), geo_vdot(a, b));
    }
    if (fabs(wind) > M_PI)
        return s * s;
    double best = INFINITY;
    for (uint32_t i = 0; i < n; i++) {
        double d2 = seg_dist2(p, g->verts[v[i]], g->verts[v[(i + 1) % n]]);
        if (d2 < best)
            best = d2;
    }
    return best;
}

static double box_dist2(const geo_bbox *b, const double p[3])
{
    double s = 0;
    for (int k = 0; k < 3; k++) {
        double d = p[k] < b->lo[k] ? b->lo[k] - p[k]
                                   : (p[k] > b->hi[k] ? p[k] - b->hi[k] : 0);
        s += d * d;
    }
    return s;
}

static void nearest(const geo_poly *g, const geo_bvh *h, uint32_t node,
                    const double p[3], double *best)
{
    const geo_bvh_node *n = &h->nodes[node];
    if (box_dist2(&n->box, p) >= *best)
        return;
    if (n->count) {
        for (uint32_t i = n->child; i < n->child + n->count; i++) {
            double d2 = sim_facet_dist2(g, h->items[i], p);
            if (d2 < *best)
                *best = d2;
        }
        return;
    }
    uint32_t a = n->child, b = n->child + 1;
    if (box_dist2(&h->nodes[b].box, p) < box_dist2(&h->nodes[a].box, p)) {
        uint32_t t = a;
        a = b;
        b = t;
    }
    nearest(g, h, a, p, best);
    nearest(g, h, b, p, best);
}

double sim_hausdorff_directed(const geo_poly *a, const geo_poly *b,
                              uint32_t samples)
{
    geo_bvh *h = geo_bvh_build_facets(b, NULL);
    double worst = 0, area = geo_poly_area(a);
    uint64_t rng = 42;
    for (uint32_t f = 0; f < a->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(a, f);
        const uint32_t *v = geo_poly_facet(a, f);
        uint32_t ns = 1 + (uint32_t)(samples * geo_poly_facet_area(a, f) /
                                     (area > 0 ? area : 1));
        for (uint32_t s = 0; s <= ns + n; s++) {
            double p[3];
            if (s < n) { /* every vertex */
                memcpy(p, a->verts[v[s]], sizeof p);
            } else { /* random points of the fan triangles */
                uint32_t t = 1 + (uint32_t)(geo_rand_next(&rng) % (n - 2));
                double r1 = geo_rand_unit(&rng), r2 = geo_rand_unit(&rng);
                if (r1 + r2 > 1)
                    r1 = 1 - r1, r2 = 1 - r2;
                const double *A = a->verts[v[0]], *B = a->verts[v[t]],
                             *C = a->verts[v[t + 1]];
                for (int k = 0; k < 3; k++)
                    p[k] = A[k] + r1 * (B[k] - A[k]) + r2 * (C[k] - A[k]);
            }
            double best = INFINITY;
            nearest(b, h, 0, p, &best);
            if (best > worst)
                worst = best;
        }
    }
    geo_bvh_free(h);
    return sqrt(worst);
}

double sim_hausdorff(const geo_poly *a, const geo_poly *b, uint32_t samples)
{
    double x = sim_hausdorff_directed(a, b, samples);
    double y = sim_hausdorff_directed(b, a, samples);
    return x > y ? x : y;
}
