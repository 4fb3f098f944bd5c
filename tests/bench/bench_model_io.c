/* bench_model_io.c — parse and write times of the model formats on the
 * K=400 scan (best of N runs, the file already in memory). Target: JSON
 * parse under 10 ms. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "model_io.h"
#include "testutil.h"

enum { RUNS = 30 };

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static double best_parse(const char *data, size_t len, proto_format fmt)
{
    double best = 1e30;
    for (int i = 0; i < RUNS; i++) {
        double t0 = now_ms();
        geo_err err;
        geo_poly *p = proto_model_read_mem(data, len, fmt, NULL, &err);
        double t = now_ms() - t0;
        if (!p) {
            fprintf(stderr, "%s: %s\n", proto_format_name(fmt), err.msg);
            exit(1);
        }
        geo_poly_free(p);
        if (t < best)
            best = t;
    }
    return best;
}

static double best_write(const geo_poly *p, proto_format fmt, char **ret,
                         size_t *ret_len)
{
    double best = 1e30;
    for (int i = 0; i < RUNS; i++) {
        double t0 = now_ms();
        geo_err err;
        if (proto_model_write_mem(p, fmt, ret, ret_len, &err) < 0) {
            fprintf(stderr, "%s: %s\n", proto_format_name(fmt), err.msg);
            exit(1);
        }
        double t = now_ms() - t0;
        if (i + 1 < RUNS)
            free(*ret);
        if (t < best)
            best = t;
    }
    return best;
}

int main(void)
{
    const char *path = tu_model_path("brilliant.scan-k400.json");
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        return 1;
    }
    static char data[8 << 20];
    size_t len = fread(data, 1, sizeof data, f);
    fclose(f);
    geo_err err;
    geo_poly *p = proto_model_read_mem(data, len, PROTO_FMT_JSON, NULL, &err);
    if (!p) {
        fprintf(stderr, "%s: %s\n", path, err.msg);
        return 1;
    }
    printf("model: %u vertices, %u facets, %zu bytes of JSON\n", p->nverts,
           p->nfacets, len);
    const proto_format fmts[] = {PROTO_FMT_JSON, PROTO_FMT_POLY,
                                 PROTO_FMT_OBJ, PROTO_FMT_STL,
                                 PROTO_FMT_STL_ASCII, PROTO_FMT_PLY,
                                 PROTO_FMT_PLY_ASCII, PROTO_FMT_FMB1,
                                 PROTO_FMT_ASE};
    for (size_t i = 0; i < sizeof fmts / sizeof fmts[0]; i++) {
        char *buf;
        size_t n;
        double w = best_write(p, fmts[i], &buf, &n);
        printf("write_%s: %.3f ms (%zu bytes)\n", proto_format_name(fmts[i]),
               w, n);
        if (fmts[i] != PROTO_FMT_ASE)
            printf("parse_%s: %.3f ms\n", proto_format_name(fmts[i]),
                   best_parse(buf, n, fmts[i]));
        free(buf);
    }
    geo_poly_free(p);
    return 0;
}
