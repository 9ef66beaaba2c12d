/* format.h: constants and bit layouts of the cbvh file format v1 (normative: fileformat/cbvh-format.md). */
#ifndef CBVH_COMMON_FORMAT_H
#define CBVH_COMMON_FORMAT_H

#include <stdint.h>

#include "cbvh.h" /* CBVH_MAX_LEAF_SIZE */

/* 89 'C' 'B' 'V' 'H' CR LF 1A: the high byte catches 7-bit channels, CR LF
 * catches line-ending conversion, 1A stops DOS `type` (as PNG does). */
#define CBVH_MAGIC                                                                                           \
    "\x89"                                                                                                   \
    "CBVH\r\n\x1a"
#define CBVH_MAGIC_SIZE 8

#define CBVH_HEADER_SIZE 128
#define CBVH_SECTION_ENTRY_SIZE 40
#define CBVH_SECTION_ALIGN 64
#define CBVH_MAX_SECTIONS 16

/* Header field offsets (little-endian). */
enum {
    CBVH_HDR_MAGIC = 0,
    CBVH_HDR_VERSION = 8,
    CBVH_HDR_HEADER_SIZE = 12,
    CBVH_HDR_COMPAT_FLAGS = 16,
    CBVH_HDR_INCOMPAT_FLAGS = 20,
    CBVH_HDR_SECTION_COUNT = 24,
    CBVH_HDR_TABLE_CRC = 28,
    CBVH_HDR_TRIANGLE_COUNT = 32,
    CBVH_HDR_VERTEX_COUNT = 36,
    CBVH_HDR_NODE_COUNT = 40,
    CBVH_HDR_DEPTH = 44,
    CBVH_HDR_MAX_LEAF = 48,
    CBVH_HDR_ORIGINAL_TRIANGLES = 52,
    CBVH_HDR_GRID_ORIGIN = 56, /* float[3] */
    CBVH_HDR_GRID_SCALE = 68,  /* float[3] */
    CBVH_HDR_BOUNDS_MIN = 80,  /* float[3] */
    CBVH_HDR_BOUNDS_MAX = 92,  /* float[3] */
    CBVH_HDR_FILE_SIZE = 104,  /* u64 */
    CBVH_HDR_RESERVED1 = 112,  /* 12 zero bytes */
    CBVH_HDR_HEADER_CRC = 124  /* CRC32 of bytes [0,124) */
};

/* Header incompat_flags bits a reader of this version knows (spec section 2). Bit 0 is reserved: its test
 * vector stands for a feature no reader knows. */
#define CBVH_INCOMPAT_W4_DEPTH_FIRST 0x2u /* wide4 leaves hold the triangles in depth-first order (5.2) */
#define CBVH_INCOMPAT_KNOWN CBVH_INCOMPAT_W4_DEPTH_FIRST

/* Section table entry field offsets. */
enum {
    CBVH_SEC_TYPE = 0,
    CBVH_SEC_CODEC = 4,
    CBVH_SEC_OFFSET = 8,       /* u64 */
    CBVH_SEC_STORED_SIZE = 16, /* u64 */
    CBVH_SEC_SIZE = 24,        /* u64 */
    CBVH_SEC_CRC = 32,         /* CRC32 of the stored bytes */
    CBVH_SEC_ENCODING = 36
};

#define CBVH_SECTION_ANCILLARY_BIT 0x80000000u /* unknown ancillary sections are skipped */

enum { CBVH_CODEC_RAW = 0, CBVH_CODEC_ZLIB = 1 };

/* Element encodings per section (element sizes, names and limits: layout/encodings.h). */
enum { CBVH_NODES_Q16 = 0, CBVH_NODES_W4 = 1 }; /* binary, wide4 layout */
/* TRIANGLES encoding 3 is reserved: the vector fileformat/unsupported-encoding stands for an unknown one.
 * Each encoding's bytes: layout/triangle_encodings.h. */
enum { CBVH_TRIS_U16 = 0, CBVH_TRIS_U32 = 1, CBVH_TRIS_DELTA16 = 2, CBVH_TRIS_LOCAL8 = 4 };
enum { CBVH_VERTS_F32 = 0, CBVH_VERTS_Q16 = 1 };
enum { CBVH_REMAP_U16 = 0, CBVH_REMAP_U32 = 1, CBVH_REMAP_U24 = 2 };
enum { CBVH_MATS_U8 = 0, CBVH_MATS_U16 = 1, CBVH_MATS_U32 = 2, CBVH_MATS_UNIFORM = 3 };
enum { CBVH_NAMES_TABLE = 0 }; /* MATERIAL_NAMES: u32 count, (u32 id, u32 offset) entries, NUL-ended names */

/* Limits of any file; each layout has narrower ones of its own
 * (layout/binary.h, layout/wide4.h). Nodes and triangles: what a wide4 child
 * reference can name. Depth: the walks' fixed stacks. */
#define CBVH_MAX_NODES 0x7FFFFFFFu
#define CBVH_MAX_TRIANGLES 0x10000000u
/* CBVH_MAX_LEAF_SIZE: cbvh.h */
#define CBVH_MAX_DEPTH 64u

/* The largest grid coordinate of a 16-bit box. */
#define CBVH_Q_MAX 65535u

/* Dequantization, normative: origin + (float)q * scale, each operation rounded
 * to binary32 (no fused multiply-add; the library is built with
 * -ffp-contract=off). The cooker checks conservativeness with this function. */
static inline float cbvh_dequantize(uint32_t q, float origin, float scale)
{
    float scaled = (float)q * scale;
    return origin + scaled;
}

#endif
