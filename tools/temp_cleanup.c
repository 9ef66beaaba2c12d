/* temp_cleanup.c: signal handlers that remove (or put back) a command's temporary files before it ends. */
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "temp_cleanup.h"

/* A command holds few temporary files at once (bench: one cooked file; demo: a folder and its file; cook: a
 * depfile and its backup). */
#define CLEANUP_SLOTS 8
#define CLEANUP_PATH 4096

typedef struct cleanup_slot {
    volatile sig_atomic_t used;
    char path[CLEANUP_PATH];
    char restore_from[CLEANUP_PATH]; /* "" : remove path */
} cleanup_slot;

static cleanup_slot slots[CLEANUP_SLOTS];
static int installed;

static void on_signal(int sig)
{
    for (int k = CLEANUP_SLOTS - 1; k >= 0; k--) {
        if (!slots[k].used)
            continue;
        if (slots[k].restore_from[0])
            rename(slots[k].restore_from, slots[k].path);
        else if (unlink(slots[k].path) != 0)
            rmdir(slots[k].path);
        slots[k].used = 0;
    }
    signal(sig, SIG_DFL);
    raise(sig);
}

int temp_cleanup_add(const char *path, const char *restore_from)
{
    if (strlen(path) >= CLEANUP_PATH || (restore_from && strlen(restore_from) >= CLEANUP_PATH))
        return -1;
    if (!installed) {
        static const int signals[] = {SIGINT, SIGTERM, SIGHUP};
        for (int k = 0; k < 3; k++) {
            struct sigaction sa, old;
            memset(&sa, 0, sizeof sa);
            sa.sa_handler = on_signal;
            sigemptyset(&sa.sa_mask);
            for (int s = 0; s < 3; s++)
                sigaddset(&sa.sa_mask, signals[s]);
            /* a signal the caller ignores (nohup) stays ignored */
            if (sigaction(signals[k], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
                sigaction(signals[k], &sa, NULL);
        }
        installed = 1;
    }
    for (int k = 0; k < CLEANUP_SLOTS; k++) {
        if (slots[k].used)
            continue;
        strcpy(slots[k].path, path);
        strcpy(slots[k].restore_from, restore_from ? restore_from : "");
        slots[k].used = 1;
        return 0;
    }
    return -1;
}

void temp_cleanup_done(const char *path)
{
    for (int k = CLEANUP_SLOTS - 1; k >= 0; k--)
        if (slots[k].used && !strcmp(slots[k].path, path)) {
            slots[k].used = 0;
            return;
        }
}
