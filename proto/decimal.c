/* decimal.c — exact decimal ↔ double conversions (decimal.h).
 *
 * Invariant of both directions: a result comes from exact integer
 * arithmetic or from the C library (strtod, snprintf); no step rounds
 * twice. The 128-bit integers are GCC's unsigned __int128. */
#include "decimal.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

__extension__ typedef unsigned __int128 u128;

/* 5^0 .. 5^27, the powers of five below 2^63. */
#define POW5_LIST(X)                                                        \
    X(1) X(5) X(25) X(125) X(625) X(3125) X(15625) X(78125) X(390625)       \
    X(1953125) X(9765625) X(48828125) X(244140625) X(1220703125)            \
    X(6103515625) X(30517578125) X(152587890625) X(762939453125)            \
    X(3814697265625) X(19073486328125) X(95367431640625)                    \
    X(476837158203125) X(2384185791015625) X(11920928955078125)             \
    X(59604644775390625) X(298023223876953125) X(1490116119384765625)       \
    X(7450580596923828125)
#define AS_U64(v) UINT64_C(v),
#define AS_RECIP(v) (~(u128)0 / UINT64_C(v)),
static const uint64_t POW5[28] = {POW5_LIST(AS_U64)};
/* floor(2^128 / 5^k) (5^k does not divide 2^128): division by 5^k as
 * two products (parse_exact) */
static const u128 RECIP5[28] = {POW5_LIST(AS_RECIP)};

/* 10^0 .. 10^22: every one is a double exactly. */
static const double POW10D[23] = {
    1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
};

/* 10^0 .. 10^19. */
static const uint64_t POW10U[20] = {
    UINT64_C(1), UINT64_C(10), UINT64_C(100), UINT64_C(1000),
    UINT64_C(10000), UINT64_C(100000), UINT64_C(1000000),
    UINT64_C(10000000), UINT64_C(100000000), UINT64_C(1000000000),
    UINT64_C(10000000000), UINT64_C(100000000000),
    UINT64_C(1000000000000), UINT64_C(10000000000000),
    UINT64_C(100000000000000), UINT64_C(1000000000000000),
    UINT64_C(10000000000000000), UINT64_C(100000000000000000),
    UINT64_C(1000000000000000000), UINT64_C(10000000000000000000),
};

#define MANT_MASK ((UINT64_C(1) << 52) - 1)

static int clz128(u128 v)
{
    uint64_t hi = (uint64_t)(v >> 64);
    return hi ? __builtin_clzll(hi) : 64 + __builtin_clzll((uint64_t)v);
}

/* The double nearest to (n + f)·2^e2, ties to even, where f is 0 when
 * sticky is false and strictly between 0 and 1 (in units of n's last bit)
 * otherwise. False when the result would not be a normal double (the
 * caller then asks strtod, which handles subnormals and overflow).
 * n ≠ 0; sticky needs n ≥ 2^54 so that f lies below the rounding bit. */
static bool round_to_double(u128 n, int e2, bool sticky, double *ret)
{
    int bits = 128 - clz128(n);
    uint64_t m;
    if (bits <= 53) {
        if (sticky)
            return false;
        m = (uint64_t)n << (53 - bits);
        e2 -= 53 - bits;
    } else {
        int sh = bits - 53;
        m = (uint64_t)(n >> sh);
        u128 rest = n & (((u128)1 << sh) - 1);
        u128 half = (u128)1 << (sh - 1);
        if (rest > half || (rest == half && (sticky || (m & 1))))
            m++;
        e2 += sh;
        if (m >> 53) {
            m >>= 1;
            e2++;
        }
    }
    int be = e2 + 52 + 1023;
    if (be < 1 || be > 2046)
        return false;
    uint64_t b = (uint64_t)be << 52 | (m & MANT_MASK);
    memcpy(ret, &b, sizeof b);
    return true;
}

