/* gen_frep.c — F-rep test objects and checks (see gen_frep.h). */
#include "gen_frep.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bvh.h"
#include "ctx.h"
#include "plane.h"
#include "vec.h"

static json_t *vec3(double x, double y, double z)
{
    return json_pack("[f,f,f]", x, y, z);
}

static json_t *object(json_t *shape, double lo, double hi)
{
    return json_pack("{s:s, s:[o,o], s:o}", "format", "frep-object/1",
                     "bounds", vec3(lo, lo, lo), vec3(hi, hi, hi), "shape",
                     shape);
}

static json_t *sphere(double x, double y, double z, double r)
{
    return json_pack("{s:{s:o, s:f}}", "sphere", "center", vec3(x, y, z),
                     "radius", r);
}

static json_t *ellipsoid(const double c[3], const double r[3])
{
    return json_pack("{s:{s:o, s:o}}", "ellipsoid", "center",
                     vec3(c[0], c[1], c[2]), "radii", vec3(r[0], r[1], r[2]));
}

json_t *gf_sphere(void)
{
    return object(sphere(0.03, -0.02, 0.01, 0.6), -1, 1);
}

json_t *gf_ellipsoid(void)
{
    static const double c[3] = {0, 0, 0}, r[3] = {0.8, 0.55, 0.4};
    return object(ellipsoid(c, r), -1, 1);
}

/* A perturbation term: shape plus amplitude. */
static json_t *term(json_t *shape, double amp)
{
    json_object_set_new(shape, "amplitude", json_real(amp));
    return shape;
}

json_t *gf_blob(uint64_t seed, int n)
{
    static const double c[3] = {0, 0, 0}, r[3] = {0.45, 0.35, 0.30};
    json_t *terms = json_array();
    uint64_t st = seed;
    for (int i = 0; i < n; i++) {
        /* a uniform direction, scaled onto the ellipsoid */
        double u[3], len;
        do {
            for (int k = 0; k < 3; k++)
                u[k] = 2 * geo_rand_unit(&st) - 1;
            len = geo_vlen(u);
        } while (len > 1 || len < 0.1);
        double q = 0;
        for (int k = 0; k < 3; k++)
            q += (u[k] / r[k]) * (u[k] / r[k]);
        double s = 1.0 / sqrt(q);
        double rad = 0.06 + 0.10 * geo_rand_unit(&st);
        /* height of the bump over the base surface, negative for a dent;
         * the base's |∇F| near the surface is about 2/0.35 */
        double h = (-0.35 + 0.95 * geo_rand_unit(&st)) * 0.5 * rad;
        double amp = h * (2.0 / 0.35) / pow(rad, 6);
        json_array_append_new(
            terms, term(sphere(u[0] * s, u[1] * s, u[2] * s, rad), amp));
    }
    json_t *shape = json_pack("{s:{s:o, s:o}}", "perturbed", "base",
                              ellipsoid(c, r), "perturbations", terms);
    return object(shape, -1, 1);
}

json_t *gf_torus(void)
{
    static const double c[3] = {0, 0, 0}, r[3] = {0.7, 0.7, 0.28};
    json_t *terms = json_array();
    /* q = 0.09 − x² − y²: a cylinder of radius 0.3 around z */
    json_array_append_new(
        terms, term(json_pack("{s:[f,f,f,f,f,f,f,f,f,f]}", "quadric", -1.0,
                              -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.09),
                    -6000.0));
    for (int i = 0; i < 12; i++) {
        double a = 2 * M_PI * i / 12.0, rad = 0.12;
        double h = (i % 2 ? 0.3 : -0.2) * rad;
        json_array_append_new(
            terms, term(sphere(0.62 * cos(a), 0.62 * sin(a), 0.12, rad),
                        h * (2.0 / 0.28) / pow(rad, 6)));
    }
    json_t *shape = json_pack("{s:{s:o, s:o}}", "perturbed", "base",
                              ellipsoid(c, r), "perturbations", terms);
    return object(shape, -1, 1);
}

/* The half-space of a facet tilted `tilt` degrees from horizontal, facing
 * azimuth `az` degrees, upwards (up = 1) or downwards, through point p. */
static json_t *facet(double az, double tilt, int up, const double p[3])
{
    double a = az * M_PI / 180, t = tilt * M_PI / 180;
    double n[3] = {sin(t) * cos(a), sin(t) * sin(a), up ? cos(t) : -cos(t)};
    return json_pack("{s:{s:[f,f,f,f]}}", "halfspace", "plane", n[0], n[1],
                     n[2], -geo_vdot(n, p));
}

