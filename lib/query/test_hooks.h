/* test_hooks.h: the settings by which the tests run every query kernel and way on their small meshes. Only
 * in lib/libcbvh_test_hooks.la (kernel_choice.c built with CBVH_TEST_HOOKS), which the test programs link
 * before the library; the library itself, static or shared, has none of them. Each is meant to be set
 * between queries; reads are atomic, so concurrent queries stay defined. */
#ifndef CBVH_QUERY_TEST_HOOKS_H
#define CBVH_QUERY_TEST_HOOKS_H

/* The kernel the wide layout's walks take from now on (an enum cbvh_walk_kernel of raycast.h; one the
 * build or the CPU lacks falls back to the best below it). Every kernel gives the same answers bit for
 * bit, so tests compare them. Returns the kernel the walks now take (never BEST). */
int cbvh_walk_set_kernel(int kernel);

/* The streams' node kernel: 0 = the best for this build (default), 1 = scalar, 2 = SSE2 (scalar when not
 * built; with the AVX2 walks chosen, the streams run its copy in AVX2's encoding). */
void cbvh_stream_set_kernel(int which);

/* The streams' way (enum cbvh_stream_way of stream.h): 0 = by the mesh and the batch (default,
 * kernel_choice.c's cbvh_stream_way_for), 1 = batched, 2 = interleaved, 3 = by window, 4 = by window with
 * single rays (2 and 3: batched on the binary layout, which has no interleaved walks). */
void cbvh_stream_set_way(int setting);

#endif
