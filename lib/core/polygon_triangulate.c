/* polygon_triangulate.c — ear clipping of one polygon in its best
 * projection plane, with exact orientation signs.
 *
 * Invariants of the clipping loop: the remaining corners form a cycle
 * through next[]/prev[]; kind[i] is the exact turn at corner i among the
 * remaining corners (+1 convex, 0 straight, −1 reflex, all seen from the
 * side the polygon's Newell normal points to) and is recomputed only for
 * the two neighbours of a clipped corner. Only non-convex corners can lie
 * inside an ear of a simple polygon, so only they are tested.
 *
 * Termination on any input: when a full turn around the cycle finds no
 * ear, the test is relaxed one step (corners on the ear's border allowed,
 * then any convex corner, then any corner); every step clips one corner,
 * so exactly n − 2 triangles come out. */
#include "polygon_triangulate.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

#include "predicates.h"

typedef struct ring {
    const double *xyz;
    const uint32_t *idx;
    uint32_t *next, *prev;
    int8_t *kind;
    int drop; /* coordinate axis dropped by the projection */
    int sign; /* +1 when the normal points along +drop */
} ring;

static const double *pt(const ring *r, uint32_t i)
{
    return r->xyz + 3 * (size_t)r->idx[i];
}

static int turn(const ring *r, uint32_t a, uint32_t b, uint32_t c)
{
    return r->sign * geo_orient2d_proj(pt(r, a), pt(r, b), pt(r, c), r->drop);
}

static void update_kind(ring *r, uint32_t i)
{
    r->kind[i] = (int8_t)turn(r, r->prev[i], i, r->next[i]);
}

/* Relaxation levels of the ear test. */
enum { EAR_STRICT, EAR_BORDER_OK, EAR_ANY_CONVEX, EAR_ANY };

static int is_ear(const ring *r, uint32_t i, int level)
{
    if (level == EAR_ANY)
        return 1;
    if (r->kind[i] <= 0)
        return 0;
    if (level == EAR_ANY_CONVEX)
        return 1;
    uint32_t a = r->prev[i], c = r->next[i];
    for (uint32_t j = r->next[c]; j != a; j = r->next[j]) {
        if (r->kind[j] > 0)
            continue;
        int s1 = turn(r, a, i, j), s2 = turn(r, i, c, j), s3 = turn(r, c, a, j);
        if (level == EAR_STRICT) {
            if (s1 >= 0 && s2 >= 0 && s3 >= 0)
                return 0;
        } else if (s1 > 0 && s2 > 0 && s3 > 0) {
            return 0;
        }
    }
    return 1;
}

/* Newell normal relative to the first corner; picks the projection. */
static int choose_projection(ring *r, uint32_t n)
{
    double nrm[3] = {0, 0, 0};
    const double *o = pt(r, 0);
    for (uint32_t i = 1; i + 1 < n; i++) {
        const double *a = pt(r, i), *b = pt(r, i + 1);
        double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]};
        double v[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
        nrm[0] += u[1] * v[2] - u[2] * v[1];
        nrm[1] += u[2] * v[0] - u[0] * v[2];
        nrm[2] += u[0] * v[1] - u[1] * v[0];
    }
    int d = 0;
    for (int k = 1; k < 3; k++)
        if (fabs(nrm[k]) > fabs(nrm[d]))
            d = k;
    if (nrm[d] == 0)
        return -1;
    r->drop = d;
    r->sign = nrm[d] > 0 ? 1 : -1;
    return 0;
}

static void fan(uint32_t n, uint32_t (*ret)[3])
{
    for (uint32_t i = 1; i + 1 < n; i++) {
        ret[i - 1][0] = 0;
        ret[i - 1][1] = i;
        ret[i - 1][2] = i + 1;
    }
}

static void clip(ring *r, uint32_t n, uint32_t (*ret)[3])
{
    uint32_t remaining = n, out = 0, cur = 0, since_clip = 0;
    int level = EAR_STRICT;
    while (remaining > 3) {
        if (is_ear(r, cur, level)) {
            uint32_t a = r->prev[cur], c = r->next[cur];
            ret[out][0] = a;
            ret[out][1] = cur;
            ret[out][2] = c;
            out++;
            r->next[a] = c;
            r->prev[c] = a;
            remaining--;
            update_kind(r, a);
            update_kind(r, c);
            cur = c;
            since_clip = 0;
            level = EAR_STRICT;
            continue;
        }
        cur = r->next[cur];
        if (++since_clip >= remaining) {
            level++;
            since_clip = 0;
        }
    }
    ret[out][0] = r->prev[cur];
    ret[out][1] = cur;
    ret[out][2] = r->next[cur];
}

int geo_polygon_triangulate(const double *xyz, const uint32_t *idx,
                            uint32_t n, uint32_t (*ret_tris)[3])
{
    if (n < 3)
        return -EINVAL;
    ring r = {.xyz = xyz, .idx = idx};
    if (n == 3 || choose_projection(&r, n) < 0) {
        fan(n, ret_tris);
        return 0;
    }
    enum { STACK = 64 };
    uint32_t next_s[STACK], prev_s[STACK];
    int8_t kind_s[STACK];
    void *heap = NULL;
    if (n <= STACK) {
        r.next = next_s;
        r.prev = prev_s;
        r.kind = kind_s;
    } else {
        heap = malloc((size_t)n * (2 * sizeof(uint32_t) + 1));
        if (!heap)
            return -ENOMEM;
        r.next = heap;
        r.prev = r.next + n;
        r.kind = (int8_t *)(r.prev + n);
    }
    int convex = 1;
    for (uint32_t i = 0; i < n; i++) {
        r.next[i] = i + 1 == n ? 0 : i + 1;
        r.prev[i] = i == 0 ? n - 1 : i - 1;
    }
    for (uint32_t i = 0; i < n; i++) {
        update_kind(&r, i);
        if (r.kind[i] <= 0)
            convex = 0;
    }
    if (convex)
        fan(n, ret_tris);
    else
        clip(&r, n, ret_tris);
    free(heap);
    return 0;
}
