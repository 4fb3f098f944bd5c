/* json_pull.c — the JSON pull tokenizer (json_pull.h).
 *
 * Two layers: lex() reads one token from the bytes (whitespace, strings
 * with their escapes and UTF-8, numbers, literals) and the state machine
 * of proto_jpull_next() checks the grammar between tokens.
 *
 * Error compatibility with jansson rests on three rules, each followed at
 * every error site:
 * - the context ("near '...'") is the token's raw bytes read so far: the
 *   whole token for grammar errors, the part before the offending byte
 *   for errors inside a token, nothing for a bad byte between tokens;
 *   printed only when it is 1–20 bytes long and does not start with NUL
 *   ("near end of file" when there is none, except after a UTF-8 error);
 * - the position is where reading stopped: after the token, or before
 *   the byte that cannot be part of it (a UTF-8 error stops before the
 *   bad sequence), or after a bad escape character;
 * - a UTF-8 sequence is checked wherever jansson reads it: inside strings,
 *   at the start of a token, and at the byte after a number or a literal
 *   (the look-ahead that ends them).
 * Line and column are computed from the position only when an error is
 * reported. Invariant of the state machine: state says what may come
 * next, kinds[0..depth) are the open containers. */
#include "json_pull.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "decimal.h"
#include "json_digits.h"

enum {
    TK_FAILED = -1, /* the lexer reported an error */
    TK_EOF = 0,
    TK_LBRACE, TK_RBRACE, TK_LBRACKET, TK_RBRACKET, TK_COLON, TK_COMMA,
    TK_STRING, TK_INTEGER, TK_REAL, TK_TRUE, TK_FALSE, TK_NULL,
    TK_INVALID, /* not a token; the grammar layer says "invalid token" */
};

enum {
    ST_START,     /* nothing read yet */
    ST_VALUE,     /* after ':' */
    ST_ARR_FIRST, /* after '[' */
    ST_ARR_NEXT,  /* after ',' in an array */
    ST_OBJ_FIRST, /* after '{' */
    ST_OBJ_NEXT,  /* after ',' in an object */
    ST_AFTER,     /* after a value */
    ST_DONE,
    ST_FAILED,
};

enum { K_OBJECT = 1, K_ARRAY = 2 };

/* A member name of an object: its bytes are arena[off, off + len). */
typedef struct proto_jkey {
    uint64_t hash; /* 0 marks an empty slot */
    uint32_t serial, len;
    size_t off;
} proto_jkey;

void proto_jpull_init(proto_jpull *j, const void *data, size_t len)
{
    memset(j, 0, sizeof *j);
    j->data = data ? data : (const unsigned char *)"";
    j->len = len;
    j->state = ST_START;
    j->str = "";
    j->behind_next = PROTO_JPULL_BEHIND_STEP;
}

void proto_jpull_clear(proto_jpull *j)
{
    free(j->kinds);
    free(j->serials);
    free(j->sbuf);
    free(j->keys);
    free(j->arena);
    free(j->log);
    free(j->marks);
    memset(j, 0, sizeof *j);
    j->state = ST_FAILED;
}

/* Line and column of a position, counted as jansson counts them. */
static void locate(const unsigned char *d, size_t pos, int *ret_line,
                   int *ret_col)
{
    int line = 1;
    size_t start = 0;
    const unsigned char *nl;
    while (start < pos && (nl = memchr(d + start, '\n', pos - start))) {
        line++;
        start = (size_t)(nl - d) + 1;
    }
    int col = 0;
    for (size_t i = start; i < pos; i++)
        col += d[i] < 0x80 || (d[i] >= 0xC2 && d[i] <= 0xF4);
    *ret_line = line;
    *ret_col = col;
}

/* Records an error stopping at pos with context [cs, ce); after_utf8
 * marks a bad UTF-8 sequence (no "near end of file"). */
static int fail_at(proto_jpull *j, size_t pos, size_t cs, size_t ce,
                   bool after_utf8, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));

static int fail_at(proto_jpull *j, size_t pos, size_t cs, size_t ce,
                   bool after_utf8, const char *fmt, ...)
{
    /* every message is short, so message + context fit the 160 bytes */
    char msg[128];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    const char *ctx = (const char *)j->data + cs;
    size_t clen = ce - cs, shown = strnlen(ctx, clen);
    proto_jerror *e = &j->error;
    if (shown > 0) {
        if (clen <= 20)
            snprintf(e->text, sizeof e->text, "%s near '%.*s'", msg,
                     (int)(shown < 20 ? shown : 20), ctx);
        else
            snprintf(e->text, sizeof e->text, "%s", msg);
    } else if (after_utf8) {
        snprintf(e->text, sizeof e->text, "%s", msg);
    } else {
        snprintf(e->text, sizeof e->text, "%s near end of file", msg);
    }
    e->code = -EINVAL;
    e->position = pos;
    locate(j->data, pos, &e->line, &e->column);
    j->pos = pos;
    j->state = ST_FAILED;
    return TK_FAILED;
}

