/* stream_node_simd.h: the batch node test, a ray against four child boxes, in SSE2 intrinsics; compiled in
 * SSE2's encoding by stream_node.c (cbvh_stream_node_sse2) and in AVX2's by stream_avx2.c
 * (cbvh_stream_node_avx2). */
#ifndef CBVH_QUERY_STREAM_NODE_SIMD_H
#define CBVH_QUERY_STREAM_NODE_SIMD_H

#include <immintrin.h>
#include <string.h>

#include "common/compiler.h"
#include "query/ray_box.h"
#include "query/stream.h"

/* The lane operations reproduce ray_box.h exactly: MAXPS(a, b) is
 * `a > b ? a : b` and MINPS(a, b) is `a < b ? a : b` (the second operand
 * wins when either is NaN), so a NaN plane distance is ignored as in the
 * scalar test, and the differences and products round identically. */

/* Ray r, which enters the boxes of `mask` (bit k: box k) at entry[k], goes on those lists. Every lane
 * stores and only the entered lists advance: no branch on the mask, which is as random as the rays. */
static inline void node_append(const struct cbvh_stream_lists *restrict out, uint16_t r, uint32_t mask,
                               const float entry[CBVH_STREAM_LANES], uint32_t c[CBVH_STREAM_LANES])
{
    /* written out lane by lane, so the counts stay in registers */
    out->ray[0][c[0]] = r;
    out->entry[0][c[0]] = entry[0];
    c[0] += mask & 1u;
    out->ray[1][c[1]] = r;
    out->entry[1][c[1]] = entry[1];
    c[1] += mask >> 1 & 1u;
    out->ray[2][c[2]] = r;
    out->entry[2][c[2]] = entry[2];
    c[2] += mask >> 2 & 1u;
    out->ray[3][c[3]] = r;
    out->entry[3][c[3]] = entry[3];
    c[3] += mask >> 3 & 1u;
}

/* Lane i of v in all four lanes. */
#define SPLAT(v, i) _mm_shuffle_ps(v, v, _MM_SHUFFLE(i, i, i, i))

/* One ray against the four boxes (near x, y, z, far x, y, z planes of the
 * boxes in lanes), onto the lists of those of `lanes` it enters. */
static inline void node_ray_sse2(const struct cbvh_stream_batch *restrict batch, uint16_t r,
                                 const __m128 plane[6], uint32_t lanes,
                                 const struct cbvh_stream_lists *restrict out,
                                 uint32_t count[CBVH_STREAM_LANES])
{
    const __m128 o = _mm_load_ps(&batch->box_ray[r][0]), d = _mm_load_ps(&batch->box_ray[r][4]);
    const __m128 ox = SPLAT(o, 0), oy = SPLAT(o, 1), oz = SPLAT(o, 2), rx = SPLAT(d, 0), ry = SPLAT(d, 1),
                 rz = SPLAT(d, 2);
    __m128 tnear = SPLAT(o, 3), tfar = SPLAT(d, 3);
    tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(plane[0], ox), rx), tnear);
    tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(plane[1], oy), ry), tnear);
    tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(plane[2], oz), rz), tnear);
    tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(plane[3], ox), rx), tfar);
    tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(plane[4], oy), ry), tfar);
    tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(plane[5], oz), rz), tfar);
    _Alignas(16) float entry[CBVH_STREAM_LANES];
    _mm_store_ps(entry, tnear);
    const uint32_t mask =
        (uint32_t)_mm_movemask_ps(_mm_cmple_ps(tnear, _mm_mul_ps(tfar, _mm_set1_ps(CBVH_BOX_PAD))));
    node_append(out, r, mask & lanes, entry, count);
}

/* The n rays of `rays` against the boxes, onto the lists of the boxes each enters; count: each list's
 * length. */
CBVH_FORCE_INLINE void stream_node_simd(const struct cbvh_stream_batch *restrict batch,
                                        const uint16_t *restrict rays, uint32_t n,
                                        const struct cbvh_stream_boxes *restrict boxes,
                                        const struct cbvh_stream_lists *restrict out,
                                        uint32_t count[CBVH_STREAM_LANES])
{
    __m128 plane[6];
    for (uint32_t p = 0; p < 6; p++)
        plane[p] = _mm_load_ps(boxes->plane[p]);
    const uint32_t lanes = (1u << boxes->count) - 1u;
    uint32_t c[CBVH_STREAM_LANES] = {0, 0, 0, 0};
    for (uint32_t j = 0; j < n; j++)
        node_ray_sse2(batch, rays[j], plane, lanes, out, c);
    memcpy(count, c, sizeof c);
}

#endif
