/* correct_table.c — the acceptance table of the correction
 * (docs/kernels/correct-convex.md): simulated stones (tests/support/
 * stone_sim.h) scanned with K views and silhouette noise, each scan
 * corrected, the result compared with the stone facet by facet
 * (tests/support/fidelity.h).
 *
 *   correct_table [--cuts brilliant,princess,...] [--seeds 1,2,3]
 *                 [--ks 100,400,800] [--noise 1,...]  (µm)
 *                 [--suite N [--first I]]
 *                 [--method auto|merge|planes|groups]
 *                 [--fit area|hinge|silhouette] [--rows] [--models DIR]
 *                 [--write DIR]
 *
 * Without --suite: every cut × seed × K × noise, views at phase 0 and
 * the stone as drawn. With --suite N: the fixed suite of N scans, scan i
 * drawn from seed i: a cut (in turn), K in {100, 200, 400, 800}, noise
 * uniform in 0–3 µm, a random view phase and stone azimuth. --method:
 * auto = geo_correct as it defaults (the convex path on), merge =
 * the convex path off (the Palachev 2012 merge only), planes = geo_convex_planes_find
 * intersected by the simulator (the planes alone, no checks), groups =
 * the true grouping given and the rest as geo_correct's silhouette fit
 * (correct_known_groups: what the grouping costs); --fit
 * the convex path's plane fit (convex.h; geo_correct's by default; with
 * --method planes the silhouette fit adjusts the planes, still without
 * the checks). --write: each row's stone, scan and result also go to
 * DIR/CUT-SEED-K.{truth,scan,corrected}.json, to look at one scan of the
 * suite with `facet compare` or the viewer.
 *
 * One Markdown row per scan (--rows; always without --suite): cut, seed,
 * K, noise, facets truth / scan / corrected, recovered % (normal within
 * 0.1° for K ≥ 400, 0.25° below, within 5 µm of the true centroid, one to
 * one), attainable % from the silhouettes and from the scan (the
 * Cramér–Rao bounds of scan_bound.h: every silhouette vertex of every
 * view, and only what the scanned model keeps of them; "—" for a scan
 * read from a file), angle
 * error median and p95 (°), Hausdorff to the truth of the
 * scan and of the result (µm) and their ratio, facet count error,
 * validity, ms. Then the totals per cut and K, the worst scans, and a
 * last line: scans, recovered %, scans meeting the four
 * acceptance figures, invalid results (and, when there are any, the scans
 * the simulator could not make, each also in its row). Exit status 1
 * when a result is invalid or a scan could not be made. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "convex.h"
#include "vec.h"
#include "correct.h"
#include "fidelity.h"
#include "halfspace.h"
#include "model_io.h"
#include "scan_bound.h"
#include "stone_sim.h"

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

enum method { M_AUTO, M_MERGE, M_PLANES, M_GROUPS };

#define MAX_CUTS 16
#define NKS 4
static const unsigned suite_ks[NKS] = {100, 200, 400, 800};

/* bound_truth, attainable, kept: the true facets of the scans with a
 * bound (scan_bound.h) and how many of them a correction at the bound
 * gets, from the silhouettes and from the scan */
typedef struct cell {
    unsigned scans, truth, recovered, bound_truth;
    double attainable, kept;
} cell;

typedef struct worst {
    char name[96];
    double rec;
} worst;

typedef struct totals {
    unsigned rows, meets, invalid, truth, recovered, bound_truth;
    unsigned unsimulated; /* scans the simulator could not make */
    double attainable, kept;
    cell cells[MAX_CUTS][NKS];
    worst w[8];
    double ratio_sum;
} totals;

/* "12.3 %" of a over n, in a static buffer (one use per printf). */
static const char *pct(double a, unsigned n)
{
    static char buf[32];
    snprintf(buf, sizeof buf, "%.1f %%", n ? 100.0 * a / n : 0);
    return buf;
}

static int kslot(unsigned k)
{
    return k < 150 ? 0 : k < 300 ? 1 : k < 600 ? 2 : 3;
}