static int fail_oom(proto_jpull *j)
{
    proto_jerror *e = &j->error;
    e->code = -ENOMEM;
    e->position = j->pos;
    locate(j->data, j->pos, &e->line, &e->column);
    snprintf(e->text, sizeof e->text, "out of memory");
    j->state = ST_FAILED;
    return TK_FAILED;
}

/* A grammar error about the token just read. */
static proto_jtok fail_token(proto_jpull *j, const char *what)
{
    fail_at(j, j->pos, j->tok_start, j->tok_end, false, "%s", what);
    return PROTO_JT_ERROR;
}

/* Length of the valid UTF-8 sequence of 2–4 bytes at s (avail bytes
 * there), or 0: no overlong forms, no surrogates, nothing above
 * U+10FFFF. */
static size_t utf8_seq(const unsigned char *s, size_t avail)
{
    unsigned c = s[0];
    size_t n;
    uint32_t cp;
    if (c >= 0xC2 && c <= 0xDF) {
        n = 2;
        cp = c & 0x1F;
    } else if (c >= 0xE0 && c <= 0xEF) {
        n = 3;
        cp = c & 0x0F;
    } else if (c >= 0xF0 && c <= 0xF4) {
        n = 4;
        cp = c & 0x07;
    } else {
        return 0;
    }
    if (avail < n)
        return 0;
    for (size_t i = 1; i < n; i++) {
        if ((s[i] & 0xC0) != 0x80)
            return 0;
        cp = cp << 6 | (s[i] & 0x3F);
    }
    if (cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF) ||
        (n == 3 && cp < 0x800) || (n == 4 && cp < 0x10000))
        return 0;
    return n;
}

static int bad_utf8(proto_jpull *j, size_t pos, size_t ctx_start)
{
    return fail_at(j, pos, ctx_start, pos, true, "unable to decode byte 0x%x",
                   j->data[pos]);
}

/* The byte at p ends a number or a literal; jansson reads it (and the
 * rest of its UTF-8 sequence) before giving it back. */
static bool lookahead_ok(proto_jpull *j, size_t p, size_t start)
{
    if (p < j->len && j->data[p] >= 0x80 &&
        !utf8_seq(j->data + p, j->len - p)) {
        bad_utf8(j, p, start);
        return false;
    }
    return true;
}

static bool sbuf_reserve(proto_jpull *j, size_t more)
{
    if (more <= j->scap - j->slen)
        return true;
    size_t cap = j->scap ? j->scap : 256;
    while (cap - j->slen < more) {
        if (cap > SIZE_MAX / 2)
            return false;
        cap *= 2;
    }
    char *b = realloc(j->sbuf, cap);
    if (!b)
        return false;
    j->sbuf = b;
    j->scap = cap;
    return true;
}

static int hexval(unsigned c)
{
    if (c >= '0' && c <= '9')
        return (int)(c - '0');
    if (c >= 'a' && c <= 'f')
        return (int)(c - 'a' + 10);
    if (c >= 'A' && c <= 'F')
        return (int)(c - 'A' + 10);
    return -1;
}

static size_t utf8_put(char *o, uint32_t cp)
{
    if (cp < 0x80) {
        o[0] = (char)cp;
        return 1;
    }
    if (cp < 0x800) {
        o[0] = (char)(0xC0 | cp >> 6);
        o[1] = (char)(0x80 | (cp & 0x3F));
        return 2;
    }
    if (cp < 0x10000) {
        o[0] = (char)(0xE0 | cp >> 12);
        o[1] = (char)(0x80 | (cp >> 6 & 0x3F));
        o[2] = (char)(0x80 | (cp & 0x3F));
        return 3;
    }
    o[0] = (char)(0xF0 | cp >> 18);
    o[1] = (char)(0x80 | (cp >> 12 & 0x3F));
    o[2] = (char)(0x80 | (cp >> 6 & 0x3F));
    o[3] = (char)(0x80 | (cp & 0x3F));
    return 4;
}

/* A string starting with the quote at start. The text is checked in one
 * pass; a surrogate problem is remembered and reported once the closing
 * quote is found, as jansson decodes only a string it has fully read. */
