/* stream_walk.h: the streams' batch and interleaved walks and node test, built by stream.c and, for AVX2,
 * stream_avx2.c. */
#ifndef CBVH_QUERY_STREAM_WALK_H
#define CBVH_QUERY_STREAM_WALK_H

#include <string.h>

#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/stream.h"

#ifdef CBVH_HAVE_SIMD
/* Ray r, which enters the boxes of `mask` at entry[k], goes on those lists: every lane stores, only the
 * entered lists advance (no branch on the mask; unrolled so the counts stay in registers). */
static inline void node_append(const struct cbvh_stream_lists *restrict out, uint16_t r, uint32_t mask,
                               const float entry[CBVH_STREAM_LANES], uint32_t c[CBVH_STREAM_LANES])
{
    CBVH_UNROLL(4)
    for (uint32_t k = 0; k < CBVH_STREAM_LANES; k++) {
        out->ray[k][c[k]] = r;
        out->entry[k][c[k]] = entry[k];
        c[k] += mask >> k & 1u;
    }
}

/* The batch node test (CBVH_STREAM_NODE_KERNEL) in SIMD, compiled in SSE2's encoding by stream_node.c and in
 * AVX2's by stream_avx2.c: lane for lane ray_box.h's slab test (MAXPS and MINPS ignore a NaN distance as
 * its compares do), each ray against the four boxes at once. */
CBVH_FORCE_INLINE void stream_node_simd(const struct cbvh_stream_batch *restrict batch,
                                        const uint16_t *restrict rays, uint32_t n,
                                        const struct cbvh_stream_boxes *restrict boxes,
                                        const struct cbvh_stream_lists *restrict out,
                                        uint32_t count[CBVH_STREAM_LANES])
{
    __m128 plane[6];
    for (uint32_t p = 0; p < 6; p++)
        plane[p] = _mm_load_ps(boxes->plane[p]);
    const uint32_t lanes = (1u << boxes->count) - 1u;
    uint32_t c[CBVH_STREAM_LANES] = {0, 0, 0, 0};
    for (uint32_t j = 0; j < n; j++) {
        const uint16_t r = rays[j];
        const __m128 o = _mm_load_ps(&batch->box_ray[r][0]), d = _mm_load_ps(&batch->box_ray[r][4]);
        const __m128 ox = CBVH_LANE(o, 0), oy = CBVH_LANE(o, 1), oz = CBVH_LANE(o, 2), rx = CBVH_LANE(d, 0),
                     ry = CBVH_LANE(d, 1), rz = CBVH_LANE(d, 2);
        __m128 tnear = CBVH_LANE(o, 3), tfar = CBVH_LANE(d, 3);
        tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(plane[0], ox), rx), tnear);
        tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(plane[1], oy), ry), tnear);
        tnear = _mm_max_ps(_mm_mul_ps(_mm_sub_ps(plane[2], oz), rz), tnear);
        tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(plane[3], ox), rx), tfar);
        tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(plane[4], oy), ry), tfar);
        tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(plane[5], oz), rz), tfar);
        _Alignas(16) float entry[CBVH_STREAM_LANES];
        _mm_store_ps(entry, tnear);
        const uint32_t mask =
            (uint32_t)_mm_movemask_ps(_mm_cmple_ps(tnear, _mm_mul_ps(tfar, _mm_set1_ps(CBVH_BOX_PAD))));
        node_append(out, r, mask & lanes, entry, c);
    }
    memcpy(count, c, sizeof c);
}
#endif

/* A batch node with at most this many live rays hands each to the single-ray walk (stream_tail). */
#define CBVH_STREAM_SOLO 4

/* The walk mode of a ray walked alone (a batch ray's tail, an interleaved walk). */
static inline struct cbvh_walk_mode stream_alone_mode(int any, int scalar)
{
    const struct cbvh_walk_mode mode = {.order = CBVH_WALK_SORTED, .any = any, .scalar = scalar};
    return mode;
}

/* Ray r of the batch is occluded: a negative TMAX fails every later box and triangle test. */
CBVH_KERNEL void stream_occlude(struct cbvh_stream_batch *restrict b, uint32_t r, uint8_t *restrict occluded)
{
    occluded[b->ray_index[r]] = 1;
    b->box_ray[r][CBVH_LANE_TMAX] = -1.0f;
    b->shrinks++;
}

