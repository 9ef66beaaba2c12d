/* test_vectors.c: every file in fileformat/ loads (or is rejected) as its expectation below says, by path and
 * from memory. */
#include <dirent.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cbvh.h"

/* ------------------------------------------------------------------ the meshes the vectors were made from */

typedef struct mesh {
    float v[16][3];
    uint32_t t[24][3];
    uint32_t triangle_count;
} mesh;

enum {
    MESH_SINGLE,
    MESH_BOX,
    MESH_BOX_FAR,
    MESH_QUAD,
    MESH_BOX_DEGENERATE,
    MESH_QUAD_SPARSE,
    MESH_TWO_BOXES,
    MESH_COUNT
};

static mesh meshes[MESH_COUNT];

/* fileformat/make_vectors.py's box: corners from {-1.5, 2.25} x {0, 3} x {1, 5}, two triangles per face. */
static void make_box(mesh *m, float offset, int degenerate)
{
    static const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (int i = 0; i < 8; i++) {
        m->v[i][0] = (i & 1 ? 2.25f : -1.5f) + offset;
        m->v[i][1] = i >> 1 & 1 ? 3.0f : 0.0f;
        m->v[i][2] = i >> 2 & 1 ? 5.0f : 1.0f;
    }
    uint32_t n = 0;
    for (int f = 0; f < 6; f++) {
        for (int h = 0; h < 2; h++) {
            if (degenerate && (n == 3 || n == 9)) { /* original ids 3 and 9 are zero-area triangles */
                uint32_t d[3] = {0, 0, 1};
                if (n == 9)
                    d[0] = 2, d[1] = 5, d[2] = 2;
                memcpy(m->t[n++], d, sizeof d);
            }
            uint32_t t[3] = {faces[f][0], faces[f][1 + h], faces[f][2 + h]};
            memcpy(m->t[n++], t, sizeof t);
        }
    }
    m->triangle_count = n;
}

static void make_meshes(void)
{
    mesh *s = &meshes[MESH_SINGLE];
    const float sv[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0.5f}};
    memcpy(s->v, sv, sizeof sv);
    s->t[0][0] = 0, s->t[0][1] = 1, s->t[0][2] = 2;
    s->triangle_count = 1;
    make_box(&meshes[MESH_BOX], 0.0f, 0);
    make_box(&meshes[MESH_BOX_FAR], 70000.0f, 0);
    make_box(&meshes[MESH_BOX_DEGENERATE], 0.0f, 1);
    mesh *q = &meshes[MESH_QUAD];
    const float qv[4][3] = {{0, 0, 2.5f}, {4, 0, 2.5f}, {4, 2, 2.5f}, {0, 2, 2.5f}};
    memcpy(q->v, qv, sizeof qv);
    const uint32_t qt[2][3] = {{0, 1, 2}, {0, 2, 3}};
    memcpy(q->t, qt, sizeof qt);
    q->triangle_count = 2;
    /* the quad's triangles at original ids 1 and 4 of 5, the others degenerate */
    mesh *p = &meshes[MESH_QUAD_SPARSE];
    memcpy(p->v, qv, sizeof qv);
    const uint32_t pt[5][3] = {{0, 0, 1}, {0, 1, 2}, {1, 1, 1}, {2, 3, 2}, {0, 2, 3}};
    memcpy(p->t, pt, sizeof pt);
    p->triangle_count = 5;
    /* make_vectors.py's TWO_BOXES: the box, then a copy 10 along x (vertices 8..15) */
    mesh *two = &meshes[MESH_TWO_BOXES];
    make_box(two, 0.0f, 0);
    mesh copy;
    make_box(&copy, 10.0f, 0);
    for (int i = 0; i < 8; i++)
        memcpy(two->v[8 + i], copy.v[i], sizeof copy.v[i]);
    for (uint32_t j = 0; j < copy.triangle_count; j++)
        for (int k = 0; k < 3; k++)
            two->t[two->triangle_count + j][k] = copy.t[j][k] + 8;
    two->triangle_count += copy.triangle_count;
}

/* ------------------------------------------------------------------ expectations (fileformat/README.md) */

typedef struct good {
    int mesh;
    uint32_t triangle_count, vertex_count, node_count, depth, max_leaf_size;
    uint32_t has_remap, vertex_format, index_encoding, compat_flags, section_count;
    uint32_t material_base;    /* materials are base + 7 x original id; 0: no MATERIALS section */
    uint32_t layout;           /* cbvh_layout of the nodes */
    uint32_t uniform_material; /* the one id of a uniform MATERIALS section (material_base 0) */
    uint32_t name_count;       /* 3: fileformat/make_vectors.py's NAMES, else 0 */
    uint32_t incompat_flags;   /* 0x2: wide4 leaves depth first */
} good;

