/* make_corpus.c: writes the fuzz seed corpora (tests/fuzz/corpus/open, tests/fuzz/corpus/cook); run once by
 * hand, its output is checked in. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cbvh.h"
#include "file_edit.h"
#include "le_bytes.h"
#include "support/scene_gen.h"
#include "support/test_os.h"

static const char *out_dir;

static void write_file(const char *sub, const char *name, const void *data, size_t size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", out_dir, sub);
    if (test_mkdir(path) != 0 && errno != EEXIST) {
        perror(path);
        exit(1);
    }
    snprintf(path, sizeof path, "%s/%s/%s", out_dir, sub, name);
    FILE *fp = fopen(path, "wb");
    if (!fp || fwrite(data, 1, size, fp) != size || fclose(fp) != 0) {
        perror(path);
        exit(1);
    }
    printf("%s/%s: %zu bytes\n", sub, name, size);
}

static uint8_t *cook(const scene *s, cbvh_layout layout, int quantized, int level, int keep_remap,
                     size_t *size)
{
    cbvh_mesh m = {s->positions, s->vertex_count, 0, s->indices, s->triangle_count, s->material_ids};
    cbvh_cook_options o;
    cbvh_cook_options_init(&o, sizeof o);
    o.vertex_format = quantized ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
    o.compress_level = level;
    o.keep_remap = keep_remap;
    o.layout = layout;
    /* scenes with material ids get names too (a MATERIAL_NAMES section) */
    static const cbvh_material_name names[] = {
        {0, "stone"}, {9, "glass"}, {70000, "wood"}, {140000, "metal"}};
    o.material_names = s->material_ids ? names : NULL;
    o.material_name_count = s->material_ids ? 4 : 0;
    void *out = NULL;
    cbvh_error err;
    if (cbvh_cook(&m, &o, NULL, &out, size, NULL, &err) != CBVH_OK) {
        fprintf(stderr, "cook failed: %s\n", err.message);
        exit(1);
    }
    uint8_t *copy = malloc(*size);
    memcpy(copy, out, *size);
    cbvh_buffer_free(NULL, out);
    return copy;
}

static void write_cooked(const scene *s, cbvh_layout layout, int quantized, int level, int keep_remap,
                         const char *name)
{
    size_t n;
    uint8_t *file = cook(s, layout, quantized, level, keep_remap, &n);
    write_file("open", name, file, n);
    free(file);
}

/* Re-encodes a u16 TRIANGLES (and REMAP) section of a raw file as `tris`
 * (1 = u32, 2 = DELTA16) and REMAP as u32, then writes it. */
static void write_transcoded(const uint8_t *file, size_t size, int tris, int remap32, int zlib,
                             const char *name)
{
    edit_file e;
    if (!edit_parse(&e, file, size)) {
        fprintf(stderr, "cannot parse the cooked file\n");
        exit(1);
    }
    int ti = edit_find(&e, 2), ri = edit_find(&e, 4);
    if (ti >= 0 && e.s[ti].encoding == 0 && tris) {
        size_t n = e.s[ti].size / 6;
        uint8_t *d = calloc(n, tris == 1 ? 12 : 8);
        for (size_t t = 0; t < n; t++) {
            uint32_t i0 = le_get_u16(e.s[ti].data + 6 * t), i1 = le_get_u16(e.s[ti].data + 6 * t + 2),
                     i2 = le_get_u16(e.s[ti].data + 6 * t + 4);
            if (tris == 1) {
                le_put_u32(d + 12 * t, i0);
                le_put_u32(d + 12 * t + 4, i1);
                le_put_u32(d + 12 * t + 8, i2);
            } else {
                le_put_u32(d + 8 * t, i0);
                le_put_u16(d + 8 * t + 4, (uint32_t)(int32_t)(i1 - i0));
                le_put_u16(d + 8 * t + 6, (uint32_t)(int32_t)(i2 - i0));
            }
        }
        edit_replace(&e, ti, d, n * (tris == 1 ? 12 : 8), (uint32_t)tris);
    }
    if (ri >= 0 && e.s[ri].encoding == 0 && remap32) {
        size_t n = e.s[ri].size / 2;
        uint8_t *d = malloc(4 * n);
        for (size_t t = 0; t < n; t++)
            le_put_u32(d + 4 * t, le_get_u16(e.s[ri].data + 2 * t));
        edit_replace(&e, ri, d, 4 * n, 1);
    }
    for (uint32_t i = 0; i < e.count; i++)
        e.s[i].codec = zlib ? 1 : 0;
    size_t out_size;
    uint8_t *out = edit_build(&e, &out_size);
    write_file("open", name, out, out_size);
    free(out);
    edit_free(&e);
}

