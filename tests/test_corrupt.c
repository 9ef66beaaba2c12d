/* test_corrupt.c: exhaustive structured corruption of small cooked files in both node layouts: every
 * truncation, every byte of header, table and nodes changed, sections moved, overlapped and pointed past the
 * end. */
#include <math.h>
#include <setjmp.h>
#include <signal.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "cbvh.h"
#include "fuzz/file_edit.h"
#include "fuzz/fuzz_support.h"
#include "fuzz/le_bytes.h"
#include "support/scene_gen.h"
#include "support/test_os.h"

enum {
    HDR_VERSION = 8,
    HDR_COMPAT = 16,
    HDR_INCOMPAT = 20,
    HDR_SECTION_COUNT = 24,
    HDR_RESERVED = 112,
    TABLE = 128,
    ENTRY = 40,
    E_TYPE = 0,
    E_CODEC = 4,
    E_OFFSET = 8,
    E_STORED = 16,
    E_SIZE = 24,
    E_ENCODING = 36
};

/* A small valid file of each kind, cooked once: raw, zlib and quantized, in each node layout. */
typedef struct sample {
    const char *name;
    uint8_t *bytes;
    size_t size;
} sample;
enum { SAMPLE_COUNT = 6 };
static sample samples[SAMPLE_COUNT];

/* Outcome counts, printed at the end for the robustness report. */
typedef struct tally {
    size_t tried, corrupt, unsupported, other_error, opened;
} tally;
static tally totals;

/* A watchdog turns a hang into a failure; Windows has no alarm(), so there a hang shows as the run's timeout.
 */
#ifdef SIGALRM
#define WATCHDOG(seconds) alarm(seconds)
static void on_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "test_corrupt: a corrupted file made open or a query hang\n";
    if (write(2, msg, sizeof msg - 1) < 0)
        _exit(3);
    _exit(3);
}
#else
#define WATCHDOG(seconds) ((void)0)
#endif

static int cook_sample(sample *s, const char *name, cbvh_layout layout, int quantized, int level)
{
    scene sc;
    float c[3] = {1.0f, 2.0f, -3.0f};
    if (!scene_sphere(&sc, 100, c, 2.0f))
        return -1;
    sc.material_ids = malloc(sc.triangle_count * sizeof(uint32_t));
    for (size_t t = 0; t < sc.triangle_count; t++)
        sc.material_ids[t] = (uint32_t)(t % 5);
    cbvh_mesh m = {sc.positions, sc.vertex_count, 0, sc.indices, sc.triangle_count, sc.material_ids};
    cbvh_cook_options o;
    cbvh_cook_options_init(&o, sizeof o);
    /* The cook defaults of the samples' first layout (leaves of 4, unit costs): the structural
     * edits assume, e.g., that no section starts at the 64-byte boundary below the file's end. */
    o.max_leaf_size = 4;
    o.traversal_cost = 1.0f;
    o.vertex_format = quantized ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
    o.compress_level = level;
    o.layout = layout;
    static const cbvh_material_name names[] = {{0, "stone"}, {1, "wood"}, {3, "metal"}, {3, "steel"}};
    o.material_names = names; /* a MATERIAL_NAMES section to corrupt too */
    o.material_name_count = 4;
    void *out = NULL;
    cbvh_result r = cbvh_cook(&m, &o, NULL, &out, &s->size, NULL, NULL);
    scene_free(&sc);
    if (r != CBVH_OK)
        return -1;
    s->name = name;
    s->bytes = malloc(s->size);
    memcpy(s->bytes, out, s->size);
    cbvh_buffer_free(NULL, out);
    return 0;
}

