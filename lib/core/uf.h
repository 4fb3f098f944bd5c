/* uf.h — the root of an element in a union-find forest held as a parent
 * array (a root is its own parent), with path halving: every other node
 * on the path is hung on its grandparent, so a long chain is halved by
 * each lookup. Unions are the caller's (each user keeps its own rule for
 * which root survives). */
#ifndef GEO_UF_H
#define GEO_UF_H

#include <stdint.h>

static inline uint32_t geo_uf_find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
    return x;
}

#endif
