/* fuzz_support.h: shared by the fuzz targets, the replay driver and the corruption tests: guard-page copies,
 * CRC repair, query invariants. */
#ifndef CBVH_FUZZ_SUPPORT_H
#define CBVH_FUZZ_SUPPORT_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"

/* A copy of some bytes placed so that the last byte is followed by an
 * unmapped (PROT_NONE) page: a one-byte overread faults at once. */
typedef struct guard_buffer {
    uint8_t *data; /* the copy; writable */
    size_t size;
    void *map; /* the whole mapping */
    size_t map_size;
} guard_buffer;

/* Copies `size` bytes to the end of fresh pages in front of a guard page.
 * Aborts when the system cannot map (the harness cannot run at all). */
void guard_copy(guard_buffer *g, const void *data, size_t size);
void guard_release(guard_buffer *g);

/* Makes a damaged file pass the checksum and size checks so the loader's
 * structural checks see it: sets file_size to `size`, then recomputes every
 * section CRC whose range lies inside the buffer, the table CRC and the header
 * CRC. Any bytes are accepted (out-of-range fields are left as they are). */
void fuzz_repair_checksums(uint8_t *bytes, size_t size);

/* MinGW-w64 checks formats against the C99 printf it is built with (__USE_MINGW_ANSI_STDIO). */
#ifdef __MINGW32__
#define FUZZ_PRINTF gnu_printf
#else
#define FUZZ_PRINTF printf
#endif
/* Fails loudly (message on stderr, then abort) so libFuzzer, the replay
 * driver and cmocka programs all stop on a broken invariant. */
void fuzz_fail(const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(FUZZ_PRINTF, 1, 2), noreturn))
#endif
    ;
#define FUZZ_CHECK(cond, ...)                                                                                \
    do {                                                                                                     \
        if (!(cond))                                                                                         \
            fuzz_fail(__VA_ARGS__);                                                                          \
    } while (0)

/* Checks an open error: a known failing code and a non-empty message. */
void fuzz_check_error(cbvh_result r, const cbvh_error *err);

/* Runs every query kind (raycast and occluded with every traversal, streams,
 * sphere/capsule/box sweeps, box and sphere overlaps) on rays, boxes and
 * shapes derived from the file's bounds and `seed`, and checks each result:
 * triangle ids valid, t within [tmin,tmax] (sweeps: [0,1]), barycentrics in
 * the triangle, the reported hit point on the reported triangle, normals of
 * unit length, overlap ids unique, invalid rays missing. `bytes` is the file
 * the handle was opened from (the header gives the original triangle count).
 * With `strict` (a file the cooker wrote) it also checks that every traversal,
 * the streams and occluded agree with the sorted raycast, that a sweep of
 * radius 0 equals the raycast, that every triangle has non-zero area, and
 * that overlaps find every triangle with a vertex inside the query. Returns the number of queries run. */
size_t fuzz_check_queries(const cbvh_file *f, const uint8_t *bytes, size_t size, uint64_t seed, int strict);

#endif
