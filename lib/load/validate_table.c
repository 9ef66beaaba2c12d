/* validate_table.c: checks the section table, the file layout and every section's CRC (format spec sections
 * 2, 4). */
#include <string.h>

#include "layout/encodings.h"
#include "common/endian.h"
#include "common/error.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)

/* Elements a section of `type` in `encoding` holds (sized_by_content kinds: whatever their size says). */
static uint64_t element_count(const cbvh_file_info *in, const cbvh_section_info *s)
{
    const cbvh_encoding *e = cbvh_encoding_of(s->type, s->encoding);
    if (cbvh_section_kind_of(s->type)->sized_by_content)
        return s->size / e->element_size;
    switch (s->type) {
    case CBVH_SECTION_NODES:
        return cbvh_elements_for(e, in->node_count);
    case CBVH_SECTION_VERTICES:
        return cbvh_elements_for(e, in->vertex_count);
    default:
        return cbvh_elements_for(e,
                                 in->triangle_count); /* TRIANGLES, REMAP, MATERIALS: per cooked triangle */
    }
}

cbvh_result cbvh_crc_mismatch(const struct cbvh_file *f, uint32_t index, uint32_t computed, cbvh_error *err)
{
    const cbvh_section_info *s = &f->sections[index];
    return CORRUPT("section %u (type 0x%x) at byte %llu: CRC mismatch (stored 0x%08x, computed 0x%08x)",
                   index, s->type, (unsigned long long)s->offset, s->crc32, computed);
}

/* Bounds, alignment, order and zero padding before it. */
static cbvh_result check_layout(const uint8_t *b, uint64_t file_size, const cbvh_section_info *s, uint32_t i,
                                uint64_t *prev_end, cbvh_error *err)
{
    if (s->offset % CBVH_SECTION_ALIGN != 0)
        return CORRUPT("section %u (type 0x%x): offset %llu is not a multiple of %d", i, s->type,
                       (unsigned long long)s->offset, CBVH_SECTION_ALIGN);
    if (s->offset < *prev_end)
        return CORRUPT("section %u (type 0x%x): offset %llu overlaps %s ending at byte %llu", i, s->type,
                       (unsigned long long)s->offset, i == 0 ? "the section table" : "the previous section",
                       (unsigned long long)*prev_end);
    if (s->offset > file_size || s->stored_size > file_size - s->offset)
        return CORRUPT("section %u (type 0x%x): bytes %llu + %llu run past the end of the file (%llu bytes)",
                       i, s->type, (unsigned long long)s->offset, (unsigned long long)s->stored_size,
                       (unsigned long long)file_size);
    for (uint64_t p = *prev_end; p < s->offset; p++)
        if (b[p] != 0)
            return CORRUPT("byte %llu: padding before section %u is 0x%02x, must be 0", (unsigned long long)p,
                           i, b[p]);
    *prev_end = s->offset + s->stored_size;
    return CBVH_OK;
}

/* Type, codec, encoding and sizes of a known section. Ancillary ones that this reader does not know, or
 * whose codec or encoding it does not know, are skipped whatever they hold. */
static cbvh_result check_content(const cbvh_file_info *in, const cbvh_section_info *sections, uint32_t i,
                                 cbvh_section_map *map, cbvh_error *err)
{
    const cbvh_section_info *s = &sections[i];
    const int slot = cbvh_section_slot(s->type);
    const cbvh_section_kind *k = cbvh_section_kind_of(s->type);
    for (uint32_t j = 0; j < i; j++)
        if (sections[j].type == s->type)
            return k ? CORRUPT("section %u: second %s section (the first is section %u)", i, k->name, j)
                     : CORRUPT("section %u: second section of type 0x%x (the first is section %u)", i,
                               s->type, j);
    const int known_codec = s->codec == CBVH_CODEC_RAW || s->codec == CBVH_CODEC_ZLIB;
    if ((s->type & CBVH_SECTION_ANCILLARY_BIT) &&
        (!k || !known_codec || !cbvh_encoding_of(s->type, s->encoding)))
        return CBVH_OK;
    if (!k || slot < 0)
        return cbvh_fail(err, CBVH_ERROR_UNSUPPORTED,
                         "section %u: critical section type %u is unknown to this reader", i, s->type);
    map->index[slot] = (int)i;
    if (!known_codec)
        return cbvh_fail(err, CBVH_ERROR_UNSUPPORTED, "section %u (%s): codec %u is unknown to this reader",
                         i, k->name, s->codec);
    const uint32_t element_size = cbvh_element_size(s->type, s->encoding);
    if (element_size == 0)
        return cbvh_fail(err, CBVH_ERROR_UNSUPPORTED,
                         "section %u (%s): encoding %u is unknown to this reader", i, k->name, s->encoding);
    if (k->sized_by_content && (s->size < 4 || s->size > CBVH_MAX_MATERIAL_NAME_BYTES))
        return CORRUPT("section %u (%s): size %llu; it must be 4 to %u bytes", i, k->name,
                       (unsigned long long)s->size, CBVH_MAX_MATERIAL_NAME_BYTES);
    uint64_t expected = element_count(in, s) * element_size;
    if (s->size != expected)
        return CORRUPT("section %u (%s): size %llu, expected %llu (%llu elements of %u bytes)", i, k->name,
                       (unsigned long long)s->size, (unsigned long long)expected,
                       (unsigned long long)element_count(in, s), element_size);
    if (s->codec == CBVH_CODEC_RAW && s->stored_size != s->size)
        return CORRUPT("section %u (%s): raw section with stored_size %llu != size %llu", i, k->name,
                       (unsigned long long)s->stored_size, (unsigned long long)s->size);
    return CBVH_OK;
}

