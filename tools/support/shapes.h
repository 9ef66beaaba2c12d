/* shapes.h: deterministic benchmark shape queries (sphere, capsule and box sweeps and overlaps, oriented box
 * sweeps, near a surface) from a seed. */
#ifndef CBVH_SHAPES_H
#define CBVH_SHAPES_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"
#include "rays.h"

typedef enum shape_kind {
    SHAPE_SPHERE = 0,
    SHAPE_CAPSULE = 1,
    SHAPE_BOX = 2,
    SHAPE_ORIENTED_BOX = 3
} shape_kind;
/* Sweeps come in every kind, overlaps in the first three (the reference judges axis-aligned boxes only). */
#define SHAPE_SWEEP_KIND_COUNT 4
#define SHAPE_OVERLAP_KIND_COUNT 3

/* "sphere", "capsule", "box", "oriented box". */
const char *shape_kind_name(shape_kind kind);

/* One query: the shape where it starts and, for a sweep, its motion (zero for an overlap). */
typedef struct shape_query {
    float p0[3];       /* sphere or box center; the capsule segment's first end */
    float p1[3];       /* the capsule segment's second end (the center again for sphere and box) */
    float size[3];     /* sphere and capsule: radius in size[0]; box: half extents along its own axes */
    float delta[3];    /* sweeps: from p0 (and p1) to p0 + delta */
    float rotation[4]; /* oriented box: the unit quaternion (x, y, z, w) turning its axes; other kinds 0 0 0 1
                        */
} shape_query;

/* The box's unit axes turned by q->rotation: the columns of axes. */
void shape_query_axes(const shape_query *q, double axes[3][3]);

/* A query's answer, whoever gave it: a sweep's first contact (tri, or CBVH_NO_HIT, and t in [0, 1] of delta),
 * or an overlap's set of triangles (how many, and a sum of their mixed ids that does not depend on order). */
typedef struct shape_answer {
    uint32_t tri;
    float t;
    uint32_t count;
    uint64_t set_hash;
} shape_answer;

/* Adds triangle `tri` to an overlap's set. */
static inline void shape_answer_add(shape_answer *a, uint32_t tri)
{
    uint64_t x =
        ((uint64_t)tri + 1) * 0x9E3779B97F4A7C15ull; /* splitmix64's finalizer: one bit of tri moves all 64 */
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    a->count++;
    a->set_hash += x ^ (x >> 31);
}

/* shape_answer_add as an engine's per-triangle callback (user: the answer). */
static inline void shape_answer_add_to(void *answer, uint32_t tri)
{
    shape_answer_add((shape_answer *)answer, tri);
}

/* An engine's triangles of one overlap query, each passed to add(user, tri). */
typedef void (*shape_overlap_each_fn)(const void *engine, shape_kind kind, const shape_query *query,
                                      void (*add)(void *user, uint32_t tri), void *user);

/* The answers of count overlap queries from an engine's `each`: every answer's set of its triangles. */
static inline void shape_answers_from_each(const void *engine, shape_overlap_each_fn each, shape_kind kind,
                                           const shape_query *queries, size_t count, shape_answer *out)
{
    for (size_t i = 0; i < count; i++) {
        out[i].tri = CBVH_NO_HIT;
        out[i].t = INFINITY;
        out[i].count = 0;
        out[i].set_hash = 0;
        each(engine, kind, &queries[i], shape_answer_add_to, &out[i]);
    }
}

/* Fills out[0..count) with sweeps (sweep nonzero) or overlaps of shape `kind` (an oriented box: sweeps only)
 * near `mesh`'s surface, the same
 * for the same seed on every platform: shapes about 1% of the bounds' diagonal across, off a surface point
 * along its normal; sweeps start clear of that triangle and move 1.5% of the diagonal in a uniform direction.
 * Precondition: mesh->triangle_count > 0. */
void shapes_generate(shape_kind kind, int sweep, const rays_mesh *mesh, uint64_t seed, shape_query *out,
                     size_t count);

#endif
