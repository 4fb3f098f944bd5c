/* fsp.c — FSP/1 frame encoder, incremental decoder and payload codecs.
 *
 * Decoder invariants: buf[0 .. n) holds the bytes of at most one candidate
 * frame (never more than 16 + max_payload bytes), and, when n > 0, buf
 * starts with a prefix of "FSP1". Input is copied only as far as the
 * current candidate needs, so the buffer never grows beyond one frame
 * however the caller splits the stream. A rejected candidate loses only
 * its first byte; the rest is searched again for a frame start. */
#include "fsp.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "crc32.h"

static const uint8_t magic[4] = {'F', 'S', 'P', '1'};

static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}

static uint16_t get16(const uint8_t *p)
{
    return (uint16_t)(p[0] | (p[1] << 8));
}

static uint32_t get32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 |
           (uint32_t)p[3] << 24;
}

const char *proto_fsp_type_name(uint8_t type)
{
    switch (type) {
    case PROTO_FSP_HELLO: return "HELLO";
    case PROTO_FSP_GET_INFO: return "GET_INFO";
    case PROTO_FSP_START_SCAN: return "START_SCAN";
    case PROTO_FSP_ACK: return "ACK";
    case PROTO_FSP_NAK: return "NAK";
    case PROTO_FSP_ABORT: return "ABORT";
    case PROTO_FSP_RESULT: return "RESULT";
    case PROTO_FSP_INFO: return "INFO";
    case PROTO_FSP_SCAN_STARTED: return "SCAN_STARTED";
    case PROTO_FSP_PROGRESS: return "PROGRESS";
    case PROTO_FSP_MODEL: return "MODEL";
    case PROTO_FSP_SCAN_DONE: return "SCAN_DONE";
    case PROTO_FSP_ERROR: return "ERROR";
    default: return "unknown";
    }
}

bool proto_fsp_type_known(uint8_t type)
{
    return strcmp(proto_fsp_type_name(type), "unknown") != 0;
}

int proto_fsp_encode(uint8_t type, uint16_t seq, const void *payload,
                     size_t len, uint8_t *out, size_t cap, size_t *ret_size)
{
    if (len > PROTO_FSP_MAX_PAYLOAD)
        return -EMSGSIZE;
    if (cap < len + PROTO_FSP_OVERHEAD)
        return -ENOBUFS;
    memcpy(out, magic, 4);
    out[4] = type;
    out[5] = 0;
    put16(out + 6, seq);
    put32(out + 8, (uint32_t)len);
    if (len)
        memcpy(out + PROTO_FSP_HEADER_SIZE, payload, len);
    put32(out + PROTO_FSP_HEADER_SIZE + len,
          proto_crc32(out, PROTO_FSP_HEADER_SIZE + len));
    *ret_size = len + PROTO_FSP_OVERHEAD;
    return 0;
}

/* --- decoder ------------------------------------------------------------ */

struct proto_fsp_decoder {
    uint8_t *buf;
    size_t n;
    uint32_t max_payload;
    size_t consume;    /* bytes of the frame returned last, dropped next call */
    bool out_of_step;  /* a loss of sync was already reported */
    uint64_t skipped;
};

proto_fsp_decoder *proto_fsp_decoder_new(uint32_t max_payload)
{
    if (max_payload == 0 || max_payload > PROTO_FSP_MAX_PAYLOAD)
        max_payload = PROTO_FSP_MAX_PAYLOAD;
    proto_fsp_decoder *d = calloc(1, sizeof *d);
    if (!d)
        return NULL;
    d->buf = malloc((size_t)max_payload + PROTO_FSP_OVERHEAD);
    if (!d->buf) {
        free(d);
        return NULL;
    }
    d->max_payload = max_payload;
    return d;
}

proto_fsp_decoder *proto_fsp_decoder_free(proto_fsp_decoder *d)
{
    if (d) {
        free(d->buf);
        free(d);
    }
    return NULL;
}