/* w·10^q (w ≠ 0) when exact integer arithmetic decides it. */
static bool parse_exact(uint64_t w, int64_t q, double *ret)
{
    if (w <= UINT64_C(1) << 53 && q >= -22 && q <= 22) {
        double d = (double)w;
        *ret = q < 0 ? d / POW10D[-q] : d * POW10D[q];
        return true;
    }
    if (q >= 0 && q <= 27)
        return round_to_double((u128)w * POW5[q], (int)q, false, ret);
    if (q < 0 && q >= -27) {
        /* w·10^q = (w·2^(64+l) / 5^k) · 2^(q−64−l) with k = −q; the
         * quotient has more than 64 bits, the remainder is the sticky
         * part */
        int l = __builtin_clzll(w);
        uint64_t h = w << l, den = POW5[-q];
        u128 num = (u128)h << 64, r = RECIP5[-q];
        /* num·r / 2^128 lies in (num/den − 1, num/den]: its floor, formed
         * exactly from h·r's two halves, is the quotient or one less, and
         * the remainder says which */
        u128 quo = (u128)h * (uint64_t)(r >> 64) +
                   (((u128)h * (uint64_t)r) >> 64);
        u128 rem = num - quo * den;
        while (rem >= den) {
            quo++;
            rem -= den;
        }
        return round_to_double(quo, (int)q - 64 - l, rem != 0, ret);
    }
    return false;
}

static int parse_libc(const char *s, size_t len, double *ret)
{
    char small[64];
    char *buf = len < sizeof small ? small : malloc(len + 1);
    if (!buf)
        return -ENOMEM;
    memcpy(buf, s, len);
    buf[len] = '\0';
    errno = 0;
    double v = strtod(buf, NULL);
    int e = errno;
    if (buf != small)
        free(buf);
    if ((v == HUGE_VAL || v == -HUGE_VAL) && e == ERANGE)
        return -ERANGE;
    *ret = v;
    return 0;
}

static bool is_digit(char c)
{
    return (unsigned)(c - '0') < 10;
}

int proto_decimal_parse(const char *s, size_t len, double *ret)
{
    const char *p = s, *end = s + len;
    bool neg = p < end && *p == '-';
    if (neg)
        p++;
    /* value = w · 10^q exactly unless a non-zero digit was dropped */
    uint64_t w = 0;
    int nd = 0;
    int64_t q = 0;
    bool dropped = false;
    for (; p < end && is_digit(*p); p++) {
        unsigned d = (unsigned)(*p - '0');
        if (nd < 19) {
            w = w * 10 + d;
            nd += w != 0;
        } else {
            q++;
            dropped |= d != 0;
        }
    }
    if (p < end && *p == '.') {
        for (p++; p < end && is_digit(*p); p++) {
            unsigned d = (unsigned)(*p - '0');
            if (nd < 19) {
                w = w * 10 + d;
                nd += w != 0;
                q--;
            } else {
                dropped |= d != 0;
            }
        }
    }
    if (p < end && (*p == 'e' || *p == 'E')) {
        p++;
        bool eneg = false;
        if (p < end && (*p == '+' || *p == '-'))
            eneg = *p++ == '-';
        int64_t ex = 0;
        for (; p < end && is_digit(*p); p++)
            if (ex < 1000000000)
                ex = ex * 10 + (*p - '0');
        q += eneg ? -ex : ex;
    }
    return proto_decimal_from_parts(neg, w, q, dropped, s, len, ret);
}

int proto_decimal_from_parts(bool neg, uint64_t w, int64_t q, bool inexact,
                             const char *s, size_t len, double *ret)
{
    if (w == 0) {
        *ret = neg ? -0.0 : 0.0;
        return 0;
    }
    double v;
    if (!inexact && parse_exact(w, q, &v)) {
        *ret = neg ? -v : v;
        return 0;
    }
    return parse_libc(s, len, ret);
}

static size_t format_libc(char *out, double x, int nmin)
{
    /* %.17g always reads back; shorter forms are tried first so that 0.1
     * prints as 0.1 rather than 0.10000000000000001 */
    int n = 0;
    for (int prec = nmin; prec <= 17; prec++) {
        n = snprintf(out, PROTO_DECIMAL_MAX, "%.*g", prec, x);
        if (prec == 17 || strtod(out, NULL) == x)
            break;
    }
    return (size_t)n;
}

/* floor(e · log10 2) for |e| ≤ 1100, within one (the caller corrects). */
static int log10_pow2(int e)
{
    return e >= 0 ? (e * 78913) >> 18 : -((-e * 78913 + (1 << 18) - 1) >> 18);
}

/* The text printf's "%.{n}g" gives for the n-digit decimal d·10^(X−n+1)
 * (10^(n−1) ≤ d < 10^n, −11 ≤ X ≤ 17, so the exponent has two digits). */
