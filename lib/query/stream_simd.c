/* stream_simd.c: the batch node test, a ray against four child boxes, with SSE2 (stream_node_simd.h). */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#ifdef CBVH_HAVE_SIMD
#include "query/stream_node_simd.h"

void cbvh_stream_node_sse2(const struct cbvh_stream_batch *restrict batch, const uint16_t *restrict rays,
                           uint32_t n, const struct cbvh_stream_boxes *restrict boxes,
                           const struct cbvh_stream_lists *restrict out, uint32_t count[CBVH_STREAM_LANES])
{
    stream_node_simd(batch, rays, n, boxes, out, count);
}
#endif