/* Ray r of the batch finishes the subtree `root` (whose box the batch tested) alone: the single-ray walk in
 * the batch's first walk slot, from the ray's current tmax and best hit (same test and tie rule). */
CBVH_KERNEL void stream_tail(const struct cbvh_file *restrict f, const uint32_t layout,
                             struct cbvh_stream_batch *restrict b, const struct cbvh_walk_mode mode,
                             int counting, uint32_t r, cbvh_ref root, uint8_t *restrict occluded,
                             uint64_t *restrict visited, uint64_t *restrict tested)
{
    struct cbvh_stream_walk *restrict t = b->walks;
    enum cbvh_walk_step_result step;
    t->best = b->best[r];
    cbvh_walk_begin(f, layout, &b->ctx[r], mode, root, CBVH_NO_BOX, NULL, b->box_ray[r][CBVH_LANE_TMAX],
                    &t->walk);
    do
        step = cbvh_walk_step(f, layout, &b->ctx[r], mode, NULL, counting, NULL, &t->walk, &t->best);
    while (step == CBVH_WALK_MORE);
    if (mode.any && step == CBVH_WALK_HIT) {
        stream_occlude(b, r, occluded);
    } else if (!mode.any && t->best.tri != b->best[r].tri) {
        b->best[r] = t->best;
        b->box_ray[r][CBVH_LANE_TMAX] = t->walk.tmax;
        b->shrinks++;
    }
    *visited += t->walk.visited;
    *tested += t->walk.tested;
}

/* The live rays live[0, m) against the leaf's triangles [tri0, tri0 + count), as the single-ray walk's leaf
 * (leaf.h) tests them: with SIMD the leaf gathered once per batch visit and filtered per ray
 * (leaf_rows_visit), else each triangle fetched once for every ray. */
