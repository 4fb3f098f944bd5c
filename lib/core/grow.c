/* grow.c — capacity doubling for dynamic arrays (grow.h). */
#include "grow.h"

#include <assert.h>
#include <errno.h>
#include <stdint.h>
#include <stdlib.h>

int geo_grow(void **buf, size_t *cap, size_t need, size_t elem)
{
    assert(elem > 0 && (*buf != NULL || *cap == 0));
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 16;
    while (c < need) {
        if (c > SIZE_MAX / 2)
            return -ENOMEM;
        c *= 2;
    }
    if (elem && c > SIZE_MAX / elem)
        return -ENOMEM;
    void *b = realloc(*buf, c * elem);
    if (!b)
        return -ENOMEM;
    *buf = b;
    *cap = c;
    return 0;
}
