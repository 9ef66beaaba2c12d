/* raycast_walks_avx2.c: the wide layout's walk instances compiled for AVX2, eight leaf triangles a vector. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#ifdef CBVH_HAVE_AVX2
#if !defined(__AVX2__) || (defined(__GNUC__) && !defined(__FMA__))
#error                                                                                                       \
    "raycast_walks_avx2.c is compiled with AVX2, BMI1, BMI2 and FMA enabled (configure and CMake add the flags)"
#endif

#include "query/raycast.h"
#include "query/walk.h"

/* The same instances as raycast_walks.c's: the answers are the other kernels' bit for bit. */
#define WALK_AVX2(name, order_, any_)                                                                        \
    int cbvh_walk_##name##_wide4_avx2(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,             \
                                      cbvh_ref start, struct cbvh_best_hit *best, cbvh_query_stats *stats)   \
    {                                                                                                        \
        const struct cbvh_walk_mode mode = {.order = order_, .any = any_};                                   \
        return cbvh_walk(f, CBVH_LAYOUT_WIDE4, ray, start, CBVH_NO_BOX, mode, NULL, best, stats);            \
    }
CBVH_WALK_INSTANCES(WALK_AVX2)
#undef WALK_AVX2
#endif
