/* least_norm.h — one Gauss–Newton step of the least-norm re-planarisation
 * (the least-norm schedule of replanar.h).
 *
 * Problem: the fixed vertices are where they were put; find the positions
 * x of the free vertices closest to their start x0 in the sum of squares,
 * Σ |x_v − x0_v|², such that every facet of four or more vertices is
 * planar (a triangle always is). The planes are free unknowns: a facet may
 * turn and shift at no cost, so a move is absorbed by the planes wherever
 * they can take it and only what they cannot is passed on to vertices.
 * That is what keeps a local edit local on a scan full of slivers: the
 * alternating schedules of the paper (§4.2.3) fit each plane to its
 * vertices and then project each vertex on its planes, and between two
 * nearly coplanar facets that projection moves the shared vertices along
 * the line where the planes meet, by up to r/θ for a residual r.
 *
 * Linearised at the current x and planes (n_f, c_f), with each plane's
 * change written as a turn (a, b) about its vertices' centroid m_f in the
 * tangent basis (t1, t2) of n_f and a shift s, the incidence of free or
 * fixed vertex v with facet f reads
 *     n_f·u_v + a·t1·(x_v − m_f) + b·t2·(x_v − m_f) + s
 *         = −(n_f·x_v + c_f) + n_f·(x_v − x0_v)
 * for the new offset u_v = x_v' − x0_v (u = 0 for a fixed vertex). The
 * least-norm solution of  min |u|² + w_turn (a² + b²) + w_shift s²  under
 * those rows is u_v = Σ_{rows r at v} n_f(r) y_r with M y = rhs,
 *     M = A_u A_uᵀ + A_p W⁻¹ A_pᵀ + λ I,
 * one row and column per incidence: sparse, symmetric positive definite,
 * factored by lib/core/spchol. The weights of the plane unknowns are
 * 1e-6 of a vertex's (the turn's scaled by the model's size), so the
 * planes are free to within 1e-6 of the vertices' cost; λ, 1e-14 of the
 * largest diagonal entry, only makes the redundant rows of a facet whose
 * fixed vertices alone fix its plane harmless. Repeated steps converge
 * quadratically to the exact (nonlinear) least-norm solution. */
#ifndef GEO_LEAST_NORM_H
#define GEO_LEAST_NORM_H

#include <stdbool.h>
#include <stdint.h>

#include "ctx.h"
#include "poly.h"

/* One step. p: the facets and, in p->verts, the start positions x0.
 * fixed[v] nonzero for a fixed vertex. in: the facets whose planarity is
 * asked for (NULL: all); a free vertex of a facet outside it must be
 * fixed by the caller, or that facet may bend. from_start: the step aims
 * at the least-norm point from x0; otherwise it restores planarity
 * nearest x (Gauss–Newton on the constraints alone). planes: the current plane of every
 * facet (unit normal), read for the facets of four or more vertices.
 * x: the current positions, overwritten by the step's (fixed vertices are
 * not written). max_nnz bounds the factor's entries (0: none). Returns 0,
 * -ERANGE (the factor would exceed max_nnz), -EDOM (the system is not
 * numerically positive definite), -ENOMEM or -ECANCELED; x is unchanged
 * on error. */
int geo_least_norm_step(const geo_poly *p, const uint8_t *fixed,
                        const uint8_t *in, const double (*planes)[4],
                        double (*x)[3],
                        bool from_start, uint64_t max_nnz, const geo_ctx *ctx);

#endif
