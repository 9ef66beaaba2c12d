/* tree_stats.h: statistics of an opened file's tree: exact node boxes, quantization inflation, SAH cost, leaf sizes. */
#ifndef CBVH_TOOLS_TREE_STATS_H
#define CBVH_TOOLS_TREE_STATS_H

#include <stdint.h>

#include "common/file.h"

/* Surface area of the box [lo, hi]. */
double tree_box_area(const float lo[3], const float hi[3]);

/* Fills boxes[6*b .. 6*b+6) (min xyz, max xyz) for every box id b of the tree (layout/tree.h)
 * with the exact float bounds of the decoded vertices of every triangle below it, and root[6]
 * with those of the whole tree. Needs 6 * cbvh_tree_box_count floats. */
void tree_exact_boxes(const struct cbvh_file *f, float *boxes, float root[6]);

/* Surface-area inflation of box b's dequantized box over its exact box: area(q) / area(exact) - 1,
 * 0 when the exact box has no area. */
double tree_box_inflation(const struct cbvh_file *f, uint32_t box, const float *exact_boxes);

typedef struct tree_stats {
    uint32_t nodes, leaves, depth;
    uint64_t leaf_histogram[CBVH_MAX_LEAF_SIZE + 1]; /* [k]: leaves holding k triangles */
    double mean_leaf_size;
    /* SAH cost relative to the root's area: traversal_cost per internal node plus intersection_cost
     * per triangle of each leaf, each weighted by its box area over the root's area (a root without
     * a box of its own counts at its full area). */
    double sah_cost;       /* with the dequantized boxes (what queries see) */
    double sah_cost_exact; /* with the exact boxes (what quantization costs: the difference) */
    /* had the boxes been stored on a frame per node rather than on the mesh grid: each child's box
     * rounded outward to 65535 (16-bit) or 255 (8-bit) steps per axis of its parent's box as stored, the
     * root's exact (tree_stats.c's frame_sah) */
    double sah_cost_frame16, sah_cost_frame8;
    double inflation_mean, inflation_max; /* over all boxes, see tree_box_inflation */
    double leaf_inflation_mean, internal_inflation_mean;
    uint32_t inflation_max_box;
} tree_stats;

/* Computes everything above in O(nodes + triangles), through the layout interface. Returns 0 when out of memory. */
int tree_stats_compute(const struct cbvh_file *f, double traversal_cost, double intersection_cost,
                       tree_stats *out);

#endif
