/* posix.c: the operating-system calls of os.h on POSIX systems (mmap, pthreads, rename), above the
 * allocator. */
#define _GNU_SOURCE /* MAP_POPULATE and O_TMPFILE where the system has them (Linux) */
#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "common/alloc.h"
#include "common/error.h"
#include "common/os.h"

/* The whole file into a 64-byte aligned buffer from `a`. */
static cbvh_result read_all(int fd, const char *path, const cbvh_allocator *a, struct cbvh_os_file_bytes *out,
                            cbvh_error *err)
{
    uint8_t *buffer = cbvh_alloc_walked(a, out->size, 64);
    if (!buffer)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "%s: cannot allocate %zu bytes to read it into", path,
                         out->size);
    size_t done = 0;
    while (done < out->size) {
        ssize_t n = read(fd, buffer + done, out->size - done);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            cbvh_result r = cbvh_fail(err, CBVH_ERROR_IO, "%s: read failed at byte %zu: %s", path, done,
                                      n < 0 ? strerror(errno) : "unexpected end of file");
            cbvh_free(a, buffer);
            return r;
        }
        done += (size_t)n;
    }
    out->bytes = buffer;
    return CBVH_OK;
}

/* On Linux, a file of at least 2 MiB mapped read-only at an address on a 2 MiB boundary, with the huge-page
 * advice given before any page is touched, then every page mapped at once (as MAP_POPULATE does:
 * validation reads every byte); else MAP_FAILED, and the caller maps it plainly. Where the kernel's page
 * cache holds the file in 2 MiB folios (a file read cold with the advice, on a file system with large
 * folios such as ext4), whole 2 MiB pages of the file are then mapped at once, as
 * cbvh_os_advise_large_pages gives a copy: a large mesh's walks miss the address translation cache less
 * (docs/PERFORMANCE.md). A file cached in small pages (just written) maps as before. */
