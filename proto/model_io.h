/* model_io.h — reading and writing polyhedra in every supported format:
 * facet-model/1 JSON, the paper's text format (Palachev 2012, §1.3, ".poly"),
 * OBJ, STL (ASCII and binary), PLY (ASCII and binary little- and
 * big-endian on reading, binary little-endian and ASCII on writing), ASE
 * (write only), FMB1 (the scanner's binary model) and OFF (text, with
 * the COFF/NOFF/4OFF/nOFF variants on reading). Coordinates are
 * millimetres; facets are listed counter-clockwise seen from outside.
 *
 * Every reader validates strictly and reports the first error with its
 * place ("facets[12].vertices[3]: index 9001 out of range (8000
 * vertices)", "line 17: ...", "byte 1234: ..."); limits (proto_limits)
 * and the counts a header declares are checked against the input before
 * anything is allocated for them. Readers never crash or hang on any
 * input bytes. A returned model has valid indices, finite coordinates and
 * finite planes (unit, or zero for a degenerate facet).
 *
 * Writers print doubles as the shortest decimal that reads back to the
 * same double, so JSON, .poly, PLY (double), FMB1 and ASCII STL round
 * trips keep every coordinate bit for bit; binary STL holds float32.
 *
 * Ownership: a returned geo_poly belongs to the caller (geo_poly_free);
 * *ret_buf from the writers is malloc'd for the caller to free.
 * All functions are reentrant and thread-safe. */
#ifndef PROTO_MODEL_IO_H
#define PROTO_MODEL_IO_H

#include <stddef.h>
#include <stdint.h>

#include <jansson.h>

#include "json_pull.h"
#include "poly.h"

typedef enum proto_format {
    PROTO_FMT_UNKNOWN = 0,
    PROTO_FMT_JSON,      /* facet-model/1 */
    PROTO_FMT_POLY,      /* the paper's text format */
    PROTO_FMT_OBJ,
    PROTO_FMT_STL,       /* binary on write; either on read */
    PROTO_FMT_STL_ASCII, /* ASCII on write */
    PROTO_FMT_PLY,       /* binary little-endian on write; either on read */
    PROTO_FMT_PLY_ASCII, /* ASCII on write */
    PROTO_FMT_ASE,       /* write only */
    PROTO_FMT_FMB1,      /* scanner binary model */
    PROTO_FMT_OFF,       /* Geomview OFF (text) */
    PROTO_FMT_ASC,       /* GemCad .asc design: tiers of facet half-spaces
                            on reading; a design of a convex model on
                            writing (docs/formats-asc.md) */
} proto_format;

/* Size limits applied by every reader. */
typedef struct proto_limits {
    uint32_t max_vertices; /* default 2,000,000 */
    uint32_t max_facets;   /* default 4,000,000 */
    uint32_t max_corners;  /* total facet indices, default 16,000,000 */
    size_t max_bytes;      /* input size, default 512 MiB */
    /* Not a limit but a reader option (default false): a model whose
     * every facet is a triangle and gives no plane keeps no planes
     * (planes NULL, see poly.h), for a caller that only reads it
     * through geo_poly_facet_plane (geo_inspect): 32 bytes a facet. */
    bool implicit_planes;
    /* Also an option (default false): proto_model_read_file maps a
     * facet-model/1 file and releases its pages as it reads them, so the
     * text is never resident whole; for a caller that may die of SIGBUS
     * if the file shrinks meanwhile (text_map.h). */
    bool map_file;
} proto_limits;

/* Fills the defaults above. */
void proto_limits_default(proto_limits *lim);

/* The format named by a file's extension (.json .poly .obj .stl .ply .ase
 * .fmb .off .asc), or by a name ("json", "poly", "obj", "stl",
 * "stl-ascii", "ply", "ply-ascii", "ase", "fmb1", "off", "asc");
 * PROTO_FMT_UNKNOWN otherwise. */
proto_format proto_format_from_path(const char *path);
proto_format proto_format_from_name(const char *name);
/* The canonical name of fmt ("json", …) and its MIME type. */
const char *proto_format_name(proto_format fmt);

/* The i-th format of the table every list of formats comes from (the
 * readers, /v1/version, error messages), or PROTO_FMT_UNKNOWN past its
 * end: for (i = 0; (f = proto_format_at(i)) != PROTO_FMT_UNKNOWN; i++). */
proto_format proto_format_at(size_t i);

/* "json, poly, obj, ... or fmb1" into buf (always terminated). */
void proto_format_list(char *buf, size_t size);
const char *proto_format_mime(proto_format fmt);

/* What a reader noticed without failing. Formats that carry planes
 * (facet-model/1, .poly, FMB1) have each given plane normalised and kept;
 * a given plane "mismatches" its facet when a vertex lies farther from it
 * than geo_poly_eps (poly.h), when its normal points against the vertex
 * order (Newell vector), or when its normal is zero (the plane is then
 * recomputed by least squares). Other formats give no planes: every plane
 * is computed and nothing is counted. */
