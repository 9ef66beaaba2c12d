/* stream.h: the ray batch shared by the stream traversal and its scalar and SIMD box-test kernels. */
#ifndef CBVH_QUERY_STREAM_H
#define CBVH_QUERY_STREAM_H

#include <stddef.h>
#include <stdint.h>

#include "query/leaf.h"
#include "query/ray_setup.h"

/* One ray as the box test reads it: 32 bytes, so SSE2 loads a ray in two
 * vectors and AVX2 in one, then transposes to one lane per ray. */
enum { CBVH_LANE_OX, CBVH_LANE_OY, CBVH_LANE_OZ, CBVH_LANE_TMIN, CBVH_LANE_RX, CBVH_LANE_RY, CBVH_LANE_RZ,
       CBVH_LANE_TMAX };

/* Rays per batch when the stream runs on its own stack (cbvh_raycast_stream): its frame and the walk's
 * stay within about 8 KiB. Caller scratch (cbvh_raycast_stream_scratch) takes up to CBVH_STREAM_MAX_BATCH,
 * the most a 16-bit live list numbers. */
#define CBVH_STREAM_STACK_BATCH 32u
#define CBVH_STREAM_MAX_BATCH 4096u

/* Up to `capacity` rays of one octant, so the sort byte orders the whole batch. Its arrays lie in one
 * block (the stream's stack or the caller's scratch), cut by stream.c. */
struct cbvh_stream_batch {
    float (*box_ray)[8];          /* CBVH_LANE_*, 32-byte aligned; TMAX shrinks with hits, -1 once occluded */
    struct cbvh_ray_ctx *ctx;     /* the prepared rays (triangle test, per-ray tails) */
    struct cbvh_best_hit *best;
    size_t *ray_index;            /* position in the caller's arrays */
    uint16_t *live;               /* the walk's live rays, batch positions */
    uint32_t count, capacity;
};

/* Tests the rays batch->box_ray[live[j]], j < n, against the box whose near
 * planes (for the batch's octant) are near[3] and far planes far[3], with the
 * arithmetic of ray_box.h. Moves the survivors to the front of live[0..n) (a
 * permutation of the same set) and returns how many survived. */
typedef uint32_t (*cbvh_stream_box_fn)(const struct cbvh_stream_batch *restrict batch, uint16_t *restrict live,
                                       uint32_t n, const float near[3], const float far[3]);

uint32_t cbvh_stream_box_scalar(const struct cbvh_stream_batch *restrict batch, uint16_t *restrict live, uint32_t n,
                                const float near[3], const float far[3]);
#ifdef CBVH_HAVE_SIMD
uint32_t cbvh_stream_box_sse2(const struct cbvh_stream_batch *restrict batch, uint16_t *restrict live, uint32_t n,
                              const float near[3], const float far[3]);
uint32_t cbvh_stream_box_avx2(const struct cbvh_stream_batch *restrict batch, uint16_t *restrict live, uint32_t n,
                              const float near[3], const float far[3]);
#endif

/* Test hook, not exported: 0 = best kernel for this CPU (default), 1 = scalar,
 * 2 = SSE2, 3 = AVX2 (falls back to scalar when not built or not supported).
 * Meant to be set before queries run; reads are atomic so concurrent queries stay defined. */
void cbvh_stream_set_kernel(int which);
/* The kernel chosen by the current setting. */
cbvh_stream_box_fn cbvh_stream_box_kernel(void);

/* Moves the lanes whose bit is set in mask (lane k = position base + k) to the
 * write position *w, keeping the set: positions after the current one are not
 * touched, so later lanes still hold their own rays. */
static inline void cbvh_stream_compact(uint16_t *restrict live, uint32_t base, uint32_t lanes, uint32_t mask,
                                       uint32_t *restrict w)
{
    for (uint32_t k = 0; k < lanes; k++) {
        if (mask >> k & 1u) {
            uint16_t tmp = live[*w];
            live[*w] = live[base + k];
            live[base + k] = tmp;
            (*w)++;
        }
    }
}

#endif
