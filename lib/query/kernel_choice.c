/* kernel_choice.c: which walk kernel and stream way the queries take. Built twice: into the library, and
 * with CBVH_TEST_HOOKS (test_hooks.h's settings, so the tests run every kernel and way) for the tests. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include <stdatomic.h>

#include "common/cpu.h"
#include "query/raycast.h"
#include "query/stream.h"
#ifdef CBVH_TEST_HOOKS
#include "query/test_hooks.h"
#endif

atomic_int cbvh_walk_kernel_chosen;

/* The best kernel this build and CPU have at or below `kernel`. */
static int walk_kernel_available(int kernel)
{
#ifdef CBVH_HAVE_SIMD
#ifdef CBVH_HAVE_AVX2
    const unsigned avx2 = CBVH_CPU_AVX2 | CBVH_CPU_BMI | CBVH_CPU_FMA;
    if (kernel >= CBVH_WALK_KERNEL_AVX2 && (cbvh_cpu_features() & avx2) == avx2)
        return CBVH_WALK_KERNEL_AVX2;
#endif
    return kernel >= CBVH_WALK_KERNEL_SSE2 ? CBVH_WALK_KERNEL_SSE2 : CBVH_WALK_KERNEL_SCALAR;
#else
    (void)kernel;
    return CBVH_WALK_KERNEL_SCALAR;
#endif
}

/* Makes the walks take the best kernel available at or below `kernel` (BEST: the best of all); returns it. */
static int walk_kernel_choose(int kernel)
{
    const int chosen =
        walk_kernel_available(kernel == CBVH_WALK_KERNEL_BEST ? CBVH_WALK_KERNEL_AVX2 : kernel);
    atomic_store_explicit(&cbvh_walk_kernel_chosen, chosen, memory_order_relaxed);
    return chosen;
}

int cbvh_walk_kernel_choose_best(void)
{
    return walk_kernel_choose(CBVH_WALK_KERNEL_BEST);
}

#ifdef CBVH_TEST_HOOKS
static atomic_int stream_kernel_setting, stream_way_setting;
#define SETTING(name) atomic_load_explicit(&(name), memory_order_relaxed)

int cbvh_walk_set_kernel(int kernel)
{
    return walk_kernel_choose(kernel);
}

void cbvh_stream_set_kernel(int which)
{
    atomic_store_explicit(&stream_kernel_setting, which, memory_order_relaxed);
}

void cbvh_stream_set_way(int setting)
{
    atomic_store_explicit(&stream_way_setting, setting, memory_order_relaxed);
}
#else
/* The library's settings: 0, by the build, the mesh and the batch. */
#define SETTING(name) 0
#endif

enum cbvh_stream_way cbvh_stream_way_for(const struct cbvh_file *f, uint32_t batch_capacity)
{
    const int wide = f->layout == CBVH_LAYOUT_WIDE4; /* the binary layout has no interleaved walks */
    switch (SETTING(stream_way_setting)) {
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
    /* a mesh in the caches batches incoherent rays only when the batch is large for it */
    if (batch_capacity <= CBVH_STREAM_STACK_BATCH ||
        (wide && f->info.triangle_count / CBVH_STREAM_SHARED_TRIANGLES_PER_RAY > batch_capacity))
        return CBVH_STREAM_BY_WINDOW_SINGLE;
    return CBVH_STREAM_BATCHED;
}

cbvh_stream_node_fn cbvh_stream_node_kernel(void)
{
#ifdef CBVH_HAVE_SIMD
    if (SETTING(stream_kernel_setting) != 1)
        return cbvh_stream_node_sse2;
#endif
    return cbvh_stream_node_scalar;
}
