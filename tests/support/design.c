/* design.c — GemCad designs as test truths (design.h).
 *
 * The brilliant is built so that its proportions are exact by
 * construction: the bezels pass through the girdle's top at their own
 * azimuth and through the table's corners; the table's corners lie at the
 * radius that gives the asked table perimeter; each star contains the two
 * table corners beside it, so the table is an octagon of exactly that
 * perimeter; the upper and lower girdle facets pass through the points
 * where the mains meet the girdle between them, so the girdle is thinnest
 * (the asked thickness) at the mains; the culet is cut at the depth where
 * the mains leave it the asked width. */
#include "design.h"

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "model_io.h"

#define DEG (M_PI / 180.0)

const char *design_dir(void)
{
    const char *env = getenv("FACET_DESIGNS");
    if (env && *env)
        return env;
    return "tests/data/designs";
}

const char *design_path(const char *name)
{
    static char buf[4096];
    snprintf(buf, sizeof buf, "%s/%s", design_dir(), name);
    return buf;
}

geo_poly *design_load(const char *path, double width_mm, geo_err *err)
{
    geo_poly *p = proto_model_read_file(path, PROTO_FMT_ASC, NULL, err);
    if (p && width_mm > 0 && proto_model_scale_to_width(p, width_mm, err) < 0)
        p = geo_poly_free(p);
    return p;
}

uint32_t design_file_planes(const char *path, double *planes, double *angle,
                            uint32_t max)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    char line[8192];
    const char *sep = " \t\r\n";
    double gear = 96, off = 0, a_deg = 0, dist = 0;
    uint32_t n = 0;
    bool open = false;
    while (fgets(line, sizeof line, f)) {
        bool cont = line[0] == ' ' || line[0] == '\t';
        char *save = NULL, *t = strtok_r(line, sep, &save);
        if (!t)
            continue;
        if (!cont && strcmp(t, "g") == 0) {
            char *g = strtok_r(NULL, sep, &save), *o = strtok_r(NULL, sep, &save);
            gear = g ? atof(g) : 96, off = o ? atof(o) : 0;
            open = false;
            continue;
        }
        if (!cont && strcmp(t, "a") == 0) {
            char *x = strtok_r(NULL, sep, &save), *y = strtok_r(NULL, sep, &save);
            a_deg = x ? atof(x) : 0, dist = y ? atof(y) : 0;
            if (x && x[0] == '-' && a_deg == 0)
                a_deg = -0.0;
            open = true;
            t = strtok_r(NULL, sep, &save);
        } else if (!cont || !open) {
            open = open && cont; /* another record ends the tier */
            continue;
        }
        bool culet = a_deg == 0 && dist < 0;
        bool pav = signbit(a_deg) || culet;
        for (; t && strcmp(t, "G") != 0; t = strtok_r(NULL, sep, &save)) {
            if (strcmp(t, "n") == 0) {
                strtok_r(NULL, sep, &save);
                continue;
            }
            if (n == max)
                break;
            /* θ counter-clockwise from −y in the top view; the gear's sign
             * turns the counting clockwise */
            double th = (atof(t) - off) * 2 * M_PI / gear;
            double a = fabs(a_deg) * DEG;
            planes[4 * n] = sin(a) * sin(th);
            planes[4 * n + 1] = -sin(a) * cos(th);
            planes[4 * n + 2] = pav ? -cos(a) : cos(a);
            planes[4 * n + 3] = -fabs(dist);
            angle[n++] = culet ? -0.0 : a_deg;
        }
    }
    fclose(f);
    return n;
}

void design_brilliant_random(uint64_t seed, design_brilliant *ret)
{
    uint64_t s = seed * 0x9e3779b97f4a7c15ull + 7;
    static const uint32_t girdles[4] = {64, 80, 96, 112};
    ret->crown_deg = 31.0 + 6.0 * geo_rand_unit(&s);
    ret->pavilion_deg = 39.8 + 2.2 * geo_rand_unit(&s);
    ret->table_percent = 52.0 + 10.0 * geo_rand_unit(&s);
    ret->girdle_percent = 2.0 + 2.5 * geo_rand_unit(&s);
    ret->star_below_deg = 10.0 + 6.0 * geo_rand_unit(&s);
    ret->upper_girdle_above_deg = 5.0 + 4.0 * geo_rand_unit(&s);
    ret->lower_girdle_above_deg = 0.8 + 1.2 * geo_rand_unit(&s);
    ret->culet_percent = geo_rand_unit(&s) < 0.5
                             ? 0.0
                             : 0.5 + 1.5 * geo_rand_unit(&s);
    ret->girdle_facets = girdles[geo_rand_next(&s) % 4];
}

