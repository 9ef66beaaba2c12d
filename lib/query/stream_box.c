/* stream_box.c: the scalar batch node test, and the run-time choices of the batch node kernel and of the
 * tails. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include <stdatomic.h>

#include "query/ray_box.h"
#include "query/stream.h"

void cbvh_stream_node_scalar(const struct cbvh_stream_batch *restrict batch, const uint16_t *restrict rays,
                             uint32_t n, const struct cbvh_stream_boxes *restrict boxes,
                             const struct cbvh_stream_lists *restrict out, uint32_t count[CBVH_STREAM_LANES])
{
    const float(*p)[CBVH_STREAM_LANES] = boxes->plane;
    for (uint32_t k = 0; k < CBVH_STREAM_LANES; k++)
        count[k] = 0;
    for (uint32_t j = 0; j < n; j++) {
        const float *r = batch->box_ray[rays[j]];
        const float org[3] = {r[CBVH_LANE_OX], r[CBVH_LANE_OY], r[CBVH_LANE_OZ]};
        const float rcp[3] = {r[CBVH_LANE_RX], r[CBVH_LANE_RY], r[CBVH_LANE_RZ]};
        for (uint32_t k = 0; k < boxes->count; k++) {
            float entry;
            if (cbvh_slab_test(p[0][k], p[1][k], p[2][k], p[3][k], p[4][k], p[5][k], org, rcp,
                               r[CBVH_LANE_TMIN], r[CBVH_LANE_TMAX], &entry)) {
                out->ray[k][count[k]] = rays[j];
                out->entry[k][count[k]] = entry;
                count[k]++;
            }
        }
    }
}

static atomic_int stream_kernel_setting;

void cbvh_stream_set_kernel(int which)
{
    atomic_store_explicit(&stream_kernel_setting, which, memory_order_relaxed);
}

static atomic_int stream_tails_setting;

void cbvh_stream_set_tails(int tails)
{
    atomic_store_explicit(&stream_tails_setting, tails, memory_order_relaxed);
}

uint32_t cbvh_stream_tails_for(const struct cbvh_file *f)
{
    const int setting = atomic_load_explicit(&stream_tails_setting, memory_order_relaxed);
    if (setting != 0)
        return setting == 1 ? 1u : CBVH_STREAM_TAILS;
    /* a mesh in the caches has no miss to overlap: one tail, without the vertex-request turn */
    return f->vertices_far ? CBVH_STREAM_TAILS : 1u;
}

static atomic_int stream_interleave_setting;

void cbvh_stream_set_interleave(int setting)
{
    atomic_store_explicit(&stream_interleave_setting, setting, memory_order_relaxed);
}

enum cbvh_stream_way cbvh_stream_way_for(const struct cbvh_file *f, uint32_t batch_capacity)
{
    const int wide = f->layout == CBVH_LAYOUT_WIDE4; /* the binary layout has no interleaved walks */
    switch (atomic_load_explicit(&stream_interleave_setting, memory_order_relaxed)) {
    case 1:
        return CBVH_STREAM_BATCHED;
    case 2:
        return wide ? CBVH_STREAM_INTERLEAVED : CBVH_STREAM_BATCHED;
    case 3:
        return wide ? CBVH_STREAM_BY_WINDOW : CBVH_STREAM_BATCHED;
    case 4:
        return CBVH_STREAM_BY_WINDOW_SINGLE;
    default:
        break;
    }
    if (f->vertices_far) /* interleaved walks overlap the misses of incoherent rays (wide layout) */
        return wide ? CBVH_STREAM_BY_WINDOW : CBVH_STREAM_BATCHED;
    /* A mesh in the caches has no misses to overlap. Its incoherent rays share a batch's node visits only
     * when the batch is large for the mesh (at least CBVH_STREAM_SHARED_TRIANGLES_PER_RAY triangles a ray on
     * the wide layout, and more than the stack's batch): otherwise they walk their windows one ray at a
     * time, which is then faster (docs/PERFORMANCE.md). */
    if (batch_capacity <= CBVH_STREAM_STACK_BATCH ||
        (wide && f->info.triangle_count / CBVH_STREAM_SHARED_TRIANGLES_PER_RAY > batch_capacity))
        return CBVH_STREAM_BY_WINDOW_SINGLE;
    return CBVH_STREAM_BATCHED;
}

cbvh_stream_node_fn cbvh_stream_node_kernel(void)
{
    int which = atomic_load_explicit(&stream_kernel_setting, memory_order_relaxed);
#ifdef CBVH_HAVE_SIMD
    if (which == 0 || which == 2)
        return cbvh_stream_node_sse2;
#else
    (void)which;
#endif
    return cbvh_stream_node_scalar;
}
