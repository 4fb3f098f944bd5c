/* stitch_trim.c — overlapping halves cut back to one plane (see
 * stitch_trim.h). */
#include "stitch_trim.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cut.h"
#include "plane.h"
#include "predicates.h"
#include "vec.h"

bool geo_loop_plane(const geo_poly *p, const uint32_t *v, uint32_t n,
                    double pl[4])
{
    double nw[3] = {0, 0, 0}, c[3] = {0, 0, 0};
    for (uint32_t q = 0; q < n; q++) {
        const double *a = p->verts[v[q]], *b = p->verts[v[(q + 1) % n]];
        nw[0] += (a[1] - b[1]) * (a[2] + b[2]);
        nw[1] += (a[2] - b[2]) * (a[0] + b[0]);
        nw[2] += (a[0] - b[0]) * (a[1] + b[1]);
        geo_vmadd(c, 1.0 / n, a, c);
    }
    if (!(geo_vnormalize(nw) > 0))
        return false;
    memcpy(pl, nw, sizeof nw);
    pl[3] = -geo_vdot(nw, c);
    return true;
}

/* The plane of loop v, planar within tol, turned so that its mesh's
 * body (the mean of its vertices) is on the positive side. */
static bool body_plane(const geo_poly *p, const uint32_t *v, uint32_t n,
                       double tol, double pl[4])
{
    if (n < 3 || !geo_loop_plane(p, v, n, pl))
        return false;
    for (uint32_t q = 0; q < n; q++)
        if (!(fabs(geo_plane_eval(pl, p->verts[v[q]])) <= tol))
            return false;
    double side = 0;
    for (uint32_t k = 0; k < p->nverts; k++)
        side += geo_plane_eval(pl, p->verts[k]);
    if (!(fabs(side) > 0))
        return false;
    if (side < 0)
        for (int k = 0; k < 4; k++)
            pl[k] = -pl[k];
    return true;
}

/* Whether every vertex of loop v (of p) is on pl's positive side, beyond
 * tol (exact signs). */
static bool loop_inside(const geo_poly *p, const uint32_t *v, uint32_t n,
                        const double pl[4], double tol)
{
    for (uint32_t q = 0; q < n; q++) {
        const double *x = p->verts[v[q]];
        if (geo_plane_sign(pl, x) <= 0 || !(geo_plane_eval(pl, x) > tol))
            return false;
    }
    return true;
}

/* p closed by its loop v as one facet, cut by plane (keeping ≤ 0), the
 * cut's facets on the plane dropped. NULL when the cut cannot be made
 * (an open mesh left open, an empty or untouched half) or memory fails
 * (*oom set). */
static geo_poly *trim_half(const geo_poly *p, const uint32_t *v, uint32_t n,
                           const double plane[4], bool *oom)
{
    geo_poly *closed = geo_poly_copy(p), *out = geo_poly_new();
    uint32_t *cap = malloc((size_t)n * sizeof *cap);
    bool *keep = NULL;
    geo_poly *ret = NULL;
    if (!closed || !out || !cap) {
        *oom = true;
        goto done;
    }
    for (uint32_t q = 0; q < n; q++)
        cap[q] = v[n - 1 - q]; /* the loop runs along the facets: reversed */
    int64_t f = geo_poly_add_facet(closed, cap, n);
    if (f < 0) {
        *oom = true;
        goto done;
    }
    geo_poly_facet_fit_plane(closed, (uint32_t)f, GEO_PLANE_UNWEIGHTED,
                             closed->planes[f]);
    geo_cut_report rep;
    geo_err err = {{0}};
    int rc = geo_cut(closed, plane, NULL, NULL, out, &rep, &err);
    if (rc == -ENOMEM)
        *oom = true;
    if (rc < 0 || rep.empty || rep.unchanged || rep.new_facets == 0 ||
        rep.first_new_facet == GEO_NONE)
        goto done;
    if (!(keep = malloc(((size_t)out->nfacets + 1) * sizeof *keep))) {
        *oom = true;
        goto done;
    }
    for (uint32_t g = 0; g < out->nfacets; g++)
        keep[g] = g < rep.first_new_facet;
    if (geo_poly_compact(out, keep, NULL, NULL) < 0) {
        *oom = true;
        goto done;
    }
    ret = out;
    out = NULL;
done:
    geo_poly_free(closed);
    geo_poly_free(out);
    free(cap);
    free(keep);
    return ret;
}

int geo_stitch_trim(const geo_poly *m1, const uint32_t *l1, uint32_t n1,
                    const geo_poly *m2, const uint32_t *l2, uint32_t n2,
                    double tol, geo_poly **t1, geo_poly **t2,
                    double mid[4])
{
    *t1 = *t2 = NULL;
    double p1[4], p2[4];
    if (!body_plane(m1, l1, n1, tol, p1) || !body_plane(m2, l2, n2, tol, p2))
        return 0;
    /* facing: the bodies' sides point at each other */
    if (!(geo_vdot(p1, p2) <= -sqrt(0.5)))
        return 0;
    if (!loop_inside(m2, l2, n2, p1, tol) || !loop_inside(m1, l1, n1, p2, tol))
        return 0;
    /* the plane midway: normal from mesh 1's body to mesh 2's, through
     * the mean of the loops' centres' projections on it */
    double m[3];
    geo_vsub(p2, p1, m);
    if (!(geo_vnormalize(m) > 0))
        return 0;
    double c1 = 0, c2 = 0;
    for (uint32_t q = 0; q < n1; q++)
        c1 += geo_vdot(m, m1->verts[l1[q]]) / n1;
    for (uint32_t q = 0; q < n2; q++)
        c2 += geo_vdot(m, m2->verts[l2[q]]) / n2;
    memcpy(mid, m, sizeof m);
    mid[3] = -(c1 + c2) / 2;
    /* mesh 1 keeps mid ≤ 0, mesh 2 the other side */
    double keep2[4] = {-mid[0], -mid[1], -mid[2], -mid[3]};
    bool oom = false;
    geo_poly *a = trim_half(m1, l1, n1, mid, &oom);
    geo_poly *b = a ? trim_half(m2, l2, n2, keep2, &oom) : NULL;
    if (!a || !b) {
        geo_poly_free(a);
        geo_poly_free(b);
        return oom ? -ENOMEM : 0;
    }
    *t1 = a;
    *t2 = b;
    return 1;
}
