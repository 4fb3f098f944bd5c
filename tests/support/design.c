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

#include "halfspace.h"
#include "model_io.h"
#include "report.h"

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

/* ---- designs of every shape (design.h) ---- */

const char *design_shape_name(enum design_shape s)
{
    static const char *const names[DESIGN_NSHAPES] = {
        "oval", "pear", "marquise", "heart", "trilliant", "princess",
        "cushion", "emerald", "radiant", "asymmetric"};
    return (unsigned)s < DESIGN_NSHAPES ? names[s] : "unknown";
}

static bool polygonal(enum design_shape s)
{
    return s == DESIGN_TRILLIANT || s == DESIGN_PRINCESS ||
           s == DESIGN_EMERALD || s == DESIGN_RADIANT;
}

void design_fancy_default(enum design_shape s, design_fancy *r)
{
    memset(r, 0, sizeof *r);
    r->shape = s;
    r->crown_deg = 34;
    r->pavilion_deg = 41;
    r->table_inset = 0.42;
    r->girdle_percent = 3;
    r->star_below_deg = 12;
    r->upper_girdle_above_deg = 6;
    r->lower_girdle_above_deg = 1.5;
    r->girdle_facets = 96;
    r->length_to_width = 1;
    switch (s) {
    case DESIGN_OVAL: r->a[2] = 0.2; break; /* length to width 1.5 */
    case DESIGN_PEAR:
        r->a[2] = 0.12, r->a[3] = 0.05, r->culet_percent = 1.5;
        r->girdle_facets = 80;
        break;
    case DESIGN_MARQUISE: r->a[2] = 0.27, r->a[4] = 0.004; break;
    case DESIGN_HEART:
        r->a[2] = -0.05, r->a[3] = -0.08, r->culet_percent = 1;
        r->girdle_facets = 120;
        break;
    case DESIGN_TRILLIANT: r->corner = 0.65; break;
    case DESIGN_PRINCESS:
        r->corner = 0.12, r->culet_percent = 1.5, r->crown_deg = 36;
        break;
    case DESIGN_CUSHION:
        r->a[4] = -0.05, r->culet_percent = 2, r->girdle_facets = 64;
        break;
    case DESIGN_EMERALD:
        r->length_to_width = 1.4, r->corner = 0.3, r->steps = 3;
        r->crown_deg = 28, r->pavilion_deg = 42, r->girdle_percent = 3.5;
        break;
    case DESIGN_RADIANT:
        r->length_to_width = 1.25, r->corner = 0.25, r->culet_percent = 1;
        break;
    case DESIGN_ASYMMETRIC:
        r->a[2] = 0.1, r->b[2] = 0.04, r->b[3] = 0.04, r->a[4] = 0.01;
        r->girdle_facets = 112;
        break;
    default: break;
    }
}

static double support(const design_fancy *d, double psi, double *d1,
                      double *d2)
{
    double h = 1, h1 = 0, h2 = 0;
    for (int k = 1; k < 8; k++) {
        double c = cos(k * psi), s = sin(k * psi);
        h += d->a[k] * c + d->b[k] * s;
        h1 += k * (d->b[k] * c - d->a[k] * s);
        h2 -= k * k * (d->a[k] * c + d->b[k] * s);
    }
    if (d1)
        *d1 = h1;
    if (d2)
        *d2 = h2;
    return h;
}

/* The outline's smallest radius of curvature h + h''. */
static double min_curvature_radius(const design_fancy *d)
{
    double m = INFINITY;
    for (int i = 0; i < 3600; i++) {
        double h2, h = support(d, i * M_PI / 1800, NULL, &h2);
        m = fmin(m, h + h2);
    }
    return m;
}