static int group_setup(void **state)
{
    (void)state;
#ifdef SIGALRM
    signal(SIGALRM, on_alarm);
#endif
    const cbvh_layout b = CBVH_LAYOUT_BINARY, w = CBVH_LAYOUT_WIDE4;
    if (cook_sample(&samples[0], "raw", b, 0, 0) || cook_sample(&samples[1], "zlib", b, 0, 6) ||
        cook_sample(&samples[2], "quantized", b, 1, 0) || cook_sample(&samples[3], "w4-raw", w, 0, 0) ||
        cook_sample(&samples[4], "w4-zlib", w, 0, 6) || cook_sample(&samples[5], "w4-q16", w, 1, 0))
        return -1;
    return 0;
}

static int group_teardown(void **state)
{
    (void)state;
    for (int i = 0; i < SAMPLE_COUNT; i++)
        free(samples[i].bytes);
    printf("corruption totals: %zu files tried: %zu rejected corrupt, %zu unsupported, %zu other errors, %zu "
           "benign opened\n",
           totals.tried, totals.corrupt, totals.unsupported, totals.other_error, totals.opened);
    return 0;
}

/* Opens `bytes` from a guarded copy; returns the result and, on success,
 * runs the query invariants. Every outcome is counted. */
static cbvh_result try_open(const uint8_t *bytes, size_t size, tally *t)
{
    guard_buffer g;
    guard_copy(&g, bytes, size);
    cbvh_file *f = NULL;
    cbvh_error err;
    WATCHDOG(20);
    cbvh_result r = cbvh_open_memory(g.data, size, NULL, &f, &err);
    t->tried++;
    if (r == CBVH_OK) {
        t->opened++;
        fuzz_check_queries(f, g.data, size, size, 0);
        cbvh_close(f);
    } else {
        fuzz_check_error(r, &err);
        if (r == CBVH_ERROR_CORRUPT)
            t->corrupt++;
        else if (r == CBVH_ERROR_UNSUPPORTED)
            t->unsupported++;
        else
            t->other_error++;
    }
    WATCHDOG(0);
    guard_release(&g);
    return r;
}

static void add_tally(const tally *t)
{
    totals.tried += t->tried;
    totals.corrupt += t->corrupt;
    totals.unsupported += t->unsupported;
    totals.other_error += t->other_error;
    totals.opened += t->opened;
}

static void print_tally(const char *what, const char *file, const tally *t)
{
    printf("%-28s %-9s tried %6zu  corrupt %6zu  unsupported %4zu  other %zu  opened %5zu\n", what, file,
           t->tried, t->corrupt, t->unsupported, t->other_error, t->opened);
    add_tally(t);
}

/* Same closest-hit distances for a fan of rays: a benign change must not
 * change any answer. */
static void assert_same_answers(const uint8_t *a, size_t na, const uint8_t *b, size_t nb)
{
    cbvh_file *fa = NULL, *fb = NULL;
    assert_int_equal(cbvh_open_memory(a, na, NULL, &fa, NULL), CBVH_OK);
    assert_int_equal(cbvh_open_memory(b, nb, NULL, &fb, NULL), CBVH_OK);
    cbvh_file_info info;
    cbvh_file_get_info(fa, &info, sizeof info);
    uint64_t rng = 99;
    for (int i = 0; i < 256; i++) {
        cbvh_ray r;
        for (int k = 0; k < 3; k++) {
            double lo = info.bounds_min[k], hi = info.bounds_max[k], ext = hi - lo;
            r.org[k] = (float)(lo - ext + 3 * ext * scene_rand_unit(&rng));
            r.dir[k] = (float)(lo + ext * scene_rand_unit(&rng) - r.org[k]);
        }
        r.tmin = 0;
        r.tmax = INFINITY;
        for (int t = 0; t < 4; t++) {
            cbvh_hit ha, hb;
            int ga = cbvh_raycast(fa, &r, (cbvh_traversal)t, &ha, NULL),
                gb = cbvh_raycast(fb, &r, (cbvh_traversal)t, &hb, NULL);
            assert_int_equal(ga, gb);
            if (ga)
                assert_true(ha.t == hb.t);
        }
    }
    cbvh_close(fa);
    cbvh_close(fb);
}

