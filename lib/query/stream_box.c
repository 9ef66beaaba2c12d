/* stream_box.c: the scalar batch box test and the run-time choice of the batch box kernel. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include <stdatomic.h>

#include "common/cpu.h"
#include "query/ray_box.h"
#include "query/stream.h"

uint32_t cbvh_stream_box_scalar(const struct cbvh_stream_batch *restrict batch, uint16_t *restrict live, uint32_t n,
                                const float near[3], const float far[3])
{
    const float nx = near[0], ny = near[1], nz = near[2], fx = far[0], fy = far[1], fz = far[2];
    uint32_t w = 0;
    for (uint32_t j = 0; j < n; j++) {
        const float *r = batch->box_ray[live[j]];
        const float org[3] = {r[CBVH_LANE_OX], r[CBVH_LANE_OY], r[CBVH_LANE_OZ]};
        const float rcp[3] = {r[CBVH_LANE_RX], r[CBVH_LANE_RY], r[CBVH_LANE_RZ]};
        float entry;
        if (cbvh_slab_test(nx, ny, nz, fx, fy, fz, org, rcp, r[CBVH_LANE_TMIN], r[CBVH_LANE_TMAX], &entry)) {
            uint16_t tmp = live[w];
            live[w] = live[j];
            live[j] = tmp;
            w++;
        }
    }
    return w;
}

static atomic_int stream_kernel_setting;

void cbvh_stream_set_kernel(int which)
{
    atomic_store_explicit(&stream_kernel_setting, which, memory_order_relaxed);
}

cbvh_stream_box_fn cbvh_stream_box_kernel(void)
{
    int which = atomic_load_explicit(&stream_kernel_setting, memory_order_relaxed);
#ifdef CBVH_HAVE_SIMD
    int avx2 = (cbvh_cpu_features() & CBVH_CPU_AVX2) != 0;
    if (which == 0)
        return avx2 ? cbvh_stream_box_avx2 : cbvh_stream_box_sse2;
    if (which == 2)
        return cbvh_stream_box_sse2;
    if (which == 3 && avx2)
        return cbvh_stream_box_avx2;
#else
    (void)which;
#endif
    return cbvh_stream_box_scalar;
}
