/* shapes.c: deterministic benchmark shape queries (sphere, capsule and box sweeps and overlaps near a
 * surface) from a seed. */
#include <math.h>
#include <string.h>

#include "scene_gen.h"
#include "shapes.h"

const char *shape_kind_name(shape_kind kind)
{
    switch (kind) {
    case SHAPE_SPHERE:
        return "sphere";
    case SHAPE_CAPSULE:
        return "capsule";
    default:
        return "box";
    }
}

/* What a game asks near its level geometry, scaled to the scene: a bullet or thrown object (a sphere 1% of
 * the diagonal across), a character or a ragdoll's limb (a capsule 0.6% across and 1.6% long along a uniform
 * direction), a crate or a
 * trigger volume (a box 1.0 x 0.6 x 0.8%). Each sits on either side of a surface point along its triangle's
 * normal: a sweep starts clear of that triangle (its extent along the normal plus half a percent) and travels
 * 1.5% in a uniform direction, so some reach the surface and some pass by; an overlap's center lies up to
 * twice its extent off, so about half of them touch. Every figure is a fraction of the diagonal, the same on
 * a 1 m mesh as on a 1 km one. */
void shapes_generate(shape_kind kind, int sweep, const rays_mesh *mesh, uint64_t seed, shape_query *out,
                     size_t count)
{
    float lo[3], hi[3];
    double diag = rays_mesh_bounds(mesh, lo, hi);
    double travel = sweep ? 0.015 * diag : 0.0;
    double size[3] = {0.005 * diag, 0.003 * diag, 0.004 * diag},
           radius = kind == SHAPE_SPHERE ? 0.005 * diag : 0.003 * diag;
    double half = kind == SHAPE_CAPSULE ? 0.005 * diag : 0.0; /* half the capsule's segment */
    /* One stream per kind and query, apart from the ray sets' streams. */
    uint64_t state = seed ^ (0x9E3779B97F4A7C15ull * (uint64_t)(2 * kind + sweep + 17));
    for (size_t i = 0; i < count; i++) {
        shape_query *q = &out[i];
        memset(q, 0, sizeof *q);
        double p[3], n[3];
        float motion[3], axis[3] = {0.0f, 1.0f, 0.0f};
        rays_surface_point(mesh, &state, p, n);
        double side = scene_rand_unit(&state) < 0.5 ? -1.0 : 1.0, jitter = scene_rand_unit(&state);
        rays_unit_direction(&state, motion);
        if (kind == SHAPE_CAPSULE) /* drawn after the others, so the sphere and box sets keep their streams */
            rays_unit_direction(&state, axis);
        /* how far the shape reaches along n from its center */
        double along = fabs(axis[0] * n[0] + axis[1] * n[1] + axis[2] * n[2]);
        double extent = kind == SHAPE_BOX ? size[0] * fabs(n[0]) + size[1] * fabs(n[1]) + size[2] * fabs(n[2])
                        : kind == SHAPE_SPHERE ? radius
                                               : radius + half * along;
        double off = side * (sweep ? extent + 0.005 * diag : 2.0 * extent * jitter);
        for (int a = 0; a < 3; a++) {
            double center = p[a] + off * n[a];
            q->p0[a] = (float)(center - half * axis[a]);
            q->p1[a] = (float)(center + half * axis[a]);
            q->delta[a] = (float)(travel * motion[a]);
            q->size[a] = (float)(kind == SHAPE_BOX ? size[a] : a == 0 ? radius : 0.0);
        }
    }
}
