/* convex_planes.c — the true facet planes of a convex scan: groups, their
 * hinge fits and the support test (convex.h, steps 1–3).
 *
 * Invariants: p is only read; every group is a connected set of facets
 * (grown across edges); group ids follow the growth order, largest seed
 * first. Moments are taken about the model's box centre so that the sums
 * of squares do not cancel. */
#include "convex.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "plane.h"
#include "select.h"
#include "topo.h"
#include "uf.h"
#include "vec.h"

/* Grouping criterion (why: merge_groups.c, whose criterion this is): the
 * deviation a vertex may have from its group's plane, in noise units and
 * as a floor relative to the model's size; the view-step roof over a
 * group of width w inclined by a is ROOF · w · step · sin a; a joining
 * facet's area RMS distance from the group's plane before it joined may
 * be RMS noise units plus STEP · extent · step. */
#define DEV_NOISE 4.0
#define DEV_REL 2e-4
#define ROOF 0.25
#define RMS_NOISE 3.0
#define RMS_STEP 0.1
#define MAX_ANGLE_DEG 30.0

/* The hinge fit: a boundary segment whose farther end lies more than
 * TRIM residual scales off the plane is left out, and the fit repeated
 * up to TRIM_ROUNDS times; the scale never goes below the noise. */
#define TRIM 2.5
#define TRIM_ROUNDS 4

/* A boundary segment counts as a hinge when it lies in the lowest
 * HINGE_LOW of its sliver's height range above the group's plane. */
#define HINGE_LOW 0.25

/* The support test: a group is dropped when its plane cuts the polytope
 * of its neighbours' planes by at most CUT_NOISE noise units (or
 * CUT_REL × size when there is no noise). */
#define CUT_NOISE 4.0
#define CUT_REL 2e-4

/* Groups with at least this many boundary segments measure the hinges'
 * scatter. */
#define HINGE_SEGMENTS 8

typedef struct mom {
    double a, s[3], ss[3][3]; /* weight, first and second moments */
} mom;

static void mom_add(mom *m, const mom *x)
{
    m->a += x->a;
    for (int i = 0; i < 3; i++) {
        m->s[i] += x->s[i];
        for (int j = i; j < 3; j++)
            m->ss[i][j] += x->ss[i][j];
    }
}

/* Area moments of facet f about o (fan triangles). */
static void facet_mom(const geo_poly *p, uint32_t f, const double o[3], mom *m)
{
    memset(m, 0, sizeof *m);
    geo_fan_moments((const double(*)[3])p->verts, geo_poly_facet(p, f),
                    geo_poly_facet_size(p, f), o, &m->a, m->s, m->ss);
}

/* Length moments of the segment a–b about o: ∫ x ds, ∫ x xᵀ ds. */
static void segment_mom(const double a[3], const double b[3], const double o[3],
                        mom *m)
{
    double x[3], d[3];
    geo_vsub(a, o, x);
    geo_vsub(b, a, d);
    double len = geo_vlen(d);
    m->a = len;
    for (int k = 0; k < 3; k++) {
        m->s[k] = len * (x[k] + d[k] / 2);
        for (int l = k; l < 3; l++)
            m->ss[k][l] = len * (x[k] * x[l] + (x[k] * d[l] + d[k] * x[l]) / 2 +
                                 d[k] * d[l] / 3);
    }
}

/* Least-squares plane of m (about o), its normal turned along orient;
 * *ret_width (may be NULL) the extent along the middle axis of inertia
 * as a uniform strip would have it. false when m is degenerate. */
static bool mom_plane(const mom *m, const double o[3], const double orient[3],
                      double ret[4], double *ret_width)
{
    if (!(m->a > 0))
        return false;
    double mu[3], c[3][3], val[3], vec[3][3];
    for (int i = 0; i < 3; i++)
        mu[i] = m->s[i] / m->a;
    for (int i = 0; i < 3; i++)
        for (int j = i; j < 3; j++)
            c[i][j] = m->ss[i][j] / m->a - mu[i] * mu[j];
    geo_sym3_eigen(c, val, vec);
    if (!(val[1] > 0))
        return false;
    double *n = vec[0];
    if (geo_vdot(n, orient) < 0)
        geo_vscale(n, -1, n);
    double x[3];
    geo_vadd(mu, o, x);
    memcpy(ret, n, 3 * sizeof *n);
    ret[3] = -geo_vdot(n, x);
    if (ret_width)
        *ret_width = sqrt(12 * fmax(val[1], 0));
    return true;
}

/* The least-squares plane of a group whose slivers form a thin strip
 * (two long slivers side by side) is ill-conditioned: any plane through
 * the strip's axis fits it about as well, and rounding picks one, up to
 * 70° off every member (a princess at K = 800: a plane cutting 0.44 mm
 * into the scan). The slivers of a facet are tilted about its hinges by
 * at most a few view steps, so its true normal lies within their cone:
 * a fitted normal farther from the group's mean normal than every member
 * (by more than a view step and CONE_MIN_DEG) gives way to the mean
 * normal through the group's centroid. 0 or -ENOMEM. */
#define CONE_MIN_DEG 0.05 /* below the angles a grader reads: no gross
                             error, and a lone sliver's own plane stays */

