"""build_ffi.py: the cffi declarations of cbvh's API the package uses, and the few C loops it adds
(compiled against include/cbvh.h, so every struct layout and enum value comes from the header)."""
import cffi

import native_build

DECLARATIONS = """
typedef enum cbvh_result { CBVH_OK, CBVH_ERROR_INVALID_ARGUMENT, CBVH_ERROR_OUT_OF_MEMORY, CBVH_ERROR_IO,
    CBVH_ERROR_CORRUPT, CBVH_ERROR_UNSUPPORTED, CBVH_ERROR_BAD_MESH, CBVH_ERROR_EMPTY_MESH, CBVH_ERROR_LIMIT,
    ... } cbvh_result;
#define CBVH_NO_HIT ...
typedef struct cbvh_error { cbvh_result code; char message[256]; ...; } cbvh_error;
const char *cbvh_result_string(cbvh_result result);
const char *cbvh_version_string(void);

typedef struct cbvh_mesh { const float *positions; size_t vertex_count; size_t position_stride;
    const uint32_t *indices; size_t triangle_count; const uint32_t *material_ids; ...; } cbvh_mesh;
typedef enum cbvh_layout { CBVH_LAYOUT_BINARY, CBVH_LAYOUT_WIDE4, ... } cbvh_layout;
typedef enum cbvh_vertex_format { CBVH_VERTEX_FLOAT32, CBVH_VERTEX_QUANTIZED16, ... } cbvh_vertex_format;
typedef struct cbvh_material_name { uint32_t id; const char *name; ...; } cbvh_material_name;
typedef struct cbvh_cook_options {
    size_t struct_size; uint32_t max_leaf_size; uint32_t sah_bins; float traversal_cost;
    float intersection_cost; cbvh_vertex_format vertex_format; int compress_level; int keep_remap;
    int keep_materials; cbvh_layout layout; const cbvh_material_name *material_names;
    uint32_t material_name_count; ...; } cbvh_cook_options;
cbvh_result cbvh_cook_options_init(cbvh_cook_options *options, size_t struct_size);
typedef struct cbvh_allocator cbvh_allocator;
typedef enum cbvh_phase { CBVH_PHASE_PREPARE, CBVH_PHASE_BUILD, CBVH_PHASE_LAYOUT, CBVH_PHASE_WRITE, ... } cbvh_phase;
typedef enum cbvh_section_type { CBVH_SECTION_NODES, CBVH_SECTION_TRIANGLES, CBVH_SECTION_VERTICES,
    CBVH_SECTION_REMAP, CBVH_SECTION_MATERIALS, ... } cbvh_section_type;
#define CBVH_SECTION_MATERIAL_NAMES ...
#define CBVH_STATS_SECTION_TYPES ...
#define CBVH_STATS_PHASES ...
typedef struct cbvh_cook_stats {
    size_t struct_size; uint64_t input_triangles; uint64_t input_vertices; uint64_t dropped_degenerate;
    uint64_t triangles; uint64_t vertices; uint64_t nodes; uint64_t leaves; uint32_t depth; double sah_cost;
    double vertex_max_error; uint64_t file_size; uint64_t section_stored_size[...]; uint64_t section_size[...];
    double seconds[...]; uint64_t peak_memory; uint64_t flushed_coordinates; ...; } cbvh_cook_stats;
cbvh_result cbvh_cook_stats_init(cbvh_cook_stats *stats, size_t struct_size);
cbvh_result cbvh_cook(const cbvh_mesh *mesh, const cbvh_cook_options *options, const cbvh_allocator *allocator,
                      void **out_data, size_t *out_size, cbvh_cook_stats *stats, cbvh_error *err);
void cbvh_buffer_free(const cbvh_allocator *allocator, void *data);

typedef struct cbvh_file cbvh_file;
cbvh_result cbvh_open_path_read(const char *path, const cbvh_allocator *allocator, cbvh_file **out_file,
                                cbvh_error *err);
cbvh_result cbvh_open_memory(const void *data, size_t size, const cbvh_allocator *allocator,
                             cbvh_file **out_file, cbvh_error *err);
void cbvh_close(cbvh_file *file);
cbvh_result cbvh_file_expand_triangles(cbvh_file *file, cbvh_error *err);
typedef struct cbvh_file_info {
    size_t struct_size; uint32_t format_version; uint32_t compat_flags; uint32_t incompat_flags;
    uint32_t section_count; uint32_t triangle_count; uint32_t vertex_count; uint32_t node_count; uint32_t depth;
    uint32_t max_leaf_size; uint32_t has_remap; uint32_t has_materials; uint32_t vertex_format;
    uint32_t index_encoding; uint64_t file_size; float bounds_min[3]; float bounds_max[3];
    float grid_origin[3]; float grid_scale[3]; uint32_t layout; uint32_t material_name_count;
    uint32_t original_triangle_count; uint64_t expanded_bytes; ...; } cbvh_file_info;
cbvh_result cbvh_file_get_info(const cbvh_file *file, cbvh_file_info *info, size_t struct_size);
int cbvh_file_get_triangle(const cbvh_file *file, uint32_t tri, float v0[3], float v1[3], float v2[3]);
const char *cbvh_file_get_material_name(const cbvh_file *file, uint32_t index, uint32_t *id);

typedef struct cbvh_ray { float org[3]; float tmin; float dir[3]; float tmax; ...; } cbvh_ray;
typedef struct cbvh_hit { uint32_t tri; float t; float u; float v; ...; } cbvh_hit;
typedef struct cbvh_query_stats cbvh_query_stats;
size_t cbvh_stream_scratch_size(size_t batch_rays);
void cbvh_raycast_stream_scratch(const cbvh_file *file, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                                 cbvh_query_stats *stats, void *scratch, size_t scratch_size);
void cbvh_occluded_stream_scratch(const cbvh_file *file, const cbvh_ray *rays, size_t count, uint8_t *occluded,
                                  cbvh_query_stats *stats, void *scratch, size_t scratch_size);

typedef enum cbvh_shape_kind { CBVH_SHAPE_SPHERE, CBVH_SHAPE_CAPSULE, CBVH_SHAPE_BOX, ... } cbvh_shape_kind;
typedef struct cbvh_shape { cbvh_shape_kind kind; float center[3]; float p0[3]; float p1[3]; float radius;
    float half_extent[3]; float rotation[4]; ...; } cbvh_shape;
typedef struct cbvh_sweep_record { uint32_t tri; float t; float point[3]; float normal[3]; float depth;
    uint32_t material; ...; } cbvh_sweep_record;
typedef struct cbvh_contact { uint32_t tri; float depth; float normal[3]; float point[3]; ...; } cbvh_contact;

typedef struct cbvhpy_rays { const float *org, *dir, *tmin, *tmax; size_t org_step, dir_step, tmin_step, tmax_step;
    } cbvhpy_rays;
typedef struct cbvhpy_details { float normal[3]; uint32_t material; } cbvhpy_details;
void cbvhpy_details_table(const cbvh_file *file, uint32_t first, uint32_t end, cbvhpy_details *table);
cbvh_result cbvhpy_raycast(const cbvh_file *file, const cbvhpy_rays *rays, size_t begin, size_t end,
                           cbvh_hit *hits, const cbvhpy_details *table, float *normals, uint32_t *materials,
                           void *scratch, size_t scratch_size);
cbvh_result cbvhpy_occluded(const cbvh_file *file, const cbvhpy_rays *rays, size_t begin, size_t end,
                            uint8_t *occluded, void *scratch, size_t scratch_size);
cbvh_result cbvhpy_sweeps(const cbvh_file *file, const cbvh_shape *shapes, const float *deltas, size_t count,
                          cbvh_sweep_record *records, size_t *failed);
cbvh_result cbvhpy_overlaps(const cbvh_file *file, const cbvh_shape *shapes, size_t count, size_t *query,
                            size_t *first, uint32_t *ids, cbvh_contact *contacts, size_t capacity,
                            size_t *written, uint64_t *offsets);
void cbvhpy_triangles(const cbvh_file *file, uint32_t count, float *vertices);
"""

