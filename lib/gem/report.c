/* report.c — proportions and facet table of a stone (report.h).
 *
 * Everything is measured in the table's frame: heights along the axis,
 * and the outline — the convex hull of the vertices projected on the
 * table plane (turns decided by geo_orient2d, so the hull is exact for
 * the projected doubles). Caliper widths of a convex polygon: the
 * smallest is the smallest over its edges of the farthest vertex from the
 * edge's line, the largest is its diameter. */
#include "report.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "predicates.h"
#include "surface.h"

#define DEG (M_PI / 180.0)

const char *geo_tier_name(enum geo_tier t)
{
    static const char *const names[] = {"table", "crown", "girdle",
                                        "pavilion", "culet"};
    return (unsigned)t < 5 ? names[t] : "unknown";
}

void geo_report_free(geo_report *r)
{
    if (r) {
        free(r->facets);
        free(r->scan);
        r->facets = NULL;
        r->scan = NULL;
    }
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static int cmp_pt(const void *pa, const void *pb)
{
    const double *a = pa, *b = pb;
    if (a[0] != b[0])
        return a[0] < b[0] ? -1 : 1;
    return (a[1] > b[1]) - (a[1] < b[1]);
}

/* Convex hull of n 2D points (sorted in place), counter-clockwise into
 * hull (room for n + 1); returns its size. */
static uint32_t hull2d(double (*pt)[2], uint32_t n, double (*hull)[2])
{
    qsort(pt, n, sizeof *pt, cmp_pt);
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++) {
        while (k >= 2 && geo_orient2d(hull[k - 2], hull[k - 1], pt[i]) <= 0)
            k--;
        memcpy(hull[k++], pt[i], sizeof *hull);
    }
    for (uint32_t i = n - 1, lo = k + 1; i-- > 0;) {
        while (k >= lo && geo_orient2d(hull[k - 2], hull[k - 1], pt[i]) <= 0)
            k--;
        memcpy(hull[k++], pt[i], sizeof *hull);
    }
    return k > 1 ? k - 1 : k;
}

static double facet_perimeter(const geo_poly *p, uint32_t f)
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *ix = geo_poly_facet(p, f);
    double per = 0;
    for (uint32_t k = 0; k < n; k++) {
        const double *a = p->verts[ix[k]], *b = p->verts[ix[(k + 1) % n]];
        per += sqrt((a[0] - b[0]) * (a[0] - b[0]) +
                    (a[1] - b[1]) * (a[1] - b[1]) +
                    (a[2] - b[2]) * (a[2] - b[2]));
    }
    return per;
}

/* The outline: perimeter, area centroid, caliper widths, length and
 * width (along and across the diameter). */
typedef struct outline {
    double perimeter, cx, cy, min_w, max_w, len, wid;
} outline;

static int measure_outline(const geo_poly *p, const double ex[3],
                           const double ey[3], outline *o)
{
    uint32_t n = p->nverts;
    double (*pt)[2] = malloc((size_t)n * sizeof *pt);
    double (*h)[2] = malloc(((size_t)n + 1) * sizeof *h);
    if (!pt || !h) {
        free(pt), free(h);
        return -ENOMEM;
    }
    for (uint32_t v = 0; v < n; v++)
        pt[v][0] = dot(p->verts[v], ex), pt[v][1] = dot(p->verts[v], ey);
    uint32_t m = hull2d(pt, n, h);
    memset(o, 0, sizeof *o);
    double area = 0;
    for (uint32_t i = 0; i < m; i++) {
        const double *a = h[i], *b = h[(i + 1) % m];
        double cr = a[0] * b[1] - b[0] * a[1];
        area += cr;
        o->cx += (a[0] + b[0]) * cr, o->cy += (a[1] + b[1]) * cr;
        o->perimeter += hypot(b[0] - a[0], b[1] - a[1]);
    }
    if (m < 3 || !(area > 0)) {
        free(pt), free(h);
        return -EINVAL;
    }
    o->cx /= 3 * area, o->cy /= 3 * area;
    o->min_w = INFINITY;
    for (uint32_t i = 0; i < m; i++) {
        const double *a = h[i], *b = h[(i + 1) % m];
        double len = hypot(b[0] - a[0], b[1] - a[1]), far = 0;
        for (uint32_t j = 0; j < m; j++)
            far = fmax(far, fabs((b[0] - a[0]) * (h[j][1] - a[1]) -
                                 (b[1] - a[1]) * (h[j][0] - a[0])) / len);
        o->min_w = fmin(o->min_w, far);
    }
    uint32_t bi = 0, bj = 0;
    for (uint32_t i = 0; i < m; i++)
        for (uint32_t j = i + 1; j < m; j++) {
            double d = hypot(h[i][0] - h[j][0], h[i][1] - h[j][1]);
            if (d > o->max_w)
                o->max_w = d, bi = i, bj = j;
        }
    double dx = (h[bj][0] - h[bi][0]) / o->max_w;
    double dy = (h[bj][1] - h[bi][1]) / o->max_w;
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t j = 0; j < m; j++) {
        double s = -dy * h[j][0] + dx * h[j][1];
        lo = fmin(lo, s), hi = fmax(hi, s);
    }
    o->len = o->max_w, o->wid = hi - lo;
    free(pt), free(h);
    return 0;
}

