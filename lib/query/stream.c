/* stream.c: ray streams: batches of same-octant rays, interleaved walks, or single rays, by window. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include <string.h>

#include "query/ray_box.h"
#include "query/raycast.h"
#include "query/stream.h"
#include "query/stream_walk.h"
#include "query/vec3d.h"

/* Rays are grouped by octant within windows of this many input rays per batch ray. */
#define CBVH_STREAM_WINDOW_PER_RAY 8u

/* The interleaved walks keep slot k's ray in the batch's ctx[k] and ray_index[k]. */
_Static_assert(CBVH_STREAM_STACK_BATCH >= CBVH_STREAM_WALKS && CBVH_STREAM_WALKS >= CBVH_STREAM_STACK_WALKS &&
                   CBVH_STREAM_WALKS <= 32u,
               "a batch holds the interleaved walks' rays, and a word their bits");

/* Entries of the walk's stack of ray lists per batch ray (the root's and its children's take 5). */
#define STREAM_LIST_PER_RAY 8u

/* Bytes a batch ray takes in the block (the window's octant bytes included), and the alignment slack. */
#define STREAM_RAY_BYTES                                                                                     \
    (8 * sizeof(float) + sizeof(struct cbvh_ray_ctx) + sizeof(struct cbvh_best_hit) + sizeof(size_t) +       \
     STREAM_LIST_PER_RAY * (sizeof(float) + sizeof(uint16_t)) + CBVH_STREAM_WINDOW_PER_RAY)
#define STREAM_SLACK 96u /* two 32-byte alignments (the walks, box_ray), and best_hit's and size_t's */
/* Bytes of a block before its rays: `walks` walk slots (stream.h), whatever the batch's size. */
#define STREAM_WALKS_BYTES(walks) ((walks) * sizeof(struct cbvh_stream_walk))

STREAM_INSTANCES(CBVH_NOINLINE, stream_wide4, CBVH_LAYOUT_WIDE4)
STREAM_INSTANCES(CBVH_NOINLINE, stream_binary, CBVH_LAYOUT_BINARY)

/* The batch walk for the file's layout, on the single-ray walks' kernel (with SIMD node tests). */
static void batch_walk(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,
                       cbvh_stream_node_fn node_test, int any, int counting, uint8_t *occluded,
                       uint64_t *visited, uint64_t *tested)
{
#ifdef CBVH_HAVE_AVX2
    if (f->layout == CBVH_LAYOUT_WIDE4 && node_test != cbvh_stream_node_scalar &&
        cbvh_walk_kernel() == CBVH_WALK_KERNEL_AVX2) {
        cbvh_stream_wide4_avx2_batch(f, b, octant, cbvh_stream_node_avx2, any, counting, occluded, visited,
                                     tested);
        return;
    }
#endif
    (f->layout == CBVH_LAYOUT_WIDE4 ? stream_wide4_batch : stream_binary_batch)(
        f, b, octant, node_test, any, counting, occluded, visited, tested);
}

/* Rays walked interleaved (hits NULL: any hit), on the single-ray walks' kernel (scalar also with the
 * scalar node kernel). */
static void interleave(const struct cbvh_file *f, struct cbvh_stream_batch *b, const cbvh_ray *rays,
                       size_t count, cbvh_hit *hits, uint8_t *occluded, cbvh_stream_node_fn node_test,
                       int counting, uint64_t *visited, uint64_t *tested)
{
    const int kernel = cbvh_walk_kernel();
    const int scalar = node_test == cbvh_stream_node_scalar || kernel == CBVH_WALK_KERNEL_SCALAR;
#ifdef CBVH_HAVE_AVX2
    if (!scalar && kernel == CBVH_WALK_KERNEL_AVX2) {
        cbvh_stream_wide4_avx2_interleave(f, b, rays, count, hits, occluded, 0, counting, visited, tested);
        return;
    }
#endif
    stream_wide4_interleave(f, b, rays, count, hits, occluded, scalar, counting, visited, tested);
}

/* Whether the rays of a window are coherent: of up to 64 pairs of consecutive rays spread over it, at least
 * half point within about 8 degrees of each other (invalid or zero directions count as apart). */