typedef struct expectation {
    const char *name;
    cbvh_result code;
    const char *message; /* a part of the error message naming the check */
    good g;
} expectation;

#define BAD(name, text)                                                                                      \
    {                                                                                                        \
        name, CBVH_ERROR_CORRUPT, text,                                                                      \
        {                                                                                                    \
            0                                                                                                \
        }                                                                                                    \
    }
#define NEWER(name, text)                                                                                    \
    {                                                                                                        \
        name, CBVH_ERROR_UNSUPPORTED, text,                                                                  \
        {                                                                                                    \
            0                                                                                                \
        }                                                                                                    \
    }
#define BIN CBVH_LAYOUT_BINARY
#define W4 CBVH_LAYOUT_WIDE4

static const expectation expectations[] = {
    {"good-single-triangle", CBVH_OK, "", {MESH_SINGLE, 1, 3, 1, 1, 4, 0, 0, 0, 0, 3, 0, BIN, 0, 0, 0}},
    {"good-box-raw", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-box-zlib", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-box-u32", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 1, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-box-delta16", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 2, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-box-q16", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 1, 0, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-box-far-q16", CBVH_OK, "", {MESH_BOX_FAR, 12, 8, 15, 4, 2, 1, 1, 0, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-quad-flat", CBVH_OK, "", {MESH_QUAD, 2, 4, 3, 2, 1, 1, 0, 0, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-remap-materials",
     CBVH_OK,
     "",
     {MESH_BOX_DEGENERATE, 12, 8, 15, 4, 2, 1, 0, 0, 0, 5, 1, BIN, 0, 0, 0}},
    {"good-remap-u32-materials-u32-zlib",
     CBVH_OK,
     "",
     {MESH_BOX_DEGENERATE, 12, 8, 15, 4, 2, 1, 0, 2, 0, 5, 70000, BIN, 0, 0, 0}},
    {"good-remap-sparse", CBVH_OK, "", {MESH_QUAD_SPARSE, 2, 4, 3, 2, 1, 1, 0, 0, 0, 5, 3, BIN, 0, 0, 0}},
    {"good-remap-u24", CBVH_OK, "", {MESH_BOX_DEGENERATE, 12, 8, 15, 4, 2, 1, 0, 0, 0, 5, 1, BIN, 0, 0, 0}},
    BAD("bad-remap-u24-range", "original id 16777215"),
    {"good-materials-u16-cooked-ids",
     CBVH_OK,
     "",
     {MESH_BOX, 12, 8, 15, 4, 2, 0, 0, 0, 0, 4, 1000, BIN, 0, 0, 0}},
    {"good-ancillary", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0, 6, 0, BIN, 0, 0, 0}},
    {"good-compat-flags", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0x80000005u, 4, 0, BIN, 0, 0, 0}},
    {"good-materials-uniform", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0, 5, 0, BIN, 7, 0, 0}},
    {"good-material-names", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0, 6, 0, BIN, 7, 3, 0}},
    {"good-material-names-zlib", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0, 6, 0, BIN, 7, 3, 0}},
    {"good-material-names-future", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 0, 0, 6, 0, BIN, 7, 0, 0}},
    BAD("bad-materials-uniform-size", "size 8, expected 4"),
    BAD("bad-names-order", "not after name 1"),
    BAD("bad-names-duplicate", "name 2 (id 7) is not after"),
    BAD("bad-names-offset", "name 1 starts at offset 7"),
    BAD("bad-names-no-nul", "no terminating NUL"),
    BAD("bad-names-trailing", "1 bytes after the last name"),
    BAD("bad-names-count", "1000 names do not fit"),
    BAD("bad-names-empty", "size 0; it must be 4 to"),
    BAD("bad-names-too-big", "size 16777217; it must be 4 to"),
    BAD("bad-names-second", "second MATERIAL_NAMES section"),
    NEWER("unsupported-materials-encoding-4", "encoding 4"),
    BAD("bad-empty", "empty"),
    BAD("bad-magic", "bad magic at byte 1"),
    BAD("bad-text-mode", "text-mode"),
    BAD("bad-version-0", "format version 0"),
    BAD("bad-truncated-header", "truncated"),
    BAD("bad-header-crc", "header CRC"),
    BAD("bad-header-size", "header_size 64"),
    BAD("bad-reserved", "byte 115: reserved"),
    BAD("bad-section-count", "section_count 2"),
    BAD("bad-triangle-count", "triangle_count 0"),
    BAD("bad-vertex-count", "vertex_count 37"),
    BAD("bad-node-count", "node_count 0"),
    BAD("bad-depth-limit", "depth 65"),
    BAD("bad-max-leaf-size", "max_leaf_size 17"),
    BAD("bad-original-count", "original_triangle_count 11 is below"),
    BAD("bad-grid-nan", "grid on axis y"),
    BAD("bad-grid-overflow", "overflows"),
    BAD("bad-bounds-inverted", "bounds on axis z"),
    BAD("bad-truncated", "(truncated)"),
    BAD("bad-trailing-byte", "(trailing bytes)"),
    BAD("bad-trailing-section-gap", "trailing bytes: the last section ends"),
    BAD("bad-table-crc", "section table CRC"),
    BAD("bad-table-past-end", "section table ends at byte 768"),
    BAD("bad-section-crc", "section 0 (type 0x1) at byte 320: CRC mismatch"),
    BAD("bad-section-misaligned", "section 1 (type 0x2): offset 580 is not a multiple of 64"),
    BAD("bad-section-overlap", "section 1 (type 0x2): offset 384 overlaps the previous section"),
    BAD("bad-section-over-table", "overlaps the section table"),
    BAD("bad-section-past-end", "section 2 (type 0x3): bytes"),
    BAD("bad-padding", "byte 575: padding before section 1"),
    BAD("bad-duplicate-section", "second VERTICES"),
    BAD("bad-duplicate-ancillary", "second section of type 0x80000007"),
    BAD("bad-missing-nodes", "required section NODES"),
    BAD("bad-section-size", "size 132, expected 144"),
    BAD("bad-raw-stored-size", "stored_size 256 != size 240"),
    BAD("bad-zlib-short", "inflates to 66 bytes"),
    BAD("bad-zlib-long", "more than its size"),
    BAD("bad-zlib-trailing", "ends at stored byte"),
    BAD("bad-zlib-cut", "cut short"),
    BAD("bad-zlib-garbage", "bad zlib stream"),
    BAD("bad-root-size", "node 0: subtree size 9"),
    BAD("bad-escape-self", "has subtree size 0"),
    BAD("bad-escape-past-parent", "leaving no room"),
    BAD("bad-second-child", "node 8: subtree size 3, but its parent leaves it nodes [8, 15)"),
    BAD("bad-leaf-past-end", "run past triangle_count"),
    BAD("bad-leaf-gap", "previous leaf ended at 1"),
    BAD("bad-leaves-short", "leaves cover triangles [0, 12), triangle_count is 13"),
    BAD("bad-leaf-too-big", "more than max_leaf_size"),
    BAD("bad-depth-mismatch", "the tree's depth is 4"),
    BAD("bad-depth-exceeded", "deeper than the header"),
    BAD("bad-qmin-gt-qmax", "node 2: qmin 100 > qmax 50 on axis 1"),
    BAD("bad-index-u16", "triangle 5 (cooked order): vertex indices"),
    BAD("bad-index-u32", "triangle 11 (cooked order): vertex indices"),
    BAD("bad-delta16-negative", "triangle 0 (cooked order): DELTA16"),
    BAD("bad-delta16-wrap", "triangle 1 (cooked order): DELTA16"),
    BAD("bad-vertex-nan", "vertex 3: coordinate 2"),
    BAD("bad-bounds-mismatch", "differ from the vertices' bounds"),
    BAD("bad-remap-duplicate", "both hold original id"),
    BAD("bad-remap-range", "original_triangle_count is 14"),
    BAD("bad-remap-duplicate-sparse", "REMAP entries 0 and 1 both hold original id 4"),
    BAD("bad-remap-range-sparse", "REMAP entry 1: original id 5"),
    BAD("bad-remap-missing", "without a REMAP section"),
    NEWER("unsupported-version-2", "format version 2"),
    NEWER("unsupported-incompat-flag", "incompatible feature flags 0x00000001"),
    NEWER("unsupported-codec", "codec 2"),
    NEWER("unsupported-encoding", "encoding 3"),
    NEWER("unsupported-critical-section", "critical section type 6"),
    {"good-w4-single-triangle", CBVH_OK, "", {MESH_SINGLE, 1, 3, 1, 1, 4, 0, 0, 0, 0, 3, 0, W4, 0, 0, 0}},
    {"good-w4-box-raw", CBVH_OK, "", {MESH_BOX, 12, 8, 3, 2, 2, 1, 0, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-box-zlib", CBVH_OK, "", {MESH_BOX, 12, 8, 3, 2, 2, 1, 0, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-box-leaf1", CBVH_OK, "", {MESH_BOX, 12, 8, 5, 3, 1, 1, 0, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-box-leaf8", CBVH_OK, "", {MESH_BOX, 12, 8, 1, 1, 8, 1, 0, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-box-q16", CBVH_OK, "", {MESH_BOX, 12, 8, 3, 2, 2, 1, 1, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-box-far-q16", CBVH_OK, "", {MESH_BOX_FAR, 12, 8, 3, 2, 2, 1, 1, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-quad-flat", CBVH_OK, "", {MESH_QUAD, 2, 4, 1, 1, 1, 1, 0, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-remap-materials",
     CBVH_OK,
     "",
     {MESH_BOX_DEGENERATE, 12, 8, 3, 2, 2, 1, 0, 0, 0, 5, 1, W4, 0, 0, 0}},
    {"good-w4-remap-u32-materials-u32-zlib",
     CBVH_OK,
     "",
     {MESH_BOX_DEGENERATE, 12, 8, 3, 2, 2, 1, 0, 2, 0, 5, 70000, W4, 0, 0, 0}},
    {"good-w4-materials-u16-cooked-ids",
     CBVH_OK,
     "",
     {MESH_BOX, 12, 8, 3, 2, 2, 0, 0, 0, 0, 4, 1000, W4, 0, 0, 0}},
    BAD("bad-w4-no-slot", "node 1: no slot in use"),
    BAD("bad-w4-internal-unused", "node 0: slots 0x8 are internal but not in use"),
    BAD("bad-w4-unused-box", "node 1: unused slot 3 has a nonzero box"),
    BAD("bad-w4-unused-count", "node 1: slot 2 is unused but has a triangle count field of 1"),
    BAD("bad-w4-internal-count", "node 0: slot 1 is internal but has a triangle count field of 1"),
    BAD("bad-w4-leaf-too-big", "node 0: slot 1 is a leaf of 2 triangles, more than max_leaf_size 1"),
    BAD("bad-w4-max-leaf-size", "max_leaf_size 9 is more than a wide4 leaf holds (8)"),
    BAD("bad-w4-triangle-count", "triangle_count 268435457 is outside 1..268435456"),
    BAD("bad-w4-qmin-gt-qmax", "node 2: slot 1: qmin 100 > qmax 50 on axis 1"),
    BAD("bad-w4-order-index", "node 3: order index 24 for octant 5 is not below 24"),
    BAD("bad-w4-first-child", "node 0: first_child 2, but the nodes before it leave the next child at 1"),
    BAD("bad-w4-first-child-self",
        "node 3: first_child 3, but the nodes before it leave the next child at 4"),
    BAD("bad-w4-children-past-end", "node 3: children [4, 5) run past node_count 4"),
    BAD("bad-w4-unallocated-node", "node 5: no node before it has it as a child"),
    BAD("bad-w4-first-triangle", "node 2: first_triangle 4, but the leaves before it end at triangle 3"),
    BAD("bad-w4-leaves-past-end", "node 4: slot 2's triangles [11, 13) run past triangle_count 12"),
    BAD("bad-w4-leaves-short", "leaves cover triangles [0, 12), triangle_count is 13"),
    BAD("bad-w4-depth-mismatch", "the tree's depth is 3, the header says 4"),
    BAD("bad-w4-depth-exceeded", "node 4: at depth 3, deeper than the header's depth 2"),
    NEWER("unsupported-w4-nodes-encoding-2", "section 0 (NODES): encoding 2 is unknown"),
    {"good-box-local8", CBVH_OK, "", {MESH_BOX, 12, 8, 15, 4, 2, 1, 0, 4, 0, 4, 0, BIN, 0, 0, 0}},
    BAD("bad-local8-index", "LOCAL8 base 7 plus offset"),
    BAD("bad-local8-padding", "offset 1 of slot 4, past triangle_count 12, must be 0"),
    BAD("bad-local8-size", "expected 56 (2 elements of 28 bytes)"),
    {"good-two-boxes", CBVH_OK, "", {MESH_TWO_BOXES, 24, 16, 47, 6, 1, 1, 0, 0, 0, 4, 0, BIN, 0, 0, 0}},
    {"good-w4-two-boxes", CBVH_OK, "", {MESH_TWO_BOXES, 24, 16, 10, 4, 1, 1, 0, 0, 0, 4, 0, W4, 0, 0, 0}},
    {"good-w4-two-boxes-local8",
     CBVH_OK,
     "",
     {MESH_TWO_BOXES, 24, 16, 10, 4, 1, 1, 0, 4, 0, 4, 0, W4, 0, 0, 2}},
    {"good-w4-local8-q16-zlib",
     CBVH_OK,
     "",
     {MESH_BOX_DEGENERATE, 12, 8, 3, 2, 2, 1, 1, 4, 0, 5, 1, W4, 0, 0, 2}},
    BAD("bad-w4-depth-first-unflagged", "but the leaves before it end at triangle"),
    BAD("bad-w4-flag-breadth-first", "in depth-first order end at triangle"),
    BAD("bad-depth-first-binary", "depth-first flag is set on a binary-layout file"),
};

#define EXPECTATION_COUNT (sizeof expectations / sizeof expectations[0])

static const char *vectors_dir(void)
{
    const char *d = getenv("CBVH_FILEFORMAT_DIR");
    return d && *d ? d : CBVH_TEST_FILEFORMAT_DIR;
}

static uint8_t *read_vector(const char *name, size_t *size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.cbvh", vectors_dir(), name);
    FILE *fp = fopen(path, "rb");
    if (!fp)
        fail_msg("cannot open %s", path);
    uint8_t *data = malloc(1 << 16);
    assert_non_null(data);
    *size = fread(data, 1, 1 << 16, fp);
    assert_true(feof(fp));
    fclose(fp);
    return data;
}

/* ------------------------------------------------------------------ checks */

static float tolerance(const cbvh_file_info *info, int a, float value)
{
    if (info->vertex_format == CBVH_VERTEX_FLOAT32)
        return 0.0f;
    /* half a grid step, plus the rounding of origin + q x scale far from the origin */
    return info->grid_scale[a] + 2.0f * (nextafterf(fabsf(value), INFINITY) - fabsf(value));
}

static int same_triangle(const cbvh_file_info *info, const mesh *m, uint32_t j, float v[3][3])
{
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) {
            float want = m->v[m->t[j][k]][a];
            if (!(fabsf(v[k][a] - want) <= tolerance(info, a, want)))
                return 0;
        }
    return 1;
}

static int degenerate(const mesh *m, uint32_t j)
{
    const uint32_t *t = m->t[j];
    return t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
}

static void check_info(const cbvh_file_info *in, const good *g, const mesh *m)
{
    assert_int_equal(in->format_version, 1);
    assert_int_equal(in->triangle_count, g->triangle_count);
    assert_int_equal(in->vertex_count, g->vertex_count);
    assert_int_equal(in->node_count, g->node_count);
    assert_int_equal(in->depth, g->depth);
    assert_int_equal(in->max_leaf_size, g->max_leaf_size);
    assert_int_equal(in->has_remap, g->has_remap);
    assert_int_equal(in->has_materials, g->material_base != 0 || g->uniform_material != 0);
    assert_int_equal(in->material_name_count, g->name_count);
    /* original ids: the input's triangles, the dropped ones included, when remapped; else cooked ids */
    assert_int_equal(in->original_triangle_count, g->has_remap ? m->triangle_count : g->triangle_count);
    assert_int_equal(in->vertex_format, g->vertex_format);
    assert_int_equal(in->index_encoding, g->index_encoding);
    assert_int_equal(in->compat_flags, g->compat_flags);
    assert_int_equal(in->incompat_flags, g->incompat_flags);
    assert_int_equal(in->section_count, g->section_count);
    assert_int_equal(in->layout, g->layout);
    for (int a = 0; a < 3; a++) {
        float lo = INFINITY, hi = -INFINITY;
        for (uint32_t j = 0; j < m->triangle_count; j++)
            for (int k = 0; k < 3; k++) {
                float x = m->v[m->t[j][k]][a];
                lo = fminf(lo, x);
                hi = fmaxf(hi, x);
            }
        assert_true(fabsf(in->bounds_min[a] - lo) <= tolerance(in, a, lo));
        assert_true(fabsf(in->bounds_max[a] - hi) <= tolerance(in, a, hi));
        assert_true(in->grid_origin[a] == lo || in->vertex_format == CBVH_VERTEX_QUANTIZED16);
    }
}

/* With REMAP: triangle j is the input's triangle j (dropped degenerate ones are absent). Without: the ids
 * are cooked ids, each one a distinct input triangle. */
static void check_triangles(const cbvh_file *f, const good *g, const mesh *m)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    float v[3][3];
    int used[14] = {0};
    uint32_t ids = g->has_remap ? m->triangle_count : g->triangle_count;
    for (uint32_t id = 0; id < ids; id++) {
        int got = cbvh_file_get_triangle(f, id, v[0], v[1], v[2]);
        uint32_t j = id;
        if (g->has_remap) {
            assert_int_equal(got, !degenerate(m, id));
            if (!got)
                continue;
            assert_true(same_triangle(&info, m, id, v));
        } else {
            assert_int_equal(got, 1);
            for (j = 0; j < m->triangle_count; j++)
                if (!used[j] && same_triangle(&info, m, j, v))
                    break;
            assert_true(j < m->triangle_count);
            used[j] = 1;
        }
        uint32_t material = cbvh_file_get_material(f, id);
        assert_int_equal(material, g->material_base ? g->material_base + 7 * j : g->uniform_material);
    }
    assert_int_equal(cbvh_file_get_triangle(f, ids, v[0], v[1], v[2]), 0);
    assert_int_equal(cbvh_file_get_triangle(f, 0xFFFFFFFFu, v[0], v[1], v[2]), 0);
    assert_int_equal(cbvh_file_get_material(f, ids), 0);
}

/* make_vectors.py's NAMES, in the file's (id, name) order, or none. */
static void check_names(const cbvh_file *f, const good *g)
{
    static const struct {
        uint32_t id;
        const char *name;
    } names[3] = {{3, "Glass"}, {7, "Oak"}, {7, "Steel \xc3\xbc"}};
    uint32_t id = 0;
    for (uint32_t k = 0; k < g->name_count; k++) {
        const char *name = cbvh_file_get_material_name(f, k, &id);
        assert_non_null(name);
        assert_string_equal(name, names[k].name);
        assert_int_equal(id, names[k].id);
        assert_ptr_equal(cbvh_file_get_material_name(f, k, NULL), name);
    }
    assert_null(cbvh_file_get_material_name(f, g->name_count, &id));
    /* the first name of an id; ids without one (below, between, above) have none */
    for (uint32_t want = 0; want < 10; want++) {
        const char *found = cbvh_file_find_material_name(f, want);
        const char *first = NULL;
        for (int k = (int)g->name_count - 1; k >= 0; k--)
            if (names[k].id == want)
                first = names[k].name;
        if (first)
            assert_string_equal(found, first);
        else
            assert_null(found);
    }
}

static void check_sections(const cbvh_file *f, uint32_t file_size)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    assert_int_equal(info.file_size, file_size);
    cbvh_section_info s, prev = {0};
    for (uint32_t i = 0; i < info.section_count; i++) {
        assert_int_equal(cbvh_file_get_section(f, i, &s), 1);
        assert_int_equal(s.offset % 64, 0);
        assert_true(s.offset >= prev.offset + prev.stored_size);
        assert_true(s.offset + s.stored_size <= file_size);
        prev = s;
    }
    assert_int_equal(prev.offset + prev.stored_size, file_size);
    assert_int_equal(cbvh_file_get_section(f, info.section_count, &s), 0);
}

