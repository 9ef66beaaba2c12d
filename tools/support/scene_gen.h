/* scene_gen.h: deterministic generated meshes (sphere, terrain, cube, triangle soup, demo scene) for the
 * tool, benchmarks and tests. */
#ifndef CBVH_SCENE_GEN_H
#define CBVH_SCENE_GEN_H

#include <stddef.h>
#include <stdint.h>

/* A mesh owned by the generator (free with scene_free). */
typedef struct scene {
    float *positions;       /* vertex_count x 3 */
    uint32_t *indices;      /* triangle_count x 3 */
    uint32_t *material_ids; /* triangle_count, or NULL */
    size_t vertex_count;
    size_t triangle_count;
} scene;

/* Closed UV sphere (shared vertices, watertight) with at least `triangles` triangles
 * (4*s*(s-1) for the smallest s >= 2 that reaches it) of `radius` around `center`. */
int scene_sphere(scene *out, size_t triangles, const float center[3], float radius);

/* Height field over [0,size]x[0,size] in x,z with about `triangles` triangles,
 * smooth deterministic hills of height up to size/8 in y. */
int scene_terrain(scene *out, size_t triangles, float size);

/* Closed axis-aligned cube [lo, hi], 12 triangles, shared vertices. */
int scene_cube(scene *out, const float lo[3], const float hi[3]);

/* `triangles` random triangles of edge up to `max_edge` in [0,1]^3, from `seed`. */
int scene_soup(scene *out, size_t triangles, float max_edge, uint64_t seed);

/* The built-in default scene: a terrain with spheres on it, several materials. */
int scene_demo(scene *out);

/* Parses "sphere:N", "terrain:N", "cube", "soup:N", "demo" into a scene; returns 0 on a bad spec. */
int scene_from_spec(scene *out, const char *spec);

/* Appends `src` to `dst` (indices offset, materials kept or set to `material`). */
int scene_append(scene *dst, const scene *src, uint32_t material);

void scene_free(scene *s);

/* Small, fast, portable PRNG (splitmix64) so every platform generates the same scenes and rays. */
static inline uint64_t scene_rand_next(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
/* Uniform in [0,1). */
static inline double scene_rand_unit(uint64_t *state)
{
    return (double)(scene_rand_next(state) >> 11) * (1.0 / 9007199254740992.0);
}

#endif
