/* orient.c — 2-colouring of facets across two-corner edges (BFS), shell
 * volumes, and the flip repair (model: orient.h). Invariant: the analysis
 * never changes the polyhedron; the repair changes it only after the
 * analysis succeeded, so on any error p is as it was. */
#include "orient.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "selfint.h"
#include "vec.h"

const char *geo_orientation_name(enum geo_orientation o)
{
    switch (o) {
    case GEO_ORIENT_OUTWARD:
        return "outward";
    case GEO_ORIENT_INWARD:
        return "inward";
    default:
        return "inconsistent";
    }
}

/* Facet f's share of the signed volume about o (fan of triangles). */
static double facet_volume(const geo_poly *p, uint32_t f, const double o[3])
{
    return geo_fan_volume6(0, (const double(*)[3])p->verts,
                           geo_poly_facet(p, f), geo_poly_facet_size(p, f),
                           o) / 6.0;
}

/* Ray parity state for one query point (a vertex of shell `self`). */
typedef struct ray_state {
    const geo_poly *p;
    const uint32_t *shell;
    const uint8_t *closed;
    uint32_t self;
    const double *x, *q;
    uint32_t *hits; /* shells crossed, with repetition */
    size_t nhits, cap;
    bool degenerate, oom;
} ray_state;

static bool ray_visit(void *user, uint32_t g)
{
    ray_state *r = user;
    uint32_t sg = r->shell[g];
    if (sg == r->self || !r->closed[sg])
        return true;
    geo_facet_shape sh;
    geo_facet_shape_of(r->p, g, &sh);
    int m = geo_segment_meets_facet(r->p, g, &sh, r->x, r->q);
    if (m == 0) {
        r->degenerate = true;
        return false;
    }
    if (m < 0)
        return true;
    if (r->nhits == r->cap) {
        size_t c = r->cap ? 2 * r->cap : 64;
        uint32_t *n = realloc(r->hits, c * sizeof *n);
        if (!n) {
            r->oom = true;
            return false;
        }
        r->hits = n;
        r->cap = c;
    }
    r->hits[r->nhits++] = sg;
    return true;
}

