/* stream.c: batched ray streams: one traversal per batch of same-octant rays, a ray list per child entered. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include <string.h>

#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/stream.h"

/* Rays are grouped by octant within windows of this many input rays per batch ray (8: one batch an
 * octant), so a batch shares one sort-byte mask and one near/far plane selection. */
#define CBVH_STREAM_WINDOW_PER_RAY 8u

/* Entries of the walk's stack of ray lists per batch ray: the root's list and its children's take 5 a ray
 * (the wide layout's four lists, each with room for every ray, above the root's), and the lists of the
 * pending children below shrink fast on incoherent rays; a node whose lists would not fit sends its rays
 * down the single-ray walk. */
#define STREAM_LIST_PER_RAY 8u

/* Bytes a batch ray takes in the block (the window's octant bytes included), and the alignment slack. */
#define STREAM_RAY_BYTES                                                                                         \
    (8 * sizeof(float) + sizeof(struct cbvh_ray_ctx) + sizeof(struct cbvh_best_hit) + sizeof(size_t) +          \
     STREAM_LIST_PER_RAY * (sizeof(float) + sizeof(uint16_t)) + CBVH_STREAM_WINDOW_PER_RAY)
#define STREAM_SLACK 64u

/* A batch node with at most this many live rays hands them to the single-ray
 * walk: below it the batch would mostly carry one ray per node, paying the
 * partition and stack bookkeeping without sharing any node fetch. */
#ifndef CBVH_STREAM_SOLO
#define CBVH_STREAM_SOLO 4
#endif

/* Ray r of the batch finishes the subtree of node `root` alone, starting
 * from its current tmax; its best hit (or occlusion) goes back to the batch.
 * The single-ray walk uses the same triangle test and tie rule, so the result
 * does not depend on where the batch handed the ray over. */
static void solo_tail(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t r, uint32_t root, int any,
                      uint8_t *occluded, cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx = b->ctx[r];
    float *box_ray = b->box_ray[r];
    ctx.tmax = box_ray[CBVH_LANE_TMAX];
    if (any) {
        if (cbvh_any_subtree(f, &ctx, root, stats)) {
            occluded[b->ray_index[r]] = 1;
            box_ray[CBVH_LANE_TMAX] = -1.0f;
            b->shrinks++;
        }
        return;
    }
    cbvh_closest_subtree(f, &ctx, root, &b->best[r], stats);
    if (b->best[r].tri != UINT32_MAX && b->best[r].t != box_ray[CBVH_LANE_TMAX]) {
        /* its t is the ray's tmax: never above the one the walk started with */
        box_ray[CBVH_LANE_TMAX] = b->best[r].t;
        b->shrinks++;
    }
}

/* Ray r of the batch, whose test of triangle k found `hit` at t (u, v): an occlusion, or a closer best
 * hit. */
CBVH_KERNEL void stream_take(struct cbvh_stream_batch *restrict b, uint32_t r, uint32_t k, int hit, float t,
                             float u, float v, int any, uint8_t *restrict occluded)
{
    if (!hit)
        return;
    float *box_ray = b->box_ray[r];
    if (any) {
        /* Occluded: a negative tmax fails every later box and triangle test. */
        occluded[b->ray_index[r]] = 1;
        box_ray[CBVH_LANE_TMAX] = -1.0f;
        b->shrinks++;
    } else if (cbvh_hit_better(t, k, box_ray[CBVH_LANE_TMAX], b->best[r].tri)) {
        box_ray[CBVH_LANE_TMAX] = t;
        b->shrinks++;
        b->best[r].tri = k;
        b->best[r].t = t;
        b->best[r].u = u;
        b->best[r].v = v;
    }
}

