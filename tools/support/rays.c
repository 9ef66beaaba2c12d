/* rays.c: deterministic benchmark ray sets (incoherent, coherent camera tiles, shadow rays, short probes)
 * from a seed. */
#include <math.h>

#include "rays.h"
#include "scene_gen.h"

#define TILE 8

const char *rays_kind_name(ray_kind kind)
{
    switch (kind) {
    case RAYS_INCOHERENT:
        return "incoherent";
    case RAYS_COHERENT:
        return "coherent";
    case RAYS_SHORT:
        return "short";
    default:
        return "shadow";
    }
}

double rays_mesh_bounds(const rays_mesh *mesh, float lo[3], float hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    const float *restrict p = mesh->positions;
    const uint32_t *restrict ix = mesh->indices;
    size_t n = 3 * mesh->triangle_count;
    for (size_t i = 0; i < n; i++) {
        const float *v = p + 3 * (size_t)ix[i];
        for (int a = 0; a < 3; a++) {
            lo[a] = fminf(lo[a], v[a]);
            hi[a] = fmaxf(hi[a], v[a]);
        }
    }
    if (n == 0)
        for (int a = 0; a < 3; a++)
            lo[a] = hi[a] = 0.0f;
    double d2 = 0.0;
    for (int a = 0; a < 3; a++)
        d2 += ((double)hi[a] - lo[a]) * ((double)hi[a] - lo[a]);
    return sqrt(d2);
}

/* Archimedes: z uniform in [-1,1], angle uniform. */
void rays_unit_direction(uint64_t *state, float dir[3])
{
    double z = 2.0 * scene_rand_unit(state) - 1.0;
    double phi = 6.283185307179586 * scene_rand_unit(state);
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    dir[0] = (float)(r * cos(phi));
    dir[1] = (float)(r * sin(phi));
    dir[2] = (float)z;
}

static void incoherent(const float lo[3], const float hi[3], double diag, uint64_t *state, cbvh_ray *out,
                       size_t count)
{
    /* From inside the bounds every hit lies within one diagonal. */
    float tmax = (float)(diag * 1.001) + 1e-6f;
    for (size_t i = 0; i < count; i++) {
        cbvh_ray *r = &out[i];
        for (int a = 0; a < 3; a++)
            r->org[a] = (float)(lo[a] + ((double)hi[a] - lo[a]) * scene_rand_unit(state));
        rays_unit_direction(state, r->dir);
        r->tmin = 0.0f;
        r->tmax = tmax;
    }
}

/* A camera on a fixed diagonal, far enough that the bounding sphere fills the
 * image; pixels are issued tile by tile so neighbouring rays stay together. */
static void coherent(const float lo[3], const float hi[3], double diag, uint64_t *state, cbvh_ray *out,
                     size_t count)
{
    double center[3], eye[3], fwd[3], right[3], up[3];
    const double view[3] = {0.48, 0.42, 0.77}; /* roughly unit, off every axis */
    double radius = 0.5 * diag + 1e-6, dist = 3.0 * radius;
    double vn = sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
    for (int a = 0; a < 3; a++) {
        center[a] = 0.5 * ((double)lo[a] + hi[a]);
        eye[a] = center[a] + dist * view[a] / vn;
        fwd[a] = -view[a] / vn;
    }
    /* right = fwd x (0,1,0), up = right x fwd. */
    right[0] = -fwd[2];
    right[1] = 0.0;
    right[2] = fwd[0];
    double rn = sqrt(right[0] * right[0] + right[2] * right[2]);
    for (int a = 0; a < 3; a++)
        right[a] /= rn;
    up[0] = right[1] * fwd[2] - right[2] * fwd[1];
    up[1] = right[2] * fwd[0] - right[0] * fwd[2];
    up[2] = right[0] * fwd[1] - right[1] * fwd[0];
    double half = radius / sqrt(dist * dist - radius * radius); /* tan of the half angle */

    size_t side = TILE;
    while (side * side < count)
        side += TILE;
    size_t tiles_per_row = side / TILE, n = 0;
    float tmax = (float)(dist + radius + 1e-6) * 1.001f;
    for (size_t tile = 0; n < count; tile++) {
        size_t tx = (tile % tiles_per_row) * TILE, ty = (tile / tiles_per_row) * TILE;
        for (size_t k = 0; k < TILE * TILE && n < count; k++) {
            double px = ((double)(tx + k % TILE) + scene_rand_unit(state)) / (double)side;
            double py = ((double)(ty + k / TILE) + scene_rand_unit(state)) / (double)side;
            double sx = (2.0 * px - 1.0) * half, sy = (1.0 - 2.0 * py) * half;
            cbvh_ray *r = &out[n++];
            double d[3], len = 0.0;
            for (int a = 0; a < 3; a++) {
                d[a] = fwd[a] + sx * right[a] + sy * up[a];
                len += d[a] * d[a];
            }
            len = sqrt(len);
            for (int a = 0; a < 3; a++) {
                r->org[a] = (float)eye[a];
                r->dir[a] = (float)(d[a] / len);
            }
            r->tmin = 0.0f;
            r->tmax = tmax;
        }
    }
}

