/* decimal.c — exact decimal ↔ double conversions (decimal.h).
 *
 * Invariant of both directions: a result comes from exact integer
 * arithmetic (Eisel–Lemire's product decides exactly in its range) or
 * from the C library (strtod, snprintf); no step rounds twice. The
 * 128-bit integers are GCC's unsigned __int128. */
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
static const uint64_t POW5[28] = {
    UINT64_C(1), UINT64_C(5), UINT64_C(25), UINT64_C(125), UINT64_C(625),
    UINT64_C(3125), UINT64_C(15625), UINT64_C(78125), UINT64_C(390625),
    UINT64_C(1953125), UINT64_C(9765625), UINT64_C(48828125),
    UINT64_C(244140625), UINT64_C(1220703125), UINT64_C(6103515625),
    UINT64_C(30517578125), UINT64_C(152587890625), UINT64_C(762939453125),
    UINT64_C(3814697265625), UINT64_C(19073486328125),
    UINT64_C(95367431640625), UINT64_C(476837158203125),
    UINT64_C(2384185791015625), UINT64_C(11920928955078125),
    UINT64_C(59604644775390625), UINT64_C(298023223876953125),
    UINT64_C(1490116119384765625), UINT64_C(7450580596923828125),
};

/* Eisel–Lemire's table for 5^q, q = −27 .. −1 (entry q + 27), as
 * fast_float generates it: floor(2^b / 5^−q) + 1 with b = 127 + the bit
 * length of 5^−q, a 128-bit number with its top bit set, high word
 * first. */
static const uint64_t POW5_INV[27][2] = {
    {UINT64_C(0x9e74d1b791e07e48), UINT64_C(0x775ea264cf55347e)},
    {UINT64_C(0xc612062576589dda), UINT64_C(0x95364afe032a819e)},
    {UINT64_C(0xf79687aed3eec551), UINT64_C(0x3a83ddbd83f52205)},
    {UINT64_C(0x9abe14cd44753b52), UINT64_C(0xc4926a9672793543)},
    {UINT64_C(0xc16d9a0095928a27), UINT64_C(0x75b7053c0f178294)},
    {UINT64_C(0xf1c90080baf72cb1), UINT64_C(0x5324c68b12dd6339)},
    {UINT64_C(0x971da05074da7bee), UINT64_C(0xd3f6fc16ebca5e04)},
    {UINT64_C(0xbce5086492111aea), UINT64_C(0x88f4bb1ca6bcf585)},
    {UINT64_C(0xec1e4a7db69561a5), UINT64_C(0x2b31e9e3d06c32e6)},
    {UINT64_C(0x9392ee8e921d5d07), UINT64_C(0x3aff322e62439fd0)},
    {UINT64_C(0xb877aa3236a4b449), UINT64_C(0x09befeb9fad487c3)},
    {UINT64_C(0xe69594bec44de15b), UINT64_C(0x4c2ebe687989a9b4)},
    {UINT64_C(0x901d7cf73ab0acd9), UINT64_C(0x0f9d37014bf60a11)},
    {UINT64_C(0xb424dc35095cd80f), UINT64_C(0x538484c19ef38c95)},
    {UINT64_C(0xe12e13424bb40e13), UINT64_C(0x2865a5f206b06fba)},
    {UINT64_C(0x8cbccc096f5088cb), UINT64_C(0xf93f87b7442e45d4)},
    {UINT64_C(0xafebff0bcb24aafe), UINT64_C(0xf78f69a51539d749)},
    {UINT64_C(0xdbe6fecebdedd5be), UINT64_C(0xb573440e5a884d1c)},
    {UINT64_C(0x89705f4136b4a597), UINT64_C(0x31680a88f8953031)},
    {UINT64_C(0xabcc77118461cefc), UINT64_C(0xfdc20d2b36ba7c3e)},
    {UINT64_C(0xd6bf94d5e57a42bc), UINT64_C(0x3d32907604691b4d)},
    {UINT64_C(0x8637bd05af6c69b5), UINT64_C(0xa63f9a49c2c1b110)},
    {UINT64_C(0xa7c5ac471b478423), UINT64_C(0x0fcf80dc33721d54)},
    {UINT64_C(0xd1b71758e219652b), UINT64_C(0xd3c36113404ea4a9)},
    {UINT64_C(0x83126e978d4fdf3b), UINT64_C(0x645a1cac083126ea)},
    {UINT64_C(0xa3d70a3d70a3d70a), UINT64_C(0x3d70a3d70a3d70a4)},
    {UINT64_C(0xcccccccccccccccc), UINT64_C(0xcccccccccccccccd)},
};

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