/* Opens one vector by path, from an aligned buffer and from an unaligned one: same outcome each way. */
static void check_vector(const expectation *e)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s.cbvh", vectors_dir(), e->name);
    size_t size;
    uint8_t *data = read_vector(e->name, &size);
    uint8_t *shifted = malloc(size + 1);
    assert_non_null(shifted);
    if (size)
        memcpy(shifted + 1, data, size);
    for (int how = 0; how < 3; how++) {
        cbvh_file *f = NULL;
        cbvh_error err;
        cbvh_result r = how == 0   ? cbvh_open_path(path, NULL, &f, &err)
                        : how == 1 ? cbvh_open_memory(data, size, NULL, &f, &err)
                                   : cbvh_open_memory(shifted + 1, size, NULL, &f, &err);
        if (r != e->code || strstr(err.message, e->message) == NULL)
            fail_msg("%s (open %s): got %s \"%s\", expected %s \"%s\"", e->name, how ? "memory" : "path",
                     cbvh_result_string(r), err.message, cbvh_result_string(e->code), e->message);
        assert_int_equal(err.code, r);
        if (r != CBVH_OK) {
            assert_null(f);
            continue;
        }
        const mesh *m = &meshes[e->g.mesh];
        cbvh_file_info info;
        cbvh_file_get_info(f, &info, sizeof info);
        check_info(&info, &e->g, m);
        check_sections(f, (uint32_t)size);
        check_triangles(f, &e->g, m);
        check_names(f, &e->g);
        cbvh_close(f);
    }
    free(shifted);
    free(data);
}