/* The extent of facet f along the axis a. */
static void facet_heights(const geo_poly *p, uint32_t f, const double a[3],
                          double *ret_lo, double *ret_hi)
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *ix = geo_poly_facet(p, f);
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t k = 0; k < n; k++) {
        double h = dot(p->verts[ix[k]], a);
        lo = fmin(lo, h), hi = fmax(hi, h);
    }
    *ret_lo = lo, *ret_hi = hi;
}

static void range_add(geo_range *r, double v, uint32_t *count)
{
    if (*count == 0)
        r->min = r->max = v;
    r->min = fmin(r->min, v), r->max = fmax(r->max, v);
    r->mean += v;
    (*count)++;
}

static void range_end(geo_range *r, uint32_t count)
{
    if (count)
        r->mean /= count;
}

int geo_report_compute(const geo_poly *p, const double *axis, uint32_t gear,
                       geo_report *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    if (p->nfacets == 0 || p->nverts < 4)
        return geo_err_set(err, -EINVAL, "an empty model has no "
                                         "proportions");
    if (gear == 0)
        return geo_err_set(err, -EINVAL, "gear: must have teeth");
    double m[3] = {0, 0, 1};
    if (axis) {
        double len = sqrt(dot(axis, axis));
        if (!(len > 0) || !isfinite(len))
            return geo_err_set(err, -EINVAL, "axis: not a direction");
        for (int k = 0; k < 3; k++)
            m[k] = axis[k] / len;
    }
    uint32_t table = UINT32_MAX;
    double best = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double a = geo_poly_facet_area(p, f);
        if (dot(p->planes[f], m) >= cos(10 * DEG) && a > best)
            best = a, table = f;
    }
    if (table == UINT32_MAX && !axis)
        return geo_err_set(err, -EINVAL, "no table: no facet's normal lies "
                           "within 10 degrees of the axis (0, 0, 1) (a rough "
                           "or a sphere?); give an axis");
    geo_report r = {.table_facet = table, .has_table = table != UINT32_MAX,
                    .nfacets = p->nfacets};
    memcpy(r.axis, r.has_table ? p->planes[table] : m, sizeof r.axis);
    const double *a = r.axis;
    /* azimuth 0: +y in the table plane (+x when the axis is near y) */
    double y[3] = {0, 1, 0};
    if (fabs(a[1]) > 0.9)
        y[0] = 1, y[1] = 0;
    double t = dot(y, a);
    for (int k = 0; k < 3; k++)
        r.ref[k] = y[k] - t * a[k];
    double rl = sqrt(dot(r.ref, r.ref));
    for (int k = 0; k < 3; k++)
        r.ref[k] /= rl;
    const double *ey = r.ref;
    double ex[3] = {ey[1] * a[2] - ey[2] * a[1], ey[2] * a[0] - ey[0] * a[2],
                    ey[0] * a[1] - ey[1] * a[0]};
    outline o;
    int e = measure_outline(p, ex, ey, &o);
    if (e == -ENOMEM)
        return geo_err_set(err, e, "out of memory");
    if (e < 0)
        return geo_err_set(err, e, "the model has no outline across its "
                                   "axis (flat along it)");
    r.facets = calloc(p->nfacets, sizeof *r.facets);
    if (!r.facets)
        return geo_err_set(err, -ENOMEM, "out of memory");
    double top = -INFINITY, bottom = INFINITY;
    for (uint32_t v = 0; v < p->nverts; v++) {
        double h = dot(p->verts[v], a);
        top = fmax(top, h), bottom = fmin(bottom, h);
    }
    /* tiers, and the girdle's extent along the axis */
    double g_hi = -INFINITY, g_lo = INFINITY;
    uint32_t ngirdle = 0, culet = UINT32_MAX;
    double culet_area = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double c = dot(p->planes[f], a);
        geo_report_facet *F = &r.facets[f];
        F->inclination_deg = acos(fmin(1.0, fabs(c))) / DEG;
        F->area_mm2 = geo_poly_facet_area(p, f);
        if (f == table)
            F->tier = GEO_TIER_TABLE;
        else if (fabs(c) <= sin(5 * DEG))
            F->tier = GEO_TIER_GIRDLE;
        else if (c < 0 && F->inclination_deg <= 5 && r.has_table)
            F->tier = GEO_TIER_CULET;
        else
            F->tier = c > 0 ? GEO_TIER_CROWN : GEO_TIER_PAVILION;
        r.tier_count[F->tier]++;
        if (F->tier == GEO_TIER_CULET && F->area_mm2 > culet_area)
            culet_area = F->area_mm2, culet = f;
        if (F->tier != GEO_TIER_GIRDLE)
            continue;
        double lo, hi;
        facet_heights(p, f, a, &lo, &hi);
        g_hi = fmax(g_hi, hi), g_lo = fmin(g_lo, lo);
        range_add(&r.girdle_thickness_percent, hi - lo, &ngirdle);
    }
    range_end(&r.girdle_thickness_percent, ngirdle);
    if (!ngirdle) { /* a knife-edge girdle: the level of the widest vertex */
        double far = -1;
        for (uint32_t v = 0; v < p->nverts; v++) {
            double px = dot(p->verts[v], ex) - o.cx;
            double py = dot(p->verts[v], ey) - o.cy;
            if (px * px + py * py > far)
                far = px * px + py * py, g_hi = g_lo = dot(p->verts[v], a);
        }
    }
    const double D = o.perimeter / M_PI;
    r.diameter_mm = (geo_range){o.min_w, o.max_w, D};
    r.length_mm = o.len, r.width_mm = o.wid;
    r.length_to_width = o.wid > 0 ? o.len / o.wid : 0;
    r.table_percent = r.has_table
                          ? 100 * facet_perimeter(p, table) / o.perimeter
                          : 0;
    r.total_depth_percent = 100 * (top - bottom) / D;
    double ch = top - g_hi, pd = g_lo - bottom;
    r.crown_height_percent = 100 * ch / D;
    r.pavilion_depth_percent = 100 * pd / D;
    r.girdle_thickness_percent.min *= 100 / D;
    r.girdle_thickness_percent.max *= 100 / D;
    r.girdle_thickness_percent.mean *= 100 / D;
    r.culet_percent = culet != UINT32_MAX
                          ? 100 * facet_perimeter(p, culet) / M_PI / D
                          : 0;
    double culet_h = bottom;
    if (culet != UINT32_MAX)
        culet_h = -p->planes[culet][3] / dot(p->planes[culet], a);
    double hmid = (g_hi + g_lo) / 2;
    for (int k = 0; k < 3; k++)
        r.center[k] = o.cx * ex[k] + o.cy * ey[k] + hmid * a[k];
    /* the mains, and the per-facet table */
    uint32_t ncm = 0, npm = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        geo_report_facet *F = &r.facets[f];
        const double *q = p->planes[f];
        double nx = dot(q, ex), ny = dot(q, ey);
        double az = hypot(nx, ny) > 1e-12 ? atan2(nx, ny) / DEG : 0.0;
        if (az < 0)
            az += 360;
        if (az >= 360)
            az -= 360;
        F->azimuth_deg = az;
        F->index = az * gear / 360.0;
        F->distance_mm = fabs(dot(q, r.center) + q[3]);
        if (F->tier != GEO_TIER_CROWN && F->tier != GEO_TIER_PAVILION)
            continue;
        double lo, hi;
        facet_heights(p, f, a, &lo, &hi);
        /* a main spans its part of the stone: from the table (culet) to
         * the girdle, so a sliver at either end is not one */
        if (F->tier == GEO_TIER_CROWN && hi >= top - 0.02 * ch &&
            lo <= g_hi + 0.10 * ch)
            range_add(&r.crown_angle_deg, F->inclination_deg, &ncm);
        if (F->tier == GEO_TIER_PAVILION && lo <= culet_h + 0.02 * pd &&
            hi >= g_lo - 0.10 * pd)
            range_add(&r.pavilion_angle_deg, F->inclination_deg, &npm);
    }
    range_end(&r.crown_angle_deg, ncm);
    range_end(&r.pavilion_angle_deg, npm);
    r.crown_mains = ncm, r.pavilion_mains = npm;
    *ret = r;
    return 0;
}

