/* write.c: the file container: header, section table, 64-byte aligned sections (raw or zlib), CRC32s, zero
 * padding. */
#include <string.h>
#include <zlib.h>

#include "common/alloc.h"
#include "common/crc32.h"
#include "common/endian.h"
#include "common/error.h"
#include "common/format.h"
#include "common/zlib_alloc.h"
#include "cook/cook_internal.h"

/* zlib works in 32-bit chunks; feed it at most this much at a time. */
#define ZCHUNK ((uint64_t)1 << 30)

/* One zlib stream of `size` bytes into a buffer from `a`; *out stays NULL when the
 * stream would not be smaller than the input (the section is then stored raw). */
static cbvh_result deflate_section(const uint8_t *in, uint64_t size, int level, cbvh_allocator *a,
                                   uint8_t **out, uint64_t *out_size)
{
    *out = NULL;
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    cbvh_zlib_use_allocator(&zs, a);
    if (deflateInit(&zs, level) != Z_OK)
        return CBVH_ERROR_OUT_OF_MEMORY;
    uint64_t bound = deflateBound(&zs, (uLong)size);
    uint8_t *buf = cbvh_alloc(a, (size_t)bound, 64);
    if (!buf) {
        deflateEnd(&zs);
        return CBVH_ERROR_OUT_OF_MEMORY;
    }
    uint64_t in_left = size, out_left = bound;
    zs.next_in = (Bytef *)(uintptr_t)in;
    zs.next_out = buf;
    int ret;
    for (;;) {
        if (zs.avail_in == 0 && in_left > 0) {
            zs.avail_in = (uInt)(in_left < ZCHUNK ? in_left : ZCHUNK);
            in_left -= zs.avail_in;
        }
        if (zs.avail_out == 0 && out_left > 0) {
            zs.avail_out = (uInt)(out_left < ZCHUNK ? out_left : ZCHUNK);
            out_left -= zs.avail_out;
        }
        ret = deflate(&zs, in_left == 0 ? Z_FINISH : Z_NO_FLUSH);
        if (ret != Z_OK)
            break;
    }
    uint64_t produced = zs.total_out;
    deflateEnd(&zs);
    if (ret != Z_STREAM_END) {
        cbvh_free(a, buf);
        return ret == Z_MEM_ERROR ? CBVH_ERROR_OUT_OF_MEMORY : CBVH_ERROR_IO;
    }
    if (produced >= size) {
        cbvh_free(a, buf);
        return CBVH_OK;
    }
    *out = buf;
    *out_size = produced;
    return CBVH_OK;
}

static uint64_t align_up(uint64_t x)
{
    return (x + CBVH_SECTION_ALIGN - 1) & ~(uint64_t)(CBVH_SECTION_ALIGN - 1);
}

static void write_f32x3(uint8_t *p, const float v[3])
{
    for (int k = 0; k < 3; k++)
        cbvh_write_f32(p + 4 * k, v[k]);
}

static void write_header(uint8_t *file, const cook_header *h, uint32_t section_count, uint64_t file_size)
{
    memcpy(file + CBVH_HDR_MAGIC, CBVH_MAGIC, CBVH_MAGIC_SIZE);
    cbvh_write_u32(file + CBVH_HDR_VERSION, CBVH_FORMAT_VERSION);
    cbvh_write_u32(file + CBVH_HDR_HEADER_SIZE, CBVH_HEADER_SIZE);
    cbvh_write_u32(file + CBVH_HDR_COMPAT_FLAGS, 0);
    cbvh_write_u32(file + CBVH_HDR_INCOMPAT_FLAGS, h->incompat_flags);
    cbvh_write_u32(file + CBVH_HDR_SECTION_COUNT, section_count);
    cbvh_write_u32(file + CBVH_HDR_TABLE_CRC,
                   cbvh_crc32(0, file + CBVH_HEADER_SIZE, (uint64_t)section_count * CBVH_SECTION_ENTRY_SIZE));
    cbvh_write_u32(file + CBVH_HDR_TRIANGLE_COUNT, h->triangle_count);
    cbvh_write_u32(file + CBVH_HDR_VERTEX_COUNT, h->vertex_count);
    cbvh_write_u32(file + CBVH_HDR_NODE_COUNT, h->node_count);
    cbvh_write_u32(file + CBVH_HDR_DEPTH, h->depth);
    cbvh_write_u32(file + CBVH_HDR_MAX_LEAF, h->max_leaf_size);
    /* Offset 52 holds original_triangle_count (spec section 3). */
    cbvh_write_u32(file + CBVH_HDR_ORIGINAL_TRIANGLES, h->original_triangle_count);
    write_f32x3(file + CBVH_HDR_GRID_ORIGIN, h->grid_origin);
    write_f32x3(file + CBVH_HDR_GRID_SCALE, h->grid_scale);
    write_f32x3(file + CBVH_HDR_BOUNDS_MIN, h->bounds_min);
    write_f32x3(file + CBVH_HDR_BOUNDS_MAX, h->bounds_max);
    cbvh_write_u64(file + CBVH_HDR_FILE_SIZE, file_size);
    cbvh_write_u32(file + CBVH_HDR_HEADER_CRC, cbvh_crc32(0, file, CBVH_HDR_HEADER_CRC));
}

