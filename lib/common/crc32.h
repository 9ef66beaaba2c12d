/* crc32.h: the CRC32 of the file format (zlib's), for the writer and the loader. */
#ifndef CBVH_COMMON_CRC32_H
#define CBVH_COMMON_CRC32_H

#include <stddef.h>
#include <stdint.h>

/* CRC32 of `size` more bytes, zlib style (start from 0, feed the result back to continue), any size:
 * by carry-less multiplication when the CPU has it, else with zlib. */
uint32_t cbvh_crc32(uint32_t crc, const uint8_t *data, uint64_t size);

/* The PCLMULQDQ kernel: the running (uninverted) state after `size` more bytes, size >= 64 and a
 * multiple of 16; callable only when cbvh_crc32_pclmul_available() says so. */
uint32_t cbvh_crc32_pclmul(uint32_t crc, const uint8_t *data, size_t size);
int cbvh_crc32_pclmul_available(void);

#endif
