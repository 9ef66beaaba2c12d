/* stream_avx2.c: the wide layout's stream walks compiled for AVX2, eight leaf triangles a vector for each
 * ray. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#ifdef CBVH_HAVE_AVX2
#if !defined(__AVX2__) || (defined(__GNUC__) && !defined(__FMA__))
#error "stream_avx2.c is compiled with AVX2, BMI1, BMI2 and FMA enabled (configure and CMake add the flags)"
#endif

#include "query/stream_node_simd.h"
#include "query/stream_walk.h"

/* The streams' node test (stream_node_simd.h) in this file's encoding. */
void cbvh_stream_node_avx2(const struct cbvh_stream_batch *restrict batch, const uint16_t *restrict rays,
                           uint32_t n, const struct cbvh_stream_boxes *restrict boxes,
                           const struct cbvh_stream_lists *restrict out, uint32_t count[CBVH_STREAM_LANES])
{
    stream_node_simd(batch, rays, n, boxes, out, count);
}

/* stream.c's instances, this file's instruction set: only the leaves' filter width differs (lanes.h), and
 * the answers are the same bit for bit. node_test: the SSE2 or AVX2 node kernel (stream.c passes the
 * latter). */
void cbvh_stream_wide4_closest_avx2(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,
                                    cbvh_stream_node_fn node_test, int counting, uint8_t *occluded,
                                    uint64_t *visited, uint64_t *tested)
{
    stream_walk(f, CBVH_LAYOUT_WIDE4, b, octant, node_test, 0, counting, occluded, visited, tested);
}

void cbvh_stream_wide4_any_avx2(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant,
                                cbvh_stream_node_fn node_test, int counting, uint8_t *occluded,
                                uint64_t *visited, uint64_t *tested)
{
    stream_walk(f, CBVH_LAYOUT_WIDE4, b, octant, node_test, 1, counting, occluded, visited, tested);
}

void cbvh_stream_interleave_wide4_closest_avx2(const struct cbvh_file *f, struct cbvh_stream_batch *b,
                                               const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                                               int counting, uint64_t *visited, uint64_t *tested)
{
    stream_interleave(f, CBVH_LAYOUT_WIDE4, b, rays, count, 0, hits, NULL, 0, counting, visited, tested);
}

void cbvh_stream_interleave_wide4_any_avx2(const struct cbvh_file *f, struct cbvh_stream_batch *b,
                                           const cbvh_ray *rays, size_t count, uint8_t *occluded,
                                           int counting, uint64_t *visited, uint64_t *tested)
{
    stream_interleave(f, CBVH_LAYOUT_WIDE4, b, rays, count, 1, NULL, occluded, 0, counting, visited, tested);
}
#endif