static int within_cone(const geo_poly *p, const uint32_t *group,
                       const double *farea, uint32_t ng, const double o[3],
                       double step, const mom *gm, double (*apl)[4])
{
    double (*mean)[3] = calloc((size_t)ng + 1, sizeof *mean);
    double *spread = malloc(((size_t)ng + 1) * sizeof *spread);
    if (!mean || !spread) {
        free(mean), free(spread);
        return -ENOMEM;
    }
    for (uint32_t h = 0; h < p->nfacets; h++)
        geo_vmadd(mean[group[h]], farea[h], p->planes[h], mean[group[h]]);
    for (uint32_t g = 0; g < ng; g++) {
        spread[g] = 0;
        if (geo_vlen(mean[g]) > 0)
            geo_vnormalize(mean[g]);
    }
    for (uint32_t h = 0; h < p->nfacets; h++) {
        uint32_t g = group[h];
        double a = geo_vangle(p->planes[h], mean[g]);
        spread[g] = a > spread[g] ? a : spread[g];
    }
    for (uint32_t g = 0; g < ng; g++) {
        if (!(geo_vlen(mean[g]) > 0) || !(gm[g].a > 0) ||
            geo_vangle(apl[g], mean[g]) <=
                spread[g] + step + CONE_MIN_DEG * M_PI / 180)
            continue;
        double x[3];
        for (int k = 0; k < 3; k++)
            x[k] = o[k] + gm[g].s[k] / gm[g].a;
        memcpy(apl[g], mean[g], sizeof mean[g]);
        apl[g][3] = -geo_vdot(mean[g], x);
    }
    free(mean), free(spread);
    return 0;
}

/* Area RMS distance from pl of the surface whose moments about o are m. */
static double mom_rms(const mom *m, const double o[3], const double pl[4])
{
    if (!(m->a > 0))
        return 0;
    double h = geo_plane_eval(pl, o), q = 0;
    for (int k = 0; k < 3; k++)
        for (int l = 0; l < 3; l++)
            q += pl[k] * pl[l] * (k <= l ? m->ss[k][l] : m->ss[l][k]);
    double v = (q + 2 * h * geo_vdot(pl, m->s)) / m->a + h * h;
    return sqrt(fmax(v, 0));
}

typedef struct finder {
    const geo_poly *p;
    const geo_topo *t;
    double o[3];
    double step, noise, dev0;
    mom *fm;            /* per facet */
    double *farea;
    uint32_t *group;    /* per facet, GEO_NONE = not yet */
    uint32_t *vstamp, stamp; /* per vertex: in the current group */
    uint32_t *fstamp;   /* per facet: rejected for the current group */
    uint32_t *mem, nmem;
    uint32_t *vs, nvs;
    uint32_t *cand, ncand;
    const geo_ctx *ctx; /* polled while the groups grow */
    bool canceled;
} finder;

/* The extent of the surface of moments m along the horizontal direction
 * z × n of the plane q (n its unit normal, not vertical): the uniform
 * strip's width of the same variance, √12·σ. 0 for a horizontal plane. */
static double horizontal_width(const mom *m, const double q[4])
{
    double s = hypot(q[0], q[1]);
    if (!(s > 0) || !(m->a > 0))
        return 0;
    double h[3] = {-q[1] / s, q[0] / s, 0}, mh = 0, hh = 0;
    for (int i = 0; i < 3; i++) {
        mh += h[i] * m->s[i] / m->a;
        for (int j = 0; j < 3; j++)
            hh += h[i] * h[j] * (i <= j ? m->ss[i][j] : m->ss[j][i]) / m->a;
    }
    return sqrt(12 * fmax(hh - mh * mh, 0));
}

/* Would facet h fit the group of moments m, vertices f->vs and plane pl?
 * On success ret gets the plane with h. The roof allowed over the group
 * is the one its slivers make: each is hinged on the true facet's edge
 * and contains its view's direction, so it rises along the facet's
 * horizontal direction (geo_convex_roof_at) — over the group's extent
 * that way, not its narrower in-plane width (a girdle facet is three
 * times as wide as it is high, and its slivers stood in two groups). */
static bool fits(finder *f, const mom *m, const double pl[4], uint32_t h,
                 double cosmax, double ret[4])
{
    const geo_poly *p = f->p;
    uint32_t n = geo_poly_facet_size(p, h);
    const uint32_t *v = geo_poly_facet(p, h);
    /* the tests are pure: the one on h's own moments against the group's
     * plane comes first, as it rejects most candidates without the
     * eigensolve of the plane with h */
    if (f->noise > 0) {
        double lo[3] = {INFINITY, INFINITY, INFINITY},
               hi[3] = {-INFINITY, -INFINITY, -INFINITY}, d[3];
        for (uint32_t i = 0; i < n; i++)
            for (int k = 0; k < 3; k++)
                geo_minmax(p->verts[v[i]][k], &lo[k], &hi[k]);
        geo_vsub(hi, lo, d);
        double tol = RMS_NOISE * f->noise + RMS_STEP * geo_vlen(d) * f->step;
        if (mom_rms(&f->fm[h], f->o, pl) > tol)
            return false;
    }
    mom m2 = *m;
    mom_add(&m2, &f->fm[h]);
    double q[4];
    if (!mom_plane(&m2, f->o, pl, q, NULL))
        return false;
    if (geo_vdot(p->planes[h], q) < cosmax)
        return false;
    double dmax = f->dev0 + ROOF * horizontal_width(&m2, q) * f->step *
                                hypot(q[0], q[1]);
    for (uint32_t i = 0; i < n; i++)
        if (fabs(geo_plane_eval(q, p->verts[v[i]])) > dmax)
            return false;
    for (uint32_t i = 0; i < f->nvs; i++)
        if (fabs(geo_plane_eval(q, p->verts[f->vs[i]])) > dmax)
            return false;
    memcpy(ret, q, sizeof q);
    return true;
}

