/* scene_gen.c: deterministic generated meshes for the tool, benchmarks and tests. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene_gen.h"

static int scene_alloc(scene *s, size_t vertices, size_t triangles, int with_materials)
{
    memset(s, 0, sizeof *s);
    s->positions = malloc(vertices * 3 * sizeof(float));
    s->indices = malloc(triangles * 3 * sizeof(uint32_t));
    s->material_ids = with_materials ? calloc(triangles, sizeof(uint32_t)) : NULL;
    if (!s->positions || !s->indices || (with_materials && !s->material_ids)) {
        scene_free(s);
        return 0;
    }
    return 1;
}

void scene_free(scene *s)
{
    free(s->positions);
    free(s->indices);
    free(s->material_ids);
    memset(s, 0, sizeof *s);
}

int scene_sphere(scene *out, size_t triangles, const float center[3], float radius)
{
    /* UV sphere with slices = 2 * stacks: 2 * slices * (stacks - 1) triangles, poles shared. */
    size_t stacks = 2;
    while (4 * stacks * (stacks - 1) < triangles)
        stacks++;
    size_t slices = 2 * stacks;
    size_t nv = 2 + slices * (stacks - 1), nt = 2 * slices * (stacks - 1);
    if (!scene_alloc(out, nv, nt, 0))
        return 0;
    const double pi = 3.14159265358979323846;
    float *p = out->positions;
    for (int pole = 0; pole < 2; pole++) {
        p[3 * pole + 0] = center[0];
        p[3 * pole + 1] = center[1] + (pole ? -radius : radius);
        p[3 * pole + 2] = center[2];
    }
    for (size_t i = 1; i < stacks; i++) {
        double theta = pi * (double)i / (double)stacks;
        for (size_t j = 0; j < slices; j++) {
            double phi = 2.0 * pi * (double)j / (double)slices;
            float *q = p + 3 * (2 + (i - 1) * slices + j);
            q[0] = (float)(center[0] + radius * sin(theta) * cos(phi));
            q[1] = (float)(center[1] + radius * cos(theta));
            q[2] = (float)(center[2] + radius * sin(theta) * sin(phi));
        }
    }
    uint32_t *ix = out->indices;
    size_t f = 0;
#define RING(i, j) ((uint32_t)(2 + ((i)-1) * slices + ((j) % slices)))
    for (size_t j = 0; j < slices; j++) {
        uint32_t top[3] = {0, RING(1, j + 1), RING(1, j)};
        uint32_t bottom[3] = {1, RING(stacks - 1, j), RING(stacks - 1, j + 1)};
        memcpy(ix + 3 * f++, top, sizeof top);
        memcpy(ix + 3 * f++, bottom, sizeof bottom);
    }
    for (size_t i = 1; i + 1 < stacks; i++)
        for (size_t j = 0; j < slices; j++) {
            uint32_t q[6] = {RING(i, j),     RING(i, j + 1),     RING(i + 1, j),
                             RING(i, j + 1), RING(i + 1, j + 1), RING(i + 1, j)};
            memcpy(ix + 3 * f, q, sizeof q);
            f += 2;
        }
#undef RING
    out->vertex_count = nv;
    out->triangle_count = f;
    return 1;
}

/* Smooth hills from a few fixed sine waves: deterministic, no tables. */
static float terrain_height(double x, double z, double size)
{
    double u = x / size * 6.283185307179586, w = z / size * 6.283185307179586;
    double h = 0.5 * sin(2 * u + 0.3) * cos(3 * w) + 0.3 * sin(5 * u + 7 * w) +
               0.2 * cos(11 * u - 4 * w + 1.0) + 0.05 * sin(37 * u) * sin(41 * w);
    return (float)(h * size / 16.0 + size / 16.0);
}

int scene_terrain(scene *out, size_t triangles, float size)
{
    size_t n = 1; /* cells per side */
    while (2 * (n + 1) * (n + 1) <= triangles)
        n++;
    if (!scene_alloc(out, (n + 1) * (n + 1), 2 * n * n, 0))
        return 0;
    for (size_t j = 0; j <= n; j++)
        for (size_t i = 0; i <= n; i++) {
            float *p = out->positions + 3 * (j * (n + 1) + i);
            double x = (double)size * (double)i / (double)n, z = (double)size * (double)j / (double)n;
            p[0] = (float)x;
            p[1] = terrain_height(x, z, size);
            p[2] = (float)z;
        }
    size_t f = 0;
    for (size_t j = 0; j < n; j++)
        for (size_t i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
            uint32_t q[6] = {a, c, b, b, c, d};
            memcpy(out->indices + 3 * f, q, sizeof q);
            f += 2;
        }
    out->vertex_count = (n + 1) * (n + 1);
    out->triangle_count = f;
    return 1;
}