void proto_fsp_decoder_reset(proto_fsp_decoder *d)
{
    d->n = 0;
    d->consume = 0;
    d->out_of_step = false;
}

uint64_t proto_fsp_decoder_skipped(const proto_fsp_decoder *d)
{
    return d->skipped;
}

static void drop(proto_fsp_decoder *d, size_t k)
{
    memmove(d->buf, d->buf + k, d->n - k);
    d->n -= k;
}

/* True when p[0 .. n) agrees with "FSP1" on their common length. */
static bool magic_prefix(const uint8_t *p, size_t n)
{
    return memcmp(p, magic, n < 4 ? n : 4) == 0;
}

static void claimed_header(const proto_fsp_decoder *d, proto_fsp_event *ev,
                           proto_fsp_event_kind kind)
{
    ev->kind = kind;
    ev->frame.type = d->buf[4];
    ev->frame.flags = d->buf[5];
    ev->frame.seq = get16(d->buf + 6);
    ev->frame.len = get32(d->buf + 8);
    ev->frame.payload = NULL;
}

/* Skips leading bytes of buf that cannot start a frame. Returns true when
 * this is a new loss of sync that must be reported. */
static bool resync_buffer(proto_fsp_decoder *d)
{
    size_t k = 0;
    while (k < d->n && !magic_prefix(d->buf + k, d->n - k))
        k++;
    if (k == 0)
        return false;
    drop(d, k);
    d->skipped += k;
    if (d->out_of_step)
        return false;
    d->out_of_step = true;
    return true;
}

/* Rejects the candidate at the start of buf: its first byte goes, the
 * rest will be searched again. */
static void reject(proto_fsp_decoder *d)
{
    drop(d, 1);
    d->skipped++;
    d->out_of_step = true;
}

size_t proto_fsp_decode(proto_fsp_decoder *d, const uint8_t *data, size_t len,
                        proto_fsp_event *ev)
{
    size_t used = 0;
    memset(ev, 0, sizeof *ev);
    if (d->consume) {
        drop(d, d->consume);
        d->consume = 0;
    }
    for (;;) {
        if (resync_buffer(d)) {
            ev->kind = PROTO_FSP_EV_BAD_MAGIC;
            return used;
        }
        size_t need = PROTO_FSP_HEADER_SIZE;
        if (d->n >= PROTO_FSP_HEADER_SIZE) {
            uint32_t plen = get32(d->buf + 8);
            if (plen > d->max_payload) {
                claimed_header(d, ev, PROTO_FSP_EV_TOO_LONG);
                reject(d);
                return used;
            }
            need = (size_t)plen + PROTO_FSP_OVERHEAD;
            if (d->n >= need) {
                size_t body = PROTO_FSP_HEADER_SIZE + plen;
                if (get32(d->buf + body) != proto_crc32(d->buf, body)) {
                    claimed_header(d, ev, PROTO_FSP_EV_BAD_CRC);
                    reject(d);
                    return used;
                }
                claimed_header(d, ev, PROTO_FSP_EV_FRAME);
                ev->frame.payload = d->buf + PROTO_FSP_HEADER_SIZE;
                d->consume = need;
                d->out_of_step = false;
                return used;
            }
        }
        if (used == len)
            return used;
        if (d->n == 0) {
            /* Out of step with nothing buffered: skip input that cannot
             * start a frame without copying it. */
            const uint8_t *f = memchr(data + used, 'F', len - used);
            size_t k = f ? (size_t)(f - (data + used)) : len - used;
            if (k) {
                used += k;
                d->skipped += k;
                if (!d->out_of_step) {
                    d->out_of_step = true;
                    ev->kind = PROTO_FSP_EV_BAD_MAGIC;
                    return used;
                }
                continue;
            }
        }
        size_t take = need - d->n;
        if (take > len - used)
            take = len - used;
        memcpy(d->buf + d->n, data + used, take);
        d->n += take;
        used += take;
    }
}

/* --- fixed-size payloads -------------------------------------------------- */

