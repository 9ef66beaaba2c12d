/* sweep_walk_avx2.c: the sweeps' tree walk and the shapes' exact triangle tests compiled for AVX2, eight
 * leaf triangles a vector through the float culls. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#ifdef CBVH_HAVE_AVX2
#if !defined(__AVX2__) || (defined(__GNUC__) && !defined(__FMA__))
#error                                                                                                       \
    "sweep_walk_avx2.c is compiled with AVX2, BMI1, BMI2 and FMA enabled (configure and CMake add the flags)"
#endif

#include "query/sweep_walk_kernel.h"

/* Some of the functions the exact tests call (closest.c, triangle_box.c) are SSE2 code: the upper halves of
 * the vector registers, which a caller's AVX code may have left in use, are cleared first (the compiler
 * clears them again after its own 256-bit code). */
int cbvh_sweep_walk_avx2(const struct cbvh_file *f, const struct cbvh_local_shape *shape,
                         const float delta[3], const struct cbvh_sweep_rules *rules,
                         struct cbvh_sweep_found *found)
{
    _mm256_zeroupper();
    return sweep_walk_kernel(f, shape, delta, rules, found, 1);
}
#endif