static void add_member(finder *f, uint32_t h, uint32_t gid)
{
    const geo_poly *p = f->p;
    f->group[h] = gid;
    f->mem[f->nmem++] = h;
    uint32_t n = geo_poly_facet_size(p, h);
    const uint32_t *v = geo_poly_facet(p, h);
    for (uint32_t i = 0; i < n; i++) {
        if (f->vstamp[v[i]] != f->stamp) {
            f->vstamp[v[i]] = f->stamp;
            f->vs[f->nvs++] = v[i];
        }
        uint32_t nb = geo_topo_neighbor(f->t, p->fstart[h] + i);
        if (nb == GEO_NONE || f->group[nb] != GEO_NONE || f->fstamp[nb] == f->stamp)
            continue;
        bool have = false;
        for (uint32_t j = 0; j < f->ncand && !have; j++)
            have = f->cand[j] == nb;
        if (!have)
            f->cand[f->ncand++] = nb;
    }
}

static int cmp_area_desc(const void *a, const void *b, void *ctx)
{
    const double *ar = ctx;
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    if (ar[x] != ar[y])
        return ar[x] > ar[y] ? -1 : 1;
    return (x > y) - (x < y);
}

/* Step 1: f->group of every facet; returns the number of groups. */
static uint32_t grow_groups(finder *f, uint32_t *order)
{
    const geo_poly *p = f->p;
    uint32_t nf = p->nfacets, ng = 0;
    double cosmax = cos(MAX_ANGLE_DEG * M_PI / 180);
    for (uint32_t i = 0; i < nf; i++)
        order[i] = i;
    qsort_r(order, nf, sizeof *order, cmp_area_desc, f->farea);
    for (uint32_t k = 0; k < nf; k++) {
        uint32_t s = order[k];
        if (f->group[s] != GEO_NONE)
            continue;
        f->stamp++;
        f->nmem = f->nvs = f->ncand = 0;
        uint32_t gid = ng++;
        add_member(f, s, gid);
        mom m = f->fm[s];
        double pl[4];
        memcpy(pl, p->planes[s], sizeof pl);
        for (uint32_t it = 1;; it++) {
            /* a group of thousands of facets checks each candidate
             * against all its vertices: poll the cancellation */
            if ((it & GEO_CTX_CHECK_MASK) == 0 && geo_ctx_canceled(f->ctx)) {
                f->canceled = true;
                return ng;
            }
            uint32_t bi = GEO_NONE;
            double bd = -2;
            for (uint32_t j = 0; j < f->ncand; j++) {
                double d = geo_vdot(p->planes[f->cand[j]], pl);
                if (d > bd) {
                    bd = d;
                    bi = j;
                }
            }
            if (bi == GEO_NONE || bd < cosmax)
                break;
            uint32_t h = f->cand[bi];
            f->cand[bi] = f->cand[--f->ncand];
            if (f->group[h] != GEO_NONE || f->fstamp[h] == f->stamp)
                continue;
            double q[4];
            if (!fits(f, &m, pl, h, cosmax, q)) {
                f->fstamp[h] = f->stamp;
                continue;
            }
            add_member(f, h, gid);
            mom_add(&m, &f->fm[h]);
            memcpy(pl, q, sizeof q);
        }
    }
    return ng;
}

/* Step 1b: joins adjacent groups whose area normals lie within the view
 * step's roof of each other. The slivers of one true facet come from the
 * views either side of its azimuth, hinged on opposite edges: two halves
 * whose normals sit on neighbouring meridians of the Gauss sphere, about
 * step × sin(inclination) apart (JOIN_STEP allows for hinges oblique to
 * the meridians), plus what the noise does to the normal of a group of
 * that size. Closest pairs first, each group once a pass; the groups'
 * moments are summed, so a joined group's normal is the area mean.
 * Returns the new number of groups (ids compacted, in order). */
#define JOIN_STEP 1.5
#define JOIN_MIN_DEG 0.05
#define JOIN_PASSES 8

typedef struct gpair {
    double angle;
    uint32_t a, b;
} gpair;

static int cmp_gpair(const void *x, const void *y)
{
    const gpair *s = x, *t = y;
    if (s->angle != t->angle)
        return s->angle < t->angle ? -1 : 1;
    if (s->a != t->a)
        return s->a < t->a ? -1 : 1;
    return (s->b > t->b) - (s->b < t->b);
}

