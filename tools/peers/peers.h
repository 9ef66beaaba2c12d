/* peers.h: a C interface to the libraries cbvh is benchmarked against (Embree 3, Bullet 3, tinybvh, Jolt
 * Physics, when configure found them; another build of cbvh, given at run time). */
#ifndef CBVH_PEERS_H
#define CBVH_PEERS_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"
#include "support/shapes.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The triangles every peer is built on: tightly packed xyz positions, 3 indices
 * per triangle. The peers keep pointers into these arrays (shared, not copied)
 * until they are destroyed. Embree reads vertices with 16-byte loads: positions
 * must stay readable for 4 bytes past the last vertex. */
typedef struct peer_mesh {
    const float *positions;
    size_t vertex_count;
    const uint32_t *indices;
    size_t triangle_count;
} peer_mesh;

/* What building a peer cost. memory_bytes counts what the peer allocated for its
 * acceleration structure; mesh_bytes the vertex and index arrays it shares with
 * the caller (which a user of that library must keep alive too). */
typedef struct peer_build_info {
    double seconds;     /* wall clock */
    double cpu_seconds; /* CPU time of the whole process (every build thread) */
    uint64_t memory_bytes;
    uint64_t mesh_bytes;
    uint64_t traversed_bytes; /* tinybvh: the blocks its queries read, within memory_bytes; other peers: 0 */
    uint64_t dropped_triangles; /* Jolt: the mesh's triangles it left out of its shape; other peers: 0 */
    uint64_t id_bytes;          /* Jolt: the part of memory_bytes holding each triangle's index; others: 0 */
} peer_build_info;

/* Include config.h before this header: HAVE_EMBREE, HAVE_BULLET, HAVE_TINYBVH, HAVE_JOLT and HAVE_DLOPEN come
 * from configure.
 *
 * Query results use cbvh's types: hits[i].tri is the triangle index in the mesh,
 * or CBVH_NO_HIT; t is in units of the ray's dir. Every ray must have a finite tmax.
 * All query functions are thread-safe on one built peer. */

#if defined(HAVE_EMBREE)
typedef struct embree_peer embree_peer;

/* Builds an Embree scene. robust selects RTC_SCENE_FLAG_ROBUST (watertight
 * triangles); threads is the build thread count (0: Embree's default).
 * Returns NULL and writes a message into err on failure. */
embree_peer *embree_peer_create(const peer_mesh *mesh, int robust, int threads, peer_build_info *info,
                                char *err, size_t err_size);
void embree_peer_destroy(embree_peer *peer);

/* Single rays (rtcIntersect1 / rtcOccluded1). */
void embree_peer_raycast(const embree_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits);
void embree_peer_occluded(const embree_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded);

/* The same rays in packets of 16 (rtcIntersect16 / rtcOccluded16), consecutive rays per packet. */
void embree_peer_raycast16(const embree_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits);
void embree_peer_occluded16(const embree_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded);
#endif

#if defined(HAVE_BULLET)
typedef struct bullet_peer bullet_peer;

/* Builds a btBvhTriangleMeshShape with quantized AABB compression over the mesh. */
bullet_peer *bullet_peer_create(const peer_mesh *mesh, peer_build_info *info, char *err, size_t err_size);
void bullet_peer_destroy(bullet_peer *peer);

/* Closest hit through performRaycast with a btTriangleRaycastCallback. */
void bullet_peer_raycast(const bullet_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits);
/* Any hit: the callback clamps the hit fraction to 0 at the first hit so every
 * later triangle is rejected at once (Bullet's walk itself cannot stop early). */
void bullet_peer_occluded(const bullet_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded);

/* Shape queries as btCollisionWorld runs them for one static triangle mesh, without the world around them:
 * a sweep is convexSweepTest's inner call, performConvexcast with a btTriangleConvexcastCallback (GJK
 * conservative advancement per triangle) keeping the smallest hit fraction; an overlap is contactTest's
 * inner loop, processAllTriangles over the shape's box with the narrow phase the dispatcher picks per
 * triangle (SphereTriangleDetector for a sphere, btGjkPairDetector with EPA for capsule and box), counting
 * the triangles at distance <= 0. Margins: btSphereShape and btCapsuleShape are their core plus a margin of
 * the radius (exact shapes); btBoxShape gets margin 0 (the default 0.04 rounds its corners in the mesh's
 * units) and the triangles margin 0, so each engine answers for the same exact shapes. */
void bullet_peer_sweep(const bullet_peer *peer, shape_kind kind, const shape_query *queries, size_t count,
                       shape_answer *out);
void bullet_peer_overlap(const bullet_peer *peer, shape_kind kind, const shape_query *queries, size_t count,
                         shape_answer *out);
/* One overlap query's triangles, each passed to add(user, tri) (in Bullet's order): what bullet_peer_overlap
 * counts, for checking its answers one triangle at a time. */
void bullet_peer_overlap_each(const bullet_peer *peer, shape_kind kind, const shape_query *query,
                              void (*add)(void *user, uint32_t tri), void *user);
#endif

#if defined(HAVE_TINYBVH)
typedef struct tinybvh_peer tinybvh_peer;

typedef enum tinybvh_layout { TINYBVH_BVH8_CPU, TINYBVH_BVH4_CPU } tinybvh_layout;

