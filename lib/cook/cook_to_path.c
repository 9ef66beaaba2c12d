/* cook_to_path.c: cooking to a file atomically: a temporary file beside the destination, fsync, rename. */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "common/alloc.h"
#include "common/error.h"
#include "cook/cook_internal.h"

static const char temp_suffix[] = ".tmp-XXXXXX";

/* "dir/name" -> "dir/.name.tmp-XXXXXX": the same folder, so rename() stays on one file system. */
static char *temp_template(const cbvh_allocator *a, const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t dir_len = slash ? (size_t)(slash - path) + 1 : 0;
    size_t len = strlen(path);
    char *t = cbvh_alloc(a, len + 1 + sizeof temp_suffix, 1);
    if (!t)
        return NULL;
    memcpy(t, path, dir_len);
    t[dir_len] = '.';
    memcpy(t + dir_len + 1, path + dir_len, len - dir_len);
    memcpy(t + len + 1, temp_suffix, sizeof temp_suffix);
    return t;
}

static int write_all(int fd, const uint8_t *p, size_t size)
{
    while (size > 0) {
        ssize_t n = write(fd, p, size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return -1;
        p += n;
        size -= (size_t)n;
    }
    return 0;
}

/* Makes the rename itself durable; best effort (some file systems refuse fsync on folders). */
static void sync_folder(char *temp, const char *path)
{
    const char *slash = strrchr(path, '/');
    int fd;
    if (!slash) {
        fd = open(".", O_RDONLY | O_DIRECTORY);
    } else {
        /* The template starts with the same folder; cut it at the same length. */
        size_t dir_len = (size_t)(slash - path) + 1;
        char saved = temp[dir_len];
        temp[dir_len] = '\0';
        fd = open(temp, O_RDONLY | O_DIRECTORY);
        temp[dir_len] = saved;
    }
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
}

static cbvh_result write_atomically(const char *path, const uint8_t *data, size_t size, const cbvh_allocator *a,
                                    cbvh_error *err)
{
    char *temp = temp_template(a, path);
    if (!temp)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory for a temporary file name");
    int fd = mkstemp(temp);
    if (fd < 0) {
        cbvh_result r = cbvh_fail(err, CBVH_ERROR_IO, "cannot create a temporary file beside '%s': %s", path,
                                  strerror(errno));
        cbvh_free(a, temp);
        return r;
    }
    const char *failed = NULL;
    int saved_errno = 0;
    /* mkstemp makes the file private (0600); a cooked file is an ordinary asset. */
    if (fchmod(fd, 0644) != 0)
        failed = "set the mode of";
    else if (write_all(fd, data, size) != 0)
        failed = "write";
    else if (fsync(fd) != 0)
        failed = "flush";
    saved_errno = errno;
    if (close(fd) != 0 && !failed) {
        failed = "close";
        saved_errno = errno;
    }
    if (!failed && rename(temp, path) != 0) {
        failed = "rename into place";
        saved_errno = errno;
    }
    cbvh_result r = CBVH_OK;
    if (failed) {
        unlink(temp);
        r = cbvh_fail(err, CBVH_ERROR_IO, "cannot %s the temporary file '%s' for '%s': %s", failed, temp, path,
                      strerror(saved_errno));
    } else {
        sync_folder(temp, path);
    }
    cbvh_free(a, temp);
    return r;
}

CBVH_API cbvh_result cbvh_cook_to_path(const cbvh_mesh *mesh, const cbvh_cook_options *options,
                                       const cbvh_allocator *allocator, const char *path,
                                       cbvh_cook_stats *stats, cbvh_error *err)
{
    if (!path || !*path)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT, "path is NULL or empty");
    void *data = NULL;
    size_t size = 0;
    cbvh_cook_stats st;
    memset(&st, 0, sizeof st);
    cbvh_result r = cbvh_cook(mesh, options, allocator, &data, &size, &st, err);
    if (r == CBVH_OK) {
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        cbvh_allocator a = cbvh_allocator_resolve(allocator);
        r = write_atomically(path, data, size, &a, err);
        cbvh_free(&a, data);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        st.seconds[CBVH_PHASE_WRITE] += (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    }
    if (stats)
        *stats = st;
    return r;
}