#define STREAM_COHERENCE_PAIRS 64u
int cbvh_stream_window_coherent(const cbvh_ray *rays, uint32_t n)
{
    const uint32_t pairs = n - 1u < STREAM_COHERENCE_PAIRS ? n - 1u : STREAM_COHERENCE_PAIRS;
    uint32_t close = 0;
    for (uint32_t p = 0; p < pairs; p++) {
        const uint32_t j = 1u + (uint32_t)((uint64_t)p * (n - 1u) / pairs);
        const cbvh_v3 a = v3_from_f(rays[j - 1u].dir), b = v3_from_f(rays[j].dir);
        const double dot = v3_dot(a, b), aa = v3_len2(a), bb = v3_len2(b);
        /* cos^2 of the angle above 0.99^2, the same way round; NaN fails */
        close += dot > 0.0 && dot * dot > 0.9801 * aa * bb;
    }
    return 2u * close >= pairs;
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
        batch_walk(f, b, octant, node_test, 0, counting, NULL, visited, tested);
        for (uint32_t r = 0; r < b->count; r++)
            cbvh_hit_output(f, &b->best[r], &b->ctx[r].t_frame, &hits[b->ray_index[r]]);
    } else {
        batch_walk(f, b, octant, node_test, 1, counting, occluded, visited, tested);
    }
    b->count = 0;
}

/* The batch's arrays cut from `size` bytes at `mem`, with `walks` slots for the interleaved walks: as many
 * rays as fit, at most CBVH_STREAM_MAX_BATCH (the alignments need at most STREAM_SLACK bytes); *octant
 * receives the window's octant bytes. Returns the batch's capacity, 0 when not even one ray fits. */