void design_fancy_random(enum design_shape s, uint64_t seed,
                         design_fancy *r)
{
    design_fancy_default(s, r);
    uint64_t st = seed * 0x9e3779b97f4a7c15ull + 11 + (uint64_t)s;
    double f = 0.7 + 0.6 * geo_rand_unit(&st);
    for (int k = 1; k < 8; k++)
        r->a[k] *= f, r->b[k] *= f;
    while (!polygonal(s) && min_curvature_radius(r) < 0.3)
        for (int k = 1; k < 8; k++) /* back towards a round */
            r->a[k] *= 0.9, r->b[k] *= 0.9;
    r->length_to_width = 1 + (r->length_to_width - 1) * f;
    r->corner *= 0.9 + 0.2 * geo_rand_unit(&st);
    r->crown_deg += -3 + 6 * geo_rand_unit(&st);
    r->pavilion_deg += -1.5 + 2.5 * geo_rand_unit(&st);
    r->table_inset *= 0.9 + 0.2 * geo_rand_unit(&st);
    r->girdle_percent = 2 + 2.5 * geo_rand_unit(&st);
    r->star_below_deg = 10 + 5 * geo_rand_unit(&st);
    r->upper_girdle_above_deg = 5 + 3 * geo_rand_unit(&st);
    r->lower_girdle_above_deg = 0.8 + 1.2 * geo_rand_unit(&st);
    if (s != DESIGN_EMERALD)
        r->culet_percent = geo_rand_unit(&st) < 0.5
                               ? 0 : 0.5 + 1.5 * geo_rand_unit(&st);
    if (!polygonal(s))
        r->girdle_facets = 64 + 8 * (uint32_t)(geo_rand_next(&st) % 8);
}

void design_free(design_cut *d)
{
    if (d) {
        free(d->f);
        d->f = NULL;
        d->n = 0;
    }
}

static double norm_az(double az)
{
    az = fmod(az, 360.0);
    return az < 0 ? az + 360.0 : az;
}

static int add_facet(design_cut *d, uint32_t *cap, double angle, double dist,
                     double az, int tier)
{
    if (d->n == *cap) {
        uint32_t c = *cap ? 2 * *cap : 128;
        design_facet *f = realloc(d->f, c * sizeof *f);
        if (!f)
            return -1;
        d->f = f, *cap = c;
    }
    d->f[d->n++] = (design_facet){angle, dist, norm_az(az), tier, false};
    return 0;
}

double *design_planes(const design_cut *d)
{
    double *pl = malloc(4 * (size_t)(d->n ? d->n : 1) * sizeof *pl);
    if (!pl)
        return NULL;
    for (uint32_t i = 0; i < d->n; i++) {
        const design_facet *f = &d->f[i];
        double a = fabs(f->angle_deg) * DEG, ph = f->azimuth_deg * DEG;
        double sa = fabs(f->angle_deg) == 90 ? 1 : sin(a);
        double ca = fabs(f->angle_deg) == 90 ? 0 : cos(a);
        pl[4 * i] = sa * sin(ph), pl[4 * i + 1] = sa * cos(ph);
        pl[4 * i + 2] = signbit(f->angle_deg) ? -ca : ca;
        pl[4 * i + 3] = -f->dist;
    }
    return pl;
}

/* A facet of inclination A (degrees; negative: pavilion) whose horizontal
 * normal points to azimuth az, through the point (x, y, z). */
static int add_through(design_cut *d, uint32_t *cap, double A, double az,
                       const double x[2], double z, int tier)
{
    double a = fabs(A) * DEG, ph = az * DEG;
    double hx = sin(ph), hy = cos(ph), nz = A < 0 ? -cos(a) : cos(a);
    double dist = sin(a) * (hx * x[0] + hy * x[1]) + nz * z;
    return add_facet(d, cap, A, dist, az, tier);
}

/* The outline's sides: azimuth (degrees) and distance of each, in order. */
static uint32_t polygon_sides(const design_fancy *d, double *az, double *h)
{
    double l = d->length_to_width, k = d->corner;
    uint32_t n = 0;
    if (d->shape == DESIGN_TRILLIANT) {
        for (int i = 0; i < 6; i++)
            az[n] = 60.0 * i, h[n++] = i % 2 ? 2 - k : 1;
        return n;
    }
    if (d->shape == DESIGN_PRINCESS)
        l = 1;
    double side[4] = {l, 1, l, 1};
    for (int i = 0; i < 4; i++) {
        az[n] = 90.0 * i, h[n++] = side[i];
        az[n] = 90.0 * i + 45, h[n++] = (l + 1) / sqrt(2.0) - k;
    }
    return n;
}

