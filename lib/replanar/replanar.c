/* replanar.c — vertex move and re-planarisation (Palachev 2012, §4.2.3, §4.3.1–3):
 * alternating least-squares planes and penalised per-vertex 3×3 solves over
 * a growing active region (see replanar.h for the quantities and the
 * schedules); the least-norm schedule's driver is replanar_least_norm.c.
 *
 * Invariants of a run: fixed vertices never move and, with the default
 * fit, every plane of a facet through a fixed vertex passes through it (up
 * to rounding of d);
 * a vertex or facet outside the active region has exactly its start
 * position / plane; the active region only grows; the Jacobi-style update
 * (all vertices of a step read the same planes and positions) makes the
 * result independent of the order of the active lists. */
#include "replanar.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "grow.h"
#include "replanar_run.h"
#include "bvh.h"
#include "plane.h"
#include "selfint.h"
#include "vec.h"

/* The names of each option enum, indexed by its values (0, 1, ...). */
static const char *const SCHEDULE_NAMES[] = {"local-exp", "scaled",
                                             "global-exp", "least-norm"};
static const char *const FIT_NAMES[] = {"through-fixed", "all"};
static const char *const SCALED_K_NAMES[] = {"s2sum", "s2"};
#define NNAMES(a) (sizeof a / sizeof a[0])

static const char *name_of(unsigned v, const char *const *names, size_t n)
{
    return v < n ? names[v] : "unknown";
}

/* 0 with *ret the index of name in names, or -EINVAL. */
static int index_of(const char *name, const char *const *names, size_t n,
                    int *ret)
{
    for (size_t i = 0; name && i < n; i++)
        if (strcmp(name, names[i]) == 0) {
            *ret = (int)i;
            return 0;
        }
    return -EINVAL;
}

const char *geo_replanar_schedule_name(enum geo_replanar_schedule s)
{
    return name_of((unsigned)s, SCHEDULE_NAMES, NNAMES(SCHEDULE_NAMES));
}

int geo_replanar_schedule_parse(const char *name,
                                enum geo_replanar_schedule *ret)
{
    int i, r = index_of(name, SCHEDULE_NAMES, NNAMES(SCHEDULE_NAMES), &i);
    if (r == 0)
        *ret = (enum geo_replanar_schedule)i;
    return r;
}

const char *geo_replanar_fit_name(enum geo_replanar_fit f)
{
    return name_of((unsigned)f, FIT_NAMES, NNAMES(FIT_NAMES));
}

int geo_replanar_fit_parse(const char *name, enum geo_replanar_fit *ret)
{
    int i, r = index_of(name, FIT_NAMES, NNAMES(FIT_NAMES), &i);
    if (r == 0)
        *ret = (enum geo_replanar_fit)i;
    return r;
}

const char *geo_replanar_scaled_k_name(enum geo_replanar_scaled_k k)
{
    return name_of((unsigned)k, SCALED_K_NAMES, NNAMES(SCALED_K_NAMES));
}

int geo_replanar_scaled_k_parse(const char *name,
                                enum geo_replanar_scaled_k *ret)
{
    int i, r = index_of(name, SCALED_K_NAMES, NNAMES(SCALED_K_NAMES), &i);
    if (r == 0)
        *ret = (enum geo_replanar_scaled_k)i;
    return r;
}

void geo_replanar_opts_default(geo_replanar_opts *o,
                               enum geo_replanar_schedule s)
{
    (void)s; /* the paper uses the same numbers for all three */
    memset(o, 0, sizeof *o);
    o->k0 = 100.0;
    o->k_factor = 2.0;
    o->eps0 = 1e-7;
    o->eps_factor = 0.5;
    o->outer_rounds = 10;
    o->eps_final = 1e-10;
    o->max_steps = 2000;
    o->wake_tol = 1e-2;
    o->count_selfint = false;
    o->check = true;
    o->fit = GEO_REPLANAR_FIT_THROUGH_FIXED;
    o->scaled_k = GEO_REPLANAR_SCALED_K_S2SUM;
}

void geo_replanar_log_clear(geo_replanar_log *log)
{
    if (!log)
        return;
    free(log->rows);
    memset(log, 0, sizeof *log);
}

bool geo_replanar_result_valid(const geo_replanar_result *r)
{
    return r->converged && r->nselfint == 0 && r->ninverted == 0 &&
           r->volume > 0;
}

/* ---- preparation ---- */

static double facet_residual(const geo_poly *p, uint32_t f,
                             const double plane[4])
{
    double m = 0;
    const uint32_t *v = geo_poly_facet(p, f);
    for (uint32_t i = 0, n = geo_poly_facet_size(p, f); i < n; i++) {
        double d = fabs(geo_plane_eval(plane, p->verts[v[i]]));
        if (d > m)
            m = d;
    }
    return m;
}