static void test_expectations(void **state)
{
    (void)state;
    for (size_t i = 0; i < EXPECTATION_COUNT; i++)
        check_vector(&expectations[i]);
}

/* ------------------------------------------------------------------ wide4 answers */

/* A wide4 vector, the binary vector of the same mesh, and how the C cooker makes the same mesh in wide4. */
typedef struct twin {
    const char *wide4, *binary;
    int mesh;
    uint32_t max_leaf_size;
    cbvh_vertex_format vertex_format;
} twin;

static const twin twins[] = {
    {"good-w4-single-triangle", "good-single-triangle", MESH_SINGLE, 4, CBVH_VERTEX_FLOAT32},
    {"good-w4-box-raw", "good-box-raw", MESH_BOX, 2, CBVH_VERTEX_FLOAT32},
    {"good-w4-box-leaf1", "good-box-raw", MESH_BOX, 1, CBVH_VERTEX_FLOAT32},
    {"good-w4-box-leaf8", "good-box-raw", MESH_BOX, 8, CBVH_VERTEX_FLOAT32},
    {"good-w4-box-q16", "good-box-q16", MESH_BOX, 2, CBVH_VERTEX_QUANTIZED16},
    {"good-w4-box-far-q16", "good-box-far-q16", MESH_BOX_FAR, 2, CBVH_VERTEX_QUANTIZED16},
    {"good-w4-quad-flat", "good-quad-flat", MESH_QUAD, 1, CBVH_VERTEX_FLOAT32},
    {"good-w4-remap-materials", "good-remap-materials", MESH_BOX_DEGENERATE, 2, CBVH_VERTEX_FLOAT32},
    {"good-w4-two-boxes", "good-two-boxes", MESH_TWO_BOXES, 1, CBVH_VERTEX_FLOAT32},
    {"good-w4-two-boxes-local8", "good-two-boxes", MESH_TWO_BOXES, 1, CBVH_VERTEX_FLOAT32},
    {"good-w4-local8-q16-zlib", "good-box-q16", MESH_BOX_DEGENERATE, 2, CBVH_VERTEX_QUANTIZED16},
};