/* The double nearest to n·2^e2 (n ≠ 0), ties to even; the caller's
 * range keeps it normal (w·10^q for q in 0..27: at most 2^64 · 10^27). */
static double round_to_double(u128 n, int e2)
{
    int bits = 128 - clz128(n);
    uint64_t m;
    if (bits <= 53) {
        m = (uint64_t)n << (53 - bits);
        e2 -= 53 - bits;
    } else {
        int sh = bits - 53;
        m = (uint64_t)(n >> sh);
        u128 rest = n & (((u128)1 << sh) - 1);
        u128 half = (u128)1 << (sh - 1);
        if (rest > half || (rest == half && (m & 1)))
            m++;
        e2 += sh;
        if (m >> 53) {
            m >>= 1;
            e2++;
        }
    }
    uint64_t b = (uint64_t)(e2 + 52 + 1023) << 52 | (m & MANT_MASK);
    double d;
    memcpy(&d, &b, sizeof d);
    return d;
}

/* w·10^q for w ≠ 0 and −27 ≤ q ≤ −1 by Eisel–Lemire (Lemire, "Number
 * parsing at a gigabyte per second", 2021, as fast_float does it): w
 * normalised times the top 64 bits of 5^q, the next 64 bits added only
 * when the product's rounding bits are all ones; then the 54 top bits
 * rounded, ties to even where the product was exact. In this range
 * 5^−q < 2^64, so the 128-bit product decides every rounding (fast_float's
 * "safe exponents": no fallback; tests/unit/test_decimal.c against
 * strtod), and the result is a normal double (1e-27 ≤ w·10^q < 2^64). */
static double eisel_lemire(uint64_t w, int q)
{
    int lz = __builtin_clzll(w);
    w <<= lz;
    const uint64_t *t = POW5_INV[q + 27];
    u128 z = (u128)w * t[0];
    uint64_t hi = (uint64_t)(z >> 64), lo = (uint64_t)z;
    if ((hi & 0x1FF) == 0x1FF) {
        uint64_t h2 = (uint64_t)(((u128)w * t[1]) >> 64);
        lo += h2;
        hi += lo < h2;
    }
    int upper = (int)(hi >> 63), shift = upper + 9;
    uint64_t m = hi >> shift;
    /* floor(q · log2 10) + 63, the division rounding −q's product up */
    int p2 = -((-(152170 + 65536) * q + 65535) / 65536) + 63 + upper - lz +
             1023;
    if (lo <= 1 && q >= -4 && (m & 3) == 1 && (m << shift) == hi)
        m &= ~UINT64_C(1); /* exactly halfway: to even */
    m += m & 1;
    m >>= 1;
    if (m >= UINT64_C(2) << 52) {
        m = UINT64_C(1) << 52;
        p2++;
    }
    uint64_t b = (uint64_t)p2 << 52 | (m & MANT_MASK);
    double d;
    memcpy(&d, &b, sizeof d);
    return d;
}

/* w·10^q (w ≠ 0) when exact integer arithmetic decides it. */
static bool parse_exact(uint64_t w, int64_t q, double *ret)
{
    if (w <= UINT64_C(1) << 53 && q >= -22 && q <= 22) {
        double d = (double)w;
        *ret = q < 0 ? d / POW10D[-q] : d * POW10D[q];
        return true;
    }
    if (q >= 0 && q <= 27) {
        *ret = round_to_double((u128)w * POW5[q], (int)q);
        return true;
    }
    if (q < 0 && q >= -27) {
        *ret = eisel_lemire(w, (int)q);
        return true;
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
