/* model_io.c — the model_io.h entry points: limits, format names and
 * extensions, dispatch to the codecs (model_json.c, model_poly.c, ...),
 * whole-file reading under the size limit and atomic file writing
 * (temporary file in the target's directory, fsync, rename), so a reader
 * of the target sees the old file or the new one, never a partial one. */
#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "model_codec.h"
#include "text_map.h"

void proto_limits_default(proto_limits *lim)
{
    lim->max_vertices = 2000000;
    lim->max_facets = 4000000;
    lim->max_corners = 16000000;
    lim->max_bytes = (size_t)512 << 20;
    lim->implicit_planes = false;
    lim->map_file = false;
}

typedef geo_poly *(*reader_fn)(const void *data, size_t len,
                               const proto_limits *lim,
                               proto_read_report *rep, geo_err *err);
typedef int (*writer_fn)(const geo_poly *p, proto_buf *buf, geo_err *err);

static int stl_binary_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    return proto_stl_write(p, false, b, err);
}

static int stl_ascii_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    return proto_stl_write(p, true, b, err);
}

static int ply_binary_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    return proto_ply_write(p, false, b, err);
}

static int ply_ascii_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    return proto_ply_write(p, true, b, err);
}

/* Every format once: its names, its media type and its codec. A NULL
 * extension is a variant reached by name only; a NULL reader, a format
 * that is written only. */
static const struct {
    proto_format fmt;
    const char *name, *ext, *mime;
    reader_fn read;
    writer_fn write;
} formats[] = {
    {PROTO_FMT_JSON, "json", "json", "application/json", proto_json_read,
     proto_json_write},
    {PROTO_FMT_POLY, "poly", "poly", "text/plain", proto_polytxt_read,
     proto_polytxt_write},
    {PROTO_FMT_OBJ, "obj", "obj", "model/obj", proto_obj_read,
     proto_obj_write},
    {PROTO_FMT_STL, "stl", "stl", "model/stl", proto_stl_read,
     stl_binary_write},
    {PROTO_FMT_STL_ASCII, "stl-ascii", NULL, "model/stl", proto_stl_read,
     stl_ascii_write},
    {PROTO_FMT_PLY, "ply", "ply", "application/x-ply", proto_ply_read,
     ply_binary_write},
    {PROTO_FMT_PLY_ASCII, "ply-ascii", NULL, "application/x-ply",
     proto_ply_read, ply_ascii_write},
    {PROTO_FMT_ASE, "ase", "ase", "text/plain", NULL, proto_ase_write},
    {PROTO_FMT_FMB1, "fmb1", "fmb", "application/octet-stream",
     proto_fmb1_read, proto_fmb1_write},
    {PROTO_FMT_OFF, "off", "off", "text/plain", proto_off_read,
     proto_off_write},
    {PROTO_FMT_ASC, "asc", "asc", "text/plain", proto_asc_read,
     proto_asc_write},
};
enum { NFORMATS = sizeof formats / sizeof formats[0] };

/* The table row of fmt, or -1. */
static int format_index(proto_format fmt)
{
    for (int i = 0; i < NFORMATS; i++)
        if (formats[i].fmt == fmt)
            return i;
    return -1;
}

/* lim, or the defaults filled into *dl when lim is NULL. */
static const proto_limits *limits_or_default(const proto_limits *lim,
                                             proto_limits *dl)
{
    if (lim)
        return lim;
    proto_limits_default(dl);
    return dl;
}

proto_format proto_format_at(size_t i)
{
    return i < NFORMATS ? formats[i].fmt : PROTO_FMT_UNKNOWN;
}

void proto_format_list(char *buf, size_t size)
{
    size_t len = 0;
    if (size)
        buf[0] = 0;
    for (int i = 0; i < NFORMATS && len < size; i++) {
        int w = snprintf(buf + len, size - len, "%s%s",
                         i == 0 ? "" : i + 1 == NFORMATS ? " or " : ", ",
                         formats[i].name);
        if (w < 0)
            break;
        len += (size_t)w;
    }
}

proto_format proto_format_from_path(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash + 1 : path, '.');
    if (!dot)
        return PROTO_FMT_UNKNOWN;
    for (int i = 0; i < NFORMATS; i++)
        if (formats[i].ext && strcasecmp(dot + 1, formats[i].ext) == 0)
            return formats[i].fmt;
    if (strcasecmp(dot + 1, "fmb1") == 0)
        return PROTO_FMT_FMB1;
    return PROTO_FMT_UNKNOWN;
}