static double next_unit(uint64_t *state)
{
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*state >> 11) * (1.0 / 9007199254740992.0);
}

enum { RAYS_PER_PAIR = 4000 };

/* A point of the file's bounds grown by `grow` of the extent (at least 1) on each side. */
static void point_near(const cbvh_file_info *info, double grow, uint64_t *rng, float out[3])
{
    for (int a = 0; a < 3; a++) {
        double lo = info->bounds_min[a], hi = info->bounds_max[a], pad = grow * fmax(hi - lo, 1.0);
        out[a] = (float)(lo - pad + next_unit(rng) * (hi - lo + 2 * pad));
    }
}

static int share_a_vertex(const cbvh_file *a, uint32_t ta, const cbvh_file *b, uint32_t tb)
{
    float va[3][3], vb[3][3];
    if (!cbvh_file_get_triangle(a, ta, va[0], va[1], va[2]) ||
        !cbvh_file_get_triangle(b, tb, vb[0], vb[1], vb[2]))
        return 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (memcmp(va[i], vb[j], sizeof va[i]) == 0)
                return 1;
    return 0;
}

/* The same triangles in two trees answer every ray alike with every traversal: hit or miss, the closest t
 * exactly, the same triangle unless two are crossed at that t (then they share an edge or a corner), and
 * occluded. Rays go from around the mesh to points of its triangles, a quarter of them along an axis. */
