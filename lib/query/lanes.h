/* lanes.h: the vector the leaf filter is written on: 8 floats in files compiled for AVX2, else 4 (SSE2). */
#ifndef CBVH_QUERY_LANES_H
#define CBVH_QUERY_LANES_H

#ifdef CBVH_HAVE_SIMD
#include <immintrin.h>

/* Comparisons are ordered, as SSE's CMPLTPS: false when either operand is NaN. */
#if defined(__AVX2__)
#define CBVH_LANES 8u
typedef __m256 cbvh_lanes;
#define lanes_set1 _mm256_set1_ps
#define lanes_zero _mm256_setzero_ps
#define lanes_add _mm256_add_ps
#define lanes_sub _mm256_sub_ps
#define lanes_mul _mm256_mul_ps
#define lanes_div _mm256_div_ps
#define lanes_min _mm256_min_ps
#define lanes_max _mm256_max_ps
#define lanes_and _mm256_and_ps
#define lanes_or _mm256_or_ps
#define lanes_andnot _mm256_andnot_ps
#define lanes_lt(a, b) _mm256_cmp_ps((a), (b), _CMP_LT_OS)
#define lanes_le(a, b) _mm256_cmp_ps((a), (b), _CMP_LE_OS)
#define lanes_gt(a, b) _mm256_cmp_ps((a), (b), _CMP_GT_OS)
#define lanes_ge(a, b) _mm256_cmp_ps((a), (b), _CMP_GE_OS)
#define lanes_bits _mm256_movemask_ps
#define lanes_store _mm256_storeu_ps
#define lanes_sqrt _mm256_sqrt_ps
/* Every bit set in every lane: the mask of all lanes. */
#define lanes_all() _mm256_castsi256_ps(_mm256_set1_epi32(-1))
/* Four floats in lanes 0-3, zeros in 4-7 (for tests of a wide node's four slots), and lanes 0-3 back. */
#define lanes_from4 _mm256_zextps128_ps256
#define lanes_low4 _mm256_castps256_ps128
/* Lanes 0-3 from lo, 4-7 from hi, each four 16-byte aligned floats. */
#define lanes_load_halves(lo, hi)                                                                            \
    _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_load_ps(lo)), _mm_load_ps(hi), 1)
/* The lowest set lane of a non-empty mask (BMI1, which every AVX2 CPU has and the file is compiled for). */
#define lanes_lowest(mask) ((uint32_t)_tzcnt_u32(mask))
#else
#define CBVH_LANES 4u
typedef __m128 cbvh_lanes;
#define lanes_set1 _mm_set1_ps
#define lanes_zero _mm_setzero_ps
#define lanes_add _mm_add_ps
#define lanes_sub _mm_sub_ps
#define lanes_mul _mm_mul_ps
#define lanes_div _mm_div_ps
#define lanes_min _mm_min_ps
#define lanes_max _mm_max_ps
#define lanes_and _mm_and_ps
#define lanes_or _mm_or_ps
#define lanes_andnot _mm_andnot_ps
#define lanes_lt _mm_cmplt_ps
#define lanes_le _mm_cmple_ps
#define lanes_gt _mm_cmpgt_ps
#define lanes_ge _mm_cmpge_ps
#define lanes_bits _mm_movemask_ps
#define lanes_store _mm_storeu_ps
#define lanes_sqrt _mm_sqrt_ps
#define lanes_all() _mm_castsi128_ps(_mm_set1_epi32(-1))
#define lanes_from4(x) (x)
#define lanes_low4(x) (x)
#define lanes_load_halves(lo, hi) _mm_load_ps(lo)
#define lanes_lowest(mask) cbvh_lowest_lane(mask)
#endif
#endif

#endif
