/* triangle_box.c: the separating-axis test of a triangle and a box and the contact point
 * (triangle_box_kernel.h) as functions, for the overlap queries. */
#include "query/triangle_box_kernel.h"

int cbvh_triangle_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, cbvh_v3 center, cbvh_v3 half, cbvh_v3 delta,
                            double tmax, double *t, cbvh_v3 *normal, double *depth)
{
    return triangle_box_sweep(a, b, c, center, half, delta, tmax, t, normal, depth);
}

int cbvh_triangle_oriented_box_sweep(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box,
                                     cbvh_v3 delta, double tmax, double *t, cbvh_v3 *normal, double *depth)
{
    return triangle_oriented_box_sweep(a, b, c, box, delta, tmax, t, normal, depth);
}

cbvh_v3 cbvh_box_contact_point(cbvh_v3 a, cbvh_v3 b, cbvh_v3 c, const struct cbvh_box *box, cbvh_v3 center,
                               cbvh_v3 normal, double tol)
{
    return box_contact_point(a, b, c, box, center, normal, tol);
}
