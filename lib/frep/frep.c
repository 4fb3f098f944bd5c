/* frep.c — F-rep objects: the node graph, its compilation into a postfix
 * program, and point, gradient, interval and specialising evaluation.
 *
 * Invariants: node ids are dense and children always have smaller ids
 * than their parent (acyclic); every quadric is stored centred,
 *   F = k + Σ a_i d_i² + b₀ d_x d_y + b₁ d_y d_z + b₂ d_x d_z + Σ g_i d_i,
 *   d = p − c,
 * which lets the interval bound treat each axis exactly; a compiled
 * program's stack never grows beyond GEO_FREP_MAX_STACK (the depth limit
 * guarantees it). */
#include "frep.h"

#include "grow.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec.h"

enum node_kind {
    NODE_PRIM,
    NODE_PERTURBED,
    NODE_UNION,
    NODE_INTERSECTION,
    NODE_DIFFERENCE,
};

typedef struct prim {
    double c[3], a[3], b[3], g[3], k;
} prim;

typedef struct node {
    uint8_t kind;
    uint32_t depth; /* 1 for a primitive */
    uint32_t prim;  /* NODE_PRIM */
    uint32_t nkids; /* children: kids[kid .. kid + nkids) */
    uint32_t kid;
} node;

struct geo_frep {
    node *nodes;
    uint32_t nnodes;
    size_t cap_nodes;
    prim *prims;
    uint32_t nprims;
    size_t cap_prims;
    uint32_t *kids; /* child ids; for perturbed: base, then terms */
    double *amps;   /* parallel to kids (perturbation amplitudes) */
    uint32_t nkids;
    size_t cap_kids;
    geo_frep_op *ops;
    uint32_t nops;
    uint32_t *pieces; /* roots of the min/max-free subtrees */
    uint32_t npieces;
    double lo[3], hi[3];
};

geo_frep *geo_frep_new(void)
{
    return calloc(1, sizeof(geo_frep));
}

geo_frep *geo_frep_free(geo_frep *f)
{
    if (f) {
        free(f->nodes);
        free(f->prims);
        free(f->kids);
        free(f->amps);
        free(f->ops);
        free(f->pieces);
        free(f);
    }
    return NULL;
}

