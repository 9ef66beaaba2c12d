/* overlap_avx2.c: the overlap and contact queries' walk compiled for AVX2, eight leaf triangles a vector
 * through the float tests (overlap.c with CBVH_OVERLAP_AVX2: the walk and its tests, not the public
 * functions). */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#ifdef CBVH_HAVE_AVX2
#if !defined(__AVX2__) || (defined(__GNUC__) && !defined(__FMA__))
#error "overlap_avx2.c is compiled with AVX2, BMI1, BMI2 and FMA enabled (configure and CMake add the flags)"
#endif

#define CBVH_OVERLAP_AVX2
#include "query/overlap.c"
#endif
