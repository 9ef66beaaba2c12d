/* test_load.c: the loader on valid, truncated, corrupted and cooked files, with allocation failures and leak
 * counting. */
#include <errno.h>
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
#include "support/counting_alloc.h"
#include "support/test_os.h"

/* ------------------------------------------------------------------ inputs */

typedef struct input {
    const char *name;
    uint8_t *data; /* 64-byte aligned */
    size_t size;
} input;

static const char *vectors_dir(void)
{
    const char *d = getenv("CBVH_FILEFORMAT_DIR");
    return d && *d ? d : CBVH_TEST_FILEFORMAT_DIR;
}

static char *vector_path(const char *name)
{
    static char path[4096];
    snprintf(path, sizeof path, "%s/%s.cbvh", vectors_dir(), name);
    return path;
}

static input load_vector(const char *name)
{
    input in = {name, NULL, 0};
    FILE *fp = fopen(vector_path(name), "rb");
    if (!fp)
        fail_msg("cannot open %s", vector_path(name));
    assert_non_null(in.data = test_aligned_alloc(1 << 16, 64));
    in.size = fread(in.data, 1, 1 << 16, fp);
    assert_true(feof(fp));
    fclose(fp);
    return in;
}

#if CBVH_HAVE_COOKER /* the cooked-file tests; a runtime-only build skips them */
/* A random mesh: positions in a box, random indices (a few triangles come out degenerate and are dropped). */
typedef struct random_mesh {
    float *positions;
    uint32_t *indices, *materials;
    cbvh_mesh mesh;
} random_mesh;

static uint32_t next_random(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (uint32_t)(*s >> 33);
}

static random_mesh make_random_mesh(uint64_t seed, size_t vertices, size_t triangles)
{
    random_mesh m;
    m.positions = malloc(vertices * 3 * sizeof(float));
    m.indices = malloc(triangles * 3 * sizeof(uint32_t));
    m.materials = malloc(triangles * sizeof(uint32_t));
    assert_true(m.positions && m.indices && m.materials);
    for (size_t i = 0; i < vertices * 3; i++)
        m.positions[i] =
            (float)(next_random(&seed) % 200000) * 0.001f - 100.0f + (i % 3 == 0 ? 5000.0f : 0.0f);
    for (size_t t = 0; t < triangles; t++) {
        /* mostly local triangles (as real meshes are), a few spanning the mesh */
        uint32_t base = next_random(&seed) % (uint32_t)vertices;
        for (int k = 0; k < 3; k++)
            m.indices[3 * t + k] = t % 17 == 0 ? next_random(&seed) % (uint32_t)vertices
                                               : (base + next_random(&seed) % 8) % (uint32_t)vertices;
        m.materials[t] = next_random(&seed) % 1000;
    }
    m.mesh = (cbvh_mesh){m.positions, vertices, 0, m.indices, triangles, m.materials};
    return m;
}

static void free_random_mesh(random_mesh *m)
{
    free(m->positions);
    free(m->indices);
    free(m->materials);
}

static input cook_input(const char *name, const random_mesh *m, int compress, cbvh_vertex_format format,
                        int keep_remap)
{
    cbvh_cook_options o;
    cbvh_cook_options_init(&o, sizeof o);
    o.compress_level = compress;
    o.vertex_format = format;
    o.keep_remap = keep_remap;
    void *data = NULL;
    size_t size = 0;
    cbvh_error err;
    cbvh_result r = cbvh_cook(&m->mesh, &o, NULL, &data, &size, NULL, &err);
    if (r != CBVH_OK)
        fail_msg("cook %s: %s", name, err.message);
    input in = {name, NULL, size};
    assert_non_null(in.data = test_aligned_alloc(size, 64));
    memcpy(in.data, data, size);
    cbvh_buffer_free(NULL, data);
    return in;
}
#endif

static const char *const valid_vectors[] = {"good-box-raw",
                                            "good-box-zlib",
                                            "good-box-q16",
                                            "good-remap-u32-materials-u32-zlib",
                                            "good-single-triangle",
                                            "good-w4-box-leaf1",
                                            "good-w4-remap-u32-materials-u32-zlib",
                                            "good-w4-single-triangle"};
#define VALID_VECTOR_COUNT (sizeof valid_vectors / sizeof valid_vectors[0])

/* ------------------------------------------------------------------ comparisons */

static void assert_same_info(const cbvh_file *a, const cbvh_file *b)
{
    cbvh_file_info x, y;
    cbvh_file_get_info(a, &x, sizeof x);
    cbvh_file_get_info(b, &y, sizeof y);
    assert_int_equal(x.format_version, y.format_version);
    assert_int_equal(x.section_count, y.section_count);
    assert_int_equal(x.triangle_count, y.triangle_count);
    assert_int_equal(x.vertex_count, y.vertex_count);
    assert_int_equal(x.node_count, y.node_count);
    assert_int_equal(x.depth, y.depth);
    assert_int_equal(x.max_leaf_size, y.max_leaf_size);
    assert_int_equal(x.has_remap, y.has_remap);
    assert_int_equal(x.has_materials, y.has_materials);
    assert_int_equal(x.vertex_format, y.vertex_format);
    assert_int_equal(x.index_encoding, y.index_encoding);
    assert_int_equal(x.file_size, y.file_size);
    assert_memory_equal(x.bounds_min, y.bounds_min, sizeof x.bounds_min);
    assert_memory_equal(x.bounds_max, y.bounds_max, sizeof x.bounds_max);
    assert_memory_equal(x.grid_origin, y.grid_origin, sizeof x.grid_origin);
    assert_memory_equal(x.grid_scale, y.grid_scale, sizeof x.grid_scale);
    for (uint32_t i = 0; i < x.section_count; i++) {
        cbvh_section_info s, t;
        assert_true(cbvh_file_get_section(a, i, &s) && cbvh_file_get_section(b, i, &t));
        assert_memory_equal(&s, &t, sizeof s);
    }
    /* every id up to the largest original one, and one past it */
    for (uint32_t id = 0; id <= x.triangle_count + 64; id++) {
        float u[3][3], v[3][3];
        int got_a = cbvh_file_get_triangle(a, id, u[0], u[1], u[2]);
        int got_b = cbvh_file_get_triangle(b, id, v[0], v[1], v[2]);
        assert_int_equal(got_a, got_b);
        if (got_a)
            assert_memory_equal(u, v, sizeof u);
        assert_int_equal(cbvh_file_get_material(a, id), cbvh_file_get_material(b, id));
    }
}

