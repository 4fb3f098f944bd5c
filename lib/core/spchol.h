/* spchol.h — direct solution of a sparse symmetric positive definite
 * system A·x = b by Cholesky factorisation A = P'·L·L'·P (the fairing
 * systems of lib/mesh/hole_fill.h: bi-Laplacians of surface patches, whose
 * graphs are planar-like meshes; the least-norm re-planarization of
 * lib/replanar/least_norm.h; the silhouette fit of lib/correct/
 * convex_refine.c).
 *
 * Orderings, on A's graph alone (no coordinates), the caller's choice.
 * GEO_SPCHOL_DISSECTION, nested dissection, for large mesh-like graphs: a
 * set of unknowns is split by a level set of a breadth-first search from a
 * pseudo-peripheral vertex — on a mesh a band across it — the smallest
 * level near the median; both sides are ordered first (recursively), the
 * separator last. Sets of at most 64 unknowns, and sets the search cannot
 * split, are eliminated as they come. On an n-vertex patch this gives
 * O(n log n) entries in L and O(n^1.5) operations, against O(n²)-O(n³)
 * for banded orderings; conjugate gradients on the same bi-Laplacian
 * need O(patch diameter²) iterations of O(n) each.
 * GEO_SPCHOL_MIN_DEGREE, approximate minimum degree on the quotient
 * graph (Amestoy, Davis and Duff), over supervariables (unknowns with
 * equal rows, eliminated together), for the small systems of many
 * cliques: the Schur complement of a polyhedron's planes (lib/correct/
 * convex_refine.c, every vertex joining all its planes: 4× fewer
 * entries of L and 20× fewer operations than nested dissection, whose
 * level sets cut through the cliques) and the least-norm systems of a
 * row per facet corner (half the entries).
 * Factorisation: up-looking (row by row of L, each row's pattern from the
 * elimination tree), L stored by columns.
 *
 * Ownership: the factor owns its arrays (geo_spchol_factor allocates,
 * geo_spchol_free releases). Inputs are read only during the call. A
 * factor may be used by several threads to solve at once (solves do not
 * write to it). */
#ifndef GEO_SPCHOL_H
#define GEO_SPCHOL_H

#include <stdint.h>

#include "ctx.h"

typedef struct geo_spchol geo_spchol;

/* The fill-reducing ordering (see above). */
typedef enum geo_spchol_order {
    GEO_SPCHOL_DISSECTION,
    GEO_SPCHOL_MIN_DEGREE,
} geo_spchol_order;

/* Factors the n×n symmetric positive definite matrix A given by its full
 * pattern in compressed rows: row i holds columns ci[rp[i] .. rp[i+1])
 * with values v[...], each column at most once, both triangles and the
 * diagonal present (A must be symmetric: each off-diagonal entry is read
 * from one of its two rows), eliminated in the given order. max_nnz
 * bounds the entries of L (0: no bound). On success *ret is the factor.
 * Returns 0, -EINVAL (a column index ≥ n), -EDOM (A is not numerically
 * positive definite), -ERANGE (L would exceed max_nnz entries: nothing
 * numeric was done), -ENOMEM or -ECANCELED (ctx checked every 4,096
 * columns, and as often in the minimum-degree ordering); *ret is NULL
 * then. */
int geo_spchol_factor(uint32_t n, const uint32_t *rp, const uint32_t *ci,
                      const double *v, geo_spchol_order order,
                      uint64_t max_nnz, const geo_ctx *ctx, geo_spchol **ret);

/* Factors again, into f, a matrix of the same pattern as the one f was
 * made from (n, rp and ci equal) with new values v: the ordering and the
 * symbolic analysis are reused, so the factor is the one
 * geo_spchol_factor would give, bit for bit. Returns 0; -EINVAL when the
 * pattern differs (f unchanged); -EDOM, -ENOMEM or -ECANCELED, after
 * which f may only be freed or factored again. */
int geo_spchol_refactor(geo_spchol *f, uint32_t n, const uint32_t *rp,
                        const uint32_t *ci, const double *v,
                        const geo_ctx *ctx);

/* Entries of L (diagonal included). */
uint64_t geo_spchol_nnz(const geo_spchol *f);

/* Solves A·x = b for three right-hand sides at once: b[i][0..3) is row
 * i's, overwritten by the solution. 0 or -ENOMEM (b unchanged). */
int geo_spchol_solve3(const geo_spchol *f, double (*b)[3]);

/* Releases f; accepts NULL; returns NULL. */
geo_spchol *geo_spchol_free(geo_spchol *f);

#endif
