/* frep_grid.c — quadtree + binary ray subdivision over an F-rep object,
 * then the crossing points. Every recursion step specialises the program
 * to its box (lib/frep/frep.h), so deep in the tree only the few perturbations
 * and half-spaces that matter there are evaluated. */
#include "frep_grid.h"

#include "grow.h"

#include <errno.h>
#include <math.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* Blocks of at most this many samples are decided sample by sample. */
enum { RAY_LEAF = 4, CHUNK_LEVEL = 4, ROOT_BLOCK = 2048 };

/* A stack of specialised programs, addressed by offset (the buffer may
 * move when it grows). */
typedef struct arena {
    geo_frep_op *ops;
    size_t cap;
} arena;

static int arena_reserve(arena *a, size_t need)
{
    return geo_grow((void **)&a->ops, &a->cap, need, sizeof *a->ops);
}

/* What one chunk of the quadtree found. */
typedef struct chunk_out {
    uint32_t *cols;    /* column id per run */
    int32_t (*runs)[2];
    uint32_t n, cap;
    uint64_t nevals, nboxes;
    int rc;            /* 0, -ENOMEM, -ECANCELED or -EINVAL (boundary) */
    uint32_t bad_col;  /* with -EINVAL: the column that reached the cube */
    int32_t bad_k;
} chunk_out;

typedef struct sampler {
    const geo_frep *f;
    const geo_frep_grid *g;
    const geo_frep_op *prog;
    uint32_t nprog;
    const geo_ctx *ctx;
    uint32_t cells_per_side; /* chunk cells per side */
    uint32_t cell_w;         /* columns per chunk cell side */
    chunk_out *out;
} sampler;

typedef struct walker {
    const sampler *s;
    chunk_out *o;
    arena ar;
    double *scratch;
    uint32_t col, i, j;
    int32_t last_s, last_e; /* the open run of the current column */
    bool open;
} walker;

static int push_run(walker *w)
{
    chunk_out *o = w->o;
    if (o->n == o->cap) {
        uint32_t nc = o->cap ? o->cap * 2 : 256;
        uint32_t *c = realloc(o->cols, nc * sizeof *c);
        if (!c)
            return -ENOMEM;
        o->cols = c;
        int32_t(*r)[2] = realloc(o->runs, nc * sizeof *r);
        if (!r)
            return -ENOMEM;
        o->runs = r;
        o->cap = nc;
    }
    o->cols[o->n] = w->col;
    o->runs[o->n][0] = w->last_s;
    o->runs[o->n][1] = w->last_e;
    o->n++;
    return 0;
}

/* Records inside samples a..b of the current column (blocks arrive in
 * increasing order), merging with the open run when adjacent. */
static int emit_block(walker *w, int32_t a, int32_t b)
{
    if (w->open && w->last_e == a - 1) {
        w->last_e = b;
        return 0;
    }
    if (w->open) {
        int rc = push_run(w);
        if (rc < 0)
            return rc;
    }
    w->open = true;
    w->last_s = a;
    w->last_e = b;
    return 0;
}

static int flush_run(walker *w)
{
    if (!w->open)
        return 0;
    w->open = false;
    return push_run(w);
}

/* Decides samples ka..kb of the current column with the program at
 * offset po (length pn); range is its enclosure over that block. */
static int ray(walker *w, size_t po, uint32_t pn, int32_t ka, int32_t kb,
               const double range[2])
{
    const sampler *s = w->s;
    const geo_frep_grid *g = s->g;
    if (range[1] < 0)
        return 0;
    if (range[0] >= 0)
        return emit_block(w, ka, kb);
    double p[3] = {geo_frep_grid_x(g, w->i), geo_frep_grid_y(g, w->j), 0};
    if (kb - ka + 1 <= RAY_LEAF) {
        for (int32_t k = ka; k <= kb; k++) {
            p[2] = geo_frep_grid_z(g, k);
            w->o->nevals++;
            if (geo_frep_run(s->f, w->ar.ops + po, pn, p) >= 0) {
                int rc = emit_block(w, k, k);
                if (rc < 0)
                    return rc;
            }
        }
        return 0;
    }
    int32_t mid = ka + (kb - ka) / 2;
    int32_t lo_k[2] = {ka, mid + 1}, hi_k[2] = {mid, kb};
    size_t co = po + pn;
    if (arena_reserve(&w->ar, co + pn) < 0)
        return -ENOMEM;
    for (int h = 0; h < 2; h++) {
        double lo[3] = {p[0], p[1], geo_frep_grid_z(g, lo_k[h])};
        double hi[3] = {p[0], p[1], geo_frep_grid_z(g, hi_k[h])};
        double r[2];
        w->o->nboxes++;
        uint32_t cn = geo_frep_specialize(s->f, w->ar.ops + po, pn, lo, hi, r,
                                          w->ar.ops + co, w->scratch);
        int rc = ray(w, co, cn, lo_k[h], hi_k[h], r);
        if (rc < 0)
            return rc;
    }
    return 0;
}

