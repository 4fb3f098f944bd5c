/* merge_shapes.c — fixtures of the facet-merging tests (merge_shapes.h). */
#include "merge_shapes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "stats.h"
#include "topo.h"
#include "vec.h"

geo_poly *ms_dipped_l_prism(double dip)
{
    /* L corners in xz, counter-clockwise seen from −y (the front) */
    static const double L[6][2] = {{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}};
    double xyz[14 * 3];
    /* 0..5 front L (y = 0), 6..11 back L (y = 1), 12 front dip, 13 back dip */
    for (int i = 0; i < 6; i++) {
        double *f = xyz + 3 * i, *b = xyz + 3 * (i + 6);
        f[0] = b[0] = L[i][0];
        f[1] = 0;
        b[1] = 1;
        f[2] = b[2] = L[i][1];
    }
    double dips[2][3] = {{1.5, 0, -dip}, {1.5, 1, -dip}};
    for (int k = 0; k < 3; k++) {
        xyz[36 + k] = dips[0][k];
        xyz[39 + k] = dips[1][k];
    }
    /* facets listed clockwise seen from outside, turned over below */
    static const uint32_t idx[] = {
        /* bottom left, bottom right (the group) */
        0, 12, 13, 6,
        12, 1, 7, 13,
        /* front L (y = 0, outward −y) with the dip vertex */
        0, 5, 4, 3, 2, 1, 12,
        /* back L (y = 1, outward +y) */
        6, 13, 7, 8, 9, 10, 11,
        /* right x = 3, step top z = 1, inner x = 1, top z = 3, left x = 0 */
        1, 2, 8, 7,
        2, 3, 9, 8,
        3, 4, 10, 9,
        4, 5, 11, 10,
        5, 0, 6, 11,
    };
    static const uint32_t start[] = {0, 4, 8, 15, 22, 26, 30, 34, 38, 42};
    geo_poly *p = geo_poly_from_arrays(14, xyz, 9, start, idx, NULL, NULL);
    for (uint32_t f = 0; p && f < p->nfacets; f++)
        geo_poly_flip_facet(p, f);
    return p;
}

geo_poly *ms_chamfered_box(double size, double depth_top, double depth_side)
{
    const double s = size, a = size - depth_top, b = size - depth_side;
    const double xyz[10 * 3] = {
        0, 0, 0, s, 0, 0, 0, s, 0, s, s, 0, /* 0..3 bottom */
        0, 0, s, a, 0, s, 0, s, s, a, s, s, /* 4..7 top */
        s, 0, b, s, s, b,                   /* 8, 9 side */
    };
    /* counter-clockwise seen from outside */
    static const uint32_t idx[] = {
        0, 2, 3, 1,    /* z = 0 */
        4, 5, 7, 6,    /* z = size */
        0, 1, 8, 5, 4, /* y = 0 */
        2, 6, 7, 9, 3, /* y = size */
        0, 4, 6, 2,    /* x = 0 */
        1, 3, 9, 8,    /* x = size */
        7, 5, 8, 9,    /* the chamfer */
    };
    static const uint32_t start[] = {0, 4, 8, 13, 18, 22, 26, 30};
    return geo_poly_from_arrays(10, xyz, 7, start, idx, NULL, NULL);
}

uint32_t ms_coplanar_group(const geo_poly *p, uint32_t seed, double max_deg,
                           uint32_t n, uint32_t *ret)
{
    geo_topo *t = geo_topo_build(p, NULL);
    if (!t)
        return 0;
    double cosmax = cos(max_deg * M_PI / 180);
    uint32_t k = 0;
    ret[k++] = seed;
    for (uint32_t i = 0; i < k && k < n; i++) {
        uint32_t f = ret[i];
        for (uint32_t c = p->fstart[f]; c < p->fstart[f + 1] && k < n; c++) {
            uint32_t g = geo_topo_neighbor(t, c);
            bool have = g == GEO_NONE;
            for (uint32_t j = 0; j < k && !have; j++)
                have = ret[j] == g;
            if (!have && geo_vdot(p->planes[g], p->planes[seed]) >= cosmax)
                ret[k++] = g;
        }
    }
    geo_topo_free(t);
    return k;
}

const char *ms_invalid(const geo_poly *p)
{
    static char msg[1024];
    geo_stats st;
    geo_err err = {{0}};
    if (geo_inspect(p, NULL, NULL, &st, &err) < 0) {
        snprintf(msg, sizeof msg, "inspect failed: %s", err.msg);
        return msg;
    }
    const char *bad = NULL;
    if (!st.valid) {
        snprintf(msg, sizeof msg,
                 "closed %d, non-manifold vertices %u, low degree %u, "
                 "orientation %d, inverted %u, non-planarity %.3g (eps %.3g), "
                 "self-intersections %llu, degenerate facets %u",
                 st.closed, st.nonmanifold_vertices, st.low_degree_vertices,
                 (int)st.orientation, st.inverted_facets, st.max_nonplanarity,
                 st.eps, (unsigned long long)st.selfint.count,
                 st.degenerate_facets);
        bad = msg;
    }
    geo_stats_clear(&st);
    return bad;
}
