/* progress.c: progress on stderr, only for a terminal, redrawn only when the percentage changes. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "progress.h"

void progress_init(progress *p, int quiet)
{
    p->enabled = !quiet && isatty(STDERR_FILENO);
    p->shown = 0;
    p->label = NULL;
    p->percent = -1;
}

void progress_update(progress *p, const char *label, double fraction)
{
    if (!p->enabled)
        return;
    int percent = fraction < 0 ? -1 : fraction > 1 ? 100 : (int)(fraction * 100.0);
    /* Redrawing on every callback would make the display the bottleneck. */
    if (p->shown && p->label && !strcmp(p->label, label) && percent == p->percent)
        return;
    p->label = label;
    p->percent = percent;
    if (percent < 0)
        fprintf(stderr, "\r\033[K%s...", label);
    else
        fprintf(stderr, "\r\033[K%-8s %3d%%", label, percent);
    fflush(stderr);
    p->shown = 1;
}

void progress_done(progress *p)
{
    if (p->enabled && p->shown) {
        fputs("\r\033[K", stderr);
        fflush(stderr);
    }
    p->shown = 0;
    p->label = NULL;
    p->percent = -1;
}

void progress_cook_callback(void *user, cbvh_phase phase, double fraction)
{
    static const char *const names[] = {"prepare", "build", "layout", "write"};
    const char *name = (unsigned)phase < 4 ? names[phase] : "cook";
    progress_update((progress *)user, name, fraction);
}
