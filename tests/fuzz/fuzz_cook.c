/* fuzz_cook.c: libFuzzer target: cook a mesh decoded from the bytes (NaN, inf, huge values, bad indices
 * included) in both node layouts; a clean error or files that open, answer like brute force and like each
 * other. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cbvh.h"
#include "fuzz_support.h"
#include "le_bytes.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Input layout (see README.md):
 *   byte 0: bit 0 quantized vertices, bits 1-2 zlib level {0,1,6,9}, bit 3 cooked ids
 *           (keep_remap = 0), bit 4 material ids present, bit 5 int8 coordinates,
 *           bit 6 keep_materials = 0, bit 7 vertex stride 16 instead of 12
 *   byte 1: low nibble max_leaf_size - 1, high nibble sah_bins = 4 + 16 * nibble
 *   byte 2: vertex count
 *   int8 mode: byte 3 a power-of-two scale 2^(b3 - 128), bytes 4-7 a float added
 *   to every coordinate, then one signed byte per coordinate;
 *   float mode: 4 bytes per coordinate, little-endian binary32.
 *   then per triangle 3 index bytes (an index >= vertex count is bad) and,
 *   with materials, one byte m giving the id m << 8 * (m & 3). */
typedef struct decoded {
    cbvh_cook_options opt;
    float positions[256 * 4];
    uint32_t indices[3 * 8192];
    uint32_t materials[8192];
    cbvh_mesh mesh;
} decoded;

static int decode(decoded *d, const uint8_t *data, size_t size)
{
    static const int levels[4] = {0, 1, 6, 9};
    if (size < 3)
        return 0;
    uint8_t flags = data[0];
    cbvh_cook_options_init(&d->opt, sizeof d->opt);
    d->opt.vertex_format = (flags & 1) ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
    d->opt.compress_level = levels[(flags >> 1) & 3];
    d->opt.keep_remap = !(flags & 8);
    d->opt.keep_materials = !(flags & 64);
    d->opt.max_leaf_size = 1u + (data[1] & 15u);
    d->opt.sah_bins = 4u + 16u * (data[1] >> 4);
    size_t stride = (flags & 128) ? 4 : 3, nv = data[2], pos = 3;
    memset(d->positions, 0, sizeof d->positions);
    if (flags & 32) {
        if (size < 8)
            return 0;
        float scale = ldexpf(1.0f, (int)data[3] - 128), offset = le_get_f32(data + 4);
        pos = 8;
        if (size - pos < 3 * nv)
            nv = (size - pos) / 3;
        for (size_t v = 0; v < nv; v++)
            for (int a = 0; a < 3; a++)
                d->positions[v * stride + a] = (float)(int8_t)data[pos++] * scale + offset;
    } else {
        if ((size - pos) / 12 < nv)
            nv = (size - pos) / 12;
        for (size_t v = 0; v < nv; v++)
            for (int a = 0; a < 3; a++, pos += 4)
                d->positions[v * stride + a] = le_get_f32(data + pos);
    }
    size_t per = (flags & 16) ? 4 : 3, nt = (size - pos) / per;
    if (nt > 8192)
        nt = 8192;
    for (size_t t = 0; t < nt; t++, pos += per) {
        for (int k = 0; k < 3; k++)
            d->indices[3 * t + k] = data[pos + k];
        if (per == 4)
            d->materials[t] = (uint32_t)data[pos + 3] << (8 * (data[pos + 3] & 3));
    }
    d->mesh.positions = d->positions;
    d->mesh.vertex_count = nv;
    d->mesh.position_stride = stride * sizeof(float);
    d->mesh.indices = d->indices;
    d->mesh.triangle_count = nt;
    d->mesh.material_ids = (flags & 16) ? d->materials : NULL;
    return 1;
}

/* What the input deserves: 2 a bad index, 1 a non-finite coordinate or one beyond the exact range
 * (CBVH_COORDINATE_MAX), 0 fine. */
static int mesh_fault(const decoded *d)
{
    const cbvh_mesh *m = &d->mesh;
    size_t stride = m->position_stride / sizeof(float);
    int fault = 0;
    for (size_t i = 0; i < 3 * m->triangle_count; i++) {
        if (m->indices[i] >= m->vertex_count)
            return 2;
        for (int a = 0; a < 3; a++)
            if (!(fabsf(m->positions[m->indices[i] * stride + a]) <= CBVH_COORDINATE_MAX))
                fault = 1;
    }
    return fault;
}

/* A coordinate as the cooker stores it: below CBVH_COORDINATE_MIN in magnitude, 0 (cbvh.h). */
static float stored(float x)
{
    return fabsf(x) < CBVH_COORDINATE_MIN ? 0.0f : x;
}