typedef struct text {
    char *s;
    size_t len, cap;
    int failed;
} text;

static void put(text *t, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static void put(text *t, const char *fmt, ...)
{
    if (t->failed)
        return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(t->s + t->len, t->cap - t->len, fmt, ap);
        va_end(ap);
        if (n >= 0 && (size_t)n < t->cap - t->len) {
            t->len += (size_t)n;
            return;
        }
        size_t cap = t->cap ? 2 * t->cap : 4096;
        char *s = realloc(t->s, cap);
        if (!s || n < 0) {
            t->failed = 1;
            return;
        }
        t->s = s, t->cap = cap;
    }
}

/* One tier line; idx[] on the 96 gear. */
static void tier(text *t, double angle, double dist, const double *idx,
                 uint32_t n, const char *name)
{
    put(t, "a %.17g %.17g", angle, dist);
    for (uint32_t i = 0; i < n; i++) {
        put(t, " %.17g", idx[i]);
        if (i == 0)
            put(t, " n %s", name);
    }
    put(t, "\n");
}

char *design_brilliant_asc(const design_brilliant *b)
{
    const double R = 1.0;
    const uint32_t N = b->girdle_facets;
    const double c = b->crown_deg * DEG, p = b->pavilion_deg * DEG;
    const double outline = N * 2.0 * R * tan(M_PI / N); /* perimeter */
    const double D = outline / M_PI;                    /* mean diameter */
    const double g = b->girdle_percent / 100.0 * D;
    const double gt = g / 2, gb = g / 2;
    const double rt =
        b->table_percent / 100.0 * outline / (16.0 * sin(22.5 * DEG));
    const double zt = gt + (R - rt) * tan(c);
    const double c22 = cos(22.5 * DEG);
    const double s = c - b->star_below_deg * DEG;
    const double u = c + b->upper_girdle_above_deg * DEG;
    const double l = p + b->lower_girdle_above_deg * DEG;
    /* The halves flank each main 3.75° (one index) to either side and
     * pass through the main's tip on the girdle, so that tip stays a
     * point of the girdle line (as on a well cut stone). */
    const double dh = 3.75;
    text t = {0};
    put(&t, "GemCad 5.0\ng -96 48\ny 8 y\nI 2.42\n");
    put(&t, "H Round brilliant: crown %.6g, pavilion %.6g, table %.6g%%, "
            "girdle %.6g%%, culet %.6g%%, %u girdle facets\n",
        b->crown_deg, b->pavilion_deg, b->table_percent, b->girdle_percent,
        b->culet_percent, N);
    double idx[128], idx2[16];
    for (int k = 0; k < 8; k++)
        idx[k] = 12.0 * k;
    tier(&t, -b->pavilion_deg, sin(p) * R + cos(p) * gb, idx, 8, "P");
    for (int k = 0; k < 8; k++) {
        idx2[2 * k] = 12.0 * k - dh / 3.75 + (k == 0 ? 96 : 0);
        idx2[2 * k + 1] = 12.0 * k + dh / 3.75;
    }
    tier(&t, -l / DEG, sin(l) * R * cos(dh * DEG) + cos(l) * gb, idx2, 16,
         "L");
    if (b->culet_percent > 0) {
        double a = b->culet_percent / 100.0 * D * M_PI /
                   (16.0 * tan(22.5 * DEG));
        double apex = gb + R * tan(p);
        put(&t, "a -0 %.17g 96 n K\n", apex - a * tan(p));
    }
    for (uint32_t k = 0; k < N; k++)
        idx[k] = 96.0 * k / N;
    tier(&t, 90.0, R, idx, N, "R");
    for (int k = 0; k < 8; k++)
        idx2[k] = 12.0 * k;
    tier(&t, b->crown_deg, sin(c) * R + cos(c) * gt, idx2, 8, "B");
    for (int k = 0; k < 8; k++)
        idx2[k] = 6.0 + 12.0 * k;
    tier(&t, s / DEG, sin(s) * rt * c22 + cos(s) * zt, idx2, 8, "S");
    for (int k = 0; k < 8; k++) {
        idx2[2 * k] = 12.0 * k - dh / 3.75 + (k == 0 ? 96 : 0);
        idx2[2 * k + 1] = 12.0 * k + dh / 3.75;
    }
    tier(&t, u / DEG, sin(u) * R * cos(dh * DEG) + cos(u) * gt, idx2, 16,
         "U");
    double zero_idx = 96;
    tier(&t, 0.0, zt, &zero_idx, 1, "T");
    if (t.failed) {
        free(t.s);
        return NULL;
    }
    return t.s;
}
