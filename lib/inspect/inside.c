/* inside.c — point in polyhedron: gab3, conv3_test, the exact on-facet
 * test, the random-ray parity test with re-shooting, the generalized
 * winding number, and the batch classifier (+x rays over a yz grid).
 *
 * Invariants: every facet is read as the fan (v0, vi, vi+1); a crossing is
 * counted only when all the signs that define it are non-zero, and any
 * zero sign either settles the point as boundary (it lies on the facet)
 * or makes the ray degenerate (a new one is cast). A point in the plane
 * of an exactly planar facet but off it is where the fan's signed cover
 * is zero: that facet contributes nothing to any ray from the point. */
#include "inside.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "classify.h"
#include "predicates.h"
#include "vec.h"

bool geo_gab3_test(const geo_bbox *box, const double q[3])
{
    return !(box->lo[0] <= q[0] && q[0] <= box->hi[0] && box->lo[1] <= q[1] &&
             q[1] <= box->hi[1] && box->lo[2] <= q[2] && q[2] <= box->hi[2]);
}

int geo_conv3_test(const geo_poly *p, const double q[3])
{
    bool all_below = true;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        int s = geo_nf_facet_sign(p, f, q);
        if (s > 0)
            return GEO_LOC_OUTSIDE;
        if (s == 0)
            all_below = false;
    }
    return all_below ? GEO_LOC_INSIDE : GEO_LOC_BOUNDARY;
}

/* ---- exact incidence ---------------------------------------------------- */

static bool collinear3(const double a[3], const double b[3], const double c[3])
{
    return geo_orient2d_proj(a, b, c, 0) == 0 &&
           geo_orient2d_proj(a, b, c, 1) == 0 &&
           geo_orient2d_proj(a, b, c, 2) == 0;
}

static bool between(double a, double b, double x)
{
    return a <= b ? (a <= x && x <= b) : (b <= x && x <= a);
}

/* q on the closed segment [a, b] (a = b: q equals it). */
static bool on_segment(const double a[3], const double b[3], const double q[3])
{
    return between(a[0], b[0], q[0]) && between(a[1], b[1], q[1]) &&
           between(a[2], b[2], q[2]) && collinear3(a, b, q);
}

/* An axis along which triangle a, b, c projects with non-zero area, or −1
 * for a collinear triangle; *ret_orient is that projection's orientation. */
static int proj_axis(const double a[3], const double b[3], const double c[3],
                     int *ret_orient)
{
    double ab[3], ac[3], n[3];
    geo_vsub(b, a, ab);
    geo_vsub(c, a, ac);
    geo_vcross(ab, ac, n);
    int order[3] = {0, 1, 2};
    /* try the float-dominant axis first: its projection is the best
     * conditioned; the exact test decides */
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (fabs(n[order[j]]) > fabs(n[order[i]])) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    for (int i = 0; i < 3; i++) {
        int o = geo_orient2d_proj(a, b, c, order[i]);
        if (o != 0) {
            *ret_orient = o;
            return order[i];
        }
    }
    return -1;
}

/* q (coplanar with a, b, c: the caller checked) in the closed triangle. */
static bool in_closed_triangle(const double a[3], const double b[3],
                               const double c[3], const double q[3])
{
    int o;
    int ax = proj_axis(a, b, c, &o);
    if (ax < 0)
        return on_segment(a, b, q) || on_segment(b, c, q) ||
               on_segment(c, a, q);
    int o1 = geo_orient2d_proj(a, b, q, ax), o2 = geo_orient2d_proj(b, c, q, ax),
        o3 = geo_orient2d_proj(c, a, q, ax);
    return o1 != -o && o2 != -o && o3 != -o;
}

/* Crossing parity of the polygon's projection along axis ax around q's
 * (the caller excluded q on an edge); half-open rule on the v axis. */
static bool in_projected_polygon(const geo_poly *p, uint32_t f, int ax,
                                 const double q[3])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    int vi = (ax + 2) % 3;
    bool in = false;
    for (uint32_t i = 0; i < n; i++) {
        const double *a = p->verts[v[i]], *b = p->verts[v[(i + 1) % n]];
        if ((a[vi] > q[vi]) == (b[vi] > q[vi]))
            continue;
        int s = geo_orient2d_proj(a, b, q, ax);
        if (b[vi] > a[vi] ? s > 0 : s < 0)
            in = !in;
    }
    return in;
}