/* The live rays live[0, m) against the leaf's triangles [tri0, tri0 + count). With SIMD the leaf is
 * gathered once per batch visit, four triangles a vector (leaf.h), and each ray runs the four-wide
 * filter on it, the scalar test deciding only the lanes it keeps: the gather, most of a single ray's
 * leaf cost, is shared by the batch. Without, triangles outside and rays inside, each triangle fetched
 * once. Each ray meets its triangles in index order either way, and the tie rule makes its answer the
 * single-ray walk's. Expanded triangles (cbvh_file_expand_triangles) are read in place instead. */
CBVH_KERNEL void stream_leaf(const struct cbvh_file *f, struct cbvh_stream_batch *restrict b,
                             const uint16_t *restrict live, uint32_t m, uint32_t tri0, uint32_t count, const int any,
                             int simd, uint8_t *restrict occluded)
{
    float a[3], v1[3], v2[3];
#ifdef CBVH_HAVE_SIMD
    if (simd && count > 1) {
        struct leaf_quad scratch[CBVH_LEAF_GROUPS][CBVH_LEAF_QUADS];
        struct leaf_group q[CBVH_LEAF_GROUPS];
        uint32_t group_first[CBVH_LEAF_GROUPS], groups = 0;
        const uint32_t end = tri0 + count;
        const struct leaf_quad *quads = (const struct leaf_quad *)f->quads;
        for (uint32_t k = leaf_groups_begin(quads, tri0); k < end; k += CBVH_LANES, groups++) {
            group_first[groups] = k;
            leaf_group_lanes(quads, f->triangles, (int)f->triangle_encoding, f->vertices,
                             (int)f->vertex_encoding, f->grid_origin, f->grid_scale, tri0, end, k,
                             scratch[groups], &q[groups]);
        }
        for (uint32_t j = 0; j < m; j++) {
            const uint32_t r = live[j];
            const struct cbvh_ray_shear *s = &b->ctx[r].shear;
            for (uint32_t g = 0; g < groups; g++) {
                float edge[3][CBVH_LANES];
                uint32_t within;
                const float *box_ray = b->box_ray[r];
                /* an occlusion: the filter's t test on the ray's range, a lane it accepts ends the ray
                 * (leaf_reject_lanes); a closest hit: the plain filter (a ray's entry into the leaf is not
                 * kept here) */
                const uint32_t rejected = leaf_reject_lanes(s, &q[g], any, box_ray[CBVH_LANE_TMIN],
                                                            box_ray[CBVH_LANE_TMAX], edge, &within);
                if (any && (within & q[g].mask)) {
                    stream_take(b, r, group_first[g] + lanes_lowest(within & q[g].mask), 1, 0.0f, 0.0f, 0.0f,
                                any, occluded);
                    break;
                }
                /* the lanes the filter keeps, lowest first */
                for (uint32_t kept = ~rejected & q[g].mask; kept; kept &= kept - 1u) {
                    const uint32_t lane = lanes_lowest(kept);
                    float t, u, v;
                    const int hit = leaf_lane_test(s, &q[g], edge, lane, box_ray[CBVH_LANE_TMIN],
                                                   box_ray[CBVH_LANE_TMAX], !any, &t, &u, &v);
                    stream_take(b, r, group_first[g] + lane, hit, t, u, v, any, occluded);
                }
            }
        }
        return;
    }
#else
    (void)simd;
#endif
    for (uint32_t k = tri0; k < tri0 + count; k++) {
        cbvh_triangle_vertices(f, k, a, v1, v2);
        for (uint32_t j = 0; j < m; j++) {
            const uint32_t r = live[j];
            const float *box_ray = b->box_ray[r];
            float t, u, v;
            const int hit = cbvh_ray_triangle(&b->ctx[r].shear, a, v1, v2, box_ray[CBVH_LANE_TMIN],
                                              box_ray[CBVH_LANE_TMAX], !any, &t, &u, &v);
            stream_take(b, r, k, hit, t, u, v, any, occluded);
        }
    }
}

