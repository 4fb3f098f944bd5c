/* fuzz_points_json.c — libFuzzer target: the point-list reader
 * (proto_points_read_mem, a pull reader) on arbitrary bytes against a
 * reference built on a jansson tree, the way the reader worked before:
 * both accept with the same points or both refuse with the same code and
 * message, under a small count limit so that -ERANGE is reached too.
 * Inputs with a NUL byte right after a number or a literal are skipped:
 * jansson drops that byte, the tokenizer refuses it (json_pull.h). */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "points_json.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { LIMIT = 6 };

/* The reference: the whole text parsed into a tree first, then checked
 * (the count before any element). */
static int reference(const uint8_t *data, size_t size, double (**ret)[3],
                     size_t *ret_n, char *msg, size_t msg_size)
{
    json_error_t je;
    json_t *root = json_loadb((const char *)data, size,
                              JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        snprintf(msg, msg_size, "line %d, column %d: %s", je.line,
                 je.column, je.text);
        return -EINVAL;
    }
    int rc = 0;
    const json_t *arr = root;
    double(*pts)[3] = NULL;
    size_t n = 0;
    if (json_is_object(root)) {
        arr = json_object_get(root, "points");
        if (!arr) {
            snprintf(msg, msg_size, "points: missing");
            rc = -EINVAL;
            goto out;
        }
        if (!json_is_array(arr)) {
            snprintf(msg, msg_size, "points: expected an array");
            rc = -EINVAL;
            goto out;
        }
    }
    n = json_array_size(arr);
    if (n > LIMIT) {
        snprintf(msg, msg_size, "points: %zu points exceed the limit of %d",
                 n, LIMIT);
        rc = -ERANGE;
        goto out;
    }
    pts = calloc(n + 1, sizeof *pts);
    for (size_t i = 0; i < n && rc == 0; i++) {
        const json_t *pt = json_array_get(arr, i);
        if (!json_is_array(pt)) {
            snprintf(msg, msg_size,
                     "points[%zu]: expected an array of 3 numbers", i);
            rc = -EINVAL;
        } else if (json_array_size(pt) != 3) {
            snprintf(msg, msg_size, "points[%zu]: expected 3 numbers, got %zu",
                     i, json_array_size(pt));
            rc = -EINVAL;
        } else {
            for (size_t k = 0; k < 3 && rc == 0; k++) {
                const json_t *c = json_array_get(pt, k);
                if (!json_is_number(c)) {
                    snprintf(msg, msg_size, "points[%zu][%zu]: expected a "
                             "number", i, k);
                    rc = -EINVAL;
                } else {
                    pts[i][k] = json_number_value(c);
                }
            }
        }
    }
out:
    json_decref(root);
    if (rc == 0) {
        *ret = pts;
        *ret_n = n;
    } else {
        free(pts);
    }
    return rc;
}

static bool nul_after_word(const uint8_t *d, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        unsigned p = d[i - 1] | 0x20;
        if (d[i] == 0 && ((d[i - 1] >= '0' && d[i - 1] <= '9') ||
                          (p >= 'a' && p <= 'z')))
            return true;
    }
    return false;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (nul_after_word(data, size))
        return 0;
    double(*want)[3] = NULL, (*got)[3] = NULL;
    size_t nwant = 0, ngot = 0;
    char msg[512];
    int rw = reference(data, size, &want, &nwant, msg, sizeof msg);
    geo_err err = {{0}};
    int rg = proto_points_read_mem(data, size, LIMIT, &got, &ngot, &err);
    if (rw != rg) {
        fprintf(stderr, "codes differ: reference %d (%s), reader %d (%s)\n",
                rw, rw ? msg : "", rg, rg ? err.msg : "");
        abort();
    }
    if (rw != 0 && strcmp(msg, err.msg) != 0) {
        fprintf(stderr, "messages differ:\n  reference %s\n  reader    %s\n",
                msg, err.msg);
        abort();
    }
    if (rw == 0 && (nwant != ngot ||
                    (ngot && memcmp(want, got, ngot * sizeof *got) != 0))) {
        fprintf(stderr, "points differ (%zu vs %zu)\n", nwant, ngot);
        abort();
    }
    free(want);
    free(got);
    return 0;
}
