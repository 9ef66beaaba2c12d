/* test_cook.c: the cooker, checked through an independent parser of the bytes it writes (not the loader). */
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <cmocka.h>

#include "cbvh.h"
#include "fuzz/le_bytes.h"
#include "support/counting_alloc.h"
#include "support/test_os.h"
#include "common/endian.h"
#include "common/format.h"
#include "layout/binary.h" /* the test parses the binary encoding from the spec on its own */

/* ------------------------------------------------------------------ test meshes */

#define TEST_PI 3.14159265358979323846

typedef struct test_mesh {
    float *pos;
    uint32_t *idx;
    uint32_t *mat;
    size_t nv, nt;
} test_mesh;

static uint64_t rng_state;

static void rng_seed(uint64_t s)
{
    rng_state = s * 0x9E3779B97F4A7C15ull + 1;
}

static double rng_unit(void)
{
    rng_state = rng_state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

static void mesh_alloc(test_mesh *m, size_t nv, size_t nt)
{
    m->nv = nv;
    m->nt = nt;
    m->pos = calloc(nv ? 3 * nv : 1, sizeof(float));
    m->idx = calloc(nt ? 3 * nt : 1, sizeof(uint32_t));
    m->mat = NULL;
    assert_non_null(m->pos);
    assert_non_null(m->idx);
}

static void mesh_free(test_mesh *m)
{
    free(m->pos);
    free(m->idx);
    free(m->mat);
    memset(m, 0, sizeof *m);
}

static cbvh_mesh as_mesh(const test_mesh *m)
{
    cbvh_mesh r = {m->pos, m->nv, 0, m->idx, m->nt, m->mat};
    return r;
}

/* The defaults with the binary layout, which the parser below reads (the default layout is wide4, whose
 * bytes test_vectors checks against an independent encoder). */
static void binary_options(cbvh_cook_options *o)
{
    cbvh_cook_options_init(o, sizeof *o);
    o->layout = CBVH_LAYOUT_BINARY;
}

/* Triangles of random size scattered in a box of half size `spread` around `center`. */
static void make_soup(test_mesh *m, size_t nt, uint64_t seed, double spread, double size,
                      const double center[3])
{
    rng_seed(seed);
    mesh_alloc(m, 3 * nt, nt);
    for (size_t t = 0; t < nt; t++) {
        double c[3];
        for (int k = 0; k < 3; k++)
            c[k] = center[k] + (rng_unit() * 2 - 1) * spread;
        for (int v = 0; v < 3; v++) {
            for (int k = 0; k < 3; k++)
                m->pos[9 * t + 3 * (size_t)v + (size_t)k] = (float)(c[k] + (rng_unit() * 2 - 1) * size);
            m->idx[3 * t + (size_t)v] = (uint32_t)(3 * t + (size_t)v);
        }
    }
}

/* An n x n grid of quads in the xy plane (z = height * noise), two triangles each. */
static void make_grid(test_mesh *m, uint32_t n, double height, uint64_t seed)
{
    rng_seed(seed);
    mesh_alloc(m, (size_t)(n + 1) * (n + 1), 2 * (size_t)n * n);
    for (uint32_t y = 0; y <= n; y++)
        for (uint32_t x = 0; x <= n; x++) {
            float *p = m->pos + 3 * ((size_t)y * (n + 1) + x);
            p[0] = (float)x;
            p[1] = (float)y;
            p[2] = (float)(height * rng_unit());
        }
    size_t t = 0;
    for (uint32_t y = 0; y < n; y++)
        for (uint32_t x = 0; x < n; x++) {
            uint32_t a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
            uint32_t *i = m->idx + 6 * t;
            i[0] = a;
            i[1] = b;
            i[2] = d;
            i[3] = a;
            i[4] = d;
            i[5] = c;
            t++;
        }
}

/* A UV sphere of radius r around `center`, computed in double then rounded. */
static void make_sphere(test_mesh *m, uint32_t rings, uint32_t segs, double r, const double center[3])
{
    mesh_alloc(m, (size_t)(rings + 1) * segs, 2 * (size_t)rings * segs);
    for (uint32_t i = 0; i <= rings; i++)
        for (uint32_t j = 0; j < segs; j++) {
            double th = TEST_PI * i / rings, ph = 2 * TEST_PI * j / segs;
            float *p = m->pos + 3 * ((size_t)i * segs + j);
            double st = i == 0 || i == rings ? 0.0 : sin(th); /* exact poles */
            p[0] = (float)(center[0] + r * st * cos(ph));
            p[1] = (float)(center[1] + r * st * sin(ph));
            p[2] = (float)(center[2] + r * cos(th));
        }
    size_t t = 0;
    for (uint32_t i = 0; i < rings; i++)
        for (uint32_t j = 0; j < segs; j++) {
            uint32_t a = i * segs + j, b = i * segs + (j + 1) % segs, c = a + segs, d = b + segs;
            uint32_t *x = m->idx + 3 * t;
            x[0] = a;
            x[1] = c;
            x[2] = d;
            x[3] = a;
            x[4] = d;
            x[5] = b;
            t += 2;
        }
    /* The poles' rings collapse to points: those triangles are degenerate and dropped. */
}

static const double origin3[3] = {0, 0, 0};

/* ------------------------------------------------------------------ an independent parser */

static uint32_t crc_table[256];

static uint32_t test_crc32(const uint8_t *p, size_t n)
{
    if (!crc_table[1])
        for (uint32_t i = 0; i < 256; i++) {
            uint32_t c = i;
            for (int k = 0; k < 8; k++)
                c = c & 1 ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            crc_table[i] = c;
        }
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++)
        c = crc_table[(c ^ p[i]) & 0xFF] ^ (c >> 8);
    return c ^ 0xFFFFFFFFu;
}

typedef struct parsed {
    uint32_t section_count, tri_count, vert_count, node_count, depth, max_leaf, orig_count;
    float origin[3], scale[3], bmin[3], bmax[3];
    uint64_t file_size;
    uint32_t codec[7], encoding[7]; /* indexed by section number: type without the ancillary bit */
    uint64_t stored[7], size[7];
    cbvh_node *nodes;
    uint32_t *tris;      /* 3 per triangle */
    float *verts;        /* 3 per vertex, decoded */
    uint16_t *qverts;    /* 3 per vertex, or NULL */
    uint32_t *remap;     /* or NULL */
    uint32_t *mats;      /* or NULL */
    int mats_uniform;    /* MATERIALS encoding 3: one id for all */
    uint32_t name_count; /* MATERIAL_NAMES */
    uint32_t *name_ids;
    char **names; /* into name_bytes */
    uint8_t *name_bytes;
} parsed;

static void parsed_free(parsed *p)
{
    free(p->nodes);
    free(p->tris);
    free(p->verts);
    free(p->qverts);
    free(p->remap);
    free(p->mats);
    free(p->name_ids);
    free(p->names);
    free(p->name_bytes);
    memset(p, 0, sizeof *p);
}

