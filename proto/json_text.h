/* json_text.h — jansson's json_dumps output written faster: the same
 * text byte for byte (separators, indentation, escapes, reals as %.17g
 * with jansson's touches) for objects and arrays dumped with
 * JSON_INDENT(n), JSON_COMPACT and JSON_PRESERVE_ORDER; any other flag or
 * a top-level scalar is passed to json_dumps. For documents of many
 * reals (a report's facet table, a job's statistics), where jansson's
 * snprintf per number is most of the time.
 *
 * Reentrant; the caller frees the text. NULL when out of memory. */
#ifndef PROTO_JSON_TEXT_H
#define PROTO_JSON_TEXT_H

#include <stdbool.h>
#include <stddef.h>

#include <jansson.h>

char *proto_json_dumps(const json_t *j, size_t flags);

/* The pieces, for writers of JSON text that do not build a tree (the
 * daemon's job view): a growing buffer kept NUL-terminated; after an
 * allocation failure `failed` is set and nothing more is written. */
typedef struct proto_text {
    char *s;
    size_t len, cap;
    bool failed;
} proto_text;

void proto_text_put(proto_text *t, const char *s, size_t n);

/* s[0..n) as a JSON string the way jansson writes it without
 * JSON_ENSURE_ASCII and JSON_ESCAPE_SLASH. */
void proto_text_string(proto_text *t, const char *s, size_t n);

/* v as jansson writes a real: %.17g, ".0" after an integral value, the
 * exponent without '+' or leading zeros. */
void proto_text_real(proto_text *t, double v);

#endif
