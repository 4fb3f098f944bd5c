/* gem_check.c — the shared checks of the F-rep triangulation tests on
 * cut gems (gem_check.h). */
#include "gem_check.h"

#include "testutil.h"

#include <math.h>
#include <stdlib.h>

#include "frep_json.h"
#include "gen_frep.h"
#include "selfint.h"
#include "topo.h"

geo_frep *gem_frep_from_json(json_t *j)
{
    geo_err err = {{0}};
    geo_frep *f = proto_frep_from_json(j, NULL, "gem", &err);
    if (!f)
        fail_msg("%s", err.msg);
    return f;
}

geo_poly *gem_triangulate(const geo_frep *f, uint32_t q, geo_tri_report *rep)
{
    geo_tri_opts o;
    geo_tri_opts_default(&o);
    o.quad_levels = q;
    o.binary_levels = q + 1;
    geo_poly *m = NULL;
    geo_err err = {{0}};
    int rc = geo_frep_triangulate(f, &o, NULL, &m, rep, &err);
    if (rc != 0)
        fail_msg("triangulate: %d %s", rc, err.msg);
    return m;
}

/* Closed, manifold, outward, a sphere's topology, no self-intersections
 * (counted again here, independently of the report), every vertex on
 * the surface, normals exact where the ring lies on one facet. */
void gem_assert_valid(const geo_poly *m, const geo_tri_report *rep,
                      const char *what)
{
    geo_topo *t = geo_topo_build(m, NULL);
    assert_non_null(t);
    if (!geo_topo_is_closed_manifold(t))
        fail_msg("%s: not a closed manifold", what);
    geo_topo_free(t);
    assert_true(geo_poly_volume(m) > 0);
    geo_selfint si;
    assert_int_equal(geo_selfint_find(m, NULL, NULL, NULL, &si, NULL), 0);
    if (si.count != 0)
        fail_msg("%s: %llu self-intersections", what,
                 (unsigned long long)si.count);
    assert_int_equal(si.ndegenerate, 0);
    geo_selfint_clear(&si);
    const geo_frep_metrics *q = &rep->quality;
    assert_int_equal(rep->self_intersections, 0);
    assert_int_equal(q->euler, 2);
    assert_int_equal(q->flipped_edges, 0);
    assert_int_equal(rep->fill.nopen, 0);
    assert_true(q->dev_max < 1e-9 * rep->voxel[0]);
    /* a fair share of the vertices lies inside facets (at Q_LEV 6 most
     * of a small gem's vertices are near some edge) */
    if (!(q->nsmooth > m->nverts / 8))
        fail_msg("%s: %u of %u vertices away from edges", what, q->nsmooth,
                 m->nverts);
    if (!(q->sdev_max < 1.0))
        fail_msg("%s: normal deviation away from edges %g°", what,
                 q->sdev_max);
}

/* The largest distance of the polytope's true edges from the mesh (d[0])
 * and, away from the corners, the median and 99th percentile. */
void gem_edge_distances(json_t *j, const geo_poly *m, double voxel,
                        double d[5])
{
    double *planes, *segs;
    int np = gf_halfspaces(j, &planes);
    assert_true(np > 0);
    int ns = gf_polytope_edges((const double(*)[4])planes, np, &segs);
    assert_true(ns > 0);
    gf_edge_distances(m, segs, ns, 0.25 * voxel, 1.5 * voxel, d);
    free(planes), free(segs);
}
