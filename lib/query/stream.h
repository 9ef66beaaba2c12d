/* stream.h: the ray batch shared by the stream traversal and its scalar and SIMD box-test kernels. */
#ifndef CBVH_QUERY_STREAM_H
#define CBVH_QUERY_STREAM_H

#include <stddef.h>
#include <stdint.h>

#include "query/leaf.h"
#include "query/ray_setup.h"
#include "query/walk.h"

/* One ray as the box test reads it: 32 bytes, two SSE2 loads. */
enum {
    CBVH_LANE_OX,
    CBVH_LANE_OY,
    CBVH_LANE_OZ,
    CBVH_LANE_TMIN,
    CBVH_LANE_RX,
    CBVH_LANE_RY,
    CBVH_LANE_RZ,
    CBVH_LANE_TMAX
};

/* Rays per batch on the stream's own stack, and at most in caller scratch (16-bit ray lists). */
#define CBVH_STREAM_STACK_BATCH 24u
#define CBVH_STREAM_MAX_BATCH 4096u

/* The most children a node test takes (CBVH_TREE_WIDTH): one SSE2 vector of boxes per ray. */
#define CBVH_STREAM_LANES 4u

/* Rays an interleaved stream walks at once: in the caller's scratch, and on the stream's own stack. */
#define CBVH_STREAM_WALKS 8u
#define CBVH_STREAM_STACK_WALKS 4u

/* A ray's single-ray walk in progress and its best hit: a slot of the interleaved walks, or (the first) a
 * batch ray finishing a subtree alone. */
struct cbvh_stream_walk {
    struct cbvh_walk_state walk;
    struct cbvh_best_hit best;
    cbvh_ref fetched; /* the leaf whose vertices were last requested (stream_walk.h) */
};

/* Up to `capacity` rays of one octant, in one block cut by stream.c. */
struct cbvh_stream_batch {
    float (*box_ray)[8];      /* CBVH_LANE_*, 32-byte aligned; TMAX shrinks with hits, -1 once occluded */
    struct cbvh_ray_ctx *ctx; /* the prepared rays (triangle test, walks alone) */
    struct cbvh_best_hit *best;
    size_t *ray_index;              /* position in the caller's arrays */
    uint16_t *list_ray;             /* the walk's ray lists, a stack of them (stream.c): batch positions, */
    float *list_entry;              /* and where each ray enters the list's box */
    struct cbvh_stream_walk *walks; /* walk_count slots */
    uint32_t walk_count;
    uint32_t list_capacity; /* entries in list_ray and list_entry */
    uint32_t shrinks;       /* changes whenever a ray's TMAX may shrink: a list made at its value is exact */
    uint32_t count, capacity;
};

/* A node's child boxes dequantized once per batch visit: plane[p][k] is plane p (near x, y, z, far x, y,
 * z for the batch's octant) of child k. */
struct cbvh_stream_boxes {
    _Alignas(16) float plane[6][CBVH_STREAM_LANES];
    uint32_t count; /* children, at most CBVH_STREAM_LANES; the planes of the other lanes are 0 */
};

/* Where a node test puts the j-th ray entering box k (ray[k][j], entry[k][j]); each list has room for every
 * ray, and lanes past the boxes' count point to one writable element each. */
struct cbvh_stream_lists {
    uint16_t *ray[CBVH_STREAM_LANES];
    float *entry[CBVH_STREAM_LANES];
};

/* A node kernel `name`: tests the rays batch->box_ray[rays[j]], j < n, against every box of `boxes` with
 * the arithmetic of ray_box.h, each ray's current [TMIN, TMAX], and puts the ray, in the order of `rays`,
 * on the list of each box it enters; count[k] receives the length of list k. */
#define CBVH_STREAM_NODE_KERNEL(name)                                                                        \
    void name(const struct cbvh_stream_batch *restrict batch, const uint16_t *restrict rays, uint32_t n,     \
              const struct cbvh_stream_boxes *restrict boxes, const struct cbvh_stream_lists *restrict out,  \
              uint32_t count[CBVH_STREAM_LANES])
typedef CBVH_STREAM_NODE_KERNEL((*cbvh_stream_node_fn));
CBVH_STREAM_NODE_KERNEL(cbvh_stream_node_scalar);
#ifdef CBVH_HAVE_SIMD
CBVH_STREAM_NODE_KERNEL(cbvh_stream_node_sse2);
#endif
#ifdef CBVH_HAVE_AVX2
/* The SSE2 kernel in AVX2's encoding for the AVX2 stream walks (SSE2 code after AVX stalls on some CPUs). */
CBVH_STREAM_NODE_KERNEL(cbvh_stream_node_avx2);
#endif

/* The streams' node kernel: the best this build has (kernel_choice.c), or a test hook's (test_hooks.h). */
cbvh_stream_node_fn cbvh_stream_node_kernel(void);

/* How the streams walk a window of rays: in batches; interleaved (wide layout); or by the window's
 * coherence, coherent ones in batches, the others interleaved (BY_WINDOW) or one at a time (_SINGLE). */
enum cbvh_stream_way {
    CBVH_STREAM_BATCHED,
    CBVH_STREAM_INTERLEAVED,
    CBVH_STREAM_BY_WINDOW,
    CBVH_STREAM_BY_WINDOW_SINGLE
};

/* A mesh in the caches batches its incoherent rays (wide layout) at most this many triangles a batch ray. */
#define CBVH_STREAM_SHARED_TRIANGLES_PER_RAY 8u

/* The way of f's streams in batches of batch_capacity rays (or a test hook's). */
enum cbvh_stream_way cbvh_stream_way_for(const struct cbvh_file *f, uint32_t batch_capacity);

/* Whether the n rays of a window look coherent (stream.c: then they are batched). */
int cbvh_stream_window_coherent(const cbvh_ray *rays, uint32_t n);

#endif