static void *map_on_large_pages(int fd, size_t size)
{
#if defined(MADV_HUGEPAGE) && defined(MAP_FIXED)
    const size_t page = (size_t)2 << 20;
    if (size < page || size > SIZE_MAX - page)
        return MAP_FAILED;
    /* room for the file and a boundary, reserved without access; the file over it from the boundary on,
     * and the rest of the room given back */
    uint8_t *room = mmap(NULL, size + page, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (room == MAP_FAILED)
        return MAP_FAILED;
    uint8_t *at = (uint8_t *)(((uintptr_t)room + page - 1u) & ~(uintptr_t)(page - 1u));
    if (mmap(at, size, PROT_READ, MAP_PRIVATE | MAP_FIXED, fd, 0) == MAP_FAILED) {
        munmap(room, size + page);
        return MAP_FAILED;
    }
    const long system_page = sysconf(_SC_PAGESIZE);
    const size_t step = system_page > 0 ? (size_t)system_page : 4096u;
    uint8_t *end = at + (size + step - 1u) / step * step; /* past the mapping's last page */
    if (at > room)
        munmap(room, (size_t)(at - room));
    if (room + size + page > end)
        munmap(end, (size_t)(room + size + page - end));
    (void)madvise(at, size, MADV_HUGEPAGE); /* advice: a refusal changes nothing */
#ifdef MADV_POPULATE_READ
    (void)madvise(at, size, MADV_POPULATE_READ); /* a kernel without it faults the pages in at validation */
#endif
    return at;
#else
    (void)fd;
    (void)size;
    return MAP_FAILED;
#endif
}

static cbvh_result map_or_read(int fd, const char *path, int map, const cbvh_allocator *a,
                               struct cbvh_os_file_bytes *out, cbvh_error *err)
{
    struct stat st;
    if (fstat(fd, &st) != 0)
        return cbvh_fail(err, CBVH_ERROR_IO, "%s: cannot stat: %s", path, strerror(errno));
    if (!S_ISREG(st.st_mode))
        return cbvh_fail(err, CBVH_ERROR_IO, "%s: not a regular file", path);
    if ((uintmax_t)st.st_size > SIZE_MAX)
        return cbvh_fail(err, CBVH_ERROR_IO, "%s: %jd bytes do not fit in the address space", path,
                         (intmax_t)st.st_size);
    out->size = (size_t)st.st_size;
    if (out->size == 0)
        return CBVH_OK; /* nothing to map; the header check reports the empty file */
    if (map) {
        /* Validation reads every byte at once: mapping all pages up front costs less than a fault per
         * page. */
#ifdef MAP_POPULATE
        const int flags = MAP_PRIVATE | MAP_POPULATE;
#else
        const int flags = MAP_PRIVATE;
#endif
        void *p = map_on_large_pages(fd, out->size);
        if (p == MAP_FAILED)
            p = mmap(NULL, out->size, PROT_READ, flags, fd, 0);
        if (p != MAP_FAILED) {
            out->bytes = p;
            out->mapped = 1;
            return CBVH_OK;
        }
    }
    return read_all(fd, path, a, out, err);
}

cbvh_result cbvh_os_read_file(const char *path, int map, const cbvh_allocator *a,
                              struct cbvh_os_file_bytes *out, cbvh_error *err)
{
    memset(out, 0, sizeof *out);
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return cbvh_fail(err, CBVH_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
    cbvh_result r = map_or_read(fd, path, map, a, out, err);
    close(fd);
    return r;
}

void cbvh_os_unmap(const uint8_t *bytes, size_t size)
{
    munmap((void *)bytes, size);
}

static const char temp_suffix[] = ".tmp-XXXXXX";

/* The longest file name the temporary name may have: a name the system takes (NAME_MAX, 255 on the common
 * file systems) must not fail only because its temporary name is longer. */
#define TEMP_NAME_MAX 255

/* "dir/name" -> "dir/.name.tmp-XXXXXX": the same folder, so rename() stays on one file system. The name part
 * is cut so the temporary name fits whenever the output's name does. */
static char *temp_template(const cbvh_allocator *a, const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t dir_len = slash ? (size_t)(slash - path) + 1 : 0;
    size_t len = strlen(path);
    size_t name_len = len - dir_len;
    const size_t room = TEMP_NAME_MAX - 1 - (sizeof temp_suffix - 1);
    if (name_len > room)
        name_len = room;
    char *t = cbvh_alloc(a, dir_len + 1 + name_len + sizeof temp_suffix, 1);
    if (!t)
        return NULL;
    memcpy(t, path, dir_len);
    t[dir_len] = '.';
    memcpy(t + dir_len + 1, path + dir_len, name_len);
    memcpy(t + dir_len + 1 + name_len, temp_suffix, sizeof temp_suffix);
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

/* What may stand at `path` before it is replaced: nothing, a regular file (whose mode the new file keeps, in
 * *mode) or a symbolic link (replaced itself; what it points to stays as it was). Anything else (a device,
 * a FIFO, a folder, a socket) is refused: writing it is not replacing a file. */
static cbvh_result check_target(const char *path, mode_t *mode, int *keep_mode, cbvh_error *err)
{
    struct stat st;
    *keep_mode = 0;
    if (lstat(path, &st) != 0) {
        if (errno == ENOENT)
            return CBVH_OK;
        return cbvh_fail(err, CBVH_ERROR_IO, "cannot inspect the output path (%s): %s", strerror(errno),
                         path);
    }
    if (S_ISLNK(st.st_mode))
        return CBVH_OK;
    if (!S_ISREG(st.st_mode)) {
        const char *what = S_ISDIR(st.st_mode)    ? "a folder"
                           : S_ISCHR(st.st_mode)  ? "a character device"
                           : S_ISBLK(st.st_mode)  ? "a block device"
                           : S_ISFIFO(st.st_mode) ? "a FIFO"
                           : S_ISSOCK(st.st_mode) ? "a socket"
                                                  : "not a regular file";
        return cbvh_fail(
            err, CBVH_ERROR_IO,
            "the output is %s: a cooked file replaces only a regular file (or a symbolic link): %s", what,
            path);
    }
    *mode = st.st_mode & 07777;
    *keep_mode = 1;
    return CBVH_OK;
}

/* Blocks (or restores) the signals that end a process at a terminal's or a job system's request, so a
 * named temporary file is always renamed or removed before the process can die of them. */
static void hold_signals(sigset_t *saved)
{
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    sigaddset(&set, SIGQUIT);
    pthread_sigmask(SIG_BLOCK, &set, saved);
}

static void release_signals(const sigset_t *saved)
{
    pthread_sigmask(SIG_SETMASK, saved, NULL);
}

/* Replaces the last six characters of `temp` (mkstemp's XXXXXX) by a name that differs per process, time
 * and attempt; linkat refuses a name that exists, so a collision only costs another attempt. */
static void fill_temp_name(char *temp, unsigned attempt)
{
    static const char digits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    uint64_t x = (uint64_t)getpid() * 0x9E3779B97F4A7C15u ^ (uint64_t)ts.tv_nsec * 0xBF58476D1CE4E5B9u ^
                 (uint64_t)ts.tv_sec ^ (uint64_t)attempt * 0x94D049BB133111EBu;
    char *p = temp + strlen(temp) - 6;
    for (int k = 0; k < 6; k++, x /= 36)
        p[k] = digits[x % 36];
}

/* Creates the temporary file: unnamed (O_TMPFILE) where the system can, so that nothing is left behind
 * whatever ends the process; else named from `temp` (mkstemp's pattern) with the signals held, which
 * the caller then keeps held until the name is gone. New files get 0666 less the umask. */
static int create_temp(char *temp, const char *path, int *named, sigset_t *saved)
{
    *named = 0;
#ifdef O_TMPFILE
    {
        const char *slash = strrchr(path, '/');
        int fd;
        if (!slash) {
            fd = open(".", O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
        } else {
            size_t dir_len = (size_t)(slash - path) + 1;
            char saved_char = temp[dir_len];
            temp[dir_len] = '\0';
            fd = open(temp, O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
            temp[dir_len] = saved_char;
        }
        if (fd >= 0)
            return fd;
    }
#endif
    (void)path;
    hold_signals(saved);
    *named = 1;
    /* mkstemp's 0600 becomes 0666 less the umask, read without changing it (umask() is process-wide). */
    int fd = mkstemp(temp);
    if (fd >= 0) {
        mode_t mask = umask(0);
        umask(mask);
        if (fchmod(fd, 0666 & ~mask) != 0) {
            int e = errno;
            close(fd);
            unlink(temp);
            release_signals(saved);
            *named = 0;
            errno = e;
            return -1;
        }
    } else {
        release_signals(saved);
        *named = 0;
    }
    return fd;
}

cbvh_result cbvh_os_write_file_replacing(const char *path, const uint8_t *data, size_t size,
                                         const cbvh_allocator *a, cbvh_error *err)
{
    mode_t mode = 0;
    int keep_mode;
    cbvh_result r = check_target(path, &mode, &keep_mode, err);
    if (r != CBVH_OK)
        return r;
    char *temp = temp_template(a, path);
    if (!temp)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory for a temporary file name");
    sigset_t saved;
    int named;
    int fd = create_temp(temp, path, &named, &saved);
    if (fd < 0) {
        r = cbvh_fail(err, CBVH_ERROR_IO, "cannot create a temporary file (%s) beside %s", strerror(errno),
                      path);
        cbvh_free(a, temp);
        return r;
    }
    const char *failed = NULL;
    int saved_errno = 0;
    if (keep_mode && fchmod(fd, mode) != 0)
        failed = "set the mode of";
    else if (write_all(fd, data, size) != 0)
        failed = "write";
    else if (fsync(fd) != 0)
        failed = "flush";
    saved_errno = errno;
    if (!failed && !named) {
        /* Give the unnamed file its temporary name only now, for the instant before the rename. */
        char proc[64];
        snprintf(proc, sizeof proc, "/proc/self/fd/%d", fd);
        hold_signals(&saved);
        named = 1;
        int tries = 0;
        for (;;) {
            fill_temp_name(temp, (unsigned)tries);
            if (linkat(AT_FDCWD, proc, AT_FDCWD, temp, AT_SYMLINK_FOLLOW) == 0)
                break;
            if (errno != EEXIST || ++tries == 100) {
                failed = "name";
                saved_errno = errno;
                break;
            }
        }
    }
    if (close(fd) != 0 && !failed) {
        failed = "close";
        saved_errno = errno;
    }
    if (!failed && rename(temp, path) != 0) {
        failed = "rename into place";
        saved_errno = errno;
    }
    if (failed) {
        if (named)
            unlink(temp);
        /* an unnamed (O_TMPFILE) file has no name to show: its template's XXXXXX would only mislead */
        if (named)
            r = cbvh_fail(err, CBVH_ERROR_IO, "cannot %s the temporary file (%s): %s", failed,
                          strerror(saved_errno), temp);
        else
            r = cbvh_fail(err, CBVH_ERROR_IO, "cannot %s the (unnamed) temporary file (%s) for %s", failed,
                          strerror(saved_errno), path);
    } else {
        sync_folder(temp, path);
    }
    if (named)
        release_signals(&saved);
    cbvh_free(a, temp);
    return r;
}

static void *thread_main(void *arg)
{
    struct cbvh_os_thread *t = arg;
    t->fn(t->arg);
    return NULL;
}

int cbvh_os_thread_start(struct cbvh_os_thread *t, void (*fn)(void *arg), void *arg)
{
    t->fn = fn;
    t->arg = arg;
    return pthread_create(&t->id, NULL, thread_main, t) == 0 ? 0 : -1;
}

void cbvh_os_thread_join(struct cbvh_os_thread *t)
{
    pthread_join(t->id, NULL);
}

double cbvh_os_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
