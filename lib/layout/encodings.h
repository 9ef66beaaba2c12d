/* encodings.h: the one table of known section types and their element encodings (format spec section 4). */
#ifndef CBVH_LAYOUT_ENCODINGS_H
#define CBVH_LAYOUT_ENCODINGS_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"
#include "common/format.h"
#include "layout/binary.h"
#include "layout/triangle_encodings.h"
#include "layout/wide4.h"

/* The writer, the validator, the readers and the tools all read sizes, names and limits from here. The
 * table lives in the header (a static inline lookup) because the tools link the shared library, which
 * exports only cbvh.h's names. */

/* A known section's number is its type without the ancillary bit: 1 (NODES) .. 6 (MATERIAL_NAMES). Numbers
 * are unique across critical and ancillary types, so they index tables (and cbvh_cook_stats' arrays). */
#define CBVH_KNOWN_SECTIONS 6
#define CBVH_MAX_ENCODINGS 5 /* encodings 0 .. 4 of any known type */

typedef struct cbvh_encoding {
    uint32_t element_size; /* bytes per element; 0: no such encoding */
    uint32_t max_value;    /* largest index or id one element holds (index and id encodings), else 0 */
    const char *name;      /* as `cbvh info` prints it */
    int uniform;           /* one element stands for every triangle (MATERIALS' uniform id) */
    uint32_t group;        /* entries one element holds (TRIANGLES LOCAL8: a block of 8 triangles); 0: one */
} cbvh_encoding;

typedef struct cbvh_section_kind {
    const char *name;     /* as the spec and the loader's messages spell it */
    int required;         /* a file without it is corrupt */
    int ancillary;        /* its type has the ancillary bit */
    int sized_by_content; /* its size is any number of elements, checked against its content */
    cbvh_encoding encodings[CBVH_MAX_ENCODINGS];
} cbvh_section_kind;

/* The index (number - 1) of the known section type `type` in tables of CBVH_KNOWN_SECTIONS entries, or -1 for
 * any other type. */
static inline int cbvh_section_slot(uint32_t type)
{
    const uint32_t number = type & ~CBVH_SECTION_ANCILLARY_BIT;
    const int ancillary = (type & CBVH_SECTION_ANCILLARY_BIT) != 0;
    if (number < 1 || number > CBVH_KNOWN_SECTIONS)
        return -1;
    return ancillary == (number == (CBVH_SECTION_MATERIAL_NAMES & ~CBVH_SECTION_ANCILLARY_BIT))
               ? (int)number - 1
               : -1;
}

/* The known section type `type` (CBVH_SECTION_*), or NULL for any other. */
static inline const cbvh_section_kind *cbvh_section_kind_of(uint32_t type)
{
    static const cbvh_section_kind kinds[CBVH_KNOWN_SECTIONS] = {
        {"NODES",
         1,
         0,
         0,
         {[CBVH_NODES_Q16] = {CBVH_NODE_SIZE, 0, "q16-node"},
          [CBVH_NODES_W4] = {CBVH_W4_NODE_SIZE, 0, "wide4-node"}}},
        {"TRIANGLES",
         1,
         0,
         0,
         {[CBVH_TRIS_U16] = {CBVH_TRIS_U16_SIZE, 0xFFFFu, "u16x3"},
          [CBVH_TRIS_U32] = {CBVH_TRIS_U32_SIZE, 0xFFFFFFFFu, "u32x3"},
          [CBVH_TRIS_DELTA16] = {CBVH_TRIS_DELTA16_SIZE, 0xFFFFFFFFu, "delta16"},
          [CBVH_TRIS_LOCAL8] = {CBVH_LOCAL8_BLOCK_SIZE, 0xFFFFFFFFu, "local8", 0, CBVH_LOCAL8_BLOCK}}},
        {"VERTICES", 1, 0, 0, {[CBVH_VERTS_F32] = {12, 0, "f32x3"}, [CBVH_VERTS_Q16] = {6, 0, "q16x3"}}},
        {"REMAP",
         0,
         0,
         0,
         {[CBVH_REMAP_U16] = {2, 0xFFFFu, "u16", 0},
          [CBVH_REMAP_U32] = {4, 0xFFFFFFFFu, "u32", 0},
          [CBVH_REMAP_U24] = {3, 0xFFFFFFu, "u24", 0}}},
        {"MATERIALS",
         0,
         0,
         0,
         {[CBVH_MATS_U8] = {1, 0xFFu, "u8", 0},
          [CBVH_MATS_U16] = {2, 0xFFFFu, "u16", 0},
          [CBVH_MATS_U32] = {4, 0xFFFFFFFFu, "u32", 0},
          [CBVH_MATS_UNIFORM] = {4, 0xFFFFFFFFu, "uniform", 1}}},
        {"MATERIAL_NAMES", 0, 1, 1, {[CBVH_NAMES_TABLE] = {1, 0, "id-name-table", 0}}},
    };
    const int slot = cbvh_section_slot(type);
    return slot >= 0 ? &kinds[slot] : NULL;
}

/* Encoding `encoding` of section type `type`, or NULL when either is unknown. */
static inline const cbvh_encoding *cbvh_encoding_of(uint32_t type, uint32_t encoding)
{
    const cbvh_section_kind *k = cbvh_section_kind_of(type);
    if (!k || encoding >= CBVH_MAX_ENCODINGS || k->encodings[encoding].element_size == 0)
        return NULL;
    return &k->encodings[encoding];
}

/* Elements a section in encoding e holds for `entries` entries (triangles, vertices, nodes): one for a
 * uniform encoding, one per group of entries for a grouped one (the last group may be partly used). */
static inline uint64_t cbvh_elements_for(const cbvh_encoding *e, uint64_t entries)
{
    if (e->uniform)
        return 1;
    const uint64_t group = e->group ? e->group : 1;
    return (entries + group - 1) / group;
}

/* Bytes per element of `encoding` in section `type`; 0 when either is unknown. */
static inline uint32_t cbvh_element_size(uint32_t type, uint32_t encoding)
{
    const cbvh_encoding *e = cbvh_encoding_of(type, encoding);
    return e ? e->element_size : 0;
}

#endif
