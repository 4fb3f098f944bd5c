/* bench_correct.c — the automatic correction (lib/correct/correct.h) and its
 * parts. Targets: `facet correct`'s kernel on brilliant.scan-k400.json
 * under 50 ms, on brilliant.scan-k800.json (4,404 vertices) under 100 ms,
 * on a synthetic scan of about 8,000 vertices under 200 ms: the jubilee
 * (sim_stone(SIM_JUBILEE), whose 128-facet girdle is beyond the scan's
 * resolution) at K = 1600, 7,122 vertices, and the jubilee96 (the same
 * crown and pavilion on a 96-facet girdle, which the correction resolves)
 * at K = 2400, 7,982 vertices. Best of several runs; the parts
 * (inspection, merging, cluster collapse, Hausdorff estimate) are timed
 * alone too. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "clusters.h"
#include "correct.h"
#include "hausdorff.h"
#include "merge.h"
#include "stats.h"
#include "stone_sim.h"
#include "tu_load.h"

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

/* Best of runs of geo_correct on copies of p. */
static double correct_ms(const geo_poly *p, int runs, uint32_t *ret_facets)
{
    double best = 1e30;
    for (int i = 0; i < runs; i++) {
        geo_poly *q = geo_poly_copy(p);
        geo_correct_report rep;
        geo_err err;
        double t0 = now_ms();
        int r = geo_correct(q, NULL, NULL, &rep, &err);
        double ms = now_ms() - t0;
        if (r < 0) {
            fprintf(stderr, "bench_correct: %s\n", err.msg);
            exit(1);
        }
        if (!rep.after.valid) {
            fprintf(stderr, "bench_correct: result not valid\n");
            exit(1);
        }
        *ret_facets = q->nfacets;
        geo_correct_report_clear(&rep);
        geo_poly_free(q);
        if (ms < best)
            best = ms;
    }
    return best;
}

static void parts(const char *name, const geo_poly *p, int runs)
{
    double bi = 1e30, bm = 1e30, bc = 1e30, bh = 1e30;
    geo_poly *merged = NULL;
    for (int i = 0; i < runs; i++) {
        geo_stats st;
        double t0 = now_ms();
        geo_inspect(p, NULL, NULL, &st, NULL);
        double t1 = now_ms();
        geo_stats_clear(&st);
        geo_poly *q = geo_poly_copy(p);
        geo_merge_report mr = {0};
        double t2 = now_ms();
        geo_merge_auto(q, NULL, NULL, &mr, NULL);
        double t3 = now_ms();
        geo_merge_report_clear(&mr);
        geo_collapse_report cr;
        double t4 = now_ms();
        geo_collapse(q, NULL, NULL, &cr, NULL);
        double t5 = now_ms();
        geo_collapse_report_clear(&cr);
        double h;
        double t6 = now_ms();
        geo_hausdorff(p, q, &h, NULL);
        double t7 = now_ms();
        bi = t1 - t0 < bi ? t1 - t0 : bi;
        bm = t3 - t2 < bm ? t3 - t2 : bm;
        bc = t5 - t4 < bc ? t5 - t4 : bc;
        bh = t7 - t6 < bh ? t7 - t6 : bh;
        geo_poly_free(merged);
        merged = q;
    }
    printf("%s inspect: %.2f ms\n", name, bi);
    printf("%s merge (all rounds): %.2f ms\n", name, bm);
    printf("%s collapse after merging: %.2f ms\n", name, bc);
    printf("%s hausdorff: %.2f ms\n", name, bh);
    geo_poly_free(merged);
}

int main(void)
{
    const char *names[] = {"brilliant.scan-k100.json", "brilliant.scan-k400.json",
                           "brilliant.scan-k800.json"};
    const char *tags[] = {"k100", "k400", "k800"};
    for (int i = 0; i < 3; i++) {
        geo_poly *p = tu_load_model(names[i]);
        if (!p)
            return 1;
        uint32_t f;
        double ms = correct_ms(p, 7, &f);
        printf("correct %s (%u vertices, %u facets -> %u): %.2f ms\n", tags[i],
               p->nverts, p->nfacets, f, ms);
        parts(tags[i], p, 5);
        geo_poly_free(p);
    }
    geo_poly *stone = sim_stone(SIM_JUBILEE, 1);
    geo_poly *scan = stone ? sim_scan(stone, 1600, 0.001, 1) : NULL;
    if (!scan)
        return 1;
    uint32_t f;
    double ms = correct_ms(scan, 3, &f);
    printf("correct jubilee K=1600 (%u vertices, %u facets -> %u): %.2f ms\n",
           scan->nverts, scan->nfacets, f, ms);
    parts("jubilee-k1600", scan, 3);
    geo_poly_free(scan);
    geo_poly_free(stone);
    stone = sim_stone(SIM_JUBILEE96, 1);
    scan = stone ? sim_scan(stone, 2400, 0.001, 1) : NULL;
    if (!scan)
        return 1;
    ms = correct_ms(scan, 3, &f);
    printf("correct jubilee96 K=2400 (%u vertices, %u facets -> %u): %.2f ms\n",
           scan->nverts, scan->nfacets, f, ms);
    parts("jubilee96-k2400", scan, 3);
    geo_poly_free(scan);
    geo_poly_free(stone);
    return 0;
}
