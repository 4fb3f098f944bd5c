/* mem_transport.h — an in-memory scan_transport for the unit tests: the
 * test plays the device by pushing bytes for the host to read and by
 * inspecting the frames the host wrote. A read with nothing to deliver
 * advances a fake clock by its timeout and returns -ETIMEDOUT, so the
 * session's timeouts run without sleeping. Single-threaded. */
#ifndef FACET_MEM_TRANSPORT_H
#define FACET_MEM_TRANSPORT_H

#include <stddef.h>
#include <stdint.h>

#include "fsp.h"
#include "transport.h"

/* One frame the host wrote (payload copied). */
typedef struct mem_frame {
    uint8_t type;
    uint16_t seq;
    uint32_t len;
    uint8_t payload[512];
} mem_frame;

/* A transport whose reads return at most chunk bytes at a time (0: no
 * limit) and advance *clock_ms on a timeout. */
scan_transport *mem_transport_new(uint64_t *clock_ms, size_t chunk);

/* Bytes for the host to read. */
void mem_transport_push(scan_transport *t, const void *bytes, size_t n);

/* Encodes one frame for the host to read; corrupt flips a payload or CRC
 * bit so that the frame fails its CRC. */
void mem_transport_push_frame(scan_transport *t, uint8_t type, uint16_t seq,
                              const void *payload, size_t len, int corrupt);

/* Frames the host wrote since creation, oldest first. */
size_t mem_transport_sent_count(const scan_transport *t);
const mem_frame *mem_transport_sent(const scan_transport *t, size_t i);

/* Counts frames of one type written since frame index from. */
size_t mem_transport_count(const scan_transport *t, uint8_t type,
                           size_t from);

/* The last frame of one type written (NULL if none). */
const mem_frame *mem_transport_last(const scan_transport *t, uint8_t type);

/* From now on every call fails with -ENODEV. */
void mem_transport_unplug(scan_transport *t);

#endif
