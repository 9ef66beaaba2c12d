/* depfile.h: the Makefile rule `cbvh cook --depfile` writes for make and ninja, put in place atomically. */
#ifndef CBVH_TOOLS_DEPFILE_H
#define CBVH_TOOLS_DEPFILE_H

#include <stddef.h>

#include "import_assimp.h"

/* Whether two paths name one file: the same device and inode when both exist (through any link), else the
 * same name in the same (resolved) folder. */
int paths_same_file(const char *a, const char *b);

/* A depfile written beside its final name and put in place before the output is replaced, with the file
 * it replaced kept until the cook is known to have succeeded. */
typedef struct depfile_commit {
    char *path;   /* the depfile */
    char *backup; /* a hard link to the depfile it replaced, or NULL (there was none, or links fail) */
    int existed;  /* a depfile was there before */
} depfile_commit;

/* Writes `target: deps...` (Makefile syntax: spaces, #, \ and $ escaped) naming `in`, then the files of
 * `found` other than `in`, then those of `missing`, then `extra` (NULL: none), and an empty rule for each
 * dependency but `in` (as gcc -MP: make and ninja then cope with a deleted side file, and a missing one
 * makes the target out of date until it appears). The text goes to a temporary file in the depfile's folder,
 * which is then renamed over `path`. Returns 0, or -1 with errno and nothing changed. */
int depfile_put(depfile_commit *d, const char *path, const char *target, const char *in,
                const path_list *found, const path_list *missing, const char *extra);

/* After the cook: `keep` 1 drops the backup; 0 puts the previous depfile back (or removes the new one when
 * there was none). */
void depfile_finish(depfile_commit *d, int keep);

#endif
