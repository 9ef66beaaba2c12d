/* cook_internal.h: the data handed from one cooking phase to the next (prepare, build, quantize, layout,
 * write). */
#ifndef CBVH_COOK_INTERNAL_H
#define CBVH_COOK_INTERNAL_H

#include <stdint.h>

#include "cbvh.h"
#include "common/alloc.h"
#include "common/format.h"
#include "layout/binary.h"
#include "layout/wide4.h"

/* The user's progress callback, bound to the phase being reported. */
typedef struct cook_progress {
    cbvh_progress_fn fn;
    void *user;
    cbvh_phase phase;
} cook_progress;

static inline void cook_report(const cook_progress *p, double fraction)
{
    if (p && p->fn)
        p->fn(p->user, p->phase, fraction);
}

/* ---- prepare: validated, welded mesh without degenerate triangles or unused vertices ---- */

typedef struct cook_mesh {
    float *positions;        /* vertex_count xyz; replaced by decoded grid positions for quantized vertices */
    int positions_for_build; /* 1: only the build reads them (the file stores grid coordinates) */
    uint32_t vertex_count;
    uint32_t *indices; /* 3 per kept triangle, in the input's corner order; NULL while shelved */
    uint32_t triangle_count;
    uint32_t input_triangle_count;
    uint64_t dropped_degenerate;
    uint64_t flushed_coordinates; /* used coordinates below CBVH_COORDINATE_MIN in magnitude, stored as 0 */
    uint32_t *dropped; /* the dropped_degenerate input ids of the dropped triangles, increasing: kept
                        * triangles are the others, in order (cbvh_cook_original_id), and few are
                        * dropped where a list of every kept one would take 4 bytes a triangle */
    float bounds_min[3], bounds_max[3];
    uint32_t *vertex_map; /* input vertex -> prepared vertex, from which the indices are restored;
                           * kept only when smaller than them, else NULL */
} cook_mesh;

/* Validates and cleans `mesh` (see mesh_prepare.c). On failure `out` holds nothing. */
cbvh_result cbvh_cook_prepare(const cbvh_mesh *mesh, const cbvh_allocator *a, const cook_progress *progress,
                              cook_mesh *out, cbvh_error *err);
void cbvh_cook_mesh_free(const cbvh_allocator *a, cook_mesh *m);

/* The build needs the triangles only for their boxes, so while it holds its largest buffers the vertex
 * map stands in for the indices (4 bytes an input vertex instead of 12 a triangle). shelve frees the
 * indices when there is a map, and the positions when only the build reads them; restore computes the
 * indices again from the input mesh (the same one prepared) and frees the map. */
void cbvh_cook_mesh_shelve_triangles(cook_mesh *m, const cbvh_allocator *a);
cbvh_result cbvh_cook_mesh_restore_triangles(cook_mesh *m, const cbvh_mesh *input, const cbvh_allocator *a,
                                             cbvh_error *err);

/* The input id of kept triangle t: t plus the number of dropped ids below it. dropped[j] - j, the kept
 * triangles before dropped[j], never decreases, and is <= t exactly for the dropped ids below t's. */
static inline uint32_t cbvh_cook_original_id(const cook_mesh *m, uint32_t t)
{
    size_t lo = 0, hi = (size_t)m->dropped_degenerate;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (m->dropped[mid] - mid <= t)
            lo = mid + 1;
        else
            hi = mid;
    }
    return t + (uint32_t)lo;
}

/* Drops the kept triangles whose current positions have zero area (quantized
 * vertices can collapse a small triangle onto a segment or a point), keeping
 * the order, and counts them in dropped_degenerate. Vertices only they used
 * stay in positions; the layout writes used vertices only. */
cbvh_result cbvh_cook_drop_collapsed(cook_mesh *m, const cbvh_allocator *a, cbvh_error *err);