int scene_cube(scene *out, const float lo[3], const float hi[3])
{
    if (!scene_alloc(out, 8, 12, 0))
        return 0;
    for (uint32_t v = 0; v < 8; v++) {
        out->positions[3 * v + 0] = (v & 1) ? hi[0] : lo[0];
        out->positions[3 * v + 1] = (v & 2) ? hi[1] : lo[1];
        out->positions[3 * v + 2] = (v & 4) ? hi[2] : lo[2];
    }
    /* Outward-facing quads, split along one diagonal each. */
    static const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                         {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (int q = 0; q < 6; q++) {
        uint32_t t[6] = {quads[q][0], quads[q][1], quads[q][2], quads[q][0], quads[q][2], quads[q][3]};
        memcpy(out->indices + 6 * q, t, sizeof t);
    }
    out->vertex_count = 8;
    out->triangle_count = 12;
    return 1;
}

int scene_soup(scene *out, size_t triangles, float max_edge, uint64_t seed)
{
    if (!scene_alloc(out, 3 * triangles, triangles, 0))
        return 0;
    uint64_t st = seed;
    for (size_t t = 0; t < triangles; t++) {
        float c[3];
        for (int k = 0; k < 3; k++)
            c[k] = (float)scene_rand_unit(&st);
        for (int v = 0; v < 3; v++)
            for (int k = 0; k < 3; k++)
                out->positions[9 * t + 3 * v + k] = c[k] + max_edge * (float)(scene_rand_unit(&st) - 0.5);
        for (int v = 0; v < 3; v++)
            out->indices[3 * t + v] = (uint32_t)(3 * t + v);
    }
    out->vertex_count = 3 * triangles;
    out->triangle_count = triangles;
    return 1;
}

int scene_append(scene *dst, const scene *src, uint32_t material)
{
    size_t nv = dst->vertex_count + src->vertex_count, nt = dst->triangle_count + src->triangle_count;
    float *p = realloc(dst->positions, nv * 3 * sizeof(float));
    if (!p)
        return 0;
    dst->positions = p;
    uint32_t *ix = realloc(dst->indices, nt * 3 * sizeof(uint32_t));
    if (!ix)
        return 0;
    dst->indices = ix;
    uint32_t *m = realloc(dst->material_ids, nt * sizeof(uint32_t));
    if (!m)
        return 0;
    if (!dst->material_ids)
        memset(m, 0, dst->triangle_count * sizeof(uint32_t));
    dst->material_ids = m;
    memcpy(p + 3 * dst->vertex_count, src->positions, src->vertex_count * 3 * sizeof(float));
    for (size_t i = 0; i < 3 * src->triangle_count; i++)
        ix[3 * dst->triangle_count + i] = src->indices[i] + (uint32_t)dst->vertex_count;
    for (size_t t = 0; t < src->triangle_count; t++)
        m[dst->triangle_count + t] = src->material_ids ? src->material_ids[t] : material;
    dst->vertex_count = nv;
    dst->triangle_count = nt;
    return 1;
}

int scene_demo(scene *out)
{
    if (!scene_terrain(out, 20000, 100.0f))
        return 0;
    uint64_t st = 7;
    for (uint32_t k = 0; k < 12; k++) {
        scene ball;
        float x = 10.0f + 80.0f * (float)scene_rand_unit(&st),
              z = 10.0f + 80.0f * (float)scene_rand_unit(&st);
        float r = 2.0f + 4.0f * (float)scene_rand_unit(&st);
        float c[3] = {x, terrain_height(x, z, 100.0) + r * 0.8f, z};
        if (!scene_sphere(&ball, 2048, c, r)) {
            scene_free(out);
            return 0;
        }
        int ok = scene_append(out, &ball, 1 + k % 3);
        scene_free(&ball);
        if (!ok) {
            scene_free(out);
            return 0;
        }
    }
    return 1;
}

int scene_from_spec(scene *out, const char *spec)
{
    char *end = NULL;
    const char *colon = strchr(spec, ':');
    size_t n = 0;
    if (colon) {
        unsigned long long v = strtoull(colon + 1, &end, 10);
        if (end == colon + 1 || *end != '\0' || v == 0 || v > 100000000ull)
            return 0;
        n = (size_t)v;
    }
    size_t name_len = colon ? (size_t)(colon - spec) : strlen(spec);
    static const float origin[3] = {0, 0, 0}, unit_lo[3] = {-1, -1, -1}, unit_hi[3] = {1, 1, 1};
    if (name_len == 6 && !strncmp(spec, "sphere", 6))
        return scene_sphere(out, colon ? n : 1000000, origin, 1.0f);
    if (name_len == 7 && !strncmp(spec, "terrain", 7))
        return scene_terrain(out, colon ? n : 500000, 1000.0f);
    if (name_len == 4 && !strncmp(spec, "soup", 4))
        return scene_soup(out, colon ? n : 100000, 0.05f, 1);
    if (!colon && !strcmp(spec, "cube"))
        return scene_cube(out, unit_lo, unit_hi);
    if (!colon && !strcmp(spec, "demo"))
        return scene_demo(out);
    return 0;
}