static int expect(const proto_fsp_frame *f, uint8_t type, size_t len,
                  geo_err *err)
{
    const char *name = proto_fsp_type_name(type);
    if (f->type != type)
        return geo_err_set(err, -EINVAL, "%s: frame is %s", name,
                           proto_fsp_type_name(f->type));
    if (f->len != len)
        return geo_err_set(err, -EINVAL,
                           "%s: payload %u bytes, expected %zu", name,
                           f->len, len);
    return 0;
}

size_t proto_fsp_build_seq(uint8_t out[2], uint16_t seq)
{
    put16(out, seq);
    return 2;
}

int proto_fsp_parse_seq(const proto_fsp_frame *f, uint16_t *ret_seq,
                        geo_err *err)
{
    if (f->type != PROTO_FSP_ACK && f->type != PROTO_FSP_NAK)
        return geo_err_set(err, -EINVAL, "ACK/NAK: frame is %s",
                           proto_fsp_type_name(f->type));
    if (f->len != 2)
        return geo_err_set(err, -EINVAL, "%s: payload %u bytes, expected 2",
                           proto_fsp_type_name(f->type), f->len);
    *ret_seq = get16(f->payload);
    return 0;
}

size_t proto_fsp_build_start_scan(uint8_t out[1], uint8_t mode)
{
    out[0] = mode;
    return 1;
}

int proto_fsp_parse_start_scan(const proto_fsp_frame *f, uint8_t *ret_mode,
                               geo_err *err)
{
    int r = expect(f, PROTO_FSP_START_SCAN, 1, err);
    if (r < 0)
        return r;
    if (f->payload[0] > PROTO_FSP_MODE_HI_ACCURACY)
        return geo_err_set(err, -EINVAL, "START_SCAN: mode %u (0..2)",
                           f->payload[0]);
    *ret_mode = f->payload[0];
    return 0;
}

size_t proto_fsp_build_scan_started(uint8_t out[5],
                                    const proto_fsp_scan_started *s)
{
    out[0] = s->mode;
    put32(out + 1, s->contours);
    return 5;
}

int proto_fsp_parse_scan_started(const proto_fsp_frame *f,
                                 proto_fsp_scan_started *ret, geo_err *err)
{
    int r = expect(f, PROTO_FSP_SCAN_STARTED, 5, err);
    if (r < 0)
        return r;
    if (f->payload[0] > PROTO_FSP_MODE_HI_ACCURACY)
        return geo_err_set(err, -EINVAL, "SCAN_STARTED: mode %u (0..2)",
                           f->payload[0]);
    ret->mode = f->payload[0];
    ret->contours = get32(f->payload + 1);
    return 0;
}

size_t proto_fsp_build_progress(uint8_t out[8], const proto_fsp_progress *p)
{
    put32(out, p->done);
    put32(out + 4, p->total);
    return 8;
}

int proto_fsp_parse_progress(const proto_fsp_frame *f,
                             proto_fsp_progress *ret, geo_err *err)
{
    int r = expect(f, PROTO_FSP_PROGRESS, 8, err);
    if (r < 0)
        return r;
    uint32_t done = get32(f->payload), total = get32(f->payload + 4);
    if (done > total)
        return geo_err_set(err, -EINVAL, "PROGRESS: done %u > total %u",
                           done, total);
    ret->done = done;
    ret->total = total;
    return 0;
}

size_t proto_fsp_build_model(uint8_t *out, uint32_t total, uint32_t offset,
                             const uint8_t *bytes, uint32_t len)
{
    put32(out, total);
    put32(out + 4, offset);
    if (len)
        memcpy(out + 8, bytes, len);
    return 8 + (size_t)len;
}

