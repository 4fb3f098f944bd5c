/* frep.h — functionally defined objects (Vyatkin, F-rep discretization; formats.md
 * frep-object/1): a tree of quadrics combined by perturbation sums and
 * min/max, compiled into a postfix program that is evaluated for values,
 * gradients and interval bounds over boxes.
 *
 * Sign convention: the inside of an object is F ≥ 0, the outside F < 0,
 * so −∇F points outward on the surface F = 0.
 *
 * Shapes and their functions (p a point, d = p − centre):
 *   sphere(c, r)             F = r² − |d|²
 *   ellipsoid(c, radii)      F = 1 − Σ (d_i / r_i)²
 *   quadric(A..J)            F = A x² + B y² + C z² + D xy + E yz + F xz
 *                                + G x + H y + I z + J
 *   halfspace(a, b, c, d)    F = −(a x + b y + c z + d)
 *   perturbed(base, terms)   F = F_base + Σ f_i · R(F_i),
 *                            R(q) = q³ for q ≥ 0, 0 elsewhere
 *   union(shapes)            F = max F_i
 *   intersection(shapes)     F = min F_i
 *   difference(a, b)         F = min(F_a, −F_b)
 *
 * Building: add shapes bottom-up (each constructor returns the new node's
 * id, children must already exist, so the graph is acyclic by
 * construction), then geo_frep_finish compiles the program from a root.
 *
 * The program is a postfix sequence of geo_frep_op. Its interval
 * evaluation over an axis-aligned box gives an enclosure of F there
 * (natural interval extension; every quadric term is bounded per axis
 * exactly, cross terms by interval products; R is monotone). The bound is
 * evaluated in ordinary floating point without outward rounding: a box
 * is reported empty only when its upper bound is negative by more than
 * rounding can explain for any F that matters to a mesh. "Specialising"
 * a program to a box drops the perturbation terms that are identically
 * zero there and the min/max branches that cannot win there: inside the
 * box the short program computes the same F (up to rounding). This is
 * what makes the surface search fast (Vyatkin: "empty regions of space
 * are discarded at once").
 *
 * Ownership: geo_frep_new allocates, geo_frep_free releases. A finished
 * object is immutable; all evaluation functions are then reentrant and
 * thread-safe (they only read it and use the caller's scratch). */
#ifndef GEO_FREP_H
#define GEO_FREP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctx.h"

/* Hard limits of the representation (the JSON reader applies its own,
 * usually smaller, limits first). */
#define GEO_FREP_MAX_NODES 1000000u
#define GEO_FREP_MAX_DEPTH 64u     /* nesting of shapes */
#define GEO_FREP_MAX_OPS 4000000u  /* compiled program length */
#define GEO_FREP_MAX_STACK (GEO_FREP_MAX_DEPTH + 2u)

typedef struct geo_frep geo_frep;

enum geo_frep_opcode {
    GEO_FREP_OP_PRIM = 0, /* push the value of primitive `arg` */
    GEO_FREP_OP_ADDR = 1, /* pop q; top += amp · R(q) */
    GEO_FREP_OP_MAX = 2,  /* pop b; top = max(top, b) */
    GEO_FREP_OP_MIN = 3,  /* pop b; top = min(top, b) */
    GEO_FREP_OP_NEG = 4,  /* top = −top */
};

/* One instruction. `start` is the index of the first instruction of the
 * subtree this instruction is the root of (its own index for PRIM), so
 * ops[start .. i] is a program by itself. */
typedef struct geo_frep_op {
    uint8_t code;   /* enum geo_frep_opcode */
    uint32_t arg;   /* PRIM: primitive index */
    uint32_t start; /* first instruction of this subtree */
    double amp;     /* ADDR: amplitude f_i */
} geo_frep_op;

/* An empty object, or NULL on out-of-memory. */
geo_frep *geo_frep_new(void);

/* Releases f; accepts NULL; returns NULL. */
geo_frep *geo_frep_free(geo_frep *f);

/* Constructors. Each returns the new node's id (≥ 0), or -EINVAL (a
 * non-finite number, a radius ≤ 0, a zero plane normal, a child id that
 * does not exist, an empty list; err names the problem), -ERANGE (more
 * than GEO_FREP_MAX_NODES nodes or nesting deeper than
 * GEO_FREP_MAX_DEPTH), or -ENOMEM. Numbers are copied. A plane's normal
 * need not be unit; a unit normal makes F the signed distance. */
int64_t geo_frep_sphere(geo_frep *f, const double center[3], double radius,
                        geo_err *err);
int64_t geo_frep_ellipsoid(geo_frep *f, const double center[3],
                           const double radii[3], geo_err *err);
int64_t geo_frep_quadric(geo_frep *f, const double coef[10], geo_err *err);
int64_t geo_frep_halfspace(geo_frep *f, const double plane[4], geo_err *err);
/* terms[k] is a shape id used as the k-th perturbation with amplitude
 * amps[k]; n may be 0. */