cbvh_result cbvh_cook_write_file(const cook_header *h, cook_sections *s, int compress_level,
                                 cbvh_meter *meter, const cook_progress *progress, uint8_t **out,
                                 size_t *out_size, uint64_t stored_size[CBVH_STATS_SECTION_TYPES],
                                 uint64_t size[CBVH_STATS_SECTION_TYPES], cbvh_error *err)
{
    cbvh_allocator a = cbvh_meter_allocator(meter);
    uint8_t *packed[COOK_SLOTS] = {NULL};
    uint64_t packed_size[COOK_SLOTS] = {0}, offset[COOK_SLOTS] = {0};
    cbvh_result r = CBVH_OK;
    *out = NULL;
    *out_size = 0;

    /* A section that compresses gives its raw bytes back at once. */
    for (uint32_t i = 0; i < s->count && compress_level > 0 && r == CBVH_OK; i++) {
        r = deflate_section(s->s[i].data, s->s[i].size, compress_level, &a, &packed[i], &packed_size[i]);
        if (packed[i]) {
            cbvh_free(&a, s->s[i].data);
            s->s[i].data = NULL;
        }
        cook_report(progress, 0.9 * (i + 1) / s->count);
    }

    uint64_t end = align_up(CBVH_HEADER_SIZE + (uint64_t)s->count * CBVH_SECTION_ENTRY_SIZE);
    for (uint32_t i = 0; i < s->count; i++) {
        if (!packed[i])
            packed_size[i] = s->s[i].size;
        offset[i] = align_up(end);
        end = offset[i] + packed_size[i];
    }
    /* The file is the caller's (cbvh_buffer_free), so it comes from the meter's inner allocator,
     * counted by hand; each section goes as soon as it is copied. */
    uint8_t *file = NULL;
    if (r == CBVH_OK && (uint64_t)(size_t)end == end)
        file = cbvh_alloc(&meter->inner, (size_t)end, 64);
    if (r == CBVH_OK && file) {
        cbvh_meter_count(meter, (size_t)end, 1);
        memset(file, 0, (size_t)end);
        for (uint32_t i = 0; i < s->count; i++) {
            const uint8_t *stored = packed[i] ? packed[i] : s->s[i].data;
            memcpy(file + offset[i], stored, (size_t)packed_size[i]);
            uint8_t *e = file + CBVH_HEADER_SIZE + (size_t)i * CBVH_SECTION_ENTRY_SIZE;
            cbvh_write_u32(e + CBVH_SEC_TYPE, s->s[i].type);
            cbvh_write_u32(e + CBVH_SEC_CODEC, packed[i] ? CBVH_CODEC_ZLIB : CBVH_CODEC_RAW);
            cbvh_write_u64(e + CBVH_SEC_OFFSET, offset[i]);
            cbvh_write_u64(e + CBVH_SEC_STORED_SIZE, packed_size[i]);
            cbvh_write_u64(e + CBVH_SEC_SIZE, s->s[i].size);
            cbvh_write_u32(e + CBVH_SEC_CRC, cbvh_crc32(0, file + offset[i], packed_size[i]));
            cbvh_write_u32(e + CBVH_SEC_ENCODING, s->s[i].encoding);
            stored_size[s->s[i].type & ~CBVH_SECTION_ANCILLARY_BIT] = packed_size[i];
            size[s->s[i].type & ~CBVH_SECTION_ANCILLARY_BIT] = s->s[i].size;
            cbvh_free(&a, packed[i]);
            packed[i] = NULL;
            cbvh_free(&a, s->s[i].data);
            s->s[i].data = NULL;
        }
        write_header(file, h, s->count, end);
        cbvh_meter_count(meter, (size_t)end, 0); /* handed to the caller */
        *out = file;
        *out_size = (size_t)end;
    } else if (r == CBVH_OK) {
        r = CBVH_ERROR_OUT_OF_MEMORY;
    }
    for (uint32_t i = 0; i < s->count; i++)
        cbvh_free(&a, packed[i]);
    if (r == CBVH_ERROR_OUT_OF_MEMORY)
        return cbvh_fail(err, r, "out of memory while writing the file (%llu bytes)",
                         (unsigned long long)end);
    if (r != CBVH_OK)
        return cbvh_fail(err, r, "zlib failed to compress a section");
    cook_report(progress, 1.0);
    return CBVH_OK;
}