int proto_fsp_parse_model(const proto_fsp_frame *f,
                          proto_fsp_model_chunk *ret, geo_err *err)
{
    if (f->type != PROTO_FSP_MODEL)
        return geo_err_set(err, -EINVAL, "MODEL: frame is %s",
                           proto_fsp_type_name(f->type));
    if (f->len < 9)
        return geo_err_set(err, -EINVAL,
                           "MODEL: payload %u bytes, expected at least 9",
                           f->len);
    uint32_t total = get32(f->payload), offset = get32(f->payload + 4);
    uint32_t n = f->len - 8;
    if (n > PROTO_FSP_MODEL_CHUNK_MAX)
        return geo_err_set(err, -EINVAL,
                           "MODEL: %u model bytes in one frame (at most %d)",
                           n, PROTO_FSP_MODEL_CHUNK_MAX);
    if (offset > total || n > total - offset)
        return geo_err_set(err, -EINVAL,
                           "MODEL: offset %u + %u bytes beyond total %u",
                           offset, n, total);
    ret->total = total;
    ret->offset = offset;
    ret->len = n;
    ret->bytes = f->payload + 8;
    return 0;
}

size_t proto_fsp_build_scan_done(uint8_t out[9], const proto_fsp_scan_done *d)
{
    put32(out, d->total);
    put32(out + 4, d->crc);
    out[8] = d->format;
    return 9;
}

int proto_fsp_parse_scan_done(const proto_fsp_frame *f,
                              proto_fsp_scan_done *ret, geo_err *err)
{
    int r = expect(f, PROTO_FSP_SCAN_DONE, 9, err);
    if (r < 0)
        return r;
    if (f->payload[8] > PROTO_FSP_MODEL_FMB1)
        return geo_err_set(err, -EINVAL, "SCAN_DONE: format %u (0..1)",
                           f->payload[8]);
    ret->total = get32(f->payload);
    ret->crc = get32(f->payload + 4);
    ret->format = f->payload[8];
    return 0;
}

/* --- text ------------------------------------------------------------------ */

/* Length of the UTF-8 sequence starting at s[0 .. n), or 0 when it is not
 * a well-formed, shortest-form, non-surrogate character or is a NUL. */
static size_t utf8_char(const uint8_t *s, size_t n)
{
    uint8_t c = s[0];
    size_t len;
    uint32_t cp;
    if (c == 0)
        return 0;
    if (c < 0x80)
        return 1;
    if ((c & 0xe0) == 0xc0) {
        len = 2;
        cp = c & 0x1f;
    } else if ((c & 0xf0) == 0xe0) {
        len = 3;
        cp = c & 0x0f;
    } else if ((c & 0xf8) == 0xf0) {
        len = 4;
        cp = c & 0x07;
    } else {
        return 0;
    }
    if (len > n)
        return 0;
    for (size_t i = 1; i < len; i++) {
        if ((s[i] & 0xc0) != 0x80)
            return 0;
        cp = cp << 6 | (s[i] & 0x3f);
    }
    static const uint32_t min_cp[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < min_cp[len] || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff))
        return 0;
    return len;
}

/* Length of the longest prefix of s[0 .. n) that is whole characters and
 * at most cap bytes; *ok is false when s is not valid UTF-8 throughout. */
static size_t utf8_prefix(const uint8_t *s, size_t n, size_t cap, bool *ok)
{
    size_t i = 0, fit = 0;
    *ok = true;
    while (i < n) {
        size_t k = utf8_char(s + i, n - i);
        if (k == 0) {
            *ok = false;
            break;
        }
        i += k;
        if (i <= cap)
            fit = i;
    }
    return fit;
}

size_t proto_fsp_build_error(uint8_t *out, size_t cap, uint16_t code,
                             const char *msg)
{
    if (cap < 2)
        return 0;
    put16(out, code);
    size_t n = msg ? strlen(msg) : 0;
    bool ok;
    size_t fit = utf8_prefix((const uint8_t *)msg, n, cap - 2, &ok);
    if (fit)
        memcpy(out + 2, msg, fit);
    return 2 + fit;
}

