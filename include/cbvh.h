/* cbvh.h: the one public header of cbvh, a cooker and runtime for quantized triangle BVH files. */
#ifndef CBVH_H
#define CBVH_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Library version (the file format has its own version, CBVH_FORMAT_VERSION). */
#define CBVH_VERSION_MAJOR 0
#define CBVH_VERSION_MINOR 1
#define CBVH_VERSION_PATCH 0
#define CBVH_VERSION_STRING "0.1.0"

/* Newest file format version this library reads and the one it writes. */
#define CBVH_FORMAT_VERSION 1

#if defined(CBVH_BUILDING_LIBRARY) && defined(__GNUC__)
#define CBVH_API __attribute__((visibility("default")))
#else
#define CBVH_API
#endif

/* ------------------------------------------------------------------ */
/* Results                                                             */
/* ------------------------------------------------------------------ */

/* Result codes. 0 is success; the values never change between versions. */
typedef enum cbvh_result {
    CBVH_OK = 0,
    CBVH_ERROR_INVALID_ARGUMENT = 1, /* a caller's argument is wrong (NULL, bad option, bad ray) */
    CBVH_ERROR_OUT_OF_MEMORY = 2,    /* an allocation failed; nothing leaked */
    CBVH_ERROR_IO = 3,               /* open, read, map, write or rename failed */
    CBVH_ERROR_CORRUPT = 4,          /* the file is damaged or not a cbvh file */
    CBVH_ERROR_UNSUPPORTED = 5,      /* the file is valid but newer: version, flag, codec or encoding unknown */
    CBVH_ERROR_BAD_MESH = 6,         /* the input mesh is unusable: NaN/inf coordinate, index out of range */
    CBVH_ERROR_EMPTY_MESH = 7,       /* no triangle left to build from (none given, or all degenerate) */
    CBVH_ERROR_LIMIT = 8             /* the input exceeds a format limit (see fileformat/cbvh-format.md) */
} cbvh_result;

/* A short, static, English description of a result code; never NULL. */
CBVH_API const char *cbvh_result_string(cbvh_result result);

/* Detailed error: the code plus a message saying what is wrong and where
 * (for files: section, node or byte offset; for meshes: triangle or vertex).
 * Every function that takes a cbvh_error* accepts NULL there. */
typedef struct cbvh_error {
    cbvh_result code;
    char message[256];
} cbvh_error;

/* ------------------------------------------------------------------ */
/* Memory                                                              */
/* ------------------------------------------------------------------ */

/* Allocator hooks. alloc returns memory aligned to at least `align` (a power
 * of two, at most 64) or NULL; free accepts what alloc returned. Pass NULL
 * wherever a cbvh_allocator* is taken to use the C library's allocator.
 * Every allocation cbvh makes goes through these hooks. */
typedef struct cbvh_allocator {
    void *(*alloc)(void *user, size_t size, size_t align);
    void (*free)(void *user, void *ptr);
    void *user;
} cbvh_allocator;

/* ------------------------------------------------------------------ */
/* Cooking (offline)                                                   */
/* ------------------------------------------------------------------ */

/* An indexed triangle mesh. positions: vertex_count xyz triples, `position_stride`
 * bytes apart (0 means 12, tightly packed floats). indices: 3 per triangle.
 * material_ids: one per triangle, or NULL. The cooker reads but never keeps
 * these arrays. */
typedef struct cbvh_mesh {
    const float *positions;
    size_t vertex_count;
    size_t position_stride;
    const uint32_t *indices;
    size_t triangle_count;
    const uint32_t *material_ids;
} cbvh_mesh;

typedef enum cbvh_vertex_format {
    CBVH_VERTEX_FLOAT32 = 0,    /* lossless (default) */
    CBVH_VERTEX_QUANTIZED16 = 1 /* 16 bits per coordinate on the mesh grid: lossy, error reported */
} cbvh_vertex_format;

/* Cook phases, for progress reports. */
typedef enum cbvh_phase {
    CBVH_PHASE_PREPARE = 0, /* validate, weld and drop degenerate triangles */
    CBVH_PHASE_BUILD = 1,   /* SAH build */
    CBVH_PHASE_LAYOUT = 2,  /* quantize, sort bytes, reorder */
    CBVH_PHASE_WRITE = 3    /* encode, compress, checksum */
} cbvh_phase;

/* Called from the cooking thread with a fraction in [0,1] of the given phase. */
typedef void (*cbvh_progress_fn)(void *user, cbvh_phase phase, double fraction);

