/* mesh_prepare.c: validating the caller's mesh, welding equal positions, dropping degenerate triangles and
 * unused vertices. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "common/alloc.h"
#include "common/error.h"
#include "cook/cook_internal.h"

#define NO_VERTEX UINT32_MAX

static const char axis_name[3] = {'x', 'y', 'z'};

/* The caller's array may be unaligned or strided: copy rather than cast. */
static void read_position(const cbvh_mesh *m, size_t stride, size_t v, float p[3])
{
    memcpy(p, (const unsigned char *)m->positions + v * stride, 3 * sizeof(float));
}

/* Welding compares bit patterns, so that it is exact and deterministic; -0 and +0 are one point. */
static uint32_t weld_bits(float f)
{
    uint32_t u;
    if (f == 0.0f)
        f = 0.0f;
    memcpy(&u, &f, sizeof u);
    return u;
}

static uint32_t weld_hash(const float p[3])
{
    uint32_t h = weld_bits(p[0]) * 0x9E3779B1u;
    h = (h ^ (h >> 15)) + weld_bits(p[1]) * 0x85EBCA77u;
    h = (h ^ (h >> 13)) + weld_bits(p[2]) * 0xC2B2AE3Du;
    return h ^ (h >> 16);
}

static int same_point(const float *a, const float *b)
{
    return weld_bits(a[0]) == weld_bits(b[0]) && weld_bits(a[1]) == weld_bits(b[1]) &&
           weld_bits(a[2]) == weld_bits(b[2]);
}

/* Exact enough zero-area test: float differences and their cross product in double. */
static int zero_area(const float *p0, const float *p1, const float *p2)
{
    double e1[3], e2[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)p1[k] - (double)p0[k];
        e2[k] = (double)p2[k] - (double)p0[k];
    }
    double cx = e1[1] * e2[2] - e1[2] * e2[1];
    double cy = e1[2] * e2[0] - e1[0] * e2[2];
    double cz = e1[0] * e2[1] - e1[1] * e2[0];
    return cx == 0.0 && cy == 0.0 && cz == 0.0;
}

/* Marks every referenced vertex in `map` (0 = used) after checking the index is in range. */
static cbvh_result check_indices(const cbvh_mesh *mesh, uint32_t *restrict map, size_t *used, cbvh_error *err)
{
    const uint32_t *restrict idx = mesh->indices;
    const size_t tris = mesh->triangle_count, verts = mesh->vertex_count;
    size_t n = 0;
    for (size_t t = 0; t < tris; t++) {
        for (int c = 0; c < 3; c++) {
            uint32_t i = idx[3 * t + (size_t)c];
            if (i >= verts)
                return cbvh_fail(
                    err, CBVH_ERROR_BAD_MESH,
                    "triangle %zu, corner %d: vertex index %u is out of range (the mesh has %zu vertices)", t,
                    c, i, verts);
            n += map[i] == NO_VERTEX;
            map[i] = 0;
        }
    }
    *used = n;
    return CBVH_OK;
}

static cbvh_result out_of_memory(cbvh_error *err, const char *what)
{
    return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while preparing the mesh (%s)", what);
}

/* Puts a used vertex into the exact range (cbvh.h, CBVH_COORDINATE_MAX): refuses a non-finite coordinate
 * or one beyond CBVH_COORDINATE_MAX, naming vertex v and the axis; sets a coordinate below
 * CBVH_COORDINATE_MIN to 0, counting it in *flushed. */
static cbvh_result into_range(float p[3], size_t v, uint64_t *flushed, cbvh_error *err)
{
    for (int k = 0; k < 3; k++) {
        if (!isfinite(p[k]))
            return cbvh_fail(err, CBVH_ERROR_BAD_MESH, "vertex %zu: %c coordinate is %s", v, axis_name[k],
                             isnan(p[k]) ? "NaN" : "infinite");
        if (fabsf(p[k]) > CBVH_COORDINATE_MAX)
            return cbvh_fail(
                err, CBVH_ERROR_BAD_MESH,
                "vertex %zu: %c coordinate %g is beyond the exact range of +-2^40 (%g): move the mesh "
                "nearer its origin or scale it down",
                v, axis_name[k], (double)p[k], (double)CBVH_COORDINATE_MAX);
        if (p[k] != 0.0f && fabsf(p[k]) < CBVH_COORDINATE_MIN) {
            p[k] = 0.0f;
            ++*flushed;
        }
    }
    return CBVH_OK;
}

/* Checks every used vertex is in the exact range (into_range; the first bad one is named) and gives it
 * the id of the first used vertex with the same position, numbering distinct positions in input order;
 * writes the distinct positions to `out`. */