/* (b − o) × (d − o) */
static void cross_at(const double o[3], const double b[3], const double d[3],
                     double t[3])
{
    double u[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
    double v[3] = {d[0] - o[0], d[1] - o[1], d[2] - o[2]};
    t[0] = u[1] * v[2] - u[2] * v[1];
    t[1] = u[2] * v[0] - u[0] * v[2];
    t[2] = u[0] * v[1] - u[1] * v[0];
}

/* Accumulates one sample of the scan at x standing for area w. */
typedef struct dev_acc {
    double sum_w, sum_wd2, sum_d2;
} dev_acc;

static void dev_sample(const geo_surface *s, const double x[3], double w,
                       uint32_t *hint, geo_scan_deviation *dev, dev_acc *acc)
{
    uint32_t f = UINT32_MAX;
    double d2 = geo_surface_dist2(s, x, hint, &f);
    if (f == UINT32_MAX || !isfinite(d2))
        return;
    double d = sqrt(d2) * 1000.0;
    dev[f].samples++;
    dev[f].max_um = fmax(dev[f].max_um, d);
    acc[f].sum_w += w;
    acc[f].sum_wd2 += w * d * d;
    acc[f].sum_d2 += d * d;
}

int geo_report_scan_deviation(geo_report *r, const geo_poly *model,
                              const geo_poly *scan, geo_err *err)
{
    free(r->scan);
    r->scan = NULL;
    if (scan->nfacets == 0)
        return geo_err_set(err, -EINVAL, "the scan has no facets");
    geo_surface *s = NULL;
    int e = geo_surface_new(model, &s, err);
    if (e < 0)
        return e;
    geo_scan_deviation *dev = calloc(model->nfacets, sizeof *dev);
    dev_acc *acc = calloc(model->nfacets, sizeof *acc);
    if (!dev || !acc) {
        free(dev), free(acc);
        geo_surface_free(s);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    uint32_t hint = UINT32_MAX;
    for (uint32_t f = 0; f < scan->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(scan, f);
        const uint32_t *ix = geo_poly_facet(scan, f);
        if (n == 0)
            continue;
        /* the area centroid from the fan of the first corner: each
         * triangle weighted by its area along the facet's area vector */
        const double *o = scan->verts[ix[0]];
        double av[3] = {0, 0, 0}, c[3] = {0, 0, 0};
        for (uint32_t k = 1; k + 1 < n; k++) {
            double t[3];
            cross_at(o, scan->verts[ix[k]], scan->verts[ix[k + 1]], t);
            for (int j = 0; j < 3; j++)
                av[j] += t[j];
        }
        double al = sqrt(dot(av, av)), wsum = 0;
        for (uint32_t k = 1; k + 1 < n && al > 0; k++) {
            const double *b = scan->verts[ix[k]], *d = scan->verts[ix[k + 1]];
            double t[3];
            cross_at(o, b, d, t);
            double w = dot(t, av) / al;
            for (int j = 0; j < 3; j++)
                c[j] += w * (o[j] + b[j] + d[j]) / 3;
            wsum += w;
        }
        double area = al / 2;
        if (wsum != 0) {
            for (int j = 0; j < 3; j++)
                c[j] /= wsum;
        } else { /* a degenerate facet: its corners' mean */
            for (uint32_t k = 0; k < n; k++)
                for (int j = 0; j < 3; j++)
                    c[j] += scan->verts[ix[k]][j] / n;
        }
        dev_sample(s, c, area / 2, &hint, dev, acc);
        for (uint32_t k = 0; k < n; k++) {
            const double *a = scan->verts[ix[k]];
            const double *b = scan->verts[ix[(k + 1) % n]];
            double m[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2,
                           (a[2] + b[2]) / 2};
            dev_sample(s, a, area / (4.0 * n), &hint, dev, acc);
            dev_sample(s, m, area / (4.0 * n), &hint, dev, acc);
        }
    }
    for (uint32_t f = 0; f < model->nfacets; f++) {
        if (!dev[f].samples)
            continue;
        /* samples of zero area only (degenerate scan facets): unweighted */
        dev[f].rms_um = acc[f].sum_w > 0
                            ? sqrt(acc[f].sum_wd2 / acc[f].sum_w)
                            : sqrt(acc[f].sum_d2 / dev[f].samples);
    }
    free(acc);
    geo_surface_free(s);
    r->scan = dev;
    return 0;
}
