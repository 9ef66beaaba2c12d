/* validate_header.c: checks the 128-byte header (format spec section 3) and copies its fields. */
#include <math.h>
#include <string.h>

#include "common/endian.h"
#include "common/error.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)

static void read_vec3(const uint8_t *p, float v[3])
{
    for (int a = 0; a < 3; a++)
        v[a] = cbvh_read_f32(p + 4 * a);
}

static const char *axis_name(int a)
{
    return a == 0 ? "x" : a == 1 ? "y" : "z";
}

/* Magic and version come first: a newer version may change everything after them. */
static cbvh_result check_identity(const uint8_t *b, size_t size, cbvh_error *err)
{
    size_t n = size < CBVH_MAGIC_SIZE ? size : CBVH_MAGIC_SIZE;
    if (memcmp(b, CBVH_MAGIC, n) != 0) {
        size_t i = 0;
        while (b[i] == (uint8_t)CBVH_MAGIC[i])
            i++;
        return CORRUPT("not a cbvh file: bad magic at byte %zu (0x%02x instead of 0x%02x)%s", i, b[i],
                       (uint8_t)CBVH_MAGIC[i],
                       i >= 5 ? "; line endings converted by a text-mode transfer?" : "");
    }
    if (size < CBVH_HDR_VERSION + 4)
        return CORRUPT("truncated: %zu bytes, the header needs %d", size, CBVH_HEADER_SIZE);
    uint32_t version = cbvh_read_u32(b + CBVH_HDR_VERSION);
    if (version == 0)
        return CORRUPT("header byte %d: format version 0 is not valid", CBVH_HDR_VERSION);
    if (version > CBVH_FORMAT_VERSION)
        return cbvh_fail(err, CBVH_ERROR_UNSUPPORTED, "format version %u is newer than this reader's (%d)",
                         version, CBVH_FORMAT_VERSION);
    if (size < CBVH_HEADER_SIZE)
        return CORRUPT("truncated: %zu bytes, the header needs %d", size, CBVH_HEADER_SIZE);
    uint32_t stored = cbvh_read_u32(b + CBVH_HDR_HEADER_CRC);
    uint32_t actual = cbvh_crc32(0, b, CBVH_HDR_HEADER_CRC);
    if (stored != actual)
        return CORRUPT("header CRC mismatch (byte %d: stored 0x%08x, computed 0x%08x)", CBVH_HDR_HEADER_CRC,
                       stored, actual);
    return CBVH_OK;
}

/* Counts and limits of format spec sections 3 and 7. */
static cbvh_result check_counts(const cbvh_file_info *in, uint32_t original, cbvh_error *err)
{
    if (in->section_count < 3 || in->section_count > CBVH_MAX_SECTIONS)
        return CORRUPT("header byte %d: section_count %u is outside 3..%d", CBVH_HDR_SECTION_COUNT,
                       in->section_count, CBVH_MAX_SECTIONS);
    if (in->triangle_count < 1 || in->triangle_count > CBVH_MAX_TRIANGLES)
        return CORRUPT("header byte %d: triangle_count %u is outside 1..%u", CBVH_HDR_TRIANGLE_COUNT,
                       in->triangle_count, CBVH_MAX_TRIANGLES);
    /* Every stored vertex is used, so at most 3 per triangle: this also bounds what a zlib section may
     * inflate to. */
    if (in->vertex_count < 3 || (uint64_t)in->vertex_count > 3u * (uint64_t)in->triangle_count)
        return CORRUPT("header byte %d: vertex_count %u is outside 3..3 x triangle_count (%u)",
                       CBVH_HDR_VERTEX_COUNT, in->vertex_count, in->triangle_count);
    if (in->node_count < 1 || in->node_count > CBVH_MAX_NODES)
        return CORRUPT("header byte %d: node_count %u is outside 1..%u", CBVH_HDR_NODE_COUNT, in->node_count,
                       CBVH_MAX_NODES);
    if (in->depth < 1 || in->depth > CBVH_MAX_DEPTH)
        return CORRUPT("header byte %d: depth %u is outside 1..%u", CBVH_HDR_DEPTH, in->depth,
                       CBVH_MAX_DEPTH);
    if (in->max_leaf_size < 1 || in->max_leaf_size > CBVH_MAX_LEAF_SIZE)
        return CORRUPT("header byte %d: max_leaf_size %u is outside 1..%u", CBVH_HDR_MAX_LEAF,
                       in->max_leaf_size, CBVH_MAX_LEAF_SIZE);
    if (original < in->triangle_count)
        return CORRUPT("header byte %d: original_triangle_count %u is below triangle_count %u",
                       CBVH_HDR_ORIGINAL_TRIANGLES, original, in->triangle_count);
    return CBVH_OK;
}