/* Every getter on every id: run under valgrind, this proves an accepted file reads nothing out of bounds. */
static void touch_everything(const cbvh_file *f)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    double sum = 0;
    for (uint32_t id = 0; id < info.triangle_count * 2u + 2u; id++) {
        float v[3][3];
        if (cbvh_file_get_triangle(f, id, v[0], v[1], v[2]))
            sum += v[0][0] + v[1][1] + v[2][2];
        sum += cbvh_file_get_material(f, id);
    }
    assert_false(isnan(sum));
}

static cbvh_result open_counted(const uint8_t *data, size_t size, long fail_at, counting_alloc *c,
                                cbvh_file **f, cbvh_error *err)
{
    cbvh_allocator a = counting_allocator(c, fail_at, 0);
    cbvh_result r = cbvh_open_memory(data, size, &a, f, err);
    assert_int_equal(err->code, r);
    if (r != CBVH_OK) {
        assert_null(*f);
        assert_int_equal(c->live, 0);
    }
    return r;
}

/* ------------------------------------------------------------------ tests on the vectors */

static void test_path_and_memory_agree(void **state)
{
    (void)state;
    for (size_t i = 0; i < VALID_VECTOR_COUNT; i++) {
        input in = load_vector(valid_vectors[i]);
        cbvh_file *by_path = NULL, *by_memory = NULL;
        cbvh_error err;
        assert_int_equal(cbvh_open_path(vector_path(in.name), NULL, &by_path, &err), CBVH_OK);
        assert_int_equal(err.code, CBVH_OK);
        assert_string_equal(err.message, "");
        assert_int_equal(cbvh_open_memory(in.data, in.size, NULL, &by_memory, &err), CBVH_OK);
        assert_same_info(by_path, by_memory);
        cbvh_close(by_path);
        cbvh_close(by_memory);
        test_aligned_free(in.data);
    }
}

/* Raw sections are used in place from a 4-byte aligned buffer and copied from any other. */
static void test_unaligned_buffer(void **state)
{
    (void)state;
    input in = load_vector("good-box-raw");
    uint8_t *shifted = malloc(in.size + 8);
    assert_non_null(shifted);
    counting_alloc c;
    cbvh_error err;
    cbvh_file *aligned = NULL;
    assert_int_equal(open_counted(in.data, in.size, -1, &c, &aligned, &err), CBVH_OK);
    size_t in_place_bytes = c.live_bytes;
    cbvh_file_info info;
    cbvh_file_get_info(aligned, &info, sizeof info);
    uint64_t known = 0;
    for (uint32_t i = 0; i < info.section_count; i++) {
        cbvh_section_info s;
        cbvh_file_get_section(aligned, i, &s);
        known += s.size;
    }
    for (size_t shift = 1; shift < 8; shift++) {
        memcpy(shifted + shift, in.data, in.size);
        counting_alloc d;
        cbvh_file *f = NULL;
        assert_int_equal(open_counted(shifted + shift, in.size, -1, &d, &f, &err), CBVH_OK);
        if (shift % 4 != 0)
            assert_true(d.live_bytes >= in_place_bytes + known); /* copies of every known section */
        else
            assert_int_equal(d.live_bytes, in_place_bytes);
        assert_same_info(aligned, f);
        cbvh_close(f);
        assert_int_equal(d.live, 0);
    }
    cbvh_close(aligned);
    assert_int_equal(c.live, 0);
    free(shifted);
    test_aligned_free(in.data);
}

/* Every prefix of a valid file is corrupt, cleanly, without leaks. */
static void check_truncations(const input *in, size_t step)
{
    for (size_t n = 0; n < in->size; n += (n < 512 ? 1 : step)) {
        uint8_t *copy = malloc(n ? n : 1);
        assert_non_null(copy);
        memcpy(copy, in->data, n); /* an exact-size buffer, so valgrind sees any read past n */
        counting_alloc c;
        cbvh_file *f = NULL;
        cbvh_error err;
        cbvh_result r = open_counted(copy, n, -1, &c, &f, &err);
        if (r != CBVH_ERROR_CORRUPT)
            fail_msg("%s cut to %zu bytes: %s (%s)", in->name, n, cbvh_result_string(r), err.message);
        free(copy);
    }
}

static void test_truncations(void **state)
{
    (void)state;
    for (size_t i = 0; i < VALID_VECTOR_COUNT; i++) {
        input in = load_vector(valid_vectors[i]);
        check_truncations(&in, 1);
        test_aligned_free(in.data);
    }
}

/* Every flipped byte is caught by a CRC, or by the version check for the version field. */
static void test_flipped_bytes(void **state)
{
    (void)state;
    input in = load_vector("good-box-raw");
    for (size_t i = 0; i < in.size; i++) {
        for (int bit = 0; bit < 8; bit += 7) {
            in.data[i] ^= (uint8_t)(1u << bit);
            counting_alloc c;
            cbvh_file *f = NULL;
            cbvh_error err;
            cbvh_result r = open_counted(in.data, in.size, -1, &c, &f, &err);
            cbvh_result want =
                i >= 8 && i < 12 && (i > 8 || bit > 0) ? CBVH_ERROR_UNSUPPORTED : CBVH_ERROR_CORRUPT;
            if (r != want)
                fail_msg("byte %zu bit %d: %s (%s)", i, bit, cbvh_result_string(r), err.message);
            in.data[i] ^= (uint8_t)(1u << bit);
        }
    }
    test_aligned_free(in.data);
}

