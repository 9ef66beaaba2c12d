/* tree_stats.c: exact node boxes recomputed from the triangles, quantization inflation, SAH cost, leaf
 * histogram. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cbvh_internal.h"
#include "inspect/inspect.h"
#include "layout/tree.h"
#include "layout/triangle_encodings.h"

/* Surface area of the box b (min xyz, max xyz) in double. */
static double box_area(const double b[6])
{
    const double dx = b[3] - b[0], dy = b[4] - b[1], dz = b[5] - b[2];
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

static double float_box_area(const float lo[3], const float hi[3])
{
    const double b[6] = {lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]};
    return box_area(b);
}

static void box_empty(float b[6])
{
    for (int a = 0; a < 3; a++) {
        b[a] = FLT_MAX;
        b[3 + a] = -FLT_MAX;
    }
}

static void box_grow(float b[6], const float lo[3], const float hi[3])
{
    for (int a = 0; a < 3; a++) {
        b[a] = lo[a] < b[a] ? lo[a] : b[a];
        b[3 + a] = hi[a] > b[3 + a] ? hi[a] : b[3 + a];
    }
}

/* The exact bounds of the subtree `r` into b, and of each box below it into boxes. The loader
 * bounded the depth, so the recursion is at most CBVH_MAX_DEPTH deep. */
static void exact_subtree(const struct cbvh_file *f, cbvh_ref r, float *boxes, float b[6])
{
    box_empty(b);
    if (cbvh_tree_is_leaf(f, f->layout, r)) {
        uint32_t first, count;
        cbvh_tree_leaf(f, f->layout, r, &first, &count);
        for (uint32_t t = first; t < first + count; t++) {
            float v[3][3];
            cbvh_triangle_vertices(f, t, v[0], v[1], v[2]);
            for (int k = 0; k < 3; k++)
                box_grow(b, v[k], v[k]);
        }
        return;
    }
    struct cbvh_child c[CBVH_TREE_WIDTH];
    const uint32_t n = cbvh_tree_children(f, f->layout, r, CBVH_NO_OCTANT, c);
    for (uint32_t k = 0; k < n; k++) {
        float *cb = boxes + 6 * (size_t)c[k].box;
        exact_subtree(f, c[k].ref, boxes, cb);
        box_grow(b, cb, cb + 3);
    }
}

void cbvh_exact_boxes(const struct cbvh_file *f, float *boxes, float root[6])
{
    const uint32_t root_box = cbvh_tree_root_box(f, f->layout);
    exact_subtree(f, cbvh_tree_root(f, f->layout), boxes, root);
    if (root_box != CBVH_NO_BOX)
        memcpy(boxes + 6 * (size_t)root_box, root, 6 * sizeof(float));
}

static double box_inflation(const struct cbvh_file *f, uint32_t box, const float *exact_boxes)
{
    float lo[3], hi[3];
    cbvh_tree_box(f, f->layout, box, lo, hi);
    const float *e = exact_boxes + 6 * (size_t)box;
    double exact = float_box_area(e, e + 3);
    return exact > 0 ? float_box_area(lo, hi) / exact - 1.0 : 0.0;
}

/* What the recursion over the tree accumulates. */
struct stats_walk {
    const struct cbvh_file *f;
    const float *exact;
    double root_area, root_exact, ct, ci;
    double sum_inflation, sum_leaf_inflation;
    uint64_t boxes, leaf_boxes, leaf_triangles;
    cbvh_tree_stats *out;
};

/* The subtree r, whose box is `box` (CBVH_NO_BOX for a root without one), at depth `depth`. */
static void stats_subtree(struct stats_walk *w, cbvh_ref r, uint32_t box, uint32_t depth)
{
    const struct cbvh_file *f = w->f;
    cbvh_tree_stats *out = w->out;
    const int leaf = cbvh_tree_is_leaf(f, f->layout, r);
    uint32_t first = 0, count = 0;
    if (leaf)
        cbvh_tree_leaf(f, f->layout, r, &first, &count);
    /* depth counts nodes, as the header's does: a wide4 leaf is a slot of its parent, not a node */
    if (!(leaf && f->layout == CBVH_LAYOUT_WIDE4) && depth > out->depth)
        out->depth = depth;
    if (box != CBVH_NO_BOX) {
        float lo[3], hi[3];
        cbvh_tree_box(f, f->layout, box, lo, hi);
        const float *e = w->exact + 6 * (size_t)box;
        const double area = w->root_area > 0 ? float_box_area(lo, hi) / w->root_area : 0;
        const double exact = w->root_exact > 0 ? float_box_area(e, e + 3) / w->root_exact : 0;
        const double inflation = box_inflation(f, box, w->exact);
        const double cost = leaf ? w->ci * count : w->ct;
        w->boxes++;
        w->sum_inflation += inflation;
        if (inflation > out->inflation_max) {
            out->inflation_max = inflation;
            out->inflation_max_box = box;
        }
        out->sah_cost += cost * area;
        out->sah_cost_exact += cost * exact;
        if (leaf) {
            w->leaf_boxes++;
            w->sum_leaf_inflation += inflation;
        }
    } else if (!leaf) {
        out->sah_cost += w->ct; /* a root without a box of its own is entered at its full area */
        out->sah_cost_exact += w->ct;
    }
    if (leaf) {
        out->leaves++;
        out->leaf_histogram[count]++;
        w->leaf_triangles += count;
        return;
    }
    struct cbvh_child c[CBVH_TREE_WIDTH];
    const uint32_t n = cbvh_tree_children(f, f->layout, r, CBVH_NO_OCTANT, c);
    for (uint32_t k = 0; k < n; k++)
        stats_subtree(w, c[k].ref, c[k].box, depth + 1);
}