/* Ray/triangle in double: the hit distance when the ray crosses the triangle
 * at least `margin` (barycentric) inside every edge, else -1. */
static double clear_hit(const double o[3], const double dir[3], const float *v0, const float *v1,
                        const float *v2, double margin)
{
    double e1[3], e2[3], s[3], p[3], q[3];
    for (int a = 0; a < 3; a++) {
        e1[a] = (double)v1[a] - v0[a];
        e2[a] = (double)v2[a] - v0[a];
        s[a] = o[a] - v0[a];
    }
    p[0] = dir[1] * e2[2] - dir[2] * e2[1];
    p[1] = dir[2] * e2[0] - dir[0] * e2[2];
    p[2] = dir[0] * e2[1] - dir[1] * e2[0];
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (det == 0 || !isfinite(det))
        return -1;
    double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
    q[0] = s[1] * e1[2] - s[2] * e1[1];
    q[1] = s[2] * e1[0] - s[0] * e1[2];
    q[2] = s[0] * e1[1] - s[1] * e1[0];
    double v = (dir[0] * q[0] + dir[1] * q[1] + dir[2] * q[2]) / det;
    double t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    if (u < margin || v < margin || u + v > 1 - margin || !(t > 0))
        return -1;
    /* and at least 1e-5 of the coordinates' magnitude from every edge: a
     * needle thinner than the float spacing at the ray origin is no clear hit */
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                   e1[0] * e2[1] - e1[1] * e2[0]};
    double area2 = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), mag = 0, e3[3];
    for (int a = 0; a < 3; a++) {
        e3[a] = (double)v2[a] - v1[a];
        mag = fmax(mag, fmax(fabs(o[a]), fmax(fabs(v0[a]), fmax(fabs(v1[a]), fabs(v2[a])))));
    }
    double len1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]),
           len2 = sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]),
           len3 = sqrt(e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2]), tol = 1e-5 * mag;
    if (v * area2 < tol * len1 || u * area2 < tol * len2 || (1 - u - v) * area2 < tol * len3)
        return -1;
    /* and not grazing: t is ill conditioned as 1/cos of the crossing angle */
    double dl = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    if (fabs(n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2]) < 1e-2 * area2 * dl)
        return -1;
    return t;
}

/* Rays from outside the bounds through points of random triangles: the cooked
 * file's closest hit may never lie clearly behind a triangle the brute force
 * sees clearly in front, and clear hits are never missed. */
static void compare_with_brute_force(const cbvh_file *f, const decoded *d, uint64_t seed)
{
    const cbvh_mesh *m = &d->mesh;
    size_t stride = m->position_stride / sizeof(float);
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    for (int i = 0; i < 16; i++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        size_t t = (size_t)(seed >> 33) % m->triangle_count;
        float v[3][3];
        for (int k = 0; k < 3; k++)
            for (int axis = 0; axis < 3; axis++)
                v[k][axis] = stored(m->positions[m->indices[3 * t + k] * stride + axis]);
        double a = (double)((seed >> 8) & 255) / 256.0, b = (double)((seed >> 16) & 255) / 256.0 * (1 - a);
        cbvh_ray r;
        double o[3], dir[3], ext = 0;
        for (int k = 0; k < 3; k++)
            ext = fmax(ext, (double)info.bounds_max[k] - info.bounds_min[k]);
        for (int k = 0; k < 3; k++) {
            double target = (1 - a - b) * v[0][k] + a * v[1][k] + b * v[2][k];
            double off = (double)((int)((seed >> (20 + 8 * k)) & 255) - 128) / 64.0;
            r.org[k] = (float)(target + (off == 0 ? 1 : off) * (ext + 1));
            r.dir[k] = (float)(target - r.org[k]);
            o[k] = r.org[k];
            dir[k] = r.dir[k];
        }
        r.tmin = 0;
        r.tmax = INFINITY;
        double best = INFINITY;
        for (size_t u = 0; u < m->triangle_count; u++) {
            float w[3][3];
            for (int k = 0; k < 3; k++)
                for (int axis = 0; axis < 3; axis++)
                    w[k][axis] = stored(m->positions[m->indices[3 * u + k] * stride + axis]);
            double th = clear_hit(o, dir, w[0], w[1], w[2], 1e-3);
            if (th >= 0 && th < best)
                best = th;
        }
        if (d->opt.vertex_format == CBVH_VERTEX_QUANTIZED16 || !isfinite(best))
            continue; /* quantized vertices move: no brute-force claim on the input mesh */
        cbvh_hit h;
        int got = cbvh_raycast(f, &r, CBVH_TRAVERSAL_SORTED, &h, NULL);
        FUZZ_CHECK(got, "ray %d misses, brute force hits clearly at t %.9g", i, best);
        FUZZ_CHECK(h.t <= best * (1 + 1e-4) + 1e-30, "ray %d: hit at t %.9g behind the clear hit at %.9g", i,
                   h.t, best);
    }
}