HELPERS = r"""
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "cbvh.h"
#if !CBVH_HAVE_COOKER
#error "the cbvh Python package needs a libcbvh with the cooker (one not configured with --disable-cooker)"
#endif

/* Rays as numpy holds them: four arrays, each read `step` floats apart (0: one value for every ray). */
typedef struct cbvhpy_rays {
    const float *org, *dir, *tmin, *tmax;
    size_t org_step, dir_step, tmin_step, tmax_step;
} cbvhpy_rays;

/* Rays a piece: the rays go to the stream a piece at a time, each piece's cbvh_ray records built into one
 * buffer reused for every piece (in the caches, where a whole batch's records would be a fresh allocation
 * written to memory and read back), and each piece's hits finished while they are still in the caches.
 * A piece holds many of the stream's octant batches, so the stream groups rays as in one call. */
#define CBVHPY_PIECE_RAYS 65536

/* The cbvh_ray records of rays first..first+count-1. */
static void cbvhpy_records(const cbvhpy_rays *r, size_t first, size_t count, cbvh_ray *records)
{
    for (size_t k = 0; k < count; k++) {
        const size_t i = first + k;
        cbvh_ray *ray = &records[k];
        memcpy(ray->org, r->org + i * r->org_step, sizeof ray->org);
        memcpy(ray->dir, r->dir + i * r->dir_step, sizeof ray->dir);
        ray->tmin = r->tmin[i * r->tmin_step];
        ray->tmax = r->tmax[i * r->tmax_step];
    }
}

/* The unit geometric normal (v1 - v0) x (v2 - v0) of the triangle with vertices v, in double, as
 * cbvh_hit_record reports it (zeros for a triangle of no area). */
static void cbvhpy_normal(const float v[9], float *n)
{
    double e1[3], e2[3];
    for (int a = 0; a < 3; a++) {
        e1[a] = (double)v[3 + a] - v[a];
        e2[a] = (double)v[6 + a] - v[a];
    }
    const double c[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
    const double length = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int a = 0; a < 3; a++)
        n[a] = length > 0 ? (float)(c[a] / length) : 0.0f;
}

/* A triangle's details as raycast returns them with each hit: its unit normal and its material id. */
typedef struct cbvhpy_details {
    float normal[3];
    uint32_t material;
} cbvhpy_details;

/* The details of triangles first..end-1 (original ids; zeros for an id the file lacks) into table[first..]. */
static void cbvhpy_details_table(const cbvh_file *file, uint32_t first, uint32_t end, cbvhpy_details *table)
{
    for (uint32_t t = first; t < end; t++) {
        float v[9];
        if (!cbvh_file_get_triangle(file, t, v, v + 3, v + 6))
            memset(v, 0, sizeof v);
        cbvhpy_normal(v, table[t].normal);
        table[t].material = cbvh_file_get_material(file, t);
    }
}

#if defined(__GNUC__) || defined(__clang__)
#define CBVHPY_PREFETCH(p) __builtin_prefetch(p)
#else
#define CBVHPY_PREFETCH(p) ((void)(p))
#endif
/* How many hits ahead the details of a hit's triangle are fetched: on a mesh larger than the caches each
 * fetch is a miss, and these overlap. */
#define CBVHPY_AHEAD 16

/* Finishes hits first..first+count-1: a miss gets t = inf, u = v = 0; normals and materials (when not NULL)
 * each hit triangle's normal and material from `table` (cbvhpy_details_table), zeros for a miss. */
static void cbvhpy_finish_hits(const cbvhpy_details *table, cbvh_hit *hits, size_t first, size_t count,
                               float *normals, uint32_t *materials)
{
    const size_t end = first + count;
    const int details = normals || materials;
    for (size_t i = first; details && i < first + CBVHPY_AHEAD && i < end; i++)
        if (hits[i].tri != CBVH_NO_HIT)
            CBVHPY_PREFETCH(&table[hits[i].tri]);
    for (size_t i = first; i < end; i++) {
        cbvh_hit *h = &hits[i];
        if (details && i + CBVHPY_AHEAD < end && hits[i + CBVHPY_AHEAD].tri != CBVH_NO_HIT)
            CBVHPY_PREFETCH(&table[hits[i + CBVHPY_AHEAD].tri]);
        if (h->tri == CBVH_NO_HIT) {
            h->t = INFINITY;
            h->u = h->v = 0.0f;
            if (normals)
                normals[3 * i] = normals[3 * i + 1] = normals[3 * i + 2] = 0.0f;
            if (materials)
                materials[i] = 0;
            continue;
        }
        if (normals)
            memcpy(normals + 3 * i, table[h->tri].normal, 3 * sizeof *normals);
        if (materials)
            materials[i] = table[h->tri].material;
    }
}

/* Rays begin..end-1 through the streams a piece at a time: their closest hits (hits given: finished by
 * cbvhpy_finish_hits) or whether they are occluded (occluded given). */
static cbvh_result cbvhpy_stream(const cbvh_file *file, const cbvhpy_rays *rays, size_t begin, size_t end,
                                 cbvh_hit *hits, const cbvhpy_details *table, float *normals, uint32_t *materials,
                                 uint8_t *occluded, void *scratch, size_t scratch_size)
{
    cbvh_ray *records = malloc(CBVHPY_PIECE_RAYS * sizeof *records);
    if (!records)
        return CBVH_ERROR_OUT_OF_MEMORY;
    for (size_t first = begin; first < end; first += CBVHPY_PIECE_RAYS) {
        const size_t count = end - first < CBVHPY_PIECE_RAYS ? end - first : CBVHPY_PIECE_RAYS;
        cbvhpy_records(rays, first, count, records);
        if (hits) {
            cbvh_raycast_stream_scratch(file, records, count, hits + first, NULL, scratch, scratch_size);
            cbvhpy_finish_hits(table, hits, first, count, normals, materials);
        } else {
            cbvh_occluded_stream_scratch(file, records, count, occluded + first, NULL, scratch, scratch_size);
        }
    }
    free(records);
    return CBVH_OK;
}

/* Closest hits of rays begin..end-1 into hits[begin..end-1] (cbvh_raycast_stream_scratch's), a miss with
 * t = inf, u = v = 0; normals and materials (when not NULL) get each hit triangle's normal and material
 * from `table`, zeros for a miss. */
static cbvh_result cbvhpy_raycast(const cbvh_file *file, const cbvhpy_rays *rays, size_t begin, size_t end,
                                  cbvh_hit *hits, const cbvhpy_details *table, float *normals, uint32_t *materials,
                                  void *scratch, size_t scratch_size)
{
    return cbvhpy_stream(file, rays, begin, end, hits, table, normals, materials, NULL, scratch, scratch_size);
}

/* Any hits of rays begin..end-1 (cbvh_occluded_stream_scratch's). */
static cbvh_result cbvhpy_occluded(const cbvh_file *file, const cbvhpy_rays *rays, size_t begin, size_t end,
                                   uint8_t *occluded, void *scratch, size_t scratch_size)
{
    return cbvhpy_stream(file, rays, begin, end, NULL, NULL, NULL, NULL, occluded, scratch, scratch_size);
}

/* cbvh_sweep_with for each shape; stops at the first error, its index in *failed. */
static cbvh_result cbvhpy_sweeps(const cbvh_file *file, const cbvh_shape *shapes, const float *deltas,
                                 size_t count, cbvh_sweep_record *records, size_t *failed)
{
    for (size_t i = 0; i < count; i++) {
        const cbvh_result r = cbvh_sweep_with(file, &shapes[i], deltas + 3 * i, NULL, &records[i]);
        if (r != CBVH_OK) {
            *failed = i;
            return r;
        }
    }
    return CBVH_OK;
}

/* Overlaps (ids != NULL) or contacts (contacts != NULL) of shapes *query.. count-1 into a buffer of
 * `capacity` records, *written of them already used; offsets[q + 1] is set as query q completes. Returns
 * when every query is done (*query == count), when the buffer is full (the caller grows it and calls again:
 * the query goes on from its *first-th triangle), or with an error at shape *query. */
static cbvh_result cbvhpy_overlaps(const cbvh_file *file, const cbvh_shape *shapes, size_t count, size_t *query,
                                   size_t *first, uint32_t *ids, cbvh_contact *contacts, size_t capacity,
                                   size_t *written, uint64_t *offsets)
{
    while (*query < count) {
        size_t n = 0;
        int more = 0;
        const cbvh_shape *s = &shapes[*query];
        const size_t room = capacity - *written;
        const cbvh_result r = ids ? cbvh_overlap_with(file, s, NULL, *first, ids + *written, room, &n, &more)
                                  : cbvh_contacts_with(file, s, NULL, *first, contacts + *written, room, &n, &more);
        if (r != CBVH_OK)
            return r;
        *written += n;
        if (more) {
            *first += n;
            return CBVH_OK;
        }
        offsets[++*query] = *written;
        *first = 0;
    }
    return CBVH_OK;
}

/* The vertices of triangles 0..count-1 (original ids), 9 floats each; zeros for an id the file lacks. */
static void cbvhpy_triangles(const cbvh_file *file, uint32_t count, float *vertices)
{
    for (uint32_t t = 0; t < count; t++) {
        float *v = vertices + 9 * (size_t)t;
        if (!cbvh_file_get_triangle(file, t, v, v + 3, v + 6))
            memset(v, 0, 9 * sizeof *v);
    }
}
"""

ffibuilder = cffi.FFI()
ffibuilder.cdef(DECLARATIONS)
ffibuilder.set_source("cbvh._native", HELPERS, **native_build.compile_args())

if __name__ == "__main__":
    native_build.build()
    ffibuilder.compile(verbose=True)
