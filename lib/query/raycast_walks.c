/* raycast_walks.c: the library's named instances of the traversal core (walk.h), one per mode, layout and
 * kernel, and the binary layout's stackless walk over escape links. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include "layout/binary.h"
#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/walk.h"

#ifdef CBVH_HAVE_AVX2
#define WALK_AVX2_CALL(name)                                                                                 \
    if (kernel == CBVH_WALK_KERNEL_AVX2)                                                                     \
        return cbvh_walk_##name##_wide4_avx2(f, ray, start, best, stats);
#else
#define WALK_AVX2_CALL(name)
#endif

/* The walks of one mode, each a function of its own with the traversal core inlined, so a caller's frame
 * holds one walk's stack: wide (the SSE2 instance reads `scalar` at run time; the AVX2 one, in its own
 * file, is chosen before either is entered) and binary. walk_##name walks the whole tree. */
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

/* The stackless walk's leaf step, out of line to keep the node loop's registers. */
CBVH_NOINLINE int stackless_leaf(const struct cbvh_file *f, uint32_t word, const struct cbvh_ray_ctx *ray,
                                 const int any, const int near, float *tmax, struct cbvh_best_hit *best)
{
    return cbvh_leaf_visit(f, cbvh_leaf_first(word), cbvh_leaf_count(word), ray, any, 0, near, tmax, best);
}

/* The binary layout's stackless walk: i = hit ? i + 1 : escape(i) (a leaf's escape is i + 1) until the
 * end of the array. Every step goes forward (the loader checked the links), so the walk ends; the order is
 * the fixed depth-first one. */
CBVH_KERNEL int stackless_walk(const struct cbvh_file *restrict f, const struct cbvh_ray_ctx *restrict ray,
                               const int any, struct cbvh_best_hit *restrict best,
                               cbvh_query_stats *restrict stats)
{
    const cbvh_node *restrict nodes = cbvh_binary_nodes(f);
    const uint32_t end = f->info.node_count;
    struct cbvh_box_ray box;
    cbvh_box_ray_init(&box, f->grid_origin, f->grid_scale, ray->shear.org, ray->rcp, ray->octant);
    const float tmin = ray->tmin;
    float tmax = ray->tmax;
    uint64_t visited = 0, tested = 0;
    int hit = 0;
    uint32_t i = 0;

    while (i < end) {
        const uint32_t word = nodes[i].word;
        float entry;
        visited++;
        if (!cbvh_box_ray_test(&box, f, CBVH_LAYOUT_BINARY, i, tmin, tmax, &entry)) {
            i += cbvh_node_span(word);
            continue;
        }
        if (cbvh_node_is_leaf(word)) {
            tested += cbvh_leaf_count(word);
            if (stackless_leaf(f, word, ray, any, entry <= tmin, &tmax, best)) {
                hit = 1;
                break;
            }
        }
        i++;
    }
    if (stats)
        cbvh_stats_add(stats, visited, tested);
    return hit;
}

CBVH_NOINLINE void closest_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,
                                     struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    stackless_walk(f, ray, 0, best, stats);
}

CBVH_NOINLINE int any_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,
                                cbvh_query_stats *stats)
{
    return stackless_walk(f, ray, 1, NULL, stats);
}

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
            closest_stackless(f, ray, best, stats);
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
            return any_stackless(f, ray, stats);
        /* fall through */
    default:
        return walk_any_sorted(f, ray, NULL, stats);
    }
}
