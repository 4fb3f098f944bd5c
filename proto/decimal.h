/* decimal.h — exact conversions between decimal text and doubles, the
 * number path of every text model format.
 *
 * Reading: proto_decimal_parse gives the double nearest to the decimal
 * (ties to even), exactly as strtod does in the C locale. Exact integer
 * arithmetic decides most numbers without strtod: Clinger's fast path (at
 * most 2^53 in the digits, |exponent| ≤ 22: one correctly rounded IEEE
 * operation on exact operands), else the digits as a 64-bit integer w
 * (≤ 19 significant digits) times 10^q with |q| ≤ 27, rounded from the
 * exact 128-bit product w·5^q (q ≥ 0) or, for q < 0, by Eisel–Lemire: w
 * times a 128-bit 5^q, which for 5^−q < 2^64 decides every rounding.
 * Anything else (more digits, larger exponents) goes to strtod.
 *
 * Writing: proto_decimal_format prints the same text as the loop
 * "%.15g, %.16g, %.17g — the first that strtod reads back as x", so files
 * written before stay byte-identical. For 1e-11 ≤ |x| < 1e17 (and x not a
 * power of two) the digits come from exact 128-bit integer arithmetic: x·10^p
 * = m·5^p·2^(e+p) with 0 ≤ p ≤ 27, rounded to 17, 16 and 15 digits with
 * ties to even as printf does, and each candidate tested against the
 * rounding interval of x (half an ulp either side, the ends included when
 * x's significand is even: what round-to-nearest-even reading accepts).
 * Other values use snprintf and strtod.
 *
 * Both are reentrant and thread-safe; they assume the C locale for
 * LC_NUMERIC (the programs never call setlocale). */
#ifndef PROTO_DECIMAL_H
#define PROTO_DECIMAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Room proto_decimal_format needs (sign, 17 digits, point, exponent). */
#define PROTO_DECIMAL_MAX 32

/* Converts a number written in the JSON grammar
 * (-?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?), s[0..len) (not
 * NUL-terminated; the caller has checked the grammar), into *ret.
 * 0, or -ERANGE when the magnitude overflows a double (*ret untouched);
 * underflow gives the nearest subnormal or zero, as strtod. -ENOMEM when
 * a very long number cannot be copied for strtod. */
int proto_decimal_parse(const char *s, size_t len, double *ret);

/* The same, for a scanner that has already gathered the digits: the value
 * is (neg ? −1 : 1)·w·10^q, exactly unless inexact (a non-zero digit
 * beyond the 19 significant ones kept in w was dropped); s[0..len) is the
 * number's text, for strtod when exact arithmetic cannot decide. */
int proto_decimal_from_parts(bool neg, uint64_t w, int64_t q, bool inexact,
                             const char *s, size_t len, double *ret);

/* Writes finite x into out (PROTO_DECIMAL_MAX bytes), NUL-terminated, as
 * described above; "0" for +0 and "-0.0" for −0 (so that −0 reads back as
 * a JSON real, keeping its sign). Returns the length. */
size_t proto_decimal_format(char *out, double x);

/* The text of printf's "%.17g" (what jansson writes for a real before
 * its own touches), from the same exact arithmetic: for documents of
 * many reals, where snprintf is most of the cost. */
size_t proto_decimal_format_g17(char *out, double x);

#endif