/* The quadtree below the cell of columns [i0, i0+wd) × [j0, j0+wd). */
static int cell(walker *w, size_t po, uint32_t pn, uint32_t i0, uint32_t j0,
                uint32_t wd)
{
    const sampler *s = w->s;
    const geo_frep_grid *g = s->g;
    double lo[3] = {geo_frep_grid_x(g, i0), geo_frep_grid_y(g, j0),
                    geo_frep_grid_z(g, 0)};
    double hi[3] = {geo_frep_grid_x(g, i0 + wd - 1),
                    geo_frep_grid_y(g, j0 + wd - 1),
                    geo_frep_grid_z(g, g->m - 1)};
    size_t co = po + pn;
    if (arena_reserve(&w->ar, co + pn) < 0)
        return -ENOMEM;
    double r[2];
    w->o->nboxes++;
    uint32_t cn = geo_frep_specialize(s->f, w->ar.ops + po, pn, lo, hi, r,
                                      w->ar.ops + co, w->scratch);
    if (r[1] < 0)
        return 0;
    if (wd == 1) {
        w->i = i0;
        w->j = j0;
        w->col = j0 * g->n + i0;
        w->open = false;
        uint32_t before = w->o->n;
        int rc = ray(w, co, cn, 0, (int32_t)g->m - 1, r);
        if (rc == 0)
            rc = flush_run(w);
        if (rc < 0)
            return rc;
        for (uint32_t q = before; q < w->o->n; q++) {
            bool edge_col = i0 == 0 || j0 == 0 || i0 == g->n - 1 ||
                            j0 == g->n - 1;
            int32_t *rr = w->o->runs[q];
            if (edge_col || rr[0] == 0 || rr[1] == (int32_t)g->m - 1) {
                w->o->bad_col = w->col;
                w->o->bad_k = rr[0] == 0 ? 0 : rr[1];
                return -EINVAL;
            }
        }
        return 0;
    }
    uint32_t hw = wd / 2;
    for (uint32_t q = 0; q < 4; q++) {
        int rc = cell(w, co, cn, i0 + (q & 1) * hw, j0 + (q >> 1) * hw, hw);
        if (rc < 0)
            return rc;
    }
    return 0;
}

typedef struct batch {
    const sampler *s;
    size_t base; /* chunk index of the batch's first task */
} batch;

static void chunk_task(void *arg, size_t k)
{
    const batch *bt = arg;
    const sampler *s = bt->s;
    size_t idx = bt->base + k;
    chunk_out *o = &s->out[idx];
    if (geo_ctx_canceled(s->ctx)) {
        o->rc = -ECANCELED;
        return;
    }
    walker w = {.s = s, .o = o};
    w.scratch = malloc(2 * (size_t)s->nprog * sizeof *w.scratch);
    if (!w.scratch || arena_reserve(&w.ar, 4 * (size_t)s->nprog) < 0) {
        o->rc = -ENOMEM;
    } else {
        memcpy(w.ar.ops, s->prog, s->nprog * sizeof *s->prog);
        uint32_t ci = (uint32_t)(idx % s->cells_per_side);
        uint32_t cj = (uint32_t)(idx / s->cells_per_side);
        o->rc = cell(&w, 0, s->nprog, ci * s->cell_w, cj * s->cell_w,
                     s->cell_w);
    }
    free(w.scratch);
    free(w.ar.ops);
}

/* ---- crossing points ---- */

typedef struct rooter {
    const geo_frep *f;
    geo_frep_grid *g;
    const geo_frep_op *prog;
    uint32_t nprog;
    const geo_ctx *ctx;
    uint64_t *nevals; /* per block */
    int *rc;          /* per block */
} rooter;