static cbvh_result weld(const cbvh_mesh *mesh, size_t stride, uint32_t *restrict map, size_t map_count,
                        size_t used, float *restrict out, uint32_t *welded, uint64_t *flushed,
                        const cbvh_allocator *a, cbvh_error *err)
{
    size_t cap = 16;
    while (cap < 2 * used)
        cap *= 2;
    uint32_t *table = cbvh_alloc_array(a, cap, sizeof(uint32_t), 64);
    if (!table)
        return out_of_memory(err, "welding");
    memset(table, 0xFF, cap * sizeof(uint32_t));
    const size_t mask = cap - 1;
    uint32_t count = 0;
    for (size_t v = 0; v < map_count; v++) {
        if (map[v] == NO_VERTEX)
            continue;
        float p[3];
        read_position(mesh, stride, v, p);
        const cbvh_result r = into_range(p, v, flushed, err);
        if (r != CBVH_OK) {
            cbvh_free(a, table);
            return r;
        }
        size_t slot = weld_hash(p) & mask;
        while (table[slot] != NO_VERTEX && !same_point(out + 3 * (size_t)table[slot], p))
            slot = (slot + 1) & mask;
        if (table[slot] == NO_VERTEX) {
            table[slot] = count;
            memcpy(out + 3 * (size_t)count, p, sizeof p);
            count++;
        }
        map[v] = table[slot];
    }
    cbvh_free(a, table);
    *welded = count;
    return CBVH_OK;
}

/* Moves the welded positions to an array of their size: the array was sized for every used vertex before
 * welding, three a triangle for meshes stored unwelded (STL always is), and is held to the end. */
static cbvh_result shrink_positions(cook_mesh *m, uint32_t welded, const cbvh_allocator *a, cbvh_error *err)
{
    float *fit = cbvh_alloc_array(a, welded, 3 * sizeof(float), 64);
    if (!fit)
        return out_of_memory(err, "positions");
    memcpy(fit, m->positions, (size_t)welded * 3 * sizeof(float));
    cbvh_free(a, m->positions);
    m->positions = fit;
    return CBVH_OK;
}

/* Per kept triangle, its input id (the mesh's list of dropped ones, expanded); NULL without memory. */
static uint32_t *original_ids(const cook_mesh *m, const cbvh_allocator *a)
{
    uint32_t *ids = cbvh_alloc_array(a, m->triangle_count, sizeof(uint32_t), 64);
    if (!ids)
        return NULL;
    size_t next_dropped = 0;
    uint32_t id = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++, id++) {
        for (; next_dropped < m->dropped_degenerate && m->dropped[next_dropped] == id; next_dropped++)
            id++;
        ids[t] = id;
    }
    return ids;
}

/* Sets the mesh's list of dropped triangles: the input ids missing from `ids` (the kept ones, increasing). */
static cbvh_result list_dropped(cook_mesh *m, const uint32_t *restrict ids, uint32_t kept,
                                const cbvh_allocator *a, cbvh_error *err)
{
    const size_t count = (size_t)m->input_triangle_count - kept;
    uint32_t *dropped = count ? cbvh_alloc_array(a, count, sizeof(uint32_t), 64) : NULL;
    if (count && !dropped)
        return out_of_memory(err, "dropped triangles");
    size_t n = 0, k = 0;
    for (size_t id = 0; id < m->input_triangle_count; id++) {
        if (k < kept && ids[k] == id)
            k++;
        else
            dropped[n++] = (uint32_t)id;
    }
    cbvh_free(a, m->dropped);
    m->dropped = dropped;
    m->dropped_degenerate = count;
    return CBVH_OK;
}

/* Keeps the triangles with three distinct welded vertices and a nonzero area, writing their input ids. */
static void drop_degenerate(const cbvh_mesh *mesh, const uint32_t *restrict map, cook_mesh *m,
                            uint32_t *restrict ids)
{
    const uint32_t *restrict idx = mesh->indices;
    const float *restrict pos = m->positions;
    uint32_t *restrict out = m->indices;
    const size_t tris = mesh->triangle_count;
    size_t kept = 0;
    for (size_t t = 0; t < tris; t++) {
        uint32_t w0 = map[idx[3 * t]], w1 = map[idx[3 * t + 1]], w2 = map[idx[3 * t + 2]];
        if (w0 == w1 || w1 == w2 || w0 == w2 ||
            zero_area(pos + 3 * (size_t)w0, pos + 3 * (size_t)w1, pos + 3 * (size_t)w2))
            continue;
        out[3 * kept] = w0;
        out[3 * kept + 1] = w1;
        out[3 * kept + 2] = w2;
        ids[kept] = (uint32_t)t;
        kept++;
    }
    m->triangle_count = kept > UINT32_MAX ? UINT32_MAX : (uint32_t)kept;
}