static int join_groups(finder *f, uint32_t *ng)
{
    const geo_poly *p = f->p;
    const geo_topo *t = f->t;
    uint32_t n = *ng, nc = geo_poly_ncorners(p);
    uint32_t *par = malloc(((size_t)n + 1) * sizeof *par);
    mom *gm = calloc((size_t)n + 1, sizeof *gm);
    double (*pl)[4] = malloc(((size_t)n + 1) * sizeof *pl);
    uint8_t *touched = malloc((size_t)n + 1);
    gpair *pr = malloc(((size_t)nc + 1) * sizeof *pr);
    int r = -ENOMEM;
    if (!par || !gm || !pl || !touched || !pr)
        goto done;
    for (uint32_t g = 0; g < n; g++)
        par[g] = g;
    for (uint32_t h = 0; h < p->nfacets; h++) {
        uint32_t g = f->group[h];
        if (gm[g].a == 0)
            memcpy(pl[g], p->planes[h], sizeof pl[0]);
        mom_add(&gm[g], &f->fm[h]);
    }
    for (uint32_t g = 0; g < n; g++) {
        double q[4];
        if (mom_plane(&gm[g], f->o, pl[g], q, NULL))
            memcpy(pl[g], q, sizeof q);
    }
    for (int pass = 0; pass < JOIN_PASSES && f->step > 0; pass++) {
        uint32_t np = 0;
        for (uint32_t c = 0; c < nc; c++) {
            uint32_t h = geo_topo_neighbor(t, c);
            if (h == GEO_NONE)
                continue;
            uint32_t a = geo_uf_find(par, f->group[t->corner_facet[c]]);
            uint32_t b = geo_uf_find(par, f->group[h]);
            if (a >= b)
                continue;
            double ang = geo_vangle(pl[a], pl[b]);
            double sin_incl = fmax(hypot(pl[a][0], pl[a][1]), hypot(pl[b][0], pl[b][1]));
            double amin = fmin(gm[a].a, gm[b].a);
            double bound = JOIN_STEP * f->step * sin_incl + JOIN_MIN_DEG * M_PI / 180 +
                           (amin > 0 ? 2 * f->noise / sqrt(amin) : 0);
            if (ang <= bound)
                pr[np++] = (gpair){ang, a, b};
        }
        if (np == 0)
            break;
        qsort(pr, np, sizeof *pr, cmp_gpair);
        memset(touched, 0, n);
        uint32_t joined = 0;
        for (uint32_t i = 0; i < np; i++) {
            uint32_t a = pr[i].a, b = pr[i].b;
            if (touched[a] || touched[b] || geo_uf_find(par, a) != a ||
                geo_uf_find(par, b) != b)
                continue;
            touched[a] = touched[b] = 1;
            par[b] = a;
            mom_add(&gm[a], &gm[b]);
            double q[4];
            if (mom_plane(&gm[a], f->o, pl[a], q, NULL))
                memcpy(pl[a], q, sizeof q);
            joined++;
        }
        if (joined == 0)
            break;
    }
    /* compact: new ids in the order of the old roots */
    uint32_t *id = malloc(((size_t)n + 1) * sizeof *id);
    if (!id)
        goto done;
    uint32_t m = 0;
    for (uint32_t g = 0; g < n; g++)
        id[g] = geo_uf_find(par, g) == g ? m++ : GEO_NONE;
    for (uint32_t h = 0; h < p->nfacets; h++)
        f->group[h] = id[geo_uf_find(par, f->group[h])];
    free(id);
    *ng = m;
    r = 0;
done:
    free(par), free(gm), free(pl), free(touched), free(pr);
    return r;
}

typedef struct seg {
    uint32_t a, b; /* vertices */
    uint32_t g;    /* group */
    uint32_t f;    /* the group's facet it bounds */
} seg;

static int cmp_seg_first(const void *x, const void *y)
{
    const seg *s = x, *t = y;
    return (s->a > t->a) - (s->a < t->a);
}

/* sg[0..ns) in the order (group, facet, first vertex): a counting sort
 * by group — the segments come in corner order, so each group's facets
 * stay in order — then each facet's segments by their first vertex,
 * by insertion where they are few (a sliver's two or three), by qsort
 * where a large facet has many. What one qsort over all gave, in a tenth
 * of the comparisons. 0 or -ENOMEM. */
#define FEW_SEGMENTS 32