static void note_worst(totals *t, const char *name, double rec)
{
    int n = sizeof t->w / sizeof t->w[0], at = -1;
    for (int i = 0; i < n; i++)
        if (t->w[i].name[0] == 0 || rec < t->w[i].rec) {
            at = i;
            break;
        }
    if (at < 0)
        return;
    memmove(&t->w[at + 1], &t->w[at], (size_t)(n - at - 1) * sizeof t->w[0]);
    snprintf(t->w[at].name, sizeof t->w[at].name, "%s", name);
    t->w[at].rec = rec;
}

/* The correction by the chosen method; a new model or NULL (msg set). */
static enum geo_convex_fit fit; /* geo_correct's unless --fit */

/* --method groups: the grouping known, the rest as geo_correct's
 * silhouette fit does it. Each scan facet goes to the true plane its
 * vertices lie nearest (the largest distance of its vertices the least);
 * a group's plane is the sum of its facets' area vectors, through their
 * area-weighted centroid (the area fit's normal and offset), a true facet
 * no scan facet went to keeps its true plane; the planes are then
 * adjusted to the silhouettes (geo_convex_refine from their intersection)
 * and intersected. What the correction could give back were its groups
 * right: its recovered % against auto's says how much of the gap to the
 * bound the grouping makes. A new model or NULL (msg set). */
static geo_poly *correct_known_groups(const geo_poly *scan,
                                      const geo_poly *truth, char *msg,
                                      size_t len)
{
    uint32_t n = truth->nfacets;
    double(*pl)[4] = malloc(((size_t)n + 1) * sizeof *pl);
    double(*acc)[4] = calloc((size_t)n + 1, sizeof *acc);
    if (!pl || !acc) {
        free(pl), free(acc);
        snprintf(msg, len, "out of memory");
        return NULL;
    }
    for (uint32_t f = 0; f < n; f++)
        geo_poly_facet_plane(truth, f, pl[f]);
    for (uint32_t g = 0; g < scan->nfacets; g++) {
        uint32_t nv = geo_poly_facet_size(scan, g);
        const uint32_t *v = geo_poly_facet(scan, g);
        double best = INFINITY, av[3], c[3] = {0, 0, 0};
        uint32_t bf = 0;
        for (uint32_t f = 0; f < n; f++) {
            double d = 0;
            for (uint32_t i = 0; i < nv; i++)
                d = fmax(d, fabs(geo_vdot(pl[f], scan->verts[v[i]]) +
                                 pl[f][3]));
            if (d < best)
                best = d, bf = f;
        }
        geo_poly_facet_area_vector(scan, g, av);
        for (uint32_t i = 0; i < nv; i++)
            for (int k = 0; k < 3; k++)
                c[k] += scan->verts[v[i]][k] / nv;
        for (int k = 0; k < 3; k++)
            acc[bf][k] += av[k];
        acc[bf][3] += geo_vdot(av, c); /* area × the offset along av */
    }
    for (uint32_t f = 0; f < n; f++) {
        double a = sqrt(geo_vdot(acc[f], acc[f]));
        if (!(a > 0))
            continue;
        for (int k = 0; k < 3; k++)
            pl[f][k] = acc[f][k] / a;
        pl[f][3] = -acc[f][3] / a;
    }
    free(acc);
    geo_err err;
    double noise = 0, sc;
    geo_merge_opts mo;
    geo_merge_opts_default(&mo);
    geo_poly *est = NULL;
    uint32_t *src = NULL;
    enum geo_halfspace_status st;
    if (geo_merge_surface_noise(scan, NULL, &mo, NULL, &noise, &err) == 0 &&
        geo_halfspace_intersect(&pl[0][0], n,
                                GEO_HALFSPACE_MERGE * geo_poly_size(scan),
                                &est, &src, &st, &err) == 0)
        geo_convex_refine(scan, est, src, GEO_CONVEX_REFINE_CLUSTER * noise,
                          pl, n, NULL, &sc);
    geo_poly_free(est);
    free(src);
    geo_poly *p = sim_halfspace_intersection(&pl[0][0], n, 10.0);
    free(pl);
    if (!p)
        snprintf(msg, len, "empty intersection");
    return p;
}

