/* reference.h: double-precision brute-force references for every cbvh query, by methods independent of the
 * kernels. */
#ifndef CBVH_TEST_REFERENCE_H
#define CBVH_TEST_REFERENCE_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"

/* Triangles as a file holds them (decoded positions), with original ids. */
typedef struct ref_tris {
    size_t count;
    double *v;    /* 9 per triangle: v0 xyz, v1 xyz, v2 xyz */
    uint32_t *id; /* original id */
} ref_tris;

/* Reads every triangle of `file` whose original id is below original_count
 * (ids the cooker dropped are skipped). Returns 0 on allocation failure. */
int ref_tris_from_file(const cbvh_file *file, uint32_t original_count, ref_tris *out);
void ref_tris_free(ref_tris *tris);

/* Cooks the mesh (positions xyz, 3 indices per triangle) with `options` (NULL
 * for the defaults) and opens the result from memory, then expands its
 * triangles (cbvh_file_expand_triangles) when ref_expand_triangles is set (the
 * tests' runs of tests/support/layouts.h). *buffer holds the file
 * bytes until the caller closes the file and frees it with cbvh_buffer_free.
 * Returns CBVH_OK or the first error. */
extern int ref_expand_triangles;
cbvh_result ref_cook_open(const float *positions, size_t vertex_count, const uint32_t *indices,
                          size_t triangle_count, const cbvh_cook_options *options, void **buffer,
                          cbvh_file **file);

/* A cooked and opened mesh with its reference triangles, for tests and tools. */
typedef struct ref_fixture {
    void *buffer; /* the file bytes */
    cbvh_file *file;
    ref_tris tris;
    size_t *index_of_id; /* original id -> index into tris, (size_t)-1 when dropped */
    uint32_t id_count;   /* the input triangle count */
    double lo[3], hi[3]; /* bounds of the reference triangles */
    double diag;         /* length of the bounds' diagonal */
} ref_fixture;

/* ref_cook_open plus the reference triangles and bounds. Returns CBVH_OK or
 * the first error (CBVH_ERROR_OUT_OF_MEMORY when the references do not fit). */
cbvh_result ref_fixture_open(ref_fixture *fx, const float *positions, size_t vertex_count,
                             const uint32_t *indices, size_t triangle_count,
                             const cbvh_cook_options *options);
void ref_fixture_close(ref_fixture *fx);

/* A ray for fixture fx from the generator state st, of kind (0 .. REF_RAY_KINDS-1):
 * 0 uniform direction from a point around the mesh, 1 aimed at a random point
 * of a triangle (t about 1 there), 2 aimed at a vertex (shared by several
 * triangles), 3 axis-aligned with 0 and -0 components from an origin on a
 * vertex's coordinates, 4 a short segment with tmin > 0. */
#define REF_RAY_KINDS 5
cbvh_ray ref_make_ray(const ref_fixture *fx, uint64_t *st, int kind);

/* The validity rule of cbvh.h, restated: 1 when every query must treat the ray as a ray. */
int ref_ray_valid(const cbvh_ray *ray);

/* The normal of triangle tri (three xyz vertices) as wound, not normalized: (v1 - v0) x (v2 - v0), in
 * double; zero for a degenerate triangle. */
void ref_triangle_normal(const double tri[9], double n[3]);

/* Ray against one triangle's plane: 1 when the plane is crossed at t in
 * [tmin, tmax] (rays parallel to the plane never are), with t, the
 * barycentrics u, v of the crossing point and its margin: the distance across
 * the ray from the ray's line to the nearest edge of the triangle (>= 0
 * inside, < 0 outside), measured in the plane perpendicular to dir. */
int ref_ray_triangle(const double tri[9], const cbvh_ray *ray, double *t, double *u, double *v,
                     double *margin);

typedef struct ref_ray_hit {
    size_t index; /* into ref_tris; (size_t)-1 for none */
    uint32_t tri; /* original id, CBVH_NO_HIT for none */
    double t, u, v, margin;
} ref_ray_hit;

/* Closest triangle with margin >= -slack (a length; 0: inside or on the boundary). */
int ref_ray_closest(const ref_tris *tris, const cbvh_ray *ray, double slack, ref_ray_hit *hit);

/* Squared distance from p to triangle tri: to the plane when p projects
 * inside, else to the nearest edge segment. */
double ref_point_triangle_dist2(const double tri[9], const double p[3]);

/* Distance from segment p0-p1 to triangle tri, by golden-section search of the
 * (convex) point distance along the segment. */
double ref_segment_triangle_dist(const double tri[9], const double p0[3], const double p1[3]);

/* Distance from the box [lo, hi] to triangle tri, by nested golden-section
 * search of the (convex) point-to-box distance over the triangle. */
double ref_box_triangle_dist(const double tri[9], const double lo[3], const double hi[3]);

/* 1 when triangle tri meets the closed box [lo, hi]: the triangle clipped to
 * the box (Sutherland-Hodgman) keeps a point, with the box grown by `grow`. */
int ref_triangle_box_overlap(const double tri[9], const double lo[3], const double hi[3], double grow);

/* Reference membership of triangle tri in an overlap query's region, the box [lo, hi], the ball (c, r) or
 * the capsule (p0-p1, r): 2 surely overlapping (also with the region shrunk by tol), 1 borderline, 0 surely
 * apart (also with the region grown by tol). */
int ref_box_class(const double *tri, const double lo[3], const double hi[3], double tol);
int ref_sphere_class(const double *tri, const double c[3], double r, double tol);
int ref_capsule_class(const double *tri, const double p0[3], const double p1[3], double r, double tol);

/* A moving shape for the sweep references. */
typedef enum ref_shape_kind { REF_SPHERE, REF_CAPSULE, REF_BOX } ref_shape_kind;
typedef struct ref_shape {
    ref_shape_kind kind;
    double p0[3], p1[3]; /* sphere: center p0; capsule: segment p0-p1; box: center p0 */
    double radius;       /* sphere and capsule */
    double half[3];      /* box */
    int rotated;         /* box: 0 for an axis-aligned one (axes ignored) */
    double axes[3][3];   /* box: its columns are the box's unit axes */
} ref_shape;

/* Distance from the shape moved by t*delta to triangle tri (0 when they overlap). */
double ref_shape_triangle_dist(const ref_shape *shape, const double delta[3], double t, const double tri[9]);

typedef struct ref_sweep_hit {
    size_t index; /* into ref_tris; (size_t)-1 for none */
    uint32_t tri;
    double t;
} ref_sweep_hit;

/* First contact over t in [0, 1], per triangle, by the convexity of the
 * distance along the motion (the distance from a point moving on a line to the
 * convex set triangle - shape): a golden-section search finds its minimum; if
 * that is above eps there is no contact, else bisection finds the first t
 * where the distance falls to eps. Independent of the kernels' closed forms:
 * it only evaluates distances. The earliest over all triangles wins. */
int ref_sweep(const ref_tris *tris, const ref_shape *shape, const double delta[3], double eps,
              ref_sweep_hit *hit);

#endif
