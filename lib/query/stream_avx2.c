/* stream_avx2.c: the wide layout's stream walks compiled for AVX2, eight leaf triangles a vector for each
 * ray. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#ifdef CBVH_HAVE_AVX2
#if !defined(__AVX2__) || (defined(__GNUC__) && !defined(__FMA__))
#error "stream_avx2.c is compiled with AVX2, BMI1, BMI2 and FMA enabled (configure and CMake add the flags)"
#endif

#include "query/stream_walk.h"

/* The streams' node test (stream_walk.h's stream_node_simd) in this file's encoding. */
CBVH_STREAM_NODE_KERNEL(cbvh_stream_node_avx2)
{
    stream_node_simd(batch, rays, n, boxes, out, count);
}

/* stream.c's wide instances in this file's instruction set: the same answers bit for bit. */
STREAM_BATCH_INSTANCE(stream_closest, CBVH_LAYOUT_WIDE4, 0)
STREAM_BATCH_INSTANCE(stream_any, CBVH_LAYOUT_WIDE4, 1)
STREAM_INTERLEAVE_INSTANCE(interleave_closest, 0)
STREAM_INTERLEAVE_INSTANCE(interleave_any, 1)

void cbvh_stream_wide4_avx2(const struct cbvh_file *f, struct cbvh_stream_batch *b, uint32_t octant, int any,
                            int counting, uint8_t *occluded, uint64_t *visited, uint64_t *tested)
{
    (any ? stream_any : stream_closest)(f, b, octant, cbvh_stream_node_avx2, counting, occluded, visited,
                                        tested);
}

void cbvh_stream_interleave_avx2(const struct cbvh_file *f, struct cbvh_stream_batch *b, const cbvh_ray *rays,
                                 size_t count, cbvh_hit *hits, uint8_t *occluded, int counting,
                                 uint64_t *visited, uint64_t *tested)
{
    (hits ? interleave_closest : interleave_any)(f, b, rays, count, hits, occluded, 0, counting, visited,
                                                 tested);
}
#endif
