/* leaf.h: testing one ray against the triangles of a leaf, for closest-hit and any-hit walks. */
#ifndef CBVH_QUERY_LEAF_H
#define CBVH_QUERY_LEAF_H

#include "common/file.h"
#include "query/ray_triangle.h"

/* The best hit so far, in cooked triangle order. */
struct cbvh_best_hit {
    uint32_t tri; /* cooked index, UINT32_MAX while there is none */
    float t, u, v;
};

/* The tie rule every ray path shares: a hit replaces the best one when it is
 * nearer, or exactly as near with a lower cooked index. It makes the result
 * independent of the order in which nodes are visited (sorted, stackless,
 * distance, streams), provided no path culls a box holding a hit at t <= tmax. */
static inline int cbvh_hit_better(float t, uint32_t tri, float best_t, uint32_t best_tri)
{
    return t < best_t || (t == best_t && tri < best_tri);
}

/* Tests the leaf's triangles [first, first+count) against the ray, updating
 * best and *tmax (the closest hit so far; hits at t == *tmax still compete by
 * index). Returns the number of triangles tested. */
static inline uint32_t cbvh_leaf_closest(const struct cbvh_file *restrict f, uint32_t word,
                                         const struct cbvh_ray_shear *restrict s, float tmin,
                                         float *restrict tmax, struct cbvh_best_hit *restrict best)
{
    const uint32_t first = cbvh_leaf_first(word), count = cbvh_leaf_count(word);
    float t, u, v, a[3], b[3], c[3];
    for (uint32_t k = first; k < first + count; k++) {
        cbvh_triangle_vertices(f, k, a, b, c);
        if (cbvh_ray_triangle(s, a, b, c, tmin, *tmax, &t, &u, &v) && cbvh_hit_better(t, k, *tmax, best->tri)) {
            *tmax = t;
            best->tri = k;
            best->t = t;
            best->u = u;
            best->v = v;
        }
    }
    return count;
}

/* Any-hit: returns 1 when a triangle of the leaf is hit; *tested receives the triangles tested. */
static inline int cbvh_leaf_any(const struct cbvh_file *restrict f, uint32_t word,
                                const struct cbvh_ray_shear *restrict s, float tmin, float tmax,
                                uint32_t *restrict tested)
{
    const uint32_t first = cbvh_leaf_first(word), count = cbvh_leaf_count(word);
    float t, u, v, a[3], b[3], c[3];
    for (uint32_t k = first; k < first + count; k++) {
        cbvh_triangle_vertices(f, k, a, b, c);
        if (cbvh_ray_triangle(s, a, b, c, tmin, tmax, &t, &u, &v)) {
            *tested = k - first + 1u;
            return 1;
        }
    }
    *tested = count;
    return 0;
}

/* The leaf step of every single-ray walk. Any-hit: returns 1 when the leaf
 * occludes the ray. Closest-hit: updates best and *tmax, returns 0. When
 * counting, adds the triangles tested to *tested. */
CBVH_KERNEL int cbvh_leaf_visit(const struct cbvh_file *restrict f, uint32_t word, const struct cbvh_ray_ctx *ray,
                                const int any, const int counting, float *restrict tmax,
                                struct cbvh_best_hit *restrict best, uint64_t *restrict tested)
{
    uint32_t count;
    int hit = 0;
    if (any)
        hit = cbvh_leaf_any(f, word, &ray->shear, ray->tmin, *tmax, &count);
    else
        count = cbvh_leaf_closest(f, word, &ray->shear, ray->tmin, tmax, best);
    if (counting)
        *tested += count;
    return hit;
}

/* Adds a walk's counters to the caller's stats. */
static inline void cbvh_stats_add(cbvh_query_stats *stats, uint64_t visited, uint64_t tested)
{
    stats->nodes_visited += visited;
    stats->triangles_tested += tested;
}

#endif
