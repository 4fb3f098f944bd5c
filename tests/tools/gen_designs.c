/* gen_designs.c — writes GemCad .asc designs (tests/support/design.h).
 *
 *   gen_designs --brilliant SEED        a round brilliant with random
 *                                       proportions, to stdout
 *   gen_designs --shape NAME [SEED]     a design of that shape (oval, pear,
 *                                       ...; design.h), its reference
 *                                       proportions or those of SEED, to
 *                                       stdout
 *   gen_designs --collection DIR        the collection of
 *                                       tests/data/designs/ into DIR
 *
 * Exit 0, 1 when a file cannot be written, 2 on bad usage. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "design.h"

static int usage(const char *msg)
{
    fprintf(stderr, "gen_designs: %s\nusage: gen_designs --brilliant SEED | "
            "--shape NAME [SEED] | --collection DIR\n", msg);
    return 2;
}

/* The design of shape s (seed 0: its reference proportions) as .asc
 * text, NULL when it does not build. */
static char *fancy_text(enum design_shape s, uint64_t seed)
{
    design_fancy fd;
    if (seed)
        design_fancy_random(s, seed, &fd);
    else
        design_fancy_default(s, &fd);
    design_cut d;
    if (design_fancy_build(&fd, &d) < 0)
        return NULL;
    if (d.dropped)
        fprintf(stderr, "gen_designs: %s seed %llu: %u listed facets did "
                "not appear and were left out\n", design_shape_name(s),
                (unsigned long long)seed, d.dropped);
    char *text = design_asc(&d);
    design_free(&d);
    return text;
}

static int write_text(const char *dir, const char *name, char *text)
{
    if (!text) {
        fprintf(stderr, "gen_designs: %s: out of memory\n", name);
        return 1;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    int rc = 0;
    if (!f || fputs(text, f) < 0 || fclose(f) != 0) {
        fprintf(stderr, "gen_designs: %s: %s\n", path, strerror(errno));
        rc = 1;
    }
    free(text);
    return rc;
}

/* The collection: each design named for its shape and what it exercises. */
static int collection(const char *dir)
{
    int rc = 0;
    /* the ideal-cut proportions (Tolkowsky) on a 96-facet girdle */
    design_brilliant b = {
        .crown_deg = 34.5, .pavilion_deg = 40.75, .table_percent = 53,
        .girdle_percent = 3, .star_below_deg = 12,
        .upper_girdle_above_deg = 7, .lower_girdle_above_deg = 1.25,
        .culet_percent = 0, .girdle_facets = 96};
    rc |= write_text(dir, "round-brilliant.asc", design_brilliant_asc(&b));
    b.culet_percent = 1.5;
    b.girdle_facets = 64;
    b.table_percent = 58;
    b.crown_deg = 33;
    rc |= write_text(dir, "round-brilliant-culet-64.asc",
                     design_brilliant_asc(&b));
    for (uint64_t seed = 1; seed <= 3; seed++) {
        char name[64];
        design_brilliant_random(seed, &b);
        snprintf(name, sizeof name, "round-brilliant-random-%llu.asc",
                 (unsigned long long)seed);
        rc |= write_text(dir, name, design_brilliant_asc(&b));
    }
    for (int sh = 0; sh < DESIGN_NSHAPES; sh++) {
        char name[64];
        snprintf(name, sizeof name, "%s.asc", design_shape_name(sh));
        rc |= write_text(dir, name, fancy_text((enum design_shape)sh, 0));
        snprintf(name, sizeof name, "%s-random-1.asc", design_shape_name(sh));
        rc |= write_text(dir, name, fancy_text((enum design_shape)sh, 1));
    }
    return rc;
}

static int shape(int argc, char **argv)
{
    int sh = 0;
    while (sh < DESIGN_NSHAPES && strcmp(design_shape_name(sh), argv[2]))
        sh++;
    if (sh == DESIGN_NSHAPES)
        return usage("--shape: unknown shape");
    unsigned long long seed = 0;
    if (argc == 4) {
        char *end;
        errno = 0;
        seed = strtoull(argv[3], &end, 10);
        if (errno || end == argv[3] || *end)
            return usage("--shape: expected a seed after the name");
    }
    char *text = fancy_text((enum design_shape)sh, seed);
    if (!text) {
        fprintf(stderr, "gen_designs: %s: the design does not build\n",
                argv[2]);
        return 1;
    }
    fputs(text, stdout);
    free(text);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 3 && argc <= 4 && strcmp(argv[1], "--shape") == 0)
        return shape(argc, argv);
    if (argc != 3)
        return usage("expected one option and its value");
    if (strcmp(argv[1], "--collection") == 0)
        return collection(argv[2]);
    if (strcmp(argv[1], "--brilliant") == 0) {
        char *end;
        errno = 0;
        unsigned long long seed = strtoull(argv[2], &end, 10);
        if (errno || end == argv[2] || *end)
            return usage("--brilliant: expected a seed");
        design_brilliant b;
        design_brilliant_random(seed, &b);
        char *text = design_brilliant_asc(&b);
        if (!text)
            return 1;
        fputs(text, stdout);
        free(text);
        return 0;
    }
    return usage("unknown option");
}
