/* inflate.c: inflates one zlib section into an exactly sized, 64-byte aligned buffer, through the caller's
 * allocator. */
#include <limits.h>
#include <stdint.h>
#include <zlib.h>

#include "common/alloc.h"
#include "common/error.h"
#include "common/zlib_alloc.h"
#include "load/load.h"

/* Hands zlib the next piece of a buffer longer than a uInt can say. */
static void feed(Bytef **next, uInt *avail, uint8_t **cursor, uint64_t *left)
{
    uInt n = *left > UINT_MAX ? UINT_MAX : (uInt)*left;
    *next = *cursor;
    *avail = n;
    *cursor += n;
    *left -= n;
}

/* Runs the stream to its end; a full output buffer gets a 1-byte scratch so a stream longer than declared
 * shows. */
static cbvh_result run(z_stream *zs, uint8_t *in, uint64_t stored_size, uint8_t *out, uint64_t size,
                       uint32_t index, cbvh_error *err)
{
    uint64_t in_left = stored_size, out_left = size;
    uint8_t scratch;
    int overflow = 0;
    for (;;) {
        if (zs->avail_in == 0 && in_left > 0)
            feed(&zs->next_in, &zs->avail_in, &in, &in_left);
        if (zs->avail_out == 0) {
            if (out_left > 0) {
                feed(&zs->next_out, &zs->avail_out, &out, &out_left);
            } else {
                zs->next_out = &scratch;
                zs->avail_out = 1;
                overflow = 1;
            }
        }
        int ret = inflate(zs, Z_NO_FLUSH);
        if (overflow && zs->avail_out == 0)
            return cbvh_fail(err, CBVH_ERROR_CORRUPT,
                             "section %u: zlib stream inflates to more than its size %llu", index,
                             (unsigned long long)size);
        if (ret == Z_STREAM_END)
            break;
        if (ret == Z_OK)
            continue;
        if (ret == Z_MEM_ERROR)
            return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "section %u: out of memory in zlib", index);
        if (ret == Z_BUF_ERROR)
            return cbvh_fail(
                err, CBVH_ERROR_CORRUPT,
                "section %u: zlib stream is cut short: inflated %llu of %llu bytes from all %llu stored",
                index, (unsigned long long)(size - out_left - zs->avail_out), (unsigned long long)size,
                (unsigned long long)stored_size);
        return cbvh_fail(err, CBVH_ERROR_CORRUPT, "section %u: bad zlib stream at stored byte %llu (%s)",
                         index, (unsigned long long)(stored_size - in_left - zs->avail_in),
                         zs->msg ? zs->msg : "no detail");
    }
    uint64_t produced = size - out_left - zs->avail_out;
    uint64_t consumed = stored_size - in_left - zs->avail_in;
    if (produced != size)
        return cbvh_fail(err, CBVH_ERROR_CORRUPT,
                         "section %u: zlib stream inflates to %llu bytes, its size is %llu", index,
                         (unsigned long long)produced, (unsigned long long)size);
    if (consumed != stored_size)
        return cbvh_fail(err, CBVH_ERROR_CORRUPT, "section %u: zlib stream ends at stored byte %llu of %llu",
                         index, (unsigned long long)consumed, (unsigned long long)stored_size);
    return CBVH_OK;
}

cbvh_result cbvh_inflate_section(const cbvh_allocator *a, const uint8_t *src, uint64_t stored_size,
                                 uint64_t size, size_t lead, uint32_t section_index, void **out,
                                 cbvh_error *err)
{
    *out = NULL;
    if (size > SIZE_MAX - lead)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "section %u: %llu bytes do not fit in memory",
                         section_index, (unsigned long long)size);
    uint8_t *buffer = cbvh_alloc_walked(a, lead + (size_t)size, 64);
    if (!buffer)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY,
                         "section %u: cannot allocate %llu bytes to inflate into", section_index,
                         (unsigned long long)size);
    z_stream zs = {0};
    cbvh_zlib_use_allocator(&zs, a);
    int ret = inflateInit(&zs);
    cbvh_result r;
    if (ret == Z_OK) {
        r = run(&zs, (uint8_t *)src, stored_size, buffer + lead, size, section_index, err);
        inflateEnd(&zs);
    } else {
        r = cbvh_fail(err, ret == Z_MEM_ERROR ? CBVH_ERROR_OUT_OF_MEMORY : CBVH_ERROR_CORRUPT,
                      "section %u: cannot start inflating (zlib error %d)", section_index, ret);
    }
    if (r != CBVH_OK) {
        cbvh_free(a, buffer);
        return r;
    }
    *out = buffer;
    return CBVH_OK;
}