static int lex_string(proto_jpull *j, size_t start)
{
    const unsigned char *d = j->data;
    size_t n = j->len, p = start + 1;
    j->slen = 0;
    j->has_nul = false;
    char bad_unicode[48] = "";
    uint32_t high = 0;   /* a high surrogate waiting for its low half */
    bool decoding = true; /* false once a surrogate problem was found */
    for (;;) {
        size_t q = p;
        while (q < n && d[q] >= 0x20 && d[q] < 0x80 && d[q] != '"' &&
               d[q] != '\\')
            q++;
        if (q > p) {
            if (high) {
                snprintf(bad_unicode, sizeof bad_unicode,
                         "invalid Unicode '\\u%04X'", (unsigned)high);
                high = 0;
                decoding = false;
            }
            if (decoding) {
                if (!sbuf_reserve(j, q - p))
                    return fail_oom(j);
                memcpy(j->sbuf + j->slen, d + p, q - p);
                j->slen += q - p;
            }
            p = q;
        }
        if (p >= n)
            return fail_at(j, n, start, n, false, "premature end of input");
        unsigned c = d[p];
        if (c == '"')
            break;
        if (c < 0x20)
            return fail_at(j, p, start, p, false,
                           c == '\n' ? "unexpected newline"
                                     : "control character 0x%x", c);
        if (high && (c != '\\' || p + 1 >= n || d[p + 1] != 'u')) {
            snprintf(bad_unicode, sizeof bad_unicode,
                     "invalid Unicode '\\u%04X'", (unsigned)high);
            high = 0;
            decoding = false;
        }
        if (c >= 0x80) {
            size_t l = utf8_seq(d + p, n - p);
            if (!l)
                return bad_utf8(j, p, start);
            if (decoding) {
                if (!sbuf_reserve(j, l))
                    return fail_oom(j);
                memcpy(j->sbuf + j->slen, d + p, l);
                j->slen += l;
            }
            p += l;
            continue;
        }
        /* a backslash */
        p++;
        if (p >= n)
            return fail_at(j, p, start, p, false, "invalid escape");
        c = d[p];
        if (c == 'u') {
            p++;
            uint32_t cp = 0;
            for (int i = 0; i < 4; i++) {
                if (p >= n)
                    return fail_at(j, p, start, p, false, "invalid escape");
                if (d[p] >= 0x80 && !utf8_seq(d + p, n - p))
                    return bad_utf8(j, p, start);
                int h = hexval(d[p]);
                if (h < 0)
                    return fail_at(j, p + 1, start, p + 1, false,
                                   "invalid escape");
                cp = cp << 4 | (uint32_t)h;
                p++;
            }
            if (!decoding)
                continue;
            if (high) {
                if (cp >= 0xDC00 && cp <= 0xDFFF) {
                    cp = ((high - 0xD800) << 10) + (cp - 0xDC00) + 0x10000;
                    high = 0;
                } else {
                    snprintf(bad_unicode, sizeof bad_unicode,
                             "invalid Unicode '\\u%04X\\u%04X'",
                             (unsigned)high, (unsigned)cp);
                    high = 0;
                    decoding = false;
                    continue;
                }
            } else if (cp >= 0xD800 && cp <= 0xDBFF) {
                high = cp;
                continue;
            } else if (cp >= 0xDC00 && cp <= 0xDFFF) {
                snprintf(bad_unicode, sizeof bad_unicode,
                         "invalid Unicode '\\u%04X'", (unsigned)cp);
                decoding = false;
                continue;
            }
            if (!sbuf_reserve(j, 4))
                return fail_oom(j);
            j->slen += utf8_put(j->sbuf + j->slen, cp);
            j->has_nul |= cp == 0;
            continue;
        }
        char out;
        switch (c) {
        case '"': case '\\': case '/':
            out = (char)c;
            break;
        case 'b':
            out = '\b';
            break;
        case 'f':
            out = '\f';
            break;
        case 'n':
            out = '\n';
            break;
        case 'r':
            out = '\r';
            break;
        case 't':
            out = '\t';
            break;
        default:
            if (c >= 0x80 && !utf8_seq(d + p, n - p))
                return bad_utf8(j, p, start);
            return fail_at(j, p + 1, start, p + 1, false, "invalid escape");
        }
        p++;
        if (decoding) {
            if (!sbuf_reserve(j, 1))
                return fail_oom(j);
            j->sbuf[j->slen++] = out;
        }
    }
    p++; /* the closing quote */
    if (high)
        snprintf(bad_unicode, sizeof bad_unicode, "invalid Unicode '\\u%04X'",
                 (unsigned)high);
    j->tok_end = j->pos = p;
    if (bad_unicode[0])
        return fail_at(j, p, start, p, false, "%s", bad_unicode);
    if (!sbuf_reserve(j, 1))
        return fail_oom(j);
    j->sbuf[j->slen] = '\0';
    j->str = j->sbuf;
    j->str_len = j->slen;
    return TK_STRING;
}

static bool is_digit(unsigned c)
{
    return c - '0' < 10;
}