void rays_surface_point(const rays_mesh *mesh, uint64_t *state, double p[3], double normal[3])
{
    size_t tri = (size_t)(scene_rand_unit(state) * (double)mesh->triangle_count);
    const uint32_t *ix = mesh->indices + 3 * tri;
    const float *v0 = mesh->positions + 3 * (size_t)ix[0];
    const float *v1 = mesh->positions + 3 * (size_t)ix[1];
    const float *v2 = mesh->positions + 3 * (size_t)ix[2];
    double b1 = scene_rand_unit(state), b2 = scene_rand_unit(state);
    if (b1 + b2 > 1.0) {
        b1 = 1.0 - b1;
        b2 = 1.0 - b2;
    }
    for (int a = 0; a < 3; a++)
        p[a] = (1.0 - b1 - b2) * v0[a] + b1 * v1[a] + b2 * v2[a];
    if (!normal)
        return;
    double e1[3], e2[3];
    for (int a = 0; a < 3; a++) {
        e1[a] = (double)v1[a] - v0[a];
        e2[a] = (double)v2[a] - v0[a];
    }
    normal[0] = e1[1] * e2[2] - e1[2] * e2[1];
    normal[1] = e1[2] * e2[0] - e1[0] * e2[2];
    normal[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double len = sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2]);
    for (int a = 0; a < 3; a++)
        normal[a] = len > 0.0 ? normal[a] / len : a == 2; /* a zero-area triangle: +z */
}

/* What games cast most (ground probes, bullet traces, line of sight): from a point half a percent of the
 * diagonal off a surface point, on either side, in a uniform direction, one percent of the diagonal long. */
static void short_rays(const rays_mesh *mesh, double diag, uint64_t *state, cbvh_ray *out, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        double p[3];
        float off[3];
        rays_surface_point(mesh, state, p, NULL);
        rays_unit_direction(state, off);
        cbvh_ray *r = &out[i];
        for (int a = 0; a < 3; a++)
            r->org[a] = (float)(p[a] + 0.005 * diag * off[a]);
        rays_unit_direction(state, r->dir);
        r->tmin = 0.0f;
        r->tmax = (float)(0.01 * diag);
    }
}

/* Points on triangles picked uniformly by index, towards a light outside the
 * bounds. tmin skips the triangle the ray starts on; tmax stops just before the light. */
static void shadow(const rays_mesh *mesh, const float lo[3], const float hi[3], double diag, uint64_t *state,
                   cbvh_ray *out, size_t count)
{
    const double toward[3] = {0.3, 0.9, 0.3};
    double tn = sqrt(toward[0] * toward[0] + toward[1] * toward[1] + toward[2] * toward[2]);
    double light[3];
    for (int a = 0; a < 3; a++)
        light[a] = 0.5 * ((double)lo[a] + hi[a]) + diag * toward[a] / tn;
    for (size_t i = 0; i < count; i++) {
        double p[3];
        rays_surface_point(mesh, state, p, NULL);
        cbvh_ray *r = &out[i];
        double len2 = 0.0;
        for (int a = 0; a < 3; a++) {
            r->org[a] = (float)p[a];
            r->dir[a] = (float)(light[a] - r->org[a]);
            len2 += (double)r->dir[a] * r->dir[a];
        }
        r->tmin = (float)(1e-4 * diag / sqrt(len2));
        r->tmax = 0.9999f;
    }
}

void rays_generate(ray_kind kind, const rays_mesh *mesh, uint64_t seed, cbvh_ray *out, size_t count)
{
    float lo[3], hi[3];
    double diag = rays_mesh_bounds(mesh, lo, hi);
    /* One stream per kind so the sets do not depend on one another. */
    uint64_t state = seed ^ (0xA0761D6478BD642Full * (uint64_t)(kind + 1));
    switch (kind) {
    case RAYS_INCOHERENT:
        incoherent(lo, hi, diag, &state, out, count);
        break;
    case RAYS_COHERENT:
        coherent(lo, hi, diag, &state, out, count);
        break;
    case RAYS_SHORT:
        short_rays(mesh, diag, &state, out, count);
        break;
    default:
        shadow(mesh, lo, hi, diag, &state, out, count);
        break;
    }
}