/* Checks the container (header, table, CRCs, alignment, padding) and decodes every section. */
static void parse(const uint8_t *b, size_t size, parsed *p)
{
    memset(p, 0, sizeof *p);
    assert_true(size >= 128);
    assert_memory_equal(b,
                        "\x89"
                        "CBVH\r\n\x1a",
                        8);
    assert_int_equal(cbvh_read_u32(b + 8), 1);
    assert_int_equal(cbvh_read_u32(b + 12), 128);
    assert_int_equal(cbvh_read_u32(b + 16), 0);
    assert_int_equal(cbvh_read_u32(b + 20), 0);
    p->section_count = cbvh_read_u32(b + 24);
    assert_true(p->section_count >= 3 && p->section_count <= 16);
    assert_int_equal(cbvh_read_u32(b + 124), test_crc32(b, 124));
    assert_true(size >= 128 + 40 * (size_t)p->section_count);
    assert_int_equal(cbvh_read_u32(b + 28), test_crc32(b + 128, 40 * (size_t)p->section_count));
    p->tri_count = cbvh_read_u32(b + 32);
    p->vert_count = cbvh_read_u32(b + 36);
    p->node_count = cbvh_read_u32(b + 40);
    p->depth = cbvh_read_u32(b + 44);
    p->max_leaf = cbvh_read_u32(b + 48);
    p->orig_count = cbvh_read_u32(b + 52);
    for (int k = 0; k < 3; k++) {
        p->origin[k] = cbvh_read_f32(b + 56 + 4 * k);
        p->scale[k] = cbvh_read_f32(b + 68 + 4 * k);
        p->bmin[k] = cbvh_read_f32(b + 80 + 4 * k);
        p->bmax[k] = cbvh_read_f32(b + 92 + 4 * k);
        assert_true(isfinite(p->origin[k]) && isfinite(p->scale[k]) && p->scale[k] >= 0);
        assert_true(isfinite(p->bmin[k]) && isfinite(p->bmax[k]) && p->bmin[k] <= p->bmax[k]);
    }
    p->file_size = cbvh_read_u64(b + 104);
    assert_int_equal(p->file_size, size);
    for (int i = 112; i < 124; i++)
        assert_int_equal(b[i], 0);
    assert_true(p->tri_count >= 1 && p->tri_count <= CBVH_MAX_TRIANGLES);
    assert_true(p->vert_count >= 3);
    assert_true(p->node_count >= 1 && p->node_count <= CBVH_MAX_NODES);
    assert_true(p->depth >= 1 && p->depth <= 64);
    assert_true(p->max_leaf >= 1 && p->max_leaf <= 16);
    assert_true(p->orig_count >= p->tri_count);

    uint64_t end = 128 + 40 * (uint64_t)p->section_count, prev_type = 0;
    uint8_t *data[7] = {NULL};
    for (uint32_t i = 0; i < p->section_count; i++) {
        const uint8_t *e = b + 128 + 40 * (size_t)i;
        uint32_t type = cbvh_read_u32(e), codec = cbvh_read_u32(e + 4);
        uint64_t off = cbvh_read_u64(e + 8), stored = cbvh_read_u64(e + 16), dsize = cbvh_read_u64(e + 24);
        if (type == 0x80000006u) /* MATERIAL_NAMES: ancillary, number 6 */
            type = 6;
        assert_true(type >= 1 && type <= 6 && type > prev_type); /* known, unique, in number order */
        prev_type = type;
        assert_true(codec <= 1);
        assert_int_equal(off % 64, 0);
        assert_true(off >= end && off + stored <= size);
        for (uint64_t z = end; z < off; z++)
            assert_int_equal(b[z], 0); /* padding is zero */
        end = off + stored;
        assert_int_equal(cbvh_read_u32(e + 32), test_crc32(b + off, stored));
        p->codec[type] = codec;
        p->encoding[type] = cbvh_read_u32(e + 36);
        p->stored[type] = stored;
        p->size[type] = dsize;
        data[type] = malloc(dsize ? dsize : 1);
        assert_non_null(data[type]);
        if (codec == 0) {
            assert_int_equal(stored, dsize);
            memcpy(data[type], b + off, dsize);
        } else {
            uLongf got = (uLongf)dsize;
            assert_int_equal(uncompress(data[type], &got, b + off, (uLong)stored), Z_OK);
            assert_int_equal(got, dsize);
            assert_true(stored < dsize); /* compressed only when it pays */
        }
    }
    assert_int_equal(end, size); /* nothing after the last section */
    assert_non_null(data[1]);
    assert_non_null(data[2]);
    assert_non_null(data[3]);

    /* NODES */
    assert_int_equal(p->encoding[1], 0);
    assert_int_equal(p->size[1], 16 * (uint64_t)p->node_count);
    p->nodes = calloc(p->node_count, sizeof(cbvh_node));
    for (uint32_t i = 0; i < p->node_count; i++) {
        const uint8_t *n = data[1] + 16 * (size_t)i;
        for (int k = 0; k < 3; k++) {
            p->nodes[i].qmin[k] = (uint16_t)le_get_u16(n + 2 * k);
            p->nodes[i].qmax[k] = (uint16_t)le_get_u16(n + 6 + 2 * k);
            assert_true(p->nodes[i].qmin[k] <= p->nodes[i].qmax[k]);
        }
        p->nodes[i].word = cbvh_read_u32(n + 12);
    }
    /* TRIANGLES: u16 x 3, u32 x 3, DELTA16 (u32 base, two i16 deltas), or LOCAL8 (encoding 4: blocks of 8
     * triangles, a u32 base and 3 u8 offsets each; the last block's unused offsets 0) */
    static const uint64_t tri_elem[5] = {6, 12, 8, 0, 28};
    const uint32_t tri_enc = p->encoding[2];
    assert_true(tri_enc <= 2 || tri_enc == 4);
    const uint64_t tri_elements = tri_enc == 4 ? (p->tri_count + 7u) / 8u : p->tri_count;
    assert_int_equal(p->size[2], tri_elem[tri_enc] * tri_elements);
    p->tris = calloc(3 * (size_t)p->tri_count, sizeof(uint32_t));
    for (uint32_t t = 0; t < p->tri_count; t++) {
        const uint8_t *e = data[2] + tri_elem[tri_enc] * (tri_enc == 4 ? t / 8u : t);
        uint32_t *o = p->tris + 3 * (size_t)t;
        if (tri_enc == 0) {
            o[0] = (uint16_t)le_get_u16(e);
            o[1] = (uint16_t)le_get_u16(e + 2);
            o[2] = (uint16_t)le_get_u16(e + 4);
        } else if (tri_enc == 1) {
            o[0] = cbvh_read_u32(e);
            o[1] = cbvh_read_u32(e + 4);
            o[2] = cbvh_read_u32(e + 8);
        } else if (tri_enc == 4) {
            const uint64_t base = cbvh_read_u32(e);
            for (int c = 0; c < 3; c++) {
                assert_true(base + e[4 + 3 * (t % 8u) + (uint32_t)c] < p->vert_count);
                o[c] = (uint32_t)(base + e[4 + 3 * (t % 8u) + (uint32_t)c]);
            }
        } else {
            int64_t base = cbvh_read_u32(e);
            o[0] = (uint32_t)base;
            o[1] = (uint32_t)(base + (int16_t)(uint16_t)le_get_u16(e + 4));
            o[2] = (uint32_t)(base + (int16_t)(uint16_t)le_get_u16(e + 6));
            assert_true(base + (int16_t)(uint16_t)le_get_u16(e + 4) >= 0 &&
                        base + (int16_t)(uint16_t)le_get_u16(e + 6) >= 0);
        }
        for (int c = 0; c < 3; c++)
            assert_true(o[c] < p->vert_count);
    }
    for (uint32_t t = p->tri_count; tri_enc == 4 && t % 8u != 0; t++)
        for (uint32_t c = 0; c < 3; c++)
            assert_int_equal(data[2][28 * (size_t)(t / 8u) + 4 + 3 * (t % 8u) + c], 0);
    /* The narrowest encoding the spec names: LOCAL8 unless another takes fewer bytes, and then u16 when every
     * index fits. */
    if (tri_enc != 4 && p->vert_count <= 65536)
        assert_int_equal(tri_enc, 0);
    else if (tri_enc != 4)
        assert_int_not_equal(tri_enc, 0);
    /* VERTICES */
    assert_true(p->encoding[3] <= 1);
    assert_int_equal(p->size[3], (p->encoding[3] ? 6 : 12) * (uint64_t)p->vert_count);
    p->verts = calloc(3 * (size_t)p->vert_count, sizeof(float));
    if (p->encoding[3])
        p->qverts = calloc(3 * (size_t)p->vert_count, sizeof(uint16_t));
    for (size_t i = 0; i < 3 * (size_t)p->vert_count; i++) {
        if (p->encoding[3]) {
            p->qverts[i] = (uint16_t)le_get_u16(data[3] + 2 * i);
            p->verts[i] = cbvh_dequantize(p->qverts[i], p->origin[i % 3], p->scale[i % 3]);
        } else {
            p->verts[i] = cbvh_read_f32(data[3] + 4 * i);
        }
    }
    /* REMAP */
    if (data[4]) {
        /* the narrowest that holds the ids: u16 (encoding 0), u24 (2), u32 (1) */
        const uint32_t width = p->orig_count <= 65536 ? 2 : p->orig_count <= (1u << 24) ? 3 : 4;
        assert_int_equal(p->encoding[4], width == 2 ? 0 : width == 3 ? 2 : 1);
        assert_int_equal(p->size[4], width * (uint64_t)p->tri_count);
        p->remap = calloc(p->tri_count, sizeof(uint32_t));
        uint8_t *seen = calloc(p->orig_count, 1);
        for (uint32_t t = 0; t < p->tri_count; t++) {
            const uint8_t *e = data[4] + width * (size_t)t;
            p->remap[t] = width == 2   ? (uint16_t)le_get_u16(e)
                          : width == 3 ? (uint16_t)le_get_u16(e) | (uint32_t)e[2] << 16
                                       : cbvh_read_u32(e);
            assert_true(p->remap[t] < p->orig_count);
            assert_int_equal(seen[p->remap[t]], 0);
            seen[p->remap[t]] = 1;
        }
        free(seen);
    } else {
        assert_int_equal(p->orig_count, p->tri_count);
    }
    /* MATERIALS: u8, u16, u32 per triangle, or one u32 for all (encoding 3) */
    if (data[5]) {
        static const uint64_t mat_elem[4] = {1, 2, 4, 0};
        assert_true(p->encoding[5] <= 3);
        p->mats_uniform = p->encoding[5] == 3;
        assert_int_equal(p->size[5], p->mats_uniform ? 4 : mat_elem[p->encoding[5]] * p->tri_count);
        p->mats = calloc(p->tri_count, sizeof(uint32_t));
        for (uint32_t t = 0; t < p->tri_count; t++) {
            const uint8_t *e = data[5] + mat_elem[p->encoding[5]] * t;
            p->mats[t] = p->encoding[5] == 0   ? e[0]
                         : p->encoding[5] == 1 ? (uint16_t)le_get_u16(e)
                                               : cbvh_read_u32(e);
        }
    }
    /* MATERIAL_NAMES: u32 count, (u32 id, u32 offset) each, NUL-terminated names tiling the rest in (id,
     * name) order */
    if (data[6]) {
        assert_int_equal(p->encoding[6], 0);
        assert_true(p->size[6] >= 4);
        p->name_count = cbvh_read_u32(data[6]);
        const uint64_t start = 4 + 8 * (uint64_t)p->name_count;
        assert_true(p->name_count >= 1 && start < p->size[6]);
        p->name_ids = calloc(p->name_count, sizeof(uint32_t));
        p->names = calloc(p->name_count, sizeof(char *));
        p->name_bytes = data[6];
        data[6] = NULL;
        uint64_t at = start;
        for (uint32_t k = 0; k < p->name_count; k++) {
            p->name_ids[k] = cbvh_read_u32(p->name_bytes + 4 + 8 * (size_t)k);
            assert_int_equal(start + cbvh_read_u32(p->name_bytes + 8 + 8 * (size_t)k), at);
            p->names[k] = (char *)p->name_bytes + at;
            const uint8_t *nul = memchr(p->names[k], 0, (size_t)(p->size[6] - at));
            assert_non_null(nul);
            at = (uint64_t)(nul - p->name_bytes) + 1;
            if (k > 0)
                assert_true(
                    p->name_ids[k] > p->name_ids[k - 1] ||
                    (p->name_ids[k] == p->name_ids[k - 1] && strcmp(p->names[k - 1], p->names[k]) < 0));
        }
        assert_int_equal(at, p->size[6]);
    }
    for (int t = 0; t < 7; t++)
        free(data[t]);
}

static float deq(const parsed *p, int a, uint32_t q)
{
    return cbvh_dequantize(q, p->origin[a], p->scale[a]);
}

static uint32_t subtree_size(const parsed *p, uint32_t i)
{
    uint32_t w = p->nodes[i].word;
    return cbvh_node_is_leaf(w) ? 1 : cbvh_node_subtree_size(w);
}

/* A stack walk that skips the subtrees of the nodes `miss` selects, against a stackless
 * walk over escape links with the same rule: same nodes, same order. miss == NULL: visit all. */
static void check_walks(const parsed *p, int (*miss)(uint32_t))
{
    uint32_t *order = malloc(sizeof(uint32_t) * p->node_count), count = 0;
    uint32_t stack[128], top = 0;
    stack[top++] = 0;
    while (top) {
        uint32_t i = stack[--top];
        order[count++] = i;
        if (cbvh_node_is_leaf(p->nodes[i].word) || (miss && miss(i)))
            continue;
        uint32_t c1 = i + 1, c2 = c1 + subtree_size(p, c1);
        stack[top++] = c2;
        stack[top++] = c1;
        assert_true(top < 128);
    }
    uint32_t k = 0;
    for (uint32_t i = 0; i < p->node_count;) {
        assert_true(k < count);
        assert_int_equal(order[k++], i);
        uint32_t next =
            cbvh_node_is_leaf(p->nodes[i].word) || !(miss && miss(i)) ? i + 1 : i + subtree_size(p, i);
        assert_true(next > i); /* escape links point forward */
        i = next;
    }
    assert_int_equal(k, count);
    free(order);
}

static int miss_odd(uint32_t i)
{
    return (i * 2654435761u >> 7) & 1;
}

/* Tree shape: sizes, second child rule, depth, leaves tiling the triangles, leaf counts. */
static void check_tree(const parsed *p, uint64_t *leaves_out)
{
    assert_int_equal(subtree_size(p, 0), p->node_count);
    uint32_t stack[128], depth_of[128], top = 0, next_tri = 0, depth = 0, leaves = 0, max_leaf = 0;
    stack[top] = 0;
    depth_of[top++] = 1;
    while (top) {
        top--;
        uint32_t i = stack[top], d = depth_of[top], w = p->nodes[i].word;
        depth = d > depth ? d : depth;
        if (cbvh_node_is_leaf(w)) {
            assert_int_equal(cbvh_leaf_first(w), next_tri);
            next_tri += cbvh_leaf_count(w);
            max_leaf = cbvh_leaf_count(w) > max_leaf ? cbvh_leaf_count(w) : max_leaf;
            leaves++;
            continue;
        }
        uint32_t s = cbvh_node_subtree_size(w);
        assert_true(s >= 3 && (uint64_t)i + s <= p->node_count);
        uint32_t c1 = i + 1, c2 = c1 + subtree_size(p, c1);
        assert_true(c2 < i + s);
        assert_int_equal(c2 + subtree_size(p, c2), i + s);
        stack[top] = c2;
        depth_of[top++] = d + 1;
        stack[top] = c1;
        depth_of[top++] = d + 1;
        assert_true(top < 128);
    }
    assert_int_equal(next_tri, p->tri_count);
    assert_int_equal(depth, p->depth);
    assert_int_equal(p->node_count, 2 * leaves - 1);
    assert_true(max_leaf <= p->max_leaf);
    if (leaves_out)
        *leaves_out = leaves;
    check_walks(p, NULL);
    check_walks(p, miss_odd);
}