geo_replanar_prep *geo_replanar_prep_free(geo_replanar_prep *prep)
{
    if (prep) {
        geo_poly_free(prep->poly);
        free(prep->vstart);
        free(prep->vfacets);
        free(prep->resid);
        geo_bvh_free(prep->fbvh);
        free(prep);
    }
    return NULL;
}

static int validate_model(const geo_poly *p, geo_err *err)
{
    int rc = geo_poly_validate_indices(p, err);
    if (rc < 0)
        return rc;
    for (uint32_t v = 0; v < p->nverts; v++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(p->verts[v][k]))
                return geo_err_set(err, -EINVAL, "vertices[%u]: not finite",
                                   v);
    return 0;
}

geo_replanar_prep *geo_replanar_prepare(const geo_poly *p, geo_err *err)
{
    if (validate_model(p, err) < 0)
        return NULL;
    geo_replanar_prep *prep = calloc(1, sizeof *prep);
    uint32_t nc = geo_poly_ncorners(p);
    if (prep) {
        prep->poly = geo_poly_copy(p);
        prep->vstart = calloc((size_t)p->nverts + 1, sizeof *prep->vstart);
        prep->vfacets = malloc(((size_t)nc + 1) * sizeof *prep->vfacets);
        prep->resid = malloc(((size_t)p->nfacets + 1) * sizeof *prep->resid);
    }
    if (!prep || !prep->poly || !prep->vstart || !prep->vfacets ||
        !prep->resid) {
        geo_err_set(err, -ENOMEM, "out of memory preparing the model");
        return geo_replanar_prep_free(prep);
    }
    geo_poly *q = prep->poly;
    for (uint32_t c = 0; c < nc; c++)
        prep->vstart[q->fidx[c] + 1]++;
    for (uint32_t v = 0; v < q->nverts; v++)
        prep->vstart[v + 1] += prep->vstart[v];
    uint32_t *fill = malloc(((size_t)q->nverts + 1) * sizeof *fill);
    if (!fill) {
        geo_err_set(err, -ENOMEM, "out of memory preparing the model");
        return geo_replanar_prep_free(prep);
    }
    memcpy(fill, prep->vstart, (size_t)q->nverts * sizeof *fill);
    for (uint32_t f = 0; f < q->nfacets; f++)
        for (uint32_t c = q->fstart[f]; c < q->fstart[f + 1]; c++)
            prep->vfacets[fill[q->fidx[c]]++] = f;
    free(fill);
    /* least-squares planes, oriented like the Newell vector; a degenerate
     * facet keeps its Newell direction through its centroid */
    for (uint32_t f = 0; f < q->nfacets; f++) {
        double *pl = q->planes[f];
        geo_poly_facet_area_vector(q, f, pl);
        if (!(geo_vnormalize(pl) > 0))
            geo_poly_facet_fit_plane(q, f, GEO_PLANE_UNWEIGHTED, pl);
        else
            rp_fit_plane(q, q->verts, NULL, f, pl);
        prep->resid[f] = facet_residual(q, f, pl);
    }
    prep->eps = geo_poly_eps(q);
    prep->volume = geo_poly_volume(q);
    prep->fbvh = geo_bvh_build_facets(q, err);
    if (!prep->fbvh)
        return geo_replanar_prep_free(prep);
    return prep;
}

/* ---- one run ---- */

void rp_activate_facet(run *r, uint32_t f)
{
    if (r->fact[f])
        return;
    r->fact[f] = 1;
    r->af[r->naf++] = f;
    const uint32_t *v = geo_poly_facet(r->p0, f);
    for (uint32_t i = 0, n = geo_poly_facet_size(r->p0, f); i < n; i++)
        if (!(r->vflag[v[i]] & V_ACTIVE)) {
            r->vflag[v[i]] |= V_ACTIVE;
            r->av[r->nav++] = v[i];
        }
}

/* The unit eigenvector of the smallest eigenvalue of the symmetric 2×2
 * matrix [[a, b], [b, c]]. */
static void small_eigvec2(double a, double b, double c, double ret[2])
{
    double h = 0.5 * (a - c);
    double lam = 0.5 * (a + c) - sqrt(h * h + b * b);
    double u[2] = {b, lam - a}, w[2] = {lam - c, b};
    double lu = u[0] * u[0] + u[1] * u[1], lw = w[0] * w[0] + w[1] * w[1];
    if (lu < lw) {
        u[0] = w[0];
        u[1] = w[1];
        lu = lw;
    }
    if (lu > 0) {
        double s = 1.0 / sqrt(lu);
        ret[0] = u[0] * s;
        ret[1] = u[1] * s;
    } else { /* a multiple of the identity: any direction */
        ret[0] = 1;
        ret[1] = 0;
    }
}

/* The unit eigenvector of the smallest eigenvalue of the symmetric PSD
 * matrix m (upper triangle), near the unit vector guess. A fitted facet
 * is nearly planar, so λ1 ≪ λ2: two steps of inverse iteration from the
 * previous normal, with the adjugate standing for det·m⁻¹ (it exists even
 * when m is singular), are exact to rounding; the error shrinks by λ1/λ2
 * per step, and λ1/λ2 ≤ (nᵀ m n)·tr(m)/tr(adj m) is checked — above 1e-3
 * the Jacobi solver decides. Returns false when m has rank ≤ 1. */