/* A file cut to `len` bytes is damaged, never valid-but-newer nor anything else: CBVH_ERROR_CORRUPT. */
static void expect_truncation_corrupt(const uint8_t *bytes, size_t len, const char *how, tally *t)
{
    cbvh_result r = try_open(bytes, len, t);
    if (r != CBVH_ERROR_CORRUPT)
        fail_msg("truncated to %zu bytes (%s): %s, expected %s", len, how, cbvh_result_string(r),
                 cbvh_result_string(CBVH_ERROR_CORRUPT));
}

static void test_truncation(void **state)
{
    (void)state;
    for (int s = 0; s < SAMPLE_COUNT; s++) {
        tally t = {0};
        for (size_t len = 0; len < samples[s].size; len++)
            expect_truncation_corrupt(samples[s].bytes, len, "as cut", &t);
        /* truncated with the size field and CRCs made to match the shorter file */
        uint8_t *copy = malloc(samples[s].size);
        for (size_t len = 128; len < samples[s].size; len++) {
            memcpy(copy, samples[s].bytes, len);
            fuzz_repair_checksums(copy, len);
            expect_truncation_corrupt(copy, len, "with repaired size and CRCs", &t);
        }
        free(copy);
        assert_int_equal(t.opened, 0);
        print_tally("truncated", samples[s].name, &t);
    }
}

/* Byte `at` of a wide4 node changed (spec section 5.2): first_child and first_triangle must equal running
 * counts and an unused slot must be all zero, so changing them is corrupt; the octant orders (meta bits
 * 24..63, bytes 59..63) only order the visit and are valid while every index is below 24. */
static int expected_wide4_node(const uint8_t *orig, const uint8_t *mut, size_t at)
{
    const uint64_t meta = le_get_u64(mut + 56);
    if (at < 48 && !(le_get_u64(orig + 56) >> (16 + at % 8 / 2) & 1u))
        return CBVH_ERROR_CORRUPT;
    if (at >= 48 && at < 56)
        return CBVH_ERROR_CORRUPT;
    if (at < 59)
        return -1;
    for (int k = 0; k < 8; k++)
        if ((meta >> (24 + 5 * k) & 31u) >= 24)
            return CBVH_ERROR_CORRUPT;
    return CBVH_OK;
}

/* Where a byte change with repaired checksums must land: -1 any outcome
 * (queries still checked), else the one result code it must give. */