typedef struct fbox {
    float lo[3], hi[3];
} fbox;

/* Every node's dequantized box holds the exact float box of its subtree's decoded vertices. */
static void check_conservative(const parsed *p)
{
    fbox *b = malloc(sizeof(fbox) * p->node_count);
    for (uint32_t i = p->node_count; i-- > 0;) {
        uint32_t w = p->nodes[i].word;
        for (int k = 0; k < 3; k++) {
            b[i].lo[k] = INFINITY;
            b[i].hi[k] = -INFINITY;
        }
        if (cbvh_node_is_leaf(w)) {
            for (uint32_t t = cbvh_leaf_first(w); t < cbvh_leaf_first(w) + cbvh_leaf_count(w); t++)
                for (int c = 0; c < 3; c++)
                    for (int k = 0; k < 3; k++) {
                        float v = p->verts[3 * (size_t)p->tris[3 * (size_t)t + (size_t)c] + (size_t)k];
                        b[i].lo[k] = fminf(b[i].lo[k], v);
                        b[i].hi[k] = fmaxf(b[i].hi[k], v);
                    }
        } else {
            uint32_t c1 = i + 1, c2 = c1 + subtree_size(p, c1);
            for (int k = 0; k < 3; k++) {
                b[i].lo[k] = fminf(b[c1].lo[k], b[c2].lo[k]);
                b[i].hi[k] = fmaxf(b[c1].hi[k], b[c2].hi[k]);
            }
        }
        for (int k = 0; k < 3; k++) {
            if (!(deq(p, k, p->nodes[i].qmin[k]) <= b[i].lo[k]) ||
                !(deq(p, k, p->nodes[i].qmax[k]) >= b[i].hi[k]))
                fail_msg("node %u axis %d: box [%.9g, %.9g] does not hold [%.9g, %.9g]", i, k,
                         (double)deq(p, k, p->nodes[i].qmin[k]), (double)deq(p, k, p->nodes[i].qmax[k]),
                         (double)b[i].lo[k], (double)b[i].hi[k]);
        }
    }
    /* Header bounds: exact bounds of the decoded vertices. */
    for (int k = 0; k < 3; k++) {
        float lo = INFINITY, hi = -INFINITY;
        for (uint32_t v = 0; v < p->vert_count; v++) {
            lo = fminf(lo, p->verts[3 * (size_t)v + (size_t)k]);
            hi = fmaxf(hi, p->verts[3 * (size_t)v + (size_t)k]);
        }
        assert_true(lo == p->bmin[k] && hi == p->bmax[k]);
        assert_true(deq(p, k, 65535) >= hi);
    }
    free(b);
}

/* Sort bytes recomputed per spec section 5 for all 8 octants; larger area first. */
static void check_sort_bytes(const parsed *p)
{
    for (uint32_t i = 0; i < p->node_count; i++) {
        uint32_t w = p->nodes[i].word;
        if (cbvh_node_is_leaf(w))
            continue;
        const cbvh_node *f = &p->nodes[i + 1], *s = &p->nodes[i + 1 + subtree_size(p, i + 1)];
        uint32_t expect = 0;
        for (uint32_t k = 0; k < 8; k++) {
            double dot = 0;
            for (int a = 0; a < 3; a++) {
                double d =
                    (double)(((int)f->qmin[a] + f->qmax[a]) - ((int)s->qmin[a] + s->qmax[a])) * p->scale[a];
                dot += (k >> a) & 1 ? -d : d;
            }
            if (dot > 0)
                expect |= 1u << k;
        }
        assert_int_equal(cbvh_node_sort_byte(w), expect);
        /* Opposite octants disagree unless the centers tie. */
        for (uint32_t k = 0; k < 8; k++)
            if ((expect >> k) & 1)
                assert_false((expect >> (7 - k)) & 1);
        double area[2];
        for (int c = 0; c < 2; c++) {
            const cbvh_node *n = c ? s : f;
            double d[3];
            for (int a = 0; a < 3; a++)
                d[a] = (double)deq(p, a, n->qmax[a]) - deq(p, a, n->qmin[a]);
            area[c] = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
        }
        assert_true(area[0] >= area[1]);
    }
}

/* SAH cost of the file's tree, per the stats' definition, on the decoded boxes. */
static double file_sah(const parsed *p, double ct, double ci)
{
    double sum = 0, root = 0;
    for (uint32_t i = 0; i < p->node_count; i++) {
        double d[3];
        for (int a = 0; a < 3; a++)
            d[a] = (double)deq(p, a, p->nodes[i].qmax[a]) - deq(p, a, p->nodes[i].qmin[a]);
        double area = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
        if (i == 0)
            root = area;
        uint32_t w = p->nodes[i].word;
        sum += cbvh_node_is_leaf(w) ? ci * cbvh_leaf_count(w) * area : ct * area;
    }
    return sum / root;
}

/* A coordinate as the cooker stores it (cbvh.h): below CBVH_COORDINATE_MIN in magnitude, 0. */
static float stored_coordinate(float x)
{
    return fabsf(x) < CBVH_COORDINATE_MIN ? 0.0f : x;
}

/* Each cooked triangle decodes to its input triangle's vertices in the input's corner order
 * (within tol per coordinate: 0 for lossless vertices). */
static void check_triangles_match(const parsed *p, const test_mesh *m, double tol)
{
    assert_non_null(p->remap);
    assert_int_equal(p->orig_count, m->nt);
    for (uint32_t t = 0; t < p->tri_count; t++) {
        uint32_t o = p->remap[t];
        for (int c = 0; c < 3; c++) {
            const float *in = m->pos + 3 * (size_t)m->idx[3 * (size_t)o + (size_t)c];
            const float *out = p->verts + 3 * (size_t)p->tris[3 * (size_t)t + (size_t)c];
            for (int k = 0; k < 3; k++)
                if (!(fabs((double)stored_coordinate(in[k]) - out[k]) <= tol))
                    fail_msg("cooked triangle %u (input %u) corner %d axis %d: %.9g vs input %.9g", t, o, c,
                             k, (double)out[k], (double)in[k]);
        }
    }
}

/* The grid per spec section 6: origin = bounds_min of the kept mesh, scale the smallest reaching bounds_max.
 */
static void check_grid(const parsed *p, const float kept_min[3], const float kept_max[3])
{
    for (int k = 0; k < 3; k++) {
        assert_true(p->origin[k] == kept_min[k]);
        assert_true(cbvh_dequantize(65535, p->origin[k], p->scale[k]) >= kept_max[k]);
        if (p->scale[k] > 0)
            assert_true(cbvh_dequantize(65535, p->origin[k], nextafterf(p->scale[k], 0)) < kept_max[k]);
        else
            assert_true(kept_min[k] == kept_max[k]);
    }
}

/* The bounds of the input mesh as stored. */
static void input_bounds(const test_mesh *m, float lo[3], float hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (size_t i = 0; i < 3 * m->nt; i++)
        for (int k = 0; k < 3; k++) {
            float v = stored_coordinate(m->pos[3 * (size_t)m->idx[i] + (size_t)k]);
            lo[k] = fminf(lo[k], v);
            hi[k] = fmaxf(hi[k], v);
        }
}

typedef struct cooked {
    uint8_t *data;
    size_t size;
    cbvh_cook_stats stats;
    parsed p;
} cooked;

/* Cooks, parses and runs every structural check; lossless meshes also get the exact match. */
static void cook_and_check(const test_mesh *m, const cbvh_cook_options *o, cooked *c)
{
    cbvh_cook_options defaults;
    binary_options(&defaults);
    if (!o)
        o = &defaults;
    cbvh_mesh mesh = as_mesh(m);
    cbvh_error err;
    void *data = NULL;
    cbvh_cook_stats_init(&c->stats, sizeof c->stats);
    cbvh_result r = cbvh_cook(&mesh, o, NULL, &data, &c->size, &c->stats, &err);
    if (r != CBVH_OK)
        fail_msg("cook failed: %d %s", r, err.message);
    c->data = data;
    parse(c->data, c->size, &c->p);
    const parsed *p = &c->p;
    uint64_t leaves = 0;
    check_tree(p, &leaves);
    check_conservative(p);
    check_sort_bytes(p);
    /* Stats agree with the file. */
    assert_int_equal(c->stats.file_size, c->size);
    assert_int_equal(c->stats.triangles, p->tri_count);
    assert_int_equal(c->stats.vertices, p->vert_count);
    assert_int_equal(c->stats.nodes, p->node_count);
    assert_int_equal(c->stats.leaves, leaves);
    assert_int_equal(c->stats.depth, p->depth);
    assert_int_equal(c->stats.input_triangles, m->nt);
    assert_int_equal(c->stats.input_vertices, m->nv);
    assert_int_equal(c->stats.triangles + c->stats.dropped_degenerate, m->nt);
    for (int t = 1; t < 7; t++) {
        assert_int_equal(c->stats.section_size[t], p->size[t]);
        assert_int_equal(c->stats.section_stored_size[t], p->stored[t]);
    }
    double sah = file_sah(p, 1.0, 1.0); /* reported with unit costs whatever the build's costs */
    assert_true(fabs(sah - c->stats.sah_cost) <= 1e-9 * sah);
    assert_true(p->max_leaf <= o->max_leaf_size);
    float lo[3], hi[3];
    input_bounds(m, lo, hi);
    if (c->stats.dropped_degenerate == 0)
        check_grid(p, lo, hi);
    if (p->remap && o->vertex_format == CBVH_VERTEX_FLOAT32)
        check_triangles_match(p, m, 0.0);
}

static void cooked_free(cooked *c)
{
    cbvh_buffer_free(NULL, c->data);
    parsed_free(&c->p);
}

/* ------------------------------------------------------------------ valid meshes */

static void test_soups(void **state)
{
    (void)state;
    static const size_t sizes[] = {1, 2, 3, 5, 17, 100, 3000};
    static const uint32_t leaf[] = {1, 4, 16};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (size_t l = 0; l < 3; l++) {
            test_mesh m;
            make_soup(&m, sizes[s], 11 + s, 10.0, 1.0, origin3);
            cbvh_cook_options o;
            binary_options(&o);
            o.max_leaf_size = leaf[l];
            cooked c;
            cook_and_check(&m, &o, &c);
            assert_int_equal(c.stats.dropped_degenerate, 0);
            if (sizes[s] == 1)
                assert_int_equal(c.p.node_count, 1);
            cooked_free(&c);
            mesh_free(&m);
        }
}

static void test_grid_and_sphere(void **state)
{
    (void)state;
    test_mesh m;
    make_grid(&m, 60, 3.0, 5);
    cooked c;
    cook_and_check(&m, NULL, &c);
    /* LOCAL8 indices (encoding 4) with the copies its windows need, fewer bytes than u16 indices to each
     * vertex once (the narrowest other encoding) */
    assert_int_equal(c.p.encoding[2], 4);
    assert_true(c.p.vert_count >= 61 * 61);
    assert_true(c.p.size[2] + c.p.size[3] < 6 * (uint64_t)c.p.tri_count + 12 * 61 * 61);
    cooked_free(&c);
    mesh_free(&m);

    make_sphere(&m, 40, 64, 2.0, origin3);
    cook_and_check(&m, NULL, &c);
    assert_int_equal(c.stats.dropped_degenerate, 2 * 64); /* pole triangles */
    cooked_free(&c);
    mesh_free(&m);
}

