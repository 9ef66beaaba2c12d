/* import_child.c: runs an import in a child process and reads the merged mesh back through a pipe. */
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include "fd_io.h"
#include "import_child.h"

/* The child's report, in this order: int32 status, string message; with status 0 the mesh (counts, the
 * positions, indices and material ids, the material names as strings with UINT32_MAX for "no name"); then
 * the opened and the missing path lists (uint64 count, strings). A string is uint32 length + bytes. */

static int write_u32(int fd, uint32_t v)
{
    return fd_write_all(fd, &v, sizeof v);
}

static int write_u64(int fd, uint64_t v)
{
    return fd_write_all(fd, &v, sizeof v);
}

static int write_string(int fd, const char *s)
{
    if (!s)
        return write_u32(fd, UINT32_MAX);
    size_t n = strlen(s);
    return write_u32(fd, (uint32_t)n) || fd_write_all(fd, s, n);
}

static int write_paths(int fd, const path_list *l)
{
    if (write_u64(fd, l->count))
        return -1;
    for (size_t k = 0; k < l->count; k++)
        if (write_string(fd, l->paths[k]))
            return -1;
    return 0;
}

static int write_report(int fd, int status, const char *message, const imported_mesh *m,
                        const import_options *o)
{
    if (write_u32(fd, (uint32_t)status) || write_string(fd, status ? message : ""))
        return -1;
    if (status == 0) {
        if (write_u64(fd, m->vertex_count) || write_u64(fd, m->triangle_count) ||
            write_u64(fd, m->dropped_points) || write_u64(fd, m->dropped_lines) ||
            write_u32(fd, m->mesh_instances) || write_u32(fd, m->material_count) ||
            fd_write_all(fd, m->positions, m->vertex_count * 3 * sizeof *m->positions) ||
            fd_write_all(fd, m->indices, m->triangle_count * 3 * sizeof *m->indices) ||
            fd_write_all(fd, m->material_ids, m->triangle_count * sizeof *m->material_ids))
            return -1;
        for (uint32_t k = 0; k < m->material_count; k++)
            if (write_string(fd, m->material_names ? m->material_names[k] : NULL))
                return -1;
    }
    return write_paths(fd, &o->opened) || write_paths(fd, &o->missing);
}

/* The child's end of the pipe and its options, for the runaway-read hook; its end of the progress pipe. */
static int child_fd = -1, child_progress_fd = -1;

/* The parent's progress callback. */
static import_progress_fn progress_fn;
static void *progress_user;

void import_contained_progress(import_progress_fn fn, void *user)
{
    progress_fn = fn;
    progress_user = user;
}

/* One byte per new percent, dropped when the pipe is full (the display only needs the latest). */
static void child_progress(void *user, int percent)
{
    (void)user;
    unsigned char b = (unsigned char)(percent < 0 ? 0 : percent > 100 ? 100 : percent);
    if (write(child_progress_fd, &b, 1) < 0) {
        /* full or closed: the display skips a step */
    }
}

static void child_runaway(void *user, const char *path)
{
    import_options *o = user;
    char message[512];
    snprintf(message, sizeof message,
             "assimp keeps reading past the end of '%s' and would not stop (a truncated file?)", path);
    _exit(write_report(child_fd, 1, message, NULL, o) ? 3 : 0);
}

/* The parent's side: reads the report against a deadline and collects the child's standard error. */
typedef struct reader {
    int fd, err_fd, progress_fd;
    pid_t pid;
    struct timespec deadline; /* tv_sec 0: none */
    int timed_out;
    char err[1024]; /* the end of what the child wrote on standard error */
    size_t err_size;
} reader;

static long ms_left(const reader *r)
{
    if (r->deadline.tv_sec == 0)
        return -1;
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    long ms = (long)(r->deadline.tv_sec - now.tv_sec) * 1000 + (r->deadline.tv_nsec - now.tv_nsec) / 1000000;
    return ms < 0 ? 0 : ms;
}

static void keep_err(reader *r, const char *data, size_t n)
{
    if (n >= sizeof r->err) {
        data += n - (sizeof r->err - 1);
        n = sizeof r->err - 1;
    }
    if (r->err_size + n >= sizeof r->err) {
        size_t drop = r->err_size + n - (sizeof r->err - 1);
        memmove(r->err, r->err + drop, r->err_size - drop);
        r->err_size -= drop;
    }
    memcpy(r->err + r->err_size, data, n);
    r->err_size += n;
    r->err[r->err_size] = '\0';
}

