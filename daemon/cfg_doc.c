/* cfg_doc.c — facetd.conf(5) and the example configuration, written from
 * the key table (cfg_key_describe), never by hand. */
#include "cfg_doc.h"

#include <stdbool.h>
#include <string.h>

#include "cfg.h"
#include "version.h"

enum { EXAMPLE_WIDTH = 72 };

/* Writes text as "# " comment lines of at most EXAMPLE_WIDTH columns,
 * breaking at spaces (a word longer than a line gets a line of its own). */
static void comment_wrapped(FILE *out, const char *text)
{
    const char *p = text;
    while (*p) {
        while (*p == ' ')
            p++;
        if (!*p)
            break;
        const char *end = p, *brk = NULL;
        int col = 2;
        while (*end && (col < EXAMPLE_WIDTH || !brk)) {
            if (*end == ' ')
                brk = end;
            /* count UTF-8 lead bytes only: one column per character */
            if (((unsigned char)*end & 0xC0) != 0x80)
                col++;
            end++;
        }
        if (*end && *end != ' ' && brk)
            end = brk;
        fprintf(out, "# %.*s\n", (int)(end - p), p);
        p = end;
    }
}

/* "HOST:PORT to listen on" + ". " + doc + " [restart]", the help's first
 * letter capitalised, as one paragraph. */
static void key_sentence(char *buf, size_t size, const cfg_key_doc *d)
{
    snprintf(buf, size, "%s.%s%s%s", d->help, *d->doc ? " " : "", d->doc,
             d->reloadable ? "" : " [restart]");
    if (buf[0] >= 'a' && buf[0] <= 'z')
        buf[0] = (char)(buf[0] - 'a' + 'A');
}

void cfg_doc_example(FILE *out)
{
    fputs("# /etc/facetd/facetd.conf — facetd's configuration (INI, like "
          "journald.conf).\n"
          "# Every key is optional; the values shown are the defaults. "
          "Files in\n"
          "# /etc/facetd/facetd.conf.d/*.conf override this file key by "
          "key, in\n"
          "# lexical order; command-line flags (facetd --help) override "
          "both. An\n"
          "# empty value resets a key to its default. SIGHUP (systemctl "
          "reload\n"
          "# facetd) reloads everything except the keys marked [restart].\n"
          "# facetd.conf(5) describes every key. This file is generated "
          "from\n"
          "# facetd's key table (facetd --dump-config-example); do not "
          "edit it.\n",
          out);
    const char *section = "";
    char buf[2048];
    for (int i = 0; i < cfg_key_count(); i++) {
        cfg_key_doc d;
        cfg_key_describe(i, &d);
        if (strcmp(section, d.section) != 0) {
            section = d.section;
            fprintf(out, "\n[%s]\n", section);
            comment_wrapped(out, d.section_doc);
        }
        fputc('\n', out);
        key_sentence(buf, sizeof buf, &d);
        comment_wrapped(out, buf);
        if (!d.repeatable) {
            fprintf(out, "#%s=%s\n", d.name, d.def);
            continue;
        }
        /* a list's default: one line per entry */
        const char *p = d.def;
        do {
            size_t n = strcspn(p, ",");
            fprintf(out, "#%s=%.*s\n", d.name, (int)n, p);
            p += n + (p[n] == ',');
        } while (*p);
    }
}

/* Writes s as roff text: backslashes escaped, a leading '.' or '\''
 * guarded, '-' as \- when minus is set (flags, keys), every non-ASCII
 * character as \[uXXXX] so that no encoding is assumed. */
static void roff(FILE *out, const char *s, bool minus)
{
    if (*s == '.' || *s == '\'')
        fputs("\\&", out);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '\\') {
            fputs("\\e", out);
        } else if (*p == '-' && minus) {
            fputs("\\-", out);
        } else if (*p < 0x80) {
            fputc(*p, out);
        } else {
            unsigned cp, extra;
            if ((*p & 0xE0) == 0xC0)
                cp = *p & 0x1F, extra = 1;
            else if ((*p & 0xF0) == 0xE0)
                cp = *p & 0x0F, extra = 2;
            else
                cp = *p & 0x07, extra = 3;
            for (; extra && (p[1] & 0xC0) == 0x80; extra--)
                cp = (cp << 6) | (*++p & 0x3F);
            fprintf(out, "\\[u%04X]", cp);
        }
    }
}