/* Grid and bounds must be finite so every dequantized coordinate is finite. */
static cbvh_result check_grid(const cbvh_file_info *in, cbvh_error *err)
{
    for (int a = 0; a < 3; a++) {
        if (!isfinite(in->grid_origin[a]) || !isfinite(in->grid_scale[a]) || !(in->grid_scale[a] >= 0.0f))
            return CORRUPT("header: grid on axis %s (origin %g, scale %g) must be finite with scale >= 0",
                           axis_name(a), (double)in->grid_origin[a], (double)in->grid_scale[a]);
        if (!isfinite(cbvh_dequantize(CBVH_Q_MAX, in->grid_origin[a], in->grid_scale[a])))
            return CORRUPT("header: grid on axis %s overflows: coordinate 65535 dequantizes to infinity",
                           axis_name(a));
        if (!isfinite(in->bounds_min[a]) || !isfinite(in->bounds_max[a]) ||
            !(in->bounds_min[a] <= in->bounds_max[a]))
            return CORRUPT("header: bounds on axis %s [%g, %g] must be finite with min <= max", axis_name(a),
                           (double)in->bounds_min[a], (double)in->bounds_max[a]);
    }
    return CBVH_OK;
}

cbvh_result cbvh_validate_header(struct cbvh_file *f, cbvh_error *err)
{
    const uint8_t *b = f->bytes;
    if (f->size == 0)
        return CORRUPT("not a cbvh file: it is empty");
    cbvh_result r = check_identity(b, f->size, err);
    if (r != CBVH_OK)
        return r;

    uint32_t header_size = cbvh_read_u32(b + CBVH_HDR_HEADER_SIZE);
    if (header_size != CBVH_HEADER_SIZE)
        return CORRUPT("header byte %d: header_size %u, version 1 has %d", CBVH_HDR_HEADER_SIZE, header_size,
                       CBVH_HEADER_SIZE);
    cbvh_file_info *in = &f->info;
    memset(in, 0, sizeof *in);
    in->format_version = cbvh_read_u32(b + CBVH_HDR_VERSION);
    in->compat_flags = cbvh_read_u32(b + CBVH_HDR_COMPAT_FLAGS);
    in->incompat_flags = cbvh_read_u32(b + CBVH_HDR_INCOMPAT_FLAGS);
    if (in->incompat_flags & ~CBVH_INCOMPAT_KNOWN)
        return cbvh_fail(err, CBVH_ERROR_UNSUPPORTED,
                         "incompatible feature flags 0x%08x are unknown to this reader",
                         in->incompat_flags & ~CBVH_INCOMPAT_KNOWN);
    for (int i = CBVH_HDR_RESERVED1; i < CBVH_HDR_HEADER_CRC; i++)
        if (b[i] != 0)
            return CORRUPT("header byte %d: reserved byte is 0x%02x, must be 0", i, b[i]);

    in->section_count = cbvh_read_u32(b + CBVH_HDR_SECTION_COUNT);
    in->triangle_count = cbvh_read_u32(b + CBVH_HDR_TRIANGLE_COUNT);
    in->vertex_count = cbvh_read_u32(b + CBVH_HDR_VERTEX_COUNT);
    in->node_count = cbvh_read_u32(b + CBVH_HDR_NODE_COUNT);
    in->depth = cbvh_read_u32(b + CBVH_HDR_DEPTH);
    in->max_leaf_size = cbvh_read_u32(b + CBVH_HDR_MAX_LEAF);
    f->original_triangle_count = cbvh_read_u32(b + CBVH_HDR_ORIGINAL_TRIANGLES);
    r = check_counts(in, f->original_triangle_count, err);
    if (r != CBVH_OK)
        return r;

    read_vec3(b + CBVH_HDR_GRID_ORIGIN, in->grid_origin);
    read_vec3(b + CBVH_HDR_GRID_SCALE, in->grid_scale);
    read_vec3(b + CBVH_HDR_BOUNDS_MIN, in->bounds_min);
    read_vec3(b + CBVH_HDR_BOUNDS_MAX, in->bounds_max);
    r = check_grid(in, err);
    if (r != CBVH_OK)
        return r;
    memcpy(f->grid_origin, in->grid_origin, sizeof f->grid_origin);
    memcpy(f->grid_scale, in->grid_scale, sizeof f->grid_scale);

    in->file_size = cbvh_read_u64(b + CBVH_HDR_FILE_SIZE);
    if (in->file_size != (uint64_t)f->size)
        return CORRUPT("header byte %d: file_size is %llu but the file has %zu bytes (%s)",
                       CBVH_HDR_FILE_SIZE, (unsigned long long)in->file_size, f->size,
                       in->file_size > (uint64_t)f->size ? "truncated" : "trailing bytes");
    return CBVH_OK;
}
