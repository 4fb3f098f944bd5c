/* crc32.h — CRC-32 as used by Ethernet, zlib and PNG (IEEE 802.3:
 * polynomial 0x04C11DB7, reflected, initial value and final XOR
 * 0xFFFFFFFF). The check value of the nine bytes "123456789" is
 * 0xCBF43926. FSP/1 frames and FSP/1 SCAN_DONE use it.
 *
 * Pure functions over caller memory: reentrant, thread-safe, no
 * allocation. */
#ifndef PROTO_CRC32_H
#define PROTO_CRC32_H

#include <stddef.h>
#include <stdint.h>

/* The CRC of the concatenation of the bytes already summarised by crc
 * and the len bytes at data. Start with crc = 0; the result after the
 * last piece is the CRC of the whole stream (no final step). data may be
 * NULL when len is 0. */
uint32_t proto_crc32_update(uint32_t crc, const void *data, size_t len);

/* The CRC of len bytes: proto_crc32_update(0, data, len). */
uint32_t proto_crc32(const void *data, size_t len);

#endif