int proto_fsp_parse_error(const proto_fsp_frame *f, uint16_t *ret_code,
                          char *msg, size_t msg_cap, geo_err *err)
{
    if (f->type != PROTO_FSP_ERROR)
        return geo_err_set(err, -EINVAL, "ERROR: frame is %s",
                           proto_fsp_type_name(f->type));
    if (f->len < 2)
        return geo_err_set(err, -EINVAL,
                           "ERROR: payload %u bytes, expected at least 2",
                           f->len);
    bool ok;
    size_t fit = utf8_prefix(f->payload + 2, f->len - 2,
                             msg_cap ? msg_cap - 1 : 0, &ok);
    if (!ok)
        return geo_err_set(err, -EINVAL,
                           "ERROR: message is not UTF-8 text");
    *ret_code = get16(f->payload);
    if (msg_cap) {
        memcpy(msg, f->payload + 2, fit);
        msg[fit] = '\0';
    }
    return 0;
}

/* --- JSON payloads -------------------------------------------------------- */

static json_t *load_object(const proto_fsp_frame *f, uint8_t type,
                           geo_err *err)
{
    const char *name = proto_fsp_type_name(type);
    if (f->type != type) {
        geo_err_set(err, -EINVAL, "%s: frame is %s", name,
                    proto_fsp_type_name(f->type));
        return NULL;
    }
    json_error_t je;
    json_t *root = json_loadb((const char *)f->payload, f->len,
                              JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        geo_err_set(err, -EINVAL, "%s: byte %d: %s", name, je.position,
                    je.text);
        return NULL;
    }
    if (!json_is_object(root)) {
        json_decref(root);
        geo_err_set(err, -EINVAL, "%s: payload is not a JSON object", name);
        return NULL;
    }
    return root;
}

/* Copies the string member key of o into out[0 .. cap); required says
 * whether a missing key is an error (then out stays ""). */
static int get_text(const json_t *o, const char *type, const char *key,
                    char *out, size_t cap, bool required, geo_err *err)
{
    out[0] = '\0';
    json_t *v = json_object_get(o, key);
    if (!v) {
        if (required)
            return geo_err_set(err, -EINVAL, "%s.%s: missing", type, key);
        return 0;
    }
    if (!json_is_string(v))
        return geo_err_set(err, -EINVAL, "%s.%s: not a string", type, key);
    size_t n = json_string_length(v);
    if (n >= cap)
        return geo_err_set(err, -EINVAL, "%s.%s: %zu bytes (at most %zu)",
                           type, key, n, cap - 1);
    if (memchr(json_string_value(v), '\0', n))
        return geo_err_set(err, -EINVAL, "%s.%s: contains NUL", type, key);
    memcpy(out, json_string_value(v), n + 1);
    return 0;
}

static char *dump(json_t *o)
{
    if (!o)
        return NULL;
    char *s = json_dumps(o, JSON_COMPACT | JSON_ENSURE_ASCII);
    json_decref(o);
    return s;
}

char *proto_fsp_build_hello(const proto_fsp_hello *h)
{
    return dump(json_pack("{s:s, s:s}", "host", h->host, "version",
                          h->version));
}

int proto_fsp_parse_hello(const proto_fsp_frame *f, proto_fsp_hello *ret,
                          geo_err *err)
{
    json_t *o = load_object(f, PROTO_FSP_HELLO, err);
    if (!o)
        return -EINVAL;
    proto_fsp_hello h;
    int r = get_text(o, "HELLO", "host", h.host, sizeof h.host, true, err);
    if (r == 0)
        r = get_text(o, "HELLO", "version", h.version, sizeof h.version,
                     true, err);
    json_decref(o);
    if (r == 0)
        *ret = h;
    return r;
}

bool proto_fsp_serial_valid(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n > PROTO_FSP_TEXT_MAX)
        return false;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') ||
                  (c >= '0' && c <= '9') || c == '.' || c == '_' ||
                  c == ':' || c == '-';
        if (!ok)
            return false;
    }
    return true;
}