/* Cooks the mesh in one node layout and checks the file: a clean error (NULL, the code in *result), or a
 * deterministic file that opens from the guarded copy *g, keeps every kept triangle and material under its
 * id, misses no clear hit and passes the strict query checks (the open file is returned). */
static cbvh_file *cook_and_check(const decoded *d, cbvh_layout layout, size_t size, guard_buffer *g,
                                 cbvh_result *result)
{
    cbvh_cook_options opt = d->opt;
    opt.layout = layout;
    void *out = NULL;
    size_t out_size = 0;
    cbvh_cook_stats stats;
    cbvh_cook_stats_init(&stats, sizeof stats);
    cbvh_error err;
    memset(&err, 0, sizeof err);
    cbvh_result r = *result = cbvh_cook(&d->mesh, &opt, NULL, &out, &out_size, &stats, &err);
    int fault = mesh_fault(d);
    if (r != CBVH_OK) {
        fuzz_check_error(r, &err);
        FUZZ_CHECK(out == NULL, "failed cook returned a buffer");
        FUZZ_CHECK(r == CBVH_ERROR_BAD_MESH || r == CBVH_ERROR_EMPTY_MESH || r == CBVH_ERROR_LIMIT,
                   "cook failed with %s: %s", cbvh_result_string(r), err.message);
        FUZZ_CHECK(r != CBVH_ERROR_EMPTY_MESH || fault == 0 || d->mesh.triangle_count == 0,
                   "bad mesh reported as empty: %s", err.message);
        FUZZ_CHECK(r != CBVH_ERROR_BAD_MESH || fault != 0, "a mesh in the exact range refused: %s",
                   err.message);
        return NULL;
    }
    FUZZ_CHECK(fault == 0, "cook accepted a mesh with %s",
               fault == 2 ? "an index out of range"
                          : "a coordinate that is not finite or beyond the exact range");
    FUZZ_CHECK(out != NULL && out_size == stats.file_size, "cook returned %zu bytes, stats say %llu",
               out_size, (unsigned long long)stats.file_size);
    FUZZ_CHECK(stats.input_triangles == d->mesh.triangle_count &&
                   stats.triangles + stats.dropped_degenerate == stats.input_triangles,
               "stats: %llu in, %llu kept, %llu dropped", (unsigned long long)stats.input_triangles,
               (unsigned long long)stats.triangles, (unsigned long long)stats.dropped_degenerate);

    /* deterministic */
    void *again = NULL;
    size_t again_size = 0;
    FUZZ_CHECK(cbvh_cook(&d->mesh, &opt, NULL, &again, &again_size, NULL, NULL) == CBVH_OK,
               "second cook failed");
    FUZZ_CHECK(again_size == out_size && memcmp(again, out, out_size) == 0, "two cooks of one mesh differ");
    cbvh_buffer_free(NULL, again);

    guard_copy(g, out, out_size);
    cbvh_buffer_free(NULL, out);
    cbvh_file *f = NULL;
    r = cbvh_open_memory(g->data, g->size, NULL, &f, &err);
    FUZZ_CHECK(r == CBVH_OK, "the cooker's own file does not open: %s", err.message);
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    FUZZ_CHECK(info.triangle_count == stats.triangles && info.node_count == stats.nodes &&
                   info.depth == stats.depth,
               "header and stats disagree");
    FUZZ_CHECK(info.layout == (uint32_t)layout, "cooked layout %u, asked for %u", info.layout,
               (unsigned)layout);

    /* every kept triangle is the input triangle as stored (exactly when lossless, within the reported error
     * when quantized); dropped ones are absent */
    size_t stride = d->mesh.position_stride / sizeof(float), present = 0;
    if (d->opt.keep_remap) {
        for (size_t t = 0; t < d->mesh.triangle_count; t++) {
            float v[3][3];
            if (!cbvh_file_get_triangle(f, (uint32_t)t, v[0], v[1], v[2]))
                continue;
            present++;
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++) {
                    float in = stored(d->positions[d->indices[3 * t + k] * stride + a]);
                    double tol = d->opt.vertex_format == CBVH_VERTEX_QUANTIZED16 ? stats.vertex_max_error : 0;
                    FUZZ_CHECK(fabs((double)v[k][a] - in) <= tol,
                               "triangle %zu vertex %d axis %d: %.9g stored as %.9g (error %g)", t, k, a, in,
                               v[k][a], tol);
                }
            /* every triangle's own id, also when all are equal (the file then stores it once: MATERIALS
             * encoding 3) */
            uint32_t want = d->mesh.material_ids && d->opt.keep_materials ? d->materials[t] : 0;
            FUZZ_CHECK(cbvh_file_get_material(f, (uint32_t)t) == want,
                       "triangle %zu material %u, expected %u", t, cbvh_file_get_material(f, (uint32_t)t),
                       want);
        }
        FUZZ_CHECK(present == stats.triangles, "%zu triangles readable, %llu kept", present,
                   (unsigned long long)stats.triangles);
        compare_with_brute_force(f, d, size);
    }
    fuzz_check_queries(f, g->data, g->size, size, 1);
    return f;
}