/* Recomputes every CRC of a file, so a change reaches the structural checks behind them. */
static void repair_crcs(uint8_t *d, size_t size)
{
    uint32_t count;
    memcpy(&count, d + 24, 4);
    if (count > 16 || 128 + (size_t)count * 40 > size)
        count = 0;
    for (uint32_t i = 0; i < count; i++) {
        uint8_t *e = d + 128 + 40 * i;
        uint64_t offset, stored;
        memcpy(&offset, e + 8, 8);
        memcpy(&stored, e + 16, 8);
        if (offset <= size && stored <= size - offset) {
            uint32_t crc = (uint32_t)crc32(0, d + offset, (uInt)stored);
            memcpy(e + 32, &crc, 4);
        }
    }
    uint32_t crc = (uint32_t)crc32(0, d + 128, (uInt)count * 40);
    memcpy(d + 28, &crc, 4);
    crc = (uint32_t)crc32(0, d, 124);
    memcpy(d + 124, &crc, 4);
}

/* Changed bytes behind repaired CRCs: whatever the loader accepts must be safe to read everywhere. */
static void check_changes(const input *in, size_t from)
{
    static const uint8_t xors[] = {0x01, 0x02, 0x10, 0x80, 0xFF};
    uint8_t *copy = malloc(in->size);
    assert_non_null(copy);
    for (size_t i = from; i < in->size; i++) {
        for (size_t k = 0; k < sizeof xors; k++) {
            memcpy(copy, in->data, in->size);
            copy[i] ^= xors[k];
            repair_crcs(copy, in->size);
            counting_alloc c;
            cbvh_file *f = NULL;
            cbvh_error err;
            cbvh_result r = open_counted(copy, in->size, -1, &c, &f, &err);
            assert_true(r == CBVH_OK || r == CBVH_ERROR_CORRUPT || r == CBVH_ERROR_UNSUPPORTED);
            assert_true(strlen(err.message) > 0 || r == CBVH_OK);
            if (r == CBVH_OK) {
                touch_everything(f);
                cbvh_close(f);
                assert_int_equal(c.live, 0);
            }
        }
    }
    free(copy);
}

static void test_changes_behind_crcs(void **state)
{
    (void)state;
    static const char *const names[] = {"good-box-raw", "good-remap-u32-materials-u32-zlib",
                                        "good-box-delta16", "good-w4-box-leaf1",
                                        "good-w4-remap-u32-materials-u32-zlib"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        input in = load_vector(names[i]);
        check_changes(&in, 12); /* everything after the magic and the version */
        test_aligned_free(in.data);
    }
}

/* Failing allocation N, for N = 0, 1, 2 ... until the open succeeds: each failure is clean,
 * and the file that finally opens answers everything. */
static void check_allocation_failures(const uint8_t *data, size_t size, const char *path)
{
    /* at least the handle is allocated */
    assert_true(counting_open_failures(data, size, path, touch_everything) >= 1);
}

static void test_allocation_failures(void **state)
{
    (void)state;
    for (size_t i = 0; i < VALID_VECTOR_COUNT; i++) {
        input in = load_vector(valid_vectors[i]);
        check_allocation_failures(in.data, in.size, NULL);
        check_allocation_failures(NULL, 0, vector_path(in.name));
        uint8_t *shifted = malloc(in.size + 1);
        assert_non_null(shifted);
        memcpy(shifted + 1, in.data, in.size);
        check_allocation_failures(shifted + 1, in.size, NULL);
        free(shifted);
        test_aligned_free(in.data);
    }
}

/* cbvh_file_get_info writes only the bytes the caller's size covers (a program built against an older
 * cbvh.h has a shorter struct) and refuses sizes out of range without writing anything. */
/* The run-time version is the header's, as a number ordered like versions and as the string. */
static void test_version(void **state)
{
    (void)state;
    unsigned major, minor, patch;
    assert_int_equal(sscanf(cbvh_version_string(), "%u.%u.%u", &major, &minor, &patch), 3);
    assert_int_equal(cbvh_version(), major * 10000u + minor * 100u + patch);
    assert_int_equal(cbvh_version(), CBVH_VERSION_NUMBER);
    assert_string_equal(cbvh_version_string(), CBVH_VERSION_STRING);
    assert_int_equal(major, CBVH_VERSION_MAJOR);
    assert_int_equal(minor, CBVH_VERSION_MINOR);
    assert_int_equal(patch, CBVH_VERSION_PATCH);
}