/* The boxes of children c[0, k) for the batch's octant (`sel`), dequantized with the arithmetic of
 * ray_box.h. */
CBVH_KERNEL void stream_boxes_of(const struct cbvh_file *restrict f, const uint32_t layout,
                                 const struct cbvh_slab_select sel, const struct cbvh_child *c, uint32_t k,
                                 struct cbvh_stream_boxes *restrict boxes)
{
    const uint32_t coord[6] = {sel.near_x, sel.near_y, sel.near_z, sel.far_x, sel.far_y, sel.far_z};
    memset(boxes->plane, 0, sizeof boxes->plane);
    for (uint32_t j = 0; j < k; j++)
        for (uint32_t p = 0; p < 6; p++)
            boxes->plane[p][j] = cbvh_dequantize(cbvh_tree_box_coord(f, layout, c[j].box, coord[p]),
                                                 f->grid_origin[p % 3], f->grid_scale[p % 3]);
    boxes->count = k;
}

/* The rays of list[0, n) that still reach their entry distance (the padded test of ray_box.h with the
 * ray's current tmax), kept in order at the front; returns how many. */
CBVH_KERNEL uint32_t stream_still_in_reach(const struct cbvh_stream_batch *restrict b, uint16_t *restrict ray,
                                           float *restrict entry, uint32_t n)
{
    uint32_t w = 0;
    for (uint32_t j = 0; j < n; j++) {
        const uint16_t r = ray[j];
        const float e = entry[j];
        ray[w] = r;
        entry[w] = e;
        w += e <= b->box_ray[r][CBVH_LANE_TMAX] * CBVH_BOX_PAD;
    }
    return w;
}

/* Walks the tree once for the batch. A node's children are tested at the
 * node, each live ray against all of their boxes at once (the planes
 * dequantized once per visit), and each child entered gets the list of its
 * rays with their entry distances. The lists form a stack in
 * b->list_ray/list_entry beside the walk's stack of children: the lists of a
 * node's children replace its own, a child's above its later siblings', so
 * popping a child frees everything above its list. A child popped after some
 * ray's tmax shrank drops the rays no longer in reach, as the single-ray walk
 * drops a popped child; a list too large for what is left of the stack sends
 * its node's rays down the single-ray walk. The triangle test and the tie
 * rule are those of the single-ray walks, so every ray gets the same hit.
 * Children come through the layout interface (layout/tree.h) in the
 * precomputed order of the batch's octant. */
