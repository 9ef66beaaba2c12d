/* depfile.c: writes `cbvh cook`'s Makefile rule (OUT: IN SIDE-FILES... plus an empty rule per side file). */
#define _XOPEN_SOURCE 700 /* realpath */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "depfile.h"
#include "temp_cleanup.h"

/* The folder part of `path` resolved (realpath) and its last name, as "resolved/name"; NULL on failure. */
static char *resolved_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *name = slash ? slash + 1 : path;
    size_t dir_len = slash ? (size_t)(slash - path) : 0;
    char *dir = malloc(dir_len + 2);
    if (!dir)
        return NULL;
    if (slash && dir_len == 0)
        strcpy(dir, "/");
    else if (slash)
        memcpy(dir, path, dir_len), dir[dir_len] = '\0';
    else
        strcpy(dir, ".");
    char *real = realpath(dir, NULL);
    free(dir);
    if (!real)
        return NULL;
    size_t size = strlen(real) + strlen(name) + 2;
    char *out = malloc(size);
    if (out)
        snprintf(out, size, "%s/%s", real, name);
    free(real);
    return out;
}

int paths_same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    char *ra = resolved_name(a), *rb = resolved_name(b);
    int same = ra && rb && !strcmp(ra, rb);
    free(ra);
    free(rb);
    return same;
}

static void put_name(FILE *f, const char *s)
{
    for (; *s; s++) {
        if (*s == ' ' || *s == '#' || *s == '\\')
            fputc('\\', f);
        if (*s == '$')
            fputc('$', f);
        fputc(*s, f);
    }
}

/* Calls `each(f, name)` for every dependency after `in`, each once, in order: found, missing, extra. */
static void for_each_side(FILE *f, const char *in, const path_list *found, const path_list *missing,
                          const char *extra, void (*each)(FILE *, const char *))
{
    for (size_t k = 0; found && k < found->count; k++)
        if (strcmp(found->paths[k], in))
            each(f, found->paths[k]);
    for (size_t k = 0; missing && k < missing->count; k++)
        each(f, missing->paths[k]);
    if (extra)
        each(f, extra);
}

static void put_dependency(FILE *f, const char *name)
{
    fputc(' ', f);
    put_name(f, name);
}

static void put_empty_rule(FILE *f, const char *name)
{
    fputc('\n', f);
    put_name(f, name);
    fputs(":\n", f);
}

/* "dir/.name.d-XXXXXX" beside `path` (a rename within one folder stays on one file system). */
static char *sibling(const char *path, const char *kind)
{
    const char *slash = strrchr(path, '/');
    size_t dir_len = slash ? (size_t)(slash + 1 - path) : 0;
    const char *name = path + dir_len;
    size_t size = strlen(path) + strlen(kind) + 16;
    char *s = malloc(size);
    if (s)
        snprintf(s, size, "%.*s.%.*s%s", (int)dir_len, path, (int)(NAME_MAX > 200 ? 200 : NAME_MAX), name,
                 kind);
    return s;
}

int depfile_put(depfile_commit *d, const char *path, const char *target, const char *in,
                const path_list *found, const path_list *missing, const char *extra)
{
    memset(d, 0, sizeof *d);
    char *temp = sibling(path, ".tmp-XXXXXX");
    d->path = strdup(path);
    if (!temp || !d->path) {
        free(temp);
        free(d->path);
        d->path = NULL;
        errno = ENOMEM;
        return -1;
    }
    int fd = mkstemp(temp);
    if (fd >= 0)
        temp_cleanup_add(temp, NULL);
    FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
    if (!f) {
        int saved = errno;
        if (fd >= 0) {
            close(fd);
            unlink(temp);
            temp_cleanup_done(temp);
        }
        free(temp);
        free(d->path);
        d->path = NULL;
        errno = saved;
        return -1;
    }
    put_name(f, target);
    fputs(": ", f);
    put_name(f, in);
    for_each_side(f, in, found, missing, extra, put_dependency);
    fputc('\n', f);
    for_each_side(f, in, found, missing, extra, put_empty_rule);
    int failed = ferror(f);
    failed |= fflush(f) != 0 || fsync(fd) != 0;
    int saved = errno;
    failed |= fclose(f) != 0;
    if (!failed) {
        /* mkstemp's 0600 becomes 0666 less the umask, as any new file */
        mode_t mask = umask(0);
        umask(mask);
        chmod(temp, 0666 & ~mask);
    }
    struct stat st;
    d->existed = lstat(path, &st) == 0;
    if (!failed && d->existed) {
        d->backup = sibling(path, ".old-XXXXXX");
        int bfd = d->backup ? mkstemp(d->backup) : -1;
        if (bfd >= 0) {
            close(bfd);
            /* a backup name no one else takes: mkstemp made it, the link replaces it */
            if (unlink(d->backup) != 0 || link(path, d->backup) != 0) {
                free(d->backup);
                d->backup = NULL;
            } else {
                /* Interrupted during the cook, the new depfile stays with the old OUT (make cooks again);
                 * the old one put back beside a new OUT would hide dependencies. */
                temp_cleanup_add(d->backup, NULL);
            }
        } else {
            free(d->backup);
            d->backup = NULL;
        }
    }
    if (failed || rename(temp, path) != 0) {
        saved = failed ? (saved ? saved : EIO) : errno;
        unlink(temp);
        temp_cleanup_done(temp);
        if (d->backup) {
            unlink(d->backup);
            temp_cleanup_done(d->backup);
        }
        free(d->backup);
        free(temp);
        free(d->path);
        memset(d, 0, sizeof *d);
        errno = saved;
        return -1;
    }
    temp_cleanup_done(temp);
    free(temp);
    return 0;
}

void depfile_finish(depfile_commit *d, int keep)
{
    if (!d->path)
        return;
    if (keep) {
        if (d->backup)
            unlink(d->backup);
    } else if (d->backup) {
        rename(d->backup, d->path);
    } else if (!d->existed) {
        unlink(d->path);
    }
    if (d->backup)
        temp_cleanup_done(d->backup);
    free(d->backup);
    free(d->path);
    memset(d, 0, sizeof *d);
}