static void assert_same_answers(const cbvh_file *a, const cbvh_file *b, const mesh *m, const char *what)
{
    cbvh_file_info info;
    cbvh_file_get_info(a, &info, sizeof info);
    uint64_t rng = 2024;
    size_t hits = 0;
    for (int i = 0; i < RAYS_PER_PAIR; i++) {
        cbvh_ray r;
        float target[3];
        point_near(&info, 1.0, &rng, r.org);
        uint32_t j = (uint32_t)(next_unit(&rng) * m->triangle_count);
        while (degenerate(m, j))
            j = (j + 1) % m->triangle_count;
        double u = next_unit(&rng), v = next_unit(&rng) * (1.0 - u);
        for (int k = 0; k < 3; k++)
            target[k] = (float)((1.0 - u - v) * m->v[m->t[j][0]][k] + u * m->v[m->t[j][1]][k] +
                                v * m->v[m->t[j][2]][k]);
        for (int k = 0; k < 3; k++)
            r.dir[k] = target[k] - r.org[k];
        if (i % 4 == 0) { /* along an axis: from outside the bounds, straight at the target */
            int axis = i / 4 % 3;
            for (int k = 0; k < 3; k++)
                r.org[k] = k == axis ? r.org[k] : target[k],
                r.dir[k] = k == axis ? target[k] - r.org[k] : 0.0f;
        }
        r.tmin = 0.0f;
        r.tmax = INFINITY;
        for (int t = 0; t < 4; t++) {
            cbvh_hit ha, hb;
            const int ga = cbvh_raycast(a, &r, (cbvh_traversal)t, &ha, NULL);
            const int gb = cbvh_raycast(b, &r, (cbvh_traversal)t, &hb, NULL);
            if (ga != gb ||
                (ga && (ha.t != hb.t || (ha.tri != hb.tri && !share_a_vertex(a, ha.tri, b, hb.tri)))))
                fail_msg("%s: ray %d, traversal %d: %s %u at t %.9g against %s %u at t %.9g", what, i, t,
                         ga ? "hit" : "miss", ha.tri, ga ? ha.t : 0.0, gb ? "hit" : "miss", hb.tri,
                         gb ? hb.t : 0.0);
            hits += (size_t)ga;
            assert_int_equal(cbvh_occluded(a, &r, (cbvh_traversal)t, NULL), ga);
            assert_int_equal(cbvh_occluded(b, &r, (cbvh_traversal)t, NULL), gb);
        }
    }
    if (hits < 4 * RAYS_PER_PAIR * 3 / 4) /* the rays aim at points of the mesh: most of them hit */
        fail_msg("%s: %zu hits of %d rays and traversals", what, hits, 4 * RAYS_PER_PAIR);
}

