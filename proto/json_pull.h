/* json_pull.h — a pull tokenizer for JSON (RFC 8259) over a buffer in
 * memory: the caller asks for one token at a time and builds what it
 * needs directly, without a tree of values.
 *
 * Strict: the grammar is checked as the tokens are read (commas, colons,
 * brackets, the top-level value followed only by whitespace), strings must
 * be valid UTF-8 without raw control characters, escapes must be valid
 * (\uXXXX surrogates paired), a string with \u0000 is refused, duplicate
 * member names of one object are refused (compared after unescaping),
 * integers must fit in 64 bits (signed) and reals must not overflow a
 * double (NaN and Infinity are not JSON). Nesting deeper than
 * PROTO_JSON_MAX_DEPTH values is refused. The text must be an object or
 * an array.
 *
 * The errors are jansson's (json_loadb with JSON_REJECT_DUPLICATES), so
 * that replacing a jansson parse keeps every message: the same text
 * ("']' expected near '0'", "duplicate object key near '\"a\"'",
 * "unable to decode byte 0xff near '\"'", ...), the same line (from 1) and
 * the same column (characters, i.e. UTF-8 sequences, since the start of
 * the line, up to the point where reading stopped). One difference: a NUL
 * byte right after a number or a literal is an error here, where jansson
 * drops it silently.
 *
 * Numbers: a number without fraction and exponent is PROTO_JT_INTEGER
 * (int64_t), any other PROTO_JT_REAL (the nearest double, exactly as
 * strtod: proto/decimal.h).
 *
 * Ownership and threads: the tokenizer borrows the input (which must stay
 * unchanged until proto_jpull_clear) and owns its buffers; str points
 * into them and is valid until the next call. One tokenizer per thread;
 * distinct tokenizers are independent. Memory: O(length of the input) at
 * most (decoded strings, the member names of the open objects). */
#ifndef PROTO_JSON_PULL_H
#define PROTO_JSON_PULL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* jansson's JSON_PARSER_MAX_DEPTH: the top-level value has depth 1. */
#define PROTO_JSON_MAX_DEPTH 2048

typedef enum proto_jtok {
    PROTO_JT_ERROR = -1,  /* see the error member */
    PROTO_JT_END = 0,     /* the text ended after its value */
    PROTO_JT_OBJECT,      /* '{' */
    PROTO_JT_OBJECT_END,  /* '}' */
    PROTO_JT_ARRAY,       /* '[' */
    PROTO_JT_ARRAY_END,   /* ']' */
    PROTO_JT_KEY,         /* a member name (str, str_len); its value follows */
    PROTO_JT_STRING,      /* str, str_len */
    PROTO_JT_INTEGER,     /* integer */
    PROTO_JT_REAL,        /* real */
    PROTO_JT_TRUE,
    PROTO_JT_FALSE,
    PROTO_JT_NULL,
} proto_jtok;

/* Where and why reading failed. code is -EINVAL for bad JSON, -ENOMEM
 * when a buffer could not grow (text "out of memory"). */
typedef struct proto_jerror {
    int code;
    int line, column;
    size_t position; /* bytes read */
    char text[160];
} proto_jerror;

typedef struct proto_jpull {
    /* The last token; read-only for the caller. */
    const char *str;      /* KEY, STRING: UTF-8, NUL-terminated (no NUL
                             inside) */
    size_t str_len;
    int64_t integer;      /* INTEGER */
    double real;          /* REAL */
    size_t tok_start, tok_end; /* the token's bytes [start, end) in the
                             input; for a KEY the name with its quotes */
    unsigned depth;       /* objects and arrays open after the token */
    proto_jerror error;   /* after PROTO_JT_ERROR */

    /* Optional, set after proto_jpull_init: called as the reading passes
     * each further PROTO_JPULL_BEHIND_STEP bytes, with the start of the
     * token just read. No byte before it is read again except to count
     * an error's line and column, so a caller whose input reads back the
     * same on demand (text_map.h) may release those pages. */
    void (*behind)(void *user, size_t pos);
    void *behind_user;

    /* Private. */
    const unsigned char *data;
    size_t len, pos;
    int state;
    proto_jtok last;      /* the token returned last */
    bool has_nul;         /* the last string decoded to a NUL byte */
    unsigned char *kinds; /* per open container: object or array */
    uint32_t *serials;    /* per open container: its object number */
    unsigned cap_depth;
    uint32_t next_serial;
    char *sbuf;           /* decoded string */
    size_t slen, scap;
    struct proto_jkey *keys; /* member names of the open objects */
    size_t nkeys, cap_keys;
    char *arena;          /* their bytes, in reading order */
    size_t alen, acap;
    struct proto_jkey *log; /* the same names in reading order, so that
                             an object's own are the last when it ends */
    size_t nlog, cap_log;
    size_t *marks;        /* per open container: nlog when it opened */
    size_t behind_next;   /* the position that calls behind next */
} proto_jpull;

#define PROTO_JPULL_BEHIND_STEP ((size_t)1 << 20)

/* Starts reading len bytes at data (data may be NULL when len is 0). */
void proto_jpull_init(proto_jpull *j, const void *data, size_t len);

/* Releases the tokenizer's buffers; j may be initialised again. */
void proto_jpull_clear(proto_jpull *j);

/* The next token. After PROTO_JT_ERROR or PROTO_JT_END every further
 * call returns the same. */
proto_jtok proto_jpull_next(proto_jpull *j);

/* Reads the rest of the value whose first token was just returned: for
 * OBJECT or ARRAY every token up to and including the matching end (all
 * checked as by proto_jpull_next); for a scalar nothing. Right after a
 * KEY it reads that member's whole value. Returns the last token of the
 * value (so j->tok_end is where its text ends) or PROTO_JT_ERROR.
 * Anywhere else it reads nothing and returns the last token again. */
proto_jtok proto_jpull_skip(proto_jpull *j);

/* For a reader that reads an object's members from the bytes itself
 * (proto/model_json.c's fast path): called right after the OBJECT token
 * that opened it, with pos just past its closing '}', the tokenizer goes
 * on as if it had read every token up to that '}' and returned its
 * OBJECT_END (which it returns). The caller answers for the bytes in
 * between: a valid object, no member name twice. */
proto_jtok proto_jpull_end_object_at(proto_jpull *j, size_t pos);

/* The number at data[start..len) as the tokenizer reads one, for such a
 * reader: true when the bytes from start are a whole number that
 * proto_jpull_next would return as PROTO_JT_INTEGER (*ret_is_int,
 * *ret_integer) or PROTO_JT_REAL (*ret_real, the same bits), ending at
 * *ret_end before a byte below 0x80 or the end. False for anything else
 * (no number, an integer beyond 64 bits, a real that overflows, a
 * look-ahead byte the tokenizer would check as UTF-8): the tokenizer
 * then says what is wrong. */
bool proto_json_number(const void *data, size_t len, size_t start,
                       size_t *ret_end, bool *ret_is_int,
                       int64_t *ret_integer, double *ret_real);

#endif
