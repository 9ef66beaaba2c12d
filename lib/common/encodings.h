/* encodings.h: the one table of known section types and their element encodings (format spec section 4). */
#ifndef CBVH_COMMON_ENCODINGS_H
#define CBVH_COMMON_ENCODINGS_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"
#include "common/format.h"
#include "layout/binary.h"
#include "layout/wide4.h"

/* The writer, the validator, the readers and the tools all read sizes, names and limits from here. The
 * table lives in the header (a static inline lookup) because the tools link the shared library, which
 * exports only cbvh.h's names. */

#define CBVH_KNOWN_SECTIONS 5 /* types 1 (NODES) .. 5 (MATERIALS) */
#define CBVH_MAX_ENCODINGS 3  /* encodings 0 .. 2 of any known type */

typedef struct cbvh_encoding {
    uint32_t element_size; /* bytes per element; 0: no such encoding */
    uint32_t max_value;    /* largest index or id one element holds (index and id encodings), else 0 */
    const char *name;      /* as `cbvh info` prints it */
} cbvh_encoding;

typedef struct cbvh_section_kind {
    const char *name; /* as the spec and the loader's messages spell it */
    int required;     /* a file without it is corrupt */
    cbvh_encoding encodings[CBVH_MAX_ENCODINGS];
} cbvh_section_kind;

/* The known section type `type` (CBVH_SECTION_*), or NULL for any other. */
static inline const cbvh_section_kind *cbvh_section_kind_of(uint32_t type)
{
    static const cbvh_section_kind kinds[CBVH_KNOWN_SECTIONS] = {
        { "NODES", 1,
          { [CBVH_NODES_Q16] = { CBVH_NODE_SIZE, 0, "q16-node" },
            [CBVH_NODES_W4] = { CBVH_W4_NODE_SIZE, 0, "wide4-node" } } },
        { "TRIANGLES", 1,
          { [CBVH_TRIS_U16] = { 6, 0xFFFFu, "u16x3" },
            [CBVH_TRIS_U32] = { 12, 0xFFFFFFFFu, "u32x3" },
            [CBVH_TRIS_DELTA16] = { 8, 0xFFFFFFFFu, "delta16" } } }, /* u32 base, two i16 deltas */
        { "VERTICES", 1, { [CBVH_VERTS_F32] = { 12, 0, "f32x3" }, [CBVH_VERTS_Q16] = { 6, 0, "q16x3" } } },
        { "REMAP", 0, { [CBVH_REMAP_U16] = { 2, 0xFFFFu, "u16" }, [CBVH_REMAP_U32] = { 4, 0xFFFFFFFFu, "u32" } } },
        { "MATERIALS", 0,
          { [CBVH_MATS_U8] = { 1, 0xFFu, "u8" },
            [CBVH_MATS_U16] = { 2, 0xFFFFu, "u16" },
            [CBVH_MATS_U32] = { 4, 0xFFFFFFFFu, "u32" } } },
    };
    return type >= 1 && type <= CBVH_KNOWN_SECTIONS ? &kinds[type - 1] : NULL;
}

/* Encoding `encoding` of section type `type`, or NULL when either is unknown. */
static inline const cbvh_encoding *cbvh_encoding_of(uint32_t type, uint32_t encoding)
{
    const cbvh_section_kind *k = cbvh_section_kind_of(type);
    if (!k || encoding >= CBVH_MAX_ENCODINGS || k->encodings[encoding].element_size == 0)
        return NULL;
    return &k->encodings[encoding];
}

/* Bytes per element of `encoding` in section `type`; 0 when either is unknown. */
static inline uint32_t cbvh_element_size(uint32_t type, uint32_t encoding)
{
    const cbvh_encoding *e = cbvh_encoding_of(type, encoding);
    return e ? e->element_size : 0;
}

#endif
