/* reserve.h — a reserve of disk space in the state directory, so that
 * facetd can start on a disk that filled up while it was stopped: opening
 * the store (its write-ahead log, the recovery of interrupted jobs) needs
 * a little space, and the reserve file is given up to provide it. It is
 * made again at a start-up that has room for it. */
#ifndef FACETD_RESERVE_H
#define FACETD_RESERVE_H

#include <stdbool.h>
#include <stddef.h>

#define RESERVE_BYTES (2u << 20)

/* Makes dir/facetd.reserve of bytes allocated bytes unless it is there;
 * 0 or a negative errno (no room: the caller carries on without). */
int reserve_keep(const char *dir, size_t bytes);

/* Deletes the reserve; true when there was one to give up. */
bool reserve_release(const char *dir);

#endif
