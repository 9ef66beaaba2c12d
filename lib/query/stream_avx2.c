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
STREAM_INSTANCES(, cbvh_stream_wide4_avx2, CBVH_LAYOUT_WIDE4)
#endif