static bool smallest_eigvec(double m[3][3], const double guess[3],
                            double ret[3])
{
    double a = m[0][0], b = m[0][1], c = m[0][2], d = m[1][1], e = m[1][2],
           f = m[2][2];
    double adj[3][3] = {{d * f - e * e, c * e - b * f, b * e - c * d},
                        {0, a * f - c * c, b * c - a * e},
                        {0, 0, a * d - b * b}};
    adj[1][0] = adj[0][1];
    adj[2][0] = adj[0][2];
    adj[2][1] = adj[1][2];
    double tr = a + d + f, tradj = adj[0][0] + adj[1][1] + adj[2][2];
    if (!(tr > 0) || !(tradj > 1e-24 * tr * tr))
        return false;
    double n[3] = {guess[0], guess[1], guess[2]};
    for (int it = 0; it < 2; it++) {
        double w[3];
        for (int i = 0; i < 3; i++)
            w[i] = adj[i][0] * n[0] + adj[i][1] * n[1] + adj[i][2] * n[2];
        if (!(geo_vnormalize(w) > 0))
            break;
        memcpy(n, w, sizeof n);
    }
    double mn[3] = {a * n[0] + b * n[1] + c * n[2],
                    b * n[0] + d * n[1] + e * n[2],
                    c * n[0] + e * n[1] + f * n[2]};
    if (geo_vdot(n, mn) * tr <= 1e-3 * tradj && geo_vlen(n) > 0.5) {
        memcpy(ret, n, sizeof n);
        return true;
    }
    double val[3], vec[3][3];
    geo_sym3_eigen(m, val, vec);
    if (!(val[1] > 1e-24 * val[2]) || !(val[2] > 0))
        return false;
    memcpy(ret, vec[0], sizeof vec[0]);
    return true;
}

/* Fits the plane of active facet f to the current positions: least squares
 * through the centroid, through the one fixed vertex, through the line of
 * two, or of the fixed vertices alone (three or more). The normal keeps
 * the side of the previous one; a degenerate facet (all points on a line)
 * keeps its previous normal. */
void rp_fit_plane(const geo_poly *p, double (*x)[3], const uint8_t *vflag,
                      uint32_t f, double prev[4])
{
    const uint32_t *v = geo_poly_facet(p, f);
    uint32_t n = geo_poly_facet_size(p, f), nfix = 0, fix[2] = {0, 0};
    for (uint32_t i = 0; i < n; i++)
        if (vflag && (vflag[v[i]] & V_FIXED)) {
            if (nfix < 2)
                fix[nfix] = v[i];
            nfix++;
        }
    double c[3] = {0, 0, 0};
    bool only_fixed = nfix >= 3;
    if (nfix == 0 || only_fixed) {
        uint32_t cnt = 0;
        for (uint32_t i = 0; i < n; i++)
            if (!only_fixed || (vflag && (vflag[v[i]] & V_FIXED))) {
                geo_vadd(c, x[v[i]], c);
                cnt++;
            }
        geo_vscale(c, 1.0 / cnt, c);
    } else {
        memcpy(c, x[fix[0]], sizeof c);
    }
    double m[3][3] = {{0}};
    for (uint32_t i = 0; i < n; i++) {
        if (only_fixed && !(vflag && (vflag[v[i]] & V_FIXED)))
            continue;
        double d[3];
        geo_vsub(x[v[i]], c, d);
        for (int a = 0; a < 3; a++)
            for (int b = a; b < 3; b++)
                m[a][b] += d[a] * d[b];
    }
    double nrm[3];
    double line[3];
    if (nfix == 2) {
        geo_vsub(x[fix[1]], x[fix[0]], line);
    }
    if (nfix == 2 && geo_vnormalize(line) > 0) {
        double e1[3], e2[3], me1[3], me2[3];
        geo_vbasis(line, e1, e2);
        for (int a = 0; a < 3; a++) {
            me1[a] = me2[a] = 0;
            for (int b = 0; b < 3; b++) {
                double mab = a <= b ? m[a][b] : m[b][a];
                me1[a] += mab * e1[b];
                me2[a] += mab * e2[b];
            }
        }
        double w[2];
        small_eigvec2(geo_vdot(e1, me1), geo_vdot(e1, me2),
                      geo_vdot(e2, me2), w);
        for (int k = 0; k < 3; k++)
            nrm[k] = w[0] * e1[k] + w[1] * e2[k];
    } else if (!smallest_eigvec(m, prev, nrm)) {
        /* all points on a line (or one point): the normal is undefined */
        prev[3] = -geo_vdot(prev, c);
        return;
    }
    if (geo_vdot(nrm, prev) < 0)
        geo_vscale(nrm, -1.0, nrm);
    geo_vnormalize(nrm);
    prev[0] = nrm[0];
    prev[1] = nrm[1];
    prev[2] = nrm[2];
    prev[3] = -geo_vdot(nrm, c);
}

