/* replanar_json.h — JSON forms of the vertex-move results (lib/replanar/replanar.h)
 * and the inversion statistics (lib/replanar/inversion.h), shared by the `facet`
 * CLI and the daemon.
 *
 * Shapes (units: mm, mm²; a non-finite number, e.g. S2 of a diverged run,
 * is written as null; a count that was not taken, −1 in the kernel, as
 * null):
 *   log row:  {"step","outer","inner","delta","s1","s2","s2sum","eps0","k",
 *              "selfint","active_vertices","active_facets"}
 *   result:   {"schedule","converged","valid","steps","s1","s2","k",
 *              "active_vertices","active_facets","selfint","inverted_facets",
 *              "volume","first_selfint_step","fixed_residual"}
 *   stats:    {"samples","seed","schedule","table":[{"m","runs","inverted",
 *              "p","ci95":[lo,hi],"not_converged","selfint",
 *              "inverted_facets","nonpositive_volume"}], "runs":[{"sample",
 *              "vertex","m","delta","dir":[x,y,z],"inverted","converged",
 *              "steps","selfint","inverted_facets","volume",
 *              "first_selfint_step"}] (only when kept)}
 * The seed is a JSON integer when below 2^63, else a decimal string.
 *
 * Every function returns a new reference (the caller json_decref's it) or
 * NULL on out-of-memory; inputs are only read. Thread-safe. */
#ifndef PROTO_REPLANAR_JSON_H
#define PROTO_REPLANAR_JSON_H

#include <jansson.h>

#include "inversion.h"
#include "replanar.h"


/* The rows of log as an array. */
json_t *proto_replanar_log_to_json(const geo_replanar_log *log);

json_t *proto_replanar_result_to_json(const geo_replanar_result *r,
                                      enum geo_replanar_schedule schedule);

json_t *proto_inversion_stats_to_json(const geo_inversion_stats *s);

#endif
