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

/* The walk of the subtree `root` (whose box the caller tested) or, when
 * `whole`, of the whole tree, for the file's layout: one instance per layout
 * and mode, every choice a constant but the wide layout's scalar switch. */
CBVH_KERNEL int walk_file(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, const int whole, cbvh_ref root,
                          const struct cbvh_walk_mode mode, struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    if (f->layout == CBVH_LAYOUT_WIDE4) {
        const uint32_t layout = CBVH_LAYOUT_WIDE4;
        const cbvh_ref start = whole ? cbvh_tree_root(f, layout) : root;
        struct cbvh_walk_mode wide = mode;
        wide.scalar = atomic_load_explicit(&walk_scalar_setting, memory_order_relaxed) != 0;
        return cbvh_walk(f, layout, ray, start, CBVH_NO_BOX, wide, NULL, best, stats);
    }
    const uint32_t layout = CBVH_LAYOUT_BINARY;
    if (whole)
        return cbvh_walk(f, layout, ray, cbvh_tree_root(f, layout), cbvh_tree_root_box(f, layout), mode, NULL, best,
                         stats);
    return cbvh_walk(f, layout, ray, root, CBVH_NO_BOX, mode, NULL, best, stats);
}

/* The wide layout has no escape links: its stackless request walks sorted (the same answer). */
void cbvh_closest(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
                  struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    if (ray->box_halve) { /* raycast.h: the sorted walk, whose set-up halves the box test */
        walk_file(f, ray, 1, 0, closest_sorted, best, stats);
        return;
    }
    switch (traversal) {
    case CBVH_TRAVERSAL_UNSORTED:
        walk_file(f, ray, 1, 0, closest_unsorted, best, stats);
        break;
    case CBVH_TRAVERSAL_DISTANCE:
        walk_file(f, ray, 1, 0, closest_distance, best, stats);
        break;
    case CBVH_TRAVERSAL_STACKLESS:
        if (f->layout == CBVH_LAYOUT_BINARY) {
            cbvh_closest_stackless(f, ray, best, stats);
            break;
        }
        /* fall through */
    default:
        walk_file(f, ray, 1, 0, closest_sorted, best, stats);
        break;
    }
}

int cbvh_any(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
             cbvh_query_stats *stats)
{
    if (ray->box_halve)
        return walk_file(f, ray, 1, 0, any_sorted, NULL, stats);
    switch (traversal) {
    case CBVH_TRAVERSAL_UNSORTED:
        return walk_file(f, ray, 1, 0, any_unsorted, NULL, stats);
    case CBVH_TRAVERSAL_DISTANCE:
        return walk_file(f, ray, 1, 0, any_distance, NULL, stats);
    case CBVH_TRAVERSAL_STACKLESS:
        if (f->layout == CBVH_LAYOUT_BINARY)
            return cbvh_any_stackless(f, ray, stats);
        /* fall through */
    default:
        return walk_file(f, ray, 1, 0, any_sorted, NULL, stats);
    }
}

void cbvh_closest_subtree(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_ref root,
                          struct cbvh_best_hit *best, cbvh_query_stats *stats)
{
    walk_file(f, ray, 0, root, closest_sorted, best, stats);
}

int cbvh_any_subtree(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_ref root, cbvh_query_stats *stats)
{
    return walk_file(f, ray, 0, root, any_sorted, NULL, stats);
}