/* The penalised position of free vertex v: x0 + y with
 * (I + K Σ n nᵀ) y = −K Σ n (n·x0 + d), solved for the displacement y so
 * that large K does not cancel large coordinates; for K > 1 the system is
 * divided by K (I/K + Σ n nᵀ) to keep it well scaled. */
static void solve_vertex(const run *r, uint32_t v, const double x0[3],
                         double k, double ret[3])
{
    const geo_replanar_prep *pr = r->prep;
    double g[3][3] = {{0}}, rhs[3] = {0, 0, 0};
    for (uint32_t i = pr->vstart[v]; i < pr->vstart[v + 1]; i++) {
        const double *pl = r->pl[pr->vfacets[i]];
        double res = geo_plane_eval(pl, x0);
        for (int a = 0; a < 3; a++) {
            rhs[a] -= pl[a] * res;
            for (int b = a; b < 3; b++)
                g[a][b] += pl[a] * pl[b];
        }
    }
    double diag = 1.0, scale = k;
    if (k > 1.0) {
        diag = 1.0 / k;
        scale = 1.0;
    }
    for (int a = 0; a < 3; a++) {
        rhs[a] *= scale;
        for (int b = a; b < 3; b++)
            g[a][b] = g[a][b] * scale + (a == b ? diag : 0.0);
    }
    /* LDLᵀ of the 3×3 SPD matrix, unrolled (the hot loop of a run) */
    double d0 = g[0][0], l10 = g[0][1] / d0, l20 = g[0][2] / d0;
    double d1 = g[1][1] - l10 * l10 * d0;
    double l21 = (g[1][2] - l20 * l10 * d0) / d1;
    double d2 = g[2][2] - l20 * l20 * d0 - l21 * l21 * d1;
    if (!(d0 > 0) || !(d1 > 0) || !(d2 > 0)) {
        memcpy(ret, x0, 3 * sizeof *ret);
        return;
    }
    double z0 = rhs[0], z1 = rhs[1] - l10 * z0;
    double z2 = rhs[2] - l20 * z0 - l21 * z1;
    double y[3];
    y[2] = z2 / d2;
    y[1] = z1 / d1 - l21 * y[2];
    y[0] = z0 / d0 - l10 * y[1] - l20 * y[2];
    geo_vadd(x0, y, ret);
}

/* S2 and S2sum over the incidences of the active free vertices with the
 * current planes. */
void rp_plane_errors(run *r)
{
    const geo_replanar_prep *pr = r->prep;
    double s2 = 0, s2sum = 0;
    for (uint32_t i = 0; i < r->nav; i++) {
        uint32_t v = r->av[i];
        if (r->vflag[v] & V_FIXED)
            continue;
        for (uint32_t j = pr->vstart[v]; j < pr->vstart[v + 1]; j++) {
            double e = geo_plane_eval(r->pl[pr->vfacets[j]], r->x[v]);
            s2sum += e * e;
            if (fabs(e) > s2 || isnan(e))
                s2 = isnan(e) ? INFINITY : fabs(e);
        }
    }
    r->s2 = s2;
    r->s2sum = s2sum;
}

/* One step: refit the active planes, move every active free vertex
 * (Jacobi: all read the same planes), measure Δ, S1, S2, S2sum, then grow
 * the active region by the facets of vertices that left their start by
 * more than wake_abs. local chooses x0 = the current position (§4.3.1,
 * §4.3.2) or the start position (§4.3.3). */
static void step(run *r, double k, bool local)
{
    const uint8_t *fixflag = r->fit_all ? NULL : r->vflag;
    for (uint32_t i = 0; i < r->naf; i++)
        rp_fit_plane(r->p0, r->x, fixflag, r->af[i], r->pl[r->af[i]]);
    for (uint32_t i = 0; i < r->nav; i++) {
        uint32_t v = r->av[i];
        if (r->vflag[v] & V_FIXED)
            continue;
        solve_vertex(r, v, local ? r->x[v] : rp_start_pos(r, v), k, r->xn[i]);
    }
    double delta = 0, s1 = 0;
    r->nwake = 0;
    for (uint32_t i = 0; i < r->nav; i++) {
        uint32_t v = r->av[i];
        if (r->vflag[v] & V_FIXED)
            continue;
        double d[3];
        geo_vsub(r->xn[i], r->x[v], d);
        delta += geo_vdot(d, d);
        memcpy(r->x[v], r->xn[i], sizeof r->x[v]);
        geo_vsub(r->x[v], rp_start_pos(r, v), d);
        double dd = geo_vdot(d, d);
        s1 += dd;
        if (dd > r->wake_abs * r->wake_abs) {
            const geo_replanar_prep *pr = r->prep;
            for (uint32_t j = pr->vstart[v]; j < pr->vstart[v + 1]; j++) {
                uint32_t f = pr->vfacets[j];
                if (!r->fact[f] && !r->fwake[f]) {
                    r->fwake[f] = 1;
                    r->wake[r->nwake++] = f;
                }
            }
        }
    }
    /* every incidence that may differ from the start touches an active
     * vertex: an active facet's vertices are all active */
    rp_plane_errors(r);
    for (uint32_t i = 0; i < r->nwake; i++) {
        r->fwake[r->wake[i]] = 0;
        rp_activate_facet(r, r->wake[i]);
    }
    r->delta = delta;
    r->s1 = s1;
}

