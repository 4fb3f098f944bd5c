/* http_web.c — the web viewer (docs/viewer.md): GET / and GET /ui/{file},
 * the files of daemon/web/ embedded in the binary at build time with the
 * assembler's .incbin, as the OpenAPI document is. The scanner PC is
 * offline, so the page needs nothing but facetd: no CDN, no installed
 * directory that could drift from the binary.
 *
 * These routes are open (no token): the page itself holds no job data;
 * it asks for the token and sends it with every API request. Every reply
 * carries a Content-Security-Policy that allows only this origin, so a
 * stray external URL in the page fails in the browser at once instead of
 * hanging on a machine without a network. Caching: "no-cache" with a
 * strong ETag (the content's hash), so a browser revalidates with a 304
 * and an upgraded facetd is never served from a stale cache. */
#include "http.h"

#include <stdio.h>
#include <string.h>

/* One asset: sym_start .. sym_end in .rodata. */
#define WEB_ASSET(sym, file)                                                  \
    __asm__(".section .rodata\n"                                              \
            ".balign 16\n"                                                    \
            ".hidden " #sym "_start\n" #sym "_start:\n"                       \
            ".incbin \"daemon/web/" file "\"\n"                               \
            ".hidden " #sym "_end\n" #sym "_end:\n"                           \
            ".previous\n");                                                   \
    extern const char sym##_start[], sym##_end[];

WEB_ASSET(web_index, "index.html")
WEB_ASSET(web_css, "app.css")
WEB_ASSET(web_boot, "boot.js")
WEB_ASSET(web_app, "app.js")
WEB_ASSET(web_api, "api.js")
WEB_ASSET(web_jobs, "jobs.js")
WEB_ASSET(web_job, "job.js")
WEB_ASSET(web_model, "model.js")
WEB_ASSET(web_gl, "gl.js")
WEB_ASSET(web_submit, "submit.js")
WEB_ASSET(web_scanners, "scanners.js")

typedef struct web_file {
    const char *name, *ctype;
    const char *start, *end;
} web_file;

static const web_file files[] = {
    {"index.html", "text/html; charset=utf-8", web_index_start,
     web_index_end},
    {"app.css", "text/css; charset=utf-8", web_css_start, web_css_end},
    {"boot.js", "text/javascript; charset=utf-8", web_boot_start,
     web_boot_end},
    {"app.js", "text/javascript; charset=utf-8", web_app_start, web_app_end},
    {"api.js", "text/javascript; charset=utf-8", web_api_start, web_api_end},
    {"jobs.js", "text/javascript; charset=utf-8", web_jobs_start,
     web_jobs_end},
    {"job.js", "text/javascript; charset=utf-8", web_job_start, web_job_end},
    {"model.js", "text/javascript; charset=utf-8", web_model_start,
     web_model_end},
    {"gl.js", "text/javascript; charset=utf-8", web_gl_start, web_gl_end},
    {"submit.js", "text/javascript; charset=utf-8", web_submit_start,
     web_submit_end},
    {"scanners.js", "text/javascript; charset=utf-8", web_scanners_start,
     web_scanners_end},
};
enum { NFILES = sizeof files / sizeof files[0] };

static const char csp[] =
    "default-src 'self'; script-src 'self'; style-src 'self'; "
    "img-src 'self' data: blob:; connect-src 'self'; object-src 'none'; "
    "base-uri 'none'; form-action 'self'; frame-ancestors 'none'";

size_t http_web_total_bytes(void)
{
    size_t n = 0;
    for (int i = 0; i < NFILES; i++)
        n += (size_t)(files[i].end - files[i].start);
    return n;
}

static enum MHD_Result serve(http_req *r, const web_file *f)
{
    size_t len = (size_t)(f->end - f->start);
    char etag[40];
    snprintf(etag, sizeof etag, "\"%016llx\"",
             (unsigned long long)job_hash64(f->start, len));
    const char *h[] = {"ETag", etag, "Cache-Control", "no-cache",
                       "Content-Security-Policy", csp,
                       "Referrer-Policy", "no-referrer", NULL};
    if (http_not_modified(r, etag))
        return http_reply(r, 304, NULL, (char *)"", 0, false, h);
    return http_reply(r, 200, f->ctype, (char *)f->start, len, false, h);
}

enum MHD_Result http_web_index(http_req *r)
{
    return serve(r, &files[0]);
}

enum MHD_Result http_web_file(http_req *r)
{
    for (int i = 1; i < NFILES; i++)
        if (strcmp(r->file, files[i].name) == 0)
            return serve(r, &files[i]);
    return http_problem(r, 404, "no-such-asset", "Not Found", NULL, NULL,
                        "the viewer has no file '%s'", r->file);
}
