/* shape.c: query shapes checked and taken into the mesh's frame (ball, capsule, oriented box). */
#include <string.h>

#include "query/shape.h"

/* x rounded to float; 0 when that overflows. */
static int to_float(double x, double *out)
{
    const float f = (float)x;
    *out = f;
    return isfinite(f);
}

static int v3_to_float(cbvh_v3 v, cbvh_v3 *out)
{
    return to_float(v.x, &out->x) && to_float(v.y, &out->y) && to_float(v.z, &out->z);
}

static int finite3(const float v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static void identity(double m[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            m[i][j] = i == j;
}

int cbvh_shape_to_mesh(const cbvh_shape *in, const struct cbvh_placement *p, struct cbvh_local_shape *out)
{
    memset(out, 0, sizeof *out);
    out->kind = in->kind;
    identity(out->axes);
    const double scale = p ? p->scale : 1.0;
    const float *a = in->center, *b = in->center;
    switch (in->kind) {
    case CBVH_SHAPE_CAPSULE:
        a = in->p0;
        b = in->p1;
        /* fall through */
    case CBVH_SHAPE_SPHERE:
        if (!isfinite(in->radius) || !(in->radius >= 0.0f) || !to_float(in->radius / scale, &out->radius))
            return 0;
        break;
    case CBVH_SHAPE_BOX: {
        const float *q = in->rotation, *h = in->half_extent;
        if (!finite3(h) || !(h[0] >= 0.0f && h[1] >= 0.0f && h[2] >= 0.0f) ||
            !v3_to_float(v3_scale(v3_from_f(h), 1.0 / scale), &out->half))
            return 0;
        double turn[3][3];
        const int zero = q[0] == 0.0f && q[1] == 0.0f && q[2] == 0.0f && q[3] == 0.0f;
        if (zero)
            identity(turn);
        else if (!cbvh_rotation_of_quaternion(q, turn))
            return 0;
        out->rotated = !zero || p != NULL;
        memcpy(out->axes, turn, sizeof turn);
        for (int j = 0; p && j < 3; j++) { /* column j, the box's axis j, by R^T into the mesh's frame */
            const cbvh_v3 axis = cbvh_rotate_back(p->rotation, v3(turn[0][j], turn[1][j], turn[2][j]));
            out->axes[0][j] = axis.x, out->axes[1][j] = axis.y, out->axes[2][j] = axis.z;
        }
        break;
    }
    default:
        return 0;
    }
    if (!finite3(a) || !finite3(b))
        return 0;
    const cbvh_v3 pa = p ? cbvh_point_to_mesh(p, v3_from_f(a)) : v3_from_f(a);
    const cbvh_v3 pb = p ? cbvh_point_to_mesh(p, v3_from_f(b)) : v3_from_f(b);
    return v3_to_float(pa, &out->p0) && v3_to_float(pb, &out->p1);
}

void cbvh_shape_bounds(const struct cbvh_local_shape *s, cbvh_v3 *lo, cbvh_v3 *hi)
{
    cbvh_v3 reach = v3(s->radius, s->radius, s->radius);
    if (s->kind == CBVH_SHAPE_BOX) { /* the box's corners reach |axes| * half along each mesh axis */
        const double(*m)[3] = s->axes;
        reach = v3(fabs(m[0][0]) * s->half.x + fabs(m[0][1]) * s->half.y + fabs(m[0][2]) * s->half.z,
                   fabs(m[1][0]) * s->half.x + fabs(m[1][1]) * s->half.y + fabs(m[1][2]) * s->half.z,
                   fabs(m[2][0]) * s->half.x + fabs(m[2][1]) * s->half.y + fabs(m[2][2]) * s->half.z);
        if (s->rotated) /* the rounding of the sums above, and of the axes themselves */
            reach = v3_scale(reach, 1.0 + 0x1p-40);
    }
    *lo = v3_sub(v3_min(s->p0, s->p1), reach);
    *hi = v3_add(v3_max(s->p0, s->p1), reach);
}

int cbvh_shape_is_point(const struct cbvh_local_shape *s)
{
    const int no_core = s->p0.x == s->p1.x && s->p0.y == s->p1.y && s->p0.z == s->p1.z;
    if (s->kind == CBVH_SHAPE_BOX)
        return s->half.x == 0.0 && s->half.y == 0.0 && s->half.z == 0.0;
    return no_core && s->radius == 0.0;
}