/* Each wide4 vector answers as the binary vector of its mesh and as the C cooker's wide4 file of that mesh:
 * an encoder written from the spec alone and the library's cooker build different trees (median split,
 * binned SAH) that must hold the same triangles. A runtime-only build has no cooker and checks the first. */
static void test_wide4_answers(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof twins / sizeof twins[0]; i++) {
        const twin *w = &twins[i];
        const mesh *m = &meshes[w->mesh];
        char path[4096];
        cbvh_file *wide = NULL, *binary = NULL;
        snprintf(path, sizeof path, "%s/%s.cbvh", vectors_dir(), w->wide4);
        assert_int_equal(cbvh_open_path(path, NULL, &wide, NULL), CBVH_OK);
        snprintf(path, sizeof path, "%s/%s.cbvh", vectors_dir(), w->binary);
        assert_int_equal(cbvh_open_path(path, NULL, &binary, NULL), CBVH_OK);
        assert_same_answers(wide, binary, m, w->wide4);
#if CBVH_HAVE_COOKER /* a runtime-only build compares the two vectors only */
        uint32_t vertex_count = 0;
        for (uint32_t t = 0; t < 3 * m->triangle_count; t++)
            vertex_count = m->t[t / 3][t % 3] + 1 > vertex_count ? m->t[t / 3][t % 3] + 1 : vertex_count;
        const cbvh_mesh input = {&m->v[0][0], vertex_count, 0, &m->t[0][0], m->triangle_count, NULL};
        cbvh_cook_options o;
        cbvh_cook_options_init(&o, sizeof o);
        o.layout = CBVH_LAYOUT_WIDE4;
        o.max_leaf_size = w->max_leaf_size;
        o.vertex_format = w->vertex_format;
        void *bytes = NULL;
        size_t size = 0;
        cbvh_file *cooked = NULL;
        assert_int_equal(cbvh_cook(&input, &o, NULL, &bytes, &size, NULL, NULL), CBVH_OK);
        assert_int_equal(cbvh_open_memory(bytes, size, NULL, &cooked, NULL), CBVH_OK);
        cbvh_file_info info;
        cbvh_file_get_info(cooked, &info, sizeof info);
        assert_int_equal(info.layout, CBVH_LAYOUT_WIDE4);
        assert_same_answers(wide, cooked, m, w->wide4);
        cbvh_close(cooked);
        cbvh_buffer_free(NULL, bytes);
#endif
        cbvh_close(binary);
        cbvh_close(wide);
    }
}

