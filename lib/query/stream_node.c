/* stream_node.c: the batch node tests, scalar and SSE2 (stream_walk.h's stream_node_simd); kernel_choice.c
 * picks one. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include "query/stream_walk.h"

CBVH_STREAM_NODE_KERNEL(cbvh_stream_node_scalar)
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

#ifdef CBVH_HAVE_SIMD
CBVH_STREAM_NODE_KERNEL(cbvh_stream_node_sse2)
{
    stream_node_simd(batch, rays, n, boxes, out, count);
}
#endif
