/* report_exact.h: the report's reference layout: a cooked tree with float node boxes recomputed exactly from its triangles. */
#ifndef CBVH_TOOLS_REPORT_EXACT_H
#define CBVH_TOOLS_REPORT_EXACT_H

#include <stdint.h>

#include "cbvh.h"

/* The same nodes, triangles and sort bytes as the opened file, but each node's
 * box is the exact float bounds of the decoded triangles below it instead of
 * the 16-bit grid box. Traversed with lib/query's own ray setup, slab test and
 * triangle test, so the only difference from cbvh_raycast is box quantization. */
typedef struct exact_tree {
    const cbvh_file *file; /* not owned; must outlive the tree */
    float *boxes;          /* 6 per box id (layout/tree.h): min x,y,z then max x,y,z */
    uint32_t node_count;
} exact_tree;

/* Returns 1, or 0 when out of memory. */
int exact_tree_build(exact_tree *tree, const cbvh_file *file);
void exact_tree_free(exact_tree *tree);

/* Closest hit and any hit, sorted by the file's sort byte; results and counters
 * as cbvh_raycast / cbvh_occluded with CBVH_TRAVERSAL_SORTED (stats may be NULL). */
int exact_raycast(const exact_tree *tree, const cbvh_ray *ray, cbvh_hit *hit, cbvh_query_stats *stats);
int exact_occluded(const exact_tree *tree, const cbvh_ray *ray, cbvh_query_stats *stats);

/* Quantization inflation of the boxes: tree_stats_compute (tools/tree_stats.h). */

#endif