bool geo_point_on_facet(const geo_poly *p, uint32_t f, const double q[3])
{
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    const double(*P)[3] = (const double(*)[3])p->verts;
    geo_bbox box;
    geo_poly_facet_bbox(p, f, &box);
    if (!geo_bbox_contains(&box, q))
        return false;
    for (uint32_t i = 0; i < n; i++)
        if (on_segment(P[v[i]], P[v[(i + 1) % n]], q))
            return true;
    if (geo_facet_is_planar_exact(p, f)) {
        uint32_t r[3];
        geo_facet_ref(p, f, r);
        if (geo_orient3d(P[r[0]], P[r[1]], P[r[2]], q) != 0)
            return false;
        int o, ax = proj_axis(P[r[0]], P[r[1]], P[r[2]], &o);
        return ax >= 0 && in_projected_polygon(p, f, ax, q);
    }
    for (uint32_t i = 1; i + 1 < n; i++) {
        const double *a = P[v[0]], *b = P[v[i]], *c = P[v[i + 1]];
        if (geo_orient3d(a, b, c, q) == 0 && in_closed_triangle(a, b, c, q))
            return true;
    }
    return false;
}

/* ---- winding number ----------------------------------------------------- */

double geo_winding_number(const geo_poly *p, const double q[3])
{
    double sum = 0;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        double A[3], B[3], C[3], bc[3];
        geo_vsub(p->verts[v[0]], q, A);
        double la = geo_vlen(A);
        for (uint32_t i = 1; i + 1 < n; i++) {
            geo_vsub(p->verts[v[i]], q, B);
            geo_vsub(p->verts[v[i + 1]], q, C);
            double lb = geo_vlen(B), lc = geo_vlen(C);
            geo_vcross(B, C, bc);
            double det = geo_vdot(A, bc);
            double den = la * lb * lc + geo_vdot(A, B) * lc +
                         geo_vdot(A, C) * lb + geo_vdot(B, C) * la;
            sum += 2.0 * atan2(det, den);
        }
    }
    return sum / (4.0 * M_PI);
}

/* ---- the prepared classifier ------------------------------------------- */

/* One fan triangle (v0, vi, vi+1) of a facet in a grid cell: its yz box
 * and largest x, copied next to its facet and i so the scan of a cell
 * reads one contiguous array. */
typedef struct cell_ref {
    double ylo, yhi, zlo, zhi, xmax;
    uint32_t facet, i;
} cell_ref;

struct geo_inside {
    const geo_poly *p;
    geo_bvh *bvh;
    geo_bbox box;     /* facets' box; empty (lo > hi) without facets */
    double center[3]; /* of box */
    double diag;      /* box diagonal */
    /* yz grid of fan triangles: cell (iy, iz) = refs from
     * cell_start[iy·gz + iz] to cell_start[iy·gz + iz + 1] */
    uint32_t gy, gz;
    double y0, z0, sy, sz; /* index = (coordinate − origin) · scale */
    uint32_t *cell_start;  /* gy·gz + 1 */
    cell_ref *refs;
};

const geo_bbox *geo_inside_bbox(const geo_inside *ix)
{
    return &ix->box;
}

geo_inside *geo_inside_free(geo_inside *ix)
{
    if (!ix)
        return NULL;
    geo_bvh_free(ix->bvh);
    free(ix->cell_start);
    free(ix->refs);
    free(ix);
    return NULL;
}

static uint32_t cell_index(double x, double origin, double scale, uint32_t g)
{
    double t = (x - origin) * scale;
    if (!(t > 0))
        return 0;
    if (t >= (double)g)
        return g - 1;
    return (uint32_t)t;
}

/* References per triangle allowed before the grid is made coarser: keeps
 * memory O(corners) when long slivers span many cells. */
enum { GRID_CELLS_PER_TRI = 4, GRID_REFS_PER_TRI = 32, GRID_MAX_SIDE = 4096 };

