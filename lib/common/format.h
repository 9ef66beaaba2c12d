/* format.h: constants and bit layouts of the cbvh file format v1 (normative text: fileformat/cbvh-format.md). */
#ifndef CBVH_COMMON_FORMAT_H
#define CBVH_COMMON_FORMAT_H

#include <stdint.h>

/* 89 'C' 'B' 'V' 'H' CR LF 1A: the high byte catches 7-bit channels, CR LF
 * catches line-ending conversion, 1A stops DOS `type` (as PNG does). */
#define CBVH_MAGIC "\x89" "CBVH\r\n\x1a"
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

/* Element encodings per section. */
enum { CBVH_NODES_Q16 = 0 };                                     /* 16 bytes per node */
enum { CBVH_TRIS_U16 = 0, CBVH_TRIS_U32 = 1, CBVH_TRIS_DELTA16 = 2 }; /* 6, 12, 8 bytes */
enum { CBVH_VERTS_F32 = 0, CBVH_VERTS_Q16 = 1 };                  /* 12, 6 bytes */
enum { CBVH_REMAP_U16 = 0, CBVH_REMAP_U32 = 1 };                  /* 2, 4 bytes */
enum { CBVH_MATS_U8 = 0, CBVH_MATS_U16 = 1, CBVH_MATS_U32 = 2 };  /* 1, 2, 4 bytes */

/* Limits. Nodes: 23 bits of subtree size in an internal node's word.
 * Triangles: 27 bits of first-triangle index in a leaf's word. Depth: the
 * sorted traversal's fixed stack. */
#define CBVH_MAX_NODES 0x7FFFFFu
#define CBVH_MAX_TRIANGLES 0x7FFFFFFu
#define CBVH_MAX_LEAF_SIZE 16u
#define CBVH_MAX_DEPTH 64u

/* A node: a conservative 16-bit box on the file's grid plus one word.
 *   internal: bit 31 = 0, bits 30..23 = sort byte, bits 22..0 = subtree size
 *             in nodes (the escape link is index + size; the first child is
 *             index + 1, the second child is the first child's escape).
 *   leaf:     bit 31 = 1, bits 30..27 = triangle count - 1, bits 26..0 =
 *             first triangle (in cooked order); its escape is index + 1.
 * Sort byte bit k, for ray octant k (bit 0: dir.x < 0, bit 1: dir.y < 0,
 * bit 2: dir.z < 0, signs taken from the reciprocal direction): set when the
 * second child is nearer and is visited first. */
typedef struct cbvh_node {
    uint16_t qmin[3];
    uint16_t qmax[3];
    uint32_t word;
} cbvh_node;

#define CBVH_NODE_LEAF_BIT 0x80000000u
#define CBVH_NODE_SIZE_MASK 0x7FFFFFu
#define CBVH_NODE_SORT_SHIFT 23
#define CBVH_NODE_COUNT_SHIFT 27
#define CBVH_NODE_FIRST_MASK 0x7FFFFFFu

static inline int cbvh_node_is_leaf(uint32_t word) { return (word & CBVH_NODE_LEAF_BIT) != 0; }
static inline uint32_t cbvh_node_subtree_size(uint32_t word) { return word & CBVH_NODE_SIZE_MASK; }
static inline uint32_t cbvh_node_sort_byte(uint32_t word) { return (word >> CBVH_NODE_SORT_SHIFT) & 0xFFu; }
static inline uint32_t cbvh_leaf_first(uint32_t word) { return word & CBVH_NODE_FIRST_MASK; }
static inline uint32_t cbvh_leaf_count(uint32_t word) { return ((word >> CBVH_NODE_COUNT_SHIFT) & 0xFu) + 1u; }

static inline uint32_t cbvh_make_internal(uint32_t subtree_size, uint32_t sort_byte)
{
    return (sort_byte << CBVH_NODE_SORT_SHIFT) | subtree_size;
}
static inline uint32_t cbvh_make_leaf(uint32_t first, uint32_t count)
{
    return CBVH_NODE_LEAF_BIT | ((count - 1u) << CBVH_NODE_COUNT_SHIFT) | first;
}

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
