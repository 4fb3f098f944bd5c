/* fbvh_pairs.h — the pair search of fbvh.h as a static function, for a
 * caller whose visitor is called hundreds of thousands of times: with the
 * visitor a constant, the compiler specialises the search for it (the
 * visitor inlined, no indirect call per pair). geo_fbvh_pairs is the same
 * search for any visitor. */
#ifndef GEO_FBVH_PAIRS_H
#define GEO_FBVH_PAIRS_H

#include "fbvh.h"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

static inline bool qbox_overlap(const geo_qbox *a, const geo_qbox *b)
{
    return a->lo[0] <= b->hi[0] && b->lo[0] <= a->hi[0] &&
           a->lo[1] <= b->hi[1] && b->lo[1] <= a->hi[1] &&
           a->lo[2] <= b->hi[2] && b->lo[2] <= a->hi[2];
}

/* qbox_overlap without branches (1 or 0), for the leaves' all-pairs
 * tests, whose outcomes follow no pattern a branch predictor learns. */
static inline unsigned qbox_meets(const geo_qbox *a, const geo_qbox *b)
{
    return (unsigned)(a->lo[0] <= b->hi[0]) & (b->lo[0] <= a->hi[0]) &
           (a->lo[1] <= b->hi[1]) & (b->lo[1] <= a->hi[1]) &
           (a->lo[2] <= b->hi[2]) & (b->lo[2] <= a->hi[2]);
}

/* The items of leaf range [lo, lo + n) whose boxes meet box: bit k for
 * item lo + k (n ≤ GEO_FBVH_LEAF ≤ 32). With SSE2 a box is one vector:
 * lanes 0-2 hold lo_b − hi_a and lanes 3-5 lo_a − hi_b as saturating
 * differences, all 0 exactly when the boxes meet; lanes 6-7 (the next
 * box's first bytes, or the array's spare slot after the last box) come
 * out 0 whatever they hold. */
_Static_assert(GEO_FBVH_LEAF <= 32, "a leaf's items are bits of a mask");
static inline uint32_t qbox_meets_mask(const geo_fbvh *h, const geo_qbox *box,
                                       uint32_t lo, uint32_t n)
{
    uint32_t m = 0;
#ifdef __SSE2__
    const __m128i hi_a =
        _mm_setr_epi16((short)box->hi[0], (short)box->hi[1],
                       (short)box->hi[2], -1, -1, -1, -1, -1);
    const __m128i lo_a =
        _mm_setr_epi16(0, 0, 0, (short)box->lo[0], (short)box->lo[1],
                       (short)box->lo[2], 0, 0);
    const __m128i zero = _mm_setzero_si128();
    for (uint32_t k = 0; k < n; k++) {
        __m128i b = _mm_loadu_si128(
            (const __m128i *)(const void *)&h->boxes[lo + k]);
        __m128i d = _mm_or_si128(_mm_subs_epu16(b, hi_a),
                                 _mm_subs_epu16(lo_a, b));
        m |= (uint32_t)(_mm_movemask_epi8(_mm_cmpeq_epi16(d, zero)) ==
                        0xFFFF)
             << k;
    }
#else
    for (uint32_t k = 0; k < n; k++)
        m |= qbox_meets(box, &h->boxes[lo + k]) << k;
#endif
    return m;
}

/* The sum of the sides, in cells (cubic cells: as the sum in mm). */
static inline int32_t qbox_extent(const geo_qbox *b)
{
    return ((int32_t)b->hi[0] - b->lo[0]) + ((int32_t)b->hi[1] - b->lo[1]) +
           ((int32_t)b->hi[2] - b->lo[2]);
}

/* geo_fbvh_pairs. */
static bool geo_fbvh_pairs_with(const geo_fbvh *h, uint32_t na, uint32_t nb,
                                geo_bvh_pair_fn visit, void *user)
{
    const geo_fbvh_node *a = &h->nodes[na], *b = &h->nodes[nb];
    if (na == nb) {
        if (a->count) {
            uint32_t end = a->child + a->count;
            for (uint32_t i = a->child; i + 1 < end; i++)
                for (uint32_t m = qbox_meets_mask(h, &h->boxes[i], i + 1,
                                                  end - i - 1);
                     m; m &= m - 1)
                    if (!visit(user, h->items[i],
                               h->items[i + 1 + __builtin_ctz(m)]))
                        return false;
            return true;
        }
        return geo_fbvh_pairs_with(h, a->child, a->child, visit, user) &&
               geo_fbvh_pairs_with(h, a->child + 1, a->child + 1, visit,
                                   user) &&
               geo_fbvh_pairs_with(h, a->child, a->child + 1, visit, user);
    }
    if (!qbox_overlap(&a->box, &b->box))
        return true;
    if (a->count && b->count) {
        for (uint32_t ma = qbox_meets_mask(h, &b->box, a->child, a->count);
             ma; ma &= ma - 1) {
            uint32_t i = a->child + __builtin_ctz(ma);
            for (uint32_t m = qbox_meets_mask(h, &h->boxes[i], b->child,
                                              b->count);
                 m; m &= m - 1)
                if (!visit(user, h->items[i],
                           h->items[b->child + __builtin_ctz(m)]))
                    return false;
        }
        return true;
    }
    bool split_a = !a->count &&
                   (b->count || qbox_extent(&a->box) >= qbox_extent(&b->box));
    if (split_a)
        return geo_fbvh_pairs_with(h, a->child, nb, visit, user) &&
               geo_fbvh_pairs_with(h, a->child + 1, nb, visit, user);
    return geo_fbvh_pairs_with(h, na, b->child, visit, user) &&
           geo_fbvh_pairs_with(h, na, b->child + 1, visit, user);
}

#endif
