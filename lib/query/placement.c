/* placement.c: query transforms (cbvh_transform) checked and turned into rotation matrices. */
#include "query/placement.h"

int cbvh_rotation_of_quaternion(const float q[4], double m[3][3])
{
    double len2 = 0.0;
    for (int i = 0; i < 4; i++) {
        if (!isfinite(q[i]))
            return 0;
        len2 += (double)q[i] * q[i];
    }
    if (!(len2 > 0.0) || !isfinite(len2))
        return 0;
    const double x = q[0], y = q[1], z = q[2], w = q[3], k = 2.0 / len2;
    m[0][0] = 1.0 - k * (y * y + z * z), m[0][1] = k * (x * y - z * w), m[0][2] = k * (x * z + y * w);
    m[1][0] = k * (x * y + z * w), m[1][1] = 1.0 - k * (x * x + z * z), m[1][2] = k * (y * z - x * w);
    m[2][0] = k * (x * z - y * w), m[2][1] = k * (y * z + x * w), m[2][2] = 1.0 - k * (x * x + y * y);
    return 1;
}

int cbvh_placement_of(const cbvh_transform *t, struct cbvh_placement *p)
{
    if (!cbvh_rotation_of_quaternion(t->rotation, p->rotation) || !isfinite(t->scale) || !(t->scale > 0.0f) ||
        !isfinite(t->translation[0]) || !isfinite(t->translation[1]) || !isfinite(t->translation[2]))
        return 0;
    p->translation = v3_from_f(t->translation);
    p->scale = t->scale;
    return 1;
}
