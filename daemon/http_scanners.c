/* http_scanners.c — the scanner routes: GET /v1/scanners (every scanner
 * seen since start, with its state, progress and last job) and
 * POST /v1/scanners/{serial}/scan (START_SCAN).
 *
 * A scan asked for here arrives like one started at the scanner: its job
 * (source usb:SERIAL) appears in GET /v1/jobs?source=usb:SERIAL once the
 * model is in, so the answer is 202 with the scanner and that link.
 * Errors: 400 malformed body, 404 unknown serial (or the intake is off),
 * 409 offline or already scanning, 422 a bad mode, 502 the device could
 * not be written to, 503 connected but not greeted yet (Retry-After). */
#include "http.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

static const char *const modes[] = {"quick", "accuracy", "hi-accuracy"};

enum MHD_Result http_scanners(http_req *r)
{
    if (!r->env->sc)
        return http_reply_json(r, 200,
                               json_pack("{s:b, s:[]}", "enabled", 0,
                                         "scanners"),
                               NULL);
    json_t *o = scanners_list_json(r->env->sc);
    if (!o)
        return http_problem(r, 500, "out-of-memory", "Internal Server Error",
                            NULL, NULL, "the scanner list could not be made");
    const char *h[] = {"Cache-Control", "no-store", NULL};
    return http_reply_json(r, 200, o, h);
}

static int invalid(http_req *r, enum MHD_Result *res, const char *path,
                   const char *msg)
{
    *res = http_problem(r, 422, "invalid-scan-request",
                        "Unprocessable Content",
                        json_pack("[{s:s, s:s}]", "path", path, "message",
                                  msg),
                        NULL, "%s%s%s", path, *path ? ": " : "", msg);
    return -1;
}

/* The mode of the body ({"mode": "quick"|"accuracy"|"hi-accuracy"}, all
 * optional; accuracy by default): 0..2, or -1 with a reply queued. */
static int mode_arg(http_req *r, enum MHD_Result *res)
{
    if (!r->body || r->len == 0)
        return 1;
    json_error_t je;
    json_t *root = json_loadb(r->body, r->len, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        json_t *errors = json_pack("[{s:s, s:s, s:i, s:i}]", "path", "",
                                   "message", je.text, "line",
                                   (json_int_t)je.line, "column",
                                   (json_int_t)je.column);
        *res = http_problem(r, 400, "malformed-json", "Bad Request", errors,
                            NULL, "line %d, column %d: %s", je.line,
                            je.column, je.text);
        return -1;
    }
    int mode = -2;
    const char *key;
    json_t *val;
    if (!json_is_object(root)) {
        mode = invalid(r, res, "", "the body must be a JSON object");
    } else {
        json_object_foreach(root, key, val) {
            if (strcmp(key, "mode") != 0) {
                mode = invalid(r, res, key, "unknown member (expected mode)");
                break;
            }
        }
    }
    if (mode == -2) {
        const json_t *v = json_object_get(root, "mode");
        const char *m = json_string_value(v);
        mode = v ? -1 : 1;
        for (int i = 0; m && i < 3; i++)
            if (strcmp(m, modes[i]) == 0)
                mode = i;
        if (mode < 0)
            invalid(r, res, "mode", "expected \"quick\", \"accuracy\" or "
                    "\"hi-accuracy\"");
    }
    json_decref(root);
    return mode;
}

enum MHD_Result http_scanner_scan(http_req *r)
{
    enum MHD_Result res;
    int mode = mode_arg(r, &res);
    if (mode < 0)
        return res;
    scanners *sc = r->env->sc;
    const char *why = "";
    if (!sc || !scanners_enabled(sc, &why))
        return http_problem(r, 404, "scanner-not-found", "Not Found", NULL,
                            NULL, "no scanner '%s': the scanner intake is "
                            "off (%s)", r->serial, sc ? why : "");
    int rc = scanners_request_scan(sc, r->serial, (uint8_t)mode);
    switch (rc) {
    case 0:
        break;
    case -ENOENT:
        return http_problem(r, 404, "scanner-not-found", "Not Found", NULL,
                            NULL, "no scanner '%s' (GET /v1/scanners lists "
                            "them)", r->serial);
    case -ENODEV:
        return http_problem(r, 409, "scanner-offline", "Conflict", NULL, NULL,
                            "scanner %s is not connected", r->serial);
    case -EBUSY:
        return http_problem(r, 409, "scanner-busy", "Conflict", NULL, NULL,
                            "scanner %s is scanning", r->serial);
    case -EAGAIN: {
        const char *h[] = {"Retry-After", "1", NULL};
        return http_problem(r, 503, "scanner-not-ready",
                            "Service Unavailable", NULL, h,
                            "scanner %s has not answered HELLO yet",
                            r->serial);
    }
    default:
        return http_problem(r, 502, "scanner-io-error", "Bad Gateway", NULL,
                            NULL, "START_SCAN could not be sent to %s: %s",
                            r->serial, strerror(rc < 0 ? -rc : EIO));
    }
    json_t *o = NULL;
    if (scanners_status_json(sc, r->serial, &o) < 0)
        o = json_object();
    char jobs[128];
    snprintf(jobs, sizeof jobs, "/v1/jobs?source=usb:%s", r->serial);
    json_object_set_new(o, "requested_mode", json_string(modes[mode]));
    json_object_set_new(o, "links", json_pack("{s:s, s:s}", "jobs", jobs,
                                              "scanners", "/v1/scanners"));
    return http_reply_json(r, 202, o, NULL);
}
