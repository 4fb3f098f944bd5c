/* cut_shapes.c — test polyhedra for the plane cut and a validity check. */
#include "cut_shapes.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctx.h"
#include "plane.h"
#include "topo.h"
#include "vec.h"

geo_poly *cs_prism(const double (*xy)[2], uint32_t n, double z0, double z1)
{
    double *v = malloc(2 * (size_t)n * 3 * sizeof *v);
    uint32_t *idx = malloc((2 * (size_t)n + 4 * (size_t)n) * sizeof *idx);
    uint32_t *start = malloc(((size_t)n + 3) * sizeof *start);
    geo_poly *p = NULL;
    if (!v || !idx || !start)
        goto done;
    for (uint32_t i = 0; i < n; i++) {
        v[3 * i] = v[3 * (n + i)] = xy[i][0];
        v[3 * i + 1] = v[3 * (n + i) + 1] = xy[i][1];
        v[3 * i + 2] = z0;
        v[3 * (n + i) + 2] = z1;
    }
    uint32_t c = 0, f = 0;
    start[f++] = c;
    for (uint32_t i = 0; i < n; i++)
        idx[c++] = n - 1 - i; /* bottom, seen from −z */
    start[f++] = c;
    for (uint32_t i = 0; i < n; i++)
        idx[c++] = n + i;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t j = (i + 1) % n;
        start[f++] = c;
        idx[c++] = i;
        idx[c++] = j;
        idx[c++] = n + j;
        idx[c++] = n + i;
    }
    start[f] = c;
    p = geo_poly_from_arrays(2 * n, v, n + 2, start, idx, NULL, NULL);
done:
    free(v), free(idx), free(start);
    return p;
}

geo_poly *cs_star_prism(uint32_t points, double r_in, double r_out, double h)
{
    double (*xy)[2] = malloc(2 * (size_t)points * sizeof *xy);
    if (!xy)
        return NULL;
    for (uint32_t i = 0; i < 2 * points; i++) {
        double a = M_PI * i / points + 0.1, r = i % 2 ? r_in : r_out;
        xy[i][0] = r * cos(a);
        xy[i][1] = r * sin(a);
    }
    geo_poly *p = cs_prism((const double(*)[2])xy, 2 * points, 0, h);
    free(xy);
    return p;
}

geo_poly *cs_comb_prism(uint32_t prongs)
{
    uint32_t n = 4 * prongs + 2;
    double (*xy)[2] = malloc(n * sizeof *xy);
    if (!xy)
        return NULL;
    double w = 2.0 * prongs - 1.0;
    uint32_t c = 0;
    xy[c][0] = 0, xy[c][1] = 0, c++;
    xy[c][0] = w, xy[c][1] = 0, c++;
    /* along the top of the bar from right to left, up and down each prong */
    for (uint32_t i = prongs; i-- > 0;) {
        double x1 = 2.0 * i + 1.0, x0 = 2.0 * i;
        xy[c][0] = x1, xy[c][1] = 8, c++;
        xy[c][0] = x0, xy[c][1] = 8, c++;
        if (i > 0) {
            xy[c][0] = x0, xy[c][1] = 2, c++;
            xy[c][0] = x0 - 1.0, xy[c][1] = 2, c++;
        }
    }
    /* the last prong's left side comes down to (0, 0) directly */
    geo_poly *p = cs_prism((const double(*)[2])xy, c, 0, 3);
    free(xy);
    return p;
}

geo_poly *cs_frame(void)
{
    static const double sq[2][4][2] = {{{0, 0}, {10, 0}, {10, 10}, {0, 10}},
                                       {{3, 3}, {7, 3}, {7, 7}, {3, 7}}};
    double v[16][3];
    /* 0..3 outer bottom, 4..7 inner bottom, 8..11 outer top, 12..15 inner top */
    for (int r = 0; r < 2; r++)
        for (int i = 0; i < 4; i++) {
            v[4 * r + i][0] = v[8 + 4 * r + i][0] = sq[r][i][0];
            v[4 * r + i][1] = v[8 + 4 * r + i][1] = sq[r][i][1];
            v[4 * r + i][2] = 0;
            v[8 + 4 * r + i][2] = 4;
        }
    uint32_t idx[16 * 4], start[17], c = 0, f = 0;
    for (uint32_t i = 0; i < 4; i++) {
        uint32_t j = (i + 1) % 4;
        uint32_t quads[4][4] = {
            {8 + i, 8 + j, 12 + j, 12 + i}, /* top trapezoid */
            {j, i, 4 + i, 4 + j},           /* bottom trapezoid */
            {i, j, 8 + j, 8 + i},           /* outer wall */
            {4 + j, 4 + i, 12 + i, 12 + j}, /* inner wall, facing in */
        };
        for (int q = 0; q < 4; q++) {
            start[f++] = c;
            for (int s = 0; s < 4; s++)
                idx[c++] = quads[q][s];
        }
    }
    start[f] = c;
    return geo_poly_from_arrays(16, &v[0][0], 16, start, idx, NULL, NULL);
}

