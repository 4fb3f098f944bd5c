/* hole_fill.h — filling the holes of a polygon or triangle mesh (Vyatkin,
 * after Liepa, "Filling holes in meshes", 2003): every boundary loop is
 * closed by a minimum-weight triangulation, the patches are refined to the
 * density of the surrounding mesh and faired.
 *
 * 1. Loops. Boundary edges (used by one facet) are walked into loops with
 *    lib/core/topo.h, split at non-manifold vertices (two holes touching at a
 *    vertex are filled separately, so that vertex stays non-manifold: a
 *    caller that wants it manifold removes its facets first, merging the
 *    holes, as the F-rep triangulator does).
 * 2. Minimum-weight triangulation. For a loop v_0 … v_{n−1}, W_{i,k} is
 *    the least weight of a triangulation of (v_i … v_k): W_{i,i+1} = 0,
 *    W_{i,k} = min_{i<m<k} W_{i,m} + W_{m,k} + ω(v_i, v_m, v_k), with the
 *    minimising m kept in the index table M_{i,k}; the triangles are read
 *    back from M. ω is the triangle's area (GEO_FILL_AREA) or the sum of
 *    its edge lengths (GEO_FILL_EDGES). GEO_FILL_ANGLE is Liepa's own
 *    weight, a pair compared lexicographically: the largest dihedral
 *    angle between a triangle and its neighbours (the two sub-patches'
 *    triangles on (v_i, v_m) and (v_m, v_k), or the loop's facet where
 *    that side is a loop edge) combined by max, then the area combined
 *    by sum — a patch that folds back over the facets around a jagged
 *    loop loses to one that carries the surface on. A bridge's side
 *    sees the triangle the first half put on it. O(n³) time, O(n²)
 *    memory. A chord
 *    that already is an edge of the mesh has infinite weight, so a patch
 *    never creates a non-manifold edge; a collinear triangle too.
 *    No folds: with every weight, a triangle is admitted only if it faces
 *    the side the loop's mean (Newell) normal points to and does not turn
 *    by more than 120° against the facet across a loop edge it lies on;
 *    when no triangulation obeys that, only the second rule holds, and
 *    when none obeys that either, none. Both are rules per triangle, so
 *    the programme still finds the least weight among the triangulations
 *    obeying them; an edge no admissible triangle can lie on (a flat lid
 *    on a steep cone) skips the run at once. On a jagged loop the least
 *    area alone laid inverted slivers across three teeth of the rim and
 *    folded over the rim's facets.
 *    Bounded cost: a loop longer than max_dp_vertices is first cut by a
 *    bridge — a chord between a vertex and one in the opposite third of
 *    the loop (≤ 256 evenly spaced start vertices are tried) that is
 *    shortest relative to the loop length it cuts off (on a round loop a
 *    diameter, not a chord leaving thin wedges), among those that, seen
 *    along the loop's mean normal, leave both ends inside the loop's
 *    angle and cross no loop edge (a chord grazing a jagged rim runs over
 *    its teeth and leaves a piece that can only be closed by folding);
 *    without such a chord, the shortest — into two loops, recursively, so
 *    a loop of n vertices costs O(n · max_dp_vertices²) instead of O(n³).
 *    Loops longer than max_hole_vertices are left open
 *    (GEO_HOLE_TOO_LARGE).
 * 3. Refinement (opts.refine). The region is every patch plus the facets
 *    the caller flags in also_refine (triangles only; the F-rep
 *    triangulator flags triangles that project with zero area). s(v) of a
 *    region-boundary vertex is the mean length of its edges outside the
 *    region. All interior edges are first restored (see below), then a
 *    triangle with centroid c, s(c) = mean s of its corners, is
 *    split into three when for all three corners v
 *      density·|c − v| > s(c) and density·|c − v| > s(v)
 *    (density 1 is the paper's rule, √2 Liepa's); after each split the
 *    triangle's three edges are "restored": an interior edge is flipped
 *    when the angles opposite it sum to more than π (the opposite vertex
 *    inside the other triangle's circumsphere) and the flipped pair neither
 *    folds, nor bends by more than hard_angle_deg, nor makes an edge that
 *    opts.crosses_feature rejects. A hard edge — an edge of
 *    the region as given whose dihedral angle exceeds hard_angle_deg,
 *    unless it is a chord of a patch made here (a minimum-weight patch's
 *    bends are no feature of the surface), or that opts.hard_edge says
 *    lies along a feature of the surface, or a piece of one — is never
 *    flipped; it is split at
 *    S = (s(P)·Q + s(Q)·P)/(s(P)+s(Q)) when √2·|PQ| > (s(P)+s(Q))/2, each
 *    of its two triangles into two (fig. 12). Passes repeat until no
 *    triangle splits. The region's boundary edges and vertices stay fixed.
 *    Every split and flip is checked exactly before it is applied: its
 *    new triangles must not touch or cross any triangle within two rings
 *    (region or not; lib/mesh/trimesh.h geo_tmesh_clashes), else it is
 *    skipped (unless opts.check_each is false).
 * 4. Fairing (opts.fair) moves only the vertices refinement added. With
 *    U¹(p) = −p + Σ w(p,i)·p_i / Σ w(p,i) and U²(p) = −U¹(p) +
 *    Σ w(p,i)·U¹(p_i) / Σ w(p,i): for w = 1 (GEO_FAIR_UNIFORM) U²(p) = 0 is
 *    linear in p and solved in closed form — and, without opts.project,
 *    for all free vertices at once: the conditions form the symmetric
 *    positive definite system (L·D⁻¹·L)_ff·x_f = −(L·D⁻¹·L)_fb·x_b
 *    (L = D − Adj the graph Laplacian, D the neighbour counts; the fixed
 *    vertices it reads are the loop and one ring of the mesh outside it,
 *    with the loop vertices' full neighbour counts, as in Liepa's
 *    fairing), assembled once and solved exactly by a sparse Cholesky
 *    factorisation (lib/core/spchol.h), or, when the factor would exceed
 *    16·2²⁰ entries (192 MB), by conjugate gradients to a residual of
 *    1e-4 of the first (at most 5,000 iterations). With w = 1 the
 *    solution depends on the connectivity alone, and a free vertex in
 *    front of a tooth of a jagged rim (three of its four neighbours on
 *    the loop) can be drawn over the tooth: when the solution folds the
 *    surface (a dihedral angle above 120° or a collapsed facet), the
 *    free corners of the folded facets are held at their unfaired place
 *    lifted along the unfaired normal as far as the solution lifted
 *    them, and the others are solved again, at most four times; if it
 *    still folds, the sweeps below run instead; for w = |p − p_i|
 *    (GEO_FAIR_LENGTH) |U²(p)| is minimised by steepest descent with a
 *    line search by quadratic interpolation through three points. Both
 *    sweep over all free vertices (Jacobi) for fair_iterations sweeps or
 *    until no vertex moves by more than 10⁻⁴ of the local edge length.
 * Every new or moved vertex is passed through opts.place or, without it,
 * opts.project when set (the F-rep triangulator keeps it on the smooth
 * piece or the crease its sources share).
 *
 * Orientation: a patch is oriented like the facets around its hole (each
 * boundary edge is used once more, in the opposite direction). Output:
 * vertices keep their indices, new ones are appended; facets outside the
 * refinement region keep their order and come first, then the region's
 * triangles; every new facet gets its least-squares plane.
 *
 * Ownership: p is modified in place; stats->holes is malloc'd (free with
 * geo_fill_stats_clear). Errors: -EINVAL (invalid indices), -ENOMEM,
 * -ECANCELED; p is then unchanged. Open holes are not errors: each one is
 * reported with its reason. Not thread-safe for one p. */
