/* stream_simd.c: the batch box test across rays with SSE2 (4 lanes) and AVX2 (8 lanes, chosen at run time). */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#ifdef CBVH_HAVE_SIMD
#include <immintrin.h>

#include "query/ray_box.h"
#include "query/stream.h"

/* The lane operations reproduce ray_box.h exactly: MAXPS(a, b) is
 * `a > b ? a : b` and MINPS(a, b) is `a < b ? a : b` (the second operand
 * wins when either is NaN), so a NaN plane distance is ignored as in the
 * scalar test, and the sums and products round identically. */

uint32_t cbvh_stream_box_sse2(const struct cbvh_stream_batch *restrict batch, uint16_t *restrict live, uint32_t n,
                              const float near[3], const float far[3])
{
    const __m128 nx = _mm_set1_ps(near[0]), ny = _mm_set1_ps(near[1]), nz = _mm_set1_ps(near[2]);
    const __m128 fx = _mm_set1_ps(far[0]), fy = _mm_set1_ps(far[1]), fz = _mm_set1_ps(far[2]);
    const __m128 pad = _mm_set1_ps(CBVH_BOX_PAD);
    uint32_t w = 0, j = 0;
    for (; j + 4 <= n; j += 4) {
        /* Rows: ray k's (ox, oy, oz, tmin) and (rx, ry, rz, tmax); transposed to lanes. */
        __m128 o0 = _mm_load_ps(&batch->box_ray[live[j]][0]), r0 = _mm_load_ps(&batch->box_ray[live[j]][4]);
        __m128 o1 = _mm_load_ps(&batch->box_ray[live[j + 1]][0]), r1 = _mm_load_ps(&batch->box_ray[live[j + 1]][4]);
        __m128 o2 = _mm_load_ps(&batch->box_ray[live[j + 2]][0]), r2 = _mm_load_ps(&batch->box_ray[live[j + 2]][4]);
        __m128 o3 = _mm_load_ps(&batch->box_ray[live[j + 3]][0]), r3 = _mm_load_ps(&batch->box_ray[live[j + 3]][4]);
        _MM_TRANSPOSE4_PS(o0, o1, o2, o3); /* o0 = ox, o1 = oy, o2 = oz, o3 = tmin */
        _MM_TRANSPOSE4_PS(r0, r1, r2, r3); /* r0 = rx, r1 = ry, r2 = rz, r3 = tmax */
        __m128 tnear = o3, tfar = r3;
        tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(nx, o0), r0), tnear);
        tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(ny, o1), r1), tnear);
        tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(nz, o2), r2), tnear);
        tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(fx, o0), r0), tfar);
        tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(fy, o1), r1), tfar);
        tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(fz, o2), r2), tfar);
        uint32_t mask = (uint32_t)_mm_movemask_ps(_mm_cmple_ps(tnear, _mm_mul_ps(tfar, pad)));
        cbvh_stream_compact(live, j, 4, mask, &w);
    }
    if (j < n) {
        uint32_t tail = cbvh_stream_box_scalar(batch, live + j, n - j, near, far);
        cbvh_stream_compact(live, j, tail, (1u << tail) - 1u, &w);
    }
    return w;
}

CBVH_TARGET("avx2") uint32_t cbvh_stream_box_avx2(const struct cbvh_stream_batch *restrict batch,
                                                               uint16_t *restrict live, uint32_t n,
                                                               const float near[3], const float far[3])
{
    const __m256 nx = _mm256_set1_ps(near[0]), ny = _mm256_set1_ps(near[1]), nz = _mm256_set1_ps(near[2]);
    const __m256 fx = _mm256_set1_ps(far[0]), fy = _mm256_set1_ps(far[1]), fz = _mm256_set1_ps(far[2]);
    const __m256 pad = _mm256_set1_ps(CBVH_BOX_PAD);
    uint32_t w = 0, j = 0;
    for (; j + 8 <= n; j += 8) {
        __m256 a0 = _mm256_load_ps(batch->box_ray[live[j]]), a1 = _mm256_load_ps(batch->box_ray[live[j + 1]]);
        __m256 a2 = _mm256_load_ps(batch->box_ray[live[j + 2]]), a3 = _mm256_load_ps(batch->box_ray[live[j + 3]]);
        __m256 a4 = _mm256_load_ps(batch->box_ray[live[j + 4]]), a5 = _mm256_load_ps(batch->box_ray[live[j + 5]]);
        __m256 a6 = _mm256_load_ps(batch->box_ray[live[j + 6]]), a7 = _mm256_load_ps(batch->box_ray[live[j + 7]]);
        /* 8x8 transpose: row k = ray k, column c = lane field c. */
        __m256 t0 = _mm256_unpacklo_ps(a0, a1), t1 = _mm256_unpackhi_ps(a0, a1);
        __m256 t2 = _mm256_unpacklo_ps(a2, a3), t3 = _mm256_unpackhi_ps(a2, a3);
        __m256 t4 = _mm256_unpacklo_ps(a4, a5), t5 = _mm256_unpackhi_ps(a4, a5);
        __m256 t6 = _mm256_unpacklo_ps(a6, a7), t7 = _mm256_unpackhi_ps(a6, a7);
        __m256 s0 = _mm256_shuffle_ps(t0, t2, 0x44), s1 = _mm256_shuffle_ps(t0, t2, 0xEE);
        __m256 s2 = _mm256_shuffle_ps(t1, t3, 0x44), s3 = _mm256_shuffle_ps(t1, t3, 0xEE);
        __m256 s4 = _mm256_shuffle_ps(t4, t6, 0x44), s5 = _mm256_shuffle_ps(t4, t6, 0xEE);
        __m256 s6 = _mm256_shuffle_ps(t5, t7, 0x44), s7 = _mm256_shuffle_ps(t5, t7, 0xEE);
        const __m256 ox = _mm256_permute2f128_ps(s0, s4, 0x20), oy = _mm256_permute2f128_ps(s1, s5, 0x20);
        const __m256 oz = _mm256_permute2f128_ps(s2, s6, 0x20), tmin = _mm256_permute2f128_ps(s3, s7, 0x20);
        const __m256 rx = _mm256_permute2f128_ps(s0, s4, 0x31), ry = _mm256_permute2f128_ps(s1, s5, 0x31);
        const __m256 rz = _mm256_permute2f128_ps(s2, s6, 0x31), tmax = _mm256_permute2f128_ps(s3, s7, 0x31);
        __m256 tnear = tmin, tfar = tmax;
        tnear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(nx, ox), rx), tnear);
        tnear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(ny, oy), ry), tnear);
        tnear = _mm256_max_ps(_mm256_mul_ps(_mm256_sub_ps(nz, oz), rz), tnear);
        tfar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fx, ox), rx), tfar);
        tfar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fy, oy), ry), tfar);
        tfar = _mm256_min_ps(_mm256_mul_ps(_mm256_sub_ps(fz, oz), rz), tfar);
        uint32_t mask = (uint32_t)_mm256_movemask_ps(_mm256_cmp_ps(tnear, _mm256_mul_ps(tfar, pad), _CMP_LE_OQ));
        cbvh_stream_compact(live, j, 8, mask, &w);
    }
    if (j < n) {
        uint32_t tail = cbvh_stream_box_sse2(batch, live + j, n - j, near, far);
        cbvh_stream_compact(live, j, tail, (1u << tail) - 1u, &w);
    }
    return w;
}

#endif