CBVH_KERNEL void stream_walk(const struct cbvh_file *restrict f, const uint32_t layout,
                             struct cbvh_stream_batch *restrict b, uint32_t octant,
                             cbvh_stream_node_fn node_test, const int any, int counting,
                             uint8_t *restrict occluded, uint64_t *restrict visited,
                             uint64_t *restrict tested)
{
    /* the scalar node kernel (the fallback, and its test) comes with scalar leaves */
    const int simd_leaves = node_test != cbvh_stream_node_scalar;
    cbvh_query_stats solo = {0, 0};
    const struct cbvh_slab_select sel = cbvh_slab_select_of(octant);
    uint16_t *restrict list_ray = b->list_ray;
    float *restrict list_entry = b->list_entry;
    struct {
        cbvh_ref ref;
        uint32_t start;   /* its list: list_ray[start, start + count) */
        uint16_t count;
        uint16_t shrinks; /* b->shrinks when the list was made (mod 2^16: a wrap costs a recheck skipped) */
    } stack[(CBVH_TREE_WIDTH - 1u) * CBVH_MAX_DEPTH + 1u];
    uint16_t sink_ray;
    float sink_entry;
    struct cbvh_stream_boxes boxes;
    struct cbvh_stream_lists lists;
    struct cbvh_child c[CBVH_TREE_WIDTH];
    uint32_t sp = 0, count[CBVH_STREAM_LANES];
    uint64_t nv = 0, nt = 0;

    /* The root's list: every ray, through the root box when the layout has one. */
    for (uint32_t j = 0; j < b->count; j++)
        list_ray[j] = (uint16_t)j;
    uint32_t start = 0, n = b->count;
    cbvh_ref r = cbvh_tree_root(f, layout);
    const uint32_t root_box = cbvh_tree_root_box(f, layout);
    if (root_box != CBVH_NO_BOX) {
        c[0].box = root_box;
        stream_boxes_of(f, layout, sel, c, 1, &boxes);
        for (uint32_t k = 0; k < CBVH_STREAM_LANES; k++) {
            lists.ray[k] = k == 0 ? list_ray + n : &sink_ray;
            lists.entry[k] = k == 0 ? list_entry + n : &sink_entry;
        }
        node_test(b, list_ray, n, &boxes, &lists, count);
        nv += n;
        start = n;
        n = count[0];
    }
    while (n > 0) {
        const uint32_t top = start + n;
        if (cbvh_tree_is_leaf(f, layout, r)) {
            uint32_t tri0, tri_count;
            cbvh_tree_leaf(f, layout, r, &tri0, &tri_count);
            nt += (uint64_t)n * tri_count;
            stream_leaf(f, b, list_ray + start, n, tri0, tri_count, any, simd_leaves, occluded);
        } else if (n <= CBVH_STREAM_SOLO || top + CBVH_TREE_WIDTH * n > b->list_capacity) {
            /* Too few rays left to share the nodes below, or no room for their lists: each finishes the
             * subtree on its own, with the single-ray walk and its current tmax. */
            for (uint32_t j = 0; j < n; j++)
                solo_tail(f, b, list_ray[start + j], r, any, occluded, counting ? &solo : NULL);
        } else {
            const uint32_t k = cbvh_tree_children(f, layout, r, octant, c);
            stream_boxes_of(f, layout, sel, c, k, &boxes);
            /* child j's list at top + (k - 1 - j) n, the nearest child's highest */
            for (uint32_t j = 0; j < CBVH_STREAM_LANES; j++) {
                lists.ray[j] = j < k ? list_ray + top + (k - 1 - j) * n : &sink_ray;
                lists.entry[j] = j < k ? list_entry + top + (k - 1 - j) * n : &sink_entry;
            }
            node_test(b, list_ray + start, n, &boxes, &lists, count);
            nv += (uint64_t)n * k;
            /* close up the lists over the node's own, now done with, farthest first, and push the children
             * entered */
            uint32_t end = start;
            for (uint32_t j = k; j-- > 0;) {
                if (count[j] == 0)
                    continue;
                memmove(list_ray + end, lists.ray[j], count[j] * sizeof *list_ray);
                memmove(list_entry + end, lists.entry[j], count[j] * sizeof *list_entry);
                stack[sp].ref = c[j].ref;
                stack[sp].start = end;
                stack[sp].count = (uint16_t)count[j];
                stack[sp].shrinks = (uint16_t)b->shrinks;
                sp++;
                end += count[j];
                /* a wide node is one cache line: start fetching it while the nearer children run */
                if (layout == CBVH_LAYOUT_WIDE4 && !cbvh_w4_ref_is_leaf(c[j].ref))
                    CBVH_PREFETCH(cbvh_w4_node(f->nodes, c[j].ref));
            }
        }
        /* the next child with rays still in reach */
        for (n = 0; n == 0 && sp > 0;) {
            sp--;
            r = stack[sp].ref;
            start = stack[sp].start;
            n = stack[sp].count;
            if (stack[sp].shrinks != (uint16_t)b->shrinks)
                n = stream_still_in_reach(b, list_ray + start, list_entry + start, n);
        }
    }
    *visited += nv + solo.nodes_visited;
    *tested += nt + solo.triangles_tested;
}

/* The stream walk per layout and query kind, each a function of its own so that a frame holds one walk's
 * stack, not the sum of all (-fstack-usage); `counting` (whether the solo tails count) is read at run
 * time. */
