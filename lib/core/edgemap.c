/* edgemap.c — linear-probing hash of edges (see edgemap.h). */
#include "edgemap.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

#define EMPTY UINT64_MAX

static inline size_t slot_of(uint64_t key, size_t cap)
{
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return (size_t)key & (cap - 1);
}

static int rehash(geo_edgemap *m, size_t cap)
{
    uint64_t *k = malloc(cap * sizeof *k);
    uint32_t *v = malloc(cap * sizeof *v);
    if (!k || !v) {
        free(k), free(v);
        return -ENOMEM;
    }
    memset(k, 0xff, cap * sizeof *k);
    for (size_t i = 0; i < m->cap; i++) {
        if (m->keys[i] == EMPTY)
            continue;
        size_t s = slot_of(m->keys[i], cap);
        while (k[s] != EMPTY)
            s = (s + 1) & (cap - 1);
        k[s] = m->keys[i];
        v[s] = m->vals[i];
    }
    free(m->keys), free(m->vals);
    m->keys = k;
    m->vals = v;
    m->cap = cap;
    return 0;
}

int geo_edgemap_init(geo_edgemap *m, size_t expected)
{
    memset(m, 0, sizeof *m);
    size_t cap = 16;
    while (cap < 2 * expected + 2)
        cap *= 2;
    return rehash(m, cap);
}

void geo_edgemap_destroy(geo_edgemap *m)
{
    free(m->keys), free(m->vals);
    memset(m, 0, sizeof *m);
}

uint32_t geo_edgemap_get(const geo_edgemap *m, uint64_t key)
{
    if (m->cap == 0)
        return UINT32_MAX;
    for (size_t s = slot_of(key, m->cap);; s = (s + 1) & (m->cap - 1)) {
        if (m->keys[s] == key)
            return m->vals[s];
        if (m->keys[s] == EMPTY)
            return UINT32_MAX;
    }
}

int geo_edgemap_reserve(geo_edgemap *m, size_t total)
{
    size_t cap = m->cap ? m->cap : 16;
    while (2 * (total + 1) > cap)
        cap *= 2;
    return cap == m->cap ? 0 : rehash(m, cap);
}

int geo_edgemap_put(geo_edgemap *m, uint64_t key, uint32_t val)
{
    if (2 * (m->n + 1) > m->cap && rehash(m, m->cap ? 2 * m->cap : 16) < 0)
        return -ENOMEM;
    size_t s = slot_of(key, m->cap);
    while (m->keys[s] != EMPTY && m->keys[s] != key)
        s = (s + 1) & (m->cap - 1);
    if (m->keys[s] == EMPTY)
        m->n++;
    m->keys[s] = key;
    m->vals[s] = val;
    return 0;
}

void geo_edgemap_del(geo_edgemap *m, uint64_t key)
{
    if (m->cap == 0)
        return;
    size_t mask = m->cap - 1, s = slot_of(key, m->cap);
    while (m->keys[s] != key) {
        if (m->keys[s] == EMPTY)
            return;
        s = (s + 1) & mask;
    }
    /* backward-shift deletion keeps every probe chain unbroken */
    size_t hole = s;
    for (size_t j = (s + 1) & mask; m->keys[j] != EMPTY; j = (j + 1) & mask) {
        size_t home = slot_of(m->keys[j], m->cap);
        /* move j into the hole when its home is not in (hole, j] */
        if (((j - home) & mask) >= ((j - hole) & mask)) {
            m->keys[hole] = m->keys[j];
            m->vals[hole] = m->vals[j];
            hole = j;
        }
    }
    m->keys[hole] = EMPTY;
    m->n--;
}