static void tri_box(const geo_poly *p, uint32_t f, uint32_t i, geo_bbox *ret)
{
    const uint32_t *v = geo_poly_facet(p, f);
    geo_bbox_empty(ret);
    geo_bbox_add(ret, p->verts[v[0]]);
    geo_bbox_add(ret, p->verts[v[i]]);
    geo_bbox_add(ret, p->verts[v[i + 1]]);
}

/* Runs the statement after it for every fan triangle (v0, vi, vi+1) of
 * every facet f. */
#define FOR_EACH_TRI(p, f, i)                                                \
    for (uint32_t f = 0; f < (p)->nfacets; f++)                              \
        for (uint32_t i = 1; i + 1 < geo_poly_facet_size((p), f); i++)

/* The z range of the part of triangle t (projected to yz) inside the
 * slab Y0 ≤ y ≤ Y1: its vertices in the slab and its edges' crossings of
 * the slab's lines. False when the triangle misses the slab. Floating
 * point: callers pad the range (it only prunes). */
static bool slab_zrange(const double *t[3], double Y0, double Y1,
                        double *ret_lo, double *ret_hi)
{
    double lo = INFINITY, hi = -INFINITY;
    for (int e = 0; e < 3; e++) {
        const double *P = t[e], *Q = t[(e + 1) % 3];
        if (Y0 <= P[1] && P[1] <= Y1) {
            lo = fmin(lo, P[2]);
            hi = fmax(hi, P[2]);
        }
        double lines[2] = {Y0, Y1};
        for (int k = 0; k < 2; k++) {
            double Yc = lines[k];
            if (!((P[1] < Yc && Yc < Q[1]) || (Q[1] < Yc && Yc < P[1])))
                continue;
            double z = P[2] + (Yc - P[1]) / (Q[1] - P[1]) * (Q[2] - P[2]);
            z = fmax(fmin(P[2], Q[2]), fmin(fmax(P[2], Q[2]), z));
            lo = fmin(lo, z);
            hi = fmax(hi, z);
        }
    }
    *ret_lo = lo;
    *ret_hi = hi;
    return lo <= hi;
}

/* Visits every cell that fan triangle (f, i) may touch in the yz
 * projection, row by row: in each row the cells between the padded z
 * range of the triangle's part in that row's slab. Padding (relative
 * 1e-6 of a cell, 1e-12 of the coordinates) covers the rounding of cell
 * bounds and of the clipping, so a point whose cell is skipped cannot lie
 * in the triangle's projection. Work is proportional to the rows and
 * cells touched: long slivers span many cells' boxes but few cells.
 * fill NULL counts into ix->cell_start[cell + 1]; else appends the
 * triangle's reference at fill[cell]. Returns the number of cells. */
static size_t grid_tri(geo_inside *ix, uint32_t f, uint32_t i, uint32_t *fill)
{
    const geo_poly *p = ix->p;
    const uint32_t *v = geo_poly_facet(p, f);
    const double *t[3] = {p->verts[v[0]], p->verts[v[i]], p->verts[v[i + 1]]};
    geo_bbox b;
    tri_box(p, f, i, &b);
    uint32_t y0 = cell_index(b.lo[1], ix->y0, ix->sy, ix->gy),
             y1 = cell_index(b.hi[1], ix->y0, ix->sy, ix->gy),
             z0 = cell_index(b.lo[2], ix->z0, ix->sz, ix->gz),
             z1 = cell_index(b.hi[2], ix->z0, ix->sz, ix->gz);
    cell_ref r = {b.lo[1], b.hi[1], b.lo[2], b.hi[2], b.hi[0], f, i};
    double cy = ix->sy > 0 ? 1.0 / ix->sy : 0, cz = ix->sz > 0 ? 1.0 / ix->sz : 0;
    double pad_y = 1e-6 * cy + 1e-12 * (fabs(b.lo[1]) + fabs(b.hi[1]));
    double pad_z = 1e-6 * cz + 1e-12 * (fabs(b.lo[2]) + fabs(b.hi[2]));
    size_t n = 0;
    for (uint32_t y = y0; y <= y1; y++) {
        uint32_t za = z0, zb = z1;
        if (y0 != y1) {
            double lo, hi;
            double Y0 = y == y0 ? b.lo[1] : ix->y0 + y * cy - pad_y;
            double Y1 = y == y1 ? b.hi[1] : ix->y0 + (y + 1) * cy + pad_y;
            if (!slab_zrange(t, Y0, Y1, &lo, &hi))
                continue;
            uint32_t a = cell_index(lo - pad_z, ix->z0, ix->sz, ix->gz),
                     c = cell_index(hi + pad_z, ix->z0, ix->sz, ix->gz);
            za = a > z0 ? a : z0;
            zb = c < z1 ? c : z1;
        }
        for (uint32_t z = za; z <= zb; z++) {
            size_t cell = (size_t)y * ix->gz + z;
            if (fill)
                ix->refs[fill[cell]++] = r;
            else
                ix->cell_start[cell + 1]++;
            n++;
        }
    }
    return n;
}

