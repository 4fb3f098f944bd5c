/* runner.h — runs a job pipeline (proto/pipeline.h) on a polyhedron: the
 * one place that maps operations to kernels, shared by facetd's workers
 * and `facet run`.
 *
 * The op table in runner.c has one entry per operation: its kernel call
 * and how it reports. An operation whose kernel is not part of this build
 * has no entry; runner_check rejects a pipeline that uses one (the daemon
 * answers 422 at submission) and runner_run fails on it, so nothing is
 * ever faked.
 *
 * Progress: operation i of n reports fractions mapped into [i/n, (i+1)/n]
 * of the caller's geo_ctx progress; cancellation passes through unchanged.
 *
 * Statistics (the JSON served as /v1/jobs/{id}/stats):
 *   {"ops": [{"op": NAME, "ms": T, "report": {...}}, ...],
 *    "before": the first inspect report or null,
 *    "after": the last inspect report, if an operation changed the model
 *             before it, else null}
 * Summary (embedded in the job): {"vertices_before", "facets_before",
 * "vertices_after", "facets_after", "ms"} plus what the operations add
 * (inspect adds "valid", "closed", "orientation", "self_intersections"
 * of the model it saw; a later inspect overwrites an earlier one's;
 * triangulate adds "closed" and "self_intersections" of its mesh;
 * compare adds "compare_aligned", "compare_rotation_deg",
 * "compare_hausdorff_mm" and "compare_mean_distance_mm").
 *
 * Inputs: a polyhedron (runner_run) or a frep-object/1 (runner_run_frep),
 * which only triangulate takes, as the first operation; its report is the
 * triangulation report of proto/tri_report_json.h.
 *
 * Thread safety: reentrant; concurrent runs on different models are fine. */
#ifndef FACETD_RUNNER_H
#define FACETD_RUNNER_H

#include <stdbool.h>

#include <jansson.h>

#include "ctx.h"
#include "frep.h"
#include "pipeline.h"
#include "poly.h"

/* True when an operation of p may change the model; false for a pipeline
 * of read-only operations (inspect), whose result is its input. */
bool runner_changes_model(const proto_pipeline *p);

/* 0 when p suits its input: a frep-object/1 input (frep true) needs an
 * operation that makes a model of it (triangulate) first and nowhere
 * else; a model input must have none. Else -EINVAL with err naming the
 * place ("pipeline[0]: op 'inspect' cannot take a 'frep' input; start
 * with 'triangulate'"). */
int runner_check_input(const proto_pipeline *p, bool frep, geo_err *err);

/* 0 when p's arguments suit model m as submitted: a vertex or facet an
 * op names must exist, when every op before it leaves the numbering as it
 * is (after one that changes the model, only the run can tell). Else
 * -EINVAL with err naming the place ("pipeline[1].vertex: 99 out of range
 * (8 vertices)"). */
int runner_check_model(const proto_pipeline *p, const geo_poly *m,
                       geo_err *err);

/* Called after each operation with its run time (for metrics). */
typedef void (*runner_op_timer)(void *user, proto_op_kind op, double seconds);

/* Validity: an inspect after an op that changed the model fails the run
 * (-EINVAL, err "pipeline[2] (inspect): the result is not a valid
 * polyhedron: not closed (4 boundary edges)") unless that inspect has
 * keep_invalid; an inspect of the unchanged input only reports.
 *
 * Runs p on *model. Operations may replace *model (the old one is freed);
 * on success *model is the result and *ret_stats, *ret_summary are new
 * JSON objects the caller owns. On failure returns a negative errno
 * (-ECANCELED when ctx canceled) with err naming the operation
 * ("pipeline[2] (merge_facets): ..."); *model is still a valid polyhedron
 * the caller frees. timer may be NULL. */
int runner_run(const proto_pipeline *p, geo_poly **model, const geo_ctx *ctx,
               runner_op_timer timer, void *timer_user, json_t **ret_stats,
               json_t **ret_summary, geo_err *err);

/* Runs p on the functionally defined object f (finished, borrowed): the
 * first operation makes the model, the others work on it as in
 * runner_run. On success *ret_model is the result (the caller frees it)
 * and the summary has no *_before counts; on failure *ret_model is NULL.
 * Errors and statistics as runner_run. */
int runner_run_frep(const proto_pipeline *p, const geo_frep *f,
                    geo_poly **ret_model, const geo_ctx *ctx,
                    runner_op_timer timer, void *timer_user,
                    json_t **ret_stats, json_t **ret_summary, geo_err *err);

#endif