static int build_planes(const design_fancy *d, design_cut *ds)
{
    uint32_t cap = 0;
    int e = 0;
    const bool poly = polygonal(d->shape), step = d->steps > 0;
    double maz[16], mh[16], mp[16][2];
    uint32_t m = 0, ng = d->girdle_facets;
    double gaz[128], gh[128];
    if (poly) {
        ng = polygon_sides(d, gaz, gh);
        for (uint32_t i = 0; i < ng; i++) {
            maz[m] = gaz[i], mh[m] = gh[i];
            mp[m][0] = gh[i] * sin(gaz[i] * DEG);
            mp[m][1] = gh[i] * cos(gaz[i] * DEG);
            m++;
        }
    } else {
        for (uint32_t k = 0; k < ng; k++) {
            gaz[k] = 360.0 * k / ng;
            gh[k] = support(d, gaz[k] * DEG, NULL, NULL);
        }
        for (m = 0; m < 8; m++) {
            double psi = 45.0 * m * DEG, h1, h = support(d, psi, &h1, NULL);
            maz[m] = 45.0 * m, mh[m] = h;
            /* the curve's point of normal ψ: h·u + h'·u' */
            mp[m][0] = h * sin(psi) + h1 * cos(psi);
            mp[m][1] = h * cos(psi) - h1 * sin(psi);
        }
    }
    double hbar = 0, hmin = INFINITY;
    for (uint32_t i = 0; i < m; i++)
        hbar += mh[i] / m, hmin = fmin(hmin, mh[i]);
    const double g = d->girdle_percent / 100 * 2 * hbar, gt = g / 2,
                 gb = g / 2;
    const double c = d->crown_deg;
    const double delta = poly ? 0 : 360.0 / ng;
    double zt;
    if (step) { /* crown and pavilion steps on every side */
        uint32_t S = d->steps;
        double ztop = gt + d->table_inset * hmin * tan(c * DEG);
        double o = 0, z = gt, dz = (ztop - gt) / S;
        for (uint32_t k = 0; k < S && !e; k++) {
            double a = c + 10.0 * (S - 1 - k);
            for (uint32_t i = 0; i < m && !e; i++) {
                double x[2] = {(mh[i] - o) * sin(maz[i] * DEG),
                               (mh[i] - o) * cos(maz[i] * DEG)};
                e = add_through(ds, &cap, a, maz[i], x, z, GEO_TIER_CROWN);
            }
            o += dz / tan(a * DEG), z += dz;
        }
        zt = ztop;
        double sum = 0;
        for (uint32_t k = 0; k + 1 < S; k++)
            sum += 1 / tan((d->pavilion_deg + 10.0 * (S - 1 - k)) * DEG);
        double dp = S > 1 ? 0.45 * hmin / sum : 0;
        o = 0, z = -gb;
        for (uint32_t k = 0; k < S && !e; k++) {
            double a = d->pavilion_deg + 10.0 * (S - 1 - k);
            for (uint32_t i = 0; i < m && !e; i++) {
                double x[2] = {(mh[i] - o) * sin(maz[i] * DEG),
                               (mh[i] - o) * cos(maz[i] * DEG)};
                e = add_through(ds, &cap, -a, maz[i], x, z,
                                GEO_TIER_PAVILION);
            }
            o += dp / tan(a * DEG), z -= dp;
        }
    } else {
        const double w = d->table_inset * hmin;
        zt = gt + w * tan(c * DEG);
        const double dpav = hmin * tan(d->pavilion_deg * DEG);
        double pmean = 0;
        for (uint32_t i = 0; i < m && !e; i++) { /* mains to the point */
            double p = atan(dpav / mh[i]) / DEG;
            pmean += p / m;
            e = add_through(ds, &cap, -p, maz[i], mp[i], -gb,
                            GEO_TIER_PAVILION);
        }
        for (uint32_t i = 0; i < m && !poly && !e; i++) {
            double l = atan(dpav / mh[i]) / DEG + d->lower_girdle_above_deg;
            e = add_through(ds, &cap, -l, maz[i] - delta, mp[i], -gb,
                            GEO_TIER_PAVILION);
            if (!e)
                e = add_through(ds, &cap, -l, maz[i] + delta, mp[i], -gb,
                                GEO_TIER_PAVILION);
        }
        if (d->culet_percent > 0 && !e) {
            double eps = d->culet_percent / 100 * 2 * hbar / 2 *
                         tan(pmean * DEG);
            e = add_facet(ds, &cap, -0.0, gb + dpav - eps, 0,
                          GEO_TIER_CULET);
        }
        for (uint32_t i = 0; i < ng && !e; i++)
            e = add_facet(ds, &cap, 90, gh[i], gaz[i], GEO_TIER_GIRDLE);
        const uint32_t m0 = ds->n; /* the crown mains' first facet */
        for (uint32_t i = 0; i < m && !e; i++)
            e = add_through(ds, &cap, c, maz[i], mp[i], gt, GEO_TIER_CROWN);
        for (uint32_t i = 0; i < m && !poly && !e; i++) {
            /* a star through the table corners beside it and the point
             * halfway up the crown where the two mains meet: stars stay
             * short of the girdle however the outline turns */
            uint32_t j = (i + 1) % m;
            double ti[3], tj[3], x[3], ni[3], nj[3];
            for (int k = 0; k < 3; k++)
                ni[k] = ds->f[m0 + i].dist, nj[k] = ds->f[m0 + j].dist;
            double pa = c * DEG;
            double ui[2] = {sin(maz[i] * DEG), cos(maz[i] * DEG)};
            double uj[2] = {sin(maz[j] * DEG), cos(maz[j] * DEG)};
            for (int k = 0; k < 2; k++)
                ti[k] = mp[i][k] - w * ui[k], tj[k] = mp[j][k] - w * uj[k];
            ti[2] = tj[2] = zt;
            /* the mains' meet at height zm: sin c (u·x) = dist − cos c zm */
            double zm = gt + 0.5 * (zt - gt);
            double ri = (ni[0] - cos(pa) * zm) / sin(pa);
            double rj = (nj[0] - cos(pa) * zm) / sin(pa);
            double det = ui[0] * uj[1] - ui[1] * uj[0];
            x[0] = (ri * uj[1] - rj * ui[1]) / det;
            x[1] = (ui[0] * rj - uj[0] * ri) / det;
            x[2] = zm;
            double a[3], b[3], n[3];
            for (int k = 0; k < 3; k++)
                a[k] = tj[k] - ti[k], b[k] = x[k] - ti[k];
            n[0] = a[1] * b[2] - a[2] * b[1];
            n[1] = a[2] * b[0] - a[0] * b[2];
            n[2] = a[0] * b[1] - a[1] * b[0];
            if (n[2] < 0)
                n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
            double az = atan2(n[0], n[1]) / DEG;
            double incl = atan2(hypot(n[0], n[1]), n[2]) / DEG;
            e = add_through(ds, &cap, incl, az, ti, zt, GEO_TIER_CROWN);
        }
        for (uint32_t i = 0; i < m && !poly && !e; i++) {
            double u = c + d->upper_girdle_above_deg;
            e = add_through(ds, &cap, u, maz[i] - delta, mp[i], gt,
                            GEO_TIER_CROWN);
            if (!e)
                e = add_through(ds, &cap, u, maz[i] + delta, mp[i], gt,
                                GEO_TIER_CROWN);
        }
    }
    if (step)
        for (uint32_t i = 0; i < ng && !e; i++)
            e = add_facet(ds, &cap, 90, gh[i], gaz[i], GEO_TIER_GIRDLE);
    if (!e)
        e = add_facet(ds, &cap, 0, zt, 0, GEO_TIER_TABLE);
    return e;
}