json_t *gf_gem(void)
{
    const double R = 0.5, zgt = 0.02, zgb = -0.02, zt = 0.16;
    json_t *list = json_array();
    double top[3] = {0, 0, zt};
    json_array_append_new(list, facet(0, 0, 1, top));
    for (int k = 0; k < 8; k++) {
        double az = 45.0 * k, a = az * M_PI / 180;
        double pg[3] = {R * cos(a), R * sin(a), zgt};
        json_array_append_new(list, facet(az, 34.5, 1, pg)); /* bezel */
        double as = (az + 22.5) * M_PI / 180;
        double ps[3] = {0.62 * R * cos(as), 0.62 * R * sin(as), zt};
        json_array_append_new(list, facet(az + 22.5, 21.0, 1, ps)); /* star */
        double pb[3] = {R * cos(a), R * sin(a), zgb};
        json_array_append_new(list, facet(az, 40.75, 0, pb)); /* main */
        for (int s = -1; s <= 1; s += 2) {
            double au = (az + 22.5 + s * 11.25) * M_PI / 180;
            double pu[3] = {R * cos(au), R * sin(au), zgt};
            json_array_append_new(list, facet(az + 22.5 + s * 11.25, 42.0, 1,
                                              pu)); /* upper girdle */
            double pl[3] = {R * cos(au), R * sin(au), zgb};
            json_array_append_new(list, facet(az + 22.5 + s * 11.25, 42.5, 0,
                                              pl)); /* lower girdle */
        }
    }
    for (int k = 0; k < 16; k++) {
        double az = 22.5 * k + 11.25, a = az * M_PI / 180;
        double pg[3] = {R * cos(a), R * sin(a), 0};
        json_array_append_new(list, facet(az, 90.0, 1, pg)); /* girdle */
    }
    return object(json_pack("{s:o}", "intersection", list), -0.7, 0.7);
}

/* The half-space of a facet as facet() builds it, turned by the rotation
 * matrix rot (row-major) about the origin. */
static json_t *facet_rot(double az, double tilt, int up, const double p[3],
                         const double rot[9])
{
    double a = az * M_PI / 180, t = tilt * M_PI / 180;
    double n[3] = {sin(t) * cos(a), sin(t) * sin(a), up ? cos(t) : -cos(t)};
    double rn[3], rp[3];
    for (int i = 0; i < 3; i++) {
        rn[i] = rot[3 * i] * n[0] + rot[3 * i + 1] * n[1] + rot[3 * i + 2] * n[2];
        rp[i] = rot[3 * i] * p[0] + rot[3 * i + 1] * p[1] + rot[3 * i + 2] * p[2];
    }
    return json_pack("{s:{s:[f,f,f,f]}}", "halfspace", "plane", rn[0], rn[1],
                     rn[2], -geo_vdot(rn, rp));
}

json_t *gf_gem_random(uint64_t seed)
{
    uint64_t st = seed * 0x9e3779b97f4a7c15ull + 1;
    double R = 0.45 + 0.1 * geo_rand_unit(&st);
    double half = 0.005 + 0.025 * geo_rand_unit(&st); /* girdle */
    double zt = half + R * (0.15 + 0.2 * geo_rand_unit(&st));
    double crown = 28 + 10 * geo_rand_unit(&st), star = crown - 8 -
                   6 * geo_rand_unit(&st);
    double pav = 38 + 5 * geo_rand_unit(&st);
    double ug = crown + 4 + 6 * geo_rand_unit(&st);
    double lg = pav + 1 + 3 * geo_rand_unit(&st);
    double tab = 0.5 + 0.15 * geo_rand_unit(&st);
    double rot[9];
    if (seed % 2 == 0) {
        /* about the axis only: the girdle stays parallel to the rays */
        double a = 2 * M_PI * geo_rand_unit(&st);
        double r[9] = {cos(a), -sin(a), 0, sin(a), cos(a), 0, 0, 0, 1};
        memcpy(rot, r, sizeof r);
    } else {
        /* a uniform random rotation from a unit quaternion */
        double q[4], len;
        do {
            len = 0;
            for (int k = 0; k < 4; k++) {
                q[k] = 2 * geo_rand_unit(&st) - 1;
                len += q[k] * q[k];
            }
        } while (len > 1 || len < 0.01);
        len = sqrt(len);
        for (int k = 0; k < 4; k++)
            q[k] /= len;
        double w = q[0], x = q[1], y = q[2], z = q[3];
        double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),
                       2 * (x * z + w * y),     2 * (x * y + w * z),
                       1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),
                       1 - 2 * (x * x + y * y)};
        memcpy(rot, r, sizeof r);
    }
    json_t *list = json_array();
    double top[3] = {0, 0, zt};
    json_array_append_new(list, facet_rot(0, 0, 1, top, rot));
    for (int k = 0; k < 8; k++) {
        double az = 45.0 * k, a = az * M_PI / 180;
        double pg[3] = {R * cos(a), R * sin(a), half};
        json_array_append_new(list, facet_rot(az, crown, 1, pg, rot));
        double as = (az + 22.5) * M_PI / 180;
        double ps[3] = {tab * R * cos(as), tab * R * sin(as), zt};
        json_array_append_new(list, facet_rot(az + 22.5, star, 1, ps, rot));
        double pb[3] = {R * cos(a), R * sin(a), -half};
        json_array_append_new(list, facet_rot(az, pav, 0, pb, rot));
        for (int s = -1; s <= 1; s += 2) {
            double au = (az + 22.5 + s * 11.25) * M_PI / 180;
            double pu[3] = {R * cos(au), R * sin(au), half};
            json_array_append_new(
                list, facet_rot(az + 22.5 + s * 11.25, ug, 1, pu, rot));
            double pl[3] = {R * cos(au), R * sin(au), -half};
            json_array_append_new(
                list, facet_rot(az + 22.5 + s * 11.25, lg, 0, pl, rot));
        }
    }
    for (int k = 0; k < 16; k++) {
        double az = 22.5 * k + 11.25, a = az * M_PI / 180;
        double pg[3] = {R * cos(a), R * sin(a), 0};
        json_array_append_new(list, facet_rot(az, 90.0, 1, pg, rot));
    }
    return object(json_pack("{s:o}", "intersection", list), -0.75, 0.75);
}