cbvh_result cbvh_validate_table(struct cbvh_file *f, cbvh_section_map *map, cbvh_error *err)
{
    const uint8_t *b = f->bytes;
    const uint64_t file_size = f->size;
    const uint32_t count = f->info.section_count;
    const uint64_t table_end = CBVH_HEADER_SIZE + (uint64_t)count * CBVH_SECTION_ENTRY_SIZE;
    if (table_end > file_size)
        return CORRUPT("truncated: the section table ends at byte %llu, the file has %llu bytes",
                       (unsigned long long)table_end, (unsigned long long)file_size);
    uint32_t stored = cbvh_read_u32(b + CBVH_HDR_TABLE_CRC);
    uint32_t actual = cbvh_crc32(0, b + CBVH_HEADER_SIZE, table_end - CBVH_HEADER_SIZE);
    if (stored != actual)
        return CORRUPT("section table CRC mismatch (stored 0x%08x, computed 0x%08x)", stored, actual);

    for (int t = 0; t < CBVH_KNOWN_SECTIONS; t++) {
        map->index[t] = -1;
        map->crc_pending[t] = 0;
    }
    uint64_t prev_end = table_end;
    for (uint32_t i = 0; i < count; i++) {
        const uint8_t *e = b + CBVH_HEADER_SIZE + (size_t)i * CBVH_SECTION_ENTRY_SIZE;
        cbvh_section_info *s = &f->sections[i];
        s->type = cbvh_read_u32(e + CBVH_SEC_TYPE);
        s->codec = cbvh_read_u32(e + CBVH_SEC_CODEC);
        s->offset = cbvh_read_u64(e + CBVH_SEC_OFFSET);
        s->stored_size = cbvh_read_u64(e + CBVH_SEC_STORED_SIZE);
        s->size = cbvh_read_u64(e + CBVH_SEC_SIZE);
        s->crc32 = cbvh_read_u32(e + CBVH_SEC_CRC);
        s->encoding = cbvh_read_u32(e + CBVH_SEC_ENCODING);
        cbvh_result r = check_layout(b, file_size, s, i, &prev_end, err);
        if (r == CBVH_OK)
            r = check_content(&f->info, f->sections, i, map, err);
        if (r != CBVH_OK)
            return r;
        /* A raw known section used in place has its CRC checked with its content, chunk by chunk. */
        const int t = cbvh_section_slot(s->type);
        if (t >= 0 && map->index[t] == (int)i && s->codec == CBVH_CODEC_RAW && cbvh_in_place(f)) {
            map->crc_pending[t] = 1;
            continue;
        }
        uint32_t crc = cbvh_crc32(0, b + s->offset, s->stored_size);
        if (crc != s->crc32)
            return cbvh_crc_mismatch(f, i, crc, err);
    }
    if (prev_end != file_size)
        return CORRUPT("trailing bytes: the last section ends at byte %llu but the file has %llu bytes",
                       (unsigned long long)prev_end, (unsigned long long)file_size);
    for (uint32_t type = 1; type <= CBVH_KNOWN_SECTIONS; type++)
        if (cbvh_section_kind_of(type) && cbvh_section_kind_of(type)->required && map->index[type - 1] < 0)
            return CORRUPT("required section %s is missing", cbvh_section_kind_of(type)->name);
    if (map->index[cbvh_section_slot(CBVH_SECTION_REMAP)] < 0 &&
        f->original_triangle_count != f->info.triangle_count)
        return CORRUPT(
            "header byte %d: original_triangle_count %u != triangle_count %u without a REMAP section",
            CBVH_HDR_ORIGINAL_TRIANGLES, f->original_triangle_count, f->info.triangle_count);
    return CBVH_OK;
}