static uint32_t batch_carve(struct cbvh_stream_batch *b, uint8_t **octant, void *mem, size_t size,
                            uint32_t walks)
{
    if (!mem || size < STREAM_SLACK + STREAM_WALKS_BYTES(walks) + STREAM_RAY_BYTES)
        return 0;
    size_t n = (size - STREAM_SLACK - STREAM_WALKS_BYTES(walks)) / STREAM_RAY_BYTES;
    n = n < CBVH_STREAM_MAX_BATCH ? n : CBVH_STREAM_MAX_BATCH;
    /* the walks first (their states hold SIMD vectors), then box_ray, both 32-byte aligned */
    uintptr_t p = ((uintptr_t)mem + 31u) & ~(uintptr_t)31u;
    b->walks = (struct cbvh_stream_walk *)p;
    b->walk_count = walks;
    p = (p + STREAM_WALKS_BYTES(walks) + 31u) & ~(uintptr_t)31u;
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

/* The count rays one at a time on the single-ray walk. */
static void stream_single_rays(const struct cbvh_file *f, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                               uint8_t *occluded, uint64_t *visited, uint64_t *tested)
{
    struct cbvh_ray_ctx ctx;
    for (size_t i = 0; i < count; i++)
        if (stream_ray_begin(f, rays, i, &ctx, hits, occluded, visited, tested))
            stream_solo_ray(f, &ctx, hits ? &hits[i] : NULL, hits ? NULL : &occluded[i], visited, tested);
}

/* Splits the stream into windows, each into same-octant batches, or (cbvh_stream_way_for) walks an
 * incoherent window's rays interleaved or one at a time. Exactly one of hits / occluded is given. Invalid
 * rays are misses. */
static void stream_run(const struct cbvh_file *f, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                       uint8_t *occluded, cbvh_query_stats *stats, struct cbvh_stream_batch *restrict batch,
                       uint8_t *restrict octant)
{
    const cbvh_stream_node_fn node_test = cbvh_stream_node_kernel();
    const enum cbvh_stream_way way = cbvh_stream_way_for(f, batch->capacity);
    const uint32_t window_size = CBVH_STREAM_WINDOW_PER_RAY * batch->capacity;
    struct cbvh_ray_ctx ctx;
    uint64_t visited = 0, tested = 0;

    for (size_t start = 0; start < count; start += window_size) {
        const uint32_t window = (uint32_t)(count - start < window_size ? count - start : window_size);
        cbvh_hit *window_hits = hits ? hits + start : NULL;
        uint8_t *window_occluded = hits ? NULL : occluded + start;
        if (way == CBVH_STREAM_INTERLEAVED ||
            (way != CBVH_STREAM_BATCHED && !cbvh_stream_window_coherent(rays + start, window))) {
            if (way == CBVH_STREAM_BY_WINDOW_SINGLE)
                stream_single_rays(f, rays + start, window, window_hits, window_occluded, &visited, &tested);
            else
                interleave(f, batch, rays + start, window, window_hits, window_occluded, node_test,
                           stats != NULL, &visited, &tested);
            continue;
        }
        uint32_t present = 0; /* octants that occur in the window */
        for (uint32_t j = 0; j < window; j++) {
            const size_t r = start + j;
            octant[j] = cbvh_ray_valid(&rays[r]) ? (uint8_t)cbvh_ray_octant(&rays[r]) : UINT8_MAX;
            if (octant[j] != UINT8_MAX)
                present |= 1u << octant[j];
            else if (hits)
                hits[r].tri = CBVH_NO_HIT;
            else
                occluded[r] = 0;
        }
        for (uint32_t o = 0; o < 8; o++) {
            if (!(present >> o & 1u))
                continue;
            for (uint32_t j = 0; j < window; j++) {
                if (octant[j] != o ||
                    !stream_ray_begin(f, rays, start + j, &ctx, hits, occluded, &visited, &tested))
                    continue;
                batch_add(batch, &ctx, start + j);
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

/* The stream in a batch on this frame, a function of its own so a caller with scratch does not reserve it. */
CBVH_NOINLINE void stream_on_stack(const struct cbvh_file *f, const cbvh_ray *rays, size_t count,
                                   cbvh_hit *hits, uint8_t *occluded, cbvh_query_stats *stats)
{
    _Alignas(32) uint8_t own[STREAM_SLACK + STREAM_WALKS_BYTES(CBVH_STREAM_STACK_WALKS) +
                             CBVH_STREAM_STACK_BATCH * STREAM_RAY_BYTES];
    struct cbvh_stream_batch batch;
    uint8_t *octant;
    batch_carve(&batch, &octant, own, sizeof own, CBVH_STREAM_STACK_WALKS);
    stream_run(f, rays, count, hits, occluded, stats, &batch, octant);
}

/* The stream (closest hits into hits, or occlusion into occluded) in the caller's scratch when it holds more
 * rays than the stack batch, else on the stack. No file or no rays: every answer a miss. */
static void stream_query(const struct cbvh_file *f, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                         uint8_t *occluded, cbvh_query_stats *stats, void *scratch, size_t scratch_size)
{
    struct cbvh_stream_batch batch;
    uint8_t *octant;
    if (!f || !rays) {
        for (size_t r = 0; hits && r < count; r++)
            hits[r].tri = CBVH_NO_HIT;
        if (occluded)
            memset(occluded, 0, count);
    } else if (!hits && !occluded) {
        return;
    } else if (batch_carve(&batch, &octant, scratch, scratch_size, CBVH_STREAM_WALKS) >
               CBVH_STREAM_STACK_BATCH) {
        stream_run(f, rays, count, hits, occluded, stats, &batch, octant);
    } else {
        stream_on_stack(f, rays, count, hits, occluded, stats);
    }
}

CBVH_API size_t cbvh_stream_scratch_size(size_t batch_rays)
{
    const size_t n = batch_rays < 1                       ? 1
                     : batch_rays > CBVH_STREAM_MAX_BATCH ? CBVH_STREAM_MAX_BATCH
                                                          : batch_rays;
    return STREAM_SLACK + STREAM_WALKS_BYTES(CBVH_STREAM_WALKS) + n * STREAM_RAY_BYTES;
}

CBVH_API void cbvh_raycast_stream_scratch(const cbvh_file *file, const cbvh_ray *rays, size_t count,
                                          cbvh_hit *hits, cbvh_query_stats *stats, void *scratch,
                                          size_t scratch_size)
{
    stream_query(file, rays, count, hits, NULL, stats, scratch, scratch_size);
}

CBVH_API void cbvh_occluded_stream_scratch(const cbvh_file *file, const cbvh_ray *rays, size_t count,
                                           uint8_t *occluded, cbvh_query_stats *stats, void *scratch,
                                           size_t scratch_size)
{
    stream_query(file, rays, count, NULL, occluded, stats, scratch, scratch_size);
}

CBVH_API void cbvh_raycast_stream(const cbvh_file *file, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                                  cbvh_query_stats *stats)
{
    stream_query(file, rays, count, hits, NULL, stats, NULL, 0);
}

CBVH_API void cbvh_occluded_stream(const cbvh_file *file, const cbvh_ray *rays, size_t count,
                                   uint8_t *occluded, cbvh_query_stats *stats)
{
    stream_query(file, rays, count, NULL, occluded, stats, NULL, 0);
}