/* The fuzz_cook input format (see fuzz_cook.c): int8 coordinates. */
static void write_cook_seed(const char *name, uint8_t flags, const int8_t *coords, size_t nv,
                            const uint8_t *tris, size_t nt, int materials)
{
    uint8_t buf[4096];
    size_t n = 0;
    buf[n++] = (uint8_t)(flags | 32);
    buf[n++] = 0x13;
    buf[n++] = (uint8_t)nv;
    buf[n++] = 128;        /* scale 1 */
    memset(buf + n, 0, 4); /* offset 0.0f */
    n += 4;
    memcpy(buf + n, coords, 3 * nv);
    n += 3 * nv;
    for (size_t t = 0; t < nt; t++) {
        memcpy(buf + n, tris + 3 * t, 3);
        n += 3;
        if (materials)
            buf[n++] = (uint8_t)(t * 37 + 1);
    }
    write_file("cook", name, buf, n);
}

/* The fuzz_cook input format with float coordinates, for a generated scene of at most 255 vertices;
 * `leaf_bins` is byte 1 (max_leaf_size - 1, SAH bins). */
static void write_cook_seed_float(const char *name, uint8_t flags, uint8_t leaf_bins, const scene *sc)
{
    static uint8_t buf[65536];
    size_t n = 0;
    buf[n++] = flags;
    buf[n++] = leaf_bins;
    buf[n++] = (uint8_t)sc->vertex_count;
    memcpy(buf + n, sc->positions, 12 * sc->vertex_count); /* little-endian host */
    n += 12 * sc->vertex_count;
    for (size_t i = 0; i < 3 * sc->triangle_count; i++)
        buf[n++] = (uint8_t)sc->indices[i];
    write_file("cook", name, buf, n);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s OUT_DIR (e.g. $srcdir/tests/fuzz/corpus)\n", argv[0]);
        return 2;
    }
    out_dir = argv[1];
    test_mkdir(out_dir);
    scene sphere, cube, soup;
    float c[3] = {0.5f, -1.0f, 2.0f}, lo[3] = {-1, -1, -1}, hi[3] = {1, 2, 3};
    if (!scene_sphere(&sphere, 40, c, 1.5f) || !scene_cube(&cube, lo, hi) || !scene_soup(&soup, 24, 0.3f, 7))
        return 1;
    soup.material_ids = malloc(soup.triangle_count * sizeof(uint32_t));
    for (size_t t = 0; t < soup.triangle_count; t++)
        soup.material_ids[t] = (uint32_t)(t % 3) * 70000u; /* needs u32 materials */

    const cbvh_layout binary = CBVH_LAYOUT_BINARY, wide4 = CBVH_LAYOUT_WIDE4;
    size_t n;
    uint8_t *raw = cook(&sphere, binary, 0, 0, 1, &n);
    write_file("open", "good-sphere-raw.cbvh", raw, n);
    write_transcoded(raw, n, 1, 1, 0, "good-sphere-tris-u32-remap-u32.cbvh");
    write_transcoded(raw, n, 2, 0, 0, "good-sphere-tris-delta16.cbvh");
    write_transcoded(raw, n, 2, 1, 1, "good-sphere-delta16-zlib.cbvh");
    uint8_t *bad = malloc(n);
    memcpy(bad, raw, n);
    write_file("open", "bad-truncated.cbvh", bad, n - 1);
    bad[n / 2] ^= 0x40; /* CRC catches it */
    write_file("open", "bad-crc.cbvh", bad, n);
    memcpy(bad, raw, n);
    bad[8] = 2; /* newer version: unsupported */
    write_file("open", "unsupported-version2.cbvh", bad, n);
    free(bad);
    free(raw);
    write_cooked(&sphere, binary, 0, 6, 1, "good-sphere-zlib.cbvh");
    write_cooked(&sphere, binary, 1, 0, 1, "good-sphere-q16.cbvh");
    write_cooked(&cube, binary, 0, 0, 0, "good-cube-noremap.cbvh");
    write_cooked(&soup, binary, 1, 9, 1, "good-soup-materials-q16-zlib.cbvh");

    /* the wide4 layout: the same kinds, and a truncated one */
    raw = cook(&sphere, wide4, 0, 0, 1, &n);
    write_file("open", "good-w4-sphere-raw.cbvh", raw, n);
    write_transcoded(raw, n, 1, 1, 0, "good-w4-sphere-tris-u32-remap-u32.cbvh");
    write_transcoded(raw, n, 2, 1, 1, "good-w4-sphere-delta16-zlib.cbvh");
    write_file("open", "bad-w4-truncated.cbvh", raw, n - 1);
    free(raw);
    write_cooked(&sphere, wide4, 1, 0, 1, "good-w4-sphere-q16.cbvh");
    write_cooked(&cube, wide4, 0, 0, 0, "good-w4-cube-noremap.cbvh");
    /* one material for all triangles (MATERIALS' uniform encoding) */
    cube.material_ids = malloc(cube.triangle_count * sizeof(uint32_t));
    for (size_t t = 0; t < cube.triangle_count; t++)
        cube.material_ids[t] = 9;
    write_cooked(&cube, binary, 0, 0, 1, "good-cube-uniform-material-names.cbvh");
    write_cooked(&cube, wide4, 0, 6, 1, "good-w4-cube-uniform-material-names-zlib.cbvh");
    write_cooked(&soup, wide4, 1, 9, 1, "good-w4-soup-materials-q16-zlib.cbvh");

    /* cook seeds: a tetrahedron, a cube with a degenerate and a duplicated
     * triangle, a bad index, a sliver */
    static const int8_t tet[] = {0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 100};
    static const uint8_t tet_t[] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
    write_cook_seed("tetra.bin", 0, tet, 4, tet_t, 4, 0);
    write_cook_seed("tetra-q16-zlib-materials.bin", 1 | 4, tet, 4, tet_t, 4, 1);
    static const int8_t box[] = {-50, -50, -50, 50, -50, -50, 50, 50, -50, -50, 50, -50,
                                 -50, -50, 50,  50, -50, 50,  50, 50, 50,  -50, 50, 50};
    static const uint8_t box_t[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4, 1, 2, 6,
                                    1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7, 0, 0, 1, 4, 5, 6};
    write_cook_seed("cube-degenerate-duplicate.bin", 8, box, 8, box_t, 14, 0);
    static const uint8_t bad_t[] = {0, 1, 2, 0, 1, 9};
    write_cook_seed("bad-index.bin", 0, tet, 4, bad_t, 2, 0);
    static const int8_t sliver[] = {-127, 0, 0, 127, 0, 0, 0, 1, 0, 0, -1, 0};
    static const uint8_t sliver_t[] = {0, 1, 2, 1, 0, 3};
    write_cook_seed("sliver.bin", 2, sliver, 4, sliver_t, 2, 0);
    if (sphere.vertex_count <= 255) {
        write_cook_seed_float("sphere-float.bin", 0, 0x23, &sphere);
        /* every input is cooked in both layouts: leaves of 1 make a deep wide4 tree, leaves of 16 are
         * more than a wide4 leaf holds (the cooker uses 8) */
        write_cook_seed_float("sphere-float-leaf1.bin", 0, 0x20, &sphere);
        write_cook_seed_float("sphere-float-leaf16-zlib.bin", 4, 0x2F, &sphere);
    }
    write_cook_seed_float("cube-float-q16.bin", 1, 0x23, &cube);
    scene_free(&sphere);
    scene_free(&cube);
    scene_free(&soup);
    return 0;
}