static int expected_code(const uint8_t *orig, const uint8_t *mut, size_t pos)
{
    uint32_t count = le_get_u32(orig + HDR_SECTION_COUNT);
    if (pos >= HDR_VERSION && pos < HDR_VERSION + 4) {
        uint32_t v = le_get_u32(mut + HDR_VERSION);
        return v == 0 ? CBVH_ERROR_CORRUPT : v > 1 ? CBVH_ERROR_UNSUPPORTED : -1;
    }
    if (pos >= HDR_COMPAT && pos < HDR_COMPAT + 4)
        return CBVH_OK; /* old readers ignore compatible flags */
    if (pos >= HDR_INCOMPAT && pos < HDR_INCOMPAT + 4) {
        /* bits this reader does not know are unsupported; the wide4 depth-first bit
         * (CBVH_INCOMPAT_W4_DEPTH_FIRST) changes how the leaves must tile the triangles: a tree whose two
         * orders differ turns corrupt */
        if (le_get_u32(mut + HDR_INCOMPAT) & ~0x2u)
            return CBVH_ERROR_UNSUPPORTED;
        return -1;
    }
    if (pos >= HDR_RESERVED && pos < HDR_RESERVED + 12)
        return CBVH_ERROR_CORRUPT;
    if (pos >= TABLE && pos < TABLE + (size_t)count * ENTRY) {
        size_t field = (pos - TABLE) % ENTRY;
        const uint8_t *e = mut + TABLE + (pos - TABLE) / ENTRY * ENTRY;
        const int ancillary =
            (le_get_u32(e) & 0x80000000u) != 0; /* skipped when its codec or encoding is unknown */
        if (field >= E_CODEC && field < E_CODEC + 4 && le_get_u32(e + E_CODEC) > 1)
            return ancillary ? CBVH_OK : CBVH_ERROR_UNSUPPORTED;
        if (field < 4 && !ancillary && le_get_u32(e) > 5)
            return CBVH_ERROR_UNSUPPORTED;
        if (field >= E_ENCODING) {
            /* encodings per type 1..5 (NODES: binary, wide4; TRIANGLES: u16, u32, DELTA16, LOCAL8 = 4, 3 is
             * reserved; REMAP: u16, u32, u24; MATERIALS: u8, u16, u32, uniform) */
            static const uint32_t known[6] = {0, 2, 5, 2, 3, 4};
            uint32_t type = le_get_u32(e), enc = le_get_u32(e + E_ENCODING);
            if (type >= 1 && type <= 5 && (enc >= known[type] || (type == 2 && enc == 3)))
                return CBVH_ERROR_UNSUPPORTED;
            if (type == CBVH_SECTION_MATERIAL_NAMES && enc >= 1)
                return CBVH_OK;
        }
        return -1;
    }
    uint64_t noff = le_get_u64(orig + TABLE + E_OFFSET), nend = noff + le_get_u64(orig + TABLE + E_STORED);
    if (le_get_u32(orig + TABLE + E_TYPE) != 1 || le_get_u32(orig + TABLE + E_CODEC) != 0 || pos < noff ||
        pos >= nend)
        return -1;
    if (le_get_u32(orig + TABLE + E_ENCODING) == 1) {
        size_t node = (size_t)(noff + (pos - noff) / 64 * 64);
        return expected_wide4_node(orig + node, mut + node, (size_t)(pos - noff) % 64);
    }
    /* the sort byte (bits 23..30) of an internal node changes only the visit order */
    if ((pos - noff) % 16 >= 12) {
        size_t word_at = (size_t)(noff + (pos - noff) / 16 * 16 + 12);
        uint32_t before = le_get_u32(orig + word_at), after = le_get_u32(mut + word_at);
        if (!(before & 0x80000000u) && ((before ^ after) & ~0x7F800000u) == 0)
            return CBVH_OK;
    }
    return -1;
}

/* Every byte in [lo, hi) (or `samples_wanted` evenly spread ones) set to each
 * of four changed values, once as is (the CRCs must catch it) and once with
 * the checksums repaired (the structural checks must). */
static void flip_range(const sample *s, size_t lo, size_t hi, size_t samples_wanted, tally *as_is,
                       tally *repaired)
{
    uint8_t *m = malloc(s->size);
    size_t step = samples_wanted && hi - lo > samples_wanted ? (hi - lo) / samples_wanted : 1;
    for (size_t pos = lo; pos < hi; pos += step) {
        const uint8_t values[4] = {(uint8_t)(s->bytes[pos] ^ 0x01), (uint8_t)(s->bytes[pos] ^ 0x80),
                                   (uint8_t)(s->bytes[pos] ^ 0xFF), 0x00};
        for (int v = 0; v < 4; v++) {
            if (values[v] == s->bytes[pos])
                continue;
            memcpy(m, s->bytes, s->size);
            m[pos] = values[v];
            cbvh_result r = try_open(m, s->size, as_is);
            if (r == CBVH_OK)
                fail_msg("%s: byte %zu set to 0x%02x opened although no checksum was repaired", s->name, pos,
                         values[v]);
            fuzz_repair_checksums(m, s->size);
            r = try_open(m, s->size, repaired);
            int want = expected_code(s->bytes, m, pos);
            if (want >= 0 && (int)r != want)
                fail_msg("%s: byte %zu set to 0x%02x (checksums repaired): %s, expected %s", s->name, pos,
                         values[v], cbvh_result_string(r), cbvh_result_string((cbvh_result)want));
            if (want == CBVH_OK)
                assert_same_answers(s->bytes, s->size, m, s->size);
        }
    }
    free(m);
}