static int collapsed(const cook_mesh *m, uint32_t t)
{
    const float *pos = m->positions;
    const uint32_t *corner = m->indices + 3 * (size_t)t;
    return zero_area(pos + 3 * (size_t)corner[0], pos + 3 * (size_t)corner[1], pos + 3 * (size_t)corner[2]);
}

cbvh_result cbvh_cook_drop_collapsed(cook_mesh *m, const cbvh_allocator *a, cbvh_error *err)
{
    uint32_t first = 0;
    while (first < m->triangle_count && !collapsed(m, first))
        first++;
    if (first == m->triangle_count)
        return CBVH_OK;
    uint32_t *restrict ids = original_ids(m, a);
    if (!ids)
        return out_of_memory(err, "collapsed triangles");
    uint32_t *restrict idx = m->indices;
    uint32_t kept = first;
    for (uint32_t t = first; t < m->triangle_count; t++) {
        if (collapsed(m, t))
            continue;
        memmove(idx + 3 * (size_t)kept, idx + 3 * (size_t)t, 3 * sizeof *idx);
        ids[kept] = ids[t];
        kept++;
    }
    m->triangle_count = kept;
    const cbvh_result r = list_dropped(m, ids, kept, a, err);
    cbvh_free(a, ids);
    return r;
}

/* Renumbers the welded vertices that kept triangles use, in welded order, compacting positions;
 * map (input vertex -> welded vertex) then leads to the renumbered ones. */
static cbvh_result drop_unused(cook_mesh *m, uint32_t welded, uint32_t *restrict map, size_t map_count,
                               const cbvh_allocator *a)
{
    uint32_t *renumber = cbvh_alloc_array(a, welded, sizeof(uint32_t), 64);
    if (!renumber)
        return CBVH_ERROR_OUT_OF_MEMORY;
    memset(renumber, 0xFF, (size_t)welded * sizeof(uint32_t));
    const size_t corners = 3 * (size_t)m->triangle_count;
    for (size_t i = 0; i < corners; i++)
        renumber[m->indices[i]] = 0;
    uint32_t count = 0;
    for (uint32_t w = 0; w < welded; w++) {
        if (renumber[w] == NO_VERTEX)
            continue;
        memmove(m->positions + 3 * (size_t)count, m->positions + 3 * (size_t)w, 3 * sizeof(float));
        renumber[w] = count++;
    }
    for (size_t i = 0; i < corners; i++)
        m->indices[i] = renumber[m->indices[i]];
    for (size_t v = 0; v < map_count; v++)
        if (map[v] != NO_VERTEX)
            map[v] = renumber[map[v]];
    m->vertex_count = count;
    cbvh_free(a, renumber);
    return CBVH_OK;
}

cbvh_result cbvh_cook_mesh_bounds(cook_mesh *m, cbvh_error *err)
{
    /* Over the vertices the triangles use: after cbvh_cook_drop_collapsed some are unused and the
     * file, which stores used vertices only, must carry their exact bounds. */
    const float *p = m->positions;
    const uint32_t *idx = m->indices;
    const size_t corners = 3 * (size_t)m->triangle_count;
    for (int k = 0; k < 3; k++)
        m->bounds_min[k] = m->bounds_max[k] = p[3 * (size_t)idx[0] + (size_t)k];
    for (size_t c = 1; c < corners; c++)
        for (int k = 0; k < 3; k++) {
            float x = p[3 * (size_t)idx[c] + (size_t)k];
            m->bounds_min[k] = x < m->bounds_min[k] ? x : m->bounds_min[k];
            m->bounds_max[k] = x > m->bounds_max[k] ? x : m->bounds_max[k];
        }
    for (int k = 0; k < 3; k++) {
        double extent = (double)m->bounds_max[k] - (double)m->bounds_min[k];
        if (extent > (double)FLT_MAX)
            return cbvh_fail(err, CBVH_ERROR_BAD_MESH,
                             "the mesh's extent on the %c axis (%g to %g) overflows a float", axis_name[k],
                             (double)m->bounds_min[k], (double)m->bounds_max[k]);
    }
    return CBVH_OK;
}

void cbvh_cook_mesh_free(const cbvh_allocator *a, cook_mesh *m)
{
    cbvh_free(a, m->positions);
    cbvh_free(a, m->indices);
    cbvh_free(a, m->dropped);
    cbvh_free(a, m->vertex_map);
    memset(m, 0, sizeof *m);
}

void cbvh_cook_mesh_shelve_triangles(cook_mesh *m, const cbvh_allocator *a)
{
    if (m->positions_for_build) {
        cbvh_free(a, m->positions);
        m->positions = NULL;
    }
    if (!m->vertex_map)
        return;
    cbvh_free(a, m->indices);
    m->indices = NULL;
}

