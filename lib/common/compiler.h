/* compiler.h: the compiler differences in one place: restrict, inlining, hints, target attributes, printf
 * checks. */
#ifndef CBVH_COMMON_COMPILER_H
#define CBVH_COMMON_COMPILER_H

/* The format is little-endian and sections are used in place: a big-endian target is refused at build
 * time (configure refuses it earlier; every Windows target is little-endian). */
#if defined(__BYTE_ORDER__) && defined(__ORDER_BIG_ENDIAN__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
#error "cbvh needs a little-endian host: its files are little-endian and are read in place"
#endif

/* restrict is a C99 keyword; MSVC's C compiler before /std:c11 knows only __restrict. */
#if defined(_MSC_VER) && !defined(__clang__) && (!defined(__STDC_VERSION__) || __STDC_VERSION__ < 201112L)
#define restrict __restrict
#endif

/* SSE2 is the x86-64 baseline: GCC and clang say so with __SSE2__, MSVC with _M_X64 or /arch:SSE2. */
#if defined(__SSE2__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 2)
#define CBVH_SSE2 1
#endif

#if defined(__GNUC__) /* GCC, clang and MinGW-w64 */
/* Kernels are written once with constant flags and instantiated per flag set; forced inlining makes each
 * instance lose the code its flags switch off. Not in the sanitizer builds (configure
 * --enable-sanitizers): the same source checked, without compiling each kernel into every instance,
 * which under ASan + UBSan took minutes (raycast_walks.c alone 95 s, against 9 s without sanitizers). */
#if defined(CBVH_SANITIZER_BUILD)
#define CBVH_FORCE_INLINE static inline
#else
#define CBVH_FORCE_INLINE static inline __attribute__((always_inline))
#endif
#define CBVH_LIKELY(x) __builtin_expect(!!(x), 1)
#define CBVH_COLD __attribute__((noinline, cold))
/* A helper kept out of line: the kernels' many instances call one copy (a path taken once per hit). */
#define CBVH_NOINLINE static __attribute__((noinline, unused))
/* Compiles one function for an instruction set the rest of the build does not assume; callers check
 * cbvh_cpu_features() first (common/cpu.h). */
#define CBVH_TARGET(features) __attribute__((target(features)))
#define CBVH_PREFETCH(p) __builtin_prefetch(p)
/* printf-style checking; MinGW-w64 builds use the C99 printf (__USE_MINGW_ANSI_STDIO), not msvcrt's. */
#if defined(__MINGW32__)
#define CBVH_PRINTF(format_arg, first_arg) __attribute__((format(gnu_printf, format_arg, first_arg)))
#else
#define CBVH_PRINTF(format_arg, first_arg) __attribute__((format(printf, format_arg, first_arg)))
#endif
#elif defined(_MSC_VER)
#define CBVH_FORCE_INLINE static __forceinline
#define CBVH_LIKELY(x) (x)
#define CBVH_COLD __declspec(noinline)
#define CBVH_NOINLINE static __inline __declspec(noinline)
/* MSVC compiles any intrinsic in any function without flags: the run-time dispatch alone keeps AVX2 code
 * off CPUs without it. */
#define CBVH_TARGET(features)
#define CBVH_PRINTF(format_arg, first_arg)
#if defined(_M_X64) || defined(_M_IX86)
#include <xmmintrin.h>
#define CBVH_PREFETCH(p) _mm_prefetch((const char *)(p), _MM_HINT_T0)
#else
#define CBVH_PREFETCH(p) ((void)(p))
#endif
#else
/* Other compilers: no hints. A SIMD build then needs the kernels' files compiled with their own flags
 * (configure --disable-simd otherwise). */
#define CBVH_FORCE_INLINE static inline
#define CBVH_LIKELY(x) (x)
#define CBVH_COLD
#define CBVH_NOINLINE static inline
#define CBVH_TARGET(features)
#define CBVH_PRINTF(format_arg, first_arg)
#define CBVH_PREFETCH(p) ((void)(p))
#endif

/* Unrolls the loop that follows completely (n: its trip count): for the kernels' short fixed loops over
 * lanes and vertices, which compilers otherwise keep as loops with their values stored and reloaded. */
#define CBVH_PRAGMA(x) _Pragma(#x)
#if defined(__clang__)
#define CBVH_UNROLL(n) CBVH_PRAGMA(unroll n)
#elif defined(__GNUC__) && __GNUC__ >= 8
#define CBVH_UNROLL(n) CBVH_PRAGMA(GCC unroll n)
#else
#define CBVH_UNROLL(n)
#endif

#endif