/* Default SAH costs: traversal 4, intersection 1, leaves of up to 16 triangles.
 * A node visit on a large mesh is a dependent cache miss while a leaf's
 * triangles are read together, so a node costs several triangle tests.
 * Measured (incoherent closest-hit MRays/s, sorted, 100K rays, CPU time) against
 * the former 1 / 1 / 4: Stanford dragon (871K) 35.6 -> 23.8 bytes/triangle,
 * 1.22 -> 1.48 MRays/s (1.8 -> 5.6 triangles per leaf); 1M sphere 33.8 -> 23.7
 * bytes/triangle, 0.76 -> 1.12 MRays/s; coherent rays unchanged or faster.
 * Traversal cost 2, 3 and 6 and leaf sizes 4 and 8 were slower or larger. */
typedef struct cbvh_cook_options {
    uint32_t max_leaf_size;        /* 1..16 triangles per leaf; default 16 */
    uint32_t sah_bins;             /* 4..256 bins per axis; default 32 */
    float traversal_cost;          /* SAH cost of visiting a node; default 4.0 */
    float intersection_cost;       /* SAH cost of one triangle test; default 1.0 */
    cbvh_vertex_format vertex_format;
    int compress_level;            /* 0 = raw sections (default), 1..9 = zlib level */
    int keep_remap;                /* 1 (default): keep original triangle ids; 0: queries report cooked order */
    int keep_materials;            /* 1 (default): store material ids when they are not all equal */
    cbvh_progress_fn progress;     /* optional */
    void *progress_user;
} cbvh_cook_options;

/* Fills `options` with the defaults above. */
CBVH_API void cbvh_cook_options_init(cbvh_cook_options *options);

/* What a cook did. Sizes are stored bytes in the file (after compression). */
typedef struct cbvh_cook_stats {
    uint64_t input_triangles;
    uint64_t input_vertices;
    uint64_t dropped_degenerate;   /* zero-area triangles removed (documented, never hit), including those
                                    * that quantized vertices collapsed to zero area */
    uint64_t triangles;            /* triangles in the file */
    uint64_t vertices;             /* vertices in the file after welding equal positions */
    uint64_t nodes;
    uint64_t leaves;
    uint32_t depth;                /* nodes on the longest root-to-leaf path */
    double sah_cost;               /* of the quantized tree, relative to the root's area, unit costs */
    double vertex_max_error;       /* worst |decoded - input| over all coordinates (0 when lossless) */
    uint64_t file_size;
    uint64_t section_stored_size[6]; /* indexed by cbvh_section_type, 0 when absent */
    uint64_t section_size[6];        /* uncompressed */
    double seconds[4];             /* per cbvh_phase */
} cbvh_cook_stats;

/* Cooks `mesh` into a complete cbvh file in memory. On success *out_data (allocated
 * with `allocator`, free it with cbvh_buffer_free) and *out_size hold the file.
 * Deterministic: the same mesh and options give the same bytes.
 * Returns CBVH_OK, or an error with `err` naming the triangle or vertex at fault.
 * The mesh is caller input and may hold anything: NaN, huge values, bad indices. */
CBVH_API cbvh_result cbvh_cook(const cbvh_mesh *mesh, const cbvh_cook_options *options,
                               const cbvh_allocator *allocator, void **out_data, size_t *out_size,
                               cbvh_cook_stats *stats, cbvh_error *err);

/* As cbvh_cook, then writes the file to `path` through a temporary file in the
 * same folder renamed into place: an existing file at `path` is replaced only
 * by a complete new one, and no partial file is left behind on failure. */
CBVH_API cbvh_result cbvh_cook_to_path(const cbvh_mesh *mesh, const cbvh_cook_options *options,
                                       const cbvh_allocator *allocator, const char *path,
                                       cbvh_cook_stats *stats, cbvh_error *err);

/* Frees a buffer returned by cbvh_cook. NULL is allowed. */
CBVH_API void cbvh_buffer_free(const cbvh_allocator *allocator, void *data);

/* ------------------------------------------------------------------ */
/* Loading (runtime)                                                   */
/* ------------------------------------------------------------------ */

/* An opened, fully validated cbvh file. Immutable after opening: any number
 * of threads may query one cbvh_file at once, without locks. */
typedef struct cbvh_file cbvh_file;

/* Opens the file at `path`: maps it read-only and validates everything once
 * (header, CRCs, section bounds, every node, leaf and index). Raw sections are
 * used in place from the mapping; zlib sections are inflated into memory
 * owned by the file. Safe on untrusted files. */
CBVH_API cbvh_result cbvh_open_path(const char *path, const cbvh_allocator *allocator,
                                    cbvh_file **out_file, cbvh_error *err);

/* Opens a file held in the caller's buffer, which must stay valid and unchanged
 * until cbvh_close (raw sections are used in place, zero copy, when the buffer
 * is at least 4-byte aligned; otherwise they are copied). Safe on untrusted bytes. */
CBVH_API cbvh_result cbvh_open_memory(const void *data, size_t size, const cbvh_allocator *allocator,
                                      cbvh_file **out_file, cbvh_error *err);