cbvh_result cbvh_cook_mesh_restore_triangles(cook_mesh *m, const cbvh_mesh *input, const cbvh_allocator *a,
                                             cbvh_error *err)
{
    if (!m->indices) {
        m->indices = cbvh_alloc_array(a, m->triangle_count, 3 * sizeof(uint32_t), 64);
        if (!m->indices)
            return out_of_memory(err, "triangles");
        const uint32_t *restrict in = input->indices, *restrict map = m->vertex_map;
        uint32_t *restrict out = m->indices;
        for (uint32_t t = 0; t < m->triangle_count; t++) {
            const uint32_t *corner = in + 3 * (size_t)cbvh_cook_original_id(m, t);
            for (size_t c = 0; c < 3; c++)
                out[3 * (size_t)t + c] = map[corner[c]];
        }
    }
    cbvh_free(a, m->vertex_map);
    m->vertex_map = NULL;
    return CBVH_OK;
}

cbvh_result cbvh_cook_prepare(const cbvh_mesh *mesh, const cbvh_allocator *a, const cook_progress *progress,
                              cook_mesh *out, cbvh_error *err)
{
    memset(out, 0, sizeof *out);
    const size_t tris = mesh->triangle_count;
    const size_t stride = mesh->position_stride ? mesh->position_stride : 3 * sizeof(float);
    if (tris == 0)
        return cbvh_fail(err, CBVH_ERROR_EMPTY_MESH, "the mesh has no triangles");
    if ((uint64_t)tris > UINT32_MAX)
        return cbvh_fail(err, CBVH_ERROR_LIMIT,
                         "the mesh has %zu triangles; original triangle ids are 32-bit (at most 4294967295)",
                         tris);
    out->input_triangle_count = (uint32_t)tris;

    /* Indices are 32-bit, so vertices past 2^32 can never be used. */
    const uint64_t map_count64 =
        (uint64_t)mesh->vertex_count > 0x100000000ull ? 0x100000000ull : mesh->vertex_count;
    const size_t map_count = (size_t)map_count64;
    uint32_t *map = cbvh_alloc_array(a, map_count ? map_count : 1, sizeof(uint32_t), 64);
    if (!map)
        return out_of_memory(err, "vertex map");
    memset(map, 0xFF, map_count * sizeof(uint32_t));

    size_t used = 0;
    cbvh_result r = check_indices(mesh, map, &used, err);
    uint32_t welded = 0;
    if (r == CBVH_OK) {
        cook_report(progress, 0.25);
        out->positions = cbvh_alloc_array(a, used, 3 * sizeof(float), 64);
        r = out->positions ? weld(mesh, stride, map, map_count, used, out->positions, &welded,
                                  &out->flushed_coordinates, a, err)
                           : out_of_memory(err, "positions");
    }
    if (r == CBVH_OK && welded < used)
        r = shrink_positions(out, welded, a, err);
    if (r != CBVH_OK) {
        cbvh_free(a, map);
        cbvh_cook_mesh_free(a, out);
        return r;
    }
    cook_report(progress, 0.5);

    out->indices = cbvh_alloc_array(a, tris, 3 * sizeof(uint32_t), 64);
    uint32_t *ids = cbvh_alloc_array(a, tris, sizeof(uint32_t), 64);
    if (out->indices && ids)
        drop_degenerate(mesh, map, out, ids);
    r = out->indices && ids ? list_dropped(out, ids, out->triangle_count, a, err)
                            : out_of_memory(err, "triangles");
    cbvh_free(a, ids);
    if (r != CBVH_OK) {
        cbvh_free(a, map);
        cbvh_cook_mesh_free(a, out);
        return r;
    }
    cook_report(progress, 0.75);

    if (out->triangle_count == 0)
        r = cbvh_fail(err, CBVH_ERROR_EMPTY_MESH,
                      "all %zu triangles are degenerate (zero area or a repeated vertex)", tris);
    else if (out->triangle_count > CBVH_MAX_TRIANGLES)
        r = cbvh_fail(err, CBVH_ERROR_LIMIT,
                      "%u triangles remain after dropping degenerate ones; a file holds at most %u",
                      out->triangle_count, CBVH_MAX_TRIANGLES);
    else if (drop_unused(out, welded, map, map_count, a) != CBVH_OK)
        r = out_of_memory(err, "vertex renumbering");
    else
        r = cbvh_cook_mesh_bounds(out, err);
    if (r != CBVH_OK) {
        cbvh_free(a, map);
        cbvh_cook_mesh_free(a, out);
        return r;
    }
    if (map_count <= 3 * (size_t)out->triangle_count)
        out->vertex_map = map;
    else
        cbvh_free(a, map);
    cook_report(progress, 1.0);
    return CBVH_OK;
}
