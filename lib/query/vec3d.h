/* vec3d.h: small double-precision 3-vector helpers for the sweep and overlap tests. */
#ifndef CBVH_QUERY_VEC3D_H
#define CBVH_QUERY_VEC3D_H

#include <math.h>

typedef struct cbvh_v3 {
    double x, y, z;
} cbvh_v3;

static inline cbvh_v3 v3(double x, double y, double z)
{
    cbvh_v3 r = {x, y, z};
    return r;
}
static inline cbvh_v3 v3_from_f(const float *p)
{
    return v3(p[0], p[1], p[2]);
}
static inline void v3_to_f(cbvh_v3 a, float *p)
{
    p[0] = (float)a.x;
    p[1] = (float)a.y;
    p[2] = (float)a.z;
}
static inline cbvh_v3 v3_add(cbvh_v3 a, cbvh_v3 b)
{
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline cbvh_v3 v3_sub(cbvh_v3 a, cbvh_v3 b)
{
    return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline cbvh_v3 v3_scale(cbvh_v3 a, double s)
{
    return v3(a.x * s, a.y * s, a.z * s);
}
/* a + s * b */
static inline cbvh_v3 v3_madd(cbvh_v3 a, cbvh_v3 b, double s)
{
    return v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s);
}
static inline double v3_dot(cbvh_v3 a, cbvh_v3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline cbvh_v3 v3_cross(cbvh_v3 a, cbvh_v3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_len2(cbvh_v3 a)
{
    return v3_dot(a, a);
}
static inline double v3_len(cbvh_v3 a)
{
    return sqrt(v3_dot(a, a));
}
/* a < b ? a : b and a > b ? a : b: one MINSD or MAXSD each (a nested conditional compiles to branches) */
static inline double cbvh_dmin(double a, double b)
{
    return a < b ? a : b;
}
static inline double cbvh_dmax(double a, double b)
{
    return a > b ? a : b;
}
/* cbvh_dmin and cbvh_dmax per coordinate. */
static inline cbvh_v3 v3_min(cbvh_v3 a, cbvh_v3 b)
{
    return v3(cbvh_dmin(a.x, b.x), cbvh_dmin(a.y, b.y), cbvh_dmin(a.z, b.z));
}
static inline cbvh_v3 v3_max(cbvh_v3 a, cbvh_v3 b)
{
    return v3(cbvh_dmax(a.x, b.x), cbvh_dmax(a.y, b.y), cbvh_dmax(a.z, b.z));
}
static inline double v3_get(cbvh_v3 a, int axis)
{
    return axis == 0 ? a.x : axis == 1 ? a.y : a.z;
}

/* m * v and m^T * v: with m a rotation, v turned into the frame whose axes are m's columns and back. */
static inline cbvh_v3 cbvh_rotate(const double m[3][3], cbvh_v3 v)
{
    return v3(m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z, m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
              m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z);
}
static inline cbvh_v3 cbvh_rotate_back(const double m[3][3], cbvh_v3 v)
{
    return v3(m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z, m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
              m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z);
}

/* a / |a|, or (0, 0, 0) when a is zero. */
static inline cbvh_v3 v3_normalize(cbvh_v3 a)
{
    double l = v3_len(a);
    return l > 0.0 ? v3_scale(a, 1.0 / l) : v3(0.0, 0.0, 0.0);
}

#endif