typedef struct proto_read_report {
    uint32_t planes_given;     /* facets whose plane came from the input */
    uint32_t plane_mismatches; /* of those, how many mismatch */
    uint32_t worst_facet;      /* facet of worst_deviation; UINT32_MAX
                                  when every vertex lies exactly on its
                                  given plane (or none was given) */
    double worst_deviation;    /* mm, largest vertex distance from a given
                                  plane over the whole model */
    char first[256];           /* the first mismatch, naming its place
                                  ("facets[3].plane: ..."), "" if none */
} proto_read_report;

/* Parses a model of format fmt from len bytes. lim NULL means defaults.
 * Returns NULL with err set on any error (or out-of-memory). */
geo_poly *proto_model_read_mem(const void *data, size_t len, proto_format fmt,
                               const proto_limits *lim, geo_err *err);

/* As proto_model_read_mem, and fills *ret_report (may be NULL) when a
 * model is returned; on error *ret_report is left untouched. */
geo_poly *proto_model_read_mem_ex(const void *data, size_t len,
                                  proto_format fmt, const proto_limits *lim,
                                  proto_read_report *ret_report, geo_err *err);

/* Reads a file; fmt PROTO_FMT_UNKNOWN picks the format by extension.
 * Errors are prefixed with the path. */
geo_poly *proto_model_read_file(const char *path, proto_format fmt,
                                const proto_limits *lim, geo_err *err);

/* Reads the whole of fd (a file, pipe or terminal) into a malloc'd
 * buffer (*ret, *ret_len bytes; the caller frees it), failing past max
 * bytes — checked on the size before reading when fd is a regular file.
 * 0, or -ERANGE, -EISDIR, -ENOMEM or the read's negative errno with err
 * set; fd is left open. */
int proto_read_fd_all(int fd, size_t max, char **ret, size_t *ret_len,
                      geo_err *err);

/* As proto_model_read_file, with a report as in proto_model_read_mem_ex. */
geo_poly *proto_model_read_file_ex(const char *path, proto_format fmt,
                                   const proto_limits *lim,
                                   proto_read_report *ret_report,
                                   geo_err *err);

/* 0 when the store's format (FMB1) can hold p; else -ERANGE with err
 * naming the place ("facets[3]: 70000 vertices, FMB1 holds at most 65535
 * per facet"). The daemon checks this at submission. */
int proto_fmb1_check(const geo_poly *p, geo_err *err);

/* Serialises p in format fmt into a malloc'd buffer. 0, or a negative
 * errno with err set (-EINVAL for a format that cannot be written). */
int proto_model_write_mem(const geo_poly *p, proto_format fmt, char **ret_buf,
                          size_t *ret_len, geo_err *err);

/* Writes a file atomically (temporary file + rename); fmt UNKNOWN picks
 * the format by extension. 0 or a negative errno with err set. */
int proto_model_write_file(const geo_poly *p, const char *path,
                           proto_format fmt, geo_err *err);

/* facet-model/1 from an already parsed JSON value (the daemon embeds a
 * model in a job body). path_prefix names the place in error messages
 * (e.g. "model" gives "model.facets[3].vertices[1]: ..."), may be NULL.
 * Returns NULL with err set. root is only read (no reference taken). */
geo_poly *proto_model_from_json(const json_t *root, const proto_limits *lim,
                                const char *path_prefix, geo_err *err);

/* As proto_model_from_json, with a report as in proto_model_read_mem_ex. */
geo_poly *proto_model_from_json_ex(const json_t *root, const proto_limits *lim,
                                   const char *path_prefix,
                                   proto_read_report *ret_report,
                                   geo_err *err);

/* facet-model/1 read straight from a pull tokenizer (proto/json_pull.h)
 * whose last token, first, begins the model's value: the daemon reads the
 * model of a job body this way, without building a tree. The whole value
 * is read even past a problem in the model, so that bad JSON later in it
 * is what gets reported. Returns the model, or NULL with err set and
 * *ret_syntax (may be NULL) true when the JSON itself is bad — j then
 * holds the error and err says "line L, column C: ..." — or false when
 * the model is invalid (err names the place, prefixed with path_prefix as
 * by proto_model_from_json). Messages are those of proto_model_from_json
 * for the same text. lim NULL means the defaults. */
geo_poly *proto_model_from_jpull(proto_jpull *j, proto_jtok first,
                                 const proto_limits *lim,
                                 const char *path_prefix,
                                 proto_read_report *ret_report,
                                 bool *ret_syntax, geo_err *err);

/* Scales p about the origin so that the largest caliper width of its
 * outline seen along z (the table plane of a design) is width_mm: the
 * `--width` of a GemCad design, whose units are arbitrary. 0, or -EINVAL
 * with err set for a width that is not positive or a model with no
 * extent across z (p unchanged). */
int proto_model_scale_to_width(geo_poly *p, double width_mm, geo_err *err);

/* facet-model/1 as a new JSON value (planes always written), or NULL on
 * out-of-memory. */
json_t *proto_model_to_json(const geo_poly *p);

#endif