/* The crossing of the column's ray between z0 (F = f0) and z1 (F = f1),
 * f0 and f1 of opposite sides (f < 0 outside, ≥ 0 inside). Illinois
 * regula falsi, with a bisection whenever two steps have not halved the
 * bracket, so the bracket shrinks to tol whatever F looks like; the
 * answer is the end of the final bracket with the smaller |F|. (Taking
 * the smallest |F| seen anywhere, and no bisection, failed where F jumps:
 * a perturbation of amplitude −1e308 makes F drop from 0.06 to −1e300
 * across a crease, regula falsi crept by 1e-3 of the bracket per step,
 * and the sample itself, a voxel from the surface, was returned.) */
static double solve(const geo_frep *f, const geo_frep_op *ops, uint32_t n,
                    double x, double y, double z0, double f0, double z1,
                    double f1, double tol, uint64_t *nevals)
{
    int side0 = f0 >= 0, last = -1;
    double w0 = f0, w1 = f1; /* Illinois weights of the ends */
    double mark = fabs(z1 - z0);
    bool bisect = false;
    for (int it = 0; it < 200 && fabs(z1 - z0) > tol; it++) {
        double z = (!bisect && w1 != w0) ? z0 + (z1 - z0) * (w0 / (w0 - w1))
                                          : 0.5 * (z0 + z1);
        /* keep the step strictly inside the bracket */
        double lo = fmin(z0, z1), hi = fmax(z0, z1), w = hi - lo;
        if (!(z > lo + 1e-3 * w && z < hi - 1e-3 * w))
            z = 0.5 * (z0 + z1);
        double p[3] = {x, y, z};
        double fz = geo_frep_run(f, ops, n, p);
        (*nevals)++;
        if (fz == 0)
            return z;
        if ((fz >= 0) == side0) {
            z0 = z;
            f0 = w0 = fz;
            if (last == 0)
                w1 *= 0.5; /* Illinois: the stale end loses weight */
            last = 0;
        } else {
            z1 = z;
            f1 = w1 = fz;
            if (last == 1)
                w0 *= 0.5;
            last = 1;
        }
        if (it % 2 == 1) {
            bisect = fabs(z1 - z0) > 0.5 * mark;
            mark = fabs(z1 - z0);
        }
    }
    return fabs(f1) < fabs(f0) ? z1 : z0;
}

static void root_task(void *arg, size_t blk)
{
    rooter *rt = arg;
    geo_frep_grid *g = rt->g;
    if (geo_ctx_canceled(rt->ctx)) {
        rt->rc[blk] = -ECANCELED;
        return;
    }
    geo_frep_op *ops = malloc(rt->nprog * sizeof *ops);
    double *scratch = malloc(2 * (size_t)rt->nprog * sizeof *scratch);
    if (!ops || !scratch) {
        free(ops), free(scratch);
        rt->rc[blk] = -ENOMEM;
        return;
    }
    size_t r0 = blk * (size_t)ROOT_BLOCK, r1 = r0 + ROOT_BLOCK;
    if (r1 > g->nruns)
        r1 = g->nruns;
    double tol = 1e-13 * g->side;
    for (size_t r = r0; r < r1; r++) {
        uint32_t col = g->run_col[r];
        double x = geo_frep_grid_x(g, col % g->n);
        double y = geo_frep_grid_y(g, col / g->n);
        for (int end = 0; end < 2; end++) {
            /* entry: samples s−1 (out) and s (in); exit: e (in), e+1 */
            int64_t ka = end == 0 ? (int64_t)g->runs[r][0] - 1 : g->runs[r][1];
            double za = geo_frep_grid_z(g, ka), zb = geo_frep_grid_z(g, ka + 1);
            double lo[3] = {x, y, za}, hi[3] = {x, y, zb}, range[2];
            uint32_t n = geo_frep_specialize(rt->f, rt->prog, rt->nprog, lo, hi,
                                             range, ops, scratch);
            double pa[3] = {x, y, za}, pb[3] = {x, y, zb};
            double fa = geo_frep_run(rt->f, ops, n, pa);
            double fb = geo_frep_run(rt->f, ops, n, pb);
            rt->nevals[blk] += 2;
            double z;
            if ((fa >= 0) == (fb >= 0)) {
                /* the bracket's sides were decided by a bound and point
                 * evaluation disagrees at rounding level: the crossing
                 * sits at the end nearer to F = 0 */
                z = fabs(fa) < fabs(fb) ? za : zb;
            } else {
                z = solve(rt->f, ops, n, x, y, za, fa, zb, fb, tol,
                          &rt->nevals[blk]);
            }
            double *pt = g->pts[2 * r + (size_t)end];
            pt[0] = x;
            pt[1] = y;
            pt[2] = z;
        }
    }
    free(ops), free(scratch);
}