static bool finite3(const double v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static int64_t add_node(geo_frep *f, uint8_t kind, uint32_t depth,
                        geo_err *err)
{
    if (f->nnodes >= GEO_FREP_MAX_NODES)
        return geo_err_set(err, -ERANGE, "more than %u shapes",
                           GEO_FREP_MAX_NODES);
    if (depth > GEO_FREP_MAX_DEPTH)
        return geo_err_set(err, -ERANGE, "shapes nested deeper than %u",
                           GEO_FREP_MAX_DEPTH);
    if (geo_grow((void **)&f->nodes, &f->cap_nodes, f->nnodes + 1,
             sizeof *f->nodes) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    node *n = &f->nodes[f->nnodes];
    memset(n, 0, sizeof *n);
    n->kind = kind;
    n->depth = depth;
    return f->nnodes++;
}

static int64_t add_prim(geo_frep *f, const prim *pr, geo_err *err)
{
    if (geo_grow((void **)&f->prims, &f->cap_prims, f->nprims + 1,
             sizeof *f->prims) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    int64_t id = add_node(f, NODE_PRIM, 1, err);
    if (id < 0)
        return id;
    f->prims[f->nprims] = *pr;
    f->nodes[id].prim = f->nprims++;
    return id;
}

int64_t geo_frep_sphere(geo_frep *f, const double center[3], double radius,
                        geo_err *err)
{
    if (!finite3(center) || !isfinite(radius))
        return geo_err_set(err, -EINVAL, "sphere: not a finite number");
    if (!(radius > 0))
        return geo_err_set(err, -EINVAL, "sphere: radius must be > 0");
    prim pr = {.k = radius * radius};
    for (int i = 0; i < 3; i++) {
        pr.c[i] = center[i];
        pr.a[i] = -1.0;
    }
    return add_prim(f, &pr, err);
}

int64_t geo_frep_ellipsoid(geo_frep *f, const double center[3],
                           const double radii[3], geo_err *err)
{
    if (!finite3(center) || !finite3(radii))
        return geo_err_set(err, -EINVAL, "ellipsoid: not a finite number");
    prim pr = {.k = 1.0};
    for (int i = 0; i < 3; i++) {
        if (!(radii[i] > 0))
            return geo_err_set(err, -EINVAL,
                               "ellipsoid: radii must be > 0");
        pr.c[i] = center[i];
        pr.a[i] = -1.0 / (radii[i] * radii[i]);
    }
    return add_prim(f, &pr, err);
}

int64_t geo_frep_quadric(geo_frep *f, const double q[10], geo_err *err)
{
    for (int i = 0; i < 10; i++)
        if (!isfinite(q[i]))
            return geo_err_set(err, -EINVAL, "quadric: not a finite number");
    prim pr = {.a = {q[0], q[1], q[2]},
               .b = {q[3], q[4], q[5]},
               .g = {q[6], q[7], q[8]},
               .k = q[9]};
    return add_prim(f, &pr, err);
}

int64_t geo_frep_halfspace(geo_frep *f, const double plane[4], geo_err *err)
{
    if (!finite3(plane) || !isfinite(plane[3]))
        return geo_err_set(err, -EINVAL, "halfspace: not a finite number");
    if (plane[0] == 0 && plane[1] == 0 && plane[2] == 0)
        return geo_err_set(err, -EINVAL, "halfspace: zero normal");
    prim pr = {.g = {-plane[0], -plane[1], -plane[2]}, .k = -plane[3]};
    return add_prim(f, &pr, err);
}

static int64_t add_combo(geo_frep *f, uint8_t kind, uint32_t n,
                         const uint32_t *ids, const double *amps,
                         const char *what, geo_err *err)
{
    if (n == 0)
        return geo_err_set(err, -EINVAL, "%s: no shapes", what);
    uint32_t depth = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (ids[i] >= f->nnodes)
            return geo_err_set(err, -EINVAL, "%s: shape %u does not exist",
                               what, ids[i]);
        if (amps && !isfinite(amps[i]))
            return geo_err_set(err, -EINVAL, "%s: not a finite number",
                               what);
        if (f->nodes[ids[i]].depth > depth)
            depth = f->nodes[ids[i]].depth;
    }
    if ((uint64_t)f->nkids + n > UINT32_MAX / 2)
        return geo_err_set(err, -ERANGE, "%s: too many shapes", what);
    if (geo_grow((void **)&f->kids, &f->cap_kids, f->nkids + n,
             sizeof *f->kids) < 0)
        return geo_err_set(err, -ENOMEM, "out of memory");
    /* amps always has kids' capacity */
    double *na = realloc(f->amps, (size_t)f->cap_kids * sizeof *na);
    if (!na)
        return geo_err_set(err, -ENOMEM, "out of memory");
    f->amps = na;
    int64_t id = add_node(f, kind, depth + 1, err);
    if (id < 0)
        return id;
    node *nd = &f->nodes[id];
    nd->kid = f->nkids;
    nd->nkids = n;
    for (uint32_t i = 0; i < n; i++) {
        f->kids[f->nkids + i] = ids[i];
        f->amps[f->nkids + i] = amps ? amps[i] : 0.0;
    }
    f->nkids += n;
    return id;
}

int64_t geo_frep_perturbed(geo_frep *f, uint32_t base, uint32_t n,
                           const uint32_t *terms, const double *amps,
                           geo_err *err)
{
    if (n > GEO_FREP_MAX_NODES)
        return geo_err_set(err, -ERANGE, "perturbed: too many terms");
    uint32_t *ids = malloc(((size_t)n + 1) * sizeof *ids);
    double *am = malloc(((size_t)n + 1) * sizeof *am);
    if (!ids || !am) {
        free(ids), free(am);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    ids[0] = base;
    am[0] = 0.0;
    for (uint32_t i = 0; i < n; i++) {
        ids[i + 1] = terms[i];
        am[i + 1] = amps[i];
    }
    int64_t id = add_combo(f, NODE_PERTURBED, n + 1, ids, am, "perturbed",
                           err);
    free(ids), free(am);
    return id;
}

int64_t geo_frep_union(geo_frep *f, uint32_t n, const uint32_t *shapes,
                       geo_err *err)
{
    return add_combo(f, NODE_UNION, n, shapes, NULL, "union", err);
}

int64_t geo_frep_intersection(geo_frep *f, uint32_t n, const uint32_t *shapes,
                              geo_err *err)
{
    return add_combo(f, NODE_INTERSECTION, n, shapes, NULL, "intersection",
                     err);
}

int64_t geo_frep_difference(geo_frep *f, uint32_t a, uint32_t b,
                            geo_err *err)
{
    uint32_t ids[2] = {a, b};
    return add_combo(f, NODE_DIFFERENCE, 2, ids, NULL, "difference", err);
}

/* ---- compilation ---- */

typedef struct emitter {
    geo_frep_op *ops;
    uint32_t n;
    size_t cap;
} emitter;

static int emit(emitter *e, uint8_t code, uint32_t arg, double amp,
                uint32_t start)
{
    if (e->n >= GEO_FREP_MAX_OPS)
        return -ERANGE;
    if (geo_grow((void **)&e->ops, &e->cap, e->n + 1, sizeof *e->ops) < 0)
        return -ENOMEM;
    e->ops[e->n] = (geo_frep_op){code, arg, start == UINT32_MAX ? e->n : start,
                                 amp};
    e->n++;
    return 0;
}

/* Emits node id; returns 0 or a negative errno. Recursion depth is
 * bounded by GEO_FREP_MAX_DEPTH. */
static int compile(const geo_frep *f, uint32_t id, emitter *e)
{
    const node *nd = &f->nodes[id];
    uint32_t begin = e->n;
    int rc;
    if (nd->kind == NODE_PRIM)
        return emit(e, GEO_FREP_OP_PRIM, nd->prim, 0.0, UINT32_MAX);
    const uint32_t *k = f->kids + nd->kid;
    const double *amp = f->amps + nd->kid;
    if ((rc = compile(f, k[0], e)) < 0)
        return rc;
    for (uint32_t i = 1; i < nd->nkids; i++) {
        if ((rc = compile(f, k[i], e)) < 0)
            return rc;
        switch (nd->kind) {
        case NODE_PERTURBED:
            rc = emit(e, GEO_FREP_OP_ADDR, 0, amp[i], begin);
            break;
        case NODE_UNION:
            rc = emit(e, GEO_FREP_OP_MAX, 0, 0.0, begin);
            break;
        case NODE_INTERSECTION:
            rc = emit(e, GEO_FREP_OP_MIN, 0, 0.0, begin);
            break;
        default: /* difference: min(a, −b) */
            rc = emit(e, GEO_FREP_OP_NEG, 0, 0.0, e->ops[e->n - 1].start);
            if (rc == 0)
                rc = emit(e, GEO_FREP_OP_MIN, 0, 0.0, begin);
            break;
        }
        if (rc < 0)
            return rc;
    }
    return 0;
}

int geo_frep_finish(geo_frep *f, uint32_t root, const double lo[3],
                    const double hi[3], geo_err *err)
{
    if (root >= f->nnodes)
        return geo_err_set(err, -EINVAL, "shape %u does not exist", root);
    if (!finite3(lo) || !finite3(hi))
        return geo_err_set(err, -EINVAL, "bounds: not a finite number");
    for (int i = 0; i < 3; i++)
        if (!(lo[i] < hi[i]))
            return geo_err_set(err, -EINVAL,
                               "bounds: lower corner must be below the upper "
                               "one on every axis");
    /* A cross term's interval is a product of two axes' intervals, and
     * far from where the quadric is centred those are wide and cancel:
     * a rotated ellipsoid given as a quadric about the origin but lying
     * at (47, −39, −24) was never pruned (25 million evaluations at
     * Q_LEV 8, ten times the blob's at 9). Such quadrics are re-centred
     * on the box, F(m + d) expanded exactly in d; spheres, ellipsoids and
     * quadrics without cross terms are bounded exactly per axis wherever
     * they are centred and are left alone. */
    double m[3];
    for (int i = 0; i < 3; i++)
        m[i] = 0.5 * (lo[i] + hi[i]);
    for (uint32_t k = 0; k < f->nprims; k++) {
        prim *q = &f->prims[k];
        if (q->b[0] == 0 && q->b[1] == 0 && q->b[2] == 0)
            continue;
        double d[3] = {m[0] - q->c[0], m[1] - q->c[1], m[2] - q->c[2]};
        double g[3] = {
            2 * q->a[0] * d[0] + q->b[0] * d[1] + q->b[2] * d[2] + q->g[0],
            2 * q->a[1] * d[1] + q->b[0] * d[0] + q->b[1] * d[2] + q->g[1],
            2 * q->a[2] * d[2] + q->b[1] * d[1] + q->b[2] * d[0] + q->g[2]};
        q->k += q->a[0] * d[0] * d[0] + q->a[1] * d[1] * d[1] +
                q->a[2] * d[2] * d[2] + q->b[0] * d[0] * d[1] +
                q->b[1] * d[1] * d[2] + q->b[2] * d[0] * d[2] +
                q->g[0] * d[0] + q->g[1] * d[1] + q->g[2] * d[2];
        memcpy(q->g, g, sizeof g);
        memcpy(q->c, m, sizeof m);
    }
    emitter e = {0};
    int rc = compile(f, root, &e);
    if (rc < 0) {
        free(e.ops);
        if (rc == -ERANGE)
            return geo_err_set(err, rc, "program longer than %u operations",
                               GEO_FREP_MAX_OPS);
        return geo_err_set(err, rc, "out of memory");
    }
    /* pieces: subtrees without min/max, NEG wrappers looked through (the
     * zero set is the same), whose parent is a min/max or a NEG */
    uint8_t *has = malloc((size_t)e.n + 1);
    uint32_t *parent = malloc(((size_t)e.n + 1) * sizeof *parent);
    uint32_t *pieces = malloc(((size_t)e.n + 1) * sizeof *pieces);
    if (!has || !parent || !pieces) {
        free(has), free(parent), free(pieces), free(e.ops);
        return geo_err_set(err, -ENOMEM, "out of memory");
    }
    for (uint32_t i = 0; i < e.n; i++) {
        const geo_frep_op *o = &e.ops[i];
        parent[i] = UINT32_MAX;
        if (o->code == GEO_FREP_OP_PRIM) {
            has[i] = 0;
        } else if (o->code == GEO_FREP_OP_NEG) {
            has[i] = has[i - 1];
            parent[i - 1] = i;
        } else {
            uint32_t b = i - 1, a = e.ops[b].start - 1;
            has[i] = has[a] || has[b] || o->code == GEO_FREP_OP_MIN ||
                     o->code == GEO_FREP_OP_MAX;
            parent[a] = parent[b] = i;
        }
    }
    uint32_t np = 0;
    for (uint32_t i = 0; i < e.n; i++) {
        if (has[i] || e.ops[i].code == GEO_FREP_OP_NEG)
            continue;
        uint32_t up = parent[i];
        if (up == UINT32_MAX || has[up] || e.ops[up].code == GEO_FREP_OP_NEG)
            pieces[np++] = i;
    }
    free(has), free(parent);
    free(f->ops);
    free(f->pieces);
    f->ops = e.ops;
    f->nops = e.n;
    f->pieces = pieces;
    f->npieces = np;
    memcpy(f->lo, lo, sizeof f->lo);
    memcpy(f->hi, hi, sizeof f->hi);
    return 0;
}

const geo_frep_op *geo_frep_program(const geo_frep *f, uint32_t *ret_n)
{
    *ret_n = f->nops;
    return f->ops;
}

void geo_frep_bounds(const geo_frep *f, double ret_lo[3], double ret_hi[3])
{
    memcpy(ret_lo, f->lo, sizeof f->lo);
    memcpy(ret_hi, f->hi, sizeof f->hi);
}

/* ---- point evaluation ---- */

static inline double prim_value(const prim *q, const double p[3])
{
    double dx = p[0] - q->c[0], dy = p[1] - q->c[1], dz = p[2] - q->c[2];
    return q->k + dx * (q->a[0] * dx + q->g[0]) +
           dy * (q->a[1] * dy + q->g[1]) + dz * (q->a[2] * dz + q->g[2]) +
           q->b[0] * dx * dy + q->b[1] * dy * dz + q->b[2] * dx * dz;
}

static inline double prim_grad(const prim *q, const double p[3], double g[3])
{
    double dx = p[0] - q->c[0], dy = p[1] - q->c[1], dz = p[2] - q->c[2];
    g[0] = 2 * q->a[0] * dx + q->b[0] * dy + q->b[2] * dz + q->g[0];
    g[1] = 2 * q->a[1] * dy + q->b[0] * dx + q->b[1] * dz + q->g[1];
    g[2] = 2 * q->a[2] * dz + q->b[1] * dy + q->b[2] * dx + q->g[2];
    return prim_value(q, p);
}

double geo_frep_run(const geo_frep *f, const geo_frep_op *ops, uint32_t n,
                    const double p[3])
{
    double st[GEO_FREP_MAX_STACK];
    int sp = -1;
    for (uint32_t i = 0; i < n; i++) {
        const geo_frep_op *o = &ops[i];
        switch (o->code) {
        case GEO_FREP_OP_PRIM:
            st[++sp] = prim_value(&f->prims[o->arg], p);
            break;
        case GEO_FREP_OP_ADDR: {
            double q = st[sp--];
            if (q > 0)
                st[sp] += o->amp * q * q * q;
            break;
        }
        case GEO_FREP_OP_MAX:
            sp--;
            if (st[sp + 1] > st[sp])
                st[sp] = st[sp + 1];
            break;
        case GEO_FREP_OP_MIN:
            sp--;
            if (st[sp + 1] < st[sp])
                st[sp] = st[sp + 1];
            break;
        default:
            st[sp] = -st[sp];
            break;
        }
    }
    return st[0];
}

double geo_frep_run_piece(const geo_frep *f, const geo_frep_op *ops,
                          uint32_t n, const double p[3], double ret_grad[3],
                          uint32_t *ret_piece)
{
    double st[GEO_FREP_MAX_STACK][4];
    uint32_t pc[GEO_FREP_MAX_STACK];
    int sp = -1;
    for (uint32_t i = 0; i < n; i++) {
        const geo_frep_op *o = &ops[i];
        switch (o->code) {
        case GEO_FREP_OP_PRIM:
            sp++;
            st[sp][3] = prim_grad(&f->prims[o->arg], p, st[sp]);
            pc[sp] = i;
            break;
        case GEO_FREP_OP_ADDR: {
            double *q = st[sp--];
            if (q[3] > 0) {
                double q2 = q[3] * q[3], s = 3.0 * o->amp * q2;
                st[sp][3] += o->amp * q2 * q[3];
                for (int k = 0; k < 3; k++)
                    st[sp][k] += s * q[k];
            }
            pc[sp] = i;
            break;
        }
        case GEO_FREP_OP_MAX:
        case GEO_FREP_OP_MIN: {
            sp--;
            bool take = o->code == GEO_FREP_OP_MAX ? st[sp + 1][3] > st[sp][3]
                                                   : st[sp + 1][3] < st[sp][3];
            if (take) {
                memcpy(st[sp], st[sp + 1], sizeof st[sp]);
                pc[sp] = pc[sp + 1];
            }
            break;
        }
        default: /* the zero set, hence the piece, is unchanged */
            for (int k = 0; k < 4; k++)
                st[sp][k] = -st[sp][k];
            break;
        }
    }
    if (ret_grad)
        memcpy(ret_grad, st[0], 3 * sizeof(double));
    if (ret_piece)
        *ret_piece = pc[0];
    return st[0][3];
}

double geo_frep_run_grad(const geo_frep *f, const geo_frep_op *ops,
                         uint32_t n, const double p[3], double ret_grad[3])
{
    return geo_frep_run_piece(f, ops, n, p, ret_grad, NULL);
}

double geo_frep_eval(const geo_frep *f, const double p[3])
{
    return geo_frep_run(f, f->ops, f->nops, p);
}

double geo_frep_eval_grad(const geo_frep *f, const double p[3],
                          double ret_grad[3])
{
    return geo_frep_run_piece(f, f->ops, f->nops, p, ret_grad, NULL);
}

/* ---- intervals ---- */

/* Exact range of a·d² + g·d for d in [lo, hi]. */
static void quad1(double a, double g, double lo, double hi, double r[2])
{
    double flo = lo * (a * lo + g), fhi = hi * (a * hi + g);
    r[0] = flo < fhi ? flo : fhi;
    r[1] = flo < fhi ? fhi : flo;
    if (a != 0) {
        double v = -g / (2 * a);
        if (v > lo && v < hi) {
            double fv = v * (a * v + g);
            if (fv < r[0])
                r[0] = fv;
            if (fv > r[1])
                r[1] = fv;
        }
    }
}

static void mul(double alo, double ahi, double blo, double bhi, double r[2])
{
    double p1 = alo * blo, p2 = alo * bhi, p3 = ahi * blo, p4 = ahi * bhi;
    r[0] = fmin(fmin(p1, p2), fmin(p3, p4));
    r[1] = fmax(fmax(p1, p2), fmax(p3, p4));
}

static void prim_range(const prim *q, const double lo[3], const double hi[3],
                       double r[2])
{
    double dl[3], dh[3], t[2];
    r[0] = r[1] = q->k;
    for (int i = 0; i < 3; i++) {
        dl[i] = lo[i] - q->c[i];
        dh[i] = hi[i] - q->c[i];
        quad1(q->a[i], q->g[i], dl[i], dh[i], t);
        r[0] += t[0];
        r[1] += t[1];
    }
    static const int ax[3][2] = {{0, 1}, {1, 2}, {0, 2}};
    for (int k = 0; k < 3; k++) {
        if (q->b[k] == 0)
            continue;
        int u = ax[k][0], v = ax[k][1];
        mul(dl[u], dh[u], dl[v], dh[v], t);
        mul(q->b[k], q->b[k], t[0], t[1], t);
        r[0] += t[0];
        r[1] += t[1];
    }
}

static inline double cube_pos(double q)
{
    return q > 0 ? q * q * q : 0.0;
}

/* Fills lo_out[i], hi_out[i] with the range of instruction i's value. */
static void run_interval(const geo_frep *f, const geo_frep_op *ops,
                         uint32_t n, const double lo[3], const double hi[3],
                         double *rlo, double *rhi)
{
    for (uint32_t i = 0; i < n; i++) {
        const geo_frep_op *o = &ops[i];
        double r[2];
        if (o->code == GEO_FREP_OP_PRIM) {
            prim_range(&f->prims[o->arg], lo, hi, r);
        } else if (o->code == GEO_FREP_OP_NEG) {
            r[0] = -rhi[i - 1];
            r[1] = -rlo[i - 1];
        } else {
            uint32_t b = i - 1, a = ops[b].start - 1;
            if (o->code == GEO_FREP_OP_ADDR) {
                double t0 = o->amp * cube_pos(rlo[b]);
                double t1 = o->amp * cube_pos(rhi[b]);
                r[0] = rlo[a] + (t0 < t1 ? t0 : t1);
                r[1] = rhi[a] + (t0 < t1 ? t1 : t0);
            } else if (o->code == GEO_FREP_OP_MAX) {
                r[0] = fmax(rlo[a], rlo[b]);
                r[1] = fmax(rhi[a], rhi[b]);
            } else {
                r[0] = fmin(rlo[a], rlo[b]);
                r[1] = fmin(rhi[a], rhi[b]);
            }
        }
        rlo[i] = r[0];
        rhi[i] = r[1];
    }
}

typedef struct pruner {
    const geo_frep_op *in;
    const double *lo, *hi;
    geo_frep_op *out;
    uint32_t n;
} pruner;

/* Copies the pruned subtree rooted at instruction i; returns the output
 * index where it begins. Recursion depth ≤ GEO_FREP_MAX_DEPTH + 1. */
static uint32_t prune(pruner *pr, uint32_t i)
{
    const geo_frep_op *o = &pr->in[i];
    uint32_t begin = pr->n;
    if (o->code == GEO_FREP_OP_PRIM) {
        pr->out[pr->n] = *o;
        pr->out[pr->n].start = pr->n;
        pr->n++;
        return begin;
    }
    if (o->code == GEO_FREP_OP_NEG) {
        prune(pr, i - 1);
    } else {
        uint32_t b = i - 1, a = pr->in[b].start - 1;
        switch (o->code) {
        case GEO_FREP_OP_ADDR:
            /* R(q) is identically 0 where q < 0 */
            if (pr->hi[b] < 0)
                return prune(pr, a);
            break;
        case GEO_FREP_OP_MAX:
            if (pr->lo[a] >= pr->hi[b])
                return prune(pr, a);
            if (pr->lo[b] >= pr->hi[a])
                return prune(pr, b);
            break;
        default:
            if (pr->hi[a] <= pr->lo[b])
                return prune(pr, a);
            if (pr->hi[b] <= pr->lo[a])
                return prune(pr, b);
            break;
        }
        prune(pr, a);
        prune(pr, b);
    }
    pr->out[pr->n] = *o;
    pr->out[pr->n].start = begin;
    pr->n++;
    return begin;
}

uint32_t geo_frep_specialize(const geo_frep *f, const geo_frep_op *ops,
                             uint32_t n, const double lo[3],
                             const double hi[3], double ret_range[2],
                             geo_frep_op *ret_ops, double *scratch)
{
    double *rlo = scratch, *rhi = scratch + n;
    run_interval(f, ops, n, lo, hi, rlo, rhi);
    ret_range[0] = rlo[n - 1];
    ret_range[1] = rhi[n - 1];
    if (!ret_ops)
        return 0;
    pruner pr = {ops, rlo, rhi, ret_ops, 0};
    prune(&pr, n - 1);
    return pr.n;
}

double geo_frep_project(const geo_frep *f, double p[3], double tol,
                        double max_step)
{
    /* |∇F| scaled (geo_vlen_scaled): its square overflowed for a
     * perturbation of amplitude 1e308, so a point half a voxel off the
     * surface measured 0 and was kept */
    double g[3], v = geo_frep_eval_grad(f, p, g);
    double gl = geo_vlen_scaled(g);
    if (!(gl > 0) || !isfinite(gl))
        return INFINITY;
    double dev = fabs(v) / gl;
    for (int it = 0; it < 8 && dev > tol; it++) {
        double q[3], s = dev;
        if (!(s <= max_step))
            break;
        s = v / gl;
        for (int k = 0; k < 3; k++)
            q[k] = p[k] - s * (g[k] / gl);
        double g2[3], v2 = geo_frep_eval_grad(f, q, g2);
        double gl2 = geo_vlen_scaled(g2);
        if (!(gl2 > 0) || !isfinite(gl2) || !(fabs(v2) < fabs(v)))
            break;
        memcpy(p, q, sizeof q);
        memcpy(g, g2, sizeof g);
        v = v2;
        gl = gl2;
        dev = fabs(v) / gl;
    }
    return dev;
}

uint32_t geo_frep_pieces_at(const geo_frep *f, const double p[3], double tol,
                            uint32_t *ret, uint32_t cap)
{
    uint32_t n = 0;
    for (uint32_t k = 0; k < f->npieces; k++) {
        uint32_t r = f->pieces[k], s = f->ops[r].start;
        double g[3], v = geo_frep_run_grad(f, f->ops + s, r - s + 1, p, g);
        double gl = geo_vlen_scaled(g);
        if (fabs(v) <= tol * gl) {
            if (n < cap)
                ret[n] = r;
            n++;
        }
    }
    return n;
}

bool geo_frep_project_pieces(const geo_frep *f, const uint32_t *pieces,
                             uint32_t n, double p[3], double tol,
                             double max_step)
{
    if (n < 1 || n > 3)
        return false;
    for (uint32_t i = 0; i < n; i++)
        if (pieces[i] >= f->nops)
            return false;
    double x[3] = {p[0], p[1], p[2]};
    bool done = false;
    for (int it = 0; it < 16 && !done; it++) {
        double g[3][3], v[3], G[3][3];
        done = true;
        for (uint32_t i = 0; i < n; i++) {
            uint32_t r = pieces[i], s = f->ops[r].start;
            v[i] = geo_frep_run_grad(f, f->ops + s, r - s + 1, x, g[i]);
            double gl = geo_vlen_scaled(g[i]);
            if (!(gl > 0) || !isfinite(gl) || !isfinite(v[i]))
                return false;
            done &= fabs(v[i]) <= tol * gl;
            /* each piece's equation divided by its |∇|: the same
             * linearisation, with a Gram matrix that cannot overflow */
            v[i] /= gl;
            for (int k = 0; k < 3; k++)
                g[i][k] /= gl;
        }
        if (done)
            break;
        /* Gram matrix G = J·Jᵀ; the least-norm step is Jᵀ·G⁻¹·v */
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t j = 0; j < n; j++)
                G[i][j] = g[i][0] * g[j][0] + g[i][1] * g[j][1] +
                          g[i][2] * g[j][2];
        double lam[3];
        if (n == 1) {
            lam[0] = v[0] / G[0][0];
        } else if (n == 2) {
            double det = G[0][0] * G[1][1] - G[0][1] * G[1][0];
            if (!(det > 1e-6 * G[0][0] * G[1][1]))
                return false;
            lam[0] = (G[1][1] * v[0] - G[0][1] * v[1]) / det;
            lam[1] = (G[0][0] * v[1] - G[1][0] * v[0]) / det;
        } else {
            double c0 = G[1][1] * G[2][2] - G[1][2] * G[2][1];
            double c1 = G[1][2] * G[2][0] - G[1][0] * G[2][2];
            double c2 = G[1][0] * G[2][1] - G[1][1] * G[2][0];
            double det = G[0][0] * c0 + G[0][1] * c1 + G[0][2] * c2;
            if (!(det > 1e-6 * G[0][0] * G[1][1] * G[2][2]))
                return false;
            double inv[3][3] = {
                {c0, G[0][2] * G[2][1] - G[0][1] * G[2][2],
                 G[0][1] * G[1][2] - G[0][2] * G[1][1]},
                {c1, G[0][0] * G[2][2] - G[0][2] * G[2][0],
                 G[0][2] * G[1][0] - G[0][0] * G[1][2]},
                {c2, G[0][1] * G[2][0] - G[0][0] * G[2][1],
                 G[0][0] * G[1][1] - G[0][1] * G[1][0]}};
            for (int i = 0; i < 3; i++)
                lam[i] = (inv[i][0] * v[0] + inv[i][1] * v[1] +
                          inv[i][2] * v[2]) / det;
        }
        for (uint32_t i = 0; i < n; i++)
            for (int k = 0; k < 3; k++)
                x[k] -= lam[i] * g[i][k];
    }
    if (!done)
        return false;
    double dx = x[0] - p[0], dy = x[1] - p[1], dz = x[2] - p[2];
    if (!(dx * dx + dy * dy + dz * dz <= max_step * max_step))
        return false;
    double g[3], v = geo_frep_eval_grad(f, x, g);
    double gl = geo_vlen_scaled(g);
    if (!(gl > 0) || !(fabs(v) <= 1e3 * tol * gl))
        return false;
    memcpy(p, x, sizeof x);
    return true;
}