/* True when all eight bytes of v are ASCII digits. */
static bool eight_digits(uint64_t v)
{
    return proto_nondigits(v) == 0;
}

/* What scan_number found. */
enum { SN_INTEGER, SN_REAL, SN_INVALID, SN_TOO_BIG };

typedef struct number_scan {
    int kind;
    size_t end;        /* where the scan stopped */
    bool neg, dropped; /* dropped: a non-zero digit beyond the 19 kept */
    uint64_t w;        /* the value is ±w·10^q */
    int64_t q;
} number_scan;

/* The grammar of a number starting at start ('-' or a digit), as jansson
 * reads it: "-" or "01" or "1." or "1e" are not numbers (SN_INVALID where
 * the grammar fails), an integer of more than 63 bits is SN_TOO_BIG. The
 * digits are gathered in the same pass (w·10^q, as proto/decimal.h wants
 * them). Wherever it stops, the byte there is the number's look-ahead. */
static inline __attribute__((always_inline)) void
scan_number(const unsigned char *d, size_t n, size_t start, number_scan *ret)
{
    size_t p = start;
    bool neg = d[p] == '-';
    if (neg)
        p++;
    uint64_t w = 0;
    int nd = 0;
    int64_t q = 0;
    bool dropped = false;
    *ret = (number_scan){.kind = SN_INVALID, .neg = neg};
    if (p < n && d[p] == '0') {
        p++;
    } else if (p < n && is_digit(d[p])) {
        /* eight digits at a time while they fit in w's 19 */
        uint64_t v;
        while (nd <= 11 && n - p >= 8 &&
               eight_digits(v = proto_load8(d + p))) {
            w = w * 100000000 + proto_eight_digits_value(v);
            nd += 8;
            p += 8;
        }
        while (p < n && is_digit(d[p])) {
            unsigned dg = d[p++] - '0';
            if (nd < 19) {
                w = w * 10 + dg;
                nd++;
            } else {
                q++;
                dropped |= dg != 0;
            }
        }
    } else {
        ret->end = p;
        return;
    }
    if (p < n && is_digit(d[p])) { /* a leading zero */
        ret->end = p;
        return;
    }
    if (p >= n || (d[p] != '.' && d[p] != 'e' && d[p] != 'E')) {
        ret->end = p;
        ret->w = w;
        /* at most 19 digits are in w; more overflow any int64 */
        ret->kind = q > 0 || w > (neg ? UINT64_C(1) << 63 : (uint64_t)INT64_MAX)
                        ? SN_TOO_BIG
                        : SN_INTEGER;
        return;
    }
    if (d[p] == '.') {
        p++;
        if (p >= n || !is_digit(d[p])) {
            ret->end = p;
            return;
        }
        uint64_t v;
        while (nd <= 11 && n - p >= 8 &&
               eight_digits(v = proto_load8(d + p))) {
            uint32_t x = proto_eight_digits_value(v);
            /* leading zeros of the fraction are not significant: the
             * first byte that is no '0' (v's lowest) starts the digits */
            uint64_t z = v ^ 0x3030303030303030u;
            nd += w ? 8 : z ? 8 - __builtin_ctzll(z) / 8 : 0;
            w = w * 100000000 + x;
            q -= 8;
            p += 8;
        }
        while (p < n && is_digit(d[p])) {
            unsigned dg = d[p++] - '0';
            if (nd < 19) {
                w = w * 10 + dg;
                nd += w != 0;
                q--;
            } else {
                dropped |= dg != 0;
            }
        }
    }
    if (p < n && (d[p] == 'e' || d[p] == 'E')) {
        p++;
        bool eneg = false;
        if (p < n && (d[p] == '+' || d[p] == '-'))
            eneg = d[p++] == '-';
        if (p >= n || !is_digit(d[p])) {
            ret->end = p;
            return;
        }
        int64_t ex = 0;
        do {
            if (ex < 1000000000)
                ex = ex * 10 + (d[p] - '0');
            p++;
        } while (p < n && is_digit(d[p]));
        q += eneg ? -ex : ex;
    }
    ret->end = p;
    ret->kind = SN_REAL;
    ret->w = w;
    ret->q = q;
    ret->dropped = dropped;
}

/* A number starting at start, read as jansson reads it: scan_number's
 * grammar, then the look-ahead byte checked as UTF-8 (wherever the scan
 * stopped: a byte of 0x80 or above can continue no part of a number),
 * then the verdict (TK_INVALID with the bytes read so far). */