CBVH_KERNEL void stream_leaf(const struct cbvh_file *f, struct cbvh_stream_batch *restrict b,
                             const uint16_t *restrict live, uint32_t m, uint32_t tri0, uint32_t count,
                             const int any, int simd, uint8_t *restrict occluded)
{
#ifdef CBVH_HAVE_SIMD
    if (simd && count > 1) {
        struct leaf_quad scratch[CBVH_LEAF_GROUPS][CBVH_LEAF_QUADS];
        struct leaf_group q[CBVH_LEAF_GROUPS];
        uint32_t group_first[CBVH_LEAF_GROUPS], groups = 0;
        const uint32_t end = tri0 + count;
        const struct leaf_quad *quads = (const struct leaf_quad *)f->quads;
        for (uint32_t k = leaf_groups_begin(quads, tri0); k < end; k += CBVH_LANES, groups++) {
            group_first[groups] = k;
            leaf_group_lanes(f, quads, (int)f->triangle_encoding, (int)f->vertex_encoding, f->grid_origin,
                             f->grid_scale, tri0, end, k, scratch[groups], &q[groups]);
        }
        for (uint32_t j = 0; j < m; j++) {
            const uint32_t r = live[j];
            const struct cbvh_ray_shear *s = &b->ctx[r].shear;
            float *box_ray = b->box_ray[r];
            const float tmin = box_ray[CBVH_LANE_TMIN];
            struct cbvh_best_hit *best = &b->best[r];
            for (uint32_t g = 0; g < groups; g++) {
                struct leaf_rows rows;
                leaf_group_rows(s, &q[g], &rows);
                if (leaf_rows_visit(f, s, &rows, &q[g], 0, NULL, NULL, q[g].mask, group_first[g], NULL, any,
                                    any, !any, tmin, &box_ray[CBVH_LANE_TMAX], best)) {
                    stream_occlude(b, r, occluded);
                    break;
                }
            }
        }
        b->shrinks += !any;
        return;
    }
#else
    (void)simd;
#endif
    float a[3], v1[3], v2[3];
    for (uint32_t k = tri0; k < tri0 + count; k++) {
        cbvh_triangle_vertices(f, k, a, v1, v2);
        for (uint32_t j = 0; j < m; j++) {
            const uint32_t r = live[j];
            float *box_ray = b->box_ray[r], t, u, v;
            if (cbvh_ray_triangle(&b->ctx[r].shear, a, v1, v2, box_ray[CBVH_LANE_TMIN],
                                  box_ray[CBVH_LANE_TMAX], !any, &t, &u, &v) &&
                leaf_take(f, NULL, k, t, u, v, any, &box_ray[CBVH_LANE_TMAX], &b->best[r]))
                stream_occlude(b, r, occluded);
        }
    }
    b->shrinks += !any;
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

/* Walks the tree once for the batch, children in the order of the batch's octant. Each live ray is tested
 * against all of a node's child boxes at once, and each child entered gets the list of its rays with their
 * entry distances. The lists form a stack in b->list_ray/list_entry: a node's children's lists replace its
 * own, so popping a child frees everything above its list. A child popped after some ray's tmax shrank
 * drops the rays no longer in reach; a node whose lists would not fit sends its rays down the single-ray
 * walk. The triangle test and the tie rule are the single-ray walks', so every ray gets the same hit. */
CBVH_KERNEL void stream_walk(const struct cbvh_file *restrict f, const uint32_t layout,
                             struct cbvh_stream_batch *restrict b, uint32_t octant,
                             cbvh_stream_node_fn node_test, const int any, int counting,
                             uint8_t *restrict occluded, uint64_t *restrict visited,
                             uint64_t *restrict tested)
{
    /* the scalar node kernel (the fallback, and its test) comes with scalar leaves */
    const int simd_leaves = node_test != cbvh_stream_node_scalar;
    const struct cbvh_slab_select sel = cbvh_slab_select_of(octant);
    uint16_t *restrict list_ray = b->list_ray;
    float *restrict list_entry = b->list_entry;
    struct {
        cbvh_ref ref;
        uint32_t start; /* its list: list_ray[start, start + count) */
        uint16_t count;
        uint16_t shrinks; /* b->shrinks at the list's making (mod 2^16: a wrap skips a recheck only) */
    } stack[(CBVH_TREE_WIDTH - 1u) * CBVH_MAX_DEPTH + 1u];
    uint16_t sink_ray;
    float sink_entry;
    struct cbvh_stream_boxes boxes;
    struct cbvh_stream_lists lists;
    struct cbvh_child c[CBVH_TREE_WIDTH];
    uint32_t sp = 0, count[CBVH_STREAM_LANES];
    uint64_t nv = 0, nt = 0;

    /* The root's list: every ray, through the root box when the layout has one. Farthest first for an
     * any-hit batch whose rays mostly start inside the mesh's bounds (any_flip, walk.h) */
    uint32_t inside = 0;
    for (uint32_t j = 0; j < b->count; j++) {
        list_ray[j] = (uint16_t)j;
        inside += b->ctx[j].any_flip & 1u;
    }
    const uint32_t order = octant ^ (any && 2u * inside > b->count ? 7u : 0u);
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
            /* too few rays to share the nodes below, or no room for their lists: each walks alone */
            for (uint32_t j = 0; j < n; j++)
                stream_tail(f, layout, b, stream_alone_mode(any, !simd_leaves), counting, list_ray[start + j],
                            r, occluded, &nv, &nt);
        } else {
            const uint32_t k = cbvh_tree_children(f, layout, r, order, c);
            stream_boxes_of(f, layout, sel, c, k, &boxes);
            /* child j's list at top + (k - 1 - j) n, the nearest child's highest */
            for (uint32_t j = 0; j < CBVH_STREAM_LANES; j++) {
                lists.ray[j] = j < k ? list_ray + top + (k - 1 - j) * n : &sink_ray;
                lists.entry[j] = j < k ? list_entry + top + (k - 1 - j) * n : &sink_entry;
            }
            node_test(b, list_ray + start, n, &boxes, &lists, count);
            nv += (uint64_t)n * k;
            /* close up the lists over the node's own, farthest first, and push the children entered */
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
    *visited += nv;
    *tested += nt;
}

/* A whole ray on the single-ray walk (raycast.h), its counters added to the stream's. */
CBVH_KERNEL void stream_solo_ray(const struct cbvh_file *f, const struct cbvh_ray_ctx *ctx, cbvh_hit *hit,
                                 uint8_t *occluded, uint64_t *visited, uint64_t *tested)
{
    cbvh_query_stats stats = {0, 0};
    if (hit) {
        struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
        cbvh_closest(f, ctx, CBVH_TRAVERSAL_SORTED, &best, &stats);
        cbvh_hit_output(f, &best, &ctx->t_frame, hit);
    } else {
        *occluded = (uint8_t)cbvh_any(f, ctx, CBVH_TRAVERSAL_SORTED, &stats);
    }
    *visited += stats.nodes_visited;
    *tested += stats.triangles_tested;
}

/* Ray i of the stream begins: its answer set to a miss and it is prepared into *ctx. Returns 1 when it is to
 * be walked; 0 when it is done (invalid, missing the top box, or walked whole by stream_solo_ray: box_halve,
 * which the batch's shared boxes do not serve). */
CBVH_KERNEL int stream_ray_begin(const struct cbvh_file *restrict f, const cbvh_ray *restrict rays, size_t i,
                                 struct cbvh_ray_ctx *restrict ctx, cbvh_hit *restrict hits,
                                 uint8_t *restrict occluded, uint64_t *restrict visited,
                                 uint64_t *restrict tested)
{
    if (hits)
        hits[i].tri = CBVH_NO_HIT;
    else
        occluded[i] = 0;
    if (!cbvh_ray_prepare(ctx, &rays[i], f, visited))
        return 0;
    if (!ctx->box_halve)
        return 1;
    stream_solo_ray(f, ctx, hits ? &hits[i] : NULL, hits ? NULL : &occluded[i], visited, tested);
    return 0;
}

/* Whether slot t's walk goes to a leaf whose vertices it has not requested yet (wide layout): then two lines
 * from its first vertex are requested now, and the leaf is tested at the slot's next turn. */
CBVH_KERNEL int stream_request_leaf(const struct cbvh_file *restrict f, struct cbvh_stream_walk *restrict t)
{
    if (!cbvh_w4_ref_is_leaf(t->walk.r) || t->fetched == t->walk.r)
        return 0;
    uint32_t idx[3];
    t->fetched = t->walk.r;
    cbvh_triangle_indices(f, cbvh_w4_ref_first(t->walk.r), idx);
    const uint8_t *v = (const uint8_t *)cbvh_vertex_address(f, idx[0]);
    CBVH_PREFETCH(v);
    CBVH_PREFETCH(v + 64);
    return 1;
}

/* Ray i of the stream starts in slot k of the interleaved walks (stream_interleave), as stream_ray_begin
 * says: returns 1 when the slot walks it. */
CBVH_KERNEL int stream_interleave_start(const struct cbvh_file *restrict f,
                                        struct cbvh_stream_batch *restrict b,
                                        const struct cbvh_walk_mode mode, const cbvh_ray *restrict rays,
                                        size_t i, uint32_t k, cbvh_hit *restrict hits,
                                        uint8_t *restrict occluded, uint64_t *restrict visited,
                                        uint64_t *restrict tested)
{
    struct cbvh_stream_walk *restrict slot = &b->walks[k];
    if (!stream_ray_begin(f, rays, i, &b->ctx[k], hits, occluded, visited, tested))
        return 0;
    b->ray_index[k] = i;
    slot->best.tri = UINT32_MAX;
    slot->fetched = CBVH_W4_LEAF_BIT - 1u; /* no leaf */
    cbvh_walk_begin(f, CBVH_LAYOUT_WIDE4, &b->ctx[k], mode, cbvh_tree_root(f, CBVH_LAYOUT_WIDE4), CBVH_NO_BOX,
                    NULL, b->ctx[k].tmax, &slot->walk);
    return 1;
}

/* The interleaved walks (wide layout): the rays walked b->walk_count at a time by the single-ray walk, one
 * step each in turn in the batch's walk slots (b->ctx[k], b->ray_index[k] for slot k), so the CPU overlaps
 * their chains of dependent loads; a ray that ends hands its slot to the next. A closest-hit walk requests a
 * leaf's vertices a turn before its test. Closest hit into hits, any hit into occluded; the single-ray
 * walk's answers. */
CBVH_KERNEL void stream_interleave(const struct cbvh_file *restrict f, struct cbvh_stream_batch *restrict b,
                                   const cbvh_ray *restrict rays, size_t count, const int any,
                                   cbvh_hit *restrict hits, uint8_t *restrict occluded, int scalar,
                                   int counting, uint64_t *restrict visited, uint64_t *restrict tested)
{
    const struct cbvh_walk_mode mode = stream_alone_mode(any, scalar);
    struct cbvh_stream_walk *restrict slot = b->walks;
    const uint32_t walks = b->walk_count;
    uint32_t running = 0; /* bit k: slot k walks a ray */
    size_t next = 0;
    uint64_t nv = 0, nt = 0;
    do {
        for (uint32_t k = 0; k < walks; k++) {
            while (!(running >> k & 1u) && next < count)
                if (stream_interleave_start(f, b, mode, rays, next++, k, hits, occluded, &nv, &nt))
                    running |= 1u << k;
            if (!(running >> k & 1u) || (!any && !f->quads && stream_request_leaf(f, &slot[k])))
                continue;
            struct cbvh_walk_state *restrict walk = &slot[k].walk;
            const enum cbvh_walk_step_result step = cbvh_walk_step(f, CBVH_LAYOUT_WIDE4, &b->ctx[k], mode,
                                                                   NULL, counting, NULL, walk, &slot[k].best);
            if (step == CBVH_WALK_MORE)
                continue;
            if (any)
                occluded[b->ray_index[k]] = step == CBVH_WALK_HIT;
            else
                cbvh_hit_output(f, &slot[k].best, &b->ctx[k].t_frame, &hits[b->ray_index[k]]);
            nv += walk->visited;
            nt += walk->tested;
            running &= ~(1u << k);
        }
    } while (running || next < count);
    *visited += nv;
    *tested += nt;
}

/* The batch walk (on layout_) and the interleaved walks (wide layout) of one query kind, as functions of
 * their own in the instruction set of the file that instantiates them (stream.c, stream_avx2.c). */
#define STREAM_KIND_INSTANCES(name, layout_, any_)                                                           \
    CBVH_NOINLINE void name##_batch(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant, \
                                    cbvh_stream_node_fn node_test, int counting, uint8_t *occluded,          \
                                    uint64_t *visited, uint64_t *tested)                                     \
    {                                                                                                        \
        stream_walk(f, layout_, b, octant, node_test, any_, counting, occluded, visited, tested);            \
    }                                                                                                        \
    CBVH_NOINLINE void name##_interleave(                                                                    \
        const struct cbvh_file *f, struct cbvh_stream_batch *b, const cbvh_ray *rays, size_t count,          \
        cbvh_hit *hits, uint8_t *occluded, int scalar, int counting, uint64_t *visited, uint64_t *tested)    \
    {                                                                                                        \
        stream_interleave(f, b, rays, count, any_, hits, occluded, scalar, counting, visited, tested);       \
    }