#define STREAM_INSTANCE(name, layout, any)                                                                   \
    CBVH_NOINLINE void name(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,         \
                            cbvh_stream_node_fn node_test, int counting, uint8_t *occluded,                  \
                            uint64_t *visited, uint64_t *tested)                                             \
    {                                                                                                        \
        stream_walk(f, layout, b, octant, node_test, any, counting, occluded, visited, tested);              \
    }
STREAM_INSTANCE(stream_wide4_closest, CBVH_LAYOUT_WIDE4, 0)
STREAM_INSTANCE(stream_wide4_any, CBVH_LAYOUT_WIDE4, 1)
STREAM_INSTANCE(stream_binary_closest, CBVH_LAYOUT_BINARY, 0)
STREAM_INSTANCE(stream_binary_any, CBVH_LAYOUT_BINARY, 1)
#undef STREAM_INSTANCE

/* The stream walk for the file's layout. */
static void stream_walk_file(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,
                             cbvh_stream_node_fn node_test, int any, int counting, uint8_t *occluded,
                             uint64_t *visited, uint64_t *tested)
{
    if (f->layout == CBVH_LAYOUT_WIDE4)
        (any ? stream_wide4_any : stream_wide4_closest)(f, b, octant, node_test, counting, occluded, visited,
                                                        tested);
    else
        (any ? stream_binary_any : stream_binary_closest)(f, b, octant, node_test, counting, occluded,
                                                          visited, tested);
}

/* Adds a validated ray to the batch. */
static void batch_add(struct cbvh_stream_batch *b, const struct cbvh_ray_ctx *ctx, size_t ray_index)
{
    const uint32_t r = b->count++;
    float *box_ray = b->box_ray[r];
    box_ray[CBVH_LANE_OX] = ctx->shear.org[0];
    box_ray[CBVH_LANE_OY] = ctx->shear.org[1];
    box_ray[CBVH_LANE_OZ] = ctx->shear.org[2];
    box_ray[CBVH_LANE_TMIN] = ctx->tmin;
    box_ray[CBVH_LANE_RX] = ctx->rcp[0];
    box_ray[CBVH_LANE_RY] = ctx->rcp[1];
    box_ray[CBVH_LANE_RZ] = ctx->rcp[2];
    box_ray[CBVH_LANE_TMAX] = ctx->tmax;
    b->ctx[r] = *ctx;
    b->best[r].tri = UINT32_MAX;
    b->ray_index[r] = ray_index;
}

/* Traverses the batch and writes its results, then empties it. */
static void batch_flush(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,
                        cbvh_stream_node_fn node_test, int counting, cbvh_hit *hits, uint8_t *occluded,
                        uint64_t *visited, uint64_t *tested)
{
    if (b->count == 0)
        return;
    if (hits) {
        stream_walk_file(f, b, octant, node_test, 0, counting, NULL, visited, tested);
        /* the hits' REMAP entries (original ids), scattered over a large mesh's table: all requested
         * before the first is read */
        for (uint32_t r = 0; f->remap && r < b->count; r++)
            if (b->best[r].tri != UINT32_MAX)
                CBVH_PREFETCH(cbvh_remap_entry(f, b->best[r].tri));
        for (uint32_t r = 0; r < b->count; r++)
            cbvh_hit_output(f, &b->best[r], b->ctx[r].t_base, &hits[b->ray_index[r]]);
    } else {
        stream_walk_file(f, b, octant, node_test, 1, counting, occluded, visited, tested);
    }
    b->count = 0;
}

