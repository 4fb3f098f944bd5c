/* model_fmb1.c — FMB1, the scanner's binary model (formats.md, "Model
 * bytes"): "FMB1", u32 vertex count, u32 facet count, every vertex as
 * 3 × f64, then per facet u16 n, its plane as 4 × f64 (a, b, c, d; unit
 * outward normal) and n × u32 vertex indices. All little-endian, f64 =
 * IEEE-754 binary64, millimetres. A round trip is bit-exact.
 *
 * Reading makes a first pass over the facets that checks every length
 * against the bytes present (a header may claim any counts: a 20-byte
 * file claiming 2^31 vertices fails at once, before allocating) and counts
 * the corners; the second pass fills an exactly sized model. Trailing
 * bytes after the last facet are an error. Errors name the byte offset:
 * "byte 1234: facets[5].vertices[2]: index 9001 out of range (8000
 * vertices)". Given planes are checked like facet-model/1's. */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "model_codec.h"

enum { HEAD = 12, VERT = 24, FACET_HEAD = 34 };

geo_poly *proto_fmb1_read(const void *data, size_t len,
                          const proto_limits *lim, proto_read_report *rep,
                          geo_err *err)
{
    const unsigned char *d = data;
    if (len < HEAD || memcmp(d, "FMB1", 4) != 0) {
        geo_err_set(err, -EINVAL, "byte 0: not an FMB1 model (expected "
                                  "\"FMB1\" and two counts)");
        return NULL;
    }
    uint32_t nv = proto_ld_u32le(d + 4), nf = proto_ld_u32le(d + 8);
    if (proto_check_limits(lim, nv, nf, 0, err) < 0) {
        geo_err_prefix(err, "byte 4");
        return NULL;
    }
    uint64_t vend = HEAD + (uint64_t)nv * VERT;
    if (vend + (uint64_t)nf * (FACET_HEAD + 12) > len) {
        geo_err_set(err, -EINVAL,
                    "byte 4: %u vertices and %u facets need at least %llu "
                    "bytes, the model has %zu (truncated?)", nv, nf,
                    (unsigned long long)(vend + (uint64_t)nf *
                                                    (FACET_HEAD + 12)),
                    len);
        return NULL;
    }
    /* first pass: lengths and the corner count */
    uint64_t nc = 0;
    size_t o = (size_t)vend;
    for (uint32_t f = 0; f < nf; f++) {
        if (len - o < FACET_HEAD) {
            geo_err_set(err, -EINVAL, "byte %zu: facets[%u]: the model ends "
                                      "inside the facet", o, f);
            return NULL;
        }
        uint16_t n = proto_ld_u16le(d + o);
        if (n < 3) {
            geo_err_set(err, -EINVAL, "byte %zu: facets[%u]: %u vertices, a "
                                      "facet needs at least 3", o, f, n);
            return NULL;
        }
        if (len - o - FACET_HEAD < 4 * (size_t)n) {
            geo_err_set(err, -EINVAL, "byte %zu: facets[%u]: %u indices do "
                                      "not fit in the remaining %zu bytes", o,
                        f, n, len - o - FACET_HEAD);
            return NULL;
        }
        nc += n;
        o += FACET_HEAD + 4 * (size_t)n;
    }
    if (o != len) {
        geo_err_set(err, -EINVAL, "byte %zu: %zu bytes after the last facet",
                    o, len - o);
        return NULL;
    }
    if (proto_check_limits(lim, nv, nf, nc, err) < 0) {
        geo_err_prefix(err, "byte 8");
        return NULL;
    }
    bool *given = NULL;
    geo_poly *p = proto_poly_alloc(nv, nf, nc, &given, err);
    if (!p)
        return NULL;
    for (uint32_t i = 0; i < nv; i++)
        for (int k = 0; k < 3; k++) {
            size_t at = HEAD + (size_t)i * VERT + 8 * (size_t)k;
            p->verts[i][k] = proto_ld_f64le(d + at);
            if (!isfinite(p->verts[i][k])) {
                geo_err_set(err, -EINVAL, "byte %zu: vertices[%u][%d]: not a "
                                          "finite number", at, i, k);
                goto fail;
            }
        }
    p->nverts = nv;
    o = (size_t)vend;
    for (uint32_t f = 0; f < nf; f++) {
        uint16_t n = proto_ld_u16le(d + o);
        for (int k = 0; k < 4; k++) {
            size_t at = o + 2 + 8 * (size_t)k;
            p->planes[f][k] = proto_ld_f64le(d + at);
            if (!isfinite(p->planes[f][k])) {
                geo_err_set(err, -EINVAL, "byte %zu: facets[%u].plane[%d]: "
                                          "not a finite number", at, f, k);
                goto fail;
            }
        }
        uint32_t c0 = p->fstart[f], *dst = p->fidx + c0;
        for (uint32_t i = 0; i < n; i++) {
            size_t at = o + FACET_HEAD + 4 * (size_t)i;
            dst[i] = proto_ld_u32le(d + at);
            if (dst[i] >= nv) {
                geo_err_set(err, -EINVAL, "byte %zu: facets[%u].vertices[%u]: "
                                          "index %u out of range (%u "
                                          "vertices)", at, f, i, dst[i], nv);
                goto fail;
            }
            if (i > 0 && dst[i] == dst[i - 1]) {
                geo_err_set(err, -EINVAL, "byte %zu: facets[%u].vertices[%u]: "
                                          "index %u repeated consecutively",
                            at, f, i, dst[i]);
                goto fail;
            }
        }
        if (dst[0] == dst[n - 1]) {
            geo_err_set(err, -EINVAL, "byte %zu: facets[%u].vertices[0]: "
                                      "index %u repeated consecutively",
                        o + FACET_HEAD, f, dst[0]);
            goto fail;
        }
        p->fstart[f + 1] = c0 + n;
        p->nfacets = f + 1;
        given[f] = true;
        o += FACET_HEAD + 4 * (size_t)n;
    }
    return proto_read_done(p, given, lim, rep, err);
fail:
    free(given);
    return geo_poly_free(p);
}

int proto_fmb1_check(const geo_poly *p, geo_err *err)
{
    /* the counts are u32 like geo_poly's; a facet's length is u16 */
    for (uint32_t f = 0; f < p->nfacets; f++)
        if (geo_poly_facet_size(p, f) > UINT16_MAX)
            return geo_err_set(err, -ERANGE, "facets[%u]: %u vertices, FMB1 "
                                             "holds at most 65535 per facet",
                               f, geo_poly_facet_size(p, f));
    return 0;
}

int proto_fmb1_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    int r = proto_fmb1_check(p, err);
    if (r < 0)
        return r;
    size_t size = HEAD + (size_t)p->nverts * VERT +
                  (size_t)p->nfacets * FACET_HEAD +
                  4 * (size_t)geo_poly_ncorners(p);
    unsigned char *o = proto_buf_grow(b, size);
    if (!o)
        return 0; /* b->failed tells */
    memcpy(o, "FMB1", 4);
    proto_st_u32le(o + 4, p->nverts);
    proto_st_u32le(o + 8, p->nfacets);
    o += HEAD;
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++, o += 8)
            proto_st_f64le(o, p->verts[i][k]);
    for (uint32_t f = 0; f < p->nfacets; f++) {
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *v = geo_poly_facet(p, f);
        proto_st_u16le(o, (uint16_t)n);
        o += 2;
        for (int k = 0; k < 4; k++, o += 8)
            proto_st_f64le(o, p->planes[f][k]);
        for (uint32_t i = 0; i < n; i++, o += 4)
            proto_st_u32le(o, v[i]);
    }
    return 0;
}