static int build_grid(geo_inside *ix, geo_err *err)
{
    const geo_poly *p = ix->p;
    size_t ntri = 0;
    FOR_EACH_TRI(p, f, i)
        ntri++;
    double ey = ix->box.hi[1] - ix->box.lo[1], ez = ix->box.hi[2] - ix->box.lo[2];
    double cells = (double)GRID_CELLS_PER_TRI * (double)(ntri ? ntri : 1);
    uint32_t gy = 1, gz = 1;
    if (ntri > 0 && ey > 0 && ez > 0) {
        double s = sqrt(cells / (ey * ez)); /* square cells */
        gy = (uint32_t)fmin(GRID_MAX_SIDE, fmax(1, ceil(ey * s)));
        gz = (uint32_t)fmin(GRID_MAX_SIDE, fmax(1, ceil(ez * s)));
    } else if (ntri > 0 && ey > 0) {
        gy = (uint32_t)fmin(GRID_MAX_SIDE, cells);
    } else if (ntri > 0 && ez > 0) {
        gz = (uint32_t)fmin(GRID_MAX_SIDE, cells);
    }
    size_t budget = (size_t)GRID_REFS_PER_TRI * ntri + 1024, total;
    for (;;) {
        ix->gy = gy, ix->gz = gz;
        ix->y0 = ix->box.lo[1], ix->z0 = ix->box.lo[2];
        ix->sy = ey > 0 ? gy / ey : 0;
        ix->sz = ez > 0 ? gz / ez : 0;
        free(ix->cell_start);
        ix->cell_start = calloc((size_t)gy * gz + 1, sizeof *ix->cell_start);
        if (!ix->cell_start)
            goto oom;
        total = 0;
        FOR_EACH_TRI(p, f, i) {
            total += grid_tri(ix, f, i, NULL);
            if (total > budget)
                break;
        }
        if (total <= budget || (gy == 1 && gz == 1))
            break;
        gy = gy > 1 ? gy / 2 : 1;
        gz = gz > 1 ? gz / 2 : 1;
    }
    if (total > UINT32_MAX)
        goto oom;
    size_t ncells = (size_t)gy * gz;
    for (size_t cell = 0; cell < ncells; cell++)
        ix->cell_start[cell + 1] += ix->cell_start[cell];
    ix->refs = malloc((total + 1) * sizeof *ix->refs);
    uint32_t *fill = malloc((ncells + 1) * sizeof *fill);
    if (!ix->refs || !fill) {
        free(fill);
        goto oom;
    }
    memcpy(fill, ix->cell_start, ncells * sizeof *fill);
    FOR_EACH_TRI(p, f, i)
        grid_tri(ix, f, i, fill);
    free(fill);
    return 0;
oom:
    return geo_err_set(err, -ENOMEM, "out of memory building the point grid");
}