/* Sets m->bounds_min/max from the positions the triangles use; CBVH_ERROR_BAD_MESH when an extent overflows a
 * float. */
cbvh_result cbvh_cook_mesh_bounds(cook_mesh *m, cbvh_error *err);

/* ---- quantize: the file's 16-bit grid (spec section 6) ---- */

typedef struct cook_grid {
    float origin[3];
    float scale[3];
} cook_grid;

/* grid_origin = bmin, grid_scale = smallest float with deq(65535) >= bmax.
 * Fails with CBVH_ERROR_BAD_MESH when no finite scale reaches bmax. */
cbvh_result cbvh_cook_grid_init(cook_grid *g, const float bmin[3], const float bmax[3], cbvh_error *err);

/* Conservative box: qmin the largest q with deq(q) <= lo, qmax the smallest q >= qmin with deq(q) >= hi.
 * Precondition: bmin <= lo <= hi <= bmax of the grid's bounds. */
void cbvh_cook_quantize_box(const cook_grid *g, const float lo[3], const float hi[3], uint16_t qmin[3],
                            uint16_t qmax[3]);

/* Half the surface area of a quantized box as readers decode it (the SAH's and the collapse's measure). */
double cbvh_cook_quantized_half_area(const cook_grid *g, const uint16_t qmin[3], const uint16_t qmax[3]);

/* Moves every position to its nearest grid point: writes the grid coordinates to q (3 per vertex)
 * and the decoded values back into positions. Returns the largest |decoded - input|. */
double cbvh_cook_quantize_vertices(const cook_grid *g, float *positions, uint16_t *q, uint32_t count);

/* ---- build: binned SAH tree over the prepared triangles ---- */

typedef struct cook_build_params {
    uint32_t max_leaf_size;
    uint32_t bins;
    float traversal_cost;
    float intersection_cost;
} cook_build_params;

/* A build node. Internal: count == 0 and the children are nodes child and child + 1.
 * Leaf: count triangles tree.prims[child .. child + count). Boxes are exact float bounds. */
typedef struct cook_bnode {
    float lo[3], hi[3];
    uint32_t child;
    uint32_t count;
} cook_bnode;

typedef struct cook_tree {
    cook_bnode *nodes; /* root at 0; a parent's index is below its children's */
    uint32_t node_count;
    uint32_t leaf_count;
    uint32_t *prims; /* prepared triangle ids, leaves' ranges index this */
} cook_tree;

/* Shelves m's triangles (cbvh_cook_mesh_shelve_triangles) once it has their boxes. */
cbvh_result cbvh_cook_build(cook_mesh *m, const cook_build_params *params, const cbvh_allocator *a,
                            const cook_progress *progress, cook_tree *out, cbvh_error *err);
void cbvh_cook_tree_free(const cbvh_allocator *a, cook_tree *t);

/* ---- layout: depth-first file order ---- */

typedef struct cook_layout {
    uint32_t layout; /* cbvh_layout */
    void *nodes;     /* node_count nodes, final: binary: cbvh_node structs in depth-first order;
                      * wide4: the file's 64-byte nodes, breadth first (layout/wide4.h) */
    uint32_t node_count;
    uint32_t leaf_count;
    uint32_t depth;
    uint32_t max_leaf_count; /* largest leaf */
    uint32_t triangle_count;
    uint32_t *triangles;        /* 3 per cooked triangle, new vertex ids (first-use order) */
    uint32_t triangle_encoding; /* CBVH_TRIS_* the TRIANGLES section stores them in (the fewest bytes) */
    uint32_t *triangle_source;  /* cooked triangle -> prepared triangle id */
    uint32_t vertex_count;
    uint32_t *vertex_source; /* new vertex id -> prepared vertex id */
    double sah_cost;         /* of the quantized tree, relative to the root's area */
} cook_layout;

