/* cbvh_internal.h: the library's introspection for its own tools, tests and report (not installed). */
#ifndef CBVH_INTERNAL_H
#define CBVH_INTERNAL_H

/* What the `cbvh` command, the tests and `cbvh report` need to see inside an opened file beyond the public
 * API: tree statistics, walks on exact boxes, the stored mesh, and the names of format values. It is the
 * one door from tools/ into the library: no tool includes another lib/ header or reads a field of struct
 * cbvh_file.
 *
 * Not part of the API: not installed, names and structs change with the library. The functions are
 * compiled into libcbvh and hidden in the shared library, so a program that calls them links the static
 * library (libtool's -static). Each takes a file cbvh_open* accepted and, like the queries, reads it only:
 * safe from any number of threads on one file. */

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"

/* ---- tree statistics (lib/inspect/tree_stats.c) ---- */

typedef struct cbvh_tree_stats {
    uint32_t nodes, leaves, depth;
    uint64_t leaf_histogram[CBVH_MAX_LEAF_SIZE + 1]; /* [k]: leaves holding k triangles */
    double mean_leaf_size;
    /* SAH cost relative to the root's area: traversal_cost per internal node plus intersection_cost per
     * triangle of each leaf, each weighted by its box area over the root's area (a root without a box of
     * its own counts at its full area). */
    double sah_cost;       /* with the dequantized boxes (what queries see) */
    double sah_cost_exact; /* with the exact boxes (what quantization costs: the difference) */
    /* had the boxes been stored on a frame per node rather than on the mesh grid: each child's box rounded
     * outward to 65535 (16-bit) or 255 (8-bit) steps per axis of its parent's box as stored, the root's
     * exact */
    double sah_cost_frame16, sah_cost_frame8;
    /* surface-area inflation of each box's dequantized box over the exact float bounds of the decoded
     * triangles below it, area(q) / area(exact) - 1 (0 when the exact box has no area), over all boxes */
    double inflation_mean, inflation_max;
    double leaf_inflation_mean, internal_inflation_mean;
    uint32_t inflation_max_box; /* box id of inflation_max: see cbvh_tree_box_place */
} cbvh_tree_stats;

/* Computes every field of *out in O(nodes + triangles) time and O(boxes) memory (malloc). Returns 1, or 0
 * when out of memory. */
int cbvh_tree_stats_compute(const cbvh_file *file, double traversal_cost, double intersection_cost,
                            cbvh_tree_stats *out);

/* Where box id `box` is stored: a binary node carries its own box (*slot = 0); a wide4 node its four
 * children's (slot 0..3). */
void cbvh_tree_box_place(const cbvh_file *file, uint32_t box, uint32_t *node, uint32_t *slot);

/* ---- the exact-box walk (lib/inspect/exact_walk.c) ---- */

/* The file's tree with each box replaced by the exact float bounds of the decoded triangles below it, so
 * that the only difference from cbvh_raycast is box quantization: the same nodes, triangles and child
 * order, walked by the library's sorted walk with its own ray set-up and triangle test. */
typedef struct cbvh_exact_tree {
    const cbvh_file *file; /* not owned; must outlive the tree */
    float *boxes;          /* 6 floats per box id: min x, y, z then max x, y, z */
    uint32_t box_count;
} cbvh_exact_tree;

/* Returns 1, or 0 when out of memory (malloc). O(nodes + triangles). */
int cbvh_exact_tree_build(cbvh_exact_tree *tree, const cbvh_file *file);
void cbvh_exact_tree_free(cbvh_exact_tree *tree);

/* Closest hit and any hit on the exact boxes: results and counters as cbvh_raycast / cbvh_occluded with
 * CBVH_TRAVERSAL_SORTED (stats may be NULL). */
int cbvh_exact_raycast(const cbvh_exact_tree *tree, const cbvh_ray *ray, cbvh_hit *hit,
                       cbvh_query_stats *stats);
int cbvh_exact_occluded(const cbvh_exact_tree *tree, const cbvh_ray *ray, cbvh_query_stats *stats);

/* ---- the stored mesh and format names (lib/inspect/file_view.c) ---- */

/* The indexed mesh the file stores: positions[3 v ...] for each of info.vertex_count vertices as queries
 * decode them, and indices[3 t ...] for each original triangle id t < info.original_triangle_count (ids the
 * cook dropped keep what the caller put there). */
void cbvh_file_mesh(const cbvh_file *file, float *positions, uint32_t *indices);

/* How the file stores material ids; with CBVH_MATERIALS_UNIFORM, *uniform_id (may be NULL) receives the
 * one id. */
typedef enum cbvh_material_storage {
    CBVH_MATERIALS_NONE,        /* every id is 0 */
    CBVH_MATERIALS_UNIFORM,     /* one id for every triangle */
    CBVH_MATERIALS_PER_TRIANGLE /* an id per triangle */
} cbvh_material_storage;
cbvh_material_storage cbvh_file_material_storage(const cbvh_file *file, uint32_t *uniform_id);

/* The name of section type `type`'s element encoding `encoding` ("u16x3", "local8", "wide4-node" ...), of
 * codec `codec` ("raw", "zlib"); "?" when unknown. Static strings. */
const char *cbvh_encoding_name(uint32_t type, uint32_t encoding);
const char *cbvh_codec_name(uint32_t codec);

/* 1 when the `size` bytes at `bytes` begin with the cbvh magic (a file to open rather than import). */
int cbvh_has_magic(const void *bytes, size_t size);
/* Bytes cbvh_has_magic reads. */
#define CBVH_MAGIC_BYTES 8u

/* 1 when the running CPU has AVX2 and FMA and the operating system saves the AVX registers (the library's
 * own detection), else 0: what the bench's tinybvh peer needs. */
int cbvh_cpu_has_avx2_fma(void);

#endif