static void test_info_struct_size(void **state)
{
    (void)state;
    input in = load_vector("good-box-raw");
    cbvh_file *f;
    assert_int_equal(cbvh_open_memory(in.data, in.size, NULL, &f, NULL), CBVH_OK);
    cbvh_file_info whole, part;
    assert_int_equal(cbvh_file_get_info(f, &whole, sizeof whole), CBVH_OK);
    assert_int_equal(whole.struct_size, sizeof whole);
    assert_true(whole.triangle_count > 0 && whole.node_count > 0);

    const size_t short_size = offsetof(cbvh_file_info, depth); /* through node_count */
    memset(&part, 0xA5, sizeof part);
    assert_int_equal(cbvh_file_get_info(f, &part, short_size), CBVH_OK);
    assert_int_equal(part.struct_size, short_size);
    assert_int_equal(part.node_count, whole.node_count);
    assert_memory_equal((const uint8_t *)&part + sizeof part.struct_size,
                        (const uint8_t *)&whole + sizeof whole.struct_size,
                        short_size - sizeof whole.struct_size);
    for (size_t i = short_size; i < sizeof part; i++)
        if (((const uint8_t *)&part)[i] != 0xA5)
            fail_msg("byte %zu past struct_size %zu was written", i, short_size);

    /* A program built before the layout field. */
    memset(&part, 0xA5, sizeof part);
    assert_int_equal(cbvh_file_get_info(f, &part, offsetof(cbvh_file_info, layout)), CBVH_OK);
    assert_int_equal(part.triangle_count, whole.triangle_count);
    assert_true(part.grid_scale[2] == whole.grid_scale[2]);
    for (size_t i = offsetof(cbvh_file_info, layout); i < sizeof part; i++)
        if (((const uint8_t *)&part)[i] != 0xA5)
            fail_msg("byte %zu past struct_size %zu was written", i, offsetof(cbvh_file_info, layout));

    const size_t bad[] = {0,
                          1,
                          sizeof(size_t),
                          offsetof(cbvh_file_info, format_version) + 3,
                          sizeof part + 1,
                          sizeof part + 4096};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        memset(&part, 0xA5, sizeof part);
        assert_int_equal(cbvh_file_get_info(f, &part, bad[k]), CBVH_ERROR_INVALID_ARGUMENT);
        for (size_t i = 0; i < sizeof part; i++)
            if (((const uint8_t *)&part)[i] != 0xA5)
                fail_msg("struct_size %zu refused, yet byte %zu was written", bad[k], i);
    }
    assert_int_equal(cbvh_file_get_info(f, NULL, sizeof whole), CBVH_ERROR_INVALID_ARGUMENT);
    cbvh_close(f);
    free(in.data);
}