/* A whole ray on the halved single-ray walk (raycast.h), its counters added to the stream's. */
static void solo_ray(const struct cbvh_file *f, const struct cbvh_ray_ctx *ctx, cbvh_hit *hit, uint8_t *occluded,
                     uint64_t *visited, uint64_t *tested)
{
    cbvh_query_stats stats = {0, 0};
    if (hit) {
        struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
        cbvh_closest(f, ctx, CBVH_TRAVERSAL_SORTED, &best, &stats);
        cbvh_hit_output(f, &best, ctx->t_base, hit);
    } else {
        *occluded = (uint8_t)cbvh_any(f, ctx, CBVH_TRAVERSAL_SORTED, &stats);
    }
    *visited += stats.nodes_visited;
    *tested += stats.triangles_tested;
}

/* The batch's arrays cut from `size` bytes at `mem`: as many rays as fit, at most CBVH_STREAM_MAX_BATCH
 * (the alignments need at most STREAM_SLACK bytes); *octant receives the window's octant bytes.
 * Returns the batch's capacity, 0 when not even one ray fits. */
static uint32_t batch_carve(struct cbvh_stream_batch *b, uint8_t **octant, void *mem, size_t size)
{
    if (!mem || size < STREAM_SLACK + STREAM_RAY_BYTES)
        return 0;
    size_t n = (size - STREAM_SLACK) / STREAM_RAY_BYTES;
    n = n < CBVH_STREAM_MAX_BATCH ? n : CBVH_STREAM_MAX_BATCH;
    /* box_ray: 16-byte aligned for SSE2 loads (32 kept) */
    uintptr_t p = ((uintptr_t)mem + 31u) & ~(uintptr_t)31u;
    b->box_ray = (float(*)[8])p;
    p += n * 8 * sizeof(float);
    b->ctx = (struct cbvh_ray_ctx *)p; /* 8-byte alignment holds: every array before is a multiple of 32 */
    p += n * sizeof(struct cbvh_ray_ctx);
    p = (p + _Alignof(struct cbvh_best_hit) - 1) & ~(uintptr_t)(_Alignof(struct cbvh_best_hit) - 1);
    b->best = (struct cbvh_best_hit *)p;
    p += n * sizeof(struct cbvh_best_hit);
    p = (p + _Alignof(size_t) - 1) & ~(uintptr_t)(_Alignof(size_t) - 1);
    b->ray_index = (size_t *)p;
    p += n * sizeof(size_t);
    b->list_entry = (float *)p; /* 4-byte alignment holds: size_t's does */
    p += STREAM_LIST_PER_RAY * n * sizeof(float);
    b->list_ray = (uint16_t *)p;
    p += STREAM_LIST_PER_RAY * n * sizeof(uint16_t);
    b->list_capacity = (uint32_t)(STREAM_LIST_PER_RAY * n);
    b->shrinks = 0;
    *octant = (uint8_t *)p;
    b->count = 0;
    b->capacity = (uint32_t)n;
    return b->capacity;
}

/* Splits the stream into windows, each window into same-octant batches of the batch's capacity.
 * Exactly one of hits / occluded is given. Invalid rays are misses. */