static void test_byte_changes(void **state)
{
    (void)state;
    for (int i = 0; i < SAMPLE_COUNT; i++) {
        const sample *s = &samples[i];
        uint32_t count = le_get_u32(s->bytes + HDR_SECTION_COUNT);
        tally as_is = {0}, repaired = {0}, as_is_s = {0}, repaired_s = {0};
        size_t table_end = TABLE + (size_t)count * ENTRY;
        flip_range(s, 0, table_end, 0, &as_is, &repaired);
        /* padding after the table */
        size_t first = (size_t)le_get_u64(s->bytes + TABLE + E_OFFSET);
        flip_range(s, table_end, first, 0, &as_is, &repaired);
        for (uint32_t k = 0; k < count; k++) {
            const uint8_t *e = s->bytes + TABLE + (size_t)k * ENTRY;
            size_t off = (size_t)le_get_u64(e + E_OFFSET), stored = (size_t)le_get_u64(e + E_STORED);
            int nodes = le_get_u32(e + E_TYPE) == 1;
            flip_range(s, off, off + stored, nodes ? 0 : 4096, nodes ? &as_is : &as_is_s,
                       nodes ? &repaired : &repaired_s);
        }
        print_tally("header+table+nodes, as is", s->name, &as_is);
        print_tally("header+table+nodes, fixed", s->name, &repaired);
        print_tally("other sections (<=4096 each)", s->name, &as_is_s);
        print_tally("other sections, fixed", s->name, &repaired_s);
    }
}

/* ---- whole-structure damage, built with the file editor (checksums valid) ---- */

static cbvh_result open_edit(const edit_file *e, tally *t, uint8_t **keep, size_t *keep_size)
{
    size_t n;
    uint8_t *b = edit_build(e, &n);
    cbvh_result r = try_open(b, n, t);
    if (keep) {
        *keep = b;
        *keep_size = n;
    } else {
        free(b);
    }
    return r;
}

/* Table edits on a copy of sample s, checksums repaired. */
static cbvh_result open_table_edit(const sample *s, tally *t,
                                   void (*edit)(uint8_t *bytes, size_t *size, void *arg), void *arg)
{
    uint8_t *m = malloc(s->size + 4096);
    memcpy(m, s->bytes, s->size);
    memset(m + s->size, 0, 4096);
    size_t n = s->size;
    edit(m, &n, arg);
    fuzz_repair_checksums(m, n);
    cbvh_result r = try_open(m, n, t);
    free(m);
    return r;
}

static void edit_swap_entries(uint8_t *b, size_t *n, void *arg)
{
    (void)n;
    int k = *(int *)arg;
    uint8_t tmp[ENTRY];
    memcpy(tmp, b + TABLE + k * ENTRY, ENTRY);
    memcpy(b + TABLE + k * ENTRY, b + TABLE + (k + 1) * ENTRY, ENTRY);
    memcpy(b + TABLE + (k + 1) * ENTRY, tmp, ENTRY);
}

static void edit_overlap(uint8_t *b, size_t *n, void *arg)
{
    (void)n;
    int k = *(int *)arg; /* section k+1 starts where section k does */
    le_put_u64(b + TABLE + (k + 1) * ENTRY + E_OFFSET, le_get_u64(b + TABLE + k * ENTRY + E_OFFSET));
}

static void edit_overlap_by_64(uint8_t *b, size_t *n, void *arg)
{
    (void)n;
    int k = *(int *)arg; /* section k+1 starts 64 bytes early, inside section k */
    uint8_t *e = b + TABLE + (k + 1) * ENTRY;
    le_put_u64(e + E_OFFSET, le_get_u64(e + E_OFFSET) - 64);
}