static void test_arguments(void **state)
{
    (void)state;
    input in = load_vector("good-box-raw");
    cbvh_file *f = (cbvh_file *)&in; /* must be overwritten with NULL on failure */
    cbvh_error err;
    assert_int_equal(cbvh_open_memory(in.data, in.size, NULL, NULL, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_open_memory(NULL, 10, NULL, &f, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_null(f);
    f = (cbvh_file *)&in;
    assert_int_equal(cbvh_open_path(NULL, NULL, &f, &err), CBVH_ERROR_INVALID_ARGUMENT);
    assert_null(f);
    assert_int_equal(cbvh_open_path(vector_path("good-box-raw"), NULL, NULL, NULL),
                     CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(cbvh_open_memory(NULL, 0, NULL, &f, &err), CBVH_ERROR_CORRUPT);
    assert_null(f);
    assert_int_equal(cbvh_open_memory(in.data, in.size, NULL, &f, NULL), CBVH_OK); /* err may be NULL */
    cbvh_close(f);
    cbvh_close(NULL);
    cbvh_file_info info;
    memset(&info, 0xA5, sizeof info);
    assert_int_equal(cbvh_file_get_info(NULL, &info, sizeof info), CBVH_ERROR_INVALID_ARGUMENT);
    assert_int_equal(info.struct_size, sizeof info);
    assert_int_equal(info.triangle_count, 0);
    float v[3][3];
    assert_int_equal(cbvh_file_get_triangle(NULL, 0, v[0], v[1], v[2]), 0);
    assert_int_equal(cbvh_file_get_material(NULL, 0), 0);
    assert_int_equal(cbvh_file_get_section(NULL, 0, NULL), 0);
    test_aligned_free(in.data);
}

/* `path` holds exactly data[0..size) (size 0: an empty file). */
static void write_whole_file(const char *path, const void *data, size_t size)
{
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    if (size > 0)
        assert_int_equal(fwrite(data, 1, size, fp), size);
    assert_int_equal(fclose(fp), 0);
}

/* Both ways of opening a path report the same errors. */
static void test_path_errors(void **state)
{
    (void)state;
    cbvh_result (*const opens[])(const char *, const cbvh_allocator *, cbvh_file **,
                                 cbvh_error *) = {cbvh_open_path, cbvh_open_path_read};
    char dir[200];
    test_temp_dir(dir, sizeof dir, "cbvh-test-load");
    char path[256];
    snprintf(path, sizeof path, "%s/empty.cbvh", dir);
    write_whole_file(path, NULL, 0);
    char missing[256];
    snprintf(missing, sizeof missing, "%s/missing.cbvh", dir);
    for (size_t i = 0; i < sizeof opens / sizeof opens[0]; i++) {
        cbvh_file *f = NULL;
        cbvh_error err;
        assert_int_equal(opens[i](missing, NULL, &f, &err), CBVH_ERROR_IO);
        assert_non_null(strstr(err.message, "missing.cbvh"));
        assert_int_equal(opens[i](dir, NULL, &f, &err), CBVH_ERROR_IO);
        assert_non_null(strstr(err.message, "not a regular file"));
        assert_int_equal(opens[i](path, NULL, &f, &err), CBVH_ERROR_CORRUPT);
        assert_non_null(strstr(err.message, "empty"));
        assert_null(f);
        assert_int_equal(opens[i](NULL, NULL, &f, &err), CBVH_ERROR_INVALID_ARGUMENT);
    }
    unlink(path);
    rmdir(dir);
}

/* Closest hits of a grid of rays along each axis through the bounds: the same on a and b. */
static void assert_same_hits(const cbvh_file *a, const cbvh_file *b)
{
    cbvh_file_info info;
    cbvh_file_get_info(a, &info, sizeof info);
    uint32_t hits = 0;
    for (int axis = 0; axis < 3; axis++) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        for (int i = 0; i <= 16; i++) {
            for (int j = 0; j <= 16; j++) {
                cbvh_ray ray = {{0, 0, 0}, 0.0f, {0, 0, 0}, INFINITY};
                ray.org[u] =
                    info.bounds_min[u] + (info.bounds_max[u] - info.bounds_min[u]) * (float)i / 16.0f;
                ray.org[v] =
                    info.bounds_min[v] + (info.bounds_max[v] - info.bounds_min[v]) * (float)j / 16.0f;
                ray.org[axis] = info.bounds_min[axis] - 1.0f;
                ray.dir[axis] = 1.0f;
                cbvh_hit x, y;
                int hit_a = cbvh_raycast(a, &ray, CBVH_TRAVERSAL_SORTED, &x, NULL);
                assert_int_equal(hit_a, cbvh_raycast(b, &ray, CBVH_TRAVERSAL_SORTED, &y, NULL));
                if (hit_a) {
                    assert_int_equal(x.tri, y.tri);
                    assert_memory_equal(&x.t, &y.t, sizeof x.t);
                    hits++;
                }
            }
        }
    }
    assert_true(hits > 0);
}

/* cbvh_open_path_read copies the file: truncating it after the open (which would make a mapping fault)
 * changes nothing, and the copy is the file's, freed at close. */
static void test_read_mode_survives_truncation(void **state)
{
    (void)state;
    char dir[200];
    test_temp_dir(dir, sizeof dir, "cbvh-test-load");
    char path[256];
    snprintf(path, sizeof path, "%s/hot.cbvh", dir);
    for (size_t i = 0; i < VALID_VECTOR_COUNT; i++) {
        input in = load_vector(valid_vectors[i]);
        write_whole_file(path, in.data, in.size);
        counting_alloc c;
        cbvh_allocator a = counting_allocator(&c, -1, 0);
        cbvh_file *f = NULL, *reference = NULL;
        cbvh_error err;
        assert_int_equal(cbvh_open_path_read(path, &a, &f, &err), CBVH_OK);
        assert_true(c.live_bytes >= in.size); /* the whole file is in memory */
        write_whole_file(path, NULL, 0);      /* truncated to 0 bytes, as `cp` over it would start */
        assert_int_equal(cbvh_open_memory(in.data, in.size, NULL, &reference, &err), CBVH_OK);
        assert_same_info(f, reference);
        assert_same_hits(f, reference);
        unlink(path); /* and removed */
        assert_same_hits(f, reference);
        cbvh_close(f);
        assert_int_equal(c.live, 0);
        cbvh_close(reference);
        test_aligned_free(in.data);
    }
    rmdir(dir);
}

/* Every allocation of a read-mode open failed in turn: a clean out-of-memory error, nothing leaked. */
static void test_read_mode_allocation_failures(void **state)
{
    (void)state;
    const char *path = vector_path("good-remap-u32-materials-u32-zlib");
    long n = 0;
    for (;; n++) {
        counting_alloc c;
        cbvh_allocator a = counting_allocator(&c, n, 0);
        cbvh_file *f = NULL;
        cbvh_error err;
        cbvh_result r = cbvh_open_path_read(path, &a, &f, &err);
        if (r == CBVH_OK) {
            cbvh_close(f);
            assert_int_equal(c.live, 0);
            break;
        }
        assert_int_equal(r, CBVH_ERROR_OUT_OF_MEMORY);
        assert_null(f);
        assert_int_equal(c.live, 0);
    }
    assert_true(n >= 2); /* the handle and the file's bytes at least */
}

/* ------------------------------------------------------------------ tests on cooked files */
#if CBVH_HAVE_COOKER
/* Mappings of this process that carry the huge-page advice ("hg" among their VmFlags in
 * /proc/self/smaps), or -1 where the system does not say (not Linux, or a kernel without transparent huge
 * pages). */
static long advised_mappings(void)
{
    FILE *fp = fopen("/proc/self/smaps", "r");
    if (!fp || access("/sys/kernel/mm/transparent_hugepage/enabled", R_OK) != 0) {
        if (fp)
            fclose(fp);
        return -1;
    }
    char line[512];
    long n = 0;
    while (fgets(line, sizeof line, fp))
        if (strncmp(line, "VmFlags:", 8) == 0 && strstr(line, " hg"))
            n++;
    fclose(fp);
    return n;
}

/* A cooked file of the mesh, more than `least` bytes, written as NAME.cbvh in a new temporary folder. */
typedef struct {
    input in;
    char dir[200];
    char path[256];
} temp_cooked;

static void temp_cooked_write(temp_cooked *t, const random_mesh *m, const char *name, size_t least)
{
    t->in = cook_input(name, m, 0, CBVH_VERTEX_FLOAT32, 1);
    assert_true(t->in.size > least);
    test_temp_dir(t->dir, sizeof t->dir, "cbvh-test-load");
    snprintf(t->path, sizeof t->path, "%s/%s.cbvh", t->dir, name);
    write_whole_file(t->path, t->in.data, t->in.size);
}

static void temp_cooked_remove(temp_cooked *t)
{
    unlink(t->path);
    rmdir(t->dir);
    test_aligned_free(t->in.data);
}

/* The mappings of the file whose path ends with `path` (in /proc/self/smaps, which names it by its full path,
 * TMPDIR's links resolved): how many, the first one's start, whether it carries the huge-page advice ("hg"
 * among its VmFlags) and whether an inaccessible anonymous mapping ("---p", no path) touches it on either
 * side (what would be left of a reservation around it). Returns 0, or -1 where the system does not say (not
 * Linux). */
typedef struct {
    long count;
    uintptr_t start;
    int advised, reserved_beside;
} file_mapping;

static int mapping_of(const char *path, file_mapping *out)
{
    FILE *fp = fopen("/proc/self/smaps", "r");
    if (!fp)
        return -1;
    memset(out, 0, sizeof *out);
    char line[512];
    int in_path = 0, after_path = 0, previous_reserved = 0;
    unsigned long previous_hi = 0, path_hi = 0;
    while (fgets(line, sizeof line, fp)) {
        unsigned long lo, hi;
        char perms[8];
        int name_at = 0;
        if (sscanf(line, "%lx-%lx %7s %*s %*s %*s %n", &lo, &hi, perms, &name_at) >= 3) {
            line[strcspn(line, "\n")] = '\0';
            const size_t len = strlen(line), plen = strlen(path);
            const int reserved = strcmp(perms, "---p") == 0 && (name_at == 0 || line[name_at] == '\0');
            in_path = len >= plen && strcmp(line + len - plen, path) == 0;
            if (in_path) {
                if (out->count++ == 0)
                    out->start = (uintptr_t)lo;
                out->reserved_beside |= previous_reserved && previous_hi == lo;
                path_hi = hi;
            } else if (after_path) {
                out->reserved_beside |= reserved && lo == path_hi;
            }
            after_path = in_path;
            previous_reserved = reserved;
            previous_hi = hi;
        } else if (in_path && strncmp(line, "VmFlags:", 8) == 0 && strstr(line, " hg")) {
            out->advised = 1;
        }
    }
    fclose(fp);
    return 0;
}

/* On Linux a mapped file of 2 MiB or more (cbvh_open_path) lies on a 2 MiB boundary with the huge-page advice
 * (the kernel then maps whole 2 MiB pages of it where its page cache holds them), nothing of the room
 * reserved to place it is left beside it, and nothing of it after cbvh_close; its answers are the copy's. */
static void test_mapping_on_large_pages(void **state)
{
    (void)state;
    random_mesh m = make_random_mesh(23, 100000, 200000);
    temp_cooked t;
    temp_cooked_write(&t, &m, "mapped", (size_t)2 << 20);
    cbvh_file *mapped = NULL, *copy = NULL;
    cbvh_error err;
    assert_int_equal(cbvh_open_memory(t.in.data, t.in.size, NULL, &copy, &err), CBVH_OK);
    const char *name = strrchr(t.path, '/'); /* "/mapped.cbvh" ... */
    while (name > t.path && name[-1] != '/') /* ... from the folder's name on: unique to this run */
        name--;
    assert_int_equal(cbvh_open_path(t.path, NULL, &mapped, &err), CBVH_OK);
    file_mapping open, closed;
    const int seen = mapping_of(name, &open);
    assert_same_hits(mapped, copy);
    cbvh_close(mapped);
    if (seen == 0) {
#if defined(__linux__)
        assert_int_equal(open.count, 1);
        assert_int_equal(open.start % ((uintptr_t)2 << 20), 0);
        if (access("/sys/kernel/mm/transparent_hugepage/enabled", R_OK) == 0)
            assert_true(open.advised);
        assert_false(open.reserved_beside);
        assert_int_equal(mapping_of(name, &closed), 0);
        assert_int_equal(closed.count, 0);
#endif
    } else {
        printf("no mappings to see on this system: only the answers checked\n");
    }
    cbvh_close(copy);
    temp_cooked_remove(&t);
    free_random_mesh(&m);
}

/* A file of several MiB read into memory (cbvh_open_path_read), its expanded triangles and the sections
 * of a compressed one, inflated at open, all from the default allocator, ask for 2 MiB pages where the system
 * has the advice (Linux); answers as the mapped file's. A caller's allocator gets no advice. (After close the
 * advice may stay on the C library's heap, which keeps freed memory: harmless, and not checked.) */
static void test_read_mode_large_pages(void **state)
{
    (void)state;
    random_mesh m = make_random_mesh(17, 150000, 300000);
    temp_cooked t;
    temp_cooked_write(&t, &m, "large", (size_t)6 << 20);
    const char *path = t.path;
    const long before = advised_mappings();
    cbvh_file *mapped = NULL, *read = NULL, *own = NULL;
    cbvh_error err;
    assert_int_equal(cbvh_open_path(path, NULL, &mapped, &err), CBVH_OK);
    assert_int_equal(cbvh_open_path_read(path, NULL, &read, &err), CBVH_OK);
    const long after_read = advised_mappings();
    assert_int_equal(cbvh_file_expand_triangles(read, &err), CBVH_OK);
    const long after_expand = advised_mappings();
    counting_alloc c;
    cbvh_allocator a = counting_allocator(&c, -1, 0);
    assert_int_equal(cbvh_open_path_read(path, &a, &own, &err), CBVH_OK);
    const long with_own = advised_mappings();
    /* a compressed file's sections, inflated at open */
    input zipped = cook_input("large-zlib", &m, 6, CBVH_VERTEX_FLOAT32, 1);
    cbvh_file *inflated = NULL;
    assert_int_equal(cbvh_open_memory(zipped.data, zipped.size, NULL, &inflated, &err), CBVH_OK);
    const long after_inflate = advised_mappings();
    assert_same_hits(mapped, read);
    assert_same_hits(mapped, own);
    assert_same_hits(mapped, inflated);
    if (before >= 0) {
#if defined(__linux__)
        cbvh_file_info info;
        cbvh_file_get_info(read, &info, sizeof info);
        assert_true(after_read > before);
        /* a build without SIMD kernels expands nothing (cbvh_file_expand_triangles) */
        assert_true(info.expanded_bytes > 0 ? after_expand > after_read : after_expand == after_read);
        assert_int_equal(with_own, after_expand);
        assert_true(after_inflate > with_own);
#endif
    } else {
        printf("no huge-page advice to see on this system: only the answers checked\n");
    }
    cbvh_close(inflated);
    cbvh_close(own);
    cbvh_close(read);
    cbvh_close(mapped);
    test_aligned_free(zipped.data);
    temp_cooked_remove(&t);
    free_random_mesh(&m);
}

static int degenerate_input(const random_mesh *m, size_t t)
{
    const uint32_t *i = m->indices + 3 * t;
    return i[0] == i[1] || i[1] == i[2] || i[0] == i[2];
}

/* Exact for float vertices; within a grid step (and an ulp of the coordinate) for 16-bit ones. */
static int near(float got, float want, float scale)
{
    return fabsf(got - want) <= scale + 2.0f * (nextafterf(fabsf(want), INFINITY) - fabsf(want));
}

static int same_as_input(const random_mesh *m, size_t t, float v[3][3], const cbvh_file_info *info)
{
    for (int k = 0; k < 3; k++)
        for (int a = 0; a < 3; a++) {
            float want = m->positions[3 * m->indices[3 * t + k] + a];
            float scale = info->vertex_format == CBVH_VERTEX_FLOAT32 ? 0.0f : info->grid_scale[a];
            if (!near(v[k][a], want, scale))
                return 0;
        }
    return 1;
}

/* Cooked keeping original ids, triangle id t is input triangle t (degenerate ones, dropped, are absent);
 * the cooker may leave REMAP out when the cooked order is the input order. */
static void check_round_trip(const cbvh_file *f, const random_mesh *m)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    size_t kept = 0;
    uint32_t first_material = CBVH_NO_HIT;
    int all_equal = 1;
    for (size_t t = 0; t < m->mesh.triangle_count; t++) {
        float v[3][3];
        int got = cbvh_file_get_triangle(f, (uint32_t)t, v[0], v[1], v[2]);
        if (degenerate_input(m, t)) {
            assert_int_equal(got, 0);
            continue;
        }
        kept++;
        assert_int_equal(got, 1);
        if (!same_as_input(m, t, v, &info))
            fail_msg("triangle %zu differs from the input", t);
        /* MATERIALS is left out when all kept ids are 0; the reader then reports 0 */
        assert_int_equal(cbvh_file_get_material(f, (uint32_t)t), info.has_materials ? m->materials[t] : 0);
        if (first_material == CBVH_NO_HIT)
            first_material = m->materials[t];
        all_equal &= m->materials[t] == first_material;
    }
    assert_int_equal(info.triangle_count, kept);
    /* left out only when every id is 0; equal ids are stored once */
    assert_int_equal(info.has_materials, !(all_equal && first_material == 0));
}

/* A triangle as 9 coordinates and its material, ordered bitwise, to compare two sets of triangles. */
typedef struct record {
    float v[9];
    uint32_t material;
} record;

static int compare_records(const void *a, const void *b)
{
    return memcmp(a, b, sizeof(record));
}

/* Without REMAP, the ids are cooked ids: the triangles are the kept input triangles in some order. */
static void check_cooked_ids(const cbvh_file *f, const random_mesh *m)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    assert_int_equal(info.has_remap, 0);
    assert_int_equal(info.vertex_format, CBVH_VERTEX_FLOAT32); /* exact comparison */
    record *got = calloc(info.triangle_count, sizeof *got);
    record *want = calloc(m->mesh.triangle_count, sizeof *want);
    assert_true(got && want);
    for (uint32_t id = 0; id < info.triangle_count; id++) {
        float v[3][3];
        assert_int_equal(cbvh_file_get_triangle(f, id, v[0], v[1], v[2]), 1);
        memcpy(got[id].v, v, sizeof v);
        got[id].material = cbvh_file_get_material(f, id);
    }
    size_t kept = 0;
    for (size_t t = 0; t < m->mesh.triangle_count; t++) {
        if (degenerate_input(m, t))
            continue;
        for (int k = 0; k < 9; k++)
            want[kept].v[k] = m->positions[3 * m->indices[3 * t + k / 3] + k % 3];
        want[kept++].material = m->materials[t];
    }
    assert_int_equal(kept, info.triangle_count);
    qsort(got, kept, sizeof *got, compare_records);
    qsort(want, kept, sizeof *want, compare_records);
    assert_memory_equal(got, want, kept * sizeof *got);
    free(got);
    free(want);
}

static void test_cooked_files(void **state)
{
    (void)state;
    random_mesh m = make_random_mesh(42, 3000, 5000);
    for (int keep_remap = 1; keep_remap >= 0; keep_remap--)
        for (int compress = 0; compress <= 6; compress += 6)
            for (int format = 0; format <= keep_remap; format++) {
                input in = cook_input("random", &m, compress, (cbvh_vertex_format)format, keep_remap);
                counting_alloc c;
                cbvh_file *f = NULL;
                cbvh_error err;
                if (open_counted(in.data, in.size, -1, &c, &f, &err) != CBVH_OK)
                    fail_msg("cooked file (compress %d, format %d, remap %d): %s", compress, format,
                             keep_remap, err.message);
                if (keep_remap)
                    check_round_trip(f, &m);
                else
                    check_cooked_ids(f, &m);
                cbvh_close(f);
                assert_int_equal(c.live, 0);
                test_aligned_free(in.data);
            }
    free_random_mesh(&m);
}

/* Meshes of many sizes (one triangle to a few thousand, u16 and u32 indices), through a file on disk. */
static void test_cooked_sizes_by_path(void **state)
{
    (void)state;
    char dir[200];
    test_temp_dir(dir, sizeof dir, "cbvh-test-load");
    char path[256];
    snprintf(path, sizeof path, "%s/mesh.cbvh", dir);
    static const size_t sizes[][2] = {{3, 1}, {4, 2}, {10, 7}, {100, 300}, {100000, 60000}};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        random_mesh m = make_random_mesh(1000 + i, sizes[i][0], sizes[i][1]);
        if (sizes[i][1] <= 2) /* no degenerate triangle: all have distinct corners */
            for (size_t k = 0; k < 3 * sizes[i][1]; k++)
                m.indices[k] = (uint32_t)(k % 3 + k / 3);
        cbvh_cook_options o;
        cbvh_cook_options_init(&o, sizeof o);
        o.compress_level = (int)(i % 2) * 9;
        cbvh_error err;
        if (cbvh_cook_to_path(&m.mesh, &o, NULL, path, NULL, &err) != CBVH_OK)
            fail_msg("cook: %s", err.message);
        cbvh_file *f = NULL;
        if (cbvh_open_path(path, NULL, &f, &err) != CBVH_OK)
            fail_msg("open %zu triangles: %s", sizes[i][1], err.message);
        check_round_trip(f, &m);
        cbvh_close(f);
        free_random_mesh(&m);
    }
    unlink(path);
    rmdir(dir);
}