static int sort_segments(seg *sg, uint32_t ns, uint32_t ng)
{
    uint32_t *start = calloc((size_t)ng + 1, sizeof *start);
    seg *out = malloc(((size_t)ns + 1) * sizeof *out);
    if (!start || !out) {
        free(start), free(out);
        return -ENOMEM;
    }
    for (uint32_t i = 0; i < ns; i++)
        start[sg[i].g + 1]++;
    for (uint32_t g = 0; g < ng; g++)
        start[g + 1] += start[g];
    for (uint32_t i = 0; i < ns; i++)
        out[start[sg[i].g]++] = sg[i];
    for (uint32_t i = 0, j; i < ns; i = j) {
        for (j = i + 1; j < ns && out[j].g == out[i].g && out[j].f == out[i].f;
             j++)
            ;
        if (j - i > FEW_SEGMENTS) {
            qsort(out + i, j - i, sizeof *out, cmp_seg_first);
            continue;
        }
        for (uint32_t k = i + 1; k < j; k++) {
            seg t = out[k];
            uint32_t m = k;
            for (; m > i && out[m - 1].a > t.a; m--)
                out[m] = out[m - 1];
            out[m] = t;
        }
    }
    memcpy(sg, out, (size_t)ns * sizeof *sg);
    free(start), free(out);
    return 0;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Step 2 for one group: the plane of its boundary segments sg[0..n),
 * trimmed (see TRIM); orient is the group's area normal, the fallback
 * plane when the boundary is degenerate. Scratch: res 2n doubles, top n
 * doubles, sm n moments (each segment's, formed once for every round). */
static void hinge_fit(const geo_poly *p, const seg *sg, uint32_t n,
                      const double o[3], double scale_floor,
                      const double fallback[4], double *res, double *top,
                      mom *sm, bool *use, double ret[4], double *ret_scale)
{
    *ret_scale = 0;
    memcpy(ret, fallback, 4 * sizeof *ret);
    double ref[4];
    memcpy(ref, fallback, sizeof ref);
    for (uint32_t i = 0; i < n; i++)
        segment_mom(p->verts[sg[i].a], p->verts[sg[i].b], o, &sm[i]);
    for (int round = 0; round <= TRIM_ROUNDS; round++) {
        /* residual of a segment: its end farther from the plane; top its
         * higher end */
        for (uint32_t i = 0; i < n; i++) {
            double ra = geo_plane_eval(ref, p->verts[sg[i].a]);
            double rb = geo_plane_eval(ref, p->verts[sg[i].b]);
            res[i] = fabs(ra) > fabs(rb) ? ra : rb;
            top[i] = ra > rb ? ra : rb;
        }
        double scale = 0;
        if (round > 0) {
            double *tmp = res + n;
            uint32_t k = 0;
            for (uint32_t i = 0; i < n; i++)
                if (use[i])
                    tmp[k++] = fabs(res[i]);
            *ret_scale = k ? 1.4826 * geo_select_kth(tmp, k, k / 2) : 0;
            scale = fmax(*ret_scale, scale_floor);
        }
        uint32_t kept = 0;
        double lo = INFINITY, hi = -INFINITY;
        for (uint32_t i = 0; i < n; i++) {
            /* a hinge is the low side of its sliver: the sliver rises
             * from it by its tilt; a facet's segments are consecutive,
             * its range is found once (a facet of 10,000 edges would
             * otherwise cost 10⁸) */
            if (i == 0 || sg[i].f != sg[i - 1].f) {
                uint32_t nv = geo_poly_facet_size(p, sg[i].f);
                const uint32_t *fv = geo_poly_facet(p, sg[i].f);
                lo = INFINITY, hi = -INFINITY;
                for (uint32_t j = 0; j < nv; j++) {
                    double d = geo_plane_eval(ref, p->verts[fv[j]]);
                    geo_minmax(d, &lo, &hi);
                }
            }
            bool low = top[i] <= lo + HINGE_LOW * (hi - lo) + scale_floor;
            use[i] = low && (round == 0 || fabs(res[i]) <= TRIM * scale);
            kept += use[i];
        }
        if (kept < 3)
            return;
        mom m = {0};
        for (uint32_t i = 0; i < n; i++)
            if (use[i])
                mom_add(&m, &sm[i]);
        double q[4];
        if (!mom_plane(&m, o, fallback, q, NULL))
            return;
        memcpy(ret, q, sizeof q);
        memcpy(ref, q, sizeof q);
    }
}

/* Step 3's measure: how far plane pl cuts the polytope of the planes
 * nb[0..k) — the largest pl(x) over the vertices of their arrangement
 * that satisfy all of them; INFINITY when there is no feasible vertex.
 * The caller closes the polytope with a far box, so a region beyond pl
 * the neighbours leave open reaches the box and counts as deep. */
static double cut_depth(const double pl[4], const double (*nb)[4], uint32_t k,
                        double tol, const geo_plane_triples *tr)
{
    double best = -INFINITY;
    for (uint32_t i = 0; i < k; i++)
        for (uint32_t j = i + 1; j < k; j++)
            for (uint32_t l = j + 1; l < k; l++) {
                double x[3];
                if (!geo_plane_triples_meet(tr, i, j, l, x))
                    continue;
                double d = geo_plane_eval(pl, x);
                if (d <= best)
                    continue;
                bool ok = true;
                for (uint32_t m = 0; m < k && ok; m++)
                    ok = geo_plane_eval(nb[m], x) <= tol;
                if (ok)
                    best = d;
            }
    return best == -INFINITY ? INFINITY : best;
}

void geo_convex_planes_clear(geo_convex_planes *r)
{
    if (!r)
        return;
    free(r->planes);
    free(r->area);
    free(r->allow);
    free(r->group);
    free(r->kept);
    free(r->spare);
    free(r->span);
    memset(r, 0, sizeof *r);
}

double geo_convex_roof_at(const geo_convex_planes *cp, uint32_t g,
                          const double n[3], const double x[3])
{
    if (!cp->span || g >= cp->ngroups)
        return 0;
    const double *s = cp->span[g];
    double u = s[0] * x[0] + s[1] * x[1];
    double u1 = u - s[2], u2 = s[3] - u;
    if (!(u1 > 0 && u2 > 0))
        return 0;
    return cp->step * hypot(n[0], n[1]) * u1 * u2 / (u1 + u2);
}

/* Each group's horizontal direction (from its plane) and the extent of
 * its scan vertices along it (geo_convex_planes.span). */
static void group_spans(const geo_poly *p, const uint32_t *group,
                        const double (*gpl)[4], uint32_t ng,
                        double (*span)[4])
{
    for (uint32_t g = 0; g < ng; g++) {
        double hl = hypot(gpl[g][0], gpl[g][1]);
        span[g][0] = hl > 0 ? -gpl[g][1] / hl : 1;
        span[g][1] = hl > 0 ? gpl[g][0] / hl : 0;
        span[g][2] = INFINITY;
        span[g][3] = -INFINITY;
    }
    for (uint32_t h = 0; h < p->nfacets; h++) {
        uint32_t g = group[h];
        if (g >= ng)
            continue;
        uint32_t n = geo_poly_facet_size(p, h);
        const uint32_t *fv = geo_poly_facet(p, h);
        for (uint32_t i = 0; i < n; i++) {
            double u = span[g][0] * p->verts[fv[i]][0] +
                       span[g][1] * p->verts[fv[i]][1];
            span[g][2] = fmin(span[g][2], u);
            span[g][3] = fmax(span[g][3], u);
        }
    }
}

/* Neighbour lists of the groups (CSR, distinct, from the scan's edges). */
static int group_neighbours(const geo_poly *p, const geo_topo *t,
                            const uint32_t *group, uint32_t ng,
                            uint32_t **ret_start, uint32_t **ret_list)
{
    uint32_t nc = geo_poly_ncorners(p);
    uint64_t *pairs = malloc(((size_t)nc + 1) * sizeof *pairs);
    uint32_t *start = calloc((size_t)ng + 1, sizeof *start);
    uint32_t *list = malloc(((size_t)nc + 1) * sizeof *list);
    if (!pairs || !start || !list) {
        free(pairs), free(start), free(list);
        return -ENOMEM;
    }
    uint32_t np = 0;
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t h = geo_topo_neighbor(t, c);
        if (h == GEO_NONE)
            continue;
        uint32_t a = group[t->corner_facet[c]], b = group[h];
        if (a != b)
            pairs[np++] = (uint64_t)a << 32 | b;
    }
    qsort(pairs, np, sizeof *pairs, cmp_u64);
    uint32_t nl = 0;
    for (uint32_t i = 0; i < np; i++) {
        if (i && pairs[i] == pairs[i - 1])
            continue;
        start[(pairs[i] >> 32) + 1]++;
        list[nl++] = (uint32_t)pairs[i];
    }
    for (uint32_t g = 0; g < ng; g++)
        start[g + 1] += start[g];
    free(pairs);
    *ret_start = start;
    *ret_list = list;
    return 0;
}

/* Step 3: marks dropped groups in drop[]. Smallest groups first, each
 * against the planes of its neighbours still kept (a dropped neighbour
 * stands for its own neighbours). */
static int support(const geo_convex_planes *r, const double (*gpl)[4],
                   const double *garea, const double *groof,
                   const uint32_t *nstart, const uint32_t *nlist,
                   const double (*box)[4], double cut_min, double tol,
                   uint8_t *drop)
{
    uint32_t ng = r->ngroups;
    uint32_t *order = malloc(((size_t)ng + 1) * sizeof *order);
    uint32_t cap = 64, k;
    double (*nb)[4] = malloc(cap * sizeof *nb);
    uint32_t *ids = malloc(cap * sizeof *ids);
    geo_plane_triples tr = {0};
    if (!order || !nb || !ids) {
        free(order), free(nb), free(ids);
        return -ENOMEM;
    }
    for (uint32_t g = 0; g < ng; g++)
        order[g] = g;
    qsort_r(order, ng, sizeof *order, cmp_area_desc, (void *)garea);
    for (uint32_t i = ng; i-- > 0;) {
        uint32_t g = order[i];
        k = 0;
        double roof = groof[g];
        for (uint32_t a = nstart[g]; a < nstart[g + 1]; a++) {
            uint32_t h = nlist[a];
            uint32_t from = h, to = h + 1;
            bool sub = drop[h];
            if (sub) {
                from = nstart[h];
                to = nstart[h + 1];
            }
            for (uint32_t b = from; b < to; b++) {
                uint32_t x = sub ? nlist[b] : b;
                if (x == g || drop[x])
                    continue;
                bool have = false;
                for (uint32_t j = 0; j < k && !have; j++)
                    have = ids[j] == x;
                if (have || k + 6 >= cap)
                    continue;
                ids[k] = x;
                roof = fmax(roof, groof[x]);
                memcpy(nb[k++], gpl[x], sizeof nb[0]);
            }
        }
        /* the box closes the region where the neighbours do not (a
         * dropped neighbour's own can include the far side) */
        if (k + 6 > cap) {
            double (*nb2)[4] = realloc(nb, (k + 6) * sizeof *nb);
            if (!nb2) {
                free(order), free(nb), free(ids);
                geo_plane_triples_free(&tr);
                return -ENOMEM;
            }
            nb = nb2;
            cap = k + 6;
        }
        memcpy(nb[k], box, 6 * sizeof nb[0]);
        if (geo_plane_triples_set(&tr, (const double(*)[4])nb, k + 6) < 0) {
            free(order), free(nb), free(ids);
            geo_plane_triples_free(&tr);
            return -ENOMEM;
        }
        if (cut_depth(gpl[g], (const double(*)[4])nb, k + 6, tol, &tr) <=
            cut_min + roof)
            drop[g] = 1;
    }
    free(order), free(nb), free(ids);
    geo_plane_triples_free(&tr);
    return 0;
}

int geo_convex_planes_find(const geo_poly *p, uint32_t views, double noise,
                           enum geo_convex_fit fit, const geo_ctx *ctx,
                           geo_convex_planes *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    geo_topo *t = geo_topo_build(p, err);
    if (!t)
        return -ENOMEM;
    int r = geo_convex_planes_find_topo(p, t, views, noise, fit, ctx, ret,
                                        err);
    geo_topo_free(t);
    return r;
}

int geo_convex_planes_find_topo(const geo_poly *p, const geo_topo *t,
                                uint32_t views, double noise,
                                enum geo_convex_fit fit, const geo_ctx *ctx,
                                geo_convex_planes *ret, geo_err *err)
{
    memset(ret, 0, sizeof *ret);
    if (!geo_topo_is_closed_manifold(t))
        return geo_err_set(err, -EINVAL, "the model is not a closed, "
                           "consistently oriented manifold");
    uint32_t nf = p->nfacets, nv = p->nverts, nc = geo_poly_ncorners(p);
    finder f;
    memset(&f, 0, sizeof f);
    f.p = p;
    f.t = t;
    double lo[3], hi[3];
    geo_poly_bbox(p, lo, hi);
    for (int k = 0; k < 3; k++)
        f.o[k] = 0.5 * (lo[k] + hi[k]);
    double size = geo_poly_size(p);
    f.step = views ? M_PI / views : 0;
    f.noise = noise > 0 ? noise : 0;
    f.dev0 = fmax(DEV_NOISE * f.noise, DEV_REL * size);
    f.fm = malloc(((size_t)nf + 1) * sizeof *f.fm);
    f.farea = malloc(((size_t)nf + 1) * sizeof *f.farea);
    f.group = malloc(((size_t)nf + 1) * sizeof *f.group);
    f.vstamp = calloc((size_t)nv + 1, sizeof *f.vstamp);
    f.fstamp = calloc((size_t)nf + 1, sizeof *f.fstamp);
    f.mem = malloc(((size_t)nf + 1) * sizeof *f.mem);
    f.vs = malloc(((size_t)nv + 1) * sizeof *f.vs);
    f.cand = malloc(((size_t)nc + 1) * sizeof *f.cand);
    uint32_t *order = malloc(((size_t)nf + 1) * sizeof *order);
    seg *sg = malloc(((size_t)nc + 1) * sizeof *sg);
    double *res = malloc((2 * (size_t)nc + 2) * sizeof *res);
    double *top = malloc(((size_t)nc + 1) * sizeof *top);
    mom *smom = malloc(((size_t)nc + 1) * sizeof *smom);
    bool *use = malloc(((size_t)nc + 1) * sizeof *use);
    uint32_t *nstart = NULL, *nlist = NULL;
    double (*gpl)[4] = NULL, *garea = NULL;
    mom *gm = NULL;
    uint8_t *drop = NULL;
    int r = -ENOMEM;
    if (!f.fm || !f.farea || !f.group || !f.vstamp || !f.fstamp || !f.mem ||
        !f.vs || !f.cand || !order || !sg || !res || !top || !smom || !use)
        goto done;
    for (uint32_t h = 0; h < nf; h++) {
        facet_mom(p, h, f.o, &f.fm[h]);
        f.farea[h] = f.fm[h].a;
        f.group[h] = GEO_NONE;
    }
    f.ctx = ctx;
    uint32_t ng = grow_groups(&f, order);
    if (f.canceled) {
        r = -ECANCELED;
        goto done;
    }
    if (join_groups(&f, &ng) < 0)
        goto done;
    ret->ngroups = ng;
    gpl = malloc(((size_t)ng + 1) * sizeof *gpl);
    garea = calloc((size_t)ng + 1, sizeof *garea);
    gm = calloc((size_t)ng + 1, sizeof *gm);
    drop = calloc((size_t)ng + 1, 1);
    ret->kept = malloc(((size_t)ng + 1) * sizeof *ret->kept);
    if (!gpl || !garea || !gm || !drop || !ret->kept)
        goto done;
    /* the group's area plane: the orientation and the fallback */
    double (*apl)[4] = malloc(((size_t)ng + 1) * sizeof *apl);
    if (!apl)
        goto done;
    for (uint32_t h = 0; h < nf; h++)
        mom_add(&gm[f.group[h]], &f.fm[h]);
    for (uint32_t h = 0; h < nf; h++) {
        uint32_t g = f.group[h];
        if (garea[g] == 0) {
            garea[g] = gm[g].a;
            if (!mom_plane(&gm[g], f.o, p->planes[h], apl[g], NULL))
                memcpy(apl[g], p->planes[h], sizeof apl[0]);
        }
    }
    if (within_cone(p, f.group, f.farea, ng, f.o, f.step, gm, apl) < 0) {
        free(apl);
        goto done;
    }
    /* step 2: the hinge fit over each group's boundary */
    uint32_t ns = 0;
    for (uint32_t c = 0; c < nc; c++) {
        uint32_t h = geo_topo_neighbor(t, c), fc = t->corner_facet[c];
        if (h == GEO_NONE || f.group[h] == f.group[fc])
            continue;
        sg[ns].a = p->fidx[c];
        sg[ns].b = p->fidx[geo_topo_next(p, t, c)];
        sg[ns].f = fc;
        sg[ns++].g = f.group[fc];
    }
    if (sort_segments(sg, ns, ng) < 0) {
        free(apl);
        goto done;
    }
    for (uint32_t g = 0; g < ng; g++)
        memcpy(gpl[g], apl[g], sizeof gpl[0]);
    /* the hinges' own scatter: the median residual scale over the groups
     * with enough boundary to tell (HINGE_SEGMENTS), a better noise
     * measure than the slivers' (whose fans hide most of it) */
    double *scales = malloc(((size_t)ng + 1) * sizeof *scales);
    if (!scales) {
        free(apl);
        goto done;
    }
    uint32_t nsc = 0;
    for (uint32_t i = 0, j; i < ns; i = j) {
        for (j = i; j < ns && sg[j].g == sg[i].g; j++)
            ;
        uint32_t g = sg[i].g;
        /* the other fits keep the area plane and take only the scatter
         * of the groups with enough boundary to tell it */
        if (fit != GEO_CONVEX_FIT_HINGE && j - i < HINGE_SEGMENTS)
            continue;
        double sc;
        hinge_fit(p, sg + i, j - i, f.o, fmax(f.noise, 1e-6 * size), apl[g],
                  res, top, smom, use, gpl[g], &sc);
        if (j - i >= HINGE_SEGMENTS)
            scales[nsc++] = sc;
        if (fit != GEO_CONVEX_FIT_HINGE)
            memcpy(gpl[g], apl[g], sizeof gpl[0]);
    }
    if (nsc) {
        ret->hinge_noise = geo_select_kth(scales, nsc, nsc / 2);
    }
    free(scales);
    /* the scan contains the stone: a hinge plane with the group's own
     * vertices deep inside it (farther than the hinges scatter) or far
     * outside it (beyond the roof) fitted something else; such a group
     * keeps its area plane */
    if (fit == GEO_CONVEX_FIT_HINGE) {
        double nzh = fmax(fmax(f.noise, ret->hinge_noise), 1e-6 * size);
        for (uint32_t h = 0; h < nf; h++) {
            uint32_t g = f.group[h];
            double width = 0, q[4];
            if (!mom_plane(&gm[g], f.o, gpl[g], q, &width))
                width = 0;
            double roof = f.dev0 + ROOF * width * f.step * hypot(gpl[g][0], gpl[g][1]);
            uint32_t n = geo_poly_facet_size(p, h);
            const uint32_t *fv = geo_poly_facet(p, h);
            for (uint32_t i = 0; i < n; i++) {
                double d = geo_plane_eval(gpl[g], p->verts[fv[i]]);
                if (d < -TRIM * 2 * nzh || d > 2 * roof) {
                    memcpy(gpl[g], apl[g], sizeof gpl[0]);
                    break;
                }
            }
        }
    }
    free(apl);
    /* step 3 */
    ret->group = f.group;
    f.group = NULL;
    if (group_neighbours(p, t, ret->group, ng, &nstart, &nlist) < 0)
        goto done;
    double nz = fmax(f.noise, ret->hinge_noise);
    double cut_min = nz > 0 ? CUT_NOISE * nz : CUT_REL * size;
    ret->cut_min = cut_min;
    /* a plane fitted to a group's surface lies up to its roof above the
     * true plane, so a cut no deeper than the roofs around it cannot be
     * told from them */
    double *groof = malloc(((size_t)ng + 1) * sizeof *groof);
    if (!groof)
        goto done;
    for (uint32_t g = 0; g < ng; g++) {
        double q[4], width = 0;
        if (!mom_plane(&gm[g], f.o, gpl[g], q, &width))
            width = 0;
        groof[g] = fit == GEO_CONVEX_FIT_HINGE ? 0
                   : ROOF * width * f.step * hypot(gpl[g][0], gpl[g][1]);
    }
    /* a box far around the scan (its planes' depth beyond any facet is
     * far more than any cut the support test allows) */
    double box[6][4], pad = 10 * size;
    for (int a = 0; a < 3; a++) {
        memset(box[2 * a], 0, sizeof box[0]);
        memset(box[2 * a + 1], 0, sizeof box[0]);
        box[2 * a][a] = 1;
        box[2 * a][3] = -(hi[a] + pad);
        box[2 * a + 1][a] = -1;
        box[2 * a + 1][3] = lo[a] - pad;
    }
    r = support(ret, (const double(*)[4])gpl, garea, groof, nstart, nlist,
                (const double(*)[4])box, cut_min, geo_poly_eps(p), drop);
    if (r < 0) {
        free(groof);
        goto done;
    }
    r = -ENOMEM;
    ret->planes = malloc(((size_t)ng + 1) * sizeof *ret->planes);
    ret->area = malloc(((size_t)ng + 1) * sizeof *ret->area);
    ret->allow = malloc(((size_t)ng + 1) * sizeof *ret->allow);
    ret->spare = malloc(((size_t)ng + 1) * sizeof *ret->spare);
    ret->span = malloc(((size_t)ng + 1) * sizeof *ret->span);
    if (!ret->planes || !ret->area || !ret->allow || !ret->spare ||
        !ret->span) {
        free(groof);
        goto done;
    }
    ret->dev0 = f.dev0;
    ret->step = f.step;
    group_spans(p, ret->group, (const double(*)[4])gpl, ng, ret->span);
    for (uint32_t g = 0; g < ng; g++) {
        double q[4], width = 0;
        if (!mom_plane(&gm[g], f.o, gpl[g], q, &width))
            width = 0;
        double allow =
            f.dev0 + ROOF * width * f.step * hypot(gpl[g][0], gpl[g][1]);
        if (drop[g]) {
            ret->kept[g] = GEO_NONE;
            ret->dropped++;
            geo_convex_spare *sp = &ret->spare[ret->nspare++];
            memcpy(sp->plane, gpl[g], sizeof sp->plane);
            sp->allow = allow;
            sp->roof = groof[g];
            sp->group = g;
            continue;
        }
        ret->kept[g] = ret->nplanes;
        memcpy(ret->planes[ret->nplanes], gpl[g], sizeof gpl[0]);
        ret->allow[ret->nplanes] = allow;
        ret->area[ret->nplanes++] = garea[g];
    }
    free(groof);
    r = 0;
done:
    if (r < 0) {
        geo_convex_planes_clear(ret);
        geo_err_set(err, r, r == -ECANCELED ? "correction canceled"
                                            : "out of memory");
    }
    free(f.fm), free(f.farea), free(f.group), free(f.vstamp), free(f.fstamp);
    free(f.mem), free(f.vs), free(f.cand), free(order), free(sg), free(res);
    free(top), free(smom);
    free(use), free(nstart), free(nlist), free(gpl), free(garea), free(gm);
    free(drop);
    return r;
}