typedef struct past_end {
    int entry;
    uint64_t offset, stored, size;
} past_end;
static void edit_past_end(uint8_t *b, size_t *n, void *arg)
{
    (void)n;
    const past_end *p = arg;
    uint8_t *e = b + TABLE + p->entry * ENTRY;
    if (p->offset != UINT64_MAX)
        le_put_u64(e + E_OFFSET, p->offset);
    if (p->stored != UINT64_MAX)
        le_put_u64(e + E_STORED, p->stored);
    if (p->size != UINT64_MAX)
        le_put_u64(e + E_SIZE, p->size);
}

static void edit_count(uint8_t *b, size_t *n, void *arg)
{
    (void)n;
    le_put_u32(b + HDR_SECTION_COUNT, *(uint32_t *)arg);
}

static void edit_append(uint8_t *b, size_t *n, void *arg)
{
    size_t extra = *(size_t *)arg;
    (void)b;
    *n += extra; /* zero bytes after the last section */
}

static void test_structure(void **state)
{
    (void)state;
    for (int i = 0; i < SAMPLE_COUNT; i++) {
        const sample *s = &samples[i];
        tally t = {0}, benign = {0};
        int count = (int)le_get_u32(s->bytes + HDR_SECTION_COUNT);
        for (int k = 0; k + 1 < count; k++) {
            assert_int_equal(open_table_edit(s, &t, edit_swap_entries, &k), CBVH_ERROR_CORRUPT);
            assert_int_equal(open_table_edit(s, &t, edit_overlap, &k), CBVH_ERROR_CORRUPT);
            assert_int_equal(open_table_edit(s, &t, edit_overlap_by_64, &k), CBVH_ERROR_CORRUPT);
        }
        const uint64_t big[] = {(uint64_t)s->size, (uint64_t)s->size + 64,
                                UINT64_MAX - 63,   UINT64_MAX - 127,
                                1ull << 62,        1ull << 32};
        for (int k = 0; k < count; k++)
            for (size_t j = 0; j < sizeof big / sizeof big[0]; j++) {
                past_end p1 = {k, big[j] & ~63ull, UINT64_MAX, UINT64_MAX}; /* starts past the end */
                past_end p2 = {k, UINT64_MAX, big[j], UINT64_MAX};          /* runs past the end */
                past_end p3 = {k, UINT64_MAX, big[j], big[j]};              /* runs past, sizes agree */
                past_end p4 = {k, UINT64_MAX, UINT64_MAX, big[j]};          /* declared size huge */
                if (p1.offset !=
                    le_get_u64(s->bytes + TABLE + (size_t)k * ENTRY + E_OFFSET)) /* else no change */
                    assert_int_equal(open_table_edit(s, &t, edit_past_end, &p1), CBVH_ERROR_CORRUPT);
                assert_int_equal(open_table_edit(s, &t, edit_past_end, &p2), CBVH_ERROR_CORRUPT);
                assert_int_equal(open_table_edit(s, &t, edit_past_end, &p3), CBVH_ERROR_CORRUPT);
                assert_int_equal(open_table_edit(s, &t, edit_past_end, &p4), CBVH_ERROR_CORRUPT);
            }
        const uint32_t counts[] = {0, 1, 2, (uint32_t)count - 1, (uint32_t)count + 1, 16, 17, 0xFFFFFFFFu};
        for (size_t j = 0; j < sizeof counts / sizeof counts[0]; j++)
            assert_int_equal(open_table_edit(s, &t, edit_count, (void *)&counts[j]), CBVH_ERROR_CORRUPT);
        const size_t extras[] = {1, 63, 64, 4096};
        for (size_t j = 0; j < sizeof extras / sizeof extras[0]; j++)
            assert_int_equal(open_table_edit(s, &t, edit_append, (void *)&extras[j]), CBVH_ERROR_CORRUPT);

        /* re-laid-out copies through the editor */
        edit_file e;
        assert_true(edit_parse(&e, s->bytes, s->size));
        uint8_t *rebuilt;
        size_t rebuilt_size;
        /* the same sections in another order is a valid file with the same answers */
        edit_section first = e.s[0];
        memmove(&e.s[0], &e.s[1], (e.count - 1) * sizeof e.s[0]);
        e.s[e.count - 1] = first;
        assert_int_equal(open_edit(&e, &benign, &rebuilt, &rebuilt_size), CBVH_OK);
        assert_same_answers(s->bytes, s->size, rebuilt, rebuilt_size);
        free(rebuilt);
        memmove(&e.s[1], &e.s[0], (e.count - 1) * sizeof e.s[0]);
        e.s[0] = first;
        /* every section compressed, or none: still the same file */
        uint32_t codecs[16];
        for (uint32_t k = 0; k < e.count; k++)
            codecs[k] = e.s[k].codec;
        for (int c = 0; c < 2; c++) {
            for (uint32_t k = 0; k < e.count; k++)
                e.s[k].codec = (uint32_t)c;
            assert_int_equal(open_edit(&e, &benign, &rebuilt, &rebuilt_size), CBVH_OK);
            assert_same_answers(s->bytes, s->size, rebuilt, rebuilt_size);
            free(rebuilt);
        }
        for (uint32_t k = 0; k < e.count; k++)
            e.s[k].codec = codecs[k];
        /* an unknown ancillary section is skipped; an unknown critical one is unsupported */
        if (e.count < 16) {
            uint8_t *extra = malloc(100);
            memset(extra, 0xA5, 100);
            e.s[e.count] = (edit_section){0x80000007u, 0, 3, extra, 100};
            e.count++;
            assert_int_equal(open_edit(&e, &benign, &rebuilt, &rebuilt_size), CBVH_OK);
            assert_same_answers(s->bytes, s->size, rebuilt, rebuilt_size);
            free(rebuilt);
            e.s[e.count - 1].type = 9;
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_UNSUPPORTED);
            e.s[e.count - 1].type = 2; /* a second TRIANGLES section */
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            e.count--;
            free(extra);
        }
        /* each required section missing */
        for (uint32_t type = 1; type <= 3; type++) {
            int k = edit_find(&e, type);
            edit_section gone = e.s[k];
            memmove(&e.s[k], &e.s[k + 1], (e.count - k - 1) * sizeof e.s[0]);
            e.count--;
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            memmove(&e.s[k + 1], &e.s[k], (e.count - k) * sizeof e.s[0]);
            e.s[k] = gone;
            e.count++;
        }
        /* payload damage with valid checksums: a vertex index out of range,
         * a repeated remap value, a NaN vertex, a leaf past the triangles */
        int ti = edit_find(&e, 2), ri = edit_find(&e, 4), vi = edit_find(&e, 3), ni = edit_find(&e, 1);
        uint32_t vcount = le_get_u32(e.header + 36), tcount = le_get_u32(e.header + 32);
        uint8_t saved[16];
        /* the first index (u16), or the first block's base (LOCAL8), made vertex_count */
        assert_true(e.s[ti].encoding == 0 || e.s[ti].encoding == 4); /* u16 or LOCAL8 for this small mesh */
        const size_t index_bytes = e.s[ti].encoding == 0 ? 2 : 4;
        memcpy(saved, e.s[ti].data, index_bytes);
        le_put_u32(saved + 8, vcount);
        memcpy(e.s[ti].data, saved + 8, index_bytes);
        assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
        memcpy(e.s[ti].data, saved, index_bytes);
        if (ri >= 0) {
            memcpy(saved, e.s[ri].data, 2);
            memcpy(e.s[ri].data, e.s[ri].data + 2, 2);
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            memcpy(e.s[ri].data, saved, 2);
        }
        if (e.s[vi].encoding == 0) {
            memcpy(saved, e.s[vi].data + 4, 4);
            le_put_u32(e.s[vi].data + 4, 0x7FC00000u);
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            memcpy(e.s[vi].data + 4, saved, 4);
        }
        for (uint32_t n = 0; e.s[ni].encoding == 1 && n < le_get_u32(e.header + 40); n++) {
            uint8_t *node = e.s[ni].data + 64 * n; /* wide4: the first node with a leaf slot */
            const uint64_t meta = le_get_u64(node + 56);
            const uint32_t first_triangle = le_get_u32(node + 52),
                           leaves = (uint32_t)(meta >> 16 & ~(meta >> 20)) & 15u;
            if (!leaves)
                continue;
            const int slot = leaves & 1u ? 0 : leaves & 2u ? 1 : leaves & 4u ? 2 : 3;
            le_put_u32(node + 52, tcount + 1); /* first triangle past the end */
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            le_put_u32(node + 52, first_triangle);
            le_put_u64(node + 56, meta | 7ull << 4 * slot); /* 8 triangles: more than max_leaf_size 4 */
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            le_put_u64(node + 56, meta);
            break;
        }
        for (uint32_t n = 0; e.s[ni].encoding == 0 && n < le_get_u32(e.header + 40); n++) {
            uint8_t *w = e.s[ni].data + 16 * n + 12;
            uint32_t word = le_get_u32(w);
            if (!(word & 0x80000000u))
                continue;
            le_put_u32(w, (word & ~0x7FFFFFFu) | (tcount + 1)); /* first triangle past the end */
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            le_put_u32(w, word | 0x78000000u); /* 16 triangles: more than max_leaf_size */
            assert_int_equal(open_edit(&e, &t, NULL, NULL), CBVH_ERROR_CORRUPT);
            le_put_u32(w, word);
            break;
        }
        /* a zlib stream that inflates to more, or less, than declared */
        int zi = e.s[ni].codec == 1 ? ni : -1;
        if (zi >= 0) {
            e.s[zi].size -= 16;
            size_t keep_n;
            uint8_t *zb = edit_build(&e, &keep_n); /* declared size smaller than the stream */
            e.s[zi].size += 16;
            assert_int_equal(try_open(zb, keep_n, &t), CBVH_ERROR_CORRUPT);
            free(zb);
        }
        edit_free(&e);
        assert_int_equal(t.opened, 0);
        print_tally("structure damage", s->name, &t);
        print_tally("structure benign", s->name, &benign);
    }
}