json_t *gf_two_spheres(void)
{
    json_t *list = json_pack("[o,o]", sphere(-0.22, 0, 0, 0.42),
                             sphere(0.28, 0.04, 0.03, 0.36));
    return object(json_pack("{s:o}", "union", list), -1, 1);
}

int gf_halfspaces(const json_t *frep, double **ret)
{
    const json_t *list = json_object_get(json_object_get(frep, "shape"),
                                         "intersection");
    size_t n = json_array_size(list);
    double *pl = malloc((4 * n + 1) * sizeof *pl);
    if (!pl)
        return -1;
    for (size_t i = 0; i < n; i++) {
        const json_t *p = json_object_get(
            json_object_get(json_array_get(list, i), "halfspace"), "plane");
        for (int k = 0; k < 4; k++)
            pl[4 * i + k] = json_number_value(json_array_get(p, (size_t)k));
    }
    *ret = pl;
    return (int)n;
}

int gf_polytope_edges(const double (*planes)[4], int n, double **ret)
{
    /* vertices: intersections of plane triples inside every half-space */
    int cap = 64, nv = 0;
    double(*v)[3] = malloc((size_t)cap * sizeof *v);
    int(*vp)[3] = malloc((size_t)cap * sizeof *vp);
    if (!v || !vp)
        goto oom;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++)
            for (int k = j + 1; k < n; k++) {
                double x[3];
                if (!geo_plane_intersect3(planes[i], planes[j], planes[k], x))
                    continue;
                bool inside = true;
                for (int q = 0; q < n && inside; q++)
                    inside = geo_plane_eval(planes[q], x) <= 1e-9;
                if (!inside)
                    continue;
                if (nv == cap) {
                    cap *= 2;
                    double(*nv2)[3] = realloc(v, (size_t)cap * sizeof *v);
                    int(*np2)[3] = realloc(vp, (size_t)cap * sizeof *vp);
                    if (!nv2 || !np2) {
                        free(nv2 ? nv2 : v);
                        free(np2 ? np2 : vp);
                        return -1;
                    }
                    v = nv2;
                    vp = np2;
                }
                memcpy(v[nv], x, sizeof x);
                vp[nv][0] = i, vp[nv][1] = j, vp[nv][2] = k;
                nv++;
            }
    /* an edge: the extreme points on both planes i and j */
    int ns = 0, scap = 64;
    double *segs = malloc((size_t)scap * 6 * sizeof *segs);
    if (!segs)
        goto oom;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            double dir[3], best_lo = INFINITY, best_hi = -INFINITY;
            int lo = -1, hi = -1;
            geo_vcross(planes[i], planes[j], dir);
            for (int q = 0; q < nv; q++) {
                if (fabs(geo_plane_eval(planes[i], v[q])) > 1e-9 ||
                    fabs(geo_plane_eval(planes[j], v[q])) > 1e-9)
                    continue;
                double t = geo_vdot(v[q], dir);
                if (t < best_lo)
                    best_lo = t, lo = q;
                if (t > best_hi)
                    best_hi = t, hi = q;
            }
            if (lo < 0 || geo_vdist(v[lo], v[hi]) < 1e-9)
                continue;
            if (ns == scap) {
                scap *= 2;
                double *n2 = realloc(segs, (size_t)scap * 6 * sizeof *segs);
                if (!n2) {
                    free(segs);
                    goto oom;
                }
                segs = n2;
            }
            memcpy(segs + 6 * ns, v[lo], 3 * sizeof(double));
            memcpy(segs + 6 * ns + 3, v[hi], 3 * sizeof(double));
            ns++;
        }
    free(v), free(vp);
    *ret = segs;
    return ns;
