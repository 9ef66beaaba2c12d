/* cpu_x86.c: x86 CPU feature detection (CPUID and XGETBV) behind cbvh_cpu_features(). */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include "common/cpu.h"

#if defined(CBVH_HAVE_SIMD) && defined(__GNUC__)
unsigned cbvh_cpu_features(void)
{
    /* libgcc and compiler-rt run CPUID and XGETBV once at program start. */
    unsigned f = 0;
    if (__builtin_cpu_supports("sse4.1"))
        f |= CBVH_CPU_SSE41;
    if (__builtin_cpu_supports("pclmul"))
        f |= CBVH_CPU_PCLMUL;
    if (__builtin_cpu_supports("avx2"))
        f |= CBVH_CPU_AVX2;
    if (__builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2"))
        f |= CBVH_CPU_BMI;
    if (__builtin_cpu_supports("fma"))
        f |= CBVH_CPU_FMA;
    return f;
}
#elif defined(CBVH_HAVE_SIMD) && defined(_MSC_VER) && (defined(_M_X64) || defined(_M_IX86))
#include <immintrin.h>
#include <intrin.h>

static unsigned detect(void)
{
    int r[4];
    __cpuid(r, 0);
    const int max_leaf = r[0];
    __cpuid(r, 1);
    unsigned f = 0;
    if (r[2] & (1 << 19))
        f |= CBVH_CPU_SSE41;
    if (r[2] & (1 << 1))
        f |= CBVH_CPU_PCLMUL;
    /* AVX2 needs OSXSAVE and the OS saving the XMM and YMM state (XCR0 bits 1 and 2). */
    const int osxsave = (r[2] & (1 << 27)) != 0, fma = (r[2] & (1 << 12)) != 0;
    if (osxsave && fma && (_xgetbv(0) & 6) == 6)
        f |= CBVH_CPU_FMA;
    if (max_leaf >= 7 && osxsave && (_xgetbv(0) & 6) == 6) {
        __cpuidex(r, 7, 0);
        if (r[1] & (1 << 5))
            f |= CBVH_CPU_AVX2;
        if ((r[1] & (1 << 3)) && (r[1] & (1 << 8)))
            f |= CBVH_CPU_BMI;
    }
    return f;
}

unsigned cbvh_cpu_features(void)
{
    /* Racing first calls compute the same value; a plain int store is atomic on x86. */
    static volatile unsigned cached; /* bit 31 marks it computed */
    unsigned f = cached;
    if (!f) {
        f = detect() | 0x80000000u;
        cached = f;
    }
    return f & 0x7fffffffu;
}
#else
unsigned cbvh_cpu_features(void)
{
    return 0;
}
#endif