geo_poly *cs_sphere(uint32_t nlat, uint32_t nlon, double bump)
{
    size_t nv = 2 + (size_t)(nlat - 1) * nlon;
    size_t nf = 2 * (size_t)nlon * (nlat - 1);
    double *v = malloc(nv * 3 * sizeof *v);
    uint32_t *idx = malloc(nf * 3 * sizeof *idx);
    uint32_t *start = malloc((nf + 1) * sizeof *start);
    geo_poly *p = NULL;
    if (!v || !idx || !start)
        goto done;
    size_t k = 0;
    for (uint32_t i = 0; i <= nlat; i++) {
        double th = M_PI * i / nlat;
        uint32_t cnt = (i == 0 || i == nlat) ? 1 : nlon;
        for (uint32_t j = 0; j < cnt; j++) {
            double ph = 2 * M_PI * j / nlon;
            double r = 1 + bump * sin(5 * th) * sin(4 * ph);
            v[3 * k] = r * sin(th) * cos(ph);
            v[3 * k + 1] = r * sin(th) * sin(ph);
            v[3 * k + 2] = r * cos(th);
            k++;
        }
    }
    /* ring i (1..nlat−1) vertex j has index 1 + (i−1)·nlon + j */
#define RV(i, j) (1 + ((i)-1) * nlon + ((j) % nlon))
    uint32_t south = (uint32_t)(nv - 1);
    size_t c = 0, f = 0;
    for (uint32_t j = 0; j < nlon; j++) {
        start[f++] = (uint32_t)c;
        idx[c++] = 0, idx[c++] = RV(1, j), idx[c++] = RV(1, j + 1);
        start[f++] = (uint32_t)c;
        idx[c++] = south, idx[c++] = RV(nlat - 1, j + 1),
        idx[c++] = RV(nlat - 1, j);
    }
    for (uint32_t i = 1; i + 1 < nlat; i++)
        for (uint32_t j = 0; j < nlon; j++) {
            start[f++] = (uint32_t)c;
            idx[c++] = RV(i, j), idx[c++] = RV(i + 1, j),
            idx[c++] = RV(i + 1, j + 1);
            start[f++] = (uint32_t)c;
            idx[c++] = RV(i, j), idx[c++] = RV(i + 1, j + 1),
            idx[c++] = RV(i, j + 1);
        }
#undef RV
    start[f] = (uint32_t)c;
    p = geo_poly_from_arrays((uint32_t)nv, v, (uint32_t)nf, start, idx, NULL,
                             NULL);
done:
    free(v), free(idx), free(start);
    return p;
}

void cs_random_planes(uint64_t *seed, uint32_t m, double (*planes)[4])
{
    for (uint32_t i = 0; i < m; i++) {
        double n[3];
        do {
            for (int k = 0; k < 3; k++)
                n[k] = 2 * geo_rand_unit(seed) - 1;
        } while (geo_vdot(n, n) > 1 || geo_vdot(n, n) < 1e-3);
        geo_vnormalize(n);
        memcpy(planes[i], n, sizeof n);
        planes[i][3] = -1;
    }
    static const double tet[4][3] = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1},
                                     {-1, -1, 1}};
    for (int i = 0; i < 4; i++) {
        double n[3] = {tet[i][0], tet[i][1], tet[i][2]};
        geo_vnormalize(n);
        memcpy(planes[m + i], n, sizeof n);
        planes[m + i][3] = -3;
    }
}

typedef struct angled {
    double angle;
    uint32_t v;
} angled;

static int cmp_angle(const void *a, const void *b)
{
    double x = ((const angled *)a)->angle, y = ((const angled *)b)->angle;
    return (x > y) - (x < y);
}

