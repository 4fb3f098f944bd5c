/* bench_inspect.c — inspection speed: parse + geo_inspect (CPU time),
 * geo_inspect and the whole `facet inspect` command on the K=400 scan
 * (target < 10 ms), and the
 * self-intersection search on a 1,000,000-triangle sphere with the BVH
 * build counted (target < 1.5 s), clean and with one vertex pushed
 * through, on 1 and 2 threads. Best of several runs (the machine may be
 * shared). Prints "name: value unit" lines. */
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>

#include "gen_sphere.h"
#include "model_io.h"
#include "parallel.h"
#include "selfint.h"
#include "stats.h"
#include "testutil.h"
#include "vec.h"

extern char **environ;

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* Process CPU time (all threads): the work done, whatever the load. */
static double cpu_now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

static double best_inspect(const geo_poly *p, int threads, int runs)
{
    par_pool *pool = par_pool_new(threads);
    geo_ctx ctx = {0};
    ctx.parallel_for = par_for;
    ctx.pf_user = pool;
    double best = 1e30;
    for (int r = 0; r < runs; r++) {
        geo_stats s;
        double t0 = now();
        if (geo_inspect(p, NULL, &ctx, &s, NULL) != 0) {
            fprintf(stderr, "bench_inspect: geo_inspect failed\n");
            exit(1);
        }
        double dt = now() - t0;
        geo_stats_clear(&s);
        if (dt < best)
            best = dt;
    }
    par_pool_free(pool);
    return best;
}

static double best_command(const char *facet, const char *model, int runs)
{
    double best = 1e30;
    for (int r = 0; r < runs; r++) {
        char *argv[] = {(char *)facet, "inspect", (char *)model, NULL};
        posix_spawn_file_actions_t fa;
        posix_spawn_file_actions_init(&fa);
        posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", 1 /*O_WRONLY*/,
                                         0);
        pid_t pid;
        double t0 = now();
        if (posix_spawn(&pid, facet, &fa, NULL, argv, environ) != 0) {
            posix_spawn_file_actions_destroy(&fa);
            return -1;
        }
        int st;
        waitpid(pid, &st, 0);
        double dt = now() - t0;
        posix_spawn_file_actions_destroy(&fa);
        if (!WIFEXITED(st) || WEXITSTATUS(st) != 0)
            return -1;
        if (dt < best)
            best = dt;
    }
    return best;
}

/* BVH build + search, best of runs; *count receives the total, *cpu the
 * CPU time of the best run. */
static double best_selfint(const geo_poly *p, int threads, int runs,
                           uint64_t *count, double *cpu)
{
    par_pool *pool = par_pool_new(threads);
    geo_ctx ctx = {0};
    ctx.parallel_for = par_for;
    ctx.pf_user = pool;
    double best = 1e30;
    for (int r = 0; r < runs; r++) {
        geo_selfint si;
        double t0 = now(), c0 = cpu_now();
        if (geo_selfint_find(p, NULL, NULL, &ctx, &si, NULL) != 0) {
            fprintf(stderr, "bench_inspect: geo_selfint_find failed\n");
            exit(1);
        }
        double dt = now() - t0, dc = cpu_now() - c0;
        *count = si.count;
        geo_selfint_clear(&si);
        if (dt < best)
            best = dt, *cpu = dc;
    }
    par_pool_free(pool);
    return best;
}

/* CPU time of parsing the model's bytes and inspecting it on the calling
 * thread (what a daemon job does at least), best of runs. */
static double best_parse_inspect_cpu(const char *path, int runs)
{
    char *text = NULL;
    size_t len = 0;
    geo_err err = {{0}};
    FILE *f = fopen(path, "rb");
    if (f) {
        fseek(f, 0, SEEK_END);
        long n = ftell(f);
        fseek(f, 0, SEEK_SET);
        text = n > 0 ? malloc((size_t)n) : NULL;
        len = text ? fread(text, 1, (size_t)n, f) : 0;
        fclose(f);
    }
    if (!text || len == 0) {
        fprintf(stderr, "bench_inspect: %s: cannot read\n", path);
        exit(1);
    }
    double best = 1e30;
    for (int r = 0; r < runs; r++) {
        double c0 = cpu_now();
        geo_poly *p = proto_model_read_mem(text, len, PROTO_FMT_JSON, NULL,
                                           &err);
        geo_stats s;
        if (!p || geo_inspect(p, NULL, NULL, &s, &err) != 0) {
            fprintf(stderr, "bench_inspect: %s: %s\n", path, err.msg);
            exit(1);
        }
        double dc = cpu_now() - c0;
        geo_stats_clear(&s);
        geo_poly_free(p);
        if (dc < best)
            best = dc;
    }
    free(text);
    return best;
}

int main(int argc, char **argv)
{
    /* --parse-inspect-cpu: only that figure for the K=400 scan, in ms
     * (bench_http.sh sets facetd's CPU per job against it) */
    if (argc == 2 && strcmp(argv[1], "--parse-inspect-cpu") == 0) {
        printf("%.3f\n", 1e3 * best_parse_inspect_cpu(
                                    tu_model_path("brilliant.scan-k400.json"),
                                    30));
        return 0;
    }
    const char *b = getenv("FACET_BUILD");
    char facet[4096];
    snprintf(facet, sizeof facet, "%s/facet", b && *b ? b : "build");
    const char *model = tu_model_path("brilliant.scan-k400.json");
    geo_err err = {{0}};
    geo_poly *p = proto_model_read_file(model, PROTO_FMT_UNKNOWN, NULL, &err);
    if (!p) {
        fprintf(stderr, "bench_inspect: %s\n", err.msg);
        return 1;
    }
    printf("inspect_k400_parse_inspect_cpu_1thread: %.2f ms\n",
           1e3 * best_parse_inspect_cpu(model, 30));
    printf("inspect_k400_geo_inspect_1thread: %.2f ms\n",
           1e3 * best_inspect(p, 1, 30));
    printf("inspect_k400_geo_inspect_2threads: %.2f ms\n",
           1e3 * best_inspect(p, 2, 30));
    double cmd = best_command(facet, model, 10);
    if (cmd < 0)
        printf("inspect_k400_command: failed (%s)\n", facet);
    else
        printf("inspect_k400_command: %.2f ms\n", 1e3 * cmd);
    geo_poly_free(p);

    p = gs_sphere(289, 1.0);
    if (!p) {
        fprintf(stderr, "bench_inspect: out of memory\n");
        return 1;
    }
    printf("sphere_triangles: %u\n", p->nfacets);
    for (int pushed = 0; pushed < 2; pushed++) {
        if (pushed) /* through the centre and out beyond the far side */
            geo_vscale(p->verts[p->nverts / 3], -1.5, p->verts[p->nverts / 3]);
        for (int th = 1; th <= 2; th++) {
            uint64_t count = 0;
            double cpu = 0, t = best_selfint(p, th, 3, &count, &cpu);
            printf("selfint_sphere1m_%s_%dthread%s: %.3f s (cpu %.3f s, "
                   "count %llu)\n",
                   pushed ? "pushed" : "clean", th, th > 1 ? "s" : "", t, cpu,
                   (unsigned long long)count);
        }
    }
    geo_poly_free(p);
    return 0;
}