int design_fancy_build(const design_fancy *d, design_cut *ret)
{
    static const uint32_t fold[DESIGN_NSHAPES] = {2, 1, 2, 1, 3, 4, 4, 2, 2,
                                                  1};
    memset(ret, 0, sizeof *ret);
    ret->fold = fold[d->shape];
    ret->mirror = d->shape != DESIGN_ASYMMETRIC;
    snprintf(ret->title, sizeof ret->title,
             "%s: crown %.6g, pavilion %.6g, table inset %.4g, girdle %.4g%%, "
             "culet %.4g%%, %u girdle facets%s", design_shape_name(d->shape),
             d->crown_deg, d->pavilion_deg, d->table_inset, d->girdle_percent,
             d->culet_percent,
             polygonal(d->shape) ? (d->shape == DESIGN_TRILLIANT ? 6 : 8)
                                 : d->girdle_facets,
             d->steps ? ", step cut" : "");
    if (build_planes(d, ret) < 0)
        goto fail;
    /* leave out what does not appear, until everything listed does */
    geo_poly *p = NULL;
    for (;;) {
        double *pl = design_planes(ret);
        uint32_t *src = NULL;
        geo_err err = {{0}};
        if (!pl || geo_halfspace_intersect(pl, ret->n, -1, &p, &src, NULL,
                                           &err) < 0) {
            free(pl);
            goto fail;
        }
        free(pl);
        double total = 0;
        for (uint32_t f = 0; f < p->nfacets; f++)
            total += geo_poly_facet_area(p, f);
        bool *keep = calloc(ret->n, sizeof *keep);
        if (!keep) {
            free(src);
            goto fail;
        }
        for (uint32_t f = 0; f < p->nfacets; f++)
            if (geo_poly_facet_area(p, f) > 1e-6 * total)
                keep[src[f]] = true;
        free(src);
        uint32_t n = 0;
        for (uint32_t i = 0; i < ret->n; i++)
            if (keep[i])
                ret->f[n++] = ret->f[i];
        free(keep);
        if (n == ret->n)
            break;
        ret->dropped += ret->n - n;
        ret->n = n;
        p = geo_poly_free(p);
    }
    /* the mains, by exact incidence on the built stone (facets in the
     * design's order now that all appear) */
    bool *on_table = calloc(p->nverts, sizeof(bool));
    bool *on_girdle = calloc(p->nverts, sizeof(bool));
    bool *on_culet = calloc(p->nverts, sizeof(bool));
    if (!on_table || !on_girdle || !on_culet) {
        free(on_table), free(on_girdle), free(on_culet);
        geo_poly_free(p);
        goto fail;
    }
    bool has_culet = false;
    for (uint32_t f = 0; f < p->nfacets; f++) {
        int t = ret->f[f].tier;
        has_culet |= t == GEO_TIER_CULET;
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *ix = geo_poly_facet(p, f);
        for (uint32_t k = 0; k < n; k++) {
            on_table[ix[k]] |= t == GEO_TIER_TABLE;
            on_girdle[ix[k]] |= t == GEO_TIER_GIRDLE;
            on_culet[ix[k]] |= t == GEO_TIER_CULET;
        }
    }
    if (!has_culet) { /* the lowest vertex */
        uint32_t low = 0;
        for (uint32_t v = 1; v < p->nverts; v++)
            if (p->verts[v][2] < p->verts[low][2])
                low = v;
        on_culet[low] = true;
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        int t = ret->f[f].tier;
        if (t != GEO_TIER_CROWN && t != GEO_TIER_PAVILION)
            continue;
        const bool *end = t == GEO_TIER_CROWN ? on_table : on_culet;
        bool a = false, b = false;
        uint32_t n = geo_poly_facet_size(p, f);
        const uint32_t *ix = geo_poly_facet(p, f);
        for (uint32_t k = 0; k < n; k++)
            a |= end[ix[k]], b |= on_girdle[ix[k]];
        ret->f[f].main = a && b;
    }
    free(on_table), free(on_girdle), free(on_culet);
    geo_poly_free(p);
    return 0;
fail:
    design_free(ret);
    return -1;
}

