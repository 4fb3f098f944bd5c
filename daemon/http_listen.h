/* http_listen.h — the listening socket of the HTTP server: parsing the
 * Listen= address, opening the socket, and describing a socket handed in
 * by systemd (socket activation), including whether it only accepts
 * loopback connections (which decides whether an API token is required).
 *
 * Address forms: "HOST:PORT" with an IPv4 literal, "[IPV6]:PORT",
 * ":PORT" (every address, IPv6 and IPv4), "localhost:PORT". Host names
 * are not resolved: a daemon should not depend on DNS to start.
 *
 * Functions are thread-safe; they return 0 or a negative errno with err. */
#ifndef FACETD_HTTP_LISTEN_H
#define FACETD_HTTP_LISTEN_H

#include <stdbool.h>
#include <stddef.h>

#include "ctx.h"

/* Parses addr without opening anything; *ret_loopback tells whether it
 * only accepts loopback connections (as http_listen_describe would). 0 or
 * -EINVAL with err. */
int http_listen_check(const char *addr, bool *ret_loopback, geo_err *err);

/* Opens a TCP socket bound to addr and listening (backlog), close-on-exec
 * and non-blocking, with SO_REUSEADDR. *ret_fd belongs to the caller. */
int http_listen_open(const char *addr, int backlog, int *ret_fd, geo_err *err);

/* Writes the socket's local address ("127.0.0.1:8080", "[::]:8080") into
 * buf and sets *ret_loopback when it only accepts loopback connections
 * (127.0.0.0/8, ::1, ::ffff:127.0.0.0/104). 0 or -errno. */
int http_listen_describe(int fd, char *buf, size_t size, bool *ret_loopback,
                         geo_err *err);

#endif
