/* edgemap.h — a hash map from an edge (a pair of vertex indices) to a
 * 32-bit value: open addressing with linear probing, power-of-two
 * capacity kept at most half full, deletion by backward shift (no
 * tombstones). Expected O(1) per operation.
 *
 * Keys: geo_edge_key(a, b) for a directed edge a→b, geo_edge_ukey(a, b)
 * for an undirected one (the smaller index first). UINT64_MAX marks an
 * empty slot and is never a key (vertex indices are < UINT32_MAX).
 *
 * Ownership: the map owns its arrays (geo_edgemap_init allocates,
 * geo_edgemap_destroy releases). Not thread-safe for concurrent writes. */
#ifndef GEO_EDGEMAP_H
#define GEO_EDGEMAP_H

#include <stddef.h>
#include <stdint.h>

typedef struct geo_edgemap {
    uint64_t *keys;
    uint32_t *vals;
    size_t cap; /* power of two, or 0 */
    size_t n;   /* keys stored */
} geo_edgemap;

static inline uint64_t geo_edge_key(uint32_t a, uint32_t b)
{
    return (uint64_t)a << 32 | b;
}

static inline uint64_t geo_edge_ukey(uint32_t a, uint32_t b)
{
    return a < b ? geo_edge_key(a, b) : geo_edge_key(b, a);
}

/* An empty map sized for about `expected` keys. 0 or -ENOMEM. */
int geo_edgemap_init(geo_edgemap *m, size_t expected);

/* Releases the arrays; m may be zeroed or initialised. */
void geo_edgemap_destroy(geo_edgemap *m);

/* The value stored under key, or UINT32_MAX when absent. */
uint32_t geo_edgemap_get(const geo_edgemap *m, uint64_t key);

/* Stores val under key (replacing an old value). 0 or -ENOMEM (the map
 * is unchanged on failure). */
int geo_edgemap_put(geo_edgemap *m, uint64_t key, uint32_t val);

/* Grows the table so that it holds `total` keys without growing again
 * (puts of new keys then cannot fail). 0 or -ENOMEM. */
int geo_edgemap_reserve(geo_edgemap *m, size_t total);

/* Removes key if present. */
void geo_edgemap_del(geo_edgemap *m, uint64_t key);

#endif