/* Far from the origin the grid's steps approach one ulp: boxes must stay conservative. */
static void test_far_from_origin(void **state)
{
    (void)state;
    static const double offsets[] = {1e5, 1e7, -1e7, 1e9};
    for (size_t i = 0; i < sizeof offsets / sizeof offsets[0]; i++) {
        const double center[3] = {offsets[i], -offsets[i] * 0.5, 7.0};
        test_mesh m;
        make_sphere(&m, 12, 24, offsets[i] > 1e8 ? 4e4 : 40.0, center);
        cooked c;
        cook_and_check(&m, NULL, &c);
        cooked_free(&c);
        mesh_free(&m);
        make_soup(&m, 500, 3 + i, 300.0, offsets[i] > 1e8 ? 500.0 : 2.0, center);
        cook_and_check(&m, NULL, &c);
        cooked_free(&c);
        mesh_free(&m);
    }
}

/* Boxes straddling 0 with tiny extents, and flat meshes (zero extent on an axis). */
static void test_zero_and_flat(void **state)
{
    (void)state;
    test_mesh m;
    make_soup(&m, 400, 21, 1e-3, 1e-3, origin3);
    cooked c;
    cook_and_check(&m, NULL, &c);
    cooked_free(&c);
    mesh_free(&m);

    /* Flat in z at z = 5, then flat in y at y = -0.0 / +0.0 mixed. */
    make_grid(&m, 30, 0.0, 1);
    for (size_t v = 0; v < m.nv; v++)
        m.pos[3 * v + 2] = 5.0f;
    cook_and_check(&m, NULL, &c);
    assert_true(c.p.scale[2] == 0.0f);
    cooked_free(&c);
    for (size_t v = 0; v < m.nv; v++) {
        m.pos[3 * v + 2] = m.pos[3 * v + 1];
        m.pos[3 * v + 1] = v & 1 ? -0.0f : 0.0f;
    }
    cook_and_check(&m, NULL, &c);
    assert_true(c.p.scale[1] == 0.0f);
    cooked_free(&c);
    mesh_free(&m);

    /* Axis-aligned cubes: many node boxes flat on one axis, at 1e7. */
    const double center[3] = {1e7, 0, -1e7};
    make_soup(&m, 300, 8, 100.0, 1.0, center);
    for (size_t t = 0; t < m.nt; t++)
        m.pos[9 * t + 3 * (t % 3) + t % 3] = m.pos[9 * t + t % 3]; /* an edge parallel to a plane */
    cook_and_check(&m, NULL, &c);
    cooked_free(&c);
    mesh_free(&m);
}

static void test_quantized_vertices(void **state)
{
    (void)state;
    static const double offsets[] = {0, 1e5, -1e7};
    for (size_t i = 0; i < 3; i++) {
        const double center[3] = {offsets[i], 1, -offsets[i]};
        test_mesh m;
        make_sphere(&m, 20, 30, 50.0, center);
        cbvh_cook_options o;
        binary_options(&o);
        o.vertex_format = CBVH_VERTEX_QUANTIZED16;
        cooked c;
        cook_and_check(&m, &o, &c);
        const parsed *p = &c.p;
        assert_int_equal(p->encoding[3], 1);
        assert_non_null(p->qverts);
        /* Each stored coordinate is the nearest grid point to its input; the worst error is reported. */
        double worst = 0;
        for (uint32_t t = 0; t < p->tri_count; t++)
            for (int k = 0; k < 9; k++) {
                uint32_t vi = p->tris[3 * (size_t)t + (size_t)(k / 3)];
                int a = k % 3;
                float in = m.pos[3 * (size_t)m.idx[3 * (size_t)p->remap[t] + (size_t)(k / 3)] + (size_t)a];
                uint32_t q = p->qverts[3 * (size_t)vi + (size_t)a];
                double e = fabs((double)deq(p, a, q) - in);
                worst = e > worst ? e : worst;
                if (q > 0)
                    assert_true(e <= fabs((double)deq(p, a, q - 1) - in));
                if (q < 65535)
                    assert_true(e <= fabs((double)deq(p, a, q + 1) - in));
            }
        assert_true(worst == c.stats.vertex_max_error);
        assert_true(worst > 0);
        double extent = 100.0;
        assert_true(worst <= extent / 65535.0 + fabs(offsets[i]) * 2e-7);
        check_triangles_match(p, &m, worst);
        cooked_free(&c);
        mesh_free(&m);
    }
}

/* More than 65536 vertices: LOCAL8 triangles, with fewer bytes than DELTA16 (the narrowest other encoding)
 * would take with each vertex once. */
static void test_large_mesh_encodings(void **state)
{
    (void)state;
    test_mesh m;
    make_grid(&m, 300, 10.0, 9);
    cooked c;
    cook_and_check(&m, NULL, &c);
    assert_int_equal(c.p.encoding[2], 4);
    assert_true(c.p.vert_count >= 301 * 301);
    assert_true(c.p.size[2] + c.p.size[3] < 8 * (uint64_t)c.p.tri_count + 12 * 301 * 301);
    assert_int_equal(c.p.encoding[4], 2); /* REMAP u24: 180000 triangles (u32 past 2^24) */
    cooked_free(&c);
    mesh_free(&m);
}

/* nt triangles whose corners are drawn at random from a pool of nv random points in the unit cube: in any
 * triangle order most corners were first used long before, so LOCAL8 would copy nearly every one. */
static void make_pool_soup(test_mesh *m, size_t nv, size_t nt, uint64_t seed)
{
    rng_seed(seed);
    mesh_alloc(m, nv, nt);
    for (size_t i = 0; i < 3 * nv; i++)
        m->pos[i] = (float)rng_unit();
    for (size_t i = 0; i < 3 * nt; i++)
        m->idx[i] = (uint32_t)(rng_unit() * (double)nv);
}

/* When LOCAL8's copies cost more than they save, the cooker keeps each vertex once with the narrowest other
 * encoding: u16 for a small pool, DELTA16 (with its own copies) past 65536 vertices. */
static void test_pool_encodings(void **state)
{
    (void)state;
    test_mesh m;
    make_pool_soup(&m, 2000, 20000, 11);
    cooked c;
    cook_and_check(&m, NULL, &c);
    assert_int_equal(c.p.encoding[2], 0);
    assert_int_equal(c.p.vert_count, 2000);
    assert_int_equal(c.p.size[2] + c.p.size[3], 6 * (uint64_t)c.p.tri_count + 12 * 2000);
    cooked_free(&c);
    mesh_free(&m);

    make_pool_soup(&m, 70000, 100000, 12);
    cook_and_check(&m, NULL, &c);
    assert_int_equal(c.p.encoding[2], 2);
    assert_true(c.p.vert_count >= 70000 - 100); /* a few points no kept triangle uses may be dropped */
    cooked_free(&c);
    mesh_free(&m);
}

static void test_weld_and_degenerate(void **state)
{
    (void)state;
    /* v0..v3 a quad; v4 duplicates v2; v5 = -0 copy of v0 (v0 at +0); v6 unused; v7 collinear with v0, v1. */
    const float pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 1, 1, 0, -0.0f, -0.0f, 0, 9, 9, 9, 2, 0, 0};
    const uint32_t idx[] = {
        0, 1, 2, /* kept */
        0, 4, 3, /* kept: v4 welds to v2 */
        5, 1, 3, /* kept: v5 welds to v0 */
        2, 4, 3, /* degenerate after welding (v2 == v4) */
        0, 1, 7, /* zero area (collinear) */
        1, 1, 2, /* repeated index */
        3, 2, 1, /* kept */
    };
    cbvh_mesh mesh = {pos, 8, 0, idx, 7, NULL};
    void *data;
    size_t size;
    cbvh_cook_stats st;
    cbvh_cook_stats_init(&st, sizeof st);
    cbvh_error err;
    cbvh_cook_options o;
    binary_options(&o);
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, &st, &err), CBVH_OK);
    assert_int_equal(st.dropped_degenerate, 3);
    assert_int_equal(st.triangles, 4);
    assert_int_equal(st.vertices, 4); /* v4, v5 welded, v6, v7 unused */
    parsed p;
    parse(data, size, &p);
    assert_int_equal(p.vert_count, 4);
    assert_int_equal(p.orig_count, 7);
    uint32_t seen = 0;
    for (uint32_t t = 0; t < p.tri_count; t++)
        seen |= 1u << p.remap[t];
    assert_int_equal(seen, 1u | 2u | 4u | 64u);
    parsed_free(&p);
    cbvh_buffer_free(NULL, data);

    /* A strided position array gives the same file as a packed one. */
    float strided[8 * 5];
    for (int v = 0; v < 8; v++) {
        memcpy(strided + 5 * v, pos + 3 * v, 12);
        strided[5 * v + 3] = NAN; /* padding the cooker must not read */
        strided[5 * v + 4] = NAN;
    }
    cbvh_mesh mesh2 = {strided, 8, 20, idx, 7, NULL};
    void *data2;
    size_t size2;
    assert_int_equal(cbvh_cook(&mesh, NULL, NULL, &data, &size, NULL, NULL), CBVH_OK);
    assert_int_equal(cbvh_cook(&mesh2, NULL, NULL, &data2, &size2, NULL, &err), CBVH_OK);
    assert_int_equal(size, size2);
    assert_memory_equal(data, data2, size);
    cbvh_buffer_free(NULL, data);
    cbvh_buffer_free(NULL, data2);
}

static void test_remap_and_materials(void **state)
{
    (void)state;
    test_mesh m;
    make_soup(&m, 200, 4, 5.0, 1.0, origin3);
    m.mat = calloc(m.nt, sizeof(uint32_t));
    cbvh_cook_options o;
    binary_options(&o);
    cooked c;
    /* All 0: no MATERIALS section. */
    cook_and_check(&m, &o, &c);
    assert_null(c.p.mats);
    assert_int_equal(c.p.section_count, 4);
    cooked_free(&c);
    /* All equal: one id for all (issue 12: it read back as 0 when the section was left out). */
    for (size_t t = 0; t < m.nt; t++)
        m.mat[t] = 7;
    cook_and_check(&m, &o, &c);
    assert_non_null(c.p.mats);
    assert_int_equal(c.p.mats_uniform, 1);
    assert_int_equal(c.p.size[5], 4);
    assert_int_equal(c.p.section_count, 5);
    for (uint32_t t = 0; t < c.p.tri_count; t++)
        assert_int_equal(c.p.mats[t], 7);
    cbvh_file *f;
    assert_int_equal(cbvh_open_memory(c.data, c.size, NULL, &f, NULL), CBVH_OK);
    for (uint32_t t = 0; t < m.nt; t++)
        assert_int_equal(cbvh_file_get_material(f, t), 7);
    cbvh_close(f);
    cooked_free(&c);
    static const uint32_t largest[] = {200, 60000, 70000};
    for (int e = 0; e < 3; e++) {
        for (size_t t = 0; t < m.nt; t++)
            m.mat[t] = (uint32_t)(t * 7919u) % (largest[e] + 1);
        m.mat[5] = largest[e];
        cook_and_check(&m, &o, &c);
        assert_non_null(c.p.mats);
        assert_int_equal(c.p.encoding[5], (uint32_t)e);
        for (uint32_t t = 0; t < c.p.tri_count; t++)
            assert_int_equal(c.p.mats[t], m.mat[c.p.remap[t]]);
        cooked_free(&c);
    }
    o.keep_materials = 0;
    cook_and_check(&m, &o, &c);
    assert_null(c.p.mats);
    cooked_free(&c);
    o.keep_remap = 0;
    cook_and_check(&m, &o, &c);
    assert_null(c.p.remap);
    assert_int_equal(c.p.section_count, 3);
    assert_int_equal(c.p.orig_count, c.p.tri_count);
    cooked_free(&c);
    mesh_free(&m);
}