static size_t emit_g(char *out, bool neg, uint64_t d, int n, int X)
{
    char dg[20];
    for (int i = n - 1; i >= 0; i--) {
        dg[i] = (char)('0' + d % 10);
        d /= 10;
    }
    int k = n;
    while (k > 1 && dg[k - 1] == '0')
        k--;
    char *o = out;
    if (neg)
        *o++ = '-';
    if (X < -4 || X >= n) {
        *o++ = dg[0];
        if (k > 1) {
            *o++ = '.';
            memcpy(o, dg + 1, (size_t)k - 1);
            o += k - 1;
        }
        int ax = X < 0 ? -X : X;
        *o++ = 'e';
        *o++ = X < 0 ? '-' : '+';
        *o++ = (char)('0' + ax / 10);
        *o++ = (char)('0' + ax % 10);
    } else if (X >= 0) {
        int ip = X + 1;
        if (k <= ip) {
            memcpy(o, dg, (size_t)k);
            o += k;
            memset(o, '0', (size_t)(ip - k));
            o += ip - k;
        } else {
            memcpy(o, dg, (size_t)ip);
            o += ip;
            *o++ = '.';
            memcpy(o, dg + ip, (size_t)(k - ip));
            o += k - ip;
        }
    } else {
        *o++ = '0';
        *o++ = '.';
        for (int i = 0; i < -X - 1; i++)
            *o++ = '0';
        memcpy(o, dg, (size_t)k);
        o += k;
    }
    *o = '\0';
    return (size_t)(o - out);
}

/* The %.{n}g text of x for the first n in nmin..17 that reads back as x
 * (nmin 17: printf's %.17g itself). */
static size_t format_g(char *out, double x, int nmin)
{
    if (nmin == 17 && (x == 0 || !isfinite(x)))
        return (size_t)snprintf(out, PROTO_DECIMAL_MAX, "%.17g", x);
    if (x == 0) {
        /* "-0" would read back as the JSON integer 0: keep the sign */
        const char *z = signbit(x) ? "-0.0" : "0";
        strcpy(out, z);
        return strlen(z);
    }
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    bool neg = bits >> 63;
    int be = (int)(bits >> 52 & 0x7ff);
    /* subnormals, and powers of two (whose lower rounding gap is half the
     * upper one), go to the C library */
    if (be == 0 || (bits & MANT_MASK) == 0)
        return format_libc(out, x, nmin);
    uint64_t m = (bits & MANT_MASK) | UINT64_C(1) << 52;
    int e = be - 1075; /* x = m · 2^e */
    int X = log10_pow2(be - 1023) + 1;
    for (int tries = 0; tries < 4; tries++) {
        int p = 16 - X;
        if (p < 0 || p > 27)
            return format_libc(out, x, nmin);
        /* V = |x|·10^p = M·2^s = I + rem/2^t exactly */
        u128 M = (u128)m * POW5[p];
        int s = e + p, t = s < 0 ? -s : 0;
        u128 V;
        if (s >= 0) {
            if (s >= 64 || M >> (64 - s)) {
                X++;
                continue;
            }
            V = M << s;
        } else {
            if (t >= 116) {
                X--;
                continue;
            }
            V = M >> t;
        }
        if (V >= POW10U[17]) {
            X++;
            continue;
        }
        if (V < POW10U[16]) {
            X--;
            continue;
        }
        uint64_t I = (uint64_t)V;
        u128 rem = s < 0 ? M & (((u128)1 << t) - 1) : 0;
        /* In units of 2^−(t+1): V, the half ulp (5^p·2^(s−1) scaled) and
         * a candidate; the candidate reads back as x when it lies within
         * the half ulp, the ends counting when m is even. */
        u128 Vu = (s >= 0 ? M << s : M) << 1;
        u128 Hu = (u128)POW5[p] << (s >= 0 ? s : 0);
        for (int n = nmin; n <= 17; n++) {
            uint64_t dv = POW10U[17 - n];
            uint64_t qn = I / dv, r = I % dv;
            u128 f2 = ((u128)r << (t + 1)) + (rem << 1);
            u128 hd = (u128)dv << t;
            if (f2 > hd || (f2 == hd && (qn & 1)))
                qn++;
            u128 Du = ((u128)qn * dv) << (t + 1);
            u128 diff = Du > Vu ? Du - Vu : Vu - Du;
            if (diff < Hu || (diff == Hu && !(m & 1))) {
                int Xn = X;
                if (qn == POW10U[n]) {
                    qn = POW10U[n - 1];
                    Xn++;
                }
                return emit_g(out, neg, qn, n, Xn);
            }
        }
        break;
    }
    return format_libc(out, x, nmin);
}

size_t proto_decimal_format(char *out, double x)
{
    return format_g(out, x, 15);
}

size_t proto_decimal_format_g17(char *out, double x)
{
    return format_g(out, x, 17);
}