proto_format proto_format_from_name(const char *name)
{
    for (int i = 0; i < NFORMATS; i++)
        if (strcasecmp(name, formats[i].name) == 0)
            return formats[i].fmt;
    if (strcasecmp(name, "fmb") == 0)
        return PROTO_FMT_FMB1;
    return PROTO_FMT_UNKNOWN;
}

const char *proto_format_name(proto_format fmt)
{
    int i = format_index(fmt);
    return i < 0 ? "unknown" : formats[i].name;
}

const char *proto_format_mime(proto_format fmt)
{
    int i = format_index(fmt);
    return i < 0 ? "application/octet-stream" : formats[i].mime;
}

geo_poly *proto_model_read_mem_ex(const void *data, size_t len,
                                  proto_format fmt, const proto_limits *lim,
                                  proto_read_report *ret_report, geo_err *err)
{
    proto_limits dl;
    lim = limits_or_default(lim, &dl);
    if (len > lim->max_bytes) {
        geo_err_set(err, -ERANGE, "%zu bytes exceed the limit of %zu", len,
                    lim->max_bytes);
        return NULL;
    }
    if (!data && len) {
        geo_err_set(err, -EINVAL, "no data");
        return NULL;
    }
    if (!data)
        data = "";
    proto_read_report rep;
    memset(&rep, 0, sizeof rep);
    geo_poly *p = NULL;
    int i = format_index(fmt);
    if (i < 0)
        geo_err_set(err, -EINVAL, "unknown model format");
    else if (!formats[i].read) {
        char upper[16];
        size_t k = 0;
        for (; formats[i].name[k] && k + 1 < sizeof upper; k++)
            upper[k] = (char)toupper((unsigned char)formats[i].name[k]);
        upper[k] = 0;
        geo_err_set(err, -EINVAL, "%s files can be written, not read", upper);
    } else
        p = formats[i].read(data, len, lim, &rep, err);
    if (p && ret_report)
        *ret_report = rep;
    return p;
}

geo_poly *proto_model_read_mem(const void *data, size_t len, proto_format fmt,
                               const proto_limits *lim, geo_err *err)
{
    return proto_model_read_mem_ex(data, len, fmt, lim, NULL, err);
}

int proto_read_fd_all(int fd, size_t max, char **ret, size_t *ret_len,
                      geo_err *err)
{
    struct stat st;
    if (fstat(fd, &st) < 0)
        return geo_err_set(err, -errno, "%s", strerror(errno));
    if (S_ISDIR(st.st_mode))
        return geo_err_set(err, -EISDIR, "is a directory");
    size_t cap = 65536;
    if (S_ISREG(st.st_mode)) {
        if ((uint64_t)st.st_size > max)
            return geo_err_set(err, -ERANGE,
                               "%llu bytes exceed the limit of %zu",
                               (unsigned long long)st.st_size, max);
        cap = (size_t)st.st_size + 1;
    }
    char *buf = malloc(cap);
    if (!buf)
        return geo_err_set(err, -ENOMEM, "out of memory");
    size_t len = 0;
    for (;;) {
        if (len == cap) {
            if (cap > max) {
                free(buf);
                return geo_err_set(err, -ERANGE,
                                   "more than %zu bytes (the limit)", max);
            }
            size_t ncap = cap * 2;
            char *nb = realloc(buf, ncap);
            if (!nb) {
                free(buf);
                return geo_err_set(err, -ENOMEM, "out of memory");
            }
            buf = nb;
            cap = ncap;
        }
        ssize_t n = read(fd, buf + len, cap - len);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            int e = errno;
            free(buf);
            return geo_err_set(err, -e, "%s", strerror(e));
        }
        if (n == 0)
            break;
        len += (size_t)n;
    }
    if (len > max) {
        free(buf);
        return geo_err_set(err, -ERANGE, "more than %zu bytes (the limit)",
                           max);
    }
    *ret = buf;
    *ret_len = len;
    return 0;
}

/* Fails for a path whose name tells no format: "PATH: cannot tell the
 * format from the name (known extensions: .json .poly ...)". */
static int unknown_extension(const char *path, geo_err *err)
{
    char list[128] = "";
    size_t len = 0;
    for (int i = 0; i < NFORMATS; i++) {
        if (!formats[i].ext || len >= sizeof list)
            continue;
        int w = snprintf(list + len, sizeof list - len, "%s.%s",
                         len ? " " : "", formats[i].ext);
        if (w > 0)
            len += (size_t)w;
    }
    return geo_err_set(err, -EINVAL, "%s: cannot tell the format from the "
                       "name (known extensions: %s)", path, list);
}