static void man_key(FILE *out, const cfg_key_doc *d)
{
    fputs(".TP\n\\fB", out);
    roff(out, d->name, true);
    fputs("=\\fR\\fI", out);
    roff(out, d->form, false);
    fputs("\\fR\n", out);
    char buf[2048];
    snprintf(buf, sizeof buf, "%s.", d->help);
    if (buf[0] >= 'a' && buf[0] <= 'z')
        buf[0] = (char)(buf[0] - 'a' + 'A');
    roff(out, buf, false);
    fputs("\n", out);
    if (*d->doc) {
        roff(out, d->doc, false);
        fputs("\n", out);
    }
    fputs(".br\nDefault: ", out);
    if (!*d->def) {
        fputs("none", out);
    } else if (d->repeatable) {
        /* a list's default: its entries, one line each in a file */
        for (const char *p = d->def; *p;) {
            size_t n = strcspn(p, ",");
            char entry[256];
            snprintf(entry, sizeof entry, "%.*s", (int)n, p);
            fputs(p == d->def ? "\\fB" : ", \\fB", out);
            roff(out, entry, true);
            fputs("\\fR", out);
            p += n + (p[n] == ',');
        }
        fputs(" (a line each)", out);
    } else {
        fputs("\\fB", out);
        roff(out, d->def, true);
        fputs("\\fR", out);
    }
    fputs(". Flag: \\fB\\-\\-", out);
    if (d->boolean)
        fputs("\\fR[\\fBno\\-\\fR]\\fB", out);
    roff(out, d->flag, true);
    fputs(d->boolean ? "\\fR" : "=\\fR\\fIV\\fR", out);
    fputs(d->reloadable ? ". Applied on reload.\n"
                        : ". Needs a restart.\n", out);
}