char *proto_fsp_build_info(const proto_fsp_info *info)
{
    if (!proto_fsp_serial_valid(info->serial))
        return NULL;
    return dump(json_pack("{s:s, s:s, s:s, s:s, s:I}", "vendor", info->vendor,
                          "model", info->model, "serial", info->serial,
                          "firmware", info->firmware, "contours",
                          (json_int_t)info->contours));
}

int proto_fsp_parse_info(const proto_fsp_frame *f, proto_fsp_info *ret,
                         geo_err *err)
{
    json_t *o = load_object(f, PROTO_FSP_INFO, err);
    if (!o)
        return -EINVAL;
    proto_fsp_info in;
    int r = get_text(o, "INFO", "vendor", in.vendor, sizeof in.vendor, true,
                     err);
    if (r == 0)
        r = get_text(o, "INFO", "model", in.model, sizeof in.model, true,
                     err);
    if (r == 0)
        r = get_text(o, "INFO", "serial", in.serial, sizeof in.serial, true,
                     err);
    if (r == 0)
        r = get_text(o, "INFO", "firmware", in.firmware, sizeof in.firmware,
                     true, err);
    if (r == 0 && !proto_fsp_serial_valid(in.serial))
        r = geo_err_set(err, -EINVAL,
                        "INFO.serial: \"%s\" is not 1..63 characters of "
                        "[A-Za-z0-9._:-]", in.serial);
    if (r == 0) {
        json_t *c = json_object_get(o, "contours");
        if (!json_is_integer(c) || json_integer_value(c) < 0 ||
            json_integer_value(c) > UINT32_MAX)
            r = geo_err_set(err, -EINVAL,
                            "INFO.contours: missing or not an integer in "
                            "0..4294967295");
        else
            in.contours = (uint32_t)json_integer_value(c);
    }
    json_decref(o);
    if (r == 0)
        *ret = in;
    return r;
}

static json_t *count_or_null(int64_t v)
{
    return v < 0 ? json_null() : json_integer((json_int_t)v);
}

char *proto_fsp_build_result(const proto_fsp_result *r)
{
    return dump(json_pack("{s:s, s:s, s:s, s:o, s:o, s:b, s:o}", "job",
                          r->job, "state", r->state, "url", r->url,
                          "facets_before", count_or_null(r->facets_before),
                          "facets_after", count_or_null(r->facets_after),
                          "valid", r->valid, "self_intersections",
                          count_or_null(r->self_intersections)));
}

static int get_count(const json_t *o, const char *key, int64_t *ret,
                     geo_err *err)
{
    json_t *v = json_object_get(o, key);
    if (json_is_null(v)) {
        *ret = -1;
        return 0;
    }
    if (!json_is_integer(v) || json_integer_value(v) < 0)
        return geo_err_set(err, -EINVAL,
                           "RESULT.%s: missing or not a count", key);
    *ret = json_integer_value(v);
    return 0;
}

int proto_fsp_parse_result(const proto_fsp_frame *f, proto_fsp_result *ret,
                           geo_err *err)
{
    json_t *o = load_object(f, PROTO_FSP_RESULT, err);
    if (!o)
        return -EINVAL;
    proto_fsp_result res;
    int r = get_text(o, "RESULT", "job", res.job, sizeof res.job, true, err);
    if (r == 0)
        r = get_text(o, "RESULT", "state", res.state, sizeof res.state, true,
                     err);
    if (r == 0)
        r = get_text(o, "RESULT", "url", res.url, sizeof res.url, true, err);
    if (r == 0)
        r = get_count(o, "facets_before", &res.facets_before, err);
    if (r == 0)
        r = get_count(o, "facets_after", &res.facets_after, err);
    if (r == 0)
        r = get_count(o, "self_intersections", &res.self_intersections, err);
    if (r == 0) {
        json_t *v = json_object_get(o, "valid");
        if (!json_is_boolean(v))
            r = geo_err_set(err, -EINVAL,
                            "RESULT.valid: missing or not a boolean");
        else
            res.valid = json_is_true(v);
    }
    json_decref(o);
    if (r == 0)
        *ret = res;
    return r;
}
