/* cli_args.c — the option parser of every command (cli_args.h). */
#include "cli_args.h"

#include <assert.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

void cli_args_init(cli_args *a, const char *cmd, int argc, char **argv,
                   const cli_opt *opts)
{
    *a = (cli_args){.cmd = cmd, .argc = argc, .i = 1, .argv = argv,
                    .opts = opts};
    for (const cli_opt *o = opts; o->name; o++)
        assert(o->key >= 0 && o->name[0] == '-');
}

void cli_args_positionals(cli_args *a, const char **slots, int n)
{
    a->slots = slots;
    a->nslots = n;
    for (int k = 0; k < n; k++)
        slots[k] = NULL;
}

int cli_args_next(cli_args *a, const char **val)
{
    *val = NULL;
    if (a->i >= a->argc)
        return CLI_ARGS_END;
    const char *s = a->argv[a->i++];
    if (!a->only_positional && strcmp(s, "--") == 0) {
        a->only_positional = true;
        return cli_args_next(a, val);
    }
    if (a->only_positional || s[0] != '-' || s[1] == '\0') {
        if (!a->slots) {
            *val = s;
            return CLI_ARGS_POSITIONAL;
        }
        for (int k = 0; k < a->nslots; k++)
            if (!a->slots[k]) {
                a->slots[k] = s;
                return cli_args_next(a, val);
            }
        return cli_args_unexpected(a, s);
    }
    const char *eq = strncmp(s, "--", 2) == 0 ? strchr(s, '=') : NULL;
    size_t len = eq ? (size_t)(eq - s) : strlen(s);
    for (const cli_opt *o = a->opts; o->name; o++) {
        if (strlen(o->name) != len || strncmp(o->name, s, len) != 0)
            continue;
        a->opt = o->name;
        if (!o->value) {
            if (eq) {
                cli_usage_error(a->cmd, "%s takes no value", o->name);
                return CLI_ARGS_ERROR;
            }
            return o->key;
        }
        if (eq) {
            *val = eq + 1;
        } else if (a->i < a->argc) {
            *val = a->argv[a->i++];
        } else {
            cli_usage_error(a->cmd, "%s needs a value", o->name);
            return CLI_ARGS_ERROR;
        }
        return o->key;
    }
    cli_usage_error(a->cmd, "unknown option '%.*s'", (int)len, s);
    return CLI_ARGS_ERROR;
}

int cli_args_long(cli_args *a, const char *s, long lo, long hi, long *ret)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end || v < lo || v > hi) {
        cli_usage_error(a->cmd, "%s: expected a whole number %ld..%ld, got "
                        "'%s'", a->opt, lo, hi, s);
        return CLI_ARGS_ERROR;
    }
    *ret = v;
    return 0;
}

int cli_args_double(cli_args *a, const char *s, double lo, double hi,
                    bool lo_open, double *ret)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end || !isfinite(v) || v < lo || v > hi ||
        (lo_open && v == lo)) {
        cli_usage_error(a->cmd, "%s: expected a number in %s%g, %g], got "
                        "'%s'", a->opt, lo_open ? "(" : "[", lo, hi, s);
        return CLI_ARGS_ERROR;
    }
    *ret = v;
    return 0;
}

int cli_args_invalid(cli_args *a, const char *s, const char *expected)
{
    cli_usage_error(a->cmd, "%s: expected %s, got '%s'", a->opt, expected, s);
    return CLI_ARGS_ERROR;
}

int cli_args_positive(cli_args *a, const char *s, double hi,
                      const char *expected, double *ret)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end || errno || !isfinite(v) || v <= 0 || v > hi)
        return cli_args_invalid(a, s, expected);
    *ret = v;
    return 0;
}

int cli_args_format(cli_args *a, const char *s, proto_format *ret)
{
    proto_format f = proto_format_from_name(s);
    if (f == PROTO_FMT_UNKNOWN) {
        cli_usage_error(a->cmd, "%s: unknown format '%s'", a->opt, s);
        return CLI_ARGS_ERROR;
    }
    *ret = f;
    return 0;
}

int cli_args_direction(cli_args *a, const char *s, double ret[3])
{
    const char *p = s;
    char *end;
    double v[3];
    for (int k = 0; k < 3; k++) {
        errno = 0;
        v[k] = strtod(p, &end);
        if (errno || end == p || !isfinite(v[k]) ||
            *end != (k < 2 ? ',' : '\0'))
            goto bad;
        p = end + 1;
    }
    if (v[0] == 0 && v[1] == 0 && v[2] == 0)
        goto bad;
    ret[0] = v[0], ret[1] = v[1], ret[2] = v[2];
    return 0;
bad:
    cli_usage_error(a->cmd, "%s: expected a direction X,Y,Z (not all zero), "
                    "got '%s'", a->opt, s);
    return CLI_ARGS_ERROR;
}

int cli_args_output(cli_args *a, const char *out)
{
    if (!out)
        return cli_usage_error(a->cmd, "needs -o OUT");
    if (proto_format_from_path(out) == PROTO_FMT_UNKNOWN)
        return cli_usage_error(a->cmd, "%s: cannot tell the format from the "
                               "name", out);
    return CLI_OK;
}

int cli_args_unexpected(cli_args *a, const char *arg)
{
    cli_usage_error(a->cmd, "unexpected argument '%s'", arg);
    return CLI_ARGS_ERROR;
}