/* tinybvh was compiled for AVX2 and FMA: call none of these functions unless the CPU has both
 * (cbvh_cpu_features() has CBVH_CPU_AVX2 and CBVH_CPU_FMA).
 *
 * Builds tinybvh's BVH8_CPU or BVH4_CPU with BuildHQ (spatial splits), as tinybvh's own speed test does.
 * info->memory_bytes counts all it keeps (its traversal blocks and the trees it converted them from);
 * info->traversed_bytes the blocks alone; mesh_bytes is 0, its leaves hold copies of the triangles.
 * Returns NULL and writes a message into err on failure. */
tinybvh_peer *tinybvh_peer_create(const peer_mesh *mesh, tinybvh_layout layout, peer_build_info *info,
                                  char *err, size_t err_size);
void tinybvh_peer_destroy(tinybvh_peer *peer);

/* Single rays (Intersect / IsOccluded). tinybvh has no tmin: a ray starts at org + tmin * dir instead. */
void tinybvh_peer_raycast(const tinybvh_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits);
void tinybvh_peer_occluded(const tinybvh_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded);
#endif

#if defined(HAVE_JOLT)
typedef struct jolt_peer jolt_peer;

/* Jolt was compiled with the options of its own build: where configure defined JOLT_NEEDS_AVX2_FMA, call none
 * of these functions unless the CPU has AVX2 and FMA (cbvh_cpu_has_avx2_fma).
 *
 * Builds a MeshShape (MeshShapeSettings from the indexed triangles, each with its index as user data, as the
 * answers name triangles by it). Jolt leaves out the triangles of area below 5e-7 in the mesh's units (its
 * degenerate test, absolute) and those degenerate once quantized: info->dropped_triangles counts them. It
 * keeps its own compressed copy of the triangles: info->memory_bytes is the shape's size (GetStats),
 * mesh_bytes 0; info->id_bytes how much smaller the same shape is without the indices (built again,
 * untimed). Sets up Jolt's allocator, factory and types with the first peer and removes them with the
 * last one destroyed (create and destroy on one thread). Returns NULL and writes a message into err on
 * failure, among them a library whose build options differ from the definitions configure read
 * (JPH_VERSION_ID). */
jolt_peer *jolt_peer_create(const peer_mesh *mesh, peer_build_info *info, char *err, size_t err_size);
void jolt_peer_destroy(jolt_peer *peer);

/* Closest hit (MeshShape::CastRay, which reports back faces) and any hit (CastRay with an any-hit collector,
 * back faces on). Jolt casts the segment from org + tmin * dir to org + tmax * dir. */
void jolt_peer_raycast(const jolt_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits);
void jolt_peer_occluded(const jolt_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded);

/* Sweeps: CastShape with a closest-hit collector; overlaps: CollideShape, every triangle it reports a
 * contact with. Both with back faces colliding and every edge active; SphereShape, CapsuleShape and a
 * BoxShape of convex radius 0 (the exact box), whose every contact takes Jolt's EPA step (no core shrunk by a
 * radius for GJK), and a contact whose EPA step fails Jolt drops (its CollideConvexVsTriangles). Jolt's
 * tolerances are absolute (its collision tolerance 1e-4 in the mesh's units): on a mesh of small units they
 * are a larger share of the shapes. */
void jolt_peer_sweep(const jolt_peer *peer, shape_kind kind, const shape_query *queries, size_t count,
                     shape_answer *out);
void jolt_peer_overlap(const jolt_peer *peer, shape_kind kind, const shape_query *queries, size_t count,
                       shape_answer *out);
/* First-hit overlaps: CollideShape with an any-hit collector, which ends the query at the first contact:
 * count 1 and that triangle in tri, or count 0. */
void jolt_peer_overlap_first(const jolt_peer *peer, shape_kind kind, const shape_query *queries, size_t count,
                             shape_answer *out);
/* One overlap query's triangles, each passed to add(user, tri): what jolt_peer_overlap counts. */
void jolt_peer_overlap_each(const jolt_peer *peer, shape_kind kind, const shape_query *query,
                            void (*add)(void *user, uint32_t tri), void *user);
#endif

#if defined(HAVE_DLOPEN)
typedef struct baseline_peer baseline_peer;

/* Loads `library`, another build of libcbvh (its shared library: a build of an earlier commit, or of other
 * options), and opens the cooked file at cbvh_path with it, so that `cbvh bench --baseline` times the same
 * queries on both builds in turns; its streams run batches of stream_batch rays. Returns NULL and writes a
 * message into err when the library cannot be loaded, lacks a function of the public API the peer calls, or
 * refuses the file (a build that reads an older format). */
baseline_peer *baseline_peer_open(const char *library, const char *cbvh_path, size_t stream_batch, char *err,
                                  size_t err_size);
void baseline_peer_destroy(baseline_peer *peer);

/* The other build's sorted single rays (cbvh_raycast / cbvh_occluded) and streams
 * (cbvh_raycast_stream_scratch / cbvh_occluded_stream_scratch). */
void baseline_peer_raycast(const baseline_peer *peer, const cbvh_ray *rays, size_t count, cbvh_hit *hits);
void baseline_peer_occluded(const baseline_peer *peer, const cbvh_ray *rays, size_t count, uint8_t *occluded);
void baseline_peer_raycast_stream(const baseline_peer *peer, const cbvh_ray *rays, size_t count,
                                  cbvh_hit *hits);
void baseline_peer_occluded_stream(const baseline_peer *peer, const cbvh_ray *rays, size_t count,
                                   uint8_t *occluded);
#endif

#ifdef __cplusplus
}
#endif
#endif
