/* http_listen.c — address parsing and the listening socket (see
 * http_listen.h). */
#include "http_listen.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

static int parse_port(const char *s, unsigned short *ret)
{
    if (!*s)
        return -EINVAL;
    char *end;
    errno = 0;
    unsigned long v = strtoul(s, &end, 10);
    if (errno || *end || v > 65535 || *s == '-' || *s == '+')
        return -EINVAL;
    *ret = (unsigned short)v;
    return 0;
}

/* Fills ss from addr; *ret_len its length. */
static int parse_addr(const char *addr, struct sockaddr_storage *ss,
                      socklen_t *ret_len)
{
    char host[64];
    const char *colon;
    memset(ss, 0, sizeof *ss);
    if (addr[0] == '[') {
        const char *close = strchr(addr, ']');
        if (!close || close[1] != ':' || (size_t)(close - addr - 1) >= sizeof host)
            return -EINVAL;
        memcpy(host, addr + 1, (size_t)(close - addr - 1));
        host[close - addr - 1] = '\0';
        colon = close + 1;
        struct sockaddr_in6 *a6 = (struct sockaddr_in6 *)ss;
        a6->sin6_family = AF_INET6;
        if (inet_pton(AF_INET6, host, &a6->sin6_addr) != 1 ||
            parse_port(colon + 1, &a6->sin6_port) < 0)
            return -EINVAL;
        a6->sin6_port = htons(a6->sin6_port);
        *ret_len = sizeof *a6;
        return 0;
    }
    colon = strrchr(addr, ':');
    if (!colon || (size_t)(colon - addr) >= sizeof host)
        return -EINVAL;
    memcpy(host, addr, (size_t)(colon - addr));
    host[colon - addr] = '\0';
    unsigned short port;
    if (parse_port(colon + 1, &port) < 0)
        return -EINVAL;
    if (!*host) {
        struct sockaddr_in6 *a6 = (struct sockaddr_in6 *)ss;
        a6->sin6_family = AF_INET6;
        a6->sin6_addr = in6addr_any;
        a6->sin6_port = htons(port);
        *ret_len = sizeof *a6;
        return 0;
    }
    struct sockaddr_in *a4 = (struct sockaddr_in *)ss;
    a4->sin_family = AF_INET;
    a4->sin_port = htons(port);
    if (strcmp(host, "localhost") == 0)
        a4->sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    else if (inet_pton(AF_INET, host, &a4->sin_addr) != 1)
        return -EINVAL;
    *ret_len = sizeof *a4;
    return 0;
}

static int bad_addr(const char *addr, geo_err *err)
{
    return geo_err_set(err, -EINVAL, "Listen: '%s' is not HOST:PORT, "
                       "[IPV6]:PORT or :PORT with a numeric address", addr);
}

static bool is_loopback(const struct sockaddr_storage *ss)
{
    if (ss->ss_family == AF_INET) {
        const struct sockaddr_in *a4 = (const struct sockaddr_in *)ss;
        return (ntohl(a4->sin_addr.s_addr) >> 24) == 127;
    }
    if (ss->ss_family == AF_INET6) {
        const struct sockaddr_in6 *a6 = (const struct sockaddr_in6 *)ss;
        return IN6_IS_ADDR_LOOPBACK(&a6->sin6_addr) ||
               (IN6_IS_ADDR_V4MAPPED(&a6->sin6_addr) &&
                a6->sin6_addr.s6_addr[12] == 127);
    }
    return ss->ss_family == AF_UNIX;
}

int http_listen_check(const char *addr, bool *ret_loopback, geo_err *err)
{
    struct sockaddr_storage ss;
    socklen_t len;
    if (parse_addr(addr, &ss, &len) < 0)
        return bad_addr(addr, err);
    *ret_loopback = is_loopback(&ss);
    return 0;
}

int http_listen_open(const char *addr, int backlog, int *ret_fd, geo_err *err)
{
    struct sockaddr_storage ss;
    socklen_t len;
    if (parse_addr(addr, &ss, &len) < 0)
        return bad_addr(addr, err);
    int fd = socket(ss.ss_family, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK,
                    0);
    if (fd < 0)
        return geo_err_set(err, -errno, "socket: %s", strerror(errno));
    int one = 1, zero = 0;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (ss.ss_family == AF_INET6)
        setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &zero, sizeof zero);
    if (bind(fd, (struct sockaddr *)&ss, len) < 0 || listen(fd, backlog) < 0) {
        int e = errno;
        close(fd);
        return geo_err_set(err, -e, "Listen: %s: %s", addr, strerror(e));
    }
    *ret_fd = fd;
    return 0;
}

int http_listen_describe(int fd, char *buf, size_t size, bool *ret_loopback,
                         geo_err *err)
{
    struct sockaddr_storage ss;
    socklen_t len = sizeof ss;
    if (getsockname(fd, (struct sockaddr *)&ss, &len) < 0)
        return geo_err_set(err, -errno, "getsockname: %s", strerror(errno));
    char host[INET6_ADDRSTRLEN];
    if (ss.ss_family == AF_INET) {
        struct sockaddr_in *a4 = (struct sockaddr_in *)&ss;
        inet_ntop(AF_INET, &a4->sin_addr, host, sizeof host);
        snprintf(buf, size, "%s:%u", host, ntohs(a4->sin_port));
    } else if (ss.ss_family == AF_INET6) {
        struct sockaddr_in6 *a6 = (struct sockaddr_in6 *)&ss;
        inet_ntop(AF_INET6, &a6->sin6_addr, host, sizeof host);
        snprintf(buf, size, "[%s]:%u", host, ntohs(a6->sin6_port));
    } else if (ss.ss_family == AF_UNIX) {
        snprintf(buf, size, "unix socket");
    } else {
        return geo_err_set(err, -EAFNOSUPPORT, "listening socket of address "
                           "family %d", ss.ss_family);
    }
    *ret_loopback = is_loopback(&ss);
    return 0;
}
