/* json_digits.h — the JSON number scanner's word arithmetic: eight ASCII
 * bytes at a time, with no branch per digit. Shared by the tokenizer
 * (json_pull.c) and the model reader's index path (model_json.c), which
 * takes a short integer inline rather than through a call. */
#ifndef PROTO_JSON_DIGITS_H
#define PROTO_JSON_DIGITS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* Eight bytes at p as a little-endian word. */
static inline uint64_t proto_load8(const unsigned char *p)
{
    uint64_t v;
    memcpy(&v, p, 8);
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
    v = __builtin_bswap64(v);
#endif
    return v;
}

/* Non-zero in each byte of v that is no ASCII digit, at least up to the
 * first such byte (a carry of the +6 moves only bytes above a byte of
 * 0xFA or more, itself no digit). */
static inline uint64_t proto_nondigits(uint64_t v)
{
    return ((v & 0xF0F0F0F0F0F0F0F0u) ^ 0x3030303030303030u) |
           (((v + 0x0606060606060606u) & 0xF0F0F0F0F0F0F0F0u) ^
            0x3030303030303030u);
}

/* The value of eight digit bytes, first byte most significant. */
static inline uint32_t proto_eight_digits_value(uint64_t v)
{
    v -= 0x3030303030303030u;
    v = v * 10 + (v >> 8);
    v = ((v & 0x000000FF000000FFu) * (100 + (UINT64_C(1000000) << 32)) +
         ((v >> 16 & 0x000000FF000000FFu) * (1 + (UINT64_C(10000) << 32)))) >>
        32;
    return (uint32_t)v;
}

/* A short integer at d + start — 1 to 7 digits, no leading zero, then a
 * byte that continues no number (no digit, '.', 'e', 'E' or byte of 0x80
 * and above): a model's indices, two numbers in three — read from one
 * word: the first byte of the word that is no digit ends it; the digits,
 * moved to the word's top with '0's below them, are its value. True with
 * its end and value; false when the word does not decide (fewer than
 * eight bytes left, a sign, anything longer), for the full scanner. */
static inline bool proto_json_short_uint(const unsigned char *d, size_t len,
                                         size_t start, size_t *ret_end,
                                         uint32_t *ret)
{
    if (len - start < 8)
        return false;
    uint64_t v = proto_load8(d + start), bad = proto_nondigits(v);
    unsigned nd = bad ? (unsigned)__builtin_ctzll(bad) / 8 : 8;
    unsigned next = nd < 8 ? (unsigned)(v >> 8 * nd) & 0xFF : 0;
    if (nd < 1 || nd >= 8 || (nd > 1 && (v & 0xFF) == '0') || next == '.' ||
        next == 'e' || next == 'E' || next >= 0x80)
        return false;
    unsigned sh = 8 * (8 - nd);
    *ret_end = start + nd;
    *ret = proto_eight_digits_value(
        v << sh | UINT64_C(0x3030303030303030) >> (64 - sh));
    return true;
}

#endif