/* The two layouts hold the same triangles, so they answer every ray alike: hit or miss, the closest t
 * exactly, occluded, with every traversal. The triangle may differ only when two are hit at that same t,
 * which a file reporting (its triangle, t) shows for its own; without REMAP the ids are cooked ids and
 * differ anyway. Rays go from outside the bounds through points of random triangles, and between random
 * points around the bounds. */
static void compare_layouts(const cbvh_file *binary, const cbvh_file *wide, const decoded *d, uint64_t seed)
{
    const cbvh_mesh *m = &d->mesh;
    const size_t stride = m->position_stride / sizeof(float);
    cbvh_file_info info;
    cbvh_file_get_info(binary, &info, sizeof info);
    double ext = 0;
    for (int k = 0; k < 3; k++)
        ext = fmax(ext, (double)info.bounds_max[k] - info.bounds_min[k]);
    for (int i = 0; i < 32; i++) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        cbvh_ray r;
        const size_t t = (size_t)(seed >> 33) % m->triangle_count;
        const double a = (double)((seed >> 8) & 255) / 256.0,
                     b = (double)((seed >> 16) & 255) / 256.0 * (1 - a);
        const uint32_t axis = i % 8 == 6 ? (uint32_t)(seed >> 62) % 3 : 3; /* some rays along an axis */
        for (uint32_t k = 0; k < 3; k++) {
            double target = (1 - a - b) * m->positions[m->indices[3 * t] * stride + k] +
                            a * m->positions[m->indices[3 * t + 1] * stride + k] +
                            b * m->positions[m->indices[3 * t + 2] * stride + k];
            const double off = (double)((int)((seed >> (20 + 8 * k)) & 255) - 128) / 64.0;
            if (i & 1) /* between two points around the bounds */
                target =
                    info.bounds_min[k] + ((double)((seed >> (44 + 6 * k)) & 63) / 32.0 - 0.5) * (ext + 1);
            r.org[k] = (float)(axis == 3 || axis == k ? target + (off == 0 ? 1 : off) * (ext + 1) : target);
            r.dir[k] = (float)(target - r.org[k]);
        }
        r.tmin = 0;
        r.tmax = INFINITY;
        for (int k = 0; k < 4; k++) {
            cbvh_hit hb, hw;
            const int gb = cbvh_raycast(binary, &r, (cbvh_traversal)k, &hb, NULL);
            const int gw = cbvh_raycast(wide, &r, (cbvh_traversal)k, &hw, NULL);
            FUZZ_CHECK(gb == gw && (!gb || hb.t == hw.t),
                       "ray %d traversal %d: binary %s tri %u t %.9g, wide4 %s tri %u t %.9g", i, k,
                       gb ? "hits" : "misses", hb.tri, gb ? hb.t : 0.0, gw ? "hits" : "misses", hw.tri,
                       gw ? hw.t : 0.0);
            FUZZ_CHECK(cbvh_occluded(binary, &r, (cbvh_traversal)k, NULL) ==
                           cbvh_occluded(wide, &r, (cbvh_traversal)k, NULL),
                       "ray %d traversal %d: binary and wide4 disagree on occluded", i, k);
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static decoded d;
    if (!decode(&d, data, size))
        return 0;
    guard_buffer gb, gw;
    cbvh_result rb, rw;
    cbvh_file *binary = cook_and_check(&d, CBVH_LAYOUT_BINARY, size, &gb, &rb);
    cbvh_file *wide = cook_and_check(&d, CBVH_LAYOUT_WIDE4, size, &gw, &rw);
    FUZZ_CHECK(rb == rw, "binary cook: %s, wide4 cook: %s", cbvh_result_string(rb), cbvh_result_string(rw));
    if (binary && wide)
        compare_layouts(binary, wide, &d, size);
    if (binary) {
        cbvh_close(binary);
        guard_release(&gb);
    }
    if (wide) {
        cbvh_close(wide);
        guard_release(&gw);
    }
    return 0;
}
