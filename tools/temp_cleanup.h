/* temp_cleanup.h: temporary files undone when SIGINT, SIGTERM or SIGHUP ends a command. */
#ifndef CBVH_TOOLS_TEMP_CLEANUP_H
#define CBVH_TOOLS_TEMP_CLEANUP_H

/* Registers `path` (a file, or a folder emptied by the files registered after it) to be removed if one of
 * those signals ends the process; when `restore_from` is not NULL, that file is renamed back over `path`
 * instead (a replaced file put back). The first call installs the handlers, which undo the registrations
 * newest first and then end the process by the same signal. Returns 0, or -1 when the path is too long
 * or all slots are taken (the path is then simply not cleaned up). */
int temp_cleanup_add(const char *path, const char *restore_from);

/* The command removed (or kept) `path` itself: forget it. */
void temp_cleanup_done(const char *path);

#endif