static int lex_number(proto_jpull *j, size_t start)
{
    number_scan sc;
    scan_number(j->data, j->len, start, &sc);
    size_t p = sc.end;
    if (!lookahead_ok(j, p, start))
        return TK_FAILED;
    switch (sc.kind) {
    case SN_INVALID:
        j->tok_end = j->pos = p;
        return TK_INVALID;
    case SN_TOO_BIG:
        j->tok_end = j->pos = p;
        return fail_at(j, p, start, p, false, sc.neg
                                                  ? "too big negative integer"
                                                  : "too big integer");
    case SN_INTEGER:
        j->tok_end = j->pos = p;
        j->integer = sc.neg && sc.w == UINT64_C(1) << 63 ? INT64_MIN
                     : sc.neg                             ? -(int64_t)sc.w
                                                          : (int64_t)sc.w;
        return TK_INTEGER;
    default:
        break;
    }
    j->tok_end = j->pos = p;
    int r = proto_decimal_from_parts(sc.neg, sc.w, sc.q, sc.dropped,
                                     (const char *)j->data + start,
                                     p - start, &j->real);
    if (r == -ENOMEM)
        return fail_oom(j);
    if (r < 0)
        return fail_at(j, p, start, p, false, "real number overflow");
    return TK_REAL;
}

bool proto_json_number(const void *data, size_t len, size_t start,
                       size_t *ret_end, bool *ret_is_int,
                       int64_t *ret_integer, double *ret_real)
{
    const unsigned char *d = data;
    if (start >= len || (d[start] != '-' && !is_digit(d[start])))
        return false;
    uint32_t u;
    if (proto_json_short_uint(d, len, start, ret_end, &u)) {
        *ret_is_int = true;
        *ret_integer = u;
        return true;
    }
    number_scan sc;
    scan_number(d, len, start, &sc);
    if (sc.end < len && d[sc.end] >= 0x80)
        return false;
    *ret_end = sc.end;
    if (sc.kind == SN_INTEGER) {
        *ret_is_int = true;
        *ret_integer = sc.neg && sc.w == UINT64_C(1) << 63 ? INT64_MIN
                       : sc.neg                             ? -(int64_t)sc.w
                                                            : (int64_t)sc.w;
        return true;
    }
    *ret_is_int = false;
    return sc.kind == SN_REAL &&
           proto_decimal_from_parts(sc.neg, sc.w, sc.q, sc.dropped,
                                    (const char *)d + start, sc.end - start,
                                    ret_real) == 0;
}

static bool is_alpha(unsigned c)
{
    return (c | 0x20) - 'a' < 26;
}

/* Past the whitespace JSON allows at p. */
static size_t skip_space(const unsigned char *d, size_t n, size_t p)
{
    while (p < n && (d[p] == ' ' || d[p] == '\n' || d[p] == '\r' ||
                     d[p] == '\t'))
        p++;
    return p;
}

static int lex(proto_jpull *j)
{
    const unsigned char *d = j->data;
    size_t n = j->len, p = skip_space(d, n, j->pos);
    j->tok_start = j->tok_end = j->pos = p;
    if (p >= n)
        return TK_EOF;
    unsigned c = d[p];
    int tk;
    switch (c) {
    case '{':
        tk = TK_LBRACE;
        break;
    case '}':
        tk = TK_RBRACE;
        break;
    case '[':
        tk = TK_LBRACKET;
        break;
    case ']':
        tk = TK_RBRACKET;
        break;
    case ':':
        tk = TK_COLON;
        break;
    case ',':
        tk = TK_COMMA;
        break;
    case '"':
        return lex_string(j, p);
    default:
        if (c == '-' || is_digit(c))
            return lex_number(j, p);
        if (is_alpha(c)) {
            size_t q = p;
            while (q < n && is_alpha(d[q]))
                q++;
            if (!lookahead_ok(j, q, p))
                return TK_FAILED;
            j->tok_end = j->pos = q;
            size_t l = q - p;
            if (l == 4 && memcmp(d + p, "true", 4) == 0)
                return TK_TRUE;
            if (l == 5 && memcmp(d + p, "false", 5) == 0)
                return TK_FALSE;
            if (l == 4 && memcmp(d + p, "null", 4) == 0)
                return TK_NULL;
            return TK_INVALID;
        }
        if (c >= 0x80) {
            size_t l = utf8_seq(d + p, n - p);
            if (!l)
                return bad_utf8(j, p, p);
            j->tok_end = j->pos = p + l;
            return TK_INVALID;
        }
        tk = TK_INVALID;
        break;
    }
    j->tok_end = j->pos = p + 1;
    return tk;
}

static uint64_t key_hash(uint32_t serial, const char *s, size_t len)
{
    uint64_t h = 0xcbf29ce484222325u ^ serial;
    for (size_t i = 0; i < len; i++)
        h = (h ^ (unsigned char)s[i]) * 0x100000001b3u;
    return h | 1;
}