/* Releases everything the file owns. NULL is allowed. */
CBVH_API void cbvh_close(cbvh_file *file);

typedef enum cbvh_section_type {
    CBVH_SECTION_NODES = 1,
    CBVH_SECTION_TRIANGLES = 2,
    CBVH_SECTION_VERTICES = 3,
    CBVH_SECTION_REMAP = 4,
    CBVH_SECTION_MATERIALS = 5
} cbvh_section_type;

typedef struct cbvh_section_info {
    uint32_t type;      /* cbvh_section_type, or an unknown ancillary type (bit 31 set) */
    uint32_t codec;     /* 0 raw, 1 zlib */
    uint32_t encoding;  /* element encoding, see fileformat/cbvh-format.md */
    uint32_t crc32;
    uint64_t offset;
    uint64_t stored_size;
    uint64_t size;
} cbvh_section_info;

typedef struct cbvh_file_info {
    uint32_t format_version;
    uint32_t compat_flags;
    uint32_t incompat_flags;
    uint32_t section_count;
    uint32_t triangle_count;
    uint32_t vertex_count;
    uint32_t node_count;
    uint32_t depth;
    uint32_t max_leaf_size;
    uint32_t has_remap;
    uint32_t has_materials;
    uint32_t vertex_format;       /* cbvh_vertex_format */
    uint32_t index_encoding;      /* triangle section encoding */
    uint64_t file_size;
    float bounds_min[3], bounds_max[3];
    float grid_origin[3], grid_scale[3];
} cbvh_file_info;

CBVH_API void cbvh_file_get_info(const cbvh_file *file, cbvh_file_info *info);

/* Describes section `index` (0 <= index < section_count); returns 0 when out of range. */
CBVH_API int cbvh_file_get_section(const cbvh_file *file, uint32_t index, cbvh_section_info *section);

/* The three vertices of triangle `tri` (an original id, as queries report it),
 * decoded as the queries see them. Returns 0 if tri is out of range. */
CBVH_API int cbvh_file_get_triangle(const cbvh_file *file, uint32_t tri, float v0[3], float v1[3], float v2[3]);

/* Material id of triangle `tri` (original id); 0 when the file stores none. */
CBVH_API uint32_t cbvh_file_get_material(const cbvh_file *file, uint32_t tri);

/* ------------------------------------------------------------------ */
/* Queries (runtime). None allocates memory; all are thread-safe.      */
/* ------------------------------------------------------------------ */

/* A ray: points org + t*dir for t in [tmin, tmax]. dir need not be normalized;
 * components may be 0, -0 or denormal. A ray is invalid, and every query
 * reports a miss for it, when a component is NaN or infinite (tmax may be
 * +infinity), when dir is all zero, when tmin < 0 or when tmin > tmax. */
typedef struct cbvh_ray {
    float org[3];
    float tmin;
    float dir[3];
    float tmax;
} cbvh_ray;

#define CBVH_NO_HIT 0xFFFFFFFFu

/* A hit: original triangle id (CBVH_NO_HIT for a miss), distance t along the
 * ray (in units of dir), barycentrics u, v of the point (1-u-v)*v0 + u*v1 + v*v2. */
typedef struct cbvh_hit {
    uint32_t tri;
    float t;
    float u;
    float v;
} cbvh_hit;

typedef enum cbvh_traversal {
    CBVH_TRAVERSAL_SORTED = 0,    /* stack, nearer child by the precomputed sort byte (default) */
    CBVH_TRAVERSAL_STACKLESS = 1, /* escape links, fixed depth-first order, no stack */
    CBVH_TRAVERSAL_UNSORTED = 2,  /* stack, always the first child first (for comparison) */
    CBVH_TRAVERSAL_DISTANCE = 3   /* stack, nearer child chosen at run time by box distance (for comparison) */
} cbvh_traversal;

/* Work counters, for benchmarks and reports. */
typedef struct cbvh_query_stats {
    uint64_t nodes_visited;   /* node boxes tested */
    uint64_t triangles_tested;
} cbvh_query_stats;

/* Closest hit. Returns 1 and fills *hit on a hit, else returns 0 and sets hit->tri
 * to CBVH_NO_HIT. `stats` may be NULL; when given, counters are added to it.
 * Ties: when several triangles are hit at exactly the same t, the one first in
 * the file's cooked (leaf) order wins, so every traversal and the streams
 * report the same triangle, t, u and v for a ray. The hit/miss decision is
 * watertight (a ray through a shared edge or vertex hits one of its triangles);
 * t is computed from the triangle's plane and u, v from the hit point, in
 * double precision, accurate on slivers and for any finite coordinates. t is capped: tmax is clamped to about
 * 1.7e38 (FLT_MAX / 2), hits beyond it are misses. An origin far from the mesh
 * (more than 16 times its extent) is moved along the ray next to it first, so
 * rays from 1e20 away still hit a unit mesh; t is reported on the caller's ray.
 * A ray whose origin lies more than FLT_MAX from some node box plane (possible
 * only when some coordinate is past FLT_MAX / 2, 1.7e38) is walked by the sorted traversal
 * whatever `traversal` says, with the box test at half scale so nothing
 * overflows: the answer is the same, the stats are the sorted walk's. */