/* Names given in any order, with repeats, come out sorted by (id, name), each once; the loader finds them. */
static void test_material_names(void **state)
{
    (void)state;
    test_mesh m;
    make_soup(&m, 50, 9, 5.0, 1.0, origin3);
    static const cbvh_material_name given[] = {{7, "Steel"}, {3, "Glass"},          {7, "Oak"},
                                               {7, "Steel"}, {1000000, "\xc3\xbc"}, {3, ""}};
    static const cbvh_material_name shuffled[] = {
        {1000000, "\xc3\xbc"}, {3, ""}, {7, "Oak"}, {3, "Glass"}, {7, "Steel"}};
    static const struct {
        uint32_t id;
        const char *name;
    } want[] = {{3, ""}, {3, "Glass"}, {7, "Oak"}, {7, "Steel"}, {1000000, "\xc3\xbc"}};
    cbvh_cook_options o;
    binary_options(&o);
    o.material_names = given;
    o.material_name_count = 6;
    for (int level = 0; level <= 9; level += 9) {
        o.compress_level = level;
        cooked c, again;
        cook_and_check(&m, &o, &c);
        assert_null(c.p.mats); /* no ids given: every triangle has material 0, and names are kept */
        assert_int_equal(c.p.name_count, 5);
        cbvh_file *f;
        assert_int_equal(cbvh_open_memory(c.data, c.size, NULL, &f, NULL), CBVH_OK);
        cbvh_file_info info;
        cbvh_file_get_info(f, &info, sizeof info);
        assert_int_equal(info.material_name_count, 5);
        for (uint32_t k = 0; k < 5; k++) {
            uint32_t id;
            assert_int_equal(c.p.name_ids[k], want[k].id);
            assert_string_equal(c.p.names[k], want[k].name);
            assert_string_equal(cbvh_file_get_material_name(f, k, &id), want[k].name);
            assert_int_equal(id, want[k].id);
        }
        assert_string_equal(cbvh_file_find_material_name(f, 3), "");
        assert_string_equal(cbvh_file_find_material_name(f, 7), "Oak");
        assert_null(cbvh_file_find_material_name(f, 4));
        assert_null(cbvh_file_find_material_name(f, 0xFFFFFFFFu));
        cbvh_close(f);
        o.material_names = shuffled;
        o.material_name_count = 5;
        cook_and_check(&m, &o, &again);
        assert_int_equal(again.size, c.size);
        assert_memory_equal(again.data, c.data, c.size);
        o.material_names = given;
        o.material_name_count = 6;
        cooked_free(&again);
        cooked_free(&c);
    }
    o.compress_level = 0;
    o.keep_materials = 0;
    cooked c;
    cook_and_check(&m, &o, &c);
    assert_int_equal(c.p.name_count, 0);
    assert_int_equal(c.p.section_count, 4);
    cooked_free(&c);

    /* Bad names are the caller's error, said before anything is cooked. */
    o.keep_materials = 1;
    cbvh_mesh mesh = as_mesh(&m);
    void *data = NULL;
    size_t size = 0;
    cbvh_error err;
    const cbvh_material_name unnamed[] = {{1, "a"}, {2, NULL}};
    o.material_names = unnamed;
    o.material_name_count = 2;
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(err.message, "material_names[1].name (material id 2) is NULL"));
    o.material_names = NULL;
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(err.message, "material_names is NULL"));
    char *huge = malloc(CBVH_MAX_MATERIAL_NAME_BYTES);
    assert_non_null(huge);
    memset(huge, 'x', CBVH_MAX_MATERIAL_NAME_BYTES - 1);
    huge[CBVH_MAX_MATERIAL_NAME_BYTES - 13] = '\0'; /* 4 + 8 + name + NUL: exactly the limit */
    const cbvh_material_name big[] = {{1, huge}};
    o.material_names = big;
    o.material_name_count = 1;
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, NULL, &err), CBVH_OK);
    cbvh_file *f;
    assert_int_equal(cbvh_open_memory(data, size, NULL, &f, NULL), CBVH_OK);
    assert_int_equal(strlen(cbvh_file_find_material_name(f, 1)), CBVH_MAX_MATERIAL_NAME_BYTES - 13);
    cbvh_close(f);
    cbvh_buffer_free(NULL, data);
    huge[CBVH_MAX_MATERIAL_NAME_BYTES - 13] = 'x'; /* one byte more */
    huge[CBVH_MAX_MATERIAL_NAME_BYTES - 12] = '\0';
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_non_null(strstr(err.message, "more than the"));
    free(huge);
    mesh_free(&m);
}

static void test_determinism(void **state)
{
    (void)state;
    test_mesh m;
    make_soup(&m, 5000, 77, 50.0, 3.0, origin3);
    for (int variant = 0; variant < 3; variant++) {
        cbvh_cook_options o;
        binary_options(&o);
        o.compress_level = variant == 1 ? 6 : 0;
        o.vertex_format = variant == 2 ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
        cooked a, b;
        cook_and_check(&m, &o, &a);
        cook_and_check(&m, &o, &b);
        assert_int_equal(a.size, b.size);
        assert_memory_equal(a.data, b.data, a.size);
        if (variant == 1) {
            /* Compressed sections decode to the raw ones. */
            cbvh_cook_options raw = o;
            raw.compress_level = 0;
            cooked r;
            cook_and_check(&m, &raw, &r);
            assert_true(a.size < r.size);
            assert_int_equal(a.p.codec[1], 1);
            assert_memory_equal(a.p.nodes, r.p.nodes, sizeof(cbvh_node) * r.p.node_count);
            assert_memory_equal(a.p.tris, r.p.tris, 12 * (size_t)r.p.tri_count);
            assert_memory_equal(a.p.verts, r.p.verts, 12 * (size_t)r.p.vert_count);
            assert_memory_equal(a.p.remap, r.p.remap, 4 * (size_t)r.p.tri_count);
            cooked_free(&r);
        }
        cooked_free(&a);
        cooked_free(&b);
    }
    mesh_free(&m);
}

/* A geometric series of triangles drives a pure SAH build to one triangle per level:
 * the depth limit forces median splits. */
static void test_depth_limit(void **state)
{
    (void)state;
    test_mesh m;
    /* from 2^-35 to 2^38.4: the series spans most of the exact range (cbvh.h, CBVH_COORDINATE_MAX) */
    mesh_alloc(&m, 3 * 280, 280);
    for (size_t t = 0; t < 280; t++) {
        double x = ldexp(pow(1.2, (double)t), -35);
        const float tri[9] = {(float)x, 0, 0, (float)(x * 1.05), 0, 0, (float)x, (float)(x * 0.05), 0};
        memcpy(m.pos + 9 * t, tri, sizeof tri);
        for (int c = 0; c < 3; c++)
            m.idx[3 * t + (size_t)c] = (uint32_t)(3 * t + (size_t)c);
    }
    for (uint32_t leaf = 1; leaf <= 16; leaf *= 4) {
        cbvh_cook_options o;
        binary_options(&o);
        o.max_leaf_size = leaf;
        cooked c;
        cook_and_check(&m, &o, &c);
        assert_true(c.stats.depth <= 64);
        assert_true(c.stats.depth >= 20); /* the SAH did peel (the test is meaningful) */
        cooked_free(&c);
    }
    mesh_free(&m);
}

/* Many copies of one triangle: no plane separates them, median splits must. */
static void test_identical_triangles(void **state)
{
    (void)state;
    test_mesh m;
    mesh_alloc(&m, 3, 1000);
    const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    memcpy(m.pos, tri, sizeof tri);
    for (size_t t = 0; t < m.nt; t++)
        for (int c = 0; c < 3; c++)
            m.idx[3 * t + (size_t)c] = (uint32_t)c;
    static const uint32_t leaf[] = {1, 3, 16};
    for (int i = 0; i < 3; i++) {
        cbvh_cook_options o;
        binary_options(&o);
        o.max_leaf_size = leaf[i];
        cooked c;
        cook_and_check(&m, &o, &c);
        assert_true(c.stats.depth <= 12);
        assert_int_equal(c.stats.vertices, 3);
        cooked_free(&c);
    }
    mesh_free(&m);
}

/* SAH cost of a median-split tree over the same triangles, in double, on exact float boxes. */
typedef struct ref_tri {
    double lo[3], hi[3], c[3];
} ref_tri;

static int sort_axis;
static int cmp_ref(const void *x, const void *y)
{
    double a = ((const ref_tri *)x)->c[sort_axis], b = ((const ref_tri *)y)->c[sort_axis];
    return (a > b) - (a < b);
}

static double median_sah(ref_tri *r, size_t n, uint32_t leaf, double *root_area)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], r[i].lo[k]);
            hi[k] = fmax(hi[k], r[i].hi[k]);
            clo[k] = fmin(clo[k], r[i].c[k]);
            chi[k] = fmax(chi[k], r[i].c[k]);
        }
    double d[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    double area = d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
    if (root_area)
        *root_area = area;
    if (n <= leaf)
        return area * (double)n;
    sort_axis = 0;
    for (int k = 1; k < 3; k++)
        if (chi[k] - clo[k] > chi[sort_axis] - clo[sort_axis])
            sort_axis = k;
    qsort(r, n, sizeof *r, cmp_ref);
    return area + median_sah(r, n / 2, leaf, NULL) + median_sah(r + n / 2, n - n / 2, leaf, NULL);
}

static void test_sah_quality(void **state)
{
    (void)state;
    /* Skewed: a dense cluster of small triangles in a corner, a few large ones elsewhere. */
    test_mesh m;
    make_soup(&m, 4000, 31, 100.0, 0.5, origin3);
    rng_seed(99);
    for (size_t t = 0; t < 3600; t++) {
        double c[3] = {90 + rng_unit() * 10, 90 + rng_unit() * 10, 90 + rng_unit() * 10};
        for (int v = 0; v < 3; v++)
            for (int k = 0; k < 3; k++)
                m.pos[9 * t + 3 * (size_t)v + (size_t)k] = (float)(c[k] + rng_unit() * 0.05);
    }
    /* Against a median build with unit costs and leaves of 4: cook with those. */
    cbvh_cook_options unit;
    binary_options(&unit);
    unit.traversal_cost = 1.0f;
    unit.max_leaf_size = 4;
    cooked c;
    cook_and_check(&m, &unit, &c);
    ref_tri *r = calloc(m.nt, sizeof *r);
    for (size_t t = 0; t < m.nt; t++)
        for (int k = 0; k < 3; k++) {
            r[t].lo[k] = INFINITY;
            r[t].hi[k] = -INFINITY;
            for (int v = 0; v < 3; v++) {
                double x = m.pos[3 * (size_t)m.idx[3 * t + (size_t)v] + (size_t)k];
                r[t].lo[k] = fmin(r[t].lo[k], x);
                r[t].hi[k] = fmax(r[t].hi[k], x);
            }
            r[t].c[k] = (r[t].lo[k] + r[t].hi[k]) / 2;
        }
    double root;
    double med = median_sah(r, m.nt, 4, &root);
    med /= root;
    print_message("SAH cost: SAH build %.3f, median build %.3f\n", c.stats.sah_cost, med);
    assert_true(c.stats.sah_cost < 0.8 * med);
    /* Costs are honoured: a dear traversal gives fewer nodes. */
    cbvh_cook_options o = unit;
    o.traversal_cost = 8.0f;
    cooked d;
    cook_and_check(&m, &o, &d);
    assert_true(d.stats.nodes < c.stats.nodes);
    cooked_free(&d);
    free(r);
    cooked_free(&c);
    mesh_free(&m);
}

