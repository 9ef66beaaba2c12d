/* validate_remap.c: checks REMAP values (in range, unique) while building the original -> cooked map. */
#include <string.h>

#include "common/alloc.h"
#include "common/error.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)
#define DIGIT_BITS 11
#define DIGIT_VALUES (1u << DIGIT_BITS)

/* LSD radix sort of (original id << 32 | cooked id) on the original id, `passes` digits; returns the
 * buffer holding the result. Memory stays proportional to triangle_count whatever
 * original_triangle_count says, which a dense table indexed by original id would not. */
static uint64_t *radix_sort(uint64_t *restrict a, uint64_t *restrict b, size_t n, int passes)
{
    for (int p = 0; p < passes; p++) {
        const int shift = 32 + p * DIGIT_BITS;
        size_t offset[DIGIT_VALUES];
        memset(offset, 0, sizeof offset);
        for (size_t i = 0; i < n; i++)
            offset[(a[i] >> shift) & (DIGIT_VALUES - 1)]++;
        size_t sum = 0;
        for (uint32_t d = 0; d < DIGIT_VALUES; d++) {
            size_t c = offset[d];
            offset[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            b[offset[(a[i] >> shift) & (DIGIT_VALUES - 1)]++] = a[i];
        uint64_t *t = a;
        a = b;
        b = t;
    }
    return a;
}

static int digits_for(uint32_t max_key)
{
    int passes = 1;
    while (passes * DIGIT_BITS < 32 && (max_key >> (passes * DIGIT_BITS)) != 0)
        passes++;
    return passes;
}

cbvh_result cbvh_unmap_begin(struct cbvh_file *f, cbvh_unmap_build *b, cbvh_error *err)
{
    b->unmap = NULL;
    b->dense = (uint64_t)f->original_triangle_count <= 2u * (uint64_t)f->info.triangle_count;
    if (!f->remap)
        return CBVH_OK;
    const uint32_t entries = b->dense ? f->original_triangle_count : f->info.triangle_count;
    b->unmap = cbvh_alloc_array(&f->allocator, entries, sizeof(uint32_t), 64);
    if (!b->unmap)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "cannot allocate the %u-entry unmap table", entries);
    cbvh_file_own(f, b->unmap);
    if (b->dense)
        memset(b->unmap, 0xFF, (size_t)entries * sizeof(uint32_t));
    f->unmap = b->unmap;
    f->unmap_sorted = !b->dense;
    return CBVH_OK;
}

/* Dense unmap, one scattered write per triangle: used when original ids are at most twice the triangles,
 * so its memory stays proportional to the file's. A slot already taken is a repeated id. */
cbvh_result cbvh_remap_check(const struct cbvh_file *f, void *build, uint32_t begin, uint32_t end,
                             cbvh_error *err)
{
    const cbvh_unmap_build *b = build;
    if (!b->dense)
        return CBVH_OK; /* checked in cbvh_unmap_finish, which needs all values */
    uint32_t *restrict unmap = b->unmap;
    const uint32_t original = f->original_triangle_count;
    for (uint32_t t = begin; t < end; t++) {
        const uint32_t id = cbvh_original_id(f, t);
        if (id >= original)
            return CORRUPT("REMAP entry %u: original id %u, original_triangle_count is %u", t, id, original);
        if (unmap[id] != CBVH_NO_HIT)
            return CORRUPT("REMAP entries %u and %u both hold original id %u", unmap[id], t, id);
        unmap[id] = t;
    }
    return CBVH_OK;
}

/* Sorted unmap for sparse original ids: radix-sorts (id, cooked) pairs, then repeated ids are neighbours. */
cbvh_result cbvh_unmap_finish(const struct cbvh_file *f, const cbvh_unmap_build *b, cbvh_error *err)
{
    if (b->dense)
        return CBVH_OK;
    const uint32_t n = f->info.triangle_count;
    const uint32_t original = f->original_triangle_count;
    uint64_t *pairs = cbvh_alloc_array(&f->allocator, 2u * (size_t)n, sizeof(uint64_t), 64);
    if (!pairs)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "cannot allocate %u remap entries to check them", n);
    cbvh_result r = CBVH_OK;
    for (uint32_t t = 0; t < n && r == CBVH_OK; t++) {
        uint32_t id = cbvh_original_id(f, t);
        if (id >= original)
            r = CORRUPT("REMAP entry %u: original id %u, original_triangle_count is %u", t, id, original);
        pairs[t] = (uint64_t)id << 32 | t;
    }
    if (r == CBVH_OK) {
        const uint64_t *sorted = radix_sort(pairs, pairs + n, n, digits_for(original - 1));
        for (uint32_t k = 1; k < n && r == CBVH_OK; k++)
            if (sorted[k] >> 32 == sorted[k - 1] >> 32)
                r = CORRUPT("REMAP entries %u and %u both hold original id %u", (uint32_t)sorted[k - 1],
                            (uint32_t)sorted[k], (uint32_t)(sorted[k] >> 32));
        for (uint32_t k = 0; k < n; k++)
            b->unmap[k] = (uint32_t)sorted[k];
    }
    cbvh_free(&f->allocator, pairs);
    return r;
}