static geo_poly *correct(const geo_poly *scan, const geo_poly *truth,
                         enum method m, bool *valid, char *msg, size_t len)
{
    geo_err err;
    *valid = false;
    if (m == M_GROUPS) {
        geo_poly *q = correct_known_groups(scan, truth, msg, len);
        geo_stats st;
        if (q && geo_inspect(q, NULL, NULL, &st, &err) == 0)
            *valid = st.valid;
        if (q)
            geo_stats_clear(&st);
        return q;
    }
    geo_poly *p = geo_poly_copy(scan);
    if (m == M_PLANES) {
        uint32_t views = 0;
        double noise = 0;
        geo_merge_opts mo;
        geo_merge_opts_default(&mo);
        geo_convex_planes cp;
        if (geo_merge_view_grid(scan, &views, NULL) < 0 ||
            geo_merge_surface_noise(scan, NULL, &mo, NULL, &noise, &err) < 0 ||
            geo_convex_planes_find(scan, views, noise, fit, NULL, &cp, &err) < 0) {
            snprintf(msg, len, "%s", err.msg);
            return geo_poly_free(p);
        }
        if (fit == GEO_CONVEX_FIT_SILHOUETTE) {
            /* the adjustment needs the planes' intersection and which
             * plane bounds each of its facets */
            geo_poly *est = NULL;
            uint32_t *src = NULL;
            enum geo_halfspace_status st;
            double sc;
            if (geo_halfspace_intersect(&cp.planes[0][0], cp.nplanes,
                                        GEO_HALFSPACE_MERGE * geo_poly_size(scan),
                                        &est, &src, &st, &err) == 0)
                geo_convex_refine(scan, est, src,
                                  GEO_CONVEX_REFINE_CLUSTER *
                                      fmax(cp.dev0, cp.hinge_noise),
                                  cp.planes, cp.nplanes, NULL, &sc);
            geo_poly_free(est);
            free(src);
        }
        geo_poly_free(p);
        p = sim_halfspace_intersection(&cp.planes[0][0], cp.nplanes, 10.0);
        geo_convex_planes_clear(&cp);
        if (!p) {
            snprintf(msg, len, "empty intersection");
            return NULL;
        }
        geo_stats st;
        if (geo_inspect(p, NULL, NULL, &st, &err) == 0)
            *valid = st.valid;
        geo_stats_clear(&st);
        return p;
    }
    geo_correct_opts o;
    geo_correct_opts_default(&o);
    o.convex = m != M_MERGE;
    o.convex_fit = fit;
    geo_correct_report rep;
    if (!p || geo_correct(p, &o, NULL, &rep, &err) < 0) {
        snprintf(msg, len, "%s", p ? err.msg : "out of memory");
        return geo_poly_free(p);
    }
    *valid = rep.after.valid;
    if (o.convex && !rep.convex)
        fprintf(stderr, "merge fallback: %s\n", rep.convex_report.reason);
    geo_correct_report_clear(&rep);
    return p;
}

/* A scan the simulator could not make (sim_scan gave NULL: out of memory,
 * or a clip in doubles that left nothing): said in its row and counted,
 * never left out in silence. */
static void no_scan(const char *cut, unsigned seed, unsigned k,
                    double noise_um, totals *t)
{
    printf("| %s | %u | %u | %.1f | error: the simulator made no scan of "
           "this stone |\n", cut, seed, k, noise_um);
    t->unsimulated++;
}

/* --write: where each row's models go, NULL for nowhere */
static const char *write_dir;

/* Writes m to write_dir/name.kind.json; a failure is said, not fatal. */
static void write_model(const geo_poly *m, const char *name, const char *kind)
{
    if (!write_dir || !m)
        return;
    char path[512];
    geo_err err;
    snprintf(path, sizeof path, "%s/%s.%s.json", write_dir, name, kind);
    if (proto_model_write_file(m, path, PROTO_FMT_UNKNOWN, &err) < 0)
        fprintf(stderr, "correct_table: %s\n", err.msg);
}

/* phase: the scan's view phase (sim_scan_phase), NAN when the scan was
 * not simulated here (then no bound). */
