/* grow.h — the one growth rule of every dynamic array in facet: capacity
 * doubles from 16 until it holds what is needed, and the size in bytes is
 * checked for overflow before realloc. */
#ifndef GEO_GROW_H
#define GEO_GROW_H

#include <stddef.h>

/* Makes *buf hold at least need elements of elem bytes; *cap is its
 * capacity in elements. 0, or -ENOMEM (also when need × elem does not fit
 * a size_t), with *buf and *cap untouched. */
int geo_grow(void **buf, size_t *cap, size_t need, size_t elem);

#endif