/* Fills `size` bytes from the report pipe; -1 at its end, on an error or when time is up. */
static int read_all(reader *r, void *data, size_t size)
{
    char *p = data;
    while (size > 0) {
        struct pollfd fds[3] = {{r->fd, POLLIN, 0}, {r->err_fd, POLLIN, 0}, {r->progress_fd, POLLIN, 0}};
        long ms = ms_left(r);
        if (ms == 0) {
            r->timed_out = 1;
            return -1;
        }
        /* a closed descriptor (-1) is skipped by poll */
        int ready = poll(fds, 3, ms > INT32_MAX ? INT32_MAX : (int)ms);
        if (ready < 0 && errno == EINTR)
            continue;
        if (ready < 0)
            return -1;
        if (r->progress_fd >= 0 && fds[2].revents) {
            unsigned char b[256];
            ssize_t n = read(r->progress_fd, b, sizeof b);
            if (n > 0 && progress_fn)
                progress_fn(progress_user, b[n - 1]);
            else if (n == 0 || (n < 0 && errno != EINTR && errno != EAGAIN)) {
                close(r->progress_fd);
                r->progress_fd = -1;
            }
        }
        if (r->err_fd >= 0 && fds[1].revents) {
            char buf[4096];
            ssize_t n = read(r->err_fd, buf, sizeof buf);
            if (n > 0)
                keep_err(r, buf, (size_t)n);
            else if (n == 0 || errno != EINTR) {
                close(r->err_fd);
                r->err_fd = -1;
            }
        }
        if (!fds[0].revents)
            continue;
        ssize_t n = read(r->fd, p, size > (1u << 20) ? (1u << 20) : size);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            return -1;
        p += n;
        size -= (size_t)n;
    }
    return 0;
}

static int read_u32(reader *r, uint32_t *v)
{
    return read_all(r, v, sizeof *v);
}

static int read_u64(reader *r, uint64_t *v)
{
    return read_all(r, v, sizeof *v);
}

/* A string, or NULL for UINT32_MAX; *ok becomes 0 on a read or allocation failure. */
static char *read_string(reader *r, int *ok)
{
    uint32_t n;
    if (read_u32(r, &n)) {
        *ok = 0;
        return NULL;
    }
    if (n == UINT32_MAX)
        return NULL;
    char *s = malloc((size_t)n + 1);
    if (!s || read_all(r, s, n)) {
        free(s);
        *ok = 0;
        return NULL;
    }
    s[n] = '\0';
    return s;
}

static int read_paths(reader *r, path_list *l)
{
    uint64_t count;
    if (read_u64(r, &count) || count > SIZE_MAX / sizeof *l->paths)
        return -1;
    l->paths = calloc((size_t)count + 1, sizeof *l->paths);
    if (!l->paths)
        return -1;
    int ok = 1;
    for (l->count = 0; ok && l->count < count;) {
        char *s = read_string(r, &ok);
        if (s)
            l->paths[l->count++] = s;
    }
    return ok ? 0 : -1;
}

static int read_mesh(reader *r, imported_mesh *m)
{
    uint64_t vertices, triangles;
    if (read_u64(r, &vertices) || read_u64(r, &triangles) || read_u64(r, &m->dropped_points) ||
        read_u64(r, &m->dropped_lines) || read_u32(r, &m->mesh_instances) ||
        read_u32(r, &m->material_count) || vertices > UINT32_MAX || triangles > UINT32_MAX)
        return -1;
    m->vertex_count = (size_t)vertices;
    m->triangle_count = (size_t)triangles;
    m->positions = malloc(m->vertex_count * 3 * sizeof *m->positions + 1);
    m->indices = malloc(m->triangle_count * 3 * sizeof *m->indices + 1);
    m->material_ids = malloc(m->triangle_count * sizeof *m->material_ids + 1);
    if (!m->positions || !m->indices || !m->material_ids ||
        read_all(r, m->positions, m->vertex_count * 3 * sizeof *m->positions) ||
        read_all(r, m->indices, m->triangle_count * 3 * sizeof *m->indices) ||
        read_all(r, m->material_ids, m->triangle_count * sizeof *m->material_ids))
        return -1;
    if (m->material_count == 0)
        return 0;
    m->material_names = calloc(m->material_count, sizeof *m->material_names);
    if (!m->material_names)
        return -1;
    int ok = 1;
    for (uint32_t k = 0; ok && k < m->material_count; k++)
        m->material_names[k] = read_string(r, &ok);
    return ok ? 0 : -1;
}