geo_poly *cs_convex(const double (*planes)[4], uint32_t m, double tol)
{
    size_t cap = 64, nv = 0;
    double (*v)[3] = malloc(cap * sizeof *v);
    geo_poly *p = NULL;
    uint32_t *idx = NULL, *start = NULL;
    angled *ring = NULL;
    if (!v)
        return NULL;
    for (uint32_t i = 0; i < m; i++)
        for (uint32_t j = i + 1; j < m; j++)
            for (uint32_t k = j + 1; k < m; k++) {
                double x[3];
                if (!geo_plane_intersect3(planes[i], planes[j], planes[k], x))
                    continue;
                bool inside = true;
                for (uint32_t q = 0; q < m && inside; q++)
                    inside = geo_plane_eval(planes[q], x) <= tol;
                if (!inside)
                    continue;
                for (size_t s = 0; s < nv; s++)
                    if (geo_vdist(v[s], x) <= 10 * tol)
                        goto fail; /* four planes through one point */
                if (nv == cap) {
                    cap *= 2;
                    void *nvp = realloc(v, cap * sizeof *v);
                    if (!nvp)
                        goto fail;
                    v = nvp;
                }
                memcpy(v[nv++], x, sizeof x);
            }
    if (nv < 4)
        goto fail;
    idx = malloc(nv * m * sizeof *idx);
    start = malloc((m + 1) * sizeof *start);
    ring = malloc(nv * sizeof *ring);
    double (*pl)[4] = malloc(m * sizeof *pl);
    if (!idx || !start || !ring || !pl) {
        free(pl);
        goto fail;
    }
    uint32_t c = 0, nf = 0;
    for (uint32_t i = 0; i < m; i++) {
        uint32_t r = 0;
        double ctr[3] = {0, 0, 0};
        for (size_t s = 0; s < nv; s++)
            if (fabs(geo_plane_eval(planes[i], v[s])) <= tol) {
                ring[r++].v = (uint32_t)s;
                geo_vadd(ctr, v[s], ctr);
            }
        if (r < 3)
            continue;
        geo_vscale(ctr, 1.0 / r, ctr);
        double u[3], w[3];
        geo_vsub(v[ring[0].v], ctr, u);
        geo_vnormalize(u);
        geo_vcross(planes[i], u, w);
        for (uint32_t s = 0; s < r; s++) {
            double d[3];
            geo_vsub(v[ring[s].v], ctr, d);
            ring[s].angle = atan2(geo_vdot(d, w), geo_vdot(d, u));
        }
        qsort(ring, r, sizeof *ring, cmp_angle);
        start[nf] = c;
        memcpy(pl[nf], planes[i], sizeof pl[nf]);
        nf++;
        for (uint32_t s = 0; s < r; s++)
            idx[c++] = ring[s].v;
    }
    start[nf] = c;
    p = geo_poly_from_arrays((uint32_t)nv, &v[0][0], nf, start, idx, &pl[0][0],
                             NULL);
    free(pl);
fail:
    free(v), free(idx), free(start), free(ring);
    return p;
}

const char *cs_check_valid(const geo_poly *p, double tol)
{
    static char msg[256];
    if (geo_poly_validate_indices(p, NULL) < 0)
        return "invalid indices";
    geo_topo *t = geo_topo_build(p, NULL);
    if (!t)
        return "out of memory";
    const char *bad = NULL;
    if (!geo_topo_is_closed_manifold(t)) {
        snprintf(msg, sizeof msg,
                 "not a closed manifold: %u boundary, %u non-manifold, %u "
                 "flipped edges, %u non-manifold vertices",
                 t->nboundary_edges, t->nnonmanifold_edges, t->nflipped_edges,
                 t->nnonmanifold_vertices);
        bad = msg;
        goto done;
    }
    for (uint32_t v = 0; v < p->nverts; v++) {
        uint32_t deg = t->vstart[v + 1] - t->vstart[v];
        if (deg < 3) {
            snprintf(msg, sizeof msg, "vertex %u in %u facets", v, deg);
            bad = msg;
            goto done;
        }
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double a[3];
        geo_poly_facet_area_vector(p, f, a);
        if (fabs(geo_vlen(p->planes[f]) - 1) > 1e-12 ||
            !(geo_vdot(a, p->planes[f]) > 0)) {
            snprintf(msg, sizeof msg, "facet %u: plane not unit or not along "
                     "the facet's orientation", f);
            bad = msg;
            goto done;
        }
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *vs = geo_poly_facet(p, f);
        for (uint32_t j = 0; j < n; j++) {
            double d = geo_plane_eval(p->planes[f], p->verts[vs[j]]);
            if (fabs(d) > tol) {
                snprintf(msg, sizeof msg, "facet %u vertex %u: %.3g off its "
                         "plane", f, vs[j], d);
                bad = msg;
                goto done;
            }
        }
    }
    if (!(geo_poly_volume(p) > 0))
        bad = "volume not positive";
done:
    geo_topo_free(t);
    return bad;
}

geo_poly *cs_dented_box(double apex_z)
{
    double v[13][3] = {
        {0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0},
        {3, 3, 0}, {7, 3, 0}, {7, 7, 0}, {3, 7, 0}, {5, 5, apex_z},
        {0, 0, 10}, {10, 0, 10}, {10, 10, 10}, {0, 10, 10}};
    uint32_t idx[64], start[18], c = 0, f = 0;
    static const uint32_t top[4] = {9, 10, 11, 12};
    start[f++] = c;
    for (int i = 0; i < 4; i++)
        idx[c++] = top[i];
    for (uint32_t i = 0; i < 4; i++) {
        uint32_t j = (i + 1) % 4;
        uint32_t side[4] = {i, j, 9 + j, 9 + i};
        uint32_t trap[4] = {j, i, 4 + i, 4 + j};
        uint32_t dent[3] = {4 + j, 4 + i, 8};
        start[f++] = c;
        for (int q = 0; q < 4; q++)
            idx[c++] = side[q];
        start[f++] = c;
        for (int q = 0; q < 4; q++)
            idx[c++] = trap[q];
        start[f++] = c;
        for (int q = 0; q < 3; q++)
            idx[c++] = dent[q];
    }
    start[f] = c;
    return geo_poly_from_arrays(13, &v[0][0], f, start, idx, NULL, NULL);
}