oom:
    free(v), free(vp);
    return -1;
}

/* Distance from p to triangle abc. */
static double point_tri(const double p[3], const double a[3],
                        const double b[3], const double c[3])
{
    double ab[3], ac[3], ap[3], n[3];
    geo_vsub(b, a, ab);
    geo_vsub(c, a, ac);
    geo_vsub(p, a, ap);
    geo_vcross(ab, ac, n);
    double nn = geo_vdot(n, n);
    if (nn > 0) {
        /* barycentric coordinates of the projection */
        double x[3], y[3];
        geo_vcross(ap, ac, x);
        geo_vcross(ab, ap, y);
        double s = geo_vdot(x, n) / nn, t = geo_vdot(y, n) / nn;
        if (s >= 0 && t >= 0 && s + t <= 1)
            return fabs(geo_vdot(ap, n)) / sqrt(nn);
    }
    const double *e[3][2] = {{a, b}, {b, c}, {c, a}};
    double best = INFINITY;
    for (int k = 0; k < 3; k++) {
        double d[3], w[3];
        geo_vsub(e[k][1], e[k][0], d);
        geo_vsub(p, e[k][0], w);
        double dd = geo_vdot(d, d), t = dd > 0 ? geo_vdot(w, d) / dd : 0;
        t = t < 0 ? 0 : (t > 1 ? 1 : t);
        double q[3];
        geo_vmadd(e[k][0], t, d, q);
        best = fmin(best, geo_vdist(p, q));
    }
    return best;
}

typedef struct near_q {
    const geo_poly *m;
    const double *p;
    double best;
} near_q;

static bool near_visit(void *user, uint32_t f)
{
    near_q *q = user;
    const uint32_t *v = geo_poly_facet(q->m, f);
    double d = point_tri(q->p, q->m->verts[v[0]], q->m->verts[v[1]],
                         q->m->verts[v[2]]);
    if (d < q->best)
        q->best = d;
    return true;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

void gf_edge_distances(const geo_poly *m, const double *segs, int nsegs,
                       double step, double clearance, double ret[5])
{
    memset(ret, 0, 5 * sizeof *ret);
    geo_bvh *h = geo_bvh_build_facets(m, NULL);
    size_t n = 0, cap = 1024;
    double *far = malloc(cap * sizeof *far);
    if (!h || !far) {
        geo_bvh_free(h);
        free(far);
        ret[0] = INFINITY;
        return;
    }
    double size = geo_poly_size(m);
    for (int s = 0; s < nsegs; s++) {
        const double *a = segs + 6 * s, *b = a + 3;
        double len = geo_vdist(a, b);
        int k = (int)ceil(len / step);
        for (int i = 0; i <= k; i++) {
            double p[3], d[3], t = (double)i / (k ? k : 1);
            geo_vsub(b, a, d);
            geo_vmadd(a, t, d, p);
            near_q q = {m, p, INFINITY};
            for (double r = step; !isfinite(q.best) || q.best > r; r *= 2) {
                geo_bbox box;
                for (int c = 0; c < 3; c++) {
                    box.lo[c] = p[c] - r;
                    box.hi[c] = p[c] + r;
                }
                geo_bvh_query_box(h, &box, near_visit, &q);
                if (r > size)
                    break;
            }
            ret[0] = fmax(ret[0], q.best);
            if (fmin(t, 1 - t) * len <= clearance)
                continue;
            if (n == cap) {
                double *nf = realloc(far, 2 * cap * sizeof *nf);
                if (!nf)
                    continue;
                far = nf;
                cap *= 2;
            }
            far[n++] = q.best;
        }
    }
    if (n) {
        qsort(far, n, sizeof *far, cmp_double);
        ret[1] = far[n / 2];
        ret[2] = far[n * 9 / 10];
        ret[3] = far[n * 99 / 100];
        ret[4] = far[n - 1];
    }
    free(far);
    geo_bvh_free(h);
}
