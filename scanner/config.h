/* config.h — which USB devices are scanners: a list of VID:PID:transport
 * entries such as "1d50:6150:bulk,1d50:6151:hid", as written in the
 * daemon's configuration file and on its command line.
 *
 * Pure functions; thread-safe. */
#ifndef SCAN_CONFIG_H
#define SCAN_CONFIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ctx.h"
#include "transport.h"

/* One entry: a device with this vendor and product id speaks FSP/1 over
 * this transport. */
typedef struct scan_match {
    uint16_t vid, pid;
    scan_kind kind;
} scan_match;

enum { SCAN_MATCH_MAX = 32 };

/* The default list when none is configured: 1d50:6150 bulk and
 * 1d50:6151 HID (the test devices of the specification). */
#define SCAN_DEFAULT_DEVICES "1d50:6150:bulk,1d50:6151:hid"

/* Parses one entry "vvvv:pppp:bulk|hid" (hex ids of 1..4 digits, case
 * insensitive, surrounding blanks allowed). 0 or -EINVAL with err naming
 * the problem ("\"1d50:615:usb\": transport must be bulk or hid"). */
int scan_match_parse(const char *s, scan_match *ret, geo_err *err);

/* Parses a comma- or whitespace-separated list into ret[0 .. cap) and
 * stores the count in *ret_n. An empty list, a bad entry, a duplicate
 * VID:PID or more than cap entries is -EINVAL with err naming the entry
 * ("devices[2]: ..."). ret is untouched on error. */
int scan_match_list_parse(const char *s, scan_match *ret, size_t cap,
                          size_t *ret_n, geo_err *err);

/* The entry of list[0 .. n) for vid:pid and kind, or NULL. */
const scan_match *scan_match_find(const scan_match *list, size_t n,
                                  uint16_t vid, uint16_t pid, scan_kind kind);

/* "bulk" or "hid". */
const char *scan_kind_name(scan_kind kind);

#endif
