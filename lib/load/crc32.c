/* crc32.c: CRC32 of any number of bytes with zlib's crc32(), which takes at most UINT_MAX bytes per call. */
#include <limits.h>
#include <zlib.h>

#include "load/load.h"

uint32_t cbvh_crc32(const uint8_t *data, uint64_t size)
{
    uLong crc = crc32(0L, Z_NULL, 0);
    while (size > 0) {
        uInt n = size > UINT_MAX ? UINT_MAX : (uInt)size;
        crc = crc32(crc, data, n);
        data += n;
        size -= n;
    }
    return (uint32_t)crc;
}
