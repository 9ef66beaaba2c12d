/* counting_alloc.h: an allocator for tests that counts live blocks and bytes and fails a chosen call. */
#ifndef CBVH_TESTS_COUNTING_ALLOC_H
#define CBVH_TESTS_COUNTING_ALLOC_H

#include <stddef.h>

#include "cbvh.h"

typedef struct counting_alloc {
    long calls;   /* allocations asked for so far */
    long fail_at; /* the call that fails (0-based); -1: none */
    int fail_all; /* also fail every call after fail_at */
    long live;    /* blocks not yet freed */
    long peak_live;
    size_t live_bytes; /* their sizes, as asked for */
    size_t peak_bytes; /* the most live_bytes reached */
} counting_alloc;

/* Resets c and returns allocator hooks that count into it. Misuse by the
 * library (an alignment that is not a power of two up to 64, a free of a
 * block not live) aborts, which fails the test. */
cbvh_allocator counting_allocator(counting_alloc *c, long fail_at, int fail_all);

/* Opens a file (from data[size], or by path when path is not NULL) with
 * allocation N failing, for N = 0, 1, 2 ... until the open succeeds. Each
 * failure must be CBVH_ERROR_OUT_OF_MEMORY with a message, no handle and no
 * live block (a cmocka failure otherwise). On success `opened` (may be NULL)
 * runs on the file, which is then closed with no block left live. Returns
 * the number of failure points. */
size_t counting_open_failures(const void *data, size_t size, const char *path,
                              void (*opened)(const cbvh_file *file));

#endif