static int cmp_u32(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

/* depth[s]: how many other closed shells enclose shell s, by the parity
 * of a ray from one of its vertices (the ray test of "Tests of graphic elements": exact crossings,
 * a new direction or vertex whenever a ray touches a facet other than
 * by crossing its interior). Shells whose rays all degenerate keep depth
 * 0 (judged by their own sign). */
static int shell_depths(const geo_poly *p, const uint32_t *shell,
                        const uint32_t *queue, const uint32_t *first,
                        uint32_t nshells, const uint8_t *closed,
                        uint32_t *depth, geo_err *err)
{
    memset(depth, 0, nshells * sizeof *depth);
    uint32_t nclosed = 0;
    for (uint32_t s = 0; s < nshells; s++)
        nclosed += closed[s];
    if (nclosed == 0)
        return 0;
    geo_bvh *h = geo_bvh_build_facets(p, err);
    if (!h)
        return -ENOMEM;
    double len = 2.0 * (geo_poly_size(p) + 1.0);
    uint64_t rng = 0x6f7269656e74ULL;
    ray_state r = {p, shell, closed, 0, NULL, NULL, NULL, 0, 0, false, false};
    for (uint32_t s = 0; s < nshells && !r.oom; s++) {
        uint32_t size = first[s + 1] - first[s];
        for (uint32_t attempt = 0; attempt < 64; attempt++) {
            /* a new vertex every 4 attempts, a new direction each time */
            uint32_t f = queue[first[s] + (attempt / 4) % size];
            const double *x = p->verts[geo_poly_facet(p, f)[attempt / 4 %
                                           geo_poly_facet_size(p, f)]];
            double d[3], q[3];
            do {
                for (int k = 0; k < 3; k++)
                    d[k] = 2 * geo_rand_unit(&rng) - 1;
            } while (geo_vdot(d, d) > 1 || geo_vdot(d, d) < 1e-6);
            geo_vnormalize(d);
            geo_vmadd(x, len, d, q);
            geo_vsub(q, x, d);
            r.self = s, r.x = x, r.q = q, r.nhits = 0, r.degenerate = false;
            geo_bvh_query_ray(h, x, d, 1.0, ray_visit, &r);
            if (r.oom)
                break;
            if (r.degenerate)
                continue;
            if (r.nhits)
                qsort(r.hits, r.nhits, sizeof *r.hits, cmp_u32);
            for (size_t i = 0, j; i < r.nhits; i = j) {
                for (j = i; j < r.nhits && r.hits[j] == r.hits[i]; j++)
                    ;
                depth[s] += (j - i) % 2;
            }
            break;
        }
    }
    free(r.hits);
    geo_bvh_free(h);
    if (r.oom)
        return geo_err_set(err, -ENOMEM, "orientation: out of memory");
    return 0;
}

int geo_orient_analyze(const geo_poly *p, const geo_topo *t,
                       uint8_t *ret_flip, geo_orient_report *ret,
                       geo_err *err)
{
    uint32_t nf = p->nfacets;
    memset(ret, 0, sizeof *ret);
    uint8_t *colour = malloc((size_t)nf + 1);
    uint32_t *shell = malloc(((size_t)nf + 1) * sizeof *shell);
    uint32_t *queue = malloc(((size_t)nf + 1) * sizeof *queue);
    uint32_t *first = malloc(((size_t)nf + 2) * sizeof *first);
    uint32_t *depth = malloc(((size_t)nf + 1) * sizeof *depth);
    uint8_t *flip_colour = malloc((size_t)nf + 1);
    uint8_t *closed = malloc((size_t)nf + 1);
    double *vol = malloc(((size_t)nf + 1) * sizeof *vol);
    int rc = 0;
    if (!colour || !shell || !queue || !first || !depth || !flip_colour ||
        !closed || !vol) {
        rc = geo_err_set(err, -ENOMEM, "orientation: out of memory");
        goto out;
    }
    for (uint32_t f = 0; f < nf; f++)
        shell[f] = GEO_NONE;

    double lo[3], hi[3], o[3];
    geo_poly_bbox(p, lo, hi);
    geo_vadd(lo, hi, o);
    geo_vscale(o, 0.5, o);

    /* Shells are numbered in order of their lowest facet, and their facets
     * lie in queue[] contiguously in BFS order: shell s occupies
     * queue[first[s] .. first[s + 1]). */
    uint32_t head = 0, ns = 0;
    for (uint32_t f0 = 0; f0 < nf; f0++) {
        if (shell[f0] != GEO_NONE)
            continue;
        uint32_t s = ns++, tail = head;
        first[s] = head;
        closed[s] = 1;
        shell[f0] = s;
        colour[f0] = 0;
        queue[tail++] = f0;
        /* edges the colouring violates, each counted from its lower
         * corner: an odd cycle, the shell is not orientable. A facet's
         * colour is set once, when it is reached, so an edge is checked
         * when its lower corner's facet is taken from the queue: if the
         * other facet is not coloured yet it gets the wanted colour, and
         * the edge agrees. */
        uint32_t n1 = 0;
        while (head < tail) {
            uint32_t f = queue[head++];
            n1 += colour[f];
            for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++) {
                uint32_t m = t->mate[c];
                if (m == GEO_NONE) {
                    closed[s] = 0;
                    continue;
                }
                uint32_t g = geo_topo_facet(t, m);
                uint8_t want = colour[f] ^
                               (t->edge_kind[c] == GEO_EDGE_FLIPPED);
                if (shell[g] == GEO_NONE) {
                    shell[g] = s;
                    colour[g] = want;
                    queue[tail++] = g;
                } else if (c < m && colour[g] != want) {
                    ret->nconflict_edges++;
                }
            }
        }
        uint32_t size = tail - first[s];
        /* colour 0 holds the shell's lowest facet (f0): flip colour 1
         * unless it is the strict majority */
        flip_colour[s] = n1 > size - n1 ? 0 : 1;
        ret->ninconsistent += flip_colour[s] ? n1 : size - n1;
        vol[s] = 0;
        for (uint32_t k = first[s]; k < tail; k++) {
            uint32_t f = queue[k];
            double v = facet_volume(p, f, o);
            vol[s] += colour[f] == flip_colour[s] ? -v : v;
        }
        ret->volume += vol[s];
    }
    first[ns] = head;
    ret->nshells = ns;
    if (ns > 1 &&
        (rc = shell_depths(p, shell, queue, first, ns, closed, depth, err)) <
            0)
        goto out;
    for (uint32_t s = 0; s < ns; s++) {
        /* a shell inside an odd number of others bounds a cavity: its
         * volume is rightly negative */
        bool cavity = ns > 1 && depth[s] % 2;
        bool inverted = cavity ? vol[s] > 0 : vol[s] < 0;
        ret->ninverted_shells += inverted;
        if (ret_flip)
            for (uint32_t k = first[s]; k < first[s + 1]; k++) {
                uint32_t f = queue[k];
                ret_flip[f] =
                    (uint8_t)((colour[f] == flip_colour[s]) ^ inverted);
            }
    }
    ret->orientable = ret->nconflict_edges == 0;
    if (ret->ninconsistent || !ret->orientable)
        ret->orientation = GEO_ORIENT_INCONSISTENT;
    else if (ret->ninverted_shells == 0)
        ret->orientation = GEO_ORIENT_OUTWARD;
    else if (ret->ninverted_shells == ret->nshells)
        ret->orientation = GEO_ORIENT_INWARD;
    else
        ret->orientation = GEO_ORIENT_INCONSISTENT;
out:
    free(colour), free(shell), free(queue), free(first), free(depth);
    free(flip_colour), free(closed), free(vol);
    return rc;
}

int geo_orient_repair(geo_poly *p, geo_orient_report *ret, geo_err *err)
{
    geo_orient_report local;
    if (!ret)
        ret = &local;
    memset(ret, 0, sizeof *ret);
    int rc;
    geo_topo *t = geo_topo_build_checked(p, &rc, err);
    if (!t)
        return rc;
    uint8_t *flip = malloc((size_t)p->nfacets + 1);
    if (!flip) {
        geo_topo_free(t);
        return geo_err_set(err, -ENOMEM, "orientation: out of memory");
    }
    rc = geo_orient_analyze(p, t, flip, ret, err);
    geo_topo_free(t);
    if (rc == 0 && !ret->orientable)
        rc = geo_err_set(err, -EINVAL,
                         "orientation: the surface is not orientable (%u "
                         "edges conflict in every choice); nothing flipped",
                         ret->nconflict_edges);
    if (rc == 0) {
        for (uint32_t f = 0; f < p->nfacets; f++)
            if (flip[f]) {
                geo_poly_flip_facet(p, f);
                ret->nflipped++;
            }
    }
    free(flip);
    return rc;
}