/* Both query kinds' instances, and name##_batch and name##_interleave (with `linkage`) that pick one: the
 * batch walk with stream_walk's arguments (any hit when `any`), the interleaved walks with
 * stream_interleave's (any hit when hits is NULL). */
#define STREAM_INSTANCES(linkage, name, layout_)                                                             \
    STREAM_KIND_INSTANCES(name##_closest, layout_, 0)                                                        \
    STREAM_KIND_INSTANCES(name##_any, layout_, 1)                                                            \
    linkage void name##_batch(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,       \
                              cbvh_stream_node_fn node_test, int any, int counting, uint8_t *occluded,       \
                              uint64_t *visited, uint64_t *tested)                                           \
    {                                                                                                        \
        (any ? name##_any_batch : name##_closest_batch)(f, b, octant, node_test, counting, occluded,         \
                                                        visited, tested);                                    \
    }                                                                                                        \
    linkage void name##_interleave(const struct cbvh_file *f, struct cbvh_stream_batch *b,                   \
                                   const cbvh_ray *rays, size_t count, cbvh_hit *hits, uint8_t *occluded,    \
                                   int scalar, int counting, uint64_t *visited, uint64_t *tested)            \
    {                                                                                                        \
        (hits ? name##_closest_interleave : name##_any_interleave)(f, b, rays, count, hits, occluded,        \
                                                                   scalar, counting, visited, tested);       \
    }

#ifdef CBVH_HAVE_AVX2
/* The wide layout's walks compiled for AVX2 (stream_avx2.c): STREAM_INSTANCES' pickers. */
void cbvh_stream_wide4_avx2_batch(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,
                                  cbvh_stream_node_fn node_test, int any, int counting, uint8_t *occluded,
                                  uint64_t *visited, uint64_t *tested);
void cbvh_stream_wide4_avx2_interleave(const struct cbvh_file *f, struct cbvh_stream_batch *b,
                                       const cbvh_ray *rays, size_t count, cbvh_hit *hits, uint8_t *occluded,
                                       int scalar, int counting, uint64_t *visited, uint64_t *tested);
#endif

#endif
