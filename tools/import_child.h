/* import_child.h: importing an asset in a child process, so that a crash, an abort or a hang in assimp
 * becomes an error message naming the file and the reason. */
#ifndef CBVH_TOOLS_IMPORT_CHILD_H
#define CBVH_TOOLS_IMPORT_CHILD_H

#include "import_assimp.h"

/* As import_assimp(path, o, out, ...), run in a forked child that sends the mesh and o's path lists back
 * through a pipe. The child inherits the process's limits (the cook's RLIMIT_AS); it is stopped after
 * `timeout_seconds` (0: no limit). A child that crashes, aborts, runs out of time or keeps reading past the
 * end of a file makes this return 1 with a message saying so (and what assimp last wrote on standard
 * error); 2 when no child can be started. The child sets o->on_runaway_read (the parent's o keeps its own).
 */
int import_contained(const char *path, import_options *o, unsigned timeout_seconds, imported_mesh *out,
                     char *message, size_t message_size);

/* Called by import_contained (when set) with the percent of the input the child has read, for a progress
 * display. */
typedef void (*import_progress_fn)(void *user, int percent);
void import_contained_progress(import_progress_fn fn, void *user);

#endif
