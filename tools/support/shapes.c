/* shapes.c: deterministic benchmark shape queries (sphere, capsule and box sweeps and overlaps, oriented box
 * sweeps, near a surface) from a seed. */
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
    case SHAPE_ORIENTED_BOX:
        return "oriented box";
    default:
        return "box";
    }
}

void shape_query_axes(const shape_query *q, double axes[3][3])
{
    const double x = q->rotation[0], y = q->rotation[1], z = q->rotation[2], w = q->rotation[3];
    const double m[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                            {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                            {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
    memcpy(axes, m, sizeof m);
}

/* A rotation uniform over all rotations (Shoemake's method: a uniform point on the unit 3-sphere). */
static void uniform_rotation(uint64_t *state, float q[4])
{
    const double u1 = scene_rand_unit(state), u2 = 6.283185307179586 * scene_rand_unit(state),
                 u3 = 6.283185307179586 * scene_rand_unit(state);
    const double a = sqrt(1.0 - u1), b = sqrt(u1);
    q[0] = (float)(a * sin(u2));
    q[1] = (float)(a * cos(u2));
    q[2] = (float)(b * sin(u3));
    q[3] = (float)(b * cos(u3));
}

/* What a game asks near its level geometry, scaled to the scene: a bullet or thrown object (a sphere 1% of
 * the diagonal across), a character or a ragdoll's limb (a capsule 0.6% across and 1.6% long along a uniform
 * direction), a crate or a
 * trigger volume (a box 1.0 x 0.6 x 0.8%, axis-aligned or turned by a uniform rotation). Each sits on either
 * side of a surface point along its triangle's normal: a sweep starts clear of that triangle (its extent
 * along the normal plus half a percent) and travels 1.5% in a uniform direction, so some reach the surface
 * and some pass by; an overlap's center lies up to twice its extent off, so about half of them touch. Every
 * figure is a fraction of the diagonal, the same on a 1 m mesh as on a 1 km one. */
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
        q->rotation[3] = 1.0f;
        if (kind == SHAPE_ORIENTED_BOX)
            uniform_rotation(&state, q->rotation);
        double box_axes[3][3];
        shape_query_axes(q, box_axes);
        /* how far the shape reaches along n from its center */
        double along = fabs(axis[0] * n[0] + axis[1] * n[1] + axis[2] * n[2]), box_reach = 0.0;
        for (int c = 0; c < 3; c++)
            box_reach +=
                size[c] * fabs(box_axes[0][c] * n[0] + box_axes[1][c] * n[1] + box_axes[2][c] * n[2]);
        double extent = kind == SHAPE_BOX || kind == SHAPE_ORIENTED_BOX ? box_reach
                        : kind == SHAPE_SPHERE                          ? radius
                                                                        : radius + half * along;
        double off = side * (sweep ? extent + 0.005 * diag : 2.0 * extent * jitter);
        for (int a = 0; a < 3; a++) {
            double center = p[a] + off * n[a];
            q->p0[a] = (float)(center - half * axis[a]);
            q->p1[a] = (float)(center + half * axis[a]);
            q->delta[a] = (float)(travel * motion[a]);
            q->size[a] = (float)(kind == SHAPE_BOX || kind == SHAPE_ORIENTED_BOX ? size[a]
                                 : a == 0                                        ? radius
                                                                                 : 0.0);
        }
    }
}
