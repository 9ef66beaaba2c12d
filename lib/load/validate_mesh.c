/* validate_mesh.c: checks every vertex index against vertex_count and every vertex against the header's bounds. */
#include <float.h>
#include <math.h>

#include "common/error.h"
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

static cbvh_result find_bad_index(const struct cbvh_file *f, cbvh_error *err)
{
    for (uint32_t t = 0; t < f->info.triangle_count; t++) {
        uint32_t idx[3];
        cbvh_triangle_indices(f, t, idx);
        if (idx[0] >= f->info.vertex_count || idx[1] >= f->info.vertex_count || idx[2] >= f->info.vertex_count)
            return CORRUPT("triangle %u (cooked order): vertex indices %u, %u, %u, vertex_count is %u", t, idx[0],
                           idx[1], idx[2], f->info.vertex_count);
    }
    return CBVH_OK;
}

/* DELTA16: base + d computed in 64 bits, so a negative or wrapped index is caught. */
static cbvh_result check_delta16(const struct cbvh_file *f, cbvh_error *err)
{
    const uint8_t *restrict t = f->triangles;
    const uint32_t n = f->info.triangle_count;
    const int64_t vc = f->info.vertex_count;
    for (uint32_t i = 0; i < n; i++, t += 8) {
        const int64_t base = (int64_t)*(const uint32_t *)t;
        const int16_t *d = (const int16_t *)(t + 4);
        const int64_t a = base + d[0], b = base + d[1];
        if (base >= vc || a < 0 || a >= vc || b < 0 || b >= vc)
            return CORRUPT("triangle %u (cooked order): DELTA16 base %lld with deltas %d, %d gives indices outside "
                           "0..%lld", i, (long long)base, d[0], d[1], (long long)vc - 1);
    }
    return CBVH_OK;
}

cbvh_result cbvh_validate_indices(const struct cbvh_file *f, cbvh_error *err)
{
    const size_t n = 3u * (size_t)f->info.triangle_count;
    switch (f->triangle_encoding) {
    case CBVH_TRIS_U16:
        return max_u16(f->triangles, n) < f->info.vertex_count ? CBVH_OK : find_bad_index(f, err);
    case CBVH_TRIS_U32:
        return max_u32(f->triangles, n) < f->info.vertex_count ? CBVH_OK : find_bad_index(f, err);
    default:
        return check_delta16(f, err);
    }
}

static cbvh_result check_bounds(const struct cbvh_file *f, const float lo[3], const float hi[3], cbvh_error *err)
{
    for (int a = 0; a < 3; a++)
        if (lo[a] != f->info.bounds_min[a] || hi[a] != f->info.bounds_max[a])
            return CORRUPT("header bounds on axis %d [%.9g, %.9g] differ from the vertices' bounds [%.9g, %.9g]", a,
                           (double)f->info.bounds_min[a], (double)f->info.bounds_max[a], (double)lo[a], (double)hi[a]);
    return CBVH_OK;
}

static cbvh_result find_bad_vertex(const float *restrict v, uint32_t n, cbvh_error *err)
{
    for (uint32_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++)
            if (!isfinite(v[3 * (size_t)i + a]))
                return CORRUPT("vertex %u: coordinate %d is %g, must be finite", i, a, (double)v[3 * (size_t)i + a]);
    return CBVH_OK;
}

static cbvh_result check_f32(const struct cbvh_file *f, cbvh_error *err)
{
    const float *restrict v = f->vertices;
    const uint32_t n = f->info.vertex_count;
    float lo[3] = { FLT_MAX, FLT_MAX, FLT_MAX }, hi[3] = { -FLT_MAX, -FLT_MAX, -FLT_MAX };
    int finite = 1;
    for (uint32_t i = 0; i < n; i++, v += 3) {
        for (int a = 0; a < 3; a++) {
            const float x = v[a];
            finite &= fabsf(x) <= FLT_MAX; /* false for NaN and infinities */
            lo[a] = x < lo[a] ? x : lo[a];
            hi[a] = x > hi[a] ? x : hi[a];
        }
    }
    if (!finite)
        return find_bad_vertex(f->vertices, n, err);
    return check_bounds(f, lo, hi, err);
}

/* Dequantization is monotonic in q (scale >= 0), so the bounds are those of the extreme grid coordinates. */
static cbvh_result check_q16(const struct cbvh_file *f, cbvh_error *err)
{
    const uint16_t *restrict v = f->vertices;
    const uint32_t n = f->info.vertex_count;
    uint32_t qlo[3] = { 65535, 65535, 65535 }, qhi[3] = { 0, 0, 0 };
    for (uint32_t i = 0; i < n; i++, v += 3) {
        for (int a = 0; a < 3; a++) {
            const uint32_t q = v[a];
            qlo[a] = q < qlo[a] ? q : qlo[a];
            qhi[a] = q > qhi[a] ? q : qhi[a];
        }
    }
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = cbvh_dequantize(qlo[a], f->grid_origin[a], f->grid_scale[a]);
        hi[a] = cbvh_dequantize(qhi[a], f->grid_origin[a], f->grid_scale[a]);
    }
    return check_bounds(f, lo, hi, err);
}

cbvh_result cbvh_validate_vertices(const struct cbvh_file *f, cbvh_error *err)
{
    return f->vertex_encoding == CBVH_VERTS_F32 ? check_f32(f, err) : check_q16(f, err);
}