static void test_cooked_truncations_and_allocations(void **state)
{
    (void)state;
    random_mesh m = make_random_mesh(7, 400, 600);
    for (int compress = 0; compress <= 6; compress += 6) {
        input in = cook_input("small cooked", &m, compress, CBVH_VERTEX_FLOAT32, 1);
        check_truncations(&in, 61);
        check_allocation_failures(in.data, in.size, NULL);
        test_aligned_free(in.data);
    }
    free_random_mesh(&m);
}

#else
static void test_cooked_files_need_the_cooker(void **state)
{
    (void)state;
    print_message("this runtime-only build (no cooker) cannot cook files: the cooked-file tests skip\n");
    skip();
}
#endif

/* cbvh.h's contracts: a failed open leaves *out_file NULL (whatever it held), and has_materials tells a
 * file without materials (cbvh_file_get_material answers 0) from one whose ids include 0. */
static void test_open_and_material_contracts(void **state)
{
    (void)state;
    static int sentinel;
    cbvh_file *f = (cbvh_file *)(void *)&sentinel;
    cbvh_error err;
    assert_int_not_equal(cbvh_open_path(vector_path("bad-magic"), NULL, &f, &err), CBVH_OK);
    assert_null(f);
    input bad = load_vector("bad-magic");
    f = (cbvh_file *)(void *)&sentinel;
    assert_int_not_equal(cbvh_open_memory(bad.data, bad.size, NULL, &f, &err), CBVH_OK);
    assert_null(f);
    test_aligned_free(bad.data);

    cbvh_file_info info;
    assert_int_equal(cbvh_open_path(vector_path("good-box-raw"), NULL, &f, &err), CBVH_OK);
    assert_int_equal(cbvh_file_get_info(f, &info, sizeof info), CBVH_OK);
    assert_int_equal(info.has_materials, 0);
    assert_int_equal(cbvh_file_get_material(f, 0), 0);
    cbvh_close(f);
    assert_int_equal(cbvh_open_path(vector_path("good-remap-materials"), NULL, &f, &err), CBVH_OK);
    assert_int_equal(cbvh_file_get_info(f, &info, sizeof info), CBVH_OK);
    assert_int_equal(info.has_materials, 1);
    cbvh_close(f);
    cbvh_close(NULL);
}

