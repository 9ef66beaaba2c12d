/* crc32.c: CRC32 of any number of bytes: the PCLMULQDQ kernel for the bulk when the CPU has it, zlib for the
 * rest. */
#include <limits.h>
#include <zlib.h>

#include "common/crc32.h"

/* zlib's crc32() takes at most UINT_MAX bytes per call. */
static uint32_t crc32_zlib(uint32_t crc, const uint8_t *data, uint64_t size)
{
    uLong c = crc;
    while (size > 0) {
        uInt n = size > UINT_MAX ? UINT_MAX : (uInt)size;
        c = crc32(c, data, n);
        data += n;
        size -= n;
    }
    return (uint32_t)c;
}

uint32_t cbvh_crc32(uint32_t crc, const uint8_t *data, uint64_t size)
{
    if (size < 64 || size > SIZE_MAX || !cbvh_crc32_pclmul_available())
        return crc32_zlib(crc, data, size);
    /* the kernel works on the inverted state; zlib's crc32() inverts on entry and exit */
    size_t bulk = (size_t)size & ~(size_t)15;
    uint32_t state = cbvh_crc32_pclmul(~crc, data, bulk);
    return crc32_zlib(~state, data + bulk, size - bulk);
}
