/* orient.c — 2-colouring of facets across two-corner edges (BFS), shell
 * volumes, and the flip repair (model: orient.h). Invariant: the analysis
 * never changes the polyhedron; the repair changes it only after the
 * analysis succeeded, so on any error p is as it was. */
#include "orient.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

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
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    double a[3], vol = 0;
    geo_vsub(p->verts[v[0]], o, a);
    for (uint32_t i = 1; i + 1 < n; i++) {
        double b[3], c[3], bc[3];
        geo_vsub(p->verts[v[i]], o, b);
        geo_vsub(p->verts[v[i + 1]], o, c);
        geo_vcross(b, c, bc);
        vol += geo_vdot(a, bc);
    }
    return vol / 6.0;
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
    if (!colour || !shell || !queue) {
        free(colour), free(shell), free(queue);
        return geo_err_set(err, -ENOMEM, "orientation: out of memory");
    }
    for (uint32_t f = 0; f < nf; f++)
        shell[f] = GEO_NONE;

    double lo[3], hi[3], o[3];
    geo_poly_bbox(p, lo, hi);
    geo_vadd(lo, hi, o);
    geo_vscale(o, 0.5, o);

    /* Shells are numbered in order of their lowest facet, and their facets
     * lie in queue[] contiguously in BFS order: shell s occupies
     * queue[first .. next first). */
    uint32_t head = 0;
    bool inconsistent = false;
    for (uint32_t f0 = 0; f0 < nf; f0++) {
        if (shell[f0] != GEO_NONE)
            continue;
        uint32_t s = ret->nshells++, first = head, tail = head;
        shell[f0] = s;
        colour[f0] = 0;
        queue[tail++] = f0;
        while (head < tail) {
            uint32_t f = queue[head++];
            for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++) {
                uint32_t m = t->mate[c];
                if (m == GEO_NONE)
                    continue;
                uint32_t g = t->corner_facet[m];
                uint8_t want = colour[f] ^
                               (t->edge_kind[c] == GEO_EDGE_FLIPPED);
                if (shell[g] == GEO_NONE) {
                    shell[g] = s;
                    colour[g] = want;
                    queue[tail++] = g;
                }
            }
        }
        /* edges the colouring violates, each counted from its lower
         * corner: an odd cycle, the shell is not orientable */
        for (uint32_t k = first; k < tail; k++) {
            uint32_t f = queue[k];
            for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1]; c++) {
                uint32_t m = t->mate[c];
                if (m == GEO_NONE || m < c)
                    continue;
                uint8_t want = colour[f] ^
                               (t->edge_kind[c] == GEO_EDGE_FLIPPED);
                if (colour[t->corner_facet[m]] != want)
                    ret->nconflict_edges++;
            }
        }
        uint32_t n1 = 0, size = tail - first;
        for (uint32_t k = first; k < tail; k++)
            n1 += colour[queue[k]];
        /* colour 0 holds the shell's lowest facet (f0): flip colour 1
         * unless it is the strict majority */
        uint8_t flip_colour = n1 > size - n1 ? 0 : 1;
        uint32_t nflip = flip_colour ? n1 : size - n1;
        ret->ninconsistent += nflip;
        if (nflip)
            inconsistent = true;
        double vol = 0;
        for (uint32_t k = first; k < tail; k++) {
            uint32_t f = queue[k];
            double v = facet_volume(p, f, o);
            vol += colour[f] == flip_colour ? -v : v;
        }
        bool inverted = vol < 0;
        if (inverted)
            ret->ninverted_shells++;
        ret->volume += vol;
        if (ret_flip)
            for (uint32_t k = first; k < tail; k++) {
                uint32_t f = queue[k];
                ret_flip[f] = (uint8_t)((colour[f] == flip_colour) ^ inverted);
            }
    }
    ret->orientable = ret->nconflict_edges == 0;
    if (inconsistent || !ret->orientable)
        ret->orientation = GEO_ORIENT_INCONSISTENT;
    else if (ret->ninverted_shells == 0)
        ret->orientation = GEO_ORIENT_OUTWARD;
    else if (ret->ninverted_shells == ret->nshells)
        ret->orientation = GEO_ORIENT_INWARD;
    else
        ret->orientation = GEO_ORIENT_INCONSISTENT;
    free(colour), free(shell), free(queue);
    return 0;
}

int geo_orient_repair(geo_poly *p, geo_orient_report *ret, geo_err *err)
{
    geo_orient_report local;
    if (!ret)
        ret = &local;
    memset(ret, 0, sizeof *ret);
    int rc = geo_poly_validate_indices(p, err);
    if (rc < 0)
        return rc;
    geo_topo *t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
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