/* ---- the schedules ---- */

int rp_log_row(geo_replanar_log *log, const run *r, uint32_t stepno,
                   uint32_t outer, uint32_t inner, double eps, double k,
                   int64_t nselfint)
{
    if (!log)
        return 0;
    if (geo_grow((void **)&log->rows, &log->cap, log->n + 1,
                 sizeof *log->rows) < 0)
        return -ENOMEM;
    log->rows[log->n++] = (geo_replanar_step){
        .step = stepno, .outer = outer, .inner = inner, .delta = r->delta,
        .s1 = r->s1, .s2 = r->s2, .s2sum = r->s2sum, .eps0 = eps, .k = k,
        .nselfint = nselfint, .active_vertices = r->nav,
        .active_facets = r->naf};
    return 0;
}

static void run_free(run *r)
{
    free(r->x);
    free(r->pl);
    free(r->xn);
    free(r->vflag);
    free(r->fact);
    free(r->av);
    free(r->af);
    free(r->wake);
    free(r->fwake);
}

static int run_init(run *r, const geo_replanar_prep *prep, uint32_t nfixed,
                    const uint32_t *fixed, const double (*targets)[3],
                    double wake_tol, bool fit_all, geo_err *err)
{
    const geo_poly *p = prep->poly;
    memset(r, 0, sizeof *r);
    r->prep = prep;
    r->p0 = p;
    size_t nv = (size_t)p->nverts + 1, nf = (size_t)p->nfacets + 1;
    r->x = malloc(nv * sizeof *r->x);
    r->pl = malloc(nf * sizeof *r->pl);
    r->xn = malloc(nv * sizeof *r->xn);
    r->vflag = calloc(nv, 1);
    r->fact = calloc(nf, 1);
    r->fwake = calloc(nf, 1);
    r->av = malloc(nv * sizeof *r->av);
    r->af = malloc(nf * sizeof *r->af);
    r->wake = malloc(nf * sizeof *r->wake);
    if (!r->x || !r->pl || !r->xn || !r->vflag || !r->fact || !r->fwake ||
        !r->av || !r->af || !r->wake)
        return geo_err_set(err, -ENOMEM, "out of memory");
    memcpy(r->x, p->verts, (size_t)p->nverts * sizeof *r->x);
    memcpy(r->pl, p->planes, (size_t)p->nfacets * sizeof *r->pl);
    r->wake_abs = wake_tol * prep->eps;
    r->fit_all = fit_all;
    for (uint32_t i = 0; i < nfixed; i++) {
        uint32_t v = fixed[i];
        if (v >= p->nverts)
            return geo_err_set(err, -EINVAL,
                               "fixed[%u]: vertex %u out of range (%u "
                               "vertices)", i, v, p->nverts);
        if (r->vflag[v] & V_FIXED)
            return geo_err_set(err, -EINVAL,
                               "fixed[%u]: vertex %u listed twice", i, v);
        if (targets) {
            for (int k = 0; k < 3; k++)
                if (!isfinite(targets[i][k]))
                    return geo_err_set(err, -EINVAL,
                                       "targets[%u]: not finite", i);
            memcpy(r->x[v], targets[i], sizeof r->x[v]);
        }
        r->vflag[v] |= V_FIXED;
    }
    for (uint32_t i = 0; i < nfixed; i++)
        for (uint32_t j = prep->vstart[fixed[i]];
             j < prep->vstart[fixed[i] + 1]; j++)
            rp_activate_facet(r, prep->vfacets[j]);
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (prep->resid[f] > r->wake_abs)
            rp_activate_facet(r, f);
    /* a facet with three or more fixed vertices is fitted to them alone:
     * they must be coplanar */
    for (uint32_t i = 0; i < r->naf && !fit_all; i++) {
        uint32_t f = r->af[i], nfix = 0;
        const uint32_t *v = geo_poly_facet(p, f);
        uint32_t n = geo_poly_facet_size(p, f);
        for (uint32_t j = 0; j < n; j++)
            nfix += (r->vflag[v[j]] & V_FIXED) != 0;
        if (nfix < 3)
            continue;
        rp_fit_plane(p, r->x, r->vflag, f, r->pl[f]);
        for (uint32_t j = 0; j < n; j++)
            if ((r->vflag[v[j]] & V_FIXED) &&
                !(fabs(geo_plane_eval(r->pl[f], r->x[v[j]])) <= prep->eps))
                return geo_err_set(err, -EINVAL,
                                   "facets[%u]: its %u fixed vertices are "
                                   "not coplanar", f, nfix);
    }
    return 0;
}