/* ------------------------------------------------------------------ bad input */

static void expect_error(const cbvh_mesh *mesh, const cbvh_cook_options *o, cbvh_result code, const char *a,
                         const char *b)
{
    void *data = (void *)1;
    size_t size = 1;
    cbvh_error err;
    cbvh_cook_stats st;
    cbvh_cook_stats_init(&st, sizeof st);
    cbvh_result r = cbvh_cook(mesh, o, NULL, &data, &size, &st, &err);
    if (r != code || err.code != code)
        fail_msg("expected %d, got %d (%s)", code, r, err.message);
    assert_null(data);
    assert_int_equal(size, 0);
    if ((a && !strstr(err.message, a)) || (b && !strstr(err.message, b)))
        fail_msg("message '%s' does not name '%s' and '%s'", err.message, a, b ? b : "");
    /* NULL err is accepted too. */
    assert_int_equal(cbvh_cook(mesh, o, NULL, &data, &size, NULL, NULL), code);
}

static void test_bad_meshes(void **state)
{
    (void)state;
    test_mesh m;
    make_grid(&m, 4, 1.0, 2);
    cbvh_mesh mesh = as_mesh(&m);

    m.pos[3 * 7 + 1] = NAN;
    expect_error(&mesh, NULL, CBVH_ERROR_BAD_MESH, "vertex 7", "y coordinate is NaN");
    m.pos[3 * 7 + 1] = 0;
    m.pos[3 * 12 + 2] = -INFINITY;
    expect_error(&mesh, NULL, CBVH_ERROR_BAD_MESH, "vertex 12", "z coordinate is infinite");
    m.pos[3 * 12 + 2] = 0;
    /* NaN in a vertex no triangle uses is harmless. */
    float *extra = malloc(sizeof(float) * 3 * (m.nv + 1));
    memcpy(extra, m.pos, sizeof(float) * 3 * m.nv);
    extra[3 * m.nv] = NAN;
    cbvh_mesh with_unused = mesh;
    with_unused.positions = extra;
    with_unused.vertex_count = m.nv + 1;
    void *data;
    size_t size;
    assert_int_equal(cbvh_cook(&with_unused, NULL, NULL, &data, &size, NULL, NULL), CBVH_OK);
    cbvh_buffer_free(NULL, data);
    free(extra);

    m.idx[3 * 3 + 2] = (uint32_t)m.nv;
    expect_error(&mesh, NULL, CBVH_ERROR_BAD_MESH, "triangle 3, corner 2", "out of range");
    m.idx[3 * 3 + 2] = 0xFFFFFFFFu;
    expect_error(&mesh, NULL, CBVH_ERROR_BAD_MESH, "triangle 3, corner 2", "4294967295");
    m.idx[3 * 3 + 2] = 0;

    /* The exact range (cbvh.h): one float step past CBVH_COORDINATE_MAX, on either side, is refused with the
     * vertex, the axis and the limit named; up to it the mesh cooks (the grid spans 4 here: times 2^38 its
     * largest coordinate is 2^40). */
    float saved = m.pos[0];
    m.pos[0] = -3e38f;
    expect_error(&mesh, NULL, CBVH_ERROR_BAD_MESH, "vertex 0: x coordinate -3e+38", "exact range of +-2^40");
    m.pos[0] = -nextafterf(CBVH_COORDINATE_MAX, INFINITY);
    expect_error(&mesh, NULL, CBVH_ERROR_BAD_MESH, "vertex 0: x coordinate -1.09951e+12",
                 "exact range of +-2^40");
    m.pos[0] = saved;
    saved = m.pos[3 * 24 + 2];
    m.pos[3 * 24 + 2] = nextafterf(CBVH_COORDINATE_MAX, INFINITY);
    expect_error(&mesh, NULL, CBVH_ERROR_BAD_MESH, "vertex 24: z coordinate 1.09951e+12",
                 "exact range of +-2^40");
    m.pos[3 * 24 + 2] = saved;
    for (size_t i = 0; i < 3 * m.nv; i++)
        m.pos[i] *= 0x1p38f;
    cooked c;
    cook_and_check(&m, NULL, &c);
    assert_int_equal(c.stats.flushed_coordinates, 0);
    cooked_free(&c);
    for (size_t i = 0; i < 3 * m.nv; i++)
        m.pos[i] /= 0x1p38f;
    /* Coordinates below CBVH_COORDINATE_MIN are stored as 0 and counted (cook_and_check compares every
     * stored vertex with the input so flushed); CBVH_COORDINATE_MIN itself is kept. */
    const float z5 = m.pos[3 * 5 + 2], z6 = m.pos[3 * 6 + 2], z7 = m.pos[3 * 7 + 2];
    m.pos[3 * 5 + 2] = nextafterf(CBVH_COORDINATE_MIN, 0.0f);
    m.pos[3 * 6 + 2] = -0x1p-149f; /* subnormal */
    m.pos[3 * 7 + 2] = CBVH_COORDINATE_MIN;
    cook_and_check(&m, NULL, &c);
    assert_int_equal(c.stats.flushed_coordinates, 2);
    cooked_free(&c);
    m.pos[3 * 5 + 2] = z5;
    m.pos[3 * 6 + 2] = z6;
    m.pos[3 * 7 + 2] = z7;

    /* More triangles than 32-bit original ids can name: a limit, found before any index is read. */
    if (SIZE_MAX > UINT32_MAX) {
        cbvh_mesh huge = mesh;
        huge.triangle_count = (size_t)UINT32_MAX + 1;
        expect_error(&huge, NULL, CBVH_ERROR_LIMIT, "4294967296 triangles", NULL);
    }

    cbvh_mesh empty = mesh;
    empty.triangle_count = 0;
    expect_error(&empty, NULL, CBVH_ERROR_EMPTY_MESH, "no triangles", NULL);
    /* All degenerate: every vertex on a line (flat on two axes). */
    for (size_t v = 0; v < m.nv; v++)
        m.pos[3 * v + 1] = m.pos[3 * v + 2] = 0;
    expect_error(&mesh, NULL, CBVH_ERROR_EMPTY_MESH, "all 32 triangles are degenerate", NULL);
    mesh_free(&m);

    /* Caller errors. */
    expect_error(NULL, NULL, CBVH_ERROR_INVALID_ARGUMENT, "mesh", NULL);
    make_soup(&m, 4, 1, 1, 1, origin3);
    mesh = as_mesh(&m);
    cbvh_mesh bad = mesh;
    bad.positions = NULL;
    expect_error(&bad, NULL, CBVH_ERROR_INVALID_ARGUMENT, "positions", NULL);
    bad = mesh;
    bad.indices = NULL;
    expect_error(&bad, NULL, CBVH_ERROR_INVALID_ARGUMENT, "indices", NULL);
    bad = mesh;
    bad.position_stride = 8;
    expect_error(&bad, NULL, CBVH_ERROR_INVALID_ARGUMENT, "position_stride", NULL);
    cbvh_error err;
    assert_int_equal(cbvh_cook(&mesh, NULL, NULL, NULL, &size, NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_cook(&mesh, NULL, NULL, &data, NULL, NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);
    mesh_free(&m);
}

static void test_bad_options(void **state)
{
    (void)state;
    test_mesh m;
    make_soup(&m, 10, 1, 1, 1, origin3);
    cbvh_mesh mesh = as_mesh(&m);
    cbvh_cook_options o;
    cbvh_cook_options_init(&o, sizeof o);
    assert_int_equal(o.max_leaf_size, 16);
    assert_int_equal(o.sah_bins, 32);
    assert_true(o.traversal_cost == 4.0f && o.intersection_cost == 1.0f);
    assert_int_equal(o.vertex_format, CBVH_VERTEX_FLOAT32);
    assert_int_equal(o.compress_level, 0);
    assert_int_equal(o.keep_remap, 1);
    assert_int_equal(o.keep_materials, 1);
    assert_int_equal(o.layout, CBVH_LAYOUT_WIDE4);
#define BAD(field, value)                                                                                    \
    do {                                                                                                     \
        cbvh_cook_options b = o;                                                                             \
        b.field = value;                                                                                     \
        expect_error(&mesh, &b, CBVH_ERROR_INVALID_ARGUMENT, #field, NULL);                                  \
    } while (0)
    BAD(max_leaf_size, 0);
    BAD(max_leaf_size, 17);
    BAD(sah_bins, 3);
    BAD(sah_bins, 257);
    BAD(traversal_cost, -1.0f);
    BAD(traversal_cost, NAN);
    BAD(intersection_cost, 0.0f);
    BAD(intersection_cost, INFINITY);
    BAD(vertex_format, (cbvh_vertex_format)2);
    BAD(compress_level, -1);
    BAD(compress_level, 10);
    BAD(keep_remap, 2);
    BAD(keep_materials, -1);
    BAD(layout, (cbvh_layout)2);
#undef BAD
    /* The extremes of each range are accepted. */
    static const uint32_t leaf[] = {1, 16}, bins[] = {4, 256};
    for (int i = 0; i < 2; i++) {
        cbvh_cook_options b = o;
        b.max_leaf_size = leaf[i];
        b.sah_bins = bins[i];
        b.compress_level = 9 * i;
        b.traversal_cost = (float)i;
        b.layout = CBVH_LAYOUT_BINARY; /* for the parser */
        cooked c;
        cook_and_check(&m, &b, &c);
        cooked_free(&c);
    }
    mesh_free(&m);
}

/* ------------------------------------------------------------------ allocation failures, progress */

/* stats.peak_memory is what the cook held at once through the caller's allocator: the same figure as an
 * allocator that counts every block it hands out (the library's block headers included), on both layouts,
 * raw and compressed. The figure must also hold the file itself. */
static void test_peak_memory(void **state)
{
    (void)state;
    test_mesh m;
    const double center[3] = {0, 0, 0};
    make_sphere(&m, 60, 90, 1.0, center);
    cbvh_mesh mesh = as_mesh(&m);
    for (int layout = CBVH_LAYOUT_BINARY; layout <= CBVH_LAYOUT_WIDE4; layout++)
        for (int level = 0; level <= 6; level += 6) {
            cbvh_cook_options o;
            binary_options(&o);
            o.layout = (cbvh_layout)layout;
            o.compress_level = level;
            cbvh_cook_stats st;
            cbvh_cook_stats_init(&st, sizeof st);
            counting_alloc c;
            cbvh_allocator a = counting_allocator(&c, -1, 0);
            void *data = NULL;
            size_t size = 0;
            assert_int_equal(cbvh_cook(&mesh, &o, &a, &data, &size, &st, NULL), CBVH_OK);
            assert_int_equal(st.peak_memory, c.peak_bytes);
            assert_true(st.peak_memory >= size + 12 * st.triangles); /* the file, and the triangles once */
            assert_int_equal(c.live, 1);
            cbvh_buffer_free(&a, data);
        }
    mesh_free(&m);
}

/* Fails allocation n for every n a successful cook makes: each run either fails cleanly
 * (out of memory, nothing leaked) or, where a failure has a fallback (the builder's second
 * thread), succeeds with the very same bytes. */
static void alloc_failure_loop(const test_mesh *m, const cbvh_cook_options *o)
{
    cbvh_mesh mesh = as_mesh(m);
    counting_alloc ref;
    cbvh_allocator ra = counting_allocator(&ref, -1, 0);
    void *expect = NULL;
    size_t expect_size = 0;
    assert_int_equal(cbvh_cook(&mesh, o, &ra, &expect, &expect_size, NULL, NULL), CBVH_OK);
    assert_true(ref.calls >= 8);
    int failures = 0;
    for (long n = 0; n < ref.calls; n++) {
        counting_alloc c;
        cbvh_allocator a = counting_allocator(&c, n, 0);
        void *data = NULL;
        size_t size = 0;
        cbvh_error err;
        cbvh_result r = cbvh_cook(&mesh, o, &a, &data, &size, NULL, &err);
        if (r == CBVH_OK) {
            assert_int_equal(size, expect_size);
            assert_memory_equal(data, expect, size);
            assert_int_equal(c.live, 1);
            cbvh_buffer_free(&a, data);
        } else {
            assert_int_equal(r, CBVH_ERROR_OUT_OF_MEMORY);
            assert_non_null(strstr(err.message, "out of memory"));
            assert_null(data);
            failures++;
        }
        assert_int_equal(c.live, 0);
    }
    assert_true(failures >= ref.calls - 2);
    cbvh_buffer_free(&ra, expect);
    assert_int_equal(ref.live, 0);
}

static void test_allocation_failures(void **state)
{
    (void)state;
    test_mesh m;
    make_grid(&m, 12, 1.0, 3);
    m.mat = calloc(m.nt, sizeof(uint32_t));
    m.mat[1] = 2;
    for (int variant = 0; variant < 4; variant++) {
        cbvh_cook_options o;
        cbvh_cook_options_init(&o, sizeof o);
        o.layout = variant & 2 ? CBVH_LAYOUT_WIDE4 : CBVH_LAYOUT_BINARY;
        o.compress_level = variant & 1 ? 9 : 0;
        o.vertex_format = variant & 1 ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
        alloc_failure_loop(&m, &o);
    }
    mesh_free(&m);
    /* Large enough for the builder's second thread, whose allocations have a fallback. */
    make_soup(&m, 70000, 12, 100, 1, origin3);
    cbvh_cook_options o;
    cbvh_cook_options_init(&o, sizeof o);
    alloc_failure_loop(&m, &o);
    mesh_free(&m);
}

typedef struct progress_log {
    int calls;
    int last_phase;
    double last;
    int ended[4];
} progress_log;

static void on_progress(void *user, cbvh_phase phase, double f)
{
    progress_log *l = user;
    assert_true(f >= 0 && f <= 1);
    assert_true((int)phase >= l->last_phase);
    if ((int)phase == l->last_phase)
        assert_true(f >= l->last);
    l->last_phase = (int)phase;
    l->last = f;
    if (f == 1.0)
        l->ended[phase] = 1;
    l->calls++;
}

static void test_progress(void **state)
{
    (void)state;
    /* Large enough for the builder's second thread: reports still come from this one. */
    test_mesh m;
    make_soup(&m, 140000, 5, 100, 1, origin3);
    cbvh_mesh mesh = as_mesh(&m);
    cbvh_cook_options o;
    cbvh_cook_options_init(&o, sizeof o);
    progress_log log = {0, 0, 0, {0}};
    o.progress = on_progress;
    o.progress_user = &log;
    void *data;
    size_t size;
    cbvh_cook_stats st;
    cbvh_cook_stats_init(&st, sizeof st);
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, &st, NULL), CBVH_OK);
    for (int p = 0; p < 4; p++) {
        assert_true(log.ended[p]);
        assert_true(st.seconds[p] >= 0);
    }
    assert_true(log.calls >= 8 && log.calls <= 400);
    cbvh_buffer_free(NULL, data);
    mesh_free(&m);
}

/* ------------------------------------------------------------------ struct sizes */

/* A progress callback that must never run: it sits past a short options struct. */
static void progress_not_expected(void *user, cbvh_phase phase, double fraction)
{
    (void)user;
    fail_msg("the library read options->progress past options->struct_size (phase %d, %g)", (int)phase,
             fraction);
}

#define GUARD_BYTE 0xA5

static void assert_guard(const void *p, size_t from, size_t to, const char *what)
{
    for (size_t i = from; i < to; i++)
        if (((const uint8_t *)p)[i] != GUARD_BYTE)
            fail_msg("%s: byte %zu past struct_size %zu was written", what, i, from);
}

/* A program built against an older cbvh.h has shorter structs: the library reads and writes only
 * the bytes their struct_size covers, and uses the defaults for options past them. */
static void test_old_struct_sizes(void **state)
{
    (void)state;
    test_mesh m;
    make_soup(&m, 2000, 9, 10, 1, origin3);
    cbvh_mesh mesh = as_mesh(&m);

    /* Options covering max_leaf_size .. vertex_format; whatever lies past them must not count. */
    const size_t short_options = offsetof(cbvh_cook_options, compress_level);
    cbvh_cook_options o;
    memset(&o, GUARD_BYTE, sizeof o);
    assert_int_equal(cbvh_cook_options_init(&o, short_options), CBVH_OK);
    assert_guard(&o, short_options, sizeof o, "cbvh_cook_options_init");
    assert_int_equal(o.struct_size, short_options);
    assert_int_equal(o.max_leaf_size, 16);
    o.max_leaf_size = 3;
    o.compress_level = 9;
    o.keep_remap = 0;
    o.progress = progress_not_expected;
    /* Reference: today's whole struct with the same covered fields and the defaults past them. */
    cbvh_cook_options whole;
    cbvh_cook_options_init(&whole, sizeof whole);
    whole.max_leaf_size = 3;

    /* Stats covering the counts up to (not including) file_size, cooked to memory and to a path. */
    const size_t short_stats = offsetof(cbvh_cook_stats, file_size);
    cbvh_cook_stats st, whole_st;
    memset(&st, GUARD_BYTE, sizeof st);
    assert_int_equal(cbvh_cook_stats_init(&st, short_stats), CBVH_OK);
    assert_guard(&st, short_stats, sizeof st, "cbvh_cook_stats_init");
    cbvh_cook_stats_init(&whole_st, sizeof whole_st);

    void *data, *whole_data;
    size_t size, whole_size;
    cbvh_error err;
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, &st, &err), CBVH_OK);
    assert_int_equal(cbvh_cook(&mesh, &whole, NULL, &whole_data, &whole_size, &whole_st, &err), CBVH_OK);
    assert_int_equal(size, whole_size);
    assert_memory_equal(data, whole_data, size); /* raw, with remap: nothing past struct_size was read */
    assert_guard(&st, short_stats, sizeof st, "cbvh_cook");
    assert_int_equal(st.struct_size, short_stats);
    assert_memory_equal((const uint8_t *)&st + sizeof st.struct_size,
                        (const uint8_t *)&whole_st + sizeof whole_st.struct_size,
                        short_stats - sizeof st.struct_size);
    assert_true(st.triangles > 0 && st.nodes > 0);

    /* cbvh_cook_to_path adds its write time to seconds, which this caller's struct does not have. */
    char dir[512], path[600];
    test_temp_dir(dir, sizeof dir, "cbvh_sizes");
    snprintf(path, sizeof path, "%s/out.cbvh", dir);
    memset(&st, GUARD_BYTE, sizeof st);
    cbvh_cook_stats_init(&st, short_stats);
    assert_int_equal(cbvh_cook_to_path(&mesh, &o, NULL, path, &st, &err), CBVH_OK);
    assert_guard(&st, short_stats, sizeof st, "cbvh_cook_to_path");
    assert_int_equal(st.nodes, whole_st.nodes);
    unlink(path);
    rmdir(dir);

    /* A program built before the layout field: its options end at progress_user, and the default layout
     * (wide4) applies whatever lies past them. */
    cbvh_buffer_free(NULL, data);
    memset(&o, GUARD_BYTE, sizeof o);
    cbvh_cook_options_init(&o, offsetof(cbvh_cook_options, layout));
    o.max_leaf_size = 3;
    o.layout = CBVH_LAYOUT_BINARY;
    assert_int_equal(cbvh_cook(&mesh, &o, NULL, &data, &size, NULL, &err), CBVH_OK);
    assert_int_equal(size, whole_size);
    assert_memory_equal(data, whole_data, size);

    cbvh_buffer_free(NULL, data);
    cbvh_buffer_free(NULL, whole_data);
    mesh_free(&m);
}

