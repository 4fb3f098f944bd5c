/* ctx.c — error messages, progress, cancellation and the seeded generator
 * shared by every kernel. */
#include "ctx.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

int geo_err_set(geo_err *err, int code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
    }
    return code;
}

void geo_err_prefix(geo_err *err, const char *prefix)
{
    if (!err || !prefix || !*prefix)
        return;
    char tmp[sizeof err->msg];
    size_t pl = strlen(prefix);
    if (pl > sizeof tmp - 3)
        pl = sizeof tmp - 3;
    memcpy(tmp, prefix, pl);
    memcpy(tmp + pl, ": ", 2);
    size_t room = sizeof tmp - pl - 3, ml = strlen(err->msg);
    if (ml > room)
        ml = room;
    memcpy(tmp + pl + 2, err->msg, ml);
    tmp[pl + 2 + ml] = '\0';
    memcpy(err->msg, tmp, sizeof tmp);
}

int64_t geo_ctx_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000 + ts.tv_nsec;
}

bool geo_ctx_canceled(const geo_ctx *ctx)
{
    if (!ctx)
        return false;
    if (ctx->cancel &&
        atomic_load_explicit(ctx->cancel, memory_order_acquire) != 0)
        return true;
    return ctx->deadline_ns && geo_ctx_now_ns() >= ctx->deadline_ns;
}

int geo_ctx_progress(const geo_ctx *ctx, double fraction)
{
    if (!ctx)
        return 0;
    if (geo_ctx_canceled(ctx))
        return -ECANCELED;
    if (ctx->progress && ctx->progress(ctx->user, fraction) != 0)
        return -ECANCELED;
    return 0;
}

void geo_ctx_parallel_for(const geo_ctx *ctx, size_t n,
                          void (*fn)(void *arg, size_t i), void *arg)
{
    if (ctx && ctx->parallel_for) {
        ctx->parallel_for(ctx->pf_user, n, fn, arg);
        return;
    }
    for (size_t i = 0; i < n; i++)
        fn(arg, i);
}

uint64_t geo_rand_next(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

double geo_rand_unit(uint64_t *state)
{
    return (double)(geo_rand_next(state) >> 11) * 0x1.0p-53;
}
