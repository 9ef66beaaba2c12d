/* inspect.h: what the introspection modules (cbvh_internal.h) share among themselves. */
#ifndef CBVH_INSPECT_INSPECT_H
#define CBVH_INSPECT_INSPECT_H

#include "common/file.h"

/* Fills boxes[6 b .. 6 b + 6) (min xyz, max xyz) for every box id b of the tree (layout/tree.h) with the
 * exact float bounds of the decoded vertices of every triangle below it, and root[6] with those of the
 * whole tree. boxes holds 6 * cbvh_tree_box_count floats. O(nodes + triangles); recursion as deep as the
 * tree, which the loader bounded. */
void cbvh_exact_boxes(const struct cbvh_file *f, float *boxes, float root[6]);

#endif
