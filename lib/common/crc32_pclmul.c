/* crc32_pclmul.c: CRC32 by carry-less multiplication (x86 PCLMULQDQ), folding 64 bytes per step. */
#include "config.h"

#include "common/compiler.h"
#include "common/cpu.h"
#include "common/crc32.h"

#ifdef CBVH_HAVE_SIMD
#include <immintrin.h>

/* Folding constants of the bit-reflected CRC-32 polynomial 0x04C11DB7, from Gopal et al., "Fast CRC
 * Computation for Generic Polynomials Using PCLMULQDQ Instruction" (Intel, 2009): x^(4*128+32) and
 * x^(4*128-32) mod P (fold by 64 bytes), x^(128+32) and x^(128-32) mod P (fold by 16 bytes),
 * x^64 mod P (fold 96 to 64 bits), then P' = floor(x^64 / P) and P for the Barrett reduction. */
static const uint64_t fold_64_bytes[2] = {0x0154442bd4u, 0x01c6e41596u};
static const uint64_t fold_16_bytes[2] = {0x01751997d0u, 0x00ccaa009eu};
static const uint64_t fold_96_bits = 0x0163cd6124u;
static const uint64_t barrett[2] = {0x01db710641u, 0x01f7011641u};

CBVH_TARGET("pclmul,sse4.1") static inline __m128i fold(__m128i acc, __m128i k, __m128i next)
{
    __m128i lo = _mm_clmulepi64_si128(acc, k, 0x00);
    __m128i hi = _mm_clmulepi64_si128(acc, k, 0x11);
    return _mm_xor_si128(_mm_xor_si128(lo, hi), next);
}

static inline __m128i load(const uint8_t *p)
{
    return _mm_loadu_si128((const __m128i *)p);
}

/* `crc` is the running state before the final inversion; size >= 64 and a multiple of 16. */
CBVH_TARGET("pclmul,sse4.1") uint32_t cbvh_crc32_pclmul(uint32_t crc, const uint8_t *restrict p, size_t size)
{
    __m128i a = _mm_xor_si128(load(p), _mm_cvtsi32_si128((int)crc));
    __m128i b = load(p + 16), c = load(p + 32), d = load(p + 48);
    __m128i k = _mm_loadu_si128((const __m128i *)fold_64_bytes);
    p += 64;
    size -= 64;
    /* four independent accumulators keep the multiplier busy */
    for (; size >= 64; p += 64, size -= 64) {
        a = fold(a, k, load(p));
        b = fold(b, k, load(p + 16));
        c = fold(c, k, load(p + 32));
        d = fold(d, k, load(p + 48));
    }
    k = _mm_loadu_si128((const __m128i *)fold_16_bytes);
    a = fold(a, k, b);
    a = fold(a, k, c);
    a = fold(a, k, d);
    for (; size >= 16; p += 16, size -= 16)
        a = fold(a, k, load(p));

    /* 128 -> 96 -> 64 bits */
    const __m128i low32 = _mm_setr_epi32(-1, 0, -1, 0);
    __m128i t = _mm_clmulepi64_si128(a, k, 0x10);
    a = _mm_xor_si128(_mm_srli_si128(a, 8), t);
    t = _mm_srli_si128(a, 4);
    a = _mm_clmulepi64_si128(_mm_and_si128(a, low32), _mm_cvtsi64_si128((long long)fold_96_bits), 0x00);
    a = _mm_xor_si128(a, t);

    /* Barrett reduction to 32 bits */
    k = _mm_loadu_si128((const __m128i *)barrett);
    t = _mm_clmulepi64_si128(_mm_and_si128(a, low32), k, 0x10);
    t = _mm_clmulepi64_si128(_mm_and_si128(t, low32), k, 0x00);
    return (uint32_t)_mm_extract_epi32(_mm_xor_si128(a, t), 1);
}

int cbvh_crc32_pclmul_available(void)
{
    const unsigned needed = CBVH_CPU_PCLMUL | CBVH_CPU_SSE41;
    return (cbvh_cpu_features() & needed) == needed;
}
#else
int cbvh_crc32_pclmul_available(void)
{
    return 0;
}

uint32_t cbvh_crc32_pclmul(uint32_t crc, const uint8_t *p, size_t size)
{
    (void)p;
    (void)size;
    return crc;
}
#endif