geo_poly *proto_model_read_file_ex(const char *path, proto_format fmt,
                                   const proto_limits *lim,
                                   proto_read_report *ret_report,
                                   geo_err *err)
{
    proto_limits dl;
    lim = limits_or_default(lim, &dl);
    if (fmt == PROTO_FMT_UNKNOWN) {
        fmt = proto_format_from_path(path);
        if (fmt == PROTO_FMT_UNKNOWN) {
            unknown_extension(path, err);
            return NULL;
        }
    }
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        geo_err_set(err, -errno, "%s: %s", path, strerror(errno));
        return NULL;
    }
    proto_text_map tm;
    int mr = lim->map_file && fmt == PROTO_FMT_JSON
                 ? proto_text_map_open(fd, lim->max_bytes, &tm, err)
                 : 1;
    if (mr <= 0) {
        close(fd);
        geo_poly *p = NULL;
        if (mr == 0) {
            proto_read_report rep;
            memset(&rep, 0, sizeof rep);
            proto_jpull j;
            proto_jpull_init(&j, tm.data, tm.len);
            j.behind = proto_text_map_behind;
            j.behind_user = &tm;
            p = proto_json_read_pull(&j, lim, &rep, err);
            proto_jpull_clear(&j);
            proto_text_map_close(&tm);
            if (p && ret_report)
                *ret_report = rep;
        }
        if (!p)
            geo_err_prefix(err, path);
        return p;
    }
    char *data = NULL;
    size_t len = 0;
    int r = proto_read_fd_all(fd, lim->max_bytes, &data, &len, err);
    close(fd);
    geo_poly *p = NULL;
    if (r == 0)
        p = proto_model_read_mem_ex(data, len, fmt, lim, ret_report, err);
    free(data);
    if (!p)
        geo_err_prefix(err, path);
    return p;
}

geo_poly *proto_model_read_file(const char *path, proto_format fmt,
                                const proto_limits *lim, geo_err *err)
{
    return proto_model_read_file_ex(path, fmt, lim, NULL, err);
}

/* What every writer relies on: finite numbers and valid indices, so that
 * no writer produces a file that its reader would reject. */
static int check_writable(const geo_poly *p, geo_err *err)
{
    for (uint32_t i = 0; i < p->nverts; i++)
        for (int k = 0; k < 3; k++)
            if (!isfinite(p->verts[i][k]))
                return geo_err_set(err, -EINVAL,
                                   "vertices[%u][%d]: not a finite number", i,
                                   k);
    for (uint32_t f = 0; f < p->nfacets; f++)
        for (int k = 0; k < 4; k++)
            if (!isfinite(p->planes[f][k]))
                return geo_err_set(err, -EINVAL,
                                   "facets[%u].plane[%d]: not a finite number",
                                   f, k);
    return geo_poly_validate_indices(p, err);
}

int proto_model_write_mem(const geo_poly *p, proto_format fmt, char **ret_buf,
                          size_t *ret_len, geo_err *err)
{
    int r = check_writable(p, err);
    if (r < 0)
        return r;
    proto_buf b = {0};
    int i = format_index(fmt);
    r = i < 0 ? geo_err_set(err, -EINVAL, "unknown model format")
              : formats[i].write(p, &b, err);
    if (r == 0 && b.failed)
        r = geo_err_set(err, -ENOMEM, "out of memory");
    if (r < 0) {
        free(b.data);
        return r;
    }
    if (!b.data) {
        b.data = malloc(1);
        if (!b.data)
            return geo_err_set(err, -ENOMEM, "out of memory");
    }
    *ret_buf = b.data;
    *ret_len = b.len;
    return 0;
}

static int write_all(int fd, const char *data, size_t len)
{
    while (len) {
        ssize_t n = write(fd, data, len);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return -errno;
        }
        data += n;
        len -= (size_t)n;
    }
    return 0;
}

/* Writes data straight into an existing path that is not a regular file
 * (a device, a FIFO, /dev/stdout): renaming a file over it would replace
 * the device node itself. */
static int write_special(const char *path, const struct stat *st,
                         const char *data, size_t len, geo_err *err)
{
    if (S_ISDIR(st->st_mode))
        return geo_err_set(err, -EISDIR, "%s: %s", path, strerror(EISDIR));
    int fd = open(path, O_WRONLY | O_CLOEXEC);
    if (fd < 0)
        return geo_err_set(err, -errno, "%s: %s", path, strerror(errno));
    int r = write_all(fd, data, len);
    if (close(fd) < 0 && r == 0)
        r = -errno;
    if (r < 0)
        geo_err_set(err, r, "%s: %s", path, strerror(-r));
    return r;
}

