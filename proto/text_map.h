/* text_map.h — a file's text mapped for one reading pass, its pages
 * released as the reader leaves them behind, so that a large file is
 * never resident as a whole (67 MB for a million-triangle mesh in
 * facet-model/1).
 *
 * The mapping is private and read-only: a released page that is read
 * again (an error's line and column are counted from the start) comes
 * back from the file, the same bytes. The file must not shrink while it
 * is mapped: reading a page beyond its new end raises SIGBUS, which is
 * why only a caller that asks for it (proto_limits.map_file: the
 * command-line tools) reads this way.
 *
 * Ownership: proto_text_map_open maps, proto_text_map_close unmaps. */
#ifndef PROTO_TEXT_MAP_H
#define PROTO_TEXT_MAP_H

#include <stddef.h>

#include "ctx.h"

typedef struct proto_text_map {
    const char *data; /* len bytes of the file */
    size_t len;
    size_t released;  /* bytes [0, released) given back, page-aligned */
} proto_text_map;

/* Maps the regular file open on fd: 0; 1 when it is not a regular file
 * or is empty (read it otherwise); or -ERANGE beyond max bytes, -errno
 * (err set). */
int proto_text_map_open(int fd, size_t max, proto_text_map *m, geo_err *err);

/* Gives back the whole pages below pos (a proto_text_map * as user):
 * the shape of a proto_jpull behind callback. */
void proto_text_map_behind(void *user, size_t pos);

/* Unmaps; m may be zeroed. */
void proto_text_map_close(proto_text_map *m);

#endif