/* The prefix of a vector's name says its class; every file on disk has an expectation. */
static void test_every_file_is_expected(void **state)
{
    (void)state;
    DIR *d = opendir(vectors_dir());
    if (!d)
        fail_msg("cannot list %s", vectors_dir());
    size_t files = 0;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        size_t n = strlen(de->d_name);
        if (n < 5 || strcmp(de->d_name + n - 5, ".cbvh") != 0)
            continue;
        files++;
        size_t i = 0;
        while (i < EXPECTATION_COUNT && (strlen(expectations[i].name) != n - 5 ||
                                         strncmp(expectations[i].name, de->d_name, n - 5) != 0))
            i++;
        if (i == EXPECTATION_COUNT)
            fail_msg("%s has no expectation in test_vectors.c", de->d_name);
    }
    closedir(d);
    assert_int_equal(files, EXPECTATION_COUNT);
    for (size_t i = 0; i < EXPECTATION_COUNT; i++) {
        const char *name = expectations[i].name;
        cbvh_result want = strncmp(name, "good-", 5) == 0  ? CBVH_OK
                           : strncmp(name, "bad-", 4) == 0 ? CBVH_ERROR_CORRUPT
                                                           : CBVH_ERROR_UNSUPPORTED;
        assert_int_equal(expectations[i].code, want);
    }
}

int main(void)
{
    make_meshes();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_file_is_expected),
        cmocka_unit_test(test_expectations),
        cmocka_unit_test(test_wide4_answers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
