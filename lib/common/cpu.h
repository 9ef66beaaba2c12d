/* cpu.h: which optional instruction sets the running CPU has, for the kernels chosen at run time. */
#ifndef CBVH_COMMON_CPU_H
#define CBVH_COMMON_CPU_H

enum {
    CBVH_CPU_SSE41 = 1u << 0,
    CBVH_CPU_PCLMUL = 1u << 1,
    CBVH_CPU_AVX2 = 1u << 2, /* also means the operating system saves the AVX registers */
    CBVH_CPU_BMI = 1u << 3,  /* BMI1 and BMI2 */
    CBVH_CPU_FMA = 1u << 4   /* FMA3 */
};

/* The CBVH_CPU_* bits of this CPU; 0 off x86 or in a build without SIMD kernels. Thread-safe and cheap
 * (computed once). */
unsigned cbvh_cpu_features(void);

#endif