/* Expects cbvh_cook to refuse `o` and `st` with a message holding `a` and `b`, writing no output. */
static void expect_size_error(const cbvh_mesh *mesh, const cbvh_cook_options *o, cbvh_cook_stats *st,
                              const char *a, const char *b)
{
    void *data = (void *)1;
    size_t size = 1;
    cbvh_error err;
    cbvh_cook_stats before;
    if (st)
        memcpy(&before, st, sizeof before);
    assert_int_equal(cbvh_cook(mesh, o, NULL, &data, &size, st, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(err.code, CBVH_ERROR_INVALID_ARGUMENT);
    assert_null(data);
    assert_int_equal(size, 0);
    if (!strstr(err.message, a) || !strstr(err.message, b))
        fail_msg("message '%s' lacks '%s' or '%s'", err.message, a, b);
    if (st)
        assert_memory_equal(&before, st, sizeof before);
}

/* A struct_size of zero, of a pointer, or past this library's struct is an invalid argument. */
static void test_bad_struct_sizes(void **state)
{
    (void)state;
    test_mesh m;
    make_soup(&m, 50, 10, 10, 1, origin3);
    cbvh_mesh mesh = as_mesh(&m);
    cbvh_cook_options o;
    cbvh_cook_stats st;
    char expect[160];

    assert_int_equal(cbvh_cook_options_init(NULL, sizeof o), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_cook_stats_init(NULL, sizeof st), CBVH_ERROR_INVALID_ARGUMENT);

    /* Too small to hold struct_size itself: nothing is written. */
    memset(&o, GUARD_BYTE, sizeof o);
    assert_int_equal(cbvh_cook_options_init(&o, 0), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_cook_options_init(&o, sizeof o.struct_size - 1), CBVH_ERROR_INVALID_ARGUMENT);
    assert_guard(&o, 0, sizeof o, "cbvh_cook_options_init with size 0");
    memset(&st, GUARD_BYTE, sizeof st);
    assert_int_equal(cbvh_cook_stats_init(&st, 0), CBVH_ERROR_INVALID_ARGUMENT);
    assert_guard(&st, 0, sizeof st, "cbvh_cook_stats_init with size 0");

    /* sizeof a pointer (a common slip) holds the size but no field: recorded, refused, explained. */
    cbvh_cook_options_init(&o, sizeof &o);
    assert_int_equal(o.struct_size, sizeof &o);
    assert_guard(&o, sizeof o.struct_size, sizeof o, "cbvh_cook_options_init with sizeof a pointer");
    snprintf(expect, sizeof expect, "options->struct_size is %zu; it must be %zu to %zu", sizeof &o,
             offsetof(cbvh_cook_options, max_leaf_size) + sizeof o.max_leaf_size, sizeof o);
    expect_size_error(&mesh, &o, NULL, expect, "cbvh_cook_options_init(options, sizeof *options)");
    o.struct_size = 0;
    expect_size_error(&mesh, &o, NULL, "options->struct_size is 0;", "cbvh_cook_options_init");

    /* Larger than this library's struct: a program built against a newer header. */
    assert_int_equal(cbvh_cook_options_init(&o, sizeof o + 8), CBVH_ERROR_INVALID_ARGUMENT);
    snprintf(expect, sizeof expect,
             "options->struct_size is %zu, larger than this library's cbvh_cook_options", sizeof o + 8);
    expect_size_error(&mesh, &o, NULL, expect, "newer cbvh.h");

    /* Stats: checked before any work, and left as they were. */
    cbvh_cook_options_init(&o, sizeof o);
    cbvh_cook_stats_init(&st, sizeof st);
    st.struct_size = offsetof(cbvh_cook_stats, input_triangles);
    expect_size_error(&mesh, &o, &st, "stats->struct_size is", "cbvh_cook_stats_init(stats, sizeof *stats)");
    st.struct_size = sizeof st + 1;
    expect_size_error(&mesh, &o, &st, "stats->struct_size is", "newer cbvh.h");
    assert_int_equal(cbvh_cook_to_path(&mesh, &o, NULL, "/tmp/cbvh-never-written.cbvh", &st, NULL),
                     CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(access("/tmp/cbvh-never-written.cbvh", F_OK), -1);
    mesh_free(&m);
}

/* ------------------------------------------------------------------ cook_to_path */

static int count_entries(const char *dir)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
            n++;
    closedir(d);
    return n;
}

static uint8_t *read_whole(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)n + 1);
    assert_int_equal(fread(b, 1, (size_t)n, f), (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return b;
}

static void test_cook_to_path(void **state)
{
    (void)state;
    char dir[512];
    test_temp_dir(dir, sizeof dir, "test_cook");
    char path[600], missing[600];
    snprintf(path, sizeof path, "%s/out.cbvh", dir);
    snprintf(missing, sizeof missing, "%s/no/such/dir/out.cbvh", dir);

    test_mesh m;
    make_soup(&m, 300, 6, 10, 1, origin3);
    cbvh_mesh mesh = as_mesh(&m);
    void *mem;
    size_t mem_size;
    assert_int_equal(cbvh_cook(&mesh, NULL, NULL, &mem, &mem_size, NULL, NULL), CBVH_OK);

    /* An existing file is replaced by the complete new one. */
    FILE *f = fopen(path, "wb");
    fputs("old content", f);
    fclose(f);
    cbvh_cook_stats st;
    cbvh_cook_stats_init(&st, sizeof st);
    cbvh_error err;
    assert_int_equal(cbvh_cook_to_path(&mesh, NULL, NULL, path, &st, &err), CBVH_OK);
    size_t size;
    uint8_t *disk = read_whole(path, &size);
    assert_int_equal(size, mem_size);
    assert_memory_equal(disk, mem, size);
    assert_int_equal(st.file_size, size);
    free(disk);
    assert_int_equal(count_entries(dir), 1);

    /* A bad mesh leaves the destination untouched and no temporary file. */
    m.pos[4] = NAN;
    assert_int_equal(cbvh_cook_to_path(&mesh, NULL, NULL, path, NULL, &err), CBVH_ERROR_BAD_MESH);
    m.pos[4] = 0;
    disk = read_whole(path, &size);
    assert_int_equal(size, mem_size);
    assert_memory_equal(disk, mem, size);
    free(disk);
    assert_int_equal(count_entries(dir), 1);

    /* A destination in a missing folder: an I/O error naming it, nothing created. */
    assert_int_equal(cbvh_cook_to_path(&mesh, NULL, NULL, missing, NULL, &err), CBVH_ERROR_IO);
    assert_non_null(strstr(err.message, missing));
    assert_int_equal(count_entries(dir), 1);

    /* A destination that is a folder: refused (POSIX: before anything is created; Windows: the rename
     * fails and the temporary file is removed). */
    char sub[600];
    snprintf(sub, sizeof sub, "%s/sub", dir);
    assert_int_equal(test_mkdir(sub), 0);
    char inner[700];
    snprintf(inner, sizeof inner, "%s/x", sub);
    f = fopen(inner, "wb");
    fclose(f);
    assert_int_equal(cbvh_cook_to_path(&mesh, NULL, NULL, sub, NULL, &err), CBVH_ERROR_IO);
    assert_non_null(strstr(err.message, sub));
    assert_int_equal(count_entries(dir), 2);
    assert_int_equal(count_entries(sub), 1);
    assert_int_equal(cbvh_cook_to_path(&mesh, NULL, NULL, NULL, NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);

    unlink(inner);
    rmdir(sub);
    unlink(path);
    rmdir(dir);
    cbvh_buffer_free(NULL, mem);
    mesh_free(&m);
}

/* ------------------------------------------------------------------ round trip through the loader */

/* Opens a cooked file with the loader, which must accept it. */
static cbvh_file *open_cooked(const cooked *c)
{
    cbvh_file *file = NULL;
    cbvh_error err;
    if (cbvh_open_memory(c->data, c->size, NULL, &file, &err) != CBVH_OK)
        fail_msg("the loader rejects a cooked file: %s", err.message);
    return file;
}

static void round_trip(const test_mesh *m, const cbvh_cook_options *o)
{
    cooked c;
    cook_and_check(m, o, &c);
    cbvh_file *file = open_cooked(&c);
    cbvh_file_info info;
    cbvh_file_get_info(file, &info, sizeof info);
    assert_int_equal(info.format_version, 1);
    assert_int_equal(info.triangle_count, c.stats.triangles);
    assert_int_equal(info.vertex_count, c.stats.vertices);
    assert_int_equal(info.node_count, c.stats.nodes);
    assert_int_equal(info.depth, c.stats.depth);
    assert_int_equal(info.file_size, c.stats.file_size);
    assert_int_equal(info.has_remap, 1);
    assert_int_equal(info.vertex_format, o->vertex_format);
    assert_int_equal(info.section_count, c.p.section_count);
    for (int k = 0; k < 3; k++) {
        assert_true(info.grid_origin[k] == c.p.origin[k] && info.grid_scale[k] == c.p.scale[k]);
        assert_true(info.bounds_min[k] == c.p.bmin[k] && info.bounds_max[k] == c.p.bmax[k]);
    }
    for (uint32_t i = 0; i < info.section_count; i++) {
        cbvh_section_info s;
        assert_int_equal(cbvh_file_get_section(file, i, &s), 1);
        assert_int_equal(s.stored_size, c.stats.section_stored_size[s.type]);
        assert_int_equal(s.size, c.stats.section_size[s.type]);
    }
    /* Every kept input triangle reads back by its original id, as the parser decoded it. */
    for (uint32_t t = 0; t < c.p.tri_count; t++) {
        uint32_t o_id = c.p.remap[t];
        float v[3][3];
        assert_int_equal(cbvh_file_get_triangle(file, o_id, v[0], v[1], v[2]), 1);
        for (int k = 0; k < 3; k++)
            assert_memory_equal(v[k], c.p.verts + 3 * (size_t)c.p.tris[3 * (size_t)t + (size_t)k], 12);
        if (o->vertex_format == CBVH_VERTEX_FLOAT32)
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++)
                    assert_true(v[k][a] ==
                                stored_coordinate(
                                    m->pos[3 * (size_t)m->idx[3 * (size_t)o_id + (size_t)k] + (size_t)a]));
    }
    cbvh_close(file);
    cooked_free(&c);
}

static void test_loader_round_trip(void **state)
{
    (void)state;
    const double far[3] = {1e7, -3e5, 2};
    test_mesh meshes[3];
    make_sphere(&meshes[0], 30, 50, 3.0, origin3);
    make_grid(&meshes[1], 20, 0.0, 1); /* flat: grid_scale[2] == 0 */
    make_sphere(&meshes[2], 10, 20, 30.0, far);
    for (int i = 0; i < 3; i++) {
        for (int variant = 0; variant < 3; variant++) {
            cbvh_cook_options o;
            binary_options(&o);
            o.compress_level = variant == 1 ? 4 : 0;
            o.vertex_format = variant == 2 ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
            round_trip(&meshes[i], &o);
        }
        mesh_free(&meshes[i]);
    }
}

/* Finding F3 (notes/findings.md): a triangle smaller than the 16-bit vertex
 * grid's step collapses to a segment when its vertices are quantized. The
 * cooker drops it (counted in dropped_degenerate), so every triangle of a
 * quantized file has a non-zero area; the loader's exact-bounds check passes
 * although one of the tiny triangles held the mesh's extreme vertex. */
static void test_quantized_collapse(void **state)
{
    (void)state;
    float pos[] = {0,    0,    0,    4,
                   0,    0,    0,    4,
                   0,    0,    0,    4, /* a tetrahedron's faces, extent 4 */
                   1,    1,    1,    1 + 1e-6f,
                   1,    1,    1,    1 + 1e-6f,
                   1, /* tiny, inside */
                   4.5f, 4.5f, 4.5f, 4.5f - 1e-6f,
                   4.5f, 4.5f, 4.5f, 4.5f - 1e-6f,
                   4.5f}; /* tiny, the maximum corner */
    uint32_t idx[] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2, 4, 5, 6, 7, 8, 9};
    test_mesh m = {pos, idx, NULL, 10, 6};
    for (int q = 0; q < 2; q++) {
        cbvh_cook_options o;
        binary_options(&o);
        o.vertex_format = q ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
        cooked c;
        cook_and_check(&m, &o, &c);
        assert_int_equal(c.stats.dropped_degenerate, q ? 2 : 0);
        assert_int_equal(c.stats.triangles, q ? 4 : 6);
        cbvh_file *file = open_cooked(&c);
        cbvh_file_info info;
        cbvh_file_get_info(file, &info, sizeof info);
        for (int a = 0; a < 3; a++)
            assert_true(q ? info.bounds_max[a] < 4.25f : info.bounds_max[a] == 4.5f);
        for (uint32_t t = 0; t < 6; t++) {
            float v[3][3];
            const int present = cbvh_file_get_triangle(file, t, v[0], v[1], v[2]);
            assert_int_equal(present, !(q && t >= 4));
            if (!present)
                continue;
            double e1[3], e2[3];
            for (int a = 0; a < 3; a++) {
                e1[a] = (double)v[1][a] - v[0][a];
                e2[a] = (double)v[2][a] - v[0][a];
            }
            assert_true(e1[1] * e2[2] - e1[2] * e2[1] != 0.0 || e1[2] * e2[0] - e1[0] * e2[2] != 0.0 ||
                        e1[0] * e2[1] - e1[1] * e2[0] != 0.0);
        }
        cbvh_close(file);
        cooked_free(&c);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_soups),
        cmocka_unit_test(test_grid_and_sphere),
        cmocka_unit_test(test_far_from_origin),
        cmocka_unit_test(test_zero_and_flat),
        cmocka_unit_test(test_quantized_vertices),
        cmocka_unit_test(test_large_mesh_encodings),
        cmocka_unit_test(test_pool_encodings),
        cmocka_unit_test(test_weld_and_degenerate),
        cmocka_unit_test(test_remap_and_materials),
        cmocka_unit_test(test_material_names),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_depth_limit),
        cmocka_unit_test(test_identical_triangles),
        cmocka_unit_test(test_sah_quality),
        cmocka_unit_test(test_bad_meshes),
        cmocka_unit_test(test_bad_options),
        cmocka_unit_test(test_allocation_failures),
        cmocka_unit_test(test_progress),
        cmocka_unit_test(test_old_struct_sizes),
        cmocka_unit_test(test_bad_struct_sizes),
        cmocka_unit_test(test_cook_to_path),
        cmocka_unit_test(test_peak_memory),
        cmocka_unit_test(test_loader_round_trip),
        cmocka_unit_test(test_quantized_collapse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
