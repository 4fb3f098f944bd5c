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

#include <jansson.h>

char *proto_json_dumps(const json_t *j, size_t flags);

#endif
