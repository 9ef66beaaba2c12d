/* raycast_walks.c: the library's named instances of the traversal core (walk.h), one per mode and node layout. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include <stdatomic.h>

#include "query/raycast.h"
#include "query/walk.h"

static const struct cbvh_walk_mode closest_sorted = {.order = CBVH_WALK_SORTED};
static const struct cbvh_walk_mode closest_unsorted = {.order = CBVH_WALK_UNSORTED};
static const struct cbvh_walk_mode closest_distance = {.order = CBVH_WALK_DISTANCE};
static const struct cbvh_walk_mode any_sorted = {.order = CBVH_WALK_SORTED, .any = 1};
static const struct cbvh_walk_mode any_unsorted = {.order = CBVH_WALK_UNSORTED, .any = 1};
static const struct cbvh_walk_mode any_distance = {.order = CBVH_WALK_DISTANCE, .any = 1};

static atomic_int walk_scalar_setting;

void cbvh_walk_set_scalar(int scalar)
{
    atomic_store_explicit(&walk_scalar_setting, scalar, memory_order_relaxed);
}

/* The walks of one mode: in the wide layout (every choice a constant but its scalar switch) and in the
 * binary layout, each a function of its own with the traversal core inlined, so a caller's frame holds
 * one walk's stack (about 1.5 KiB), not the sum of every instance's (with all of them inlined into it,
 * cbvh_closest's frame was 11.6 KiB; -fstack-usage); the call costs one jump per ray. `name` walks the
 * subtree `root` (whose box the caller tested) or, when `whole`, the whole tree, for the file's layout. */
#define WALK_INSTANCE(name, mode)                                                                              \
    CBVH_NOINLINE int name##_wide4(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_ref start,   \
                                   struct cbvh_best_hit *best, cbvh_query_stats *stats)                         \
    {                                                                                                          \
        struct cbvh_walk_mode wide = mode;                                                                     \
        wide.scalar = atomic_load_explicit(&walk_scalar_setting, memory_order_relaxed) != 0;                   \
        return cbvh_walk(f, CBVH_LAYOUT_WIDE4, ray, start, CBVH_NO_BOX, wide, NULL, best, stats);              \
    }                                                                                                          \
    CBVH_NOINLINE int name##_binary(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_ref start,  \
                                    uint32_t start_box, struct cbvh_best_hit *best, cbvh_query_stats *stats)    \
    {                                                                                                          \
        return cbvh_walk(f, CBVH_LAYOUT_BINARY, ray, start, start_box, mode, NULL, best, stats);               \
    }                                                                                                          \
    static int name(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, const int whole, cbvh_ref root,  \
                    struct cbvh_best_hit *best, cbvh_query_stats *stats)                                        \
    {                                                                                                          \
        const uint32_t layout = f->layout;                                                                     \
        const cbvh_ref start = whole ? cbvh_tree_root(f, layout) : root;                                      \
        if (layout == CBVH_LAYOUT_WIDE4)                                                                       \
            return name##_wide4(f, ray, start, best, stats);                                                   \
        return name##_binary(f, ray, start, whole ? cbvh_tree_root_box(f, layout) : CBVH_NO_BOX, best, stats); \
    }
WALK_INSTANCE(walk_closest_sorted, closest_sorted)
WALK_INSTANCE(walk_closest_unsorted, closest_unsorted)
WALK_INSTANCE(walk_closest_distance, closest_distance)
WALK_INSTANCE(walk_any_sorted, any_sorted)
WALK_INSTANCE(walk_any_unsorted, any_unsorted)
WALK_INSTANCE(walk_any_distance, any_distance)
#undef WALK_INSTANCE

/* The wide layout has no escape links: its stackless request walks sorted (the same answer). */
void cbvh_closest(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
                  struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    if (ray->box_halve) { /* raycast.h: the sorted walk, whose set-up halves the box test */
        walk_closest_sorted(f, ray, 1, 0, best, stats);
        return;
    }
    switch (traversal) {
    case CBVH_TRAVERSAL_UNSORTED:
        walk_closest_unsorted(f, ray, 1, 0, best, stats);
        break;
    case CBVH_TRAVERSAL_DISTANCE:
        walk_closest_distance(f, ray, 1, 0, best, stats);
        break;
    case CBVH_TRAVERSAL_STACKLESS:
        if (f->layout == CBVH_LAYOUT_BINARY) {
            cbvh_closest_stackless(f, ray, best, stats);
            break;
        }
        /* fall through */
    default:
        walk_closest_sorted(f, ray, 1, 0, best, stats);
        break;
    }
}

int cbvh_any(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
             cbvh_query_stats *stats)
{
    if (ray->box_halve)
        return walk_any_sorted(f, ray, 1, 0, NULL, stats);
    switch (traversal) {
    case CBVH_TRAVERSAL_UNSORTED:
        return walk_any_unsorted(f, ray, 1, 0, NULL, stats);
    case CBVH_TRAVERSAL_DISTANCE:
        return walk_any_distance(f, ray, 1, 0, NULL, stats);
    case CBVH_TRAVERSAL_STACKLESS:
        if (f->layout == CBVH_LAYOUT_BINARY)
            return cbvh_any_stackless(f, ray, stats);
        /* fall through */
    default:
        return walk_any_sorted(f, ray, 1, 0, NULL, stats);
    }
}

void cbvh_closest_subtree(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_ref root,
                          struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    walk_closest_sorted(f, ray, 0, root, best, stats);
}

int cbvh_any_subtree(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_ref root, cbvh_query_stats *stats)
{
    return walk_any_sorted(f, ray, 0, root, NULL, stats);
}
