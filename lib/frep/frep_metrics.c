/* frep_metrics.c — deviation, normal deviation, uniformity and topology
 * of a mesh against an F-rep object (see frep_metrics.h). */
#include "frep_metrics.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "topo.h"
#include "vec.h"

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double percentile(double *v, size_t n, double q)
{
    if (n == 0)
        return 0.0;
    qsort(v, n, sizeof *v, cmp_double);
    size_t k = (size_t)ceil(q * (double)n);
    return v[k == 0 ? 0 : (k > n ? n - 1 : k - 1)];
}

/* Angle at corner b of triangle a, b, c. */
static double corner_angle(const double *a, const double *b, const double *c)
{
    double u[3], v[3], x[3];
    geo_vsub(a, b, u);
    geo_vsub(c, b, v);
    geo_vcross(u, v, x);
    return atan2(geo_vlen(x), geo_vdot(u, v));
}

int geo_frep_mesh_metrics(const geo_frep *f, const geo_poly *m,
                          const geo_ctx *ctx, geo_frep_metrics *ret,
                          geo_err *err)
{
    geo_frep_metrics r = {.nverts = m->nverts, .nfacets = m->nfacets};
    uint32_t nv = m->nverts;
    double(*vn)[3] = calloc((size_t)nv + 1, sizeof *vn);
    uint32_t *piece = malloc(((size_t)nv + 1) * sizeof *piece);
    uint8_t *mixed = calloc((size_t)nv + 1, 1);
    uint8_t *used = calloc((size_t)nv + 1, 1);
    double *all = malloc(((size_t)nv + 1) * sizeof *all);
    double *smooth = malloc(((size_t)nv + 1) * sizeof *smooth);
    geo_topo *t = NULL;
    int rc = 0;
    if (!vn || !piece || !mixed || !used || !all || !smooth) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto out;
    }
    uint32_t nprog;
    const geo_frep_op *prog = geo_frep_program(f, &nprog);
    /* vertex normals, pieces, edges, areas */
    double esum = 0, esq = 0, asum = 0, asq = 0;
    uint64_t ne = 0;
    for (uint32_t v = 0; v < nv; v++) {
        if ((v & 65535) == 0 && geo_ctx_canceled(ctx))
            goto canceled;
        geo_frep_run_piece(f, prog, nprog, m->verts[v], NULL, &piece[v]);
    }
    for (uint32_t fc = 0; fc < m->nfacets; fc++) {
        if ((fc & 65535) == 0 && geo_ctx_canceled(ctx))
            goto canceled;
        const uint32_t *fv = geo_poly_facet(m, fc);
        uint32_t k = geo_poly_facet_size(m, fc);
        double a = geo_poly_facet_area(m, fc);
        asum += a;
        asq += a * a;
        for (uint32_t i = 0; i < k; i++) {
            uint32_t p = fv[(i + k - 1) % k], q = fv[i], s = fv[(i + 1) % k];
            used[q] = 1;
            double l = geo_vdist(m->verts[q], m->verts[s]);
            esum += l;
            esq += l * l;
            ne++;
            if (piece[q] != piece[s])
                mixed[q] = mixed[s] = 1;
            /* the corner's own normal, weighted by its angle */
            double e1[3], e2[3], n[3];
            geo_vsub(m->verts[s], m->verts[q], e1);
            geo_vsub(m->verts[p], m->verts[q], e2);
            geo_vcross(e1, e2, n);
            if (geo_vnormalize(n) > 0)
                geo_vmadd(vn[q],
                          corner_angle(m->verts[p], m->verts[q], m->verts[s]),
                          n, vn[q]);
        }
    }
    if (ne) {
        r.edge_mean = esum / (double)ne;
        double var = esq / (double)ne - r.edge_mean * r.edge_mean;
        r.edge_cv = r.edge_mean > 0 ? sqrt(fmax(var, 0)) / r.edge_mean : 0;
    }
    if (m->nfacets) {
        r.area_mean = asum / m->nfacets;
        double var = asq / m->nfacets - r.area_mean * r.area_mean;
        r.area_cv = r.area_mean > 0 ? sqrt(fmax(var, 0)) / r.area_mean : 0;
    }
    size_t na = 0, ns = 0, nd = 0;
    double dsum = 0, dsq = 0, nsum = 0, ssum = 0;
    for (uint32_t v = 0; v < nv; v++) {
        if ((v & 65535) == 0 && geo_ctx_canceled(ctx))
            goto canceled;
        if (!used[v])
            continue;
        double g[3], val = geo_frep_eval_grad(f, m->verts[v], g);
        double gl = geo_vlen_scaled(g);
        double dev = gl > 0 ? fabs(val) / gl : INFINITY;
        r.dev_max = fmax(r.dev_max, dev);
        dsum += dev;
        dsq += dev * dev;
        nd++;
        double n[3] = {vn[v][0], vn[v][1], vn[v][2]};
        if (geo_vnormalize(n) == 0 || !(gl > 0))
            continue;
        double c = -geo_vdot(n, g) / gl;
        double ang = acos(c > 1 ? 1 : (c < -1 ? -1 : c)) * 180.0 / M_PI;
        all[na++] = ang;
        nsum += ang;
        r.ndev_max = fmax(r.ndev_max, ang);
        if (!mixed[v]) {
            smooth[ns++] = ang;
            ssum += ang;
            r.sdev_max = fmax(r.sdev_max, ang);
        }
    }
    if (nd) {
        r.dev_mean = dsum / (double)nd;
        r.dev_rms = sqrt(dsq / (double)nd);
    }
    if (na) {
        r.ndev_mean = nsum / (double)na;
        r.ndev_p95 = percentile(all, na, 0.95);
    }
    r.nsmooth = (uint32_t)ns;
    if (ns) {
        r.sdev_mean = ssum / (double)ns;
        r.sdev_p95 = percentile(smooth, ns, 0.95);
    }
    if (geo_ctx_canceled(ctx))
        goto canceled;
    t = geo_topo_build(m, err);
    if (!t) {
        rc = -ENOMEM;
        goto out;
    }
    r.boundary_edges = t->nboundary_edges;
    r.nonmanifold_edges = t->nnonmanifold_edges;
    r.flipped_edges = t->nflipped_edges;
    r.nonmanifold_vertices = t->nnonmanifold_vertices;
    uint32_t nused = 0;
    for (uint32_t v = 0; v < nv; v++)
        nused += used[v];
    r.euler = (int64_t)nused - (int64_t)t->nedges + (int64_t)m->nfacets;
    r.volume = geo_poly_volume(m);
    r.area = geo_poly_area(m);
    *ret = r;
    goto out;
canceled:
    rc = geo_err_set(err, -ECANCELED, "canceled");
out:
    geo_topo_free(t);
    free(vn), free(piece), free(mixed), free(used), free(all), free(smooth);
    return rc;
}