int64_t geo_frep_perturbed(geo_frep *f, uint32_t base, uint32_t n,
                           const uint32_t *terms, const double *amps,
                           geo_err *err);
int64_t geo_frep_union(geo_frep *f, uint32_t n, const uint32_t *shapes,
                       geo_err *err);
int64_t geo_frep_intersection(geo_frep *f, uint32_t n, const uint32_t *shapes,
                              geo_err *err);
int64_t geo_frep_difference(geo_frep *f, uint32_t a, uint32_t b,
                            geo_err *err);

/* Compiles the program of node `root` and sets the bounds box [lo, hi]
 * (it must contain the object; lo < hi on every axis, finite). Returns 0,
 * -EINVAL (bad root or box), -ERANGE (program longer than
 * GEO_FREP_MAX_OPS; a node shared by several parents is compiled once per
 * use) or -ENOMEM; err set. May be called again to change root or box. */
int geo_frep_finish(geo_frep *f, uint32_t root, const double lo[3],
                    const double hi[3], geo_err *err);


/* The compiled program (valid until the next geo_frep_finish or free);
 * NULL with *ret_n = 0 before geo_frep_finish. */
const geo_frep_op *geo_frep_program(const geo_frep *f, uint32_t *ret_n);

/* The bounds box given to geo_frep_finish. */
void geo_frep_bounds(const geo_frep *f, double ret_lo[3], double ret_hi[3]);

/* F at p with the whole program. */
double geo_frep_eval(const geo_frep *f, const double p[3]);

/* F at p and its gradient ∇F into ret_grad. Where a min/max is tied the
 * first operand's gradient is taken. */
double geo_frep_eval_grad(const geo_frep *f, const double p[3],
                          double ret_grad[3]);

/* The same with an explicit program (a specialised one, or a subtree
 * ops[s..r] of the full program, which is a program by itself). n ≥ 1. */
double geo_frep_run(const geo_frep *f, const geo_frep_op *ops, uint32_t n,
                    const double p[3]);
double geo_frep_run_grad(const geo_frep *f, const geo_frep_op *ops,
                         uint32_t n, const double p[3], double ret_grad[3]);

/* Like geo_frep_run_grad, and also names the smooth piece F comes from at
 * p: the index (within ops) of the root of the subtree without min/max
 * that wins every min/max on the way up. Points on two sides of a crease
 * of a union/intersection get different pieces. */
double geo_frep_run_piece(const geo_frep *f, const geo_frep_op *ops,
                          uint32_t n, const double p[3], double ret_grad[3],
                          uint32_t *ret_piece);

/* The smooth pieces of F passing through p: the roots (indices in the
 * program) of the maximal subtrees without min/max whose value is zero
 * at p within tol·|∇|, at most cap of them into ret (in program order).
 * Returns how many there are (may exceed cap). A point on a crease of
 * two pieces gets two, on a corner three. */
uint32_t geo_frep_pieces_at(const geo_frep *f, const double p[3], double tol,
                            uint32_t *ret, uint32_t cap);

/* Moves p onto the surface F = 0 by Newton steps along ∇F,
 * p ← p − F(p)·∇F/|∇F|², at most 8 of them, until |F|/|∇F| ≤ tol. A step
 * longer than max_step, a vanishing gradient or a step that does not
 * reduce |F| stops the iteration and keeps the best point seen. Returns
 * the final |F|/|∇F| (INFINITY where ∇F = 0). */
double geo_frep_project(const geo_frep *f, double p[3], double tol,
                        double max_step);

/* Moves p onto the part of the surface where the smooth pieces
 * pieces[0..n) (n = 1, 2 or 3; roots in the program as returned by
 * geo_frep_pieces_at) all vanish: on one piece by Newton steps along its
 * gradient, on the crease of two or the corner of three by least-norm
 * Gauss–Newton steps (at most 16), until every piece's |G|/|∇G| ≤ tol.
 * The result must also lie on the surface itself (|F|/|∇F| ≤ 1000·tol:
 * no other piece cuts that part away) and within max_step of the start.
 * Returns true with p moved, or false with p unchanged (no convergence,
 * nearly parallel pieces, off the surface, too far). */
bool geo_frep_project_pieces(const geo_frep *f, const uint32_t *pieces,
                             uint32_t n, double p[3], double tol,
                             double max_step);


/* Specialises program ops[0..n) to the box [lo, hi]: ret_range receives
 * an enclosure of F over the box, and, when ret_ops is non-NULL
 * (capacity n, must not overlap ops), the pruned program, whose length is
 * returned (1 ≤ length ≤ n; 0 is returned when ret_ops is NULL).
 * scratch must hold 2·n doubles. Never fails. */
uint32_t geo_frep_specialize(const geo_frep *f, const geo_frep_op *ops,
                             uint32_t n, const double lo[3],
                             const double hi[3], double ret_range[2],
                             geo_frep_op *ret_ops, double *scratch);

#endif