/* The layout in two steps, so that the tree is freed before the triangles are numbered. place: out's nodes
 * and triangle_source from the tree (on failure out holds nothing); number: the vertices in first-use
 * order, the triangles by their ids and the TRIANGLES encoding (on failure l keeps what it held). */
cbvh_result cbvh_cook_layout_place(const cook_tree *t, uint32_t triangle_count, const cook_grid *g,
                                   cbvh_layout layout, float traversal_cost, float intersection_cost,
                                   const cbvh_allocator *a, cook_layout *out, cbvh_error *err);
cbvh_result cbvh_cook_layout_number(const cook_mesh *m, uint32_t vertex_size, const cbvh_allocator *a,
                                    cook_layout *l, cbvh_error *err);

/* The wide layout's placement (place_wide4.c): fills out's nodes, node and leaf counts, depth, largest
 * leaf, SAH cost and triangle_source (out->triangle_count set, triangle_source NULL on entry). */
cbvh_result cbvh_cook_place_wide4(const cook_tree *t, const cook_grid *g, float traversal_cost,
                                  float intersection_cost, const cbvh_allocator *a, cook_layout *out,
                                  cbvh_error *err);
void cbvh_cook_layout_free(const cbvh_allocator *a, cook_layout *l);

/* ---- sections: little-endian payloads in the narrowest encoding the spec allows ---- */

enum {
    COOK_SLOT_NODES,
    COOK_SLOT_TRIANGLES,
    COOK_SLOT_VERTICES,
    COOK_SLOT_REMAP,
    COOK_SLOT_MATERIALS,
    COOK_SLOT_MATERIAL_NAMES,
    COOK_SLOTS
};

typedef struct cook_section {
    uint32_t type; /* cbvh_section_type */
    uint32_t encoding;
    uint8_t *data; /* owned, `size` bytes */
    uint64_t size;
} cook_section;

typedef struct cook_sections {
    cook_section s[COOK_SLOTS];
    uint32_t count; /* present sections, s[0 .. count) in file order */
    uint32_t original_triangle_count;
} cook_sections;

/* Bytes of the MATERIAL_NAMES section for o's names, counting an exact repeat once each time (an upper
 * bound, checked against CBVH_MAX_MATERIAL_NAME_BYTES before the cook starts). */
uint64_t cbvh_cook_material_names_size(const cbvh_cook_options *o);

/* quantized: the 3 grid coordinates per prepared vertex, or NULL for float vertices. The wide4 nodes
 * become their section and the triangles are freed once encoded (l's other fields stay). */
cbvh_result cbvh_cook_sections_encode(cook_layout *l, const cook_mesh *m, const uint16_t *quantized,
                                      const cbvh_mesh *input, const cbvh_cook_options *o,
                                      const cbvh_allocator *a, cook_sections *out, cbvh_error *err);
void cbvh_cook_sections_free(const cbvh_allocator *a, cook_sections *s);

/* ---- write: header, table, aligned (optionally zlib) sections, CRCs ---- */

typedef struct cook_header {
    uint32_t incompat_flags; /* CBVH_INCOMPAT_* */
    uint32_t triangle_count, vertex_count, node_count, depth, max_leaf_size, original_triangle_count;
    float grid_origin[3], grid_scale[3];
    float bounds_min[3], bounds_max[3];
} cook_header;

/* Writes the whole file into one buffer (64-byte aligned) from meter->inner, the caller's allocator;
 * its temporaries come through the meter, and each section's data is freed as soon as it is stored
 * (the sections keep their types and sizes). stored_size[type] and size[type] receive each section's
 * sizes (indexed by section type). */
cbvh_result cbvh_cook_write_file(const cook_header *h, cook_sections *s, int compress_level,
                                 cbvh_meter *meter, const cook_progress *progress, uint8_t **out,
                                 size_t *out_size, uint64_t stored_size[CBVH_STATS_SECTION_TYPES],
                                 uint64_t size[CBVH_STATS_SECTION_TYPES], cbvh_error *err);

#endif
