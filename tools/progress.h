/* progress.h: a one-line progress display on stderr, shown only when stderr is a terminal. */
#ifndef CBVH_TOOLS_PROGRESS_H
#define CBVH_TOOLS_PROGRESS_H

#include "cbvh.h"

typedef struct progress {
    int enabled; /* stderr is a terminal and the user did not ask for --quiet */
    int shown;   /* something is on the line that progress_done must clear */
    const char *label;
    int percent; /* last percentage printed, -1 for none */
} progress;

/* Enables the display when `quiet` is 0 and stderr is a terminal. */
void progress_init(progress *p, int quiet);

/* Shows "label  NN%" (fraction in [0,1], or a negative fraction for a phase without a measure). */
void progress_update(progress *p, const char *label, double fraction);

/* Clears the line (so the summary that follows starts on a clean line). */
void progress_done(progress *p);

/* A cbvh_progress_fn: pass the progress* as progress_user. */
void progress_cook_callback(void *user, cbvh_phase phase, double fraction);

#endif
