/* stack_walk.h: the closest-hit and any-hit walk with a fixed stack: children ordered by the sort byte, by distance, or not. */
#ifndef CBVH_QUERY_STACK_WALK_H
#define CBVH_QUERY_STACK_WALK_H

#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/tree.h"

/* Node i's box against the ray: quantized from the node, or float_boxes[6 i ...]. */
CBVH_KERNEL int walk_box_test(const struct cbvh_box_ray *restrict box, const cbvh_node *restrict nodes,
                              const float *restrict float_boxes, uint32_t i, float tmin, float tmax, float *entry)
{
    if (!float_boxes)
        return cbvh_box_ray_test(box, &nodes[i], tmin, tmax, entry);
    const float *b = float_boxes + 6 * (size_t)i;
    const struct cbvh_slab_select s = box->sel;
    return cbvh_slab_test(b[s.near_x], b[s.near_y], b[s.near_z], b[s.far_x], b[s.far_y], b[s.far_z], box->org,
                          box->rcp, tmin, tmax, entry);
}

/* One walk for every stack variant. Both children's boxes are tested at the
 * parent, so a missed child is never pushed, and the farther one is pushed
 * with its entry distance: when it is popped after the ray became shorter
 * than that, it is dropped without a second box test. The order of two hit
 * children is `word & mask` (mask = the ray's sort mask: one AND; mask = 0:
 * first child first) or, with by_distance, the smaller entry distance. The
 * loader checked depth <= CBVH_MAX_DEPTH and a walk pushes at most one node
 * per level, so the stack cannot overflow. The walk covers the subtree of
 * `root` (0: the whole tree): everything it pushes lies in that subtree.
 * halved: the ray's box_halve axes are tested at half scale (ray_box.h); a
 * constant, so the instances for every other ray carry none of it.
 * float_boxes: NULL for the file's quantized boxes (every library walk, where
 * the constant folds the choice away); else six floats per node (min xyz,
 * max xyz), for tools that measure another box precision on the same tree
 * and the same walk (cbvh report's exact reference; never with halved). */
CBVH_KERNEL int cbvh_stack_walk(const struct cbvh_file *restrict f, const struct cbvh_ray_ctx *restrict ray,
                                uint32_t root, uint32_t mask, const int by_distance, const int any, const int counting,
                                const int halved, const float *restrict float_boxes,
                                struct cbvh_best_hit *restrict best, cbvh_query_stats *restrict stats)
{
    const cbvh_node *restrict nodes = f->nodes;
    struct cbvh_box_ray box;
    cbvh_box_ray_init(&box, f->grid_origin, f->grid_scale, ray->shear.org, ray->rcp, ray->octant);
    if (halved)
        cbvh_box_ray_halve(&box, ray->box_halve);
    const float tmin = ray->tmin;
    float tmax = ray->tmax;
    struct {
        uint32_t node;
        float entry;
    } stack[CBVH_MAX_DEPTH];
    uint32_t sp = 0, i = root;
    uint64_t visited = 1, tested = 0;
    int hit = 0;
    float entry0, entry1;

    if (!walk_box_test(&box, nodes, float_boxes, root, tmin, tmax, &entry0))
        goto done;
    for (;;) {
        const uint32_t word = nodes[i].word;
        if (!cbvh_node_is_leaf(word)) {
            uint32_t near = i + 1u, far = cbvh_second_child(nodes, i);
            const int h0 = walk_box_test(&box, nodes, float_boxes, near, tmin, tmax, &entry0);
            const int h1 = walk_box_test(&box, nodes, float_boxes, far, tmin, tmax, &entry1);
            if (counting)
                visited += 2;
            if (h0 && h1) {
                if (by_distance ? entry1 < entry0 : (word & mask) != 0) {
                    uint32_t tmp = near;
                    near = far;
                    far = tmp;
                    entry1 = entry0;
                }
                stack[sp].node = far;
                stack[sp].entry = entry1;
                sp++;
                i = near;
                continue;
            }
            if (h0 || h1) {
                i = h0 ? near : far;
                continue;
            }
        } else if (cbvh_leaf_visit(f, word, ray, any, counting, &tmax, best, &tested)) {
            hit = 1;
            break;
        }
        /* Pop the next node still in reach: the padded test of ray_box.h with the current tmax. */
        do {
            if (sp == 0)
                goto done;
            sp--;
        } while (!(stack[sp].entry <= tmax * CBVH_BOX_PAD));
        i = stack[sp].node;
    }
done:
    if (counting)
        cbvh_stats_add(stats, visited, tested);
    return hit;
}

#endif