/* Opening by path: empty, short and truncated files, a folder, nothing. */
static void test_paths(void **state)
{
    (void)state;
    char dir[200];
    test_temp_dir(dir, sizeof dir, "cbvh_corrupt");
    char path[256];
    snprintf(path, sizeof path, "%s/f.cbvh", dir);
    const sample *s = &samples[1];
    const size_t lengths[] = {0, 1, 8, 127, 128, s->size / 2, s->size - 1, s->size};
    for (size_t i = 0; i < sizeof lengths / sizeof lengths[0]; i++) {
        FILE *fp = fopen(path, "wb");
        assert_non_null(fp);
        assert_int_equal(fwrite(s->bytes, 1, lengths[i], fp), lengths[i]);
        fclose(fp);
        cbvh_file *f = NULL;
        cbvh_error err;
        cbvh_result r = cbvh_open_path(path, NULL, &f, &err);
        if (lengths[i] == s->size) {
            assert_int_equal(r, CBVH_OK);
            cbvh_close(f);
        } else {
            fuzz_check_error(r, &err);
            assert_int_equal(r, CBVH_ERROR_CORRUPT);
        }
    }
    cbvh_file *f = NULL;
    cbvh_error err;
    assert_int_equal(cbvh_open_path(dir, NULL, &f, &err), CBVH_ERROR_IO);
    assert_true(err.message[0] != 0);
    unlink(path);
    assert_int_equal(cbvh_open_path(path, NULL, &f, &err), CBVH_ERROR_IO);
    assert_true(err.message[0] != 0);
    rmdir(dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_truncation),
        cmocka_unit_test(test_byte_changes),
        cmocka_unit_test(test_structure),
        cmocka_unit_test(test_paths),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
