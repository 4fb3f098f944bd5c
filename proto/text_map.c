/* text_map.c — mmap of a file's text, madvise(MADV_DONTNEED) behind the
 * reader (text_map.h). */
#include "text_map.h"

#include <errno.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

int proto_text_map_open(int fd, size_t max, proto_text_map *m, geo_err *err)
{
    memset(m, 0, sizeof *m);
    struct stat st;
    if (fstat(fd, &st) < 0)
        return geo_err_set(err, -errno, "%s", strerror(errno));
    if (!S_ISREG(st.st_mode) || st.st_size <= 0)
        return 1;
    if ((uint64_t)st.st_size > max)
        return geo_err_set(err, -ERANGE, "%llu bytes exceed the limit of %zu",
                           (unsigned long long)st.st_size, max);
    size_t len = (size_t)st.st_size;
    void *d = mmap(NULL, len, PROT_READ, MAP_PRIVATE, fd, 0);
    if (d == MAP_FAILED)
        return 1; /* e.g. a file system without mmap: read it instead */
    /* read once from start to end: read ahead, and drop behind */
    madvise(d, len, MADV_SEQUENTIAL);
    m->data = d;
    m->len = len;
    return 0;
}

void proto_text_map_behind(void *user, size_t pos)
{
    proto_text_map *m = user;
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    size_t end = pos < m->len ? pos / page * page : m->len / page * page;
    if (end <= m->released)
        return;
    /* a private mapping never written: the pages come back from the
     * file if they are read again */
    madvise((char *)m->data + m->released, end - m->released, MADV_DONTNEED);
    m->released = end;
}

void proto_text_map_close(proto_text_map *m)
{
    if (m->data)
        munmap((void *)m->data, m->len);
    memset(m, 0, sizeof *m);
}
