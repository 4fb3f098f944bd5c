/* frep_json.h — frep-object/1 (formats.md): a functionally defined object
 * as JSON, read into a finished geo_frep (lib/frep/frep.h).
 *
 *   {"format": "frep-object/1",
 *    "bounds": [[x0,y0,z0],[x1,y1,z1]],
 *    "shape": SHAPE}
 *   SHAPE = {"sphere": {"center": [x,y,z], "radius": r}}
 *         | {"ellipsoid": {"center": [x,y,z], "radii": [rx,ry,rz]}}
 *         | {"quadric": [A,B,C,D,E,F,G,H,I,J]}
 *         | {"halfspace": {"plane": [a,b,c,d]}}
 *         | {"perturbed": {"base": SHAPE,
 *                          "perturbations": [{SHAPE-KEY: ..., "amplitude": f}, ...]}}
 *         | {"union": [SHAPE, ...]} | {"intersection": [SHAPE, ...]}
 *         | {"difference": [SHAPE, SHAPE]}
 *
 * Validation is strict and the first error names its place, e.g.
 * "shape.perturbed.perturbations[3].amplitude: expected a number".
 * Unknown keys are ignored; duplicate keys, a shape object with no or two
 * shape keys, non-finite numbers, radii ≤ 0, zero plane normals, empty
 * lists, bounds with lo ≥ hi, corners beyond ±PROTO_MAX_COORD or a box
 * less than PROTO_MIN_EXTENT across (proto/model_codec.h: the range of a
 * model the readers take back) are errors. Limits (proto_frep_limits) bound
 * the number of shapes and their nesting before anything is allocated for
 * them, so no input can exhaust memory or the stack.
 *
 * Ownership: a returned geo_frep belongs to the caller (geo_frep_free).
 * Reentrant and thread-safe. */
#ifndef PROTO_FREP_JSON_H
#define PROTO_FREP_JSON_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "frep.h"

typedef struct proto_frep_limits {
    uint32_t max_shapes; /* every shape object counts, default 100,000 */
    uint32_t max_depth;  /* nesting of shapes, default 32 (≤ GEO_FREP_MAX_DEPTH) */
    size_t max_bytes;    /* input size, default 64 MiB */
} proto_frep_limits;

/* Fills the defaults above. */
void proto_frep_limits_default(proto_frep_limits *lim);

/* The object from an already parsed JSON value. path_prefix names the
 * place in error messages (e.g. "frep"), may be NULL. lim NULL means
 * defaults. Returns NULL with err set on any error or out-of-memory. */
geo_frep *proto_frep_from_json(const json_t *root,
                               const proto_frep_limits *lim,
                               const char *path_prefix, geo_err *err);

/* Parses len bytes of JSON (duplicate keys rejected). NULL with err set
 * ("line 3 column 7: ..." for syntax errors). */
geo_frep *proto_frep_read_mem(const void *data, size_t len,
                              const proto_frep_limits *lim, geo_err *err);

/* Reads a file; errors are prefixed with the path. */
geo_frep *proto_frep_read_file(const char *path, const proto_frep_limits *lim,
                               geo_err *err);

#endif
