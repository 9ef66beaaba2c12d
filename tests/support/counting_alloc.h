/* counting_alloc.h: an allocator for tests that counts live blocks and bytes and fails a chosen call. */
#ifndef CBVH_TESTS_COUNTING_ALLOC_H
#define CBVH_TESTS_COUNTING_ALLOC_H

#include <stddef.h>

#include "cbvh.h"

typedef struct counting_alloc {
    long calls;        /* allocations asked for so far */
    long fail_at;      /* the call that fails (0-based); -1: none */
    int fail_all;      /* also fail every call after fail_at */
    long live;         /* blocks not yet freed */
    long peak_live;
    size_t live_bytes; /* their sizes, as asked for */
} counting_alloc;

/* Resets c and returns allocator hooks that count into it. Misuse by the
 * library (an alignment that is not a power of two up to 64, a free of a
 * block not live) aborts, which fails the test. */
cbvh_allocator counting_allocator(counting_alloc *c, long fail_at, int fail_all);

#endif