/* Puts e in the table of names (it is not there). */
static bool table_put(proto_jpull *j, const proto_jkey *e)
{
    if ((j->nkeys + 1) * 2 > j->cap_keys) {
        size_t cap = j->cap_keys ? j->cap_keys * 2 : 64;
        proto_jkey *nk = calloc(cap, sizeof *nk);
        if (!nk)
            return false;
        for (size_t i = 0; i < j->cap_keys; i++) {
            if (!j->keys[i].hash)
                continue;
            size_t k = j->keys[i].hash & (cap - 1);
            while (nk[k].hash)
                k = (k + 1) & (cap - 1);
            nk[k] = j->keys[i];
        }
        free(j->keys);
        j->keys = nk;
        j->cap_keys = cap;
    }
    size_t mask = j->cap_keys - 1, k = e->hash & mask;
    while (j->keys[k].hash)
        k = (k + 1) & mask;
    j->keys[k] = *e;
    j->nkeys++;
    return true;
}

/* True when the table holds name s of object serial (hash h). */
static bool table_has(const proto_jpull *j, uint64_t h, uint32_t serial,
                      const char *s, size_t len)
{
    if (!j->cap_keys)
        return false;
    size_t mask = j->cap_keys - 1;
    for (size_t k = h & mask; j->keys[k].hash; k = (k + 1) & mask) {
        const proto_jkey *e = &j->keys[k];
        if (e->hash == h && e->serial == serial && e->len == len &&
            (len == 0 || memcmp(j->arena + e->off, s, len) == 0))
            return true;
    }
    return false;
}

/* Remembers a member name of the innermost open object; false when that
 * object already has it (or, with *oom set, when memory ran out). An
 * object's first name is only logged: nothing can clash with it until a
 * second one comes, which then puts both in the table. Most objects of a
 * model (a facet each) have one member, and never touch the table. */
static bool key_insert(proto_jpull *j, const char *s, size_t len, bool *oom)
{
    uint32_t serial = j->serials[j->depth - 1];
    size_t mark = j->marks[j->depth - 1], before = j->nlog - mark;
    uint64_t h = 0;
    if (before > 0) {
        h = key_hash(serial, s, len);
        if (before == 1) {
            proto_jkey *first = &j->log[mark];
            /* an empty first name may have left the arena unallocated */
            first->hash = key_hash(serial,
                                   first->len ? j->arena + first->off : "",
                                   first->len);
            if (!table_put(j, first)) {
                *oom = true;
                return false;
            }
        }
        if (table_has(j, h, serial, s, len))
            return false;
    }
    if (len > j->acap - j->alen) {
        size_t cap = j->acap ? j->acap : 1024;
        while (cap - j->alen < len) {
            if (cap > SIZE_MAX / 2 || cap > UINT32_MAX) {
                *oom = true;
                return false;
            }
            cap *= 2;
        }
        char *a = realloc(j->arena, cap);
        if (!a) {
            *oom = true;
            return false;
        }
        j->arena = a;
        j->acap = cap;
    }
    if (j->nlog == j->cap_log) {
        size_t cap = j->cap_log ? j->cap_log * 2 : 64;
        proto_jkey *l = realloc(j->log, cap * sizeof *l);
        if (!l) {
            *oom = true;
            return false;
        }
        j->log = l;
        j->cap_log = cap;
    }
    if (len)
        memcpy(j->arena + j->alen, s, len);
    proto_jkey e = {h, serial, (uint32_t)len, j->alen};
    j->log[j->nlog++] = e;
    j->alen += len;
    if (before > 0 && !table_put(j, &e)) {
        j->nlog--;
        j->alen -= len;
        *oom = true;
        return false;
    }
    return true;
}

/* Forgets the names of the object that ends: they can no longer clash,
 * and a table holding only the open objects' names stays in cache where
 * one holding every name read grows with the document. Its names are the
 * log's last (those of the objects inside it went when they ended); in
 * the table only when there are two or more, each leaves it by
 * backward-shift deletion, which keeps every probe sequence unbroken. */
static void keys_drop(proto_jpull *j, size_t mark)
{
    size_t mask = j->cap_keys - 1;
    for (size_t n = j->nlog; j->nlog - mark > 1 && n > mark; n--) {
        const proto_jkey *e = &j->log[n - 1];
        size_t i = e->hash & mask;
        while (!(j->keys[i].hash == e->hash && j->keys[i].serial == e->serial &&
                 j->keys[i].off == e->off))
            i = (i + 1) & mask;
        for (size_t k = (i + 1) & mask; j->keys[k].hash; k = (k + 1) & mask) {
            size_t home = j->keys[k].hash & mask;
            /* k's entry stays unless the hole at i lies on its probe path
             * (its home cyclically outside (i, k]) */
            bool stays = i <= k ? home > i && home <= k : home > i || home <= k;
            if (!stays) {
                j->keys[i] = j->keys[k];
                i = k;
            }
        }
        j->keys[i].hash = 0;
        j->nkeys--;
    }
    if (j->nlog > mark)
        j->alen = j->log[mark].off;
    j->nlog = mark;
}