/* ---- self-intersections of the active region ---- */

typedef struct si_count {
    const run *r;
    const geo_poly *view;  /* the facets with the current positions */
    geo_facet_shape *shape; /* by active-list slot */
    uint32_t f;            /* slot of the facet being queried */
    int64_t count;
    int rc;
} si_count;

static bool si_test(si_count *c, uint32_t f, uint32_t g,
                    const geo_facet_shape *sf, const geo_facet_shape *sg)
{
    int hit = geo_facets_intersect(c->view, f, g, sf, sg);
    if (hit < 0) {
        c->rc = hit;
        return false;
    }
    c->count += hit;
    return true;
}

/* An active facet against a facet outside the region (start box, and
 * positions that differ from the start by at most wake_abs). */
static bool si_visit_outer(void *user, uint32_t g)
{
    si_count *c = user;
    if (c->r->fact[g])
        return true;
    geo_facet_shape sg;
    geo_facet_shape_of(c->view, g, &sg);
    return si_test(c, c->r->af[c->f], g, &c->shape[c->f], &sg);
}

static bool si_visit_pair(void *user, uint32_t a, uint32_t b)
{
    si_count *c = user;
    return si_test(c, c->r->af[a], c->r->af[b], &c->shape[a], &c->shape[b]);
}

static void facet_box(const geo_poly *p, uint32_t f, double (*x)[3],
                      double margin, geo_bbox *ret)
{
    const uint32_t *v = geo_poly_facet(p, f);
    geo_bbox_empty(ret);
    for (uint32_t i = 0, n = geo_poly_facet_size(p, f); i < n; i++)
        geo_bbox_add(ret, x[v[i]]);
    for (int k = 0; k < 3; k++) {
        ret->lo[k] -= margin;
        ret->hi[k] += margin;
    }
}

/* Self-intersections with at least one facet in the active region (all
 * others are as at the start): active facets whose own polygon
 * intersects itself, active pairs (a BVH of their current boxes) and
 * active–inactive pairs (the start's facet BVH, queried with current boxes
 * grown by wake_abs). Exact tests of lib/inspect/selfint.h. Count in *ret; 0 or
 * -ENOMEM. */
int rp_count_selfint(const run *r, int64_t *ret)
{
    const geo_poly *p0 = r->p0;
    geo_poly view = *p0;
    view.verts = r->x;
    view.planes = r->pl;
    si_count c = {.r = r, .view = &view};
    c.shape = malloc(((size_t)r->naf + 1) * sizeof *c.shape);
    geo_bbox *boxes = malloc(((size_t)r->naf + 1) * sizeof *boxes);
    geo_bvh *h = NULL;
    int rc = 0;
    if (!c.shape || !boxes) {
        rc = -ENOMEM;
        goto out;
    }
    for (uint32_t i = 0; i < r->naf; i++) {
        uint32_t f = r->af[i];
        geo_facet_shape_of(&view, f, &c.shape[i]);
        c.count += geo_facet_self_intersects(&view, f, &c.shape[i]);
        facet_box(p0, f, r->x, 0.0, &boxes[i]);
    }
    for (uint32_t i = 0; i < r->naf && c.rc == 0; i++) {
        geo_bbox q;
        facet_box(p0, r->af[i], r->x, r->wake_abs, &q);
        c.f = i;
        geo_bvh_query_box(r->prep->fbvh, &q, si_visit_outer, &c);
    }
    if (c.rc == 0 && r->naf > 1) {
        h = geo_bvh_build(boxes, r->naf, NULL);
        if (!h)
            rc = -ENOMEM;
        else
            geo_bvh_pairs(h, 0, 0, si_visit_pair, &c);
    }
    if (c.rc < 0)
        rc = c.rc;
out:
    geo_bvh_free(h);
    free(boxes);
    free(c.shape);
    *ret = c.count;
    return rc;
}

/* Signed volume of facet f's fan about o (×6), from positions x. */
static double facet_volume6(const geo_poly *p, uint32_t f, double (*x)[3],
                            const double o[3])
{
    return geo_fan_volume6(0, (const double(*)[3])x, geo_poly_facet(p, f),
                           geo_poly_facet_size(p, f), o);
}

/* Newell vector of facet f from positions x. */
static void facet_newell(const geo_poly *p, uint32_t f, double (*x)[3],
                         double ret[3])
{
    const uint32_t *v = geo_poly_facet(p, f);
    uint32_t n = geo_poly_facet_size(p, f);
    ret[0] = ret[1] = ret[2] = 0;
    for (uint32_t i = 1; i + 1 < n; i++) {
        double a[3], b[3], c[3];
        geo_vsub(x[v[i]], x[v[0]], a);
        geo_vsub(x[v[i + 1]], x[v[0]], b);
        geo_vcross(a, b, c);
        geo_vadd(ret, c, ret);
    }
}

