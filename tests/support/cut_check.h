/* cut_check.h — checking plane-cut results in tests: validity by
 * geo_inspect and by cs_check_valid, and the two halves of a cut (by a
 * plane and by its opposite) adding up to the model. */
#ifndef FACET_CUT_CHECK_H
#define FACET_CUT_CHECK_H

#include "cut.h"
#include "poly.h"

/* NULL when geo_inspect finds p valid, else a static message naming
 * what it found wrong. */
const char *cc_inspect_problem(const geo_poly *p);

/* NULL when p is valid by cs_check_valid (tolerance 1e-9 of the size of
 * `model`) and by geo_inspect, else a static message. */
const char *cc_result_problem(const geo_poly *model, const geo_poly *p);

typedef struct cc_halves {
    int code[2];             /* geo_cut for the plane and for its opposite */
    geo_err err[2];
    geo_cut_report rep[2];
    double volume[2];        /* of each result (0 when empty or refused) */
} cc_halves;

/* Cuts p by plane and by −plane into *ret. Returns NULL, or a static
 * message when a cut that succeeded gave an invalid result, or when both
 * succeeded and their volumes do not add up to p's within 1e-9
 * relative. A refusal (negative code) is not a problem here: the caller
 * judges ret->code. */
const char *cc_cut_both(const geo_poly *p, const double plane[4],
                        cc_halves *ret);

#endif