#ifndef GEO_HOLE_FILL_H
#define GEO_HOLE_FILL_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"

enum geo_fill_weight {
    GEO_FILL_AREA = 0,  /* minimum total area */
    GEO_FILL_EDGES = 1, /* minimum total edge length */
    GEO_FILL_ANGLE = 2, /* Liepa's own weight: the least largest dihedral
                           angle (between a patch triangle and its
                           neighbours, the loop's facets included), ties
                           broken by the least area */
};

enum geo_fill_fair {
    GEO_FAIR_NONE = 0,
    GEO_FAIR_UNIFORM = 1, /* w(p, i) = 1, closed form */
    GEO_FAIR_LENGTH = 2,  /* w(p, i) = |p − p_i|, gradient descent */
};

enum geo_hole_status {
    GEO_HOLE_FILLED = 0,
    GEO_HOLE_TOO_LARGE = 1,        /* more than max_hole_vertices */
    GEO_HOLE_NOT_A_LOOP = 2,       /* the walk ends at a non-manifold edge */
    GEO_HOLE_NO_TRIANGULATION = 3, /* every triangulation repeats an edge
                                      of the mesh or is degenerate */
    GEO_HOLE_DEGENERATE = 4,       /* fewer than three vertices */
    GEO_HOLE_INTERSECTS = 5,       /* every patch tried would intersect
                                      the mesh (lib/mesh/fill.h checks) */
    GEO_HOLE_FILLED_PLANAR = 6,    /* closed by one planar facet
                                      (lib/mesh/fill.h) */
};

/* A stable name for a status ("filled", "too_large", ...). */
const char *geo_hole_status_name(enum geo_hole_status s);