/* Writes data to path through a temporary file beside it. A new file
 * gets mode 0644, an existing one keeps its mode. */
static int write_atomic(const char *path, const char *data, size_t len,
                        geo_err *err)
{
    struct stat target;
    if (stat(path, &target) == 0 && !S_ISREG(target.st_mode))
        return write_special(path, &target, data, len, err);
    size_t pl = strlen(path);
    char *tmp = malloc(pl + 16);
    if (!tmp)
        return geo_err_set(err, -ENOMEM, "out of memory");
    memcpy(tmp, path, pl);
    memcpy(tmp + pl, ".tmp.XXXXXX", 12);
    int fd = mkostemp(tmp, O_CLOEXEC);
    if (fd < 0) {
        int e = errno;
        free(tmp);
        return geo_err_set(err, -e, "%s: %s", path, strerror(e));
    }
    struct stat st;
    mode_t mode = stat(path, &st) == 0 ? (st.st_mode & 07777) : 0644;
    int r = fchmod(fd, mode) < 0 ? -errno : 0;
    if (r == 0)
        r = write_all(fd, data, len);
    if (r == 0 && fsync(fd) < 0)
        r = -errno;
    if (close(fd) < 0 && r == 0)
        r = -errno;
    if (r == 0 && rename(tmp, path) < 0)
        r = -errno;
    if (r < 0) {
        unlink(tmp);
        geo_err_set(err, r, "%s: %s", path, strerror(-r));
    }
    free(tmp);
    return r;
}

int proto_model_write_file(const geo_poly *p, const char *path,
                           proto_format fmt, geo_err *err)
{
    if (fmt == PROTO_FMT_UNKNOWN) {
        fmt = proto_format_from_path(path);
        if (fmt == PROTO_FMT_UNKNOWN)
            return unknown_extension(path, err);
    }
    char *data;
    size_t len;
    int r = proto_model_write_mem(p, fmt, &data, &len, err);
    if (r < 0) {
        geo_err_prefix(err, path);
        return r;
    }
    r = write_atomic(path, data, len, err);
    free(data);
    return r;
}

/* Prefixes a facet-model/1 error with the place of the model in a larger
 * document: "model.facets[3]: ..." for a message that names a key,
 * "model: ..." otherwise. */
static void prefix_json_path(geo_err *err, const char *prefix)
{
    if (!err || !prefix || !*prefix)
        return;
    static const char *const keys[] = {"format", "units", "vertices",
                                       "facets"};
    for (size_t i = 0; i < sizeof keys / sizeof keys[0]; i++) {
        size_t n = strlen(keys[i]);
        char c = err->msg[n];
        if (strncmp(err->msg, keys[i], n) == 0 &&
            (c == '[' || c == '.' || c == ':')) {
            char tmp[sizeof err->msg];
            memcpy(tmp, err->msg, sizeof tmp);
            geo_err_set(err, 0, "%s.%s", prefix, tmp);
            return;
        }
    }
    geo_err_prefix(err, prefix);
}

geo_poly *proto_model_from_json_ex(const json_t *root, const proto_limits *lim,
                                   const char *path_prefix,
                                   proto_read_report *ret_report,
                                   geo_err *err)
{
    proto_limits dl;
    lim = limits_or_default(lim, &dl);
    proto_read_report rep;
    memset(&rep, 0, sizeof rep);
    geo_poly *p = proto_json_from_value(root, lim, &rep, err);
    if (!p)
        prefix_json_path(err, path_prefix);
    else if (ret_report)
        *ret_report = rep;
    return p;
}

geo_poly *proto_model_from_json(const json_t *root, const proto_limits *lim,
                                const char *path_prefix, geo_err *err)
{
    return proto_model_from_json_ex(root, lim, path_prefix, NULL, err);
}

geo_poly *proto_model_from_jpull(proto_jpull *j, proto_jtok first,
                                 const proto_limits *lim,
                                 const char *path_prefix,
                                 proto_read_report *ret_report,
                                 bool *ret_syntax, geo_err *err)
{
    proto_limits dl;
    lim = limits_or_default(lim, &dl);
    proto_read_report rep;
    memset(&rep, 0, sizeof rep);
    bool syntax;
    geo_poly *p = proto_json_from_pull(j, first, lim, &rep, &syntax, err);
    if (!p && !syntax)
        prefix_json_path(err, path_prefix);
    else if (p && ret_report)
        *ret_report = rep;
    if (ret_syntax)
        *ret_syntax = syntax;
    return p;
}
