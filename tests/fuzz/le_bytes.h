/* le_bytes.h: little-endian fields of a cbvh file read and written at any alignment, for the tests and fuzz
 * tools that take files apart. Kept apart from the library's own readers, so that a test does not share a
 * fault of the code it checks. */
#ifndef CBVH_TESTS_LE_BYTES_H
#define CBVH_TESTS_LE_BYTES_H

#include <stdint.h>
#include <string.h>

static inline uint32_t le_get_u16(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8;
}
static inline uint32_t le_get_u32(const uint8_t *p)
{
    return le_get_u16(p) | le_get_u16(p + 2) << 16;
}
static inline uint64_t le_get_u64(const uint8_t *p)
{
    return (uint64_t)le_get_u32(p) | (uint64_t)le_get_u32(p + 4) << 32;
}
static inline float le_get_f32(const uint8_t *p)
{
    const uint32_t u = le_get_u32(p);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
static inline void le_put_u16(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static inline void le_put_u32(uint8_t *p, uint32_t v)
{
    le_put_u16(p, v);
    le_put_u16(p + 2, v >> 16);
}
static inline void le_put_u64(uint8_t *p, uint64_t v)
{
    le_put_u32(p, (uint32_t)v);
    le_put_u32(p + 4, (uint32_t)(v >> 32));
}

#endif
