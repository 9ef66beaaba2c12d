/* validate_mesh.c: checks every vertex index against vertex_count and every vertex against the header's
 * bounds. */
#include <float.h>
#include <math.h>

#include "common/endian.h"
#include "common/error.h"
#include "layout/triangle_encodings.h"
#include "load/load.h"

#define CORRUPT(...) cbvh_fail(err, CBVH_ERROR_CORRUPT, __VA_ARGS__)

/* The largest index of a packed u16 or u32 index array: a branch-free reduction the compiler vectorizes;
 * only a failing file pays for finding the triangle at fault. */
static uint32_t max_u16(const uint16_t *restrict v, size_t n)
{
    uint32_t m = 0;
    for (size_t i = 0; i < n; i++)
        m = v[i] > m ? v[i] : m;
    return m;
}

static uint32_t max_u32(const uint32_t *restrict v, size_t n)
{
    uint32_t m = 0;
    for (size_t i = 0; i < n; i++)
        m = v[i] > m ? v[i] : m;
    return m;
}

static cbvh_result find_bad_index(const struct cbvh_file *f, uint32_t begin, uint32_t end, cbvh_error *err)
{
    for (uint32_t t = begin; t < end; t++) {
        uint32_t idx[3];
        cbvh_triangle_indices(f, t, idx);
        if (idx[0] >= f->info.vertex_count || idx[1] >= f->info.vertex_count ||
            idx[2] >= f->info.vertex_count)
            return CORRUPT("triangle %u (cooked order): vertex indices %u, %u, %u, vertex_count is %u", t,
                           idx[0], idx[1], idx[2], f->info.vertex_count);
    }
    return CBVH_OK;
}

/* DELTA16 triangles [begin, end) by their rule (layout/triangle_encodings.h). */
static cbvh_result check_delta16(const struct cbvh_file *f, uint32_t begin, uint32_t end, cbvh_error *err)
{
    const uint8_t *restrict t = (const uint8_t *)f->triangles + CBVH_TRIS_DELTA16_SIZE * (size_t)begin;
    for (uint32_t i = begin; i < end; i++, t += CBVH_TRIS_DELTA16_SIZE)
        if (!cbvh_delta16_valid(t, f->info.vertex_count)) {
            const int16_t *d = cbvh_delta16_deltas(t);
            return CORRUPT("triangle %u (cooked order): DELTA16 base %u with deltas %d, %d gives indices "
                           "outside 0..%lld",
                           i, cbvh_delta16_base(t), d[0], d[1], (long long)f->info.vertex_count - 1);
        }
    return CBVH_OK;
}

/* LOCAL8 blocks [begin, end) by their rule (layout/triangle_encodings.h). */
static cbvh_result check_local8(const struct cbvh_file *f, uint32_t begin, uint32_t end, cbvh_error *err)
{
    const uint8_t *restrict b = (const uint8_t *)f->triangles + (size_t)CBVH_LOCAL8_BLOCK_SIZE * begin;
    const uint64_t vc = f->info.vertex_count, tc = f->info.triangle_count;
    for (uint32_t i = begin; i < end; i++, b += CBVH_LOCAL8_BLOCK_SIZE) {
        const uint64_t base = cbvh_read_u32(b), first = (uint64_t)i * CBVH_LOCAL8_BLOCK;
        const uint32_t used = tc - first < CBVH_LOCAL8_BLOCK ? (uint32_t)(tc - first) : CBVH_LOCAL8_BLOCK;
        const uint32_t largest = cbvh_local8_largest_offset(b, used),
                       loose = cbvh_local8_first_loose_offset(b, used);
        if (loose < CBVH_LOCAL8_TRIANGLE_BYTES * CBVH_LOCAL8_BLOCK)
            return CORRUPT("triangle block %u: offset %u of slot %u, past triangle_count %llu, must be 0", i,
                           b[CBVH_LOCAL8_OFFSETS_AT + loose], loose / CBVH_LOCAL8_TRIANGLE_BYTES,
                           (unsigned long long)tc);
        if (base + largest >= vc)
            return CORRUPT(
                "triangle block %u (triangles from %llu): LOCAL8 base %llu plus offset %u is not below "
                "vertex_count %llu",
                i, (unsigned long long)first, (unsigned long long)base, largest, (unsigned long long)vc);
    }
    return CBVH_OK;
}