char *design_asc(const design_cut *d)
{
    text t = {0};
    put(&t, "GemCad 5.0\ng -96 48\ny %u %s\nI 1.76\nH %s\n", d->fold,
        d->mirror ? "y" : "n", d->title);
    static const char tag[5] = {'T', 'C', 'R', 'P', 'K'};
    for (uint32_t i = 0; i < d->n; i++) {
        const design_facet *f = &d->f[i];
        bool same = i > 0 && d->f[i - 1].angle_deg == f->angle_deg &&
                    signbit(d->f[i - 1].angle_deg) == signbit(f->angle_deg) &&
                    d->f[i - 1].dist == f->dist;
        double idx = f->azimuth_deg / 3.75;
        if (idx <= 0)
            idx += 96; /* GemCad writes the top index as 96 */
        if (!same) {
            if (i > 0)
                put(&t, "\n");
            if (f->angle_deg == 0 && signbit(f->angle_deg))
                put(&t, "a -0 %.17g %.17g n %c%u", f->dist, idx,
                    tag[f->tier], i + 1);
            else
                put(&t, "a %.17g %.17g %.17g n %c%u", f->angle_deg, f->dist,
                    idx, tag[f->tier], i + 1);
        } else {
            put(&t, " %.17g", idx);
        }
    }
    put(&t, "\n");
    if (t.failed) {
        free(t.s);
        return NULL;
    }
    return t.s;
}