/* cbvh.h's one rule for returns: an invalid query is a miss (or a count of 0) for the plain forms and
 * CBVH_ERROR_INVALID_ARGUMENT for the _with forms; a valid one agrees between them. */
static void test_invalid_query_rule(void **state)
{
    (void)state;
    cbvh_file *f;
    cbvh_error err;
    assert_int_equal(cbvh_open_path(vector_path("good-box-raw"), NULL, &f, &err), CBVH_OK);
    const float nan = (float)NAN;
    const cbvh_ray invalid[] = {
        {{0, 0, -5}, 0, {0, 0, nan}, INFINITY}, /* NaN direction */
        {{0, 0, -5}, 0, {0, 0, 0}, INFINITY},   /* zero direction */
        {{0, 0, -5}, 2, {0, 0, 1}, 1},          /* tmin > tmax */
    };
    for (size_t k = 0; k < sizeof invalid / sizeof *invalid; k++) {
        cbvh_hit hit;
        assert_int_equal(cbvh_raycast(f, &invalid[k], CBVH_TRAVERSAL_SORTED, &hit, NULL), 0);
        assert_int_equal(hit.tri, CBVH_NO_HIT);
        assert_int_equal(cbvh_occluded(f, &invalid[k], CBVH_TRAVERSAL_SORTED, NULL), 0);
        cbvh_hit_record with_hit;
        assert_int_equal(cbvh_raycast_with(f, &invalid[k], NULL, &with_hit, NULL),
                         CBVH_ERROR_INVALID_ARGUMENT);
        assert_int_equal(with_hit.tri, CBVH_NO_HIT);
        int occluded = 1;
        assert_int_equal(cbvh_occluded_with(f, &invalid[k], NULL, &occluded, NULL),
                         CBVH_ERROR_INVALID_ARGUMENT);
    }
    const float center[3] = {0, 0, 0};
    assert_int_equal(cbvh_overlap_sphere(f, center, nan, NULL, NULL, NULL, 0), 0);
    cbvh_close(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_open_and_material_contracts),
        cmocka_unit_test(test_invalid_query_rule),
        cmocka_unit_test(test_path_and_memory_agree),
        cmocka_unit_test(test_unaligned_buffer),
        cmocka_unit_test(test_truncations),
        cmocka_unit_test(test_flipped_bytes),
        cmocka_unit_test(test_changes_behind_crcs),
        cmocka_unit_test(test_allocation_failures),
        cmocka_unit_test(test_arguments),
        cmocka_unit_test(test_version),
        cmocka_unit_test(test_info_struct_size),
        cmocka_unit_test(test_path_errors),
        cmocka_unit_test(test_read_mode_survives_truncation),
        cmocka_unit_test(test_read_mode_allocation_failures),
#if CBVH_HAVE_COOKER
        cmocka_unit_test(test_cooked_files),
        cmocka_unit_test(test_cooked_sizes_by_path),
        cmocka_unit_test(test_cooked_truncations_and_allocations),
        cmocka_unit_test(test_read_mode_large_pages),
        cmocka_unit_test(test_mapping_on_large_pages),
#else
        cmocka_unit_test(test_cooked_files_need_the_cooker),
#endif
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