cbvh_result cbvh_indices_check(const struct cbvh_file *f, void *unused, uint32_t begin, uint32_t end,
                               cbvh_error *err)
{
    (void)unused;
    const size_t first = 3u * (size_t)begin, n = 3u * (size_t)(end - begin);
    uint32_t max;
    switch (f->triangle_encoding) {
    case CBVH_TRIS_U16:
        max = max_u16((const uint16_t *)f->triangles + first, n);
        break;
    case CBVH_TRIS_U32:
        max = max_u32((const uint32_t *)f->triangles + first, n);
        break;
    case CBVH_TRIS_LOCAL8:
        return check_local8(f, begin, end, err);
    default:
        return check_delta16(f, begin, end, err);
    }
    return max < f->info.vertex_count ? CBVH_OK : find_bad_index(f, begin, end, err);
}

void cbvh_vertex_bounds_init(cbvh_vertex_bounds *b)
{
    for (int a = 0; a < 3; a++) {
        b->lo[a] = FLT_MAX;
        b->hi[a] = -FLT_MAX;
        b->qlo[a] = CBVH_Q_MAX;
        b->qhi[a] = 0;
    }
}

static cbvh_result find_bad_vertex(const float *restrict v, uint32_t begin, uint32_t end, cbvh_error *err)
{
    for (uint32_t i = begin; i < end; i++)
        for (int a = 0; a < 3; a++)
            if (!isfinite(v[3 * (size_t)i + a]))
                return CORRUPT("vertex %u: coordinate %d is %g, must be finite", i, a,
                               (double)v[3 * (size_t)i + a]);
    return CBVH_OK;
}

static cbvh_result check_f32(const struct cbvh_file *f, cbvh_vertex_bounds *b, uint32_t begin, uint32_t end,
                             cbvh_error *err)
{
    const float *restrict v = (const float *)f->vertices + 3u * (size_t)begin;
    float lo[3] = {b->lo[0], b->lo[1], b->lo[2]}, hi[3] = {b->hi[0], b->hi[1], b->hi[2]};
    int finite = 1;
    for (uint32_t i = begin; i < end; i++, v += 3) {
        for (int a = 0; a < 3; a++) {
            const float x = v[a];
            finite &= fabsf(x) <= FLT_MAX; /* false for NaN and infinities */
            lo[a] = x < lo[a] ? x : lo[a];
            hi[a] = x > hi[a] ? x : hi[a];
        }
    }
    if (!finite)
        return find_bad_vertex(f->vertices, begin, end, err);
    for (int a = 0; a < 3; a++) {
        b->lo[a] = lo[a];
        b->hi[a] = hi[a];
    }
    return CBVH_OK;
}

static void check_q16(const struct cbvh_file *f, cbvh_vertex_bounds *b, uint32_t begin, uint32_t end)
{
    const uint16_t *restrict v = (const uint16_t *)f->vertices + 3u * (size_t)begin;
    uint32_t qlo[3] = {b->qlo[0], b->qlo[1], b->qlo[2]}, qhi[3] = {b->qhi[0], b->qhi[1], b->qhi[2]};
    for (uint32_t i = begin; i < end; i++, v += 3) {
        for (int a = 0; a < 3; a++) {
            const uint32_t q = v[a];
            qlo[a] = q < qlo[a] ? q : qlo[a];
            qhi[a] = q > qhi[a] ? q : qhi[a];
        }
    }
    for (int a = 0; a < 3; a++) {
        b->qlo[a] = qlo[a];
        b->qhi[a] = qhi[a];
    }
}

cbvh_result cbvh_vertices_check(const struct cbvh_file *f, void *bounds, uint32_t begin, uint32_t end,
                                cbvh_error *err)
{
    if (f->vertex_encoding == CBVH_VERTS_F32)
        return check_f32(f, bounds, begin, end, err);
    check_q16(f, bounds, begin, end);
    return CBVH_OK;
}

/* Grid vertices: dequantization is monotonic in q (scale >= 0), so their bounds are those of the extreme
 * grid coordinates. */
cbvh_result cbvh_vertices_finish(const struct cbvh_file *f, const cbvh_vertex_bounds *b, cbvh_error *err)
{
    for (int a = 0; a < 3; a++) {
        float lo = b->lo[a], hi = b->hi[a];
        if (f->vertex_encoding == CBVH_VERTS_Q16) {
            lo = cbvh_dequantize(b->qlo[a], f->grid_origin[a], f->grid_scale[a]);
            hi = cbvh_dequantize(b->qhi[a], f->grid_origin[a], f->grid_scale[a]);
        }
        if (lo != f->info.bounds_min[a] || hi != f->info.bounds_max[a])
            return CORRUPT(
                "header bounds on axis %d [%.9g, %.9g] differ from the vertices' bounds [%.9g, %.9g]", a,
                (double)f->info.bounds_min[a], (double)f->info.bounds_max[a], (double)lo, (double)hi);
    }
    return CBVH_OK;
}
