/* gem_check.c — the shared checks of the F-rep triangulation tests on
 * cut gems (gem_check.h). No cmocka here: the support objects are linked
 * into the benchmarks and tools too, so problems come back as messages. */
#include "gem_check.h"

#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>

#include "frep_json.h"
#include "gen_frep.h"
#include "selfint.h"
#include "topo.h"

static char problem[512];

static const char *say(const char *fmt, ...)
    __attribute__((format(printf, 1, 2)));

static const char *say(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(problem, sizeof problem, fmt, ap);
    va_end(ap);
    return problem;
}

geo_frep *gem_frep_from_json(json_t *j, geo_err *err)
{
    return proto_frep_from_json(j, NULL, "gem", err);
}

geo_poly *gem_triangulate(const geo_frep *f, uint32_t q, geo_tri_report *rep,
                          geo_err *err)
{
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    o.quad_levels = q;
    o.binary_levels = q + 1;
    geo_poly *m = NULL;
    if (geo_triangulate(f, &o, NULL, &m, rep, err) != 0)
        return geo_poly_free(m);
    return m;
}

const char *gem_problem(const geo_poly *m, const geo_tri_report *rep,
                        const char *what)
{
    geo_topo *t = geo_topo_build(m, NULL);
    if (!t)
        return say("%s: no topology", what);
    bool closed = geo_topo_is_closed_manifold(t);
    geo_topo_free(t);
    if (!closed)
        return say("%s: not a closed manifold", what);
    if (!(geo_poly_volume(m) > 0))
        return say("%s: volume not positive", what);
    geo_selfint si;
    if (geo_selfint_find(m, NULL, NULL, NULL, &si, NULL) != 0)
        return say("%s: the self-intersection search failed", what);
    uint64_t count = si.count, ndeg = si.ndegenerate;
    geo_selfint_clear(&si);
    if (count != 0)
        return say("%s: %llu self-intersections", what,
                   (unsigned long long)count);
    if (ndeg != 0)
        return say("%s: %llu degenerate facets", what,
                   (unsigned long long)ndeg);
    const geo_frep_metrics *q = &rep->quality;
    if (rep->self_intersections != 0)
        return say("%s: the report counts self-intersections", what);
    if (q->euler != 2)
        return say("%s: Euler characteristic %d", what, (int)q->euler);
    if (q->flipped_edges != 0)
        return say("%s: %u flipped edges", what, (unsigned)q->flipped_edges);
    if (rep->fill.nopen != 0)
        return say("%s: %u holes left open", what, (unsigned)rep->fill.nopen);
    if (!(q->dev_max < 1e-9 * rep->voxel[0]))
        return say("%s: vertex deviation %g", what, q->dev_max);
    /* a fair share of the vertices lies inside facets (at Q_LEV 6 most
     * of a small gem's vertices are near some edge) */
    if (!(q->nsmooth > m->nverts / 8))
        return say("%s: %u of %u vertices away from edges", what,
                   q->nsmooth, m->nverts);
    if (!(q->sdev_max < 1.0))
        return say("%s: normal deviation away from edges %g°", what,
                   q->sdev_max);
    return NULL;
}

int gem_edge_distances(json_t *j, const geo_poly *m, double voxel,
                       double d[5])
{
    double *planes = NULL, *segs = NULL;
    int np = gf_halfspaces(j, &planes);
    int ns = np > 0 ? gf_polytope_edges((const double(*)[4])planes, np, &segs)
                    : 0;
    if (ns > 0)
        gf_edge_distances(m, segs, ns, 0.25 * voxel, 1.5 * voxel, d);
    free(planes), free(segs);
    return ns > 0 ? 0 : -1;
}
