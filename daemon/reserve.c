/* reserve.c — the state directory's reserve file (reserve.h). */
#include "reserve.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <sys/stat.h>
#include <unistd.h>

static void reserve_path(const char *dir, const char *suffix, char *buf,
                         size_t size)
{
    snprintf(buf, size, "%s/facetd.reserve%s", dir, suffix);
}

int reserve_keep(const char *dir, size_t bytes)
{
    char path[4096], tmp[4096];
    reserve_path(dir, "", path, sizeof path);
    struct stat st;
    if (stat(path, &st) == 0 && (size_t)st.st_size >= bytes)
        return 0;
    reserve_path(dir, ".tmp", tmp, sizeof tmp);
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0)
        return -errno;
    /* allocated blocks, not a sparse file: deleting it must free them */
    int r = posix_fallocate(fd, 0, (off_t)bytes);
    if (r == 0 && fsync(fd) < 0)
        r = errno;
    close(fd);
    if (r == 0 && rename(tmp, path) < 0)
        r = errno;
    if (r != 0)
        unlink(tmp);
    return -r;
}

bool reserve_release(const char *dir)
{
    char path[4096];
    reserve_path(dir, "", path, sizeof path);
    return unlink(path) == 0;
}
