/* scansim.c — writes a simulated stone and its shadow-profile scan as
 * facet-model/1 JSON (tests/support/stone_sim.h), for the correction's
 * acceptance runs and for anyone who wants a scan to look at.
 *
 *   scansim --cut brilliant|princess|emerald|jubilee|jubilee96 [--k 400]
 *           [--seed 3]
 *           [--noise 0.001] [--truth T.json] [--scan S.json]
 *   scansim --design D.asc [--width 6.5] ... (the same options)
 *
 * With --design the stone is a GemCad design (tests/support/design.h)
 * scaled to --width mm across; otherwise the stone's proportions come
 * from --seed, the scan's silhouette noise
 * (mm, standard deviation) from --noise and the same seed. Prints one line
 * "cut=... seed=... k=... truth=V/F scan=V/F hausdorff_mm=..." (the scan's
 * Hausdorff distance to the stone, sim_hausdorff with 2000 samples per
 * facet budget). Exit 0, 1 on failure, 2 on bad usage. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "design.h"
#include "model_io.h"
#include "stone_sim.h"

static int usage(const char *msg)
{
    fprintf(stderr, "scansim: %s\nusage: scansim --cut brilliant|princess|"
            "emerald|jubilee|jubilee96 | --design D.asc [--width 6.5]] "
            "[--k 400] [--seed 3] [--noise 0.001] "
            "[--truth T.json] [--scan S.json]\n", msg);
    return 2;
}

static int parse_u(const char *s, unsigned long max, unsigned long *ret)
{
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (errno || end == s || *end || v > max)
        return -1;
    *ret = v;
    return 0;
}

int main(int argc, char **argv)
{
    const char *cut = NULL, *truth_path = NULL, *scan_path = NULL;
    const char *design = NULL;
    double width = DESIGN_WIDTH_MM;
    unsigned long k = 400, seed = 3;
    double noise = 0.001;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (i + 1 >= argc)
            return usage("every option needs a value");
        const char *v = argv[++i];
        if (strcmp(a, "--cut") == 0)
            cut = v;
        else if (strcmp(a, "--design") == 0)
            design = v;
        else if (strcmp(a, "--width") == 0) {
            char *end;
            width = strtod(v, &end);
            if (end == v || *end || !(width > 0) || width > 1000)
                return usage("--width: expected mm in (0, 1000]");
        }
        else if (strcmp(a, "--k") == 0) {
            if (parse_u(v, 100000, &k) < 0 || k == 0)
                return usage("--k: expected a number of views 1..100000");
        } else if (strcmp(a, "--seed") == 0) {
            if (parse_u(v, (unsigned long)-1, &seed) < 0)
                return usage("--seed: expected a non-negative integer");
        } else if (strcmp(a, "--noise") == 0) {
            char *end;
            noise = strtod(v, &end);
            if (end == v || *end || !(noise >= 0) || noise > 1)
                return usage("--noise: expected mm in [0, 1]");
        } else if (strcmp(a, "--truth") == 0)
            truth_path = v;
        else if (strcmp(a, "--scan") == 0)
            scan_path = v;
        else
            return usage("unknown option");
    }
    enum sim_cut c = SIM_BRILLIANT;
    if (!cut && !design)
        return usage("--cut or --design is required");
    if (design)
        cut = design;
    else if (strcmp(cut, "brilliant") == 0)
        c = SIM_BRILLIANT;
    else if (strcmp(cut, "princess") == 0)
        c = SIM_PRINCESS;
    else if (strcmp(cut, "emerald") == 0)
        c = SIM_EMERALD;
    else if (strcmp(cut, "jubilee") == 0)
        c = SIM_JUBILEE;
    else if (strcmp(cut, "jubilee96") == 0)
        c = SIM_JUBILEE96;
    else
        return usage("--cut: expected brilliant, princess, emerald, jubilee or "
                         "jubilee96");

    geo_err err;
    geo_poly *stone = NULL;
    if (design) {
        stone = design_load(design, width, &err);
        if (!stone) {
            fprintf(stderr, "scansim: %s\n", err.msg);
            return 1;
        }
    } else {
        stone = sim_stone(c, seed);
    }
    geo_poly *scan = stone ? sim_scan(stone, (uint32_t)k, noise, seed) : NULL;
    if (!stone || !scan) {
        fprintf(stderr, "scansim: the simulation failed\n");
        geo_poly_free(stone);
        geo_poly_free(scan);
        return 1;
    }
    int rc = 0;
    if (truth_path && proto_model_write_file(stone, truth_path, PROTO_FMT_JSON, &err) < 0) {
        fprintf(stderr, "scansim: %s\n", err.msg);
        rc = 1;
    }
    if (scan_path && proto_model_write_file(scan, scan_path, PROTO_FMT_JSON, &err) < 0) {
        fprintf(stderr, "scansim: %s\n", err.msg);
        rc = 1;
    }
    printf("cut=%s seed=%lu k=%lu truth=%u/%u scan=%u/%u hausdorff_mm=%.6g\n",
           cut, seed, k, stone->nverts, stone->nfacets, scan->nverts,
           scan->nfacets, sim_hausdorff(scan, stone, 2000));
    geo_poly_free(stone);
    geo_poly_free(scan);
    return rc;
}
