/* endian.h: little-endian readers and writers for file fields, safe at any alignment. */
#ifndef CBVH_COMMON_ENDIAN_H
#define CBVH_COMMON_ENDIAN_H

#include <stdint.h>
#include <string.h>

static inline uint32_t cbvh_read_u32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static inline uint64_t cbvh_read_u64(const uint8_t *p)
{
    return (uint64_t)cbvh_read_u32(p) | (uint64_t)cbvh_read_u32(p + 4) << 32;
}
static inline float cbvh_read_f32(const uint8_t *p)
{
    uint32_t u = cbvh_read_u32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}
static inline void cbvh_write_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

static inline void cbvh_write_u32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
static inline void cbvh_write_u64(uint8_t *p, uint64_t v)
{
    cbvh_write_u32(p, (uint32_t)v);
    cbvh_write_u32(p + 4, (uint32_t)(v >> 32));
}
static inline void cbvh_write_f32(uint8_t *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    cbvh_write_u32(p, u);
}

/* In-place use of raw sections needs a little-endian host. */
static inline int cbvh_host_is_little_endian(void)
{
    const uint16_t one = 1;
    return *(const uint8_t *)&one == 1;
}

#endif