/* The SAH cost had each box been stored on a frame per node instead of the mesh grid: a child's box
 * rounded outward to `levels` steps per axis of its parent's box as so stored (the root's: its exact box,
 * stored in floats), as a node that carries its own frame would store it. */
struct frame_walk {
    const struct cbvh_file *f;
    const float *exact;
    double root_area, ct, ci, levels, cost;
};

/* Adds to w->cost the children of node r, whose stored box is frame (min xyz, max xyz), and their subtrees,
 * each box weighted as in stats_subtree. */
static void frame_subtree(struct frame_walk *w, cbvh_ref r, const double frame[6])
{
    const struct cbvh_file *f = w->f;
    struct cbvh_child c[CBVH_TREE_WIDTH];
    const uint32_t n = cbvh_tree_children(f, f->layout, r, CBVH_NO_OCTANT, c);
    for (uint32_t k = 0; k < n; k++) {
        const float *e = w->exact + 6 * (size_t)c[k].box;
        double q[6];
        for (int a = 0; a < 3; a++) {
            const double lo = frame[a], step = (frame[3 + a] - lo) / w->levels;
            q[a] = step > 0 ? lo + floor(((double)e[a] - lo) / step) * step : lo;
            q[3 + a] = step > 0 ? lo + ceil(((double)e[3 + a] - lo) / step) * step : frame[3 + a];
            /* inside the frame, and around the exact box whatever the rounding of the steps */
            q[a] = fmin(fmax(q[a], lo), (double)e[a]);
            q[3 + a] = fmax(fmin(q[3 + a], frame[3 + a]), (double)e[3 + a]);
        }
        const double area = box_area(q);
        const int leaf = cbvh_tree_is_leaf(f, f->layout, c[k].ref);
        uint32_t first = 0, count = 0;
        if (leaf)
            cbvh_tree_leaf(f, f->layout, c[k].ref, &first, &count);
        w->cost += (leaf ? w->ci * count : w->ct) * (w->root_area > 0 ? area / w->root_area : 0);
        if (!leaf)
            frame_subtree(w, c[k].ref, q);
    }
}

static double frame_sah(const struct cbvh_file *f, const float *exact, const float root[6], double ct,
                        double ci, double levels)
{
    const double frame[6] = {root[0], root[1], root[2], root[3], root[4], root[5]};
    struct frame_walk w = {f, exact, float_box_area(root, root + 3), ct, ci, levels, ct};
    const cbvh_ref r = cbvh_tree_root(f, f->layout);
    if (cbvh_tree_is_leaf(f, f->layout, r)) { /* a one-leaf tree: its box is the root's */
        uint32_t first, count;
        cbvh_tree_leaf(f, f->layout, r, &first, &count);
        return ci * count;
    }
    frame_subtree(&w, r, frame);
    return w.cost;
}

int cbvh_tree_stats_compute(const struct cbvh_file *f, double traversal_cost, double intersection_cost,
                            cbvh_tree_stats *out)
{
    const uint32_t box_count = cbvh_tree_box_count(f, f->layout);
    float *boxes = malloc(6 * (size_t)box_count * sizeof(float));
    if (!boxes)
        return 0;
    memset(out, 0, sizeof *out);
    float root[6], qlo[3], qhi[3];
    cbvh_exact_boxes(f, boxes, root);
    const uint32_t root_box = cbvh_tree_root_box(f, f->layout);
    if (root_box != CBVH_NO_BOX)
        cbvh_tree_box(f, f->layout, root_box, qlo, qhi);
    else
        memcpy(qlo, root, sizeof qlo), memcpy(qhi, root + 3, sizeof qhi);
    struct stats_walk w = {f,
                           boxes,
                           float_box_area(qlo, qhi),
                           float_box_area(root, root + 3),
                           traversal_cost,
                           intersection_cost,
                           0,
                           0,
                           0,
                           0,
                           0,
                           out};
    stats_subtree(&w, cbvh_tree_root(f, f->layout), root_box, 1);
    out->sah_cost_frame16 = frame_sah(f, boxes, root, traversal_cost, intersection_cost, 65535.0);
    out->sah_cost_frame8 = frame_sah(f, boxes, root, traversal_cost, intersection_cost, 255.0);
    out->nodes = f->info.node_count;
    out->mean_leaf_size = out->leaves ? (double)w.leaf_triangles / out->leaves : 0;
    out->inflation_mean = w.boxes ? w.sum_inflation / (double)w.boxes : 0;
    out->leaf_inflation_mean = w.leaf_boxes ? w.sum_leaf_inflation / (double)w.leaf_boxes : 0;
    out->internal_inflation_mean =
        w.boxes > w.leaf_boxes ? (w.sum_inflation - w.sum_leaf_inflation) / (double)(w.boxes - w.leaf_boxes)
                               : 0;
    free(boxes);
    return 1;
}

void cbvh_tree_box_place(const struct cbvh_file *f, uint32_t box, uint32_t *node, uint32_t *slot)
{
    const int wide = f->layout == CBVH_LAYOUT_WIDE4;
    *node = wide ? box / CBVH_W4_WIDTH : box;
    *slot = wide ? box % CBVH_W4_WIDTH : 0;
}