void cfg_doc_man(FILE *out)
{
    fputs(".\\\" facetd.conf(5), generated by facetd --dump-config-man from "
          "the\n"
          ".\\\" configuration table (daemon/cfg.c); do not edit.\n", out);
    fprintf(out, ".TH FACETD.CONF 5 \"\" \"facetd %s\" "
                 "\"File Formats Manual\"\n", FACET_VERSION);
    fputs(
        ".SH NAME\n"
        "facetd.conf \\- configuration of the facetd job server\n"
        ".SH SYNOPSIS\n"
        ".I /etc/facetd/facetd.conf\n"
        ".br\n"
        ".I /etc/facetd/facetd.conf.d/*.conf\n"
        ".SH DESCRIPTION\n"
        "\\fBfacetd\\fR(8) takes its configuration from built-in defaults, "
        "then the file\n"
        ".I /etc/facetd/facetd.conf\n"
        "(or the one given with \\fB\\-c\\fR \\fIPATH\\fR, which must "
        "exist), then the drop-ins\n"
        "\\fIPATH\\fR\\fB.d/\\fR\\fINAME\\fR\\fB.conf\\fR in lexical "
        "order, then its command-line flags;\n"
        "a later source overrides an earlier one key by key.\n"
        ".PP\n"
        "The syntax is that of \\fBjournald.conf\\fR(5): "
        "\\fB[\\fR\\fISection\\fR\\fB]\\fR lines,\n"
        "\\fIKey\\fR\\fB=\\fR\\fIValue\\fR lines, blank lines, and "
        "comment lines starting with\n"
        "\\fB#\\fR or \\fB;\\fR.\n"
        "Whitespace around keys and values is trimmed.\n"
        "An empty value resets a key to its default.\n"
        "An unknown section or key, or a malformed value, is an error "
        "naming the file and the line\n"
        "(\\fBfacetd.conf:12: Workers: expected a whole number\\fR); "
        "facetd does not start with it,\n"
        "and a reload keeps the running configuration.\n"
        ".PP\n"
        "Every key is also a flag of \\fBfacetd\\fR(8): "
        "\\fB\\-\\-workers=4\\fR or \\fB\\-\\-workers 4\\fR;\n"
        "a boolean flag also takes the form "
        "\\fB\\-\\-no\\-\\fR\\fIFLAG\\fR.\n"
        "\\fBfacetd \\-\\-help\\fR lists the flags with their defaults.\n"
        "This page, \\fBfacetd \\-\\-help\\fR and the example file are "
        "written from the one table of keys.\n"
        ".SH VALUES\n"
        ".TP\n"
        ".I SIZE\n"
        "Bytes, with an optional \\fBK\\fR, \\fBM\\fR, \\fBG\\fR or "
        "\\fBT\\fR suffix (powers of 1024).\n"
        ".TP\n"
        ".I DURATION\n"
        "Seconds, with an optional \\fBms\\fR, \\fBs\\fR, \\fBmin\\fR, "
        "\\fBh\\fR or \\fBd\\fR suffix.\n"
        ".TP\n"
        ".I BOOLEAN\n"
        "\\fByes\\fR/\\fBno\\fR, \\fBtrue\\fR/\\fBfalse\\fR, "
        "\\fBon\\fR/\\fBoff\\fR, \\fB1\\fR/\\fB0\\fR.\n"
        ".TP\n"
        ".I NUMBER\n"
        "A whole number within the key's range.\n"
        ".TP\n"
        ".I LEVEL\n"
        "\\fBerr\\fR, \\fBwarning\\fR, \\fBnotice\\fR, \\fBinfo\\fR or "
        "\\fBdebug\\fR.\n"
        ".TP\n"
        ".I PIPELINE\n"
        "\\fBcorrect\\fR (the post-scan correction; \\fBauto\\fR is its "
        "deprecated name); operation names separated by commas "
        "(\\fBinspect,triangulate\\fR, each with its defaults);\n"
        "a JSON array or string written inline; or the path of a file "
        "holding that JSON\n"
        "(starting with \\fB/\\fR or \\fB./\\fR), as "
        "\\fBfacet run\\fR takes it (\\fBfacet\\fR(1)).\n"
        ".TP\n"
        ".I DEVICE\n"
        "\\fIVID\\fR\\fB:\\fR\\fIPID\\fR\\fB:bulk\\fR or "
        "\\fIVID\\fR\\fB:\\fR\\fIPID\\fR\\fB:hid\\fR, the USB ids in "
        "hexadecimal and the transport.\n"
        ".TP\n"
        ".I TEXT\n"
        "Any text, up to the end of the line.\n"
        ".SH OPTIONS\n"
        "Keys marked \"Needs a restart\" keep their value when facetd "
        "reloads (SIGHUP,\n"
        "\\fBsystemctl reload facetd\\fR); facetd logs the ones that "
        "changed.\n",
        out);
    const char *section = "";
    for (int i = 0; i < cfg_key_count(); i++) {
        cfg_key_doc d;
        cfg_key_describe(i, &d);
        if (strcmp(section, d.section) != 0) {
            section = d.section;
            fprintf(out, ".SS [%s]\n", section);
            roff(out, d.section_doc, false);
            fputc('\n', out);
        }
        man_key(out, &d);
    }
    fputs(
        ".SH FILES\n"
        ".TP\n"
        ".I /etc/facetd/facetd.conf\n"
        "The configuration; every key is optional.\n"
        ".TP\n"
        ".I /etc/facetd/facetd.conf.d/*.conf\n"
        "Drop-ins, read in lexical order after the file.\n"
        ".TP\n"
        ".I PREFIX/share/doc/facetd/facetd.conf.example\n"
        "Every key with its default, commented out (installed by "
        "\\fBmake install\\fR).\n"
        ".SH EXAMPLE\n"
        "Serve the plant's network with a token, four workers, and a "
        "month of finished jobs:\n"
        ".PP\n"
        ".nf\n"
        ".RS\n"
        "[Server]\n"
        "Listen=0.0.0.0:8080\n"
        "ApiTokenFile=/etc/facetd/api\\-token\n"
        "\n"
        "[Jobs]\n"
        "Workers=4\n"
        "\n"
        "[Store]\n"
        "RetentionAge=30d\n"
        ".RE\n"
        ".fi\n"
        ".SH SEE ALSO\n"
        "\\fBfacetd\\fR(8), \\fBfacet\\fR(1), \\fBjournald.conf\\fR(5), "
        "\\fBsystemd.service\\fR(5)\n",
        out);
}