static void row(const char *cut, int ci, unsigned seed, unsigned k,
                double noise_um, double phase, const geo_poly *truth,
                const geo_poly *scan, enum method m, bool rows, totals *t)
{
    char msg[600] = "";
    bool valid;
    double t0 = now();
    geo_poly *p = correct(scan, truth, m, &valid, msg, sizeof msg);
    double ms = (now() - t0) * 1e3;
    t->rows++;
    char file[96];
    snprintf(file, sizeof file, "%s-%u-%u", cut, seed, k);
    write_model(truth, file, "truth");
    write_model(scan, file, "scan");
    write_model(p, file, "corrected");
    char name[96];
    snprintf(name, sizeof name, "%s seed %u K %u noise %.1f µm", cut, seed, k,
             noise_um);
    if (!p) {
        printf("| %s | %u | %u | %.1f | error: %s |\n", cut, seed, k, noise_um, msg);
        t->invalid++;
        note_worst(t, name, 0);
        return;
    }
    sim_fidelity fd;
    double tol = k >= 400 ? 0.1 : 0.25;
    sim_fidelity_measure(truth, p, tol, 0.005, &fd);
    double hs = sim_hausdorff(scan, truth, 2000) * 1e3;
    double hc = sim_hausdorff(p, truth, 2000) * 1e3;
    double rec = 100.0 * fd.recovered / fd.truth;
    sim_scan_bound bd = {0}, bs = {0};
    bool bounded = !isnan(phase) &&
                   sim_scan_bound_measure(truth, k, noise_um * 1e-3, phase, tol,
                                          NULL, &bd) == 0 &&
                   sim_scan_bound_of_scan(truth, scan, noise_um * 1e-3, tol,
                                          NULL, &bs) == 0;
    double ferr = 100.0 * ((double)p->nfacets / truth->nfacets - 1);
    bool meets = rec >= 95 && fabs(ferr) <= 5 && fd.spurious == 0 &&
                 hc <= 0.8 * hs && valid;
    t->meets += meets;
    t->invalid += !valid;
    t->truth += fd.truth;
    t->recovered += fd.recovered;
    t->ratio_sum += hs > 0 ? hc / hs : 1;
    cell *c = &t->cells[ci][kslot(k)];
    c->scans++;
    c->truth += fd.truth;
    c->recovered += fd.recovered;
    if (bounded) {
        c->bound_truth += fd.truth;
        c->attainable += bd.attainable;
        c->kept += bs.attainable;
        t->bound_truth += fd.truth;
        t->attainable += bd.attainable;
        t->kept += bs.attainable;
    }
    note_worst(t, name, rec);
    if (rows) {
        printf("| %s | %u | %u | %.1f | %u / %u / %u | %.1f | %s / ", cut,
               seed, k, noise_um, truth->nfacets, scan->nfacets, p->nfacets,
               rec, bounded ? pct(bd.attainable, bd.truth) : "—");
        printf("%s | %.3f / %.3f | %.2f / %.2f (%.2f) | %+.1f%% | %s | %s | "
               "%.0f |\n", bounded ? pct(bs.attainable, bs.truth) : "—",
               fd.angle_median, fd.angle_p95, hs, hc,
               hs > 0 ? hc / hs : 1, ferr, valid ? "yes" : "NO",
               meets ? "yes" : "no", ms);
    }
    fflush(stdout);
    geo_poly_free(p);
}

static int split(char *s, char **out, int max)
{
    int n = 0;
    for (char *tok = strtok(s, ","); tok && n < max; tok = strtok(NULL, ","))
        out[n++] = tok;
    return n;
}

static const struct {
    const char *name;
    enum sim_cut cut;
} cut_names[] = {
    {"brilliant", SIM_BRILLIANT}, {"princess", SIM_PRINCESS},
    {"emerald", SIM_EMERALD},     {"jubilee", SIM_JUBILEE},
    {"jubilee96", SIM_JUBILEE96},
};

static int find_cut(const char *s)
{
    for (size_t i = 0; i < sizeof cut_names / sizeof cut_names[0]; i++)
        if (strcmp(cut_names[i].name, s) == 0)
            return (int)i;
    return -1;
}

