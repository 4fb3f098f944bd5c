/* gen_frep.c — writes the F-rep test objects (tests/support/gen_frep.h)
 * as frep-object/1 files. Usage: gen_frep [DIR] (default tests/data/frep). */
#include <stdio.h>

#include "gen_frep.h"

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "tests/data/frep";
    struct {
        const char *name;
        json_t *obj;
    } objs[] = {
        {"sphere", gf_sphere()},       {"ellipsoid", gf_ellipsoid()},
        {"blob83", gf_blob(1, 83)},    {"torus", gf_torus()},
        {"gem", gf_gem()},             {"two-spheres", gf_two_spheres()},
    };
    int status = 0;
    for (size_t i = 0; i < sizeof objs / sizeof objs[0]; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s.json", dir, objs[i].name);
        if (!objs[i].obj ||
            json_dump_file(objs[i].obj, path,
                           JSON_INDENT(1) | JSON_REAL_PRECISION(15)) != 0) {
            fprintf(stderr, "gen_frep: cannot write %s\n", path);
            status = 1;
        }
        json_decref(objs[i].obj);
    }
    return status;
}
