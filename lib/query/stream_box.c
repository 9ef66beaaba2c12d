/* stream_box.c: the scalar batch node test. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

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
