/* file_view.c: an opened file's stored mesh, material storage and the names of its format values, and the
 * CPU's features, for the tools. */
#include <string.h>

#include "cbvh_internal.h"
#include "layout/encodings.h"
#include "layout/triangle_encodings.h"
#include "common/cpu.h"
#include "common/endian.h"
#include "common/file.h"
#include "common/format.h"

_Static_assert(CBVH_MAGIC_BYTES == CBVH_MAGIC_SIZE, "cbvh_has_magic reads the whole magic");

void cbvh_file_mesh(const cbvh_file *file, float *positions, uint32_t *indices)
{
    const struct cbvh_file *f = file;
    for (uint32_t v = 0; v < f->info.vertex_count; v++)
        cbvh_vertex_position(f, v, positions + 3 * (size_t)v);
    for (uint32_t t = 0; t < f->info.triangle_count; t++)
        cbvh_triangle_indices(f, t, indices + 3 * (size_t)cbvh_original_id(f, t));
}

cbvh_material_storage cbvh_file_material_storage(const cbvh_file *file, uint32_t *uniform_id)
{
    if (!file->materials)
        return CBVH_MATERIALS_NONE;
    if (file->material_encoding != CBVH_MATS_UNIFORM)
        return CBVH_MATERIALS_PER_TRIANGLE;
    if (uniform_id)
        *uniform_id = cbvh_read_u32((const uint8_t *)file->materials);
    return CBVH_MATERIALS_UNIFORM;
}

const char *cbvh_encoding_name(uint32_t type, uint32_t encoding)
{
    const cbvh_encoding *e = cbvh_encoding_of(type, encoding);
    return e ? e->name : "?";
}

const char *cbvh_codec_name(uint32_t codec)
{
    return codec == CBVH_CODEC_RAW ? "raw" : codec == CBVH_CODEC_ZLIB ? "zlib" : "?";
}

int cbvh_has_magic(const void *bytes, size_t size)
{
    return size >= CBVH_MAGIC_SIZE && memcmp(bytes, CBVH_MAGIC, CBVH_MAGIC_SIZE) == 0;
}

int cbvh_cpu_has_avx2_fma(void)
{
    const unsigned needed = CBVH_CPU_AVX2 | CBVH_CPU_FMA;
    return (cbvh_cpu_features() & needed) == needed;
}
