/* points_json.h — point lists in JSON for point classification (`facet
 * inside`): reading a JSON array of
 * [x, y, z] numbers (mm), bare or as {"points": [...]}, and writing the
 * answers as a JSON array of "inside" / "outside" / "boundary".
 *
 * Reading validates strictly and names the place of the first error
 * ("points[17][2]: expected a number", "points[3]: expected 3 numbers,
 * got 2"); NaN/Infinity literals and numbers that overflow a double are
 * not JSON. The count is checked against a limit: at most that many
 * points are ever stored.
 *
 * Ownership: *ret_pts and the returned text are malloc'd for the caller to
 * free. All functions are reentrant and thread-safe. */
#ifndef PROTO_POINTS_JSON_H
#define PROTO_POINTS_JSON_H

#include <stddef.h>
#include <stdint.h>

#include "ctx.h"

/* Default limits: points per list, and bytes of a points file. */
#define PROTO_POINTS_MAX 50000000u
#define PROTO_POINTS_MAX_BYTES ((size_t)2 << 30)

/* Points from JSON text of len bytes: an array of [x, y, z], or an
 * object whose "points" member is one (other members are ignored).
 * max_points 0 means PROTO_POINTS_MAX. On success *ret_pts (n triples;
 * NULL when n is 0) and *ret_n are set and 0 is returned; else -EINVAL
 * (bad JSON: "line 3, column 7: ..."; or a bad value, named), -ERANGE
 * (more than max_points) or -ENOMEM, with err set and the outputs
 * untouched. The whole text is checked as JSON first: a syntax error
 * anywhere is the error reported. */
int proto_points_read_mem(const void *data, size_t len, size_t max_points,
                          double (**ret_pts)[3], size_t *ret_n, geo_err *err);

/* The same from a file ("-" reads standard input) of at most
 * PROTO_POINTS_MAX_BYTES; errors are prefixed with the path. */
int proto_points_read_file(const char *path, size_t max_points,
                           double (**ret_pts)[3], size_t *ret_n, geo_err *err);

/* The name of a classification (lib/inspect/inside.h enum geo_loc: −1, 0, 1):
 * "inside", "boundary", "outside"; "invalid" for anything else. */
const char *proto_loc_name(int loc);

/* The answers as JSON text, one array of names with a final newline:
 * ["inside","outside",...]. Returns a malloc'd NUL-terminated string
 * (length in *ret_len if not NULL), or NULL on out-of-memory. */
char *proto_locs_to_text(const int8_t *loc, size_t n, size_t *ret_len);

#endif