/* The alive runs of column (i + di, j + dj) as [first, end) into
 * g->runs; empty outside the grid (all outside there). */
static void neighbour_runs(const geo_frep_grid *g, uint32_t col, int di,
                           int dj, uint32_t *q0, uint32_t *q1)
{
    uint32_t n = g->n;
    int64_t i = (int64_t)(col % n) + di, j = (int64_t)(col / n) + dj;
    *q0 = *q1 = 0;
    if (i < 0 || j < 0 || i >= (int64_t)n || j >= (int64_t)n)
        return;
    uint32_t c = (uint32_t)j * n + (uint32_t)i;
    *q0 = g->col_start[c];
    *q1 = g->col_start[c + 1];
}

/* Whether a neighbouring column has an inside sample in [a, b]. */
static bool inside_near(const geo_frep_grid *g, const uint8_t *dead,
                        uint32_t col, int di, int dj, int32_t a, int32_t b)
{
    uint32_t q0, q1;
    neighbour_runs(g, col, di, dj, &q0, &q1);
    for (uint32_t q = q0; q < q1 && g->runs[q][0] <= b; q++)
        if (!dead[q] && g->runs[q][1] >= a)
            return true;
    return false;
}

/* Whether a neighbouring column has an outside sample in [a, b]: its
 * alive runs are disjoint and apart, so [a, b] is all inside only when
 * one of them covers it. */
static bool outside_near(const geo_frep_grid *g, const uint8_t *dead,
                         uint32_t col, int di, int dj, int32_t a, int32_t b)
{
    uint32_t q0, q1;
    neighbour_runs(g, col, di, dj, &q0, &q1);
    for (uint32_t q = q0; q < q1 && g->runs[q][0] <= a; q++)
        if (!dead[q] && g->runs[q][1] >= b)
            return false;
    return true;
}

/* Makes the digital object representable by section contours: every
 * block of inside samples and every gap of outside samples between two
 * runs of a column must meet its own kind in a neighbouring column on at
 * least one side along x and on at least one side along y. A part one
 * column thick fails that: its section across that axis is a single
 * column, a contour of two points enclosing no area, and the quads on its
 * two sides are the same triangles facing both ways — a sheet of zero
 * volume (a sphere smaller than a column gave two coplanar quads facing
 * opposite ways, thin walls folded through each other, and a crack one
 * column wide between two nearly touching spheres left a double sheet
 * inside the union). Such a run is removed, such a gap filled (its two
 * runs merged); either way whole crossings disappear and every remaining
 * run still ends at true crossings of F. Parts that thin cannot be
 * resolved at these levels. Sweeps repeat until nothing changes (a change
 * can make a neighbour thin); each change removes a run, so they end.
 * Returns 0 or -ENOMEM. */
static int regularise_runs(geo_frep_grid *g)
{
    uint32_t nr = g->nruns, n = g->n;
    uint8_t *dead = calloc((size_t)nr + 1, 1);
    if (!dead)
        return -ENOMEM;
    uint32_t nchanged = 0;
    for (bool changed = true; changed;) {
        changed = false;
        for (uint32_t r = 0; r < nr; r++) {
            if (dead[r])
                continue;
            uint32_t col = g->run_col[r];
            int32_t a = g->runs[r][0], b = g->runs[r][1];
            if ((!inside_near(g, dead, col, -1, 0, a, b) &&
                 !inside_near(g, dead, col, 1, 0, a, b)) ||
                (!inside_near(g, dead, col, 0, -1, a, b) &&
                 !inside_near(g, dead, col, 0, 1, a, b))) {
                dead[r] = 1;
                changed = true;
                nchanged++;
                continue;
            }
            uint32_t next = r + 1, end = g->col_start[col + 1];
            while (next < end && dead[next])
                next++;
            if (next == end)
                continue;
            a = g->runs[r][1] + 1;
            b = g->runs[next][0] - 1;
            if ((!outside_near(g, dead, col, -1, 0, a, b) &&
                 !outside_near(g, dead, col, 1, 0, a, b)) ||
                (!outside_near(g, dead, col, 0, -1, a, b) &&
                 !outside_near(g, dead, col, 0, 1, a, b))) {
                g->runs[r][1] = g->runs[next][1];
                dead[next] = 1;
                changed = true;
                nchanged++;
                r--; /* the merged run is checked again */
            }
        }
    }
    if (nchanged > 0) {
        uint32_t w = 0, c = 0;
        for (uint32_t r = 0; r < nr; r++) {
            while (c < g->run_col[r])
                g->col_start[++c] = w;
            if (dead[r])
                continue;
            g->runs[w][0] = g->runs[r][0];
            g->runs[w][1] = g->runs[r][1];
            g->run_col[w] = g->run_col[r];
            w++;
        }
        while (c < (size_t)n * n)
            g->col_start[++c] = w;
        g->nruns = w;
        g->nregularised = nchanged;
    }
    free(dead);
    return 0;
}