static double unit(uint64_t *s)
{
    *s = *s * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*s >> 11) / 9007199254740992.0;
}

int main(int argc, char **argv)
{
    char cuts_s[256] = "brilliant,princess,emerald,jubilee96";
    char seeds_s[256] = "1,2,3", ks_s[256] = "100,400,800", noise_s[256] = "1";
    const char *models = NULL;
    unsigned suite = 0, first = 0;
    bool rows = false;
    enum method m = M_AUTO;
    geo_correct_opts defaults;
    geo_correct_opts_default(&defaults);
    fit = defaults.convex_fit;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (strcmp(a, "--rows") == 0) {
            rows = true;
            continue;
        }
        if (!v) {
            fprintf(stderr, "correct_table: %s needs a value\n", a);
            return 2;
        }
        i++;
        if (strcmp(a, "--cuts") == 0)
            snprintf(cuts_s, sizeof cuts_s, "%s", v);
        else if (strcmp(a, "--seeds") == 0)
            snprintf(seeds_s, sizeof seeds_s, "%s", v);
        else if (strcmp(a, "--ks") == 0)
            snprintf(ks_s, sizeof ks_s, "%s", v);
        else if (strcmp(a, "--noise") == 0)
            snprintf(noise_s, sizeof noise_s, "%s", v);
        else if (strcmp(a, "--suite") == 0)
            suite = (unsigned)strtoul(v, NULL, 10);
        else if (strcmp(a, "--first") == 0)
            first = (unsigned)strtoul(v, NULL, 10);
        else if (strcmp(a, "--method") == 0) {
            static const char *names[] = {"auto", "merge", "planes", "groups"};
            int k = 0;
            while (k < 4 && strcmp(v, names[k]) != 0)
                k++;
            if (k == 4) {
                fprintf(stderr, "correct_table: --method: unknown '%s' "
                        "(auto, merge, planes, groups)\n", v);
                return 2;
            }
            m = (enum method)k;
        } else if (strcmp(a, "--fit") == 0) {
            static const char *names[] = {"area", "hinge", "silhouette"};
            int k = 0;
            while (k < 3 && strcmp(v, names[k]) != 0)
                k++;
            if (k == 3) {
                fprintf(stderr, "correct_table: --fit: unknown '%s' "
                        "(area, hinge, silhouette)\n", v);
                return 2;
            }
            fit = (enum geo_convex_fit)k;
        }
        else if (strcmp(a, "--models") == 0)
            models = v;
        else if (strcmp(a, "--write") == 0)
            write_dir = v;
        else {
            fprintf(stderr, "correct_table: unknown option %s\n", a);
            return 2;
        }
    }
    char *cuts[MAX_CUTS], *seeds[64], *ks[16], *noises[16];
    int nc = split(cuts_s, cuts, MAX_CUTS), ns = split(seeds_s, seeds, 64),
        nk = split(ks_s, ks, 16), nn = split(noise_s, noises, 16);
    for (int c = 0; c < nc; c++)
        if (find_cut(cuts[c]) < 0) {
            fprintf(stderr, "correct_table: --cuts: unknown cut '%s'\n", cuts[c]);
            return 2;
        }
    if (!suite)
        rows = true;
    if (rows)
        printf("| cut | seed | K | noise µm | facets truth / scan / corrected "
               "| recovered %% | attainable silhouettes / scan | angle error median / p95 ° | Hausdorff to truth "
               "scan / corrected µm (ratio) | facet count | valid | meets | ms |\n"
               "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    totals t;
    memset(&t, 0, sizeof t);
    if (suite) {
        for (unsigned i = first; i < first + suite; i++) {
            uint64_t rng = 0x5eed0000ULL + i;
            int ci = (int)(i % (unsigned)nc);
            unsigned k = suite_ks[(unsigned)(unit(&rng) * NKS) % NKS];
            double noise = 3e-3 * unit(&rng);
            double phase = M_PI * unit(&rng), az = 2 * M_PI * unit(&rng);
            geo_poly *stone = sim_stone(cut_names[find_cut(cuts[ci])].cut, i);
            if (!stone)
                continue;
            sim_rotate_z(stone, az);
            geo_poly *scan = sim_scan_phase(stone, k, noise, phase, i);
            if (scan)
                row(cuts[ci], ci, i, k, noise * 1e3, phase, stone, scan, m, rows, &t);
            else
                no_scan(cuts[ci], i, k, noise * 1e3, &t);
            geo_poly_free(scan);
            geo_poly_free(stone);
        }
    }
    for (int c = 0; !suite && c < nc; c++)
        for (int s = 0; s < ns; s++) {
            unsigned seed = (unsigned)strtoul(seeds[s], NULL, 10);
            geo_poly *stone = sim_stone(cut_names[find_cut(cuts[c])].cut, seed);
            for (int k = 0; stone && k < nk; k++)
                for (int q = 0; q < nn; q++) {
                    unsigned kv = (unsigned)strtoul(ks[k], NULL, 10);
                    double noise = atof(noises[q]) * 1e-3;
                    geo_poly *scan = sim_scan(stone, kv, noise, seed);
                    if (scan)
                        row(cuts[c], c, seed, kv, noise * 1e3, 0, stone, scan, m, rows,
                            &t);
                    else
                        no_scan(cuts[c], seed, kv, noise * 1e3, &t);
                    geo_poly_free(scan);
                }
            geo_poly_free(stone);
        }
    if (models) {
        char path[4096];
        geo_err err;
        snprintf(path, sizeof path, "%s/brilliant.truth.json", models);
        geo_poly *truth = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
        unsigned kk[3] = {100, 400, 800};
        for (int k = 0; truth && k < 3; k++) {
            snprintf(path, sizeof path, "%s/brilliant.scan-k%u.json", models, kk[k]);
            geo_poly *scan = proto_model_read_file(path, PROTO_FMT_UNKNOWN, NULL, &err);
            if (scan)
                row("sample brilliant", 0, 0, kk[k], 1, NAN, truth, scan, m, true,
                    &t);
            geo_poly_free(scan);
        }
        geo_poly_free(truth);
    }
    printf("\nrecovered / attainable from the scan / from the silhouettes "
           "(the Cramér–Rao bounds, scan_bound.h):\n\n| cut | K=100 | K=200 | K=400 | K=800 |\n"
           "|---|---|---|---|---|\n");
    for (int c = 0; c < nc; c++) {
        printf("| %s |", cuts[c]);
        for (int k = 0; k < NKS; k++) {
            cell *x = &t.cells[c][k];
            if (x->truth && x->bound_truth)
            {
                printf(" %.1f / %s /", 100.0 * x->recovered / x->truth,
                       pct(x->kept, x->bound_truth));
                printf(" %s (%u) |", pct(x->attainable, x->bound_truth),
                       x->scans);
            }
            else if (x->truth)
                printf(" %.1f %% (%u) |", 100.0 * x->recovered / x->truth, x->scans);
            else
                printf(" — |");
        }
        printf("\n");
    }
    printf("\nworst scans:");
    for (size_t i = 0; i < sizeof t.w / sizeof t.w[0] && t.w[i].name[0]; i++)
        printf("%s %s (%.1f %%)", i ? "," : "", t.w[i].name, t.w[i].rec);
    printf("\n\nscans: %u, recovered: %.1f %% of %u true facets (attainable: "
           "%s from the scan, ", t.rows,
           t.truth ? 100.0 * t.recovered / t.truth : 0, t.truth,
           pct(t.kept, t.bound_truth));
    printf("%s from the silhouettes), meeting the acceptance (≥ 95 %% recovered, facets within 5 %%, no spurious "
           "facet, Hausdorff ≤ 0.8 × the scan's, valid): %u, mean Hausdorff "
           "ratio %.2f, invalid: %u\n", pct(t.attainable, t.bound_truth), t.meets,
           t.rows ? t.ratio_sum / t.rows : 0, t.invalid);
    if (t.unsimulated)
        printf("scans the simulator could not make: %u\n", t.unsimulated);
    return t.invalid || t.unsimulated ? 1 : 0;
}