typedef struct geo_fill_opts {
    enum geo_fill_weight weight; /* [GEO_FILL_AREA] */
    bool refine;                 /* [true] */
    enum geo_fill_fair fair;     /* [GEO_FAIR_UNIFORM] */
    double density;              /* centroid split factor [1.0] */
    double hard_angle_deg;       /* [45] */
    uint32_t max_dp_vertices;    /* [128], ≥ 8 */
    uint32_t max_hole_vertices;  /* [100000] */
    uint32_t fair_iterations;    /* [50] */
    /* Facets (indices of the input) to refine with the patches; NULL for
     * none. Non-triangles are ignored. Not kept. */
    const uint8_t *also_refine;
    /* Moves a point onto the surface being approximated; false refuses
     * it (it could not be brought onto the surface: the triangle is not
     * split, the vertex does not move). NULL leaves points where the
     * construction puts them. Called from the calling thread only. */
    bool (*project)(void *user, double p[3]);
    /* Places point p on the surface knowing which vertices it is made
     * from (from[0..n): the three corners of a triangle split at its
     * centroid, the two ends of a hard edge split at S, or, for a vertex
     * moved by fairing, its position before the move); false refuses it
     * (the triangle or edge is not split, the vertex does not move). A
     * surface with hard edges needs this to keep each new point on the
     * smooth piece or crease its sources lie on. NULL: project is used.
     * Pointers are valid only during the call. */
    bool (*place)(void *user, double p[3], const double *const *from,
                  uint32_t n);
    /* Whether the segment p–q lies along a hard edge (a feature line) of
     * that surface; NULL means unknown, and then an edge is hard when the
     * dihedral angle of its two triangles exceeds hard_angle_deg. */
    bool (*hard_edge)(void *user, const double p[3], const double q[3]);
    /* Whether the segment p–q would cut across a feature line; a flip
     * never creates such an edge. NULL: no such test. */
    bool (*crosses_feature)(void *user, const double p[3], const double q[3]);
    /* user argument of the callbacks, which are called from the calling
     * thread only */
    void *project_user;
    /* Which loops to fill: called once per loop with its vertex cycle
     * (n vertices, in the patch's order: against the loop's facets); a
     * loop it rejects is neither filled nor reported. NULL fills all. */
    bool (*select_loop)(void *user, const uint32_t *cycle, uint32_t n);
    void *select_user;
    /* Whether the minimum-weight triangulation may use triangle (a, b, c)
     * (vertex indices of p); a rejected triangle is treated like a
     * degenerate one. It must answer the same for the same triangle
     * during one call. lib/mesh/fill.c steers the search around the
     * triangles that crossed the mesh. NULL admits all. */
    bool (*admit)(void *user, uint32_t a, uint32_t b, uint32_t c);
    void *admit_user;
    /* [true] every split and flip is checked exactly against its two
     * rings before it is applied (step 3). false skips those checks: for
     * a caller that checks the finished patch itself and retries with
     * them when it crosses (lib/mesh/fill.c); refinement is then several
     * times faster. */
    bool check_each;
} geo_fill_opts;

/* Fills the defaults above. */
void geo_fill_opts_default(geo_fill_opts *o);

typedef struct geo_hole_report {
    uint32_t nverts;       /* boundary vertices */
    uint32_t first_vertex; /* one vertex of the loop (mesh index) */
    uint8_t status;        /* enum geo_hole_status */
    uint32_t ntriangles;   /* triangles of its minimum-weight patch */
    uint32_t nbridges;     /* chords that cut it for the bounded search */
    double weight;         /* the patch's total weight (area or length) */
    double max_angle;      /* GEO_FILL_ANGLE: the patch's largest dihedral
                              angle, radians (0 for the other weights) */
} geo_hole_report;

typedef struct geo_fill_stats {
    uint32_t nholes, nfilled, nopen;
    geo_hole_report *holes;   /* nholes reports in loop order */
    uint32_t nverts_added;    /* by refinement */
    uint32_t nregion_facets;  /* triangles refined (patches + flagged) */
    uint32_t nsplits;         /* centroid splits */
    uint32_t nflips;          /* edge restorations */
    uint32_t nhard_splits;    /* hard edges split */
    uint32_t nfair_sweeps;    /* fairing sweeps run (or CG iterations, and
                                 1 per direct solve) */
} geo_fill_stats;

/* Fills every hole of p as described above. 0 or a negative errno (see
 * the file comment); stats may be NULL. */
int geo_fill_loops(geo_poly *p, const geo_fill_opts *opts, const geo_ctx *ctx,
                   geo_fill_stats *stats, geo_err *err);

/* Steps 3 and 4 alone: refines (when opts->refine) and fairs (opts->fair)
 * the triangles of p flagged in region (one byte per facet; other facets
 * and non-triangles are left alone), with the same rules, fixed region
 * boundary, output order and error contract as geo_fill_loops; only the
 * refinement fields of *stats are set (stats may be NULL). */
int geo_refine_region(geo_poly *p, const uint8_t *region,
                      const geo_fill_opts *opts, const geo_ctx *ctx,
                      geo_fill_stats *stats, geo_err *err);

/* Step 4 alone: fairs vertices first_free … p->nverts − 1 of p with
 * opts->fair (every other vertex fixed: the fixed ring of the U²
 * operator), with the same rules as geo_fill_loops; the facets touching
 * them get new least-squares planes. Only nfair_sweeps of *stats is set
 * (stats may be NULL). 0, -EINVAL (invalid indices, first_free beyond
 * the vertices), -ENOMEM (p unchanged) or -ECANCELED (the free vertices
 * may be partly moved). */
int geo_fair_vertices(geo_poly *p, uint32_t first_free,
                      const geo_fill_opts *opts, const geo_ctx *ctx,
                      geo_fill_stats *stats, geo_err *err);

/* Frees stats->holes and zeroes *stats; accepts NULL. */
void geo_fill_stats_clear(geo_fill_stats *stats);

#endif