/* Orientation part of the inspection, over the active facets (the others
 * are as at the start): inverted facets and the signed volume, updated
 * from the start's by the active facets' change. */
static void inspect_orientation(const run *r, geo_replanar_result *ret)
{
    const geo_poly *p = r->p0;
    double o[3] = {0, 0, 0}, vol6 = 0;
    if (p->nverts)
        memcpy(o, p->verts[0], sizeof o);
    int64_t ninv = 0;
    for (uint32_t i = 0; i < r->naf; i++) {
        uint32_t f = r->af[i];
        vol6 += facet_volume6(p, f, r->x, o) -
                facet_volume6(p, f, p->verts, o);
        double nw[3];
        facet_newell(p, f, r->x, nw);
        if (geo_vdot(r->pl[f], p->planes[f]) < 0 ||
            !(geo_vdot(nw, r->pl[f]) > 0))
            ninv++;
    }
    ret->ninverted = ninv;
    ret->volume = r->prep->volume + vol6 / 6.0;
}

/* The largest distance of a fixed vertex from the plane of one of its
 * facets (mm). */
static double fixed_residual(const run *r, uint32_t nfixed,
                             const uint32_t *fixed)
{
    const geo_replanar_prep *pr = r->prep;
    double m = 0;
    for (uint32_t i = 0; i < nfixed; i++)
        for (uint32_t j = pr->vstart[fixed[i]]; j < pr->vstart[fixed[i] + 1];
             j++) {
            double e = fabs(geo_plane_eval(r->pl[pr->vfacets[j]],
                                           r->x[fixed[i]]));
            if (e > m || isnan(e))
                m = e;
        }
    return m;
}