geo_inside *geo_inside_new(const geo_poly *p, geo_err *err)
{
    if (geo_poly_validate_indices(p, err) != 0)
        return NULL;
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(p->verts[i][k])) {
                geo_err_set(err, -EINVAL, "vertices[%u]: coordinate is not finite",
                            i);
                return NULL;
            }
    geo_inside *ix = calloc(1, sizeof *ix);
    if (!ix) {
        geo_err_set(err, -ENOMEM, "out of memory");
        return NULL;
    }
    ix->p = p;
    ix->bvh = geo_bvh_build_facets(p, err);
    if (!ix->bvh)
        return geo_inside_free(ix);
    if (p->nfacets > 0) {
        ix->box = ix->bvh->nodes[0].box;
    } else {
        geo_bbox_empty(&ix->box);
    }
    double d2 = 0;
    for (int k = 0; k < 3; k++) {
        double e = p->nfacets ? ix->box.hi[k] - ix->box.lo[k] : 0;
        ix->center[k] = p->nfacets ? 0.5 * (ix->box.lo[k] + ix->box.hi[k]) : 0;
        d2 += e * e;
    }
    ix->diag = sqrt(d2);
    if (build_grid(ix, err) != 0)
        return geo_inside_free(ix);
    return ix;
}

/* ---- the random-ray test ------------------------------------------------ */

enum ray_status { RAY_OK = 0, RAY_BOUNDARY, RAY_DEGENERATE };

typedef struct ray_state {
    const geo_poly *p;
    const double *q, *e; /* the segment [q, e]; e lies outside the box */
    unsigned parity;
    enum ray_status status;
} ray_state;

/* The crossings of segment [q, e] with facet f's fan, or a boundary /
 * degenerate verdict in st->status. */
static bool ray_visit(void *user, uint32_t f)
{
    ray_state *st = user;
    const geo_poly *p = st->p;
    const double *q = st->q, *e = st->e;
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    const double *a = p->verts[v[0]];
    int crossings = 0, on_checked = 0;
    for (uint32_t i = 1; i + 1 < n; i++) {
        const double *b = p->verts[v[i]], *c = p->verts[v[i + 1]];
        int sq = geo_orient3d(a, b, c, q);
        int se = geo_orient3d(a, b, c, e);
        if (sq == 0) {
            /* rule 3: t = 0 on the facet */
            if (!on_checked++ && geo_point_on_facet(p, f, q)) {
                st->status = RAY_BOUNDARY;
                return false;
            }
            if (se == 0) {
                if (collinear3(a, b, c))
                    continue; /* a zero-area fan triangle covers nothing */
                st->status = RAY_DEGENERATE; /* the ray runs in its plane */
                return false;
            }
            /* q in the plane, off the facet: the segment meets this
             * triangle's plane only at q, outside the triangle; for an
             * exactly planar facet q lies where the fan's signed cover is
             * zero, so the whole facet contributes nothing */
            if (geo_facet_is_planar_exact(p, f))
                return true;
            continue;
        }
        /* se = 0: the plane is met at e only, outside the box */
        if (se == 0 || se == sq)
            continue;
        int s1 = geo_orient3d(q, e, a, b), s2 = geo_orient3d(q, e, b, c),
            s3 = geo_orient3d(q, e, c, a);
        if ((s1 > 0 || s2 > 0 || s3 > 0) && (s1 < 0 || s2 < 0 || s3 < 0))
            continue;
        if (s1 == 0 || s2 == 0 || s3 == 0) {
            st->status = RAY_DEGENERATE; /* through an edge or a vertex */
            return false;
        }
        crossings++;
    }
    st->parity ^= (unsigned)crossings & 1u;
    return true;
}

static bool facet_holds(void *user, uint32_t f)
{
    ray_state *st = user;
    if (geo_point_on_facet(st->p, f, st->q)) {
        st->status = RAY_BOUNDARY;
        return false;
    }
    return true;
}

/* Boundary by the exact on-facet test over the facets whose box holds q. */
static bool on_surface(const geo_inside *ix, const double q[3])
{
    ray_state st = {.p = ix->p, .q = q};
    geo_bbox qb = {{q[0], q[1], q[2]}, {q[0], q[1], q[2]}};
    geo_bvh_query_box(ix->bvh, &qb, facet_holds, &st);
    return st.status == RAY_BOUNDARY;
}

