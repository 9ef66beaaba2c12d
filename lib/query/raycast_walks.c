/* raycast_walks.c: the library's named instances of the traversal core (walk.h), one per mode, layout and
 * kernel. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include "query/raycast.h"
#include "query/walk.h"
#include "query/walk_instances.h"

#ifdef CBVH_HAVE_AVX2
#define WALK_AVX2_CALL(name)                                                                                 \
    if (kernel == CBVH_WALK_KERNEL_AVX2)                                                                     \
        return cbvh_walk_##name##_wide4_avx2(f, ray, start, best, stats);
#else
#define WALK_AVX2_CALL(name)
#endif

/* The walks of one mode: in the wide layout (every choice a constant but the scalar switch of the SSE2
 * instance, a predictable branch rather than doubling its code; the AVX2 instance in its own file) and
 * in the binary layout, each a function of its own with the traversal core inlined, so a caller's frame
 * holds one walk's stack (about 3 KiB), not the sum of every instance's (with all of them inlined into
 * it, cbvh_closest's frame was 11.6 KiB; -fstack-usage); the call costs one jump per ray. The kernel is
 * chosen before either wide instance is entered, so the AVX2 walk never runs under the SSE2 one's frame
 * (3.2 KiB and six saved registers a ray when the choice was made inside it). walk_##name walks the
 * whole tree for the file's layout. */
#define WALK_INSTANCE(name, order_, any_)                                                                    \
    CBVH_NOINLINE int walk_##name##_wide4(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,         \
                                          cbvh_ref start, const int scalar, struct cbvh_best_hit *best,      \
                                          cbvh_query_stats *stats)                                           \
    {                                                                                                        \
        const struct cbvh_walk_mode mode = {.order = order_, .any = any_, .scalar = scalar};                 \
        return cbvh_walk(f, CBVH_LAYOUT_WIDE4, ray, start, CBVH_NO_BOX, mode, NULL, best, stats);            \
    }                                                                                                        \
    CBVH_NOINLINE int walk_##name##_binary(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,        \
                                           cbvh_ref start, uint32_t start_box, struct cbvh_best_hit *best,   \
                                           cbvh_query_stats *stats)                                          \
    {                                                                                                        \
        const struct cbvh_walk_mode mode = {.order = order_, .any = any_};                                   \
        return cbvh_walk(f, CBVH_LAYOUT_BINARY, ray, start, start_box, mode, NULL, best, stats);             \
    }                                                                                                        \
    CBVH_FORCE_INLINE int walk_##name(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,             \
                                      struct cbvh_best_hit *best, cbvh_query_stats *stats)                   \
    {                                                                                                        \
        const uint32_t layout = f->layout;                                                                   \
        const cbvh_ref start = cbvh_tree_root(f, layout);                                                    \
        if (layout == CBVH_LAYOUT_WIDE4) {                                                                   \
            const int kernel = cbvh_walk_kernel();                                                           \
            WALK_AVX2_CALL(name)                                                                             \
            return walk_##name##_wide4(f, ray, start, kernel == CBVH_WALK_KERNEL_SCALAR, best, stats);       \
        }                                                                                                    \
        return walk_##name##_binary(f, ray, start, cbvh_tree_root_box(f, layout), best, stats);              \
    }
CBVH_WALK_INSTANCES(WALK_INSTANCE)
#undef WALK_INSTANCE
#undef WALK_AVX2_CALL

/* The wide layout has no escape links: its stackless request walks sorted (the same answer). */
void cbvh_closest(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
                  struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    if (ray->box_halve) { /* raycast.h: the sorted walk, whose set-up halves the box test */
        walk_closest_sorted(f, ray, best, stats);
        return;
    }
    switch (traversal) {
    case CBVH_TRAVERSAL_UNSORTED:
        walk_closest_unsorted(f, ray, best, stats);
        break;
    case CBVH_TRAVERSAL_DISTANCE:
        walk_closest_distance(f, ray, best, stats);
        break;
    case CBVH_TRAVERSAL_STACKLESS:
        if (f->layout == CBVH_LAYOUT_BINARY) {
            cbvh_closest_stackless(f, ray, best, stats);
            break;
        }
        /* fall through */
    default:
        walk_closest_sorted(f, ray, best, stats);
        break;
    }
}

int cbvh_any(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
             cbvh_query_stats *stats)
{
    if (ray->box_halve)
        return walk_any_sorted(f, ray, NULL, stats);
    switch (traversal) {
    case CBVH_TRAVERSAL_UNSORTED:
        return walk_any_unsorted(f, ray, NULL, stats);
    case CBVH_TRAVERSAL_DISTANCE:
        return walk_any_distance(f, ray, NULL, stats);
    case CBVH_TRAVERSAL_STACKLESS:
        if (f->layout == CBVH_LAYOUT_BINARY)
            return cbvh_any_stackless(f, ray, stats);
        /* fall through */
    default:
        return walk_any_sorted(f, ray, NULL, stats);
    }
}
