/* brute_force.h: double-precision reference geometry (ray, point, segment and box against a triangle) to check query answers. */
#ifndef CBVH_TOOLS_BRUTE_FORCE_H
#define CBVH_TOOLS_BRUTE_FORCE_H

/* Written independently of lib/query so that a shared mistake cannot hide. Points are double[3]. */

/* Moller-Trumbore ray/triangle test: returns 1 when org + t*dir with t in [tmin, tmax] lies on the
 * triangle (a, b, c), with the barycentrics u (weight of b) and v (weight of c). *margin receives
 * min(u, v, 1-u-v): a hit with a tiny margin grazes an edge, where float and double may disagree. */
int bf_ray_triangle(const double org[3], const double dir[3], double tmin, double tmax, const double a[3],
                    const double b[3], const double c[3], double *t, double *u, double *v, double *margin);

/* Squared distance from p to the triangle (a, b, c) (Voronoi regions; degenerate triangles too). */
double bf_point_triangle_dist2(const double p[3], const double a[3], const double b[3], const double c[3]);

/* Squared distance between the segments p0-p1 and q0-q1 (degenerate segments allowed). */
double bf_segment_segment_dist2(const double p0[3], const double p1[3], const double q0[3], const double q1[3]);

/* Squared distance between the segment p0-p1 and the triangle (a, b, c): 0 when the segment
 * crosses it. */
double bf_segment_triangle_dist2(const double p0[3], const double p1[3], const double a[3], const double b[3],
                                 const double c[3]);

/* Separating-axis test of the closed box (center, half extents) against the triangle (13 axes). */
int bf_box_triangle_overlap(const double center[3], const double half[3], const double a[3], const double b[3],
                            const double c[3]);

#endif