int geo_inside_winding(const geo_inside *ix, const double q[3])
{
    if (geo_gab3_test(&ix->box, q))
        return GEO_LOC_OUTSIDE;
    if (on_surface(ix, q))
        return GEO_LOC_BOUNDARY;
    return geo_winding_number(ix->p, q) >= 0.5 ? GEO_LOC_INSIDE
                                               : GEO_LOC_OUTSIDE;
}

int geo_inside_ray(const geo_inside *ix, const double q[3],
                   const double dir0[3], uint64_t *rng, unsigned *ret_shots)
{
    if (ret_shots)
        *ret_shots = 0;
    if (geo_gab3_test(&ix->box, q))
        return GEO_LOC_OUTSIDE;
    double reach = 2.0 * (ix->diag + geo_vdist(q, ix->center));
    if (!(reach > 0))
        reach = 1.0;
    for (unsigned shot = 1; shot <= GEO_INSIDE_MAX_SHOTS; shot++) {
        double d[3];
        if (shot == 1 && dir0 && geo_vlen(dir0) > 0) {
            memcpy(d, dir0, sizeof d);
            geo_vnormalize(d);
        } else {
            double phi = 2.0 * M_PI * geo_rand_unit(rng);
            double psi = M_PI * geo_rand_unit(rng);
            d[0] = sin(phi) * sin(psi);
            d[1] = cos(psi);
            d[2] = cos(phi) * sin(psi);
        }
        double e[3];
        geo_vmadd(q, reach, d, e);
        ray_state st = {.p = ix->p, .q = q, .e = e};
        geo_bvh_query_ray(ix->bvh, q, d, reach, ray_visit, &st);
        if (ret_shots)
            *ret_shots = shot;
        if (st.status == RAY_BOUNDARY)
            return GEO_LOC_BOUNDARY;
        if (st.status == RAY_OK)
            return st.parity ? GEO_LOC_INSIDE : GEO_LOC_OUTSIDE;
    }
    return geo_inside_winding(ix, q);
}

/* ---- the batch's +x ray ------------------------------------------------- */

enum axis_status { AXIS_OK = 0, AXIS_BOUNDARY, AXIS_DEGENERATE };

/* Whether the ray q + t·(1,0,0), t > 0, crosses fan triangle (a, b, c)
 * of facet f. In the yz projection the ray is the point q: it passes
 * through the triangle iff q lies strictly inside the projected triangle
 * (orient2d signs all equal to the triangle's, s = the sign of its
 * normal's x), and it meets the plane ahead of q iff q lies on the side
 * of the plane opposite to s. *ret_cross is 1 for a crossing, else 0. */
static enum axis_status axis_tri(const geo_poly *p, uint32_t f, uint32_t i,
                                 const double q[3], int *ret_cross)
{
    const uint32_t *v = geo_poly_facet(p, f);
    const double *a = p->verts[v[0]], *b = p->verts[v[i]],
                 *c = p->verts[v[i + 1]];
    *ret_cross = 0;
    int o1 = geo_orient2d_proj(a, b, q, 0);
    int o2 = geo_orient2d_proj(b, c, q, 0);
    if (o1 * o2 < 0)
        return AXIS_OK;
    int o3 = geo_orient2d_proj(c, a, q, 0);
    if ((o1 > 0 || o2 > 0 || o3 > 0) && (o1 < 0 || o2 < 0 || o3 < 0))
        return AXIS_OK;
    if (o1 == 0 || o2 == 0 || o3 == 0)
        return AXIS_DEGENERATE;
    int sq = geo_orient3d(a, b, c, q);
    if (sq == 0) {
        if (geo_point_on_facet(p, f, q))
            return AXIS_BOUNDARY;
        /* only an exactly planar facet holds q in a triangle's plane,
         * inside its projection, yet off the facet: q is where the fan's
         * signed cover is zero, and every triangle of the facet has q in
         * its plane too, so the facet adds nothing */
        return AXIS_OK;
    }
    *ret_cross = sq == -o1;
    return AXIS_OK;
}