/* Says why a child that sent no complete report ended; `status` from waitpid. */
static void describe_end(const reader *r, int status, unsigned timeout_seconds, char *message,
                         size_t message_size)
{
    if (r->timed_out)
        snprintf(
            message, message_size,
            "the import took longer than %u s and was stopped (--import-timeout SECONDS raises the limit, "
            "0 removes it)",
            timeout_seconds);
    else if (WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
        snprintf(message, message_size, "the import was killed (signal %d: %s; out of memory?)",
                 WTERMSIG(status), strsignal(WTERMSIG(status)));
    else if (WIFSIGNALED(status))
        snprintf(message, message_size, "assimp %s on this file (signal %d: %s)",
                 WTERMSIG(status) == SIGABRT ? "aborted" : "crashed", WTERMSIG(status),
                 strsignal(WTERMSIG(status)));
    else
        snprintf(message, message_size, "the import ended with status %d and no report",
                 WIFEXITED(status) ? WEXITSTATUS(status) : -1);
    /* assimp's last line on standard error (an ai_assert's file, line and condition) */
    const char *end = r->err + r->err_size;
    while (end > r->err && (end[-1] == '\n' || end[-1] == '\r'))
        end--;
    const char *start = end;
    while (start > r->err && start[-1] != '\n')
        start--;
    size_t used = strlen(message);
    if (end > start && used + 16 < message_size)
        snprintf(message + used, message_size - used, "; assimp said: %.*s", (int)(end - start), start);
}

int import_contained(const char *path, import_options *o, unsigned timeout_seconds, imported_mesh *out,
                     char *message, size_t message_size)
{
    memset(out, 0, sizeof *out);
    int fds[2], errs[2], progress[2] = {-1, -1};
    if (progress_fn && pipe(progress) == 0) {
        /* neither end blocks: the child drops a step when the pipe is full */
        fcntl(progress[0], F_SETFL, fcntl(progress[0], F_GETFL) | O_NONBLOCK);
        fcntl(progress[1], F_SETFL, fcntl(progress[1], F_GETFL) | O_NONBLOCK);
    }
    if (pipe(fds) != 0) {
        snprintf(message, message_size, "cannot create a pipe: %s", strerror(errno));
        return 2;
    }
    if (pipe(errs) != 0) {
        snprintf(message, message_size, "cannot create a pipe: %s", strerror(errno));
        close(fds[0]);
        close(fds[1]);
        return 2;
    }
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    if (pid == 0) {
#ifdef __linux__
        prctl(PR_SET_PDEATHSIG, SIGKILL); /* a parent stopped by its build system takes its import along */
#endif
        close(fds[0]);
        close(errs[0]);
        if (progress[0] >= 0)
            close(progress[0]);
        dup2(errs[1], STDERR_FILENO);
        close(errs[1]);
        signal(SIGPIPE, SIG_DFL);
        if (timeout_seconds)
            alarm(timeout_seconds + 1); /* ends the child even if the parent is gone */
        child_fd = fds[1];
        o->on_runaway_read = child_runaway;
        child_progress_fd = progress[1];
        o->on_read_progress = progress[1] >= 0 ? child_progress : NULL;
        o->hook_user = o;
        imported_mesh m;
        char child_message[1024];
        int status = import_assimp(path, o, &m, child_message, sizeof child_message);
        int failed = write_report(fds[1], status, child_message, &m, o);
        _exit(failed ? 3 : 0);
    }
    close(fds[1]);
    close(errs[1]);
    if (progress[1] >= 0)
        close(progress[1]);
    if (pid < 0) {
        close(fds[0]);
        close(errs[0]);
        if (progress[0] >= 0)
            close(progress[0]);
        snprintf(message, message_size, "cannot start the import: %s", strerror(errno));
        return 2;
    }
    reader r;
    memset(&r, 0, sizeof r);
    r.fd = fds[0];
    r.err_fd = errs[0];
    r.progress_fd = progress[0];
    r.pid = pid;
    if (timeout_seconds) {
        clock_gettime(CLOCK_MONOTONIC, &r.deadline);
        r.deadline.tv_sec += timeout_seconds;
    }
    uint32_t status = 1;
    int ok = read_u32(&r, &status) == 0;
    char *child_message = ok ? read_string(&r, &ok) : NULL;
    if (ok && status == 0)
        ok = read_mesh(&r, out) == 0;
    path_list opened = {NULL, 0}, missing = {NULL, 0};
    ok = ok && read_paths(&r, &opened) == 0 && read_paths(&r, &missing) == 0;
    /* The import's side files, whatever its outcome: the depfile lists them. */
    o->opened = opened;
    o->missing = missing;
    if (!ok)
        kill(pid, SIGKILL);
    int wstatus = 0;
    while (waitpid(pid, &wstatus, 0) < 0 && errno == EINTR)
        continue;
    /* Drain what the child wrote on standard error after its report (or before it died). */
    if (r.err_fd >= 0) {
        char buf[4096];
        ssize_t n;
        while ((n = read(r.err_fd, buf, sizeof buf)) > 0)
            keep_err(&r, buf, (size_t)n);
        close(r.err_fd);
    }
    close(r.fd);
    if (r.progress_fd >= 0)
        close(r.progress_fd);
    int rc;
    if (!ok) {
        imported_mesh_free(out);
        describe_end(&r, wstatus, timeout_seconds, message, message_size);
        rc = 1;
    } else if (status != 0) {
        imported_mesh_free(out);
        snprintf(message, message_size, "%s", child_message ? child_message : "");
        rc = (int)status;
    } else {
        rc = 0;
    }
    free(child_message);
    return rc;
}