static void stream_run(const struct cbvh_file *f, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                       uint8_t *occluded, cbvh_query_stats *stats, struct cbvh_stream_batch *restrict batch,
                       uint8_t *restrict octant)
{
    const cbvh_stream_node_fn node_test = cbvh_stream_node_kernel();
    const uint32_t window_size = CBVH_STREAM_WINDOW_PER_RAY * batch->capacity;
    struct cbvh_ray_ctx ctx;
    uint64_t visited = 0, tested = 0;

    for (size_t start = 0; start < count; start += window_size) {
        const uint32_t window = (uint32_t)(count - start < window_size ? count - start : window_size);
        uint32_t present = 0; /* octants that occur in the window */
        for (uint32_t j = 0; j < window; j++) {
            const size_t r = start + j;
            if (hits)
                hits[r].tri = CBVH_NO_HIT;
            else
                occluded[r] = 0;
            /* the octant alone here; each ray is prepared once, when its octant's turn comes */
            octant[j] = cbvh_ray_valid(&rays[r]) ? (uint8_t)cbvh_ray_octant(&rays[r]) : UINT8_MAX;
            if (octant[j] != UINT8_MAX)
                present |= 1u << octant[j];
        }
        for (uint32_t o = 0; o < 8; o++) {
            if (!(present >> o & 1u))
                continue;
            for (uint32_t j = 0; j < window; j++) {
                if (octant[j] != o)
                    continue;
                const size_t r = start + j;
                cbvh_ray_prepare(&ctx, &rays[r], f);
                if (ctx.box_halve) {
                    /* the batch shares one dequantized box between its rays; a ray whose box test needs
                     * half scale (coordinates past FLT_MAX / 2, ray_box.h) takes the single-ray walk */
                    solo_ray(f, &ctx, hits ? &hits[r] : NULL, occluded ? &occluded[r] : NULL, &visited, &tested);
                    continue;
                }
                batch_add(batch, &ctx, r);
                if (batch->count == batch->capacity)
                    batch_flush(f, batch, o, node_test, stats != NULL, hits, occluded, &visited, &tested);
            }
            batch_flush(f, batch, o, node_test, stats != NULL, hits, occluded, &visited, &tested);
        }
    }
    if (stats) {
        stats->nodes_visited += visited;
        stats->triangles_tested += tested;
    }
}

/* A batch of CBVH_STREAM_STACK_BATCH rays on this frame, or the caller's scratch when it holds more. */
static void stream_query(const struct cbvh_file *f, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                         uint8_t *occluded, cbvh_query_stats *stats, void *scratch, size_t scratch_size)
{
    _Alignas(32) uint8_t own[STREAM_SLACK + CBVH_STREAM_STACK_BATCH * STREAM_RAY_BYTES];
    struct cbvh_stream_batch batch;
    uint8_t *octant;
    if (batch_carve(&batch, &octant, scratch, scratch_size) <= CBVH_STREAM_STACK_BATCH)
        batch_carve(&batch, &octant, own, sizeof own);
    stream_run(f, rays, count, hits, occluded, stats, &batch, octant);
}

CBVH_API size_t cbvh_stream_scratch_size(size_t batch_rays)
{
    const size_t n = batch_rays < 1 ? 1 : batch_rays > CBVH_STREAM_MAX_BATCH ? CBVH_STREAM_MAX_BATCH : batch_rays;
    return STREAM_SLACK + n * STREAM_RAY_BYTES;
}

CBVH_API void cbvh_raycast_stream_scratch(const cbvh_file *file, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                                          cbvh_query_stats *stats, void *scratch, size_t scratch_size)
{
    if (!hits)
        return;
    if (!file || !rays) {
        for (size_t r = 0; r < count; r++)
            hits[r].tri = CBVH_NO_HIT;
        return;
    }
    stream_query(file, rays, count, hits, NULL, stats, scratch, scratch_size);
}

CBVH_API void cbvh_occluded_stream_scratch(const cbvh_file *file, const cbvh_ray *rays, size_t count,
                                           uint8_t *occluded, cbvh_query_stats *stats, void *scratch,
                                           size_t scratch_size)
{
    if (!occluded)
        return;
    if (!file || !rays) {
        memset(occluded, 0, count);
        return;
    }
    stream_query(file, rays, count, NULL, occluded, stats, scratch, scratch_size);
}

CBVH_API void cbvh_raycast_stream(const cbvh_file *file, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                                  cbvh_query_stats *stats)
{
    cbvh_raycast_stream_scratch(file, rays, count, hits, stats, NULL, 0);
}

CBVH_API void cbvh_occluded_stream(const cbvh_file *file, const cbvh_ray *rays, size_t count, uint8_t *occluded,
                                   cbvh_query_stats *stats)
{
    cbvh_occluded_stream_scratch(file, rays, count, occluded, stats, NULL, 0);
}