/* The +x ray over the grid cell holding q; AXIS_OK fills *ret_loc. */
static enum axis_status axis_test(const geo_inside *ix, const double q[3],
                                  int *ret_loc)
{
    uint32_t iy = cell_index(q[1], ix->y0, ix->sy, ix->gy);
    uint32_t iz = cell_index(q[2], ix->z0, ix->sz, ix->gz);
    size_t cell = (size_t)iy * ix->gz + iz;
    unsigned parity = 0;
    for (uint32_t k = ix->cell_start[cell]; k < ix->cell_start[cell + 1]; k++) {
        const cell_ref *r = &ix->refs[k];
        if (q[0] > r->xmax || q[1] < r->ylo || q[1] > r->yhi ||
            q[2] < r->zlo || q[2] > r->zhi)
            continue;
        int cross;
        enum axis_status s = axis_tri(ix->p, r->facet, r->i, q, &cross);
        if (s != AXIS_OK) {
            if (s == AXIS_BOUNDARY)
                *ret_loc = GEO_LOC_BOUNDARY;
            return s;
        }
        parity ^= (unsigned)cross;
    }
    *ret_loc = parity ? GEO_LOC_INSIDE : GEO_LOC_OUTSIDE;
    return AXIS_OK;
}

static uint64_t point_seed(uint64_t seed, const double q[3])
{
    uint64_t s = seed;
    for (int k = 0; k < 3; k++) {
        uint64_t bits;
        memcpy(&bits, &q[k], sizeof bits);
        s ^= bits;
        (void)geo_rand_next(&s);
    }
    return s;
}

int geo_inside_point(const geo_inside *ix, const double q[3], uint64_t seed)
{
    if (geo_gab3_test(&ix->box, q))
        return GEO_LOC_OUTSIDE;
    int loc;
    enum axis_status s = axis_test(ix, q, &loc);
    if (s != AXIS_DEGENERATE)
        return loc;
    uint64_t rng = point_seed(seed, q);
    return geo_inside_ray(ix, q, NULL, &rng, NULL);
}

/* ---- batches ------------------------------------------------------------ */

/* Points per parallel task, and tasks per round between progress reports. */
enum { CHUNK_RAY = 2048, CHUNK_WINDING = 32, ROUND_CHUNKS = 64 };

typedef struct batch {
    const geo_inside *ix;
    const double (*pts)[3];
    size_t n, chunk, first_chunk;
    enum geo_inside_method method;
    uint64_t seed;
    int8_t *out;
} batch;

static void batch_chunk(void *arg, size_t i)
{
    const batch *b = arg;
    size_t lo = (b->first_chunk + i) * b->chunk;
    size_t hi = lo + b->chunk < b->n ? lo + b->chunk : b->n;
    for (size_t j = lo; j < hi; j++)
        b->out[j] = (int8_t)(b->method == GEO_INSIDE_WINDING
                                 ? geo_inside_winding(b->ix, b->pts[j])
                                 : geo_inside_point(b->ix, b->pts[j], b->seed));
}

int geo_inside_classify(const geo_inside *ix, const double (*pts)[3], size_t n,
                        enum geo_inside_method method, int8_t *ret_loc,
                        const geo_ctx *ctx, geo_err *err)
{
    for (size_t j = 0; j < n; j++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(pts[j][k]))
                return geo_err_set(err, -EINVAL,
                                   "points[%zu]: coordinate is not finite", j);
    batch b = {.ix = ix, .pts = pts, .n = n, .method = method,
               .seed = ctx ? ctx->seed : 0, .out = ret_loc};
    b.chunk = method == GEO_INSIDE_WINDING ? CHUNK_WINDING : CHUNK_RAY;
    size_t nchunks = (n + b.chunk - 1) / b.chunk;
    for (size_t c = 0; c < nchunks; c += ROUND_CHUNKS) {
        if (geo_ctx_progress(ctx, (double)c / (double)nchunks) != 0)
            return geo_err_set(err, -ECANCELED, "canceled");
        b.first_chunk = c;
        size_t m = nchunks - c < ROUND_CHUNKS ? nchunks - c : ROUND_CHUNKS;
        geo_ctx_parallel_for(ctx, m, batch_chunk, &b);
    }
    if (geo_ctx_progress(ctx, 1.0) != 0)
        return geo_err_set(err, -ECANCELED, "canceled");
    return 0;
}