CBVH_API int cbvh_raycast(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal,
                          cbvh_hit *hit, cbvh_query_stats *stats);

/* Any hit (occlusion): returns 1 as soon as any triangle is hit in [tmin, tmax]. */
CBVH_API int cbvh_occluded(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal,
                           cbvh_query_stats *stats);

/* Batched streams: `count` rays (any coherence) traversed together, each node
 * dequantized once per batch visit, live rays partitioned in place. Results
 * equal cbvh_raycast / cbvh_occluded ray by ray. hits[i] (occluded[i]: 0 or 1)
 * receives ray i's result. Uses no heap memory: rays are processed in chunks. */
CBVH_API void cbvh_raycast_stream(const cbvh_file *file, const cbvh_ray *rays, size_t count,
                                  cbvh_hit *hits, cbvh_query_stats *stats);
CBVH_API void cbvh_occluded_stream(const cbvh_file *file, const cbvh_ray *rays, size_t count,
                                   uint8_t *occluded, cbvh_query_stats *stats);

/* Result of a sweep: the first contact along the motion. t in [0,1] is the
 * fraction of `delta` travelled; point is the contact point on the triangle
 * and normal the unit contact normal pointing from the triangle towards the
 * moving shape. Ties at equal t go to the triangle first in cooked order.
 * A shape that overlaps a triangle at the start reports t = 0 with point the
 * triangle's point nearest the shape (sphere: nearest its center) and normal
 * from that point towards the shape; when they touch with no separating
 * direction (the center, axis or box reaches into the triangle) the normal is
 * the face normal turned against delta (as wound when delta is zero or
 * parallel to the face; -delta or +z for a zero-area triangle). */
typedef struct cbvh_sweep_hit {
    uint32_t tri;
    float t;
    float point[3];
    float normal[3];
} cbvh_sweep_hit;

/* Sweeps a sphere from `center` to `center + delta`. Returns 1 on contact. radius >= 0
 * (radius 0 is a raycast). Invalid input (NaN, inf, negative radius) is a miss.
 * Zero-size shapes (radius 0; a capsule with radius 0 and p0 == p1; a box with
 * zero half extents) are the ray center + t*delta, t in [0, 1], answered by
 * cbvh_raycast's kernel (same triangle and t), normal the face normal against
 * delta; with delta zero as well that ray is invalid and the sweep is a miss,
 * even for a point lying on a triangle. A shape of non-zero size with zero delta
 * reports t = 0 for what it overlaps, else a miss. */
CBVH_API int cbvh_sweep_sphere(const cbvh_file *file, const float center[3], float radius,
                               const float delta[3], cbvh_sweep_hit *hit);

/* Sweeps a capsule (segment p0-p1, radius) by `delta`. */
CBVH_API int cbvh_sweep_capsule(const cbvh_file *file, const float p0[3], const float p1[3], float radius,
                                const float delta[3], cbvh_sweep_hit *hit);

/* Sweeps an axis-aligned box (center, half extents >= 0) by `delta`. */
CBVH_API int cbvh_sweep_box(const cbvh_file *file, const float center[3], const float half_extent[3],
                            const float delta[3], cbvh_sweep_hit *hit);

/* Overlap callback: called once per overlapping triangle (original id);
 * return nonzero to stop the query early. */
typedef int (*cbvh_overlap_fn)(void *user, uint32_t tri);

/* All triangles that intersect the closed box [box_min, box_max] (exact
 * triangle/box test). Each is reported to `callback` (if not NULL) and written
 * to `out` (if not NULL) while fewer than `capacity` were written; the query
 * stops early when the callback returns nonzero or `out` is full.
 * Returns the number of triangles reported. Invalid input reports none. */
CBVH_API size_t cbvh_overlap_box(const cbvh_file *file, const float box_min[3], const float box_max[3],
                                 cbvh_overlap_fn callback, void *user, uint32_t *out, size_t capacity);

/* The same for the closed ball of `radius` around `center` (exact triangle/sphere test). */
CBVH_API size_t cbvh_overlap_sphere(const cbvh_file *file, const float center[3], float radius,
                                    cbvh_overlap_fn callback, void *user, uint32_t *out, size_t capacity);

#ifdef __cplusplus
}
#endif
#endif /* CBVH_H */
