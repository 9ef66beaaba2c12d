/* tree_stats.c: exact node boxes recomputed from the triangles, quantization inflation, SAH cost, leaf histogram. */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "tree_stats.h"

uint32_t tree_escape(const struct cbvh_file *f, uint32_t i)
{
    uint32_t word = f->nodes[i].word;
    return i + (cbvh_node_is_leaf(word) ? 1u : cbvh_node_subtree_size(word));
}

double tree_box_area(const float lo[3], const float hi[3])
{
    double dx = (double)hi[0] - lo[0], dy = (double)hi[1] - lo[1], dz = (double)hi[2] - lo[2];
    return 2.0 * (dx * dy + dy * dz + dz * dx);
}

void tree_exact_boxes(const struct cbvh_file *f, float *boxes)
{
    const uint32_t n = f->info.node_count;
    /* Children come after their parent in depth-first order, so one backward pass sees
     * every child's box before its parent needs it. */
    for (uint32_t i = n; i-- > 0;) {
        uint32_t word = f->nodes[i].word;
        float *b = boxes + 6 * (size_t)i;
        if (cbvh_node_is_leaf(word)) {
            for (int a = 0; a < 3; a++) {
                b[a] = FLT_MAX;
                b[3 + a] = -FLT_MAX;
            }
            uint32_t first = cbvh_leaf_first(word), count = cbvh_leaf_count(word);
            for (uint32_t t = first; t < first + count; t++) {
                float v[3][3];
                cbvh_triangle_vertices(f, t, v[0], v[1], v[2]);
                for (int k = 0; k < 3; k++)
                    for (int a = 0; a < 3; a++) {
                        if (v[k][a] < b[a])
                            b[a] = v[k][a];
                        if (v[k][a] > b[3 + a])
                            b[3 + a] = v[k][a];
                    }
            }
        } else {
            uint32_t c0 = i + 1, c1 = tree_escape(f, c0);
            const float *b0 = boxes + 6 * (size_t)c0, *b1 = boxes + 6 * (size_t)c1;
            for (int a = 0; a < 3; a++) {
                b[a] = b0[a] < b1[a] ? b0[a] : b1[a];
                b[3 + a] = b0[3 + a] > b1[3 + a] ? b0[3 + a] : b1[3 + a];
            }
        }
    }
}

double tree_node_inflation(const struct cbvh_file *f, uint32_t i, const float *exact_boxes)
{
    float lo[3], hi[3];
    cbvh_node_box(f, &f->nodes[i], lo, hi);
    const float *e = exact_boxes + 6 * (size_t)i;
    double exact = tree_box_area(e, e + 3);
    return exact > 0 ? tree_box_area(lo, hi) / exact - 1.0 : 0.0;
}

int tree_stats_compute(const struct cbvh_file *f, double traversal_cost, double intersection_cost,
                       tree_stats *out)
{
    const uint32_t n = f->info.node_count;
    float *boxes = malloc(6 * (size_t)n * sizeof(float));
    uint8_t *depth = malloc(n);
    if (!boxes || !depth) {
        free(boxes);
        free(depth);
        return 0;
    }
    memset(out, 0, sizeof *out);
    tree_exact_boxes(f, boxes);

    float rlo[3], rhi[3];
    cbvh_node_box(f, &f->nodes[0], rlo, rhi);
    double root_area = tree_box_area(rlo, rhi), root_exact = tree_box_area(boxes, boxes + 3);
    double sum_inflation = 0, sum_leaf_inflation = 0;
    uint64_t leaf_triangles = 0;
    depth[0] = 1;
    for (uint32_t i = 0; i < n; i++) {
        uint32_t word = f->nodes[i].word;
        float lo[3], hi[3];
        cbvh_node_box(f, &f->nodes[i], lo, hi);
        const float *e = boxes + 6 * (size_t)i;
        double area = root_area > 0 ? tree_box_area(lo, hi) / root_area : 0;
        double exact = root_exact > 0 ? tree_box_area(e, e + 3) / root_exact : 0;
        double inflation = tree_node_inflation(f, i, boxes);
        sum_inflation += inflation;
        if (inflation > out->inflation_max) {
            out->inflation_max = inflation;
            out->inflation_max_node = i;
        }
        if (depth[i] > out->depth)
            out->depth = depth[i];
        if (cbvh_node_is_leaf(word)) {
            uint32_t count = cbvh_leaf_count(word);
            out->leaves++;
            out->leaf_histogram[count]++;
            leaf_triangles += count;
            out->sah_cost += intersection_cost * count * area;
            out->sah_cost_exact += intersection_cost * count * exact;
            sum_leaf_inflation += inflation;
        } else {
            /* The loader checked the links and the depth limit, so children are in range. */
            uint32_t c0 = i + 1, c1 = tree_escape(f, c0);
            depth[c0] = depth[c1] = (uint8_t)(depth[i] + 1);
            out->sah_cost += traversal_cost * area;
            out->sah_cost_exact += traversal_cost * exact;
        }
    }
    out->nodes = n;
    out->mean_leaf_size = out->leaves ? (double)leaf_triangles / out->leaves : 0;
    out->inflation_mean = n ? sum_inflation / n : 0;
    out->leaf_inflation_mean = out->leaves ? sum_leaf_inflation / out->leaves : 0;
    out->internal_inflation_mean = n > out->leaves ? (sum_inflation - sum_leaf_inflation) / (n - out->leaves) : 0;
    free(boxes);
    free(depth);
    return 1;
}