geo_frep_grid *geo_frep_grid_free(geo_frep_grid *g)
{
    if (g) {
        free(g->col_start);
        free(g->runs);
        free(g->run_col);
        free(g->pts);
        free(g);
    }
    return NULL;
}

int geo_frep_grid_build(const geo_frep *f, uint32_t qlev, uint32_t blev,
                        const geo_ctx *ctx, double p0, double p1,
                        geo_frep_grid **ret, geo_err *err)
{
    if (qlev < 1 || qlev > GEO_FREP_MAX_QLEV)
        return geo_err_set(err, -EINVAL, "quad levels must be in 1..%u",
                           GEO_FREP_MAX_QLEV);
    if (blev < 1 || blev > GEO_FREP_MAX_BLEV)
        return geo_err_set(err, -EINVAL, "binary levels must be in 1..%u",
                           GEO_FREP_MAX_BLEV);
    uint32_t nprog;
    const geo_frep_op *prog = geo_frep_program(f, &nprog);
    if (!prog || nprog == 0)
        return geo_err_set(err, -EINVAL, "the object has no program");
    geo_frep_grid *g = calloc(1, sizeof *g);
    if (!g)
        return geo_err_set(err, -ENOMEM, "out of memory");
    g->qlev = qlev;
    g->blev = blev;
    g->n = 1u << qlev;
    g->m = 1u << blev;
    double lo[3], hi[3];
    geo_frep_bounds(f, lo, hi);
    g->side = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    for (int k = 0; k < 3; k++)
        g->origin[k] = 0.5 * (lo[k] + hi[k]) - 0.5 * g->side;
    g->hx = g->side / g->n;
    g->hz = g->side / g->m;
    /* Every later stage (crossings, centroids, Newton steps, contact
     * checks) needs points a sample apart to be many units in the last
     * place apart: a box far from the origin and small against its
     * distance (a 2 mm box at 1e15 mm) has samples closer together than
     * the doubles there, and refinement then split triangles whose
     * corners round onto each other without end. */
    double mag = 0;
    for (int k = 0; k < 3; k++)
        mag = fmax(mag, fmax(fabs(g->origin[k]),
                             fabs(g->origin[k] + g->side)));
    if (!isfinite(g->side) || !isfinite(mag)) {
        geo_frep_grid_free(g);
        return geo_err_set(err, -EINVAL,
                           "bounds: the box's extent is not a finite number");
    }
    double spacing = fmin(g->hx, g->hz);
    if (spacing < GEO_FREP_MIN_RESOLUTION * mag) {
        geo_frep_grid_free(g);
        return geo_err_set(err, -EINVAL,
                           "bounds: a sample spacing of %g is below the "
                           "resolution of coordinates as large as %g; "
                           "move the object nearer the origin or lower "
                           "the levels",
                           spacing, mag);
    }

    int rc = 0;
    sampler s = {.f = f, .g = g, .prog = prog, .nprog = nprog, .ctx = ctx};
    uint32_t cl = qlev < CHUNK_LEVEL ? qlev : CHUNK_LEVEL;
    s.cells_per_side = 1u << cl;
    s.cell_w = g->n >> cl;
    size_t nchunks = (size_t)s.cells_per_side * s.cells_per_side;
    s.out = calloc(nchunks, sizeof *s.out);
    g->col_start = calloc((size_t)g->n * g->n + 1, sizeof *g->col_start);
    if (!s.out || !g->col_start) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
    /* batches let the calling thread report progress between them */
    enum { BATCHES = 8 };
    double pmid = p0 + 0.7 * (p1 - p0);
    for (size_t b = 0; b < BATCHES; b++) {
        batch bt = {&s, nchunks * b / BATCHES};
        size_t c1 = nchunks * (b + 1) / BATCHES;
        geo_ctx_parallel_for(ctx, c1 - bt.base, chunk_task, &bt);
        if ((rc = geo_ctx_progress(ctx, p0 + (pmid - p0) * (double)(b + 1) /
                                             BATCHES)) < 0) {
            geo_err_set(err, rc, "canceled");
            goto done;
        }
    }
    /* the first failing chunk in chunk order decides the error, so the
     * message does not depend on scheduling */
    uint32_t bad_col = UINT32_MAX;
    int32_t bad_k = 0;
    for (size_t c = 0; c < nchunks; c++) {
        int crc = s.out[c].rc;
        if (crc == -EINVAL) {
            if (s.out[c].bad_col < bad_col) {
                bad_col = s.out[c].bad_col;
                bad_k = s.out[c].bad_k;
            }
        } else if (crc < 0 && rc == 0) {
            rc = crc;
        }
        g->nevals += s.out[c].nevals;
        g->nboxes += s.out[c].nboxes;
    }
    if (rc == -ENOMEM) {
        geo_err_set(err, rc, "out of memory");
        goto done;
    }
    if (rc == -ECANCELED) {
        geo_err_set(err, rc, "canceled");
        goto done;
    }
    if (bad_col != UINT32_MAX) {
        rc = geo_err_set(
            err, -EINVAL,
            "bounds: the object reaches the boundary of the sampling cube "
            "near (%.6g, %.6g, %.6g); enlarge the bounds",
            geo_frep_grid_x(g, bad_col % g->n),
            geo_frep_grid_y(g, bad_col / g->n), geo_frep_grid_z(g, bad_k));
        goto done;
    }
    /* runs into CSR by column id */
    uint64_t total = 0;
    for (size_t c = 0; c < nchunks; c++) {
        for (uint32_t q = 0; q < s.out[c].n; q++)
            g->col_start[s.out[c].cols[q] + 1]++;
        total += s.out[c].n;
    }
    if (total > UINT32_MAX / 4) {
        rc = geo_err_set(err, -ERANGE, "more than %u surface runs",
                         UINT32_MAX / 4);
        goto done;
    }
    g->nruns = (uint32_t)total;
    for (size_t c = 0; c < (size_t)g->n * g->n; c++)
        g->col_start[c + 1] += g->col_start[c];
    g->runs = malloc(((size_t)g->nruns + 1) * sizeof *g->runs);
    g->run_col = malloc(((size_t)g->nruns + 1) * sizeof *g->run_col);
    g->pts = malloc((2 * (size_t)g->nruns + 1) * sizeof *g->pts);
    uint32_t *fill = malloc(((size_t)g->n * g->n + 1) * sizeof *fill);
    if (!g->runs || !g->run_col || !g->pts || !fill) {
        free(fill);
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
    memcpy(fill, g->col_start, (size_t)g->n * g->n * sizeof *fill);
    /* a column's runs come from one chunk, already in increasing z */
    for (size_t c = 0; c < nchunks; c++)
        for (uint32_t q = 0; q < s.out[c].n; q++) {
            uint32_t col = s.out[c].cols[q], r = fill[col]++;
            g->runs[r][0] = s.out[c].runs[q][0];
            g->runs[r][1] = s.out[c].runs[q][1];
            g->run_col[r] = col;
        }
    free(fill);
    if (regularise_runs(g) < 0) {
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }

    size_t nblk = (g->nruns + (size_t)ROOT_BLOCK - 1) / ROOT_BLOCK;
    rooter rt = {.f = f, .g = g, .prog = prog, .nprog = nprog, .ctx = ctx};
    rt.nevals = calloc(nblk + 1, sizeof *rt.nevals);
    rt.rc = calloc(nblk + 1, sizeof *rt.rc);
    if (!rt.nevals || !rt.rc) {
        free(rt.nevals), free(rt.rc);
        rc = geo_err_set(err, -ENOMEM, "out of memory");
        goto done;
    }
    geo_ctx_parallel_for(ctx, nblk, root_task, &rt);
    for (size_t b = 0; b < nblk; b++) {
        g->nevals += rt.nevals[b];
        if (rt.rc[b] < 0 && rc == 0)
            rc = rt.rc[b];
    }
    free(rt.nevals), free(rt.rc);
    if (rc == 0)
        rc = geo_ctx_progress(ctx, p1);
    if (rc < 0)
        geo_err_set(err, rc, rc == -ENOMEM ? "out of memory" : "canceled");
done:
    if (s.out)
        for (size_t c = 0; c < nchunks; c++) {
            free(s.out[c].cols);
            free(s.out[c].runs);
        }
    free(s.out);
    if (rc < 0)
        geo_frep_grid_free(g);
    else
        *ret = g;
    return rc;
}