static bool push(proto_jpull *j, unsigned char kind)
{
    if (j->depth == j->cap_depth) {
        unsigned cap = j->cap_depth ? j->cap_depth * 2 : 32;
        unsigned char *k = realloc(j->kinds, cap);
        if (!k)
            return false;
        j->kinds = k;
        uint32_t *s = realloc(j->serials, cap * sizeof *s);
        if (!s)
            return false;
        j->serials = s;
        size_t *m = realloc(j->marks, cap * sizeof *m);
        if (!m)
            return false;
        j->marks = m;
        j->cap_depth = cap;
    }
    j->marks[j->depth] = j->nlog;
    j->kinds[j->depth] = kind;
    j->serials[j->depth] = kind == K_OBJECT ? ++j->next_serial : 0;
    j->depth++;
    return true;
}

static proto_jtok oom_error(proto_jpull *j)
{
    fail_oom(j);
    return PROTO_JT_ERROR;
}

/* The first token of a value has been read. */
static proto_jtok begin_value(proto_jpull *j, int tk)
{
    if (j->depth + 1 > PROTO_JSON_MAX_DEPTH)
        return fail_token(j, "maximum parsing depth reached");
    switch (tk) {
    case TK_LBRACE:
        if (!push(j, K_OBJECT))
            return oom_error(j);
        j->state = ST_OBJ_FIRST;
        return PROTO_JT_OBJECT;
    case TK_LBRACKET:
        if (!push(j, K_ARRAY))
            return oom_error(j);
        j->state = ST_ARR_FIRST;
        return PROTO_JT_ARRAY;
    case TK_STRING:
        if (j->has_nul)
            return fail_token(j, "\\u0000 is not allowed without "
                                 "JSON_ALLOW_NUL");
        j->state = ST_AFTER;
        return PROTO_JT_STRING;
    case TK_INTEGER:
        j->state = ST_AFTER;
        return PROTO_JT_INTEGER;
    case TK_REAL:
        j->state = ST_AFTER;
        return PROTO_JT_REAL;
    case TK_TRUE:
        j->state = ST_AFTER;
        return PROTO_JT_TRUE;
    case TK_FALSE:
        j->state = ST_AFTER;
        return PROTO_JT_FALSE;
    case TK_NULL:
        j->state = ST_AFTER;
        return PROTO_JT_NULL;
    case TK_INVALID:
        return fail_token(j, "invalid token");
    default:
        return fail_token(j, "unexpected token");
    }
}

/* A member name has been read (or should have been). */
static proto_jtok begin_member(proto_jpull *j, int tk)
{
    if (tk != TK_STRING)
        return fail_token(j, "string or '}' expected");
    if (j->has_nul)
        return fail_token(j, "NUL byte in object key not supported");
    bool oom = false;
    if (!key_insert(j, j->str, j->str_len, &oom))
        return oom ? oom_error(j) : fail_token(j, "duplicate object key");
    size_t ks = j->tok_start, ke = j->tok_end;
    int colon = lex(j);
    if (colon == TK_FAILED)
        return PROTO_JT_ERROR;
    if (colon != TK_COLON)
        return fail_token(j, "':' expected");
    j->tok_start = ks;
    j->tok_end = ke;
    j->state = ST_VALUE;
    return PROTO_JT_KEY;
}

static proto_jtok end_container(proto_jpull *j, proto_jtok t)
{
    if (t == PROTO_JT_OBJECT_END)
        keys_drop(j, j->marks[j->depth - 1]);
    j->depth--;
    j->state = ST_AFTER;
    return t;
}