int geo_replanar_solve(const geo_replanar_prep *prep, uint32_t nfixed,
                       const uint32_t *fixed, const double (*targets)[3],
                       enum geo_replanar_schedule schedule,
                       const geo_replanar_opts *opts, const geo_ctx *ctx,
                       geo_replanar_log *log, geo_replanar_result *ret,
                       geo_poly *ret_poly, geo_err *err)
{
    geo_replanar_opts o;
    if (opts)
        o = *opts;
    else
        geo_replanar_opts_default(&o, schedule);
    if (!(o.k0 > 0 && isfinite(o.k0)) || !(o.k_factor >= 1) ||
        !isfinite(o.k_factor) || !(o.eps0 > 0) || !(o.eps_factor > 0) ||
        !(o.eps_factor <= 1) || !(o.eps_final > 0) || o.max_steps == 0 ||
        !(o.wake_tol >= 0) || o.outer_rounds == 0 ||
        (o.fit != GEO_REPLANAR_FIT_THROUGH_FIXED &&
         o.fit != GEO_REPLANAR_FIT_ALL) ||
        (o.scaled_k != GEO_REPLANAR_SCALED_K_S2SUM &&
         o.scaled_k != GEO_REPLANAR_SCALED_K_S2))
        return geo_err_set(err, -EINVAL, "options: out of range");
    if (schedule != GEO_REPLANAR_LOCAL_EXP &&
        schedule != GEO_REPLANAR_SCALED &&
        schedule != GEO_REPLANAR_GLOBAL_EXP &&
        schedule != GEO_REPLANAR_LEAST_NORM)
        return geo_err_set(err, -EINVAL, "schedule: unknown (%d)",
                           (int)schedule);
    if (schedule == GEO_REPLANAR_LEAST_NORM && o.fit == GEO_REPLANAR_FIT_ALL)
        return geo_err_set(err, -EINVAL, "fit all: the least-norm schedule "
                           "fits its planes through the fixed vertices");
    if (ret_poly && (ret_poly->nverts != prep->poly->nverts ||
                     ret_poly->nfacets != prep->poly->nfacets))
        return geo_err_set(err, -EINVAL,
                           "result model: not a copy of the prepared one");
    memset(ret, 0, sizeof *ret);
    ret->nselfint = ret->ninverted = ret->first_selfint_step = -1;

    run r;
    int rc = run_init(&r, prep, nfixed, fixed, targets, o.wake_tol,
                      o.fit == GEO_REPLANAR_FIT_ALL, err);
    if (rc < 0) {
        run_free(&r);
        return rc;
    }
    double k = o.k0, eps = schedule == GEO_REPLANAR_LOCAL_EXP ? o.eps0
                                                              : o.eps_final;
    bool local = schedule != GEO_REPLANAR_GLOBAL_EXP;
    uint32_t stepno = 0, outer = 0, inner = 0;
    bool converged = false;
    int64_t nsi = -1;
    if (schedule == GEO_REPLANAR_LEAST_NORM) {
        rc = rp_least_norm_run(&r, &o, ctx, log, &stepno, &converged, &nsi,
                            ret, err);
        k = 0;
    } else {
        for (;;) {
            if (stepno >= o.max_steps)
                break;
            rc = geo_ctx_progress(ctx, (double)stepno / o.max_steps);
            if (rc < 0) {
                geo_err_set(err, rc, "canceled");
                break;
            }
            step(&r, k, local);
            bool below = r.s2 < eps;
            if (o.count_selfint) {
                rc = rp_count_selfint(&r, &nsi);
                if (rc < 0) {
                    geo_err_set(err, rc, "out of memory");
                    break;
                }
                if (nsi > 0 && ret->first_selfint_step < 0)
                    ret->first_selfint_step = stepno;
            }
            rc = rp_log_row(log, &r, stepno, schedule == GEO_REPLANAR_LOCAL_EXP
                                              ? outer : stepno,
                         schedule == GEO_REPLANAR_LOCAL_EXP ? inner : stepno, eps,
                         k, nsi);
            if (rc < 0) {
                geo_err_set(err, rc, "out of memory for the log");
                break;
            }
            stepno++;
            inner++;
            if (!isfinite(r.s2) || !isfinite(r.s1))
                break; /* diverged */
            if (schedule == GEO_REPLANAR_LOCAL_EXP) {
                if (below) {
                    if (++outer == o.outer_rounds) {
                        converged = true;
                        break;
                    }
                    inner = 0;
                    k *= o.k_factor;
                    eps *= o.eps_factor;
                } else if (r.delta == 0) {
                    break; /* stalled: the next step would repeat this one */
                }
            } else if (below) {
                converged = true;
                break;
            } else if (schedule == GEO_REPLANAR_SCALED) {
                double nk = k;
                if (o.scaled_k == GEO_REPLANAR_SCALED_K_S2)
                    nk = r.s2 > 0 ? r.s1 / r.s2 : k;
                else if (r.s2sum > 0)
                    nk = r.s1 / r.s2sum;
                if (r.delta == 0 && nk == k)
                    break;
                k = nk;
            } else {
                k *= o.k_factor;
            }
            if (!isfinite(k) || !(k > 0))
                break;
        }
    }
    if (rc == 0) {
        ret->converged = converged;
        ret->steps = stepno;
        ret->s1 = r.s1;
        ret->s2 = r.s2;
        ret->k = k;
        ret->active_vertices = r.nav;
        ret->active_facets = r.naf;
        ret->fixed_resid = fixed_residual(&r, nfixed, fixed);
        if (o.check) {
            inspect_orientation(&r, ret);
            if (nsi < 0)
                rc = rp_count_selfint(&r, &nsi);
            if (rc < 0)
                geo_err_set(err, rc, "out of memory");
            ret->nselfint = nsi;
        }
        if (ret_poly && rc == 0) {
            memcpy(ret_poly->verts, r.x,
                   (size_t)prep->poly->nverts * sizeof *r.x);
            memcpy(ret_poly->planes, r.pl,
                   (size_t)prep->poly->nfacets * sizeof *r.pl);
        }
    }
    run_free(&r);
    return rc;
}

/* One solve from p's own start (validated and prepared for it), the
 * result written back into p. */
static int solve_once(geo_poly *p, uint32_t nfixed, const uint32_t *fixed,
                      const double (*targets)[3],
                      enum geo_replanar_schedule schedule,
                      const geo_replanar_opts *opts, const geo_ctx *ctx,
                      geo_replanar_log *log, geo_replanar_result *ret,
                      geo_err *err)
{
    int rc = validate_model(p, err);
    if (rc < 0)
        return rc;
    geo_replanar_prep *prep = geo_replanar_prepare(p, err);
    if (!prep)
        return -ENOMEM;
    rc = geo_replanar_solve(prep, nfixed, fixed, targets, schedule, opts, ctx,
                            log, ret, p, err);
    geo_replanar_prep_free(prep);
    return rc;
}

int geo_replanarize(geo_poly *p, const uint32_t *fixed, uint32_t nfixed,
                    enum geo_replanar_schedule schedule,
                    const geo_replanar_opts *opts, const geo_ctx *ctx,
                    geo_replanar_log *log, geo_replanar_result *ret,
                    geo_err *err)
{
    return solve_once(p, nfixed, fixed, NULL, schedule, opts, ctx, log, ret,
                      err);
}

int geo_move(geo_poly *p, uint32_t v, const double target[3],
                    enum geo_replanar_schedule schedule,
                    const geo_replanar_opts *opts, const geo_ctx *ctx,
                    geo_replanar_log *log, geo_replanar_result *ret,
                    geo_err *err)
{
    if (v >= p->nverts)
        return geo_err_set(err, -EINVAL,
                           "vertex %u out of range (%u vertices)", v,
                           p->nverts);
    return solve_once(p, 1, &v, (const double(*)[3])target, schedule, opts,
                      ctx, log, ret, err);
}
