/* model_codec.h — internal to proto/: what the model format codecs share
 * (a growable output buffer, exact number printing, plane finishing,
 * limit checks) and the entry points of each codec, dispatched by
 * model_io.c. Nothing outside proto/ includes this header.
 *
 * Reader contract (every proto_*_read below): data holds len bytes (not
 * NUL-terminated), lim is never NULL, rep is never NULL and zeroed by the
 * caller. A reader returns a new geo_poly whose planes are unit (or zero
 * for a degenerate facet) and whose indices are validated, or NULL with
 * err naming the place ("line 17: ...", "byte 84: ...",
 * "facets[3].vertices[1]: ..."). It never allocates more than a small
 * multiple of len, whatever counts the input claims.
 *
 * Writer contract: appends to buf; the model has finite coordinates and
 * planes and valid indices (model_io.c checks that first). Returns 0 or a
 * negative errno with err set; out-of-memory shows as buf->failed. */
#ifndef PROTO_MODEL_CODEC_H
#define PROTO_MODEL_CODEC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "model_io.h"

/* A growable byte buffer. After an allocation failure `failed` is set and
 * every later append is a no-op, so writers check once at the end. */
typedef struct proto_buf {
    char *data;
    size_t len, cap;
    bool failed;
} proto_buf;

void proto_buf_append(proto_buf *b, const void *bytes, size_t n);
void proto_buf_puts(proto_buf *b, const char *s);
void proto_buf_printf(proto_buf *b, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
/* The shortest decimal that reads back (strtod) as exactly x; "-0.0" for
 * negative zero (proto_decimal_format). x must be finite. */
void proto_buf_double(proto_buf *b, double x);
/* v in decimal digits. */
void proto_buf_u32(proto_buf *b, uint32_t v);
/* Appends n bytes and returns where they start, for the caller to fill;
 * NULL after an allocation failure (then failed is set). */
unsigned char *proto_buf_grow(proto_buf *b, size_t n);
/* Little-endian stores to and loads from unaligned bytes; inline, since
 * the binary formats (FMB1 above all: the store's) call them for every
 * number, and on a little-endian machine each is one move. */
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define PROTO_LE_MOVE 1
#else
#define PROTO_LE_MOVE 0
#endif

static inline void proto_st_u16le(unsigned char *p, uint16_t v)
{
    p[0] = (unsigned char)v;
    p[1] = (unsigned char)(v >> 8);
}

static inline void proto_st_u32le(unsigned char *p, uint32_t v)
{
    if (PROTO_LE_MOVE) {
        memcpy(p, &v, 4);
        return;
    }
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static inline void proto_st_f64le(unsigned char *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    if (PROTO_LE_MOVE) {
        memcpy(p, &u, 8);
        return;
    }
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(u >> (8 * i));
}

void proto_buf_u16le(proto_buf *b, uint16_t v);
void proto_buf_u32le(proto_buf *b, uint32_t v);
void proto_buf_f32le(proto_buf *b, float v);
void proto_buf_f64le(proto_buf *b, double v);

static inline uint16_t proto_ld_u16le(const unsigned char *p)
{
    return (uint16_t)(p[0] | (unsigned)p[1] << 8);
}

static inline uint32_t proto_ld_u32le(const unsigned char *p)
{
    uint32_t u;
    if (PROTO_LE_MOVE) {
        memcpy(&u, p, 4);
        return u;
    }
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
           (uint32_t)p[3] << 24;
}

static inline double proto_ld_f64le(const unsigned char *p)
{
    uint64_t u = 0;
    if (PROTO_LE_MOVE) {
        memcpy(&u, p, 8);
    } else {
        for (int i = 7; i >= 0; i--)
            u = u << 8 | p[i];
    }
    double d;
    memcpy(&d, &u, 8);
    return d;
}

static inline float proto_ld_f32le(const unsigned char *p)
{
    uint32_t u = proto_ld_u32le(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* A whitespace tokenizer over text that is not NUL-terminated; counts
 * lines (from 1) for error messages. With hash_comments, '#' starts a
 * comment that runs to the end of the line. */
typedef struct proto_scan {
    const char *p, *end;
    uint32_t line;      /* line of the position p */
    uint32_t tok_line;  /* line of the last token returned */
    bool hash_comments;
} proto_scan;

void proto_scan_init(proto_scan *s, const void *data, size_t len,
                     bool hash_comments);
/* The next token (*ret, *ret_len), or false at the end of the text. */
bool proto_scan_token(proto_scan *s, const char **ret, size_t *ret_len);
/* The rest of the current line (without its newline) as one span,
 * advancing past the newline; false at the end of the text. Leading and
 * trailing blanks are trimmed. */
bool proto_scan_line(proto_scan *s, const char **ret, size_t *ret_len);

/* A finite double from a whole token (C locale syntax, strtod). 0,
 * -EINVAL when the token is not a number or not finite, -ERANGE when it
 * overflows a double. */
int proto_parse_double(const char *tok, size_t len, double *ret);
/* An unsigned 32-bit integer written in decimal digits only. 0, -EINVAL,
 * or -ERANGE above UINT32_MAX. */
int proto_parse_u32(const char *tok, size_t len, uint32_t *ret);
/* A signed decimal integer within ±2^62. 0, -EINVAL or -ERANGE. */
int proto_parse_i64(const char *tok, size_t len, int64_t *ret);
/* Reads the n coordinates (n <= 4) of vertex i, the rest of text line
 * `line`, into c: 0, or -EINVAL with err "line L: vertices[I]: expected
 * N numbers" or "line L: vertices[I][K]: expected a number, found \"X\""
 * ("number out of range" for an overflow). */
int proto_scan_coords(proto_scan *ls, uint32_t line, uint32_t i, int n,
                      double *c, geo_err *err);
/* Formats a token for an error message: at most 24 bytes, non-printable
 * bytes as '?', into out (32 bytes). */
const char *proto_tok_show(const char *tok, size_t len, char *out);

/* Fails with -ERANGE and a message when a count exceeds lim ("vertices:
 * 3000000 exceed the limit of 2000000"). Counts are 64-bit so that a
 * claimed count is checked before any arithmetic on it. */
int proto_check_limits(const proto_limits *lim, uint64_t nverts,
                       uint64_t nfacets, uint64_t ncorners, geo_err *err);

/* The range of coordinates a model may have, mm: within ±PROTO_MAX_COORD
 * (a kilometre is 1e6), and, unless all vertices coincide, at least
 * PROTO_MIN_EXTENT across in some axis (a nanometre). */
#define PROTO_MAX_COORD 1e9
#define PROTO_MIN_EXTENT 1e-6

/* Completes a freshly read model: checks the range of its coordinates
 * (above), then its planes: facets with given[f] false (or given NULL:
 * all) get a least-squares plane; given planes are normalised and
 * checked against their vertices, filling rep (see proto_read_report).
 * 0, or -ERANGE with err naming the vertex (out of range, or a model
 * too small) or the facet (a plane that cannot be computed in doubles).
 * With lim->implicit_planes (lim may be NULL: none), a model of triangles
 * without a given plane keeps none (planes NULL; see proto_limits). */
int proto_finish_planes(geo_poly *p, const bool *given,
                        const proto_limits *lim, proto_read_report *rep,
                        geo_err *err);

/* A new model with room for nv vertices, nf facets and nc corners, and,
 * when ret_given is not NULL, *ret_given an array of nf flags (false) for
 * the readers of formats that give planes. NULL with err set on
 * out-of-memory, nothing left allocated. */
geo_poly *proto_poly_alloc(uint64_t nv, uint64_t nf, uint64_t nc,
                           bool **ret_given, geo_err *err);

/* The end of every reader: p completed by proto_finish_planes and
 * returned, or freed and NULL when that fails; given (may be NULL) is
 * freed either way. */
geo_poly *proto_read_done(geo_poly *p, bool *given, const proto_limits *lim,
                          proto_read_report *rep, geo_err *err);

/* Appends every vertex of p as a line "PREFIXx y z" (prefix "" or "v "),
 * coordinates as by proto_buf_double. */
void proto_buf_vertex_lines(proto_buf *b, const geo_poly *p,
                            const char *prefix);

/* Calls emit(p, f, q, arg) for every triangle of every facet f of p
 * (polygon_triangulate.h), q holding its corners as positions in the
 * facet's vertex list, in the facet's turning direction. 0, or -ENOMEM
 * with err set. */
int proto_each_triangle(const geo_poly *p,
                        void (*emit)(const geo_poly *p, uint32_t f,
                                     const uint32_t *q, void *arg),
                        void *arg, geo_err *err);

/* The codecs. */
geo_poly *proto_json_read(const void *data, size_t len,
                          const proto_limits *lim, proto_read_report *rep,
                          geo_err *err);
geo_poly *proto_json_from_value(const json_t *root, const proto_limits *lim,
                                proto_read_report *rep, geo_err *err);
/* proto_json_read of the text j was initialised with (j->behind may be
 * set); j is not cleared. */
geo_poly *proto_json_read_pull(proto_jpull *j, const proto_limits *lim,
                               proto_read_report *rep, geo_err *err);
/* The model whose value begins with first, read from j (see
 * proto_model_from_jpull); *ret_syntax tells a JSON error (err "line L,
 * column C: ...") from an invalid model. */
geo_poly *proto_json_from_pull(proto_jpull *j, proto_jtok first,
                               const proto_limits *lim, proto_read_report *rep,
                               bool *ret_syntax, geo_err *err);
int proto_json_write(const geo_poly *p, proto_buf *buf, geo_err *err);

geo_poly *proto_polytxt_read(const void *data, size_t len,
                             const proto_limits *lim, proto_read_report *rep,
                             geo_err *err);
int proto_polytxt_write(const geo_poly *p, proto_buf *buf, geo_err *err);

geo_poly *proto_obj_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err);
int proto_obj_write(const geo_poly *p, proto_buf *buf, geo_err *err);

geo_poly *proto_stl_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err);
int proto_stl_write(const geo_poly *p, bool ascii, proto_buf *buf,
                    geo_err *err);

geo_poly *proto_ply_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err);
int proto_ply_write(const geo_poly *p, bool ascii, proto_buf *buf,
                    geo_err *err);

int proto_ase_write(const geo_poly *p, proto_buf *buf, geo_err *err);

geo_poly *proto_fmb1_read(const void *data, size_t len,
                          const proto_limits *lim, proto_read_report *rep,
                          geo_err *err);
int proto_fmb1_write(const geo_poly *p, proto_buf *buf, geo_err *err);

geo_poly *proto_off_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err);
int proto_off_write(const geo_poly *p, proto_buf *buf, geo_err *err);

geo_poly *proto_asc_read(const void *data, size_t len,
                         const proto_limits *lim, proto_read_report *rep,
                         geo_err *err);
int proto_asc_write(const geo_poly *p, proto_buf *buf, geo_err *err);

#endif