static proto_jtok next_token(proto_jpull *j)
{
    int tk;
    for (;;) {
        switch (j->state) {
        case ST_DONE:
            return PROTO_JT_END;
        case ST_START:
            if ((tk = lex(j)) == TK_FAILED)
                return PROTO_JT_ERROR;
            if (tk != TK_LBRACE && tk != TK_LBRACKET)
                return fail_token(j, "'[' or '{' expected");
            return begin_value(j, tk);
        case ST_VALUE:
            if ((tk = lex(j)) == TK_FAILED)
                return PROTO_JT_ERROR;
            return begin_value(j, tk);
        case ST_ARR_FIRST:
        case ST_ARR_NEXT:
            if ((tk = lex(j)) == TK_FAILED)
                return PROTO_JT_ERROR;
            if (tk == TK_RBRACKET && j->state == ST_ARR_FIRST)
                return end_container(j, PROTO_JT_ARRAY_END);
            if (tk == TK_EOF)
                return fail_token(j, "']' expected");
            return begin_value(j, tk);
        case ST_OBJ_FIRST:
        case ST_OBJ_NEXT:
            if ((tk = lex(j)) == TK_FAILED)
                return PROTO_JT_ERROR;
            if (tk == TK_RBRACE && j->state == ST_OBJ_FIRST)
                return end_container(j, PROTO_JT_OBJECT_END);
            return begin_member(j, tk);
        case ST_AFTER:
            if ((tk = lex(j)) == TK_FAILED)
                return PROTO_JT_ERROR;
            if (j->depth == 0) {
                if (tk != TK_EOF)
                    return fail_token(j, "end of file expected");
                j->state = ST_DONE;
                return PROTO_JT_END;
            }
            if (j->kinds[j->depth - 1] == K_ARRAY) {
                if (tk == TK_COMMA) {
                    j->state = ST_ARR_NEXT;
                    continue;
                }
                if (tk == TK_RBRACKET)
                    return end_container(j, PROTO_JT_ARRAY_END);
                return fail_token(j, "']' expected");
            }
            if (tk == TK_COMMA) {
                j->state = ST_OBJ_NEXT;
                continue;
            }
            if (tk == TK_RBRACE)
                return end_container(j, PROTO_JT_OBJECT_END);
            return fail_token(j, "'}' expected");
        default:
            return PROTO_JT_ERROR;
        }
    }
}

/* A number element of an array, its first byte at p; what next_token's
 * lex() and begin_value() would do with it. */
static proto_jtok array_number(proto_jpull *j, size_t p)
{
    j->tok_start = j->tok_end = j->pos = p;
    int tk = lex_number(j, p);
    if (tk == TK_FAILED)
        return PROTO_JT_ERROR;
    if (tk == TK_INVALID)
        return fail_token(j, "invalid token");
    j->state = ST_AFTER;
    return tk == TK_INTEGER ? PROTO_JT_INTEGER : PROTO_JT_REAL;
}

/* The tokens of arrays of numbers (a model's coordinates and indices,
 * most of its text) without the general state machine: a number as the
 * first element or after a comma, and the array's end after an element.
 * Exactly what next_token returns for them; -2 for anything else. */
static proto_jtok next_in_array(proto_jpull *j)
{
    if (j->depth >= PROTO_JSON_MAX_DEPTH)
        return (proto_jtok)-2;
    const unsigned char *d = j->data;
    size_t n = j->len, p = skip_space(d, n, j->pos);
    if (j->state == ST_ARR_FIRST) {
        if (p < n && (d[p] == '-' || is_digit(d[p])))
            return array_number(j, p);
        return (proto_jtok)-2;
    }
    if (j->state != ST_AFTER || j->depth == 0 ||
        j->kinds[j->depth - 1] != K_ARRAY || p >= n)
        return (proto_jtok)-2;
    if (d[p] == ']') {
        j->tok_start = p;
        j->tok_end = j->pos = p + 1;
        return end_container(j, PROTO_JT_ARRAY_END);
    }
    if (d[p] != ',')
        return (proto_jtok)-2;
    size_t q = skip_space(d, n, p + 1);
    if (q < n && (d[q] == '-' || is_digit(d[q])))
        return array_number(j, q);
    return (proto_jtok)-2;
}

/* The token t has been read: remembered, and the pages behind it
 * offered back every PROTO_JPULL_BEHIND_STEP bytes. */
static proto_jtok returned(proto_jpull *j, proto_jtok t)
{
    j->last = t;
    if (j->behind && j->pos >= j->behind_next) {
        j->behind_next = j->pos + PROTO_JPULL_BEHIND_STEP;
        j->behind(j->behind_user, j->tok_start);
    }
    return t;
}

proto_jtok proto_jpull_next(proto_jpull *j)
{
    proto_jtok t = next_in_array(j);
    if (t == (proto_jtok)-2)
        t = next_token(j);
    return returned(j, t);
}

proto_jtok proto_jpull_end_object_at(proto_jpull *j, size_t pos)
{
    j->tok_start = pos - 1;
    j->tok_end = j->pos = pos;
    return returned(j, end_container(j, PROTO_JT_OBJECT_END));
}

proto_jtok proto_jpull_skip(proto_jpull *j)
{
    if (j->last == PROTO_JT_KEY)
        proto_jpull_next(j);
    if (j->last != PROTO_JT_OBJECT && j->last != PROTO_JT_ARRAY)
        return j->last;
    unsigned target = j->depth - 1;
    for (;;) {
        proto_jtok t = proto_jpull_next(j);
        if (t == PROTO_JT_ERROR)
            return t;
        if ((t == PROTO_JT_OBJECT_END || t == PROTO_JT_ARRAY_END) &&
            j->depth == target)
            return t;
    }
}
