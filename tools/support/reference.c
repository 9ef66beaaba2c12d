/* reference.c: double-precision brute-force references for every cbvh query, by methods independent of the
 * kernels. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "support/reference.h"
#include "support/scene_gen.h"

#define REF_PI 3.14159265358979323846

static void sub3(const double *a, const double *b, double *r)
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}
static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static void cross3(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}
static void lerp3(const double *a, const double *b, double s, double *r)
{
    for (int k = 0; k < 3; k++)
        r[k] = a[k] + (b[k] - a[k]) * s;
}

int ref_tris_from_file(const cbvh_file *file, uint32_t original_count, ref_tris *out)
{
    out->count = 0;
    out->v = malloc(sizeof(double) * 9 * (original_count ? original_count : 1));
    out->id = malloc(sizeof(uint32_t) * (original_count ? original_count : 1));
    if (!out->v || !out->id) {
        ref_tris_free(out);
        return 0;
    }
    for (uint32_t id = 0; id < original_count; id++) {
        float v0[3], v1[3], v2[3];
        if (!cbvh_file_get_triangle(file, id, v0, v1, v2))
            continue;
        double *d = out->v + 9 * out->count;
        for (int k = 0; k < 3; k++) {
            d[k] = v0[k];
            d[3 + k] = v1[k];
            d[6 + k] = v2[k];
        }
        out->id[out->count++] = id;
    }
    return 1;
}

void ref_tris_free(ref_tris *tris)
{
    free(tris->v);
    free(tris->id);
    tris->v = NULL;
    tris->id = NULL;
    tris->count = 0;
}

int ref_expand_triangles;

cbvh_result ref_cook_open(const float *positions, size_t vertex_count, const uint32_t *indices,
                          size_t triangle_count, const cbvh_cook_options *options, void **buffer,
                          cbvh_file **file)
{
    const cbvh_mesh mesh = {positions, vertex_count, 0, indices, triangle_count, NULL};
    size_t size;
    *buffer = NULL;
    *file = NULL;
    cbvh_result r = cbvh_cook(&mesh, options, NULL, buffer, &size, NULL, NULL);
    if (r != CBVH_OK)
        return r;
    r = cbvh_open_memory(*buffer, size, NULL, file, NULL);
    if (r == CBVH_OK && ref_expand_triangles) {
        r = cbvh_file_expand_triangles(*file, NULL);
        if (r != CBVH_OK) {
            cbvh_close(*file);
            *file = NULL;
        }
    }
    if (r != CBVH_OK) {
        cbvh_buffer_free(NULL, *buffer);
        *buffer = NULL;
    }
    return r;
}

cbvh_result ref_fixture_open(ref_fixture *fx, const float *positions, size_t vertex_count,
                             const uint32_t *indices, size_t triangle_count, const cbvh_cook_options *options)
{
    memset(fx, 0, sizeof(*fx));
    cbvh_result r =
        ref_cook_open(positions, vertex_count, indices, triangle_count, options, &fx->buffer, &fx->file);
    if (r != CBVH_OK)
        return r;
    fx->id_count = (uint32_t)triangle_count;
    fx->index_of_id = malloc(sizeof(size_t) * (triangle_count ? triangle_count : 1));
    if (!fx->index_of_id || !ref_tris_from_file(fx->file, fx->id_count, &fx->tris)) {
        ref_fixture_close(fx);
        return CBVH_ERROR_OUT_OF_MEMORY;
    }
    for (size_t k = 0; k < triangle_count; k++)
        fx->index_of_id[k] = (size_t)-1;
    for (int a = 0; a < 3; a++) {
        fx->lo[a] = INFINITY;
        fx->hi[a] = -INFINITY;
    }
    for (size_t k = 0; k < fx->tris.count; k++) {
        fx->index_of_id[fx->tris.id[k]] = k;
        for (int v = 0; v < 9; v++) {
            fx->lo[v % 3] = fmin(fx->lo[v % 3], fx->tris.v[9 * k + v]);
            fx->hi[v % 3] = fmax(fx->hi[v % 3], fx->tris.v[9 * k + v]);
        }
    }
    double d[3];
    sub3(fx->hi, fx->lo, d);
    fx->diag = sqrt(dot3(d, d));
    return CBVH_OK;
}

void ref_fixture_close(ref_fixture *fx)
{
    cbvh_close(fx->file);
    cbvh_buffer_free(NULL, fx->buffer);
    ref_tris_free(&fx->tris);
    free(fx->index_of_id);
    memset(fx, 0, sizeof(*fx));
}

int ref_ray_valid(const cbvh_ray *ray)
{
    for (int k = 0; k < 3; k++)
        if (isnan(ray->org[k]) || isinf(ray->org[k]) || isnan(ray->dir[k]) || isinf(ray->dir[k]))
            return 0;
    if (isnan(ray->tmin) || isinf(ray->tmin) || isnan(ray->tmax) || ray->tmax == -INFINITY)
        return 0;
    if (ray->dir[0] == 0 && ray->dir[1] == 0 && ray->dir[2] == 0)
        return 0;
    return ray->tmin >= 0 && ray->tmin <= ray->tmax;
}

void ref_triangle_normal(const double tri[9], double n[3])
{
    double e1[3], e2[3];
    sub3(tri + 3, tri, e1);
    sub3(tri + 6, tri, e2);
    cross3(e1, e2, n);
}

int ref_ray_triangle(const double tri[9], const cbvh_ray *ray, double *t, double *u, double *v,
                     double *margin)
{
    const double o[3] = {ray->org[0], ray->org[1], ray->org[2]},
                 d[3] = {ray->dir[0], ray->dir[1], ray->dir[2]};
    double n[3], ao[3];
    ref_triangle_normal(tri, n);
    const double nn = dot3(n, n), denom = dot3(n, d);
    if (nn == 0.0 || denom == 0.0)
        return 0;
    sub3(tri, o, ao);
    const double tt = dot3(n, ao) / denom;
    if (!(tt >= ray->tmin && tt <= ray->tmax))
        return 0;
    /* Barycentrics and margin in the plane across the ray (an orthonormal
     * projection along dir), where they are well conditioned at any angle. */
    const double dl = sqrt(dot3(d, d));
    const double dn[3] = {d[0] / dl, d[1] / dl, d[2] / dl};
    const int least =
        fabs(dn[0]) < fabs(dn[1]) ? (fabs(dn[0]) < fabs(dn[2]) ? 0 : 2) : (fabs(dn[1]) < fabs(dn[2]) ? 1 : 2);
    double axis[3] = {0, 0, 0}, b1[3], b2[3], q[3][2], rel[3];
    axis[least] = 1.0;
    cross3(dn, axis, b1);
    const double b1l = sqrt(dot3(b1, b1));
    for (int k = 0; k < 3; k++)
        b1[k] /= b1l;
    cross3(dn, b1, b2);
    for (int k = 0; k < 3; k++) {
        sub3(tri + 3 * k, o, rel);
        q[k][0] = dot3(rel, b1);
        q[k][1] = dot3(rel, b2);
    }
    const double area = (q[1][0] - q[0][0]) * (q[2][1] - q[0][1]) - (q[1][1] - q[0][1]) * (q[2][0] - q[0][0]);
    if (area == 0.0)
        return 0;
    double w[3], margin_len = INFINITY;
    for (int k = 0; k < 3; k++) {
        const double *qa = q[(k + 1) % 3], *qb = q[(k + 2) % 3];
        w[k] = (qa[0] * qb[1] - qa[1] * qb[0]) / area; /* sub-triangle (ray, qa, qb) over the whole */
        const double elen = hypot(qb[0] - qa[0], qb[1] - qa[1]);
        margin_len = fmin(margin_len, w[k] * fabs(area) / elen);
    }
    *t = tt;
    *u = w[1];
    *v = w[2];
    *margin = margin_len;
    return 1;
}

int ref_ray_closest(const ref_tris *tris, const cbvh_ray *ray, double slack, ref_ray_hit *hit)
{
    hit->index = (size_t)-1;
    hit->tri = CBVH_NO_HIT;
    hit->t = INFINITY;
    if (!ref_ray_valid(ray))
        return 0;
    for (size_t k = 0; k < tris->count; k++) {
        double t, u, v, m;
        if (ref_ray_triangle(tris->v + 9 * k, ray, &t, &u, &v, &m) && m >= -slack && t < hit->t) {
            hit->index = k;
            hit->tri = tris->id[k];
            hit->t = t;
            hit->u = u;
            hit->v = v;
            hit->margin = m;
        }
    }
    return hit->index != (size_t)-1;
}

/* Squared distance from p to segment a-b, by projection clamped to the segment. */
static double point_segment_dist2(const double *p, const double *a, const double *b)
{
    double ab[3], ap[3], q[3], r[3];
    sub3(b, a, ab);
    sub3(p, a, ap);
    const double len2 = dot3(ab, ab);
    double s = len2 > 0.0 ? dot3(ap, ab) / len2 : 0.0;
    s = s < 0.0 ? 0.0 : s > 1.0 ? 1.0 : s;
    lerp3(a, b, s, q);
    sub3(p, q, r);
    return dot3(r, r);
}

/* Squared distance from p to the nearest of tri's three edge segments. */
static double point_edges_dist2(const double tri[9], const double p[3])
{
    double best = INFINITY;
    for (int k = 0; k < 3; k++)
        best = fmin(best, point_segment_dist2(p, tri + 3 * k, tri + 3 * ((k + 1) % 3)));
    return best;
}

double ref_point_triangle_dist2(const double tri[9], const double p[3])
{
    const double edges = point_edges_dist2(tri, p);
    double n[3], ap[3];
    ref_triangle_normal(tri, n);
    const double nn = dot3(n, n);
    if (!(nn > 0.0))
        return edges;
    sub3(p, tri, ap);
    const double h = dot3(ap, n) / nn; /* p minus h*n lies in the plane */
    double q[3], x[3], y[3], c[3];
    int inside = 1;
    for (int k = 0; k < 3; k++)
        q[k] = p[k] - h * n[k];
    for (int k = 0; k < 3 && inside; k++) {
        const double *a = tri + 3 * k, *b = tri + 3 * ((k + 1) % 3);
        sub3(b, a, x);
        sub3(q, a, y);
        cross3(x, y, c);
        inside = dot3(c, n) >= 0.0;
    }
    /* A point of the triangle lies in its bounding box. On a needle the
     * long edges' directions carry more rounding than the needle's angle,
     * and the edge tests above can accept a projection far beyond its tip
     * (finding F5): the box, exact, refuses it. */
    double mag = 0.0; /* q carries rounding relative to p's and the vertices' magnitudes */
    for (int k = 0; k < 3; k++)
        mag = fmax(mag, fmax(fabs(p[k]), fmax(fabs(tri[k]), fmax(fabs(tri[3 + k]), fabs(tri[6 + k])))));
    for (int k = 0; k < 3 && inside; k++) {
        const double lo = fmin(tri[k], fmin(tri[3 + k], tri[6 + k])),
                     hi = fmax(tri[k], fmax(tri[3 + k], tri[6 + k]));
        inside = q[k] >= lo - 1e-9 * mag && q[k] <= hi + 1e-9 * mag;
    }
    /* A point of the triangle lies within half its width (|n| over its longest edge) of an edge. With
     * corners in a row n is rounding alone, points anywhere, and the tests above can accept a q off the
     * triangle (it lies in a plane through the corners' line, so it would understate the distance): the
     * width, that rounding's size, refuses it. */
    double longest2 = 0.0;
    for (int k = 0; k < 3; k++) {
        sub3(tri + 3 * ((k + 1) % 3), tri + 3 * k, x);
        longest2 = fmax(longest2, dot3(x, x));
    }
    if (inside && sqrt(point_edges_dist2(tri, q)) > 0.5 * sqrt(nn / longest2) + 1e-9 * mag)
        inside = 0;
    return inside ? fmin(edges, h * h * nn) : edges;
}

/* Minimum of a convex function on [lo, hi] by golden-section search. */
static double golden_min(double (*f)(void *, double), void *ctx, double lo, double hi, double *at)
{
    const double g = 0.6180339887498949;
    double a = lo, b = hi, x1 = b - g * (b - a), x2 = a + g * (b - a);
    double f1 = f(ctx, x1), f2 = f(ctx, x2);
    for (int it = 0; it < 44; it++) { /* 0.618^44: about 1e-9 of the interval */
        if (f1 <= f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = f(ctx, x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = f(ctx, x2);
        }
    }
    /* The ends too: a convex function on an interval may be smallest there. */
    double best = f1 <= f2 ? f1 : f2, x = f1 <= f2 ? x1 : x2, e;
    if ((e = f(ctx, lo)) < best) {
        best = e;
        x = lo;
    }
    if ((e = f(ctx, hi)) < best) {
        best = e;
        x = hi;
    }
    if (at)
        *at = x;
    return best;
}

struct seg_ctx {
    const double *tri, *p0, *p1;
};
static double seg_point_dist(void *c, double s)
{
    const struct seg_ctx *x = c;
    double p[3];
    lerp3(x->p0, x->p1, s, p);
    return sqrt(ref_point_triangle_dist2(x->tri, p));
}

double ref_segment_triangle_dist(const double tri[9], const double p0[3], const double p1[3])
{
    struct seg_ctx c = {tri, p0, p1};
    return golden_min(seg_point_dist, &c, 0.0, 1.0, NULL);
}

struct box_ctx {
    const double *tri, *lo, *hi;
    double y;
};
/* Point of the triangle a + y (c - a) + z (b - a) to the box. */
static double box_point_dist(void *c, double z)
{
    const struct box_ctx *x = c;
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) {
        const double p = x->tri[k] + x->y * (x->tri[6 + k] - x->tri[k]) + z * (x->tri[3 + k] - x->tri[k]);
        const double out = p < x->lo[k] ? x->lo[k] - p : p > x->hi[k] ? p - x->hi[k] : 0.0;
        d2 += out * out;
    }
    return sqrt(d2);
}
static double box_row_dist(void *c, double y)
{
    struct box_ctx *x = c;
    x->y = y;
    return golden_min(box_point_dist, x, 0.0, 1.0 - y, NULL);
}

double ref_box_triangle_dist(const double tri[9], const double lo[3], const double hi[3])
{
    struct box_ctx c = {tri, lo, hi, 0.0};
    return golden_min(box_row_dist, &c, 0.0, 1.0, NULL);
}

int ref_triangle_box_overlap(const double tri[9], const double lo[3], const double hi[3], double grow)
{
    double poly[2][16][3];
    int n = 3, cur = 0;
    memcpy(poly[0], tri, sizeof(double) * 9);
    for (int plane = 0; plane < 6; plane++) {
        const int axis = plane % 3;
        const double sign = plane < 3 ? 1.0 : -1.0; /* keep sign * (x - bound) <= 0 */
        const double bound = plane < 3 ? hi[axis] + grow : lo[axis] - grow;
        int m = 0;
        for (int k = 0; k < n; k++) {
            const double *a = poly[cur][k], *b = poly[cur][(k + 1) % n];
            const double da = sign * (a[axis] - bound), db = sign * (b[axis] - bound);
            if (da <= 0.0)
                memcpy(poly[1 - cur][m++], a, sizeof(double) * 3);
            if ((da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0))
                lerp3(a, b, da / (da - db), poly[1 - cur][m++]);
        }
        n = m;
        cur = 1 - cur;
        if (n == 0)
            return 0;
    }
    return 1;
}

int ref_box_class(const double *tri, const double lo[3], const double hi[3], double tol)
{
    if (!ref_triangle_box_overlap(tri, lo, hi, tol))
        return 0;
    return ref_triangle_box_overlap(tri, lo, hi, -tol) ? 2 : 1;
}

int ref_sphere_class(const double *tri, const double c[3], double r, double tol)
{
    const double d = sqrt(ref_point_triangle_dist2(tri, c));
    return d > r + tol ? 0 : d <= r - tol ? 2 : 1;
}

int ref_capsule_class(const double *tri, const double p0[3], const double p1[3], double r, double tol)
{
    const double d = ref_segment_triangle_dist(tri, p0, p1);
    return d > r + tol ? 0 : d <= r - tol ? 2 : 1;
}

double ref_shape_triangle_dist(const ref_shape *shape, const double delta[3], double t, const double tri[9])
{
    double p0[3], p1[3];
    for (int k = 0; k < 3; k++) {
        p0[k] = shape->p0[k] + t * delta[k];
        p1[k] = shape->p1[k] + t * delta[k];
    }
    switch (shape->kind) {
    case REF_SPHERE:
        return fmax(0.0, sqrt(ref_point_triangle_dist2(tri, p0)) - shape->radius);
    case REF_CAPSULE:
        return fmax(0.0, ref_segment_triangle_dist(tri, p0, p1) - shape->radius);
    default: {
        double lo[3], hi[3], local[9];
        for (int k = 0; k < 3; k++) {
            lo[k] = (shape->rotated ? 0.0 : p0[k]) - shape->half[k];
            hi[k] = (shape->rotated ? 0.0 : p0[k]) + shape->half[k];
        }
        if (!shape->rotated)
            return ref_box_triangle_dist(tri, lo, hi);
        for (int v = 0; v < 3; v++) { /* the triangle in the box's frame: axes^T (vertex - center) */
            double e[3];
            sub3(tri + 3 * v, p0, e);
            for (int j = 0; j < 3; j++)
                local[3 * v + j] =
                    shape->axes[0][j] * e[0] + shape->axes[1][j] * e[1] + shape->axes[2][j] * e[2];
        }
        return ref_box_triangle_dist(local, lo, hi);
    }
    }
}

struct sweep_ctx {
    const ref_shape *shape;
    const double *delta, *tri;
};
static double sweep_dist(void *c, double t)
{
    const struct sweep_ctx *x = c;
    return ref_shape_triangle_dist(x->shape, x->delta, t, x->tri);
}

/* Conservative bounds of the swept shape, to skip far triangles quickly. */
static void swept_bounds(const ref_shape *s, const double delta[3], double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        double a = fmin(s->p0[k], s->kind == REF_CAPSULE ? s->p1[k] : s->p0[k]);
        double b = fmax(s->p0[k], s->kind == REF_CAPSULE ? s->p1[k] : s->p0[k]);
        const double grow = s->kind != REF_BOX ? s->radius
                            : s->rotated       ? sqrt(dot3(s->half, s->half))
                                               : s->half[k];
        lo[k] = fmin(a, a + delta[k]) - grow;
        hi[k] = fmax(b, b + delta[k]) + grow;
    }
}

/* 1 when the bounding spheres of shape and triangle never come within eps:
 * the triangle's centroid is farther from the path of the shape's center
 * than the sum of the radii. */
static int sweep_far_apart(const ref_shape *s, const double delta[3], const double tri[9], double eps)
{
    double center[3], end[3], cen[3], reach = 0.0, r_shape;
    for (int k = 0; k < 3; k++) {
        center[k] = s->kind == REF_CAPSULE ? 0.5 * (s->p0[k] + s->p1[k]) : s->p0[k];
        end[k] = center[k] + delta[k];
        cen[k] = (tri[k] + tri[3 + k] + tri[6 + k]) / 3.0;
    }
    for (int v = 0; v < 3; v++) {
        double e[3];
        sub3(tri + 3 * v, cen, e);
        reach = fmax(reach, sqrt(dot3(e, e)));
    }
    if (s->kind == REF_BOX) {
        r_shape = sqrt(dot3(s->half, s->half));
    } else {
        double seg[3];
        sub3(s->p1, s->p0, seg);
        r_shape = s->radius + 0.5 * sqrt(dot3(seg, seg));
    }
    return sqrt(point_segment_dist2(cen, center, end)) > reach + r_shape + eps;
}

int ref_sweep(const ref_tris *tris, const ref_shape *shape, const double delta[3], double eps,
              ref_sweep_hit *hit)
{
    double lo[3], hi[3];
    swept_bounds(shape, delta, lo, hi);
    hit->index = (size_t)-1;
    hit->tri = CBVH_NO_HIT;
    hit->t = INFINITY;
    for (size_t k = 0; k < tris->count; k++) {
        const double *tri = tris->v + 9 * k;
        int far = 0;
        for (int a = 0; a < 3 && !far; a++) {
            const double tl = fmin(tri[a], fmin(tri[3 + a], tri[6 + a]));
            const double th = fmax(tri[a], fmax(tri[3 + a], tri[6 + a]));
            far = tl > hi[a] + eps || th < lo[a] - eps;
        }
        if (far || sweep_far_apart(shape, delta, tri, eps))
            continue;
        struct sweep_ctx c = {shape, delta, tri};
        double t_min, t;
        if (sweep_dist(&c, 0.0) <= eps) {
            t = 0.0;
        } else {
            if (golden_min(sweep_dist, &c, 0.0, 1.0, &t_min) > eps)
                continue;
            double a = 0.0, b = t_min; /* d(a) > eps >= d(b), d decreasing on [a, b] */
            for (int it = 0; it < 52; it++) {
                const double m = 0.5 * (a + b);
                if (sweep_dist(&c, m) <= eps)
                    b = m;
                else
                    a = m;
            }
            t = b;
        }
        if (t < hit->t) {
            hit->index = k;
            hit->tri = tris->id[k];
            hit->t = t;
        }
    }
    return hit->index != (size_t)-1;
}

/* Rays of several kinds for a fixture: uniform, aimed at triangles, aimed at
 * vertices (shared by several triangles), axis-aligned with 0 and -0
 * components from origins on vertex coordinates, and short segments. */
cbvh_ray ref_make_ray(const ref_fixture *fx, uint64_t *st, int kind)
{
    cbvh_ray ray;
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = fx->lo[a] - 0.25 * fx->diag;
        hi[a] = fx->hi[a] + 0.25 * fx->diag;
        ray.org[a] = (float)(lo[a] + (hi[a] - lo[a]) * scene_rand_unit(st));
    }
    ray.tmin = 0.0f;
    ray.tmax = INFINITY;
    const size_t k = (size_t)(scene_rand_unit(st) * (double)fx->tris.count);
    const double *tri = fx->tris.v + 9 * k;
    switch (kind) {
    case 0: { /* uniform direction */
        const double z = 2.0 * scene_rand_unit(st) - 1.0, phi = 2.0 * REF_PI * scene_rand_unit(st);
        ray.dir[0] = (float)(sqrt(1 - z * z) * cos(phi));
        ray.dir[1] = (float)(sqrt(1 - z * z) * sin(phi));
        ray.dir[2] = (float)z;
        break;
    }
    case 1:   /* at a random point of a triangle, t about 1 there */
    case 2: { /* at a vertex */
        double w0 = scene_rand_unit(st), w1 = scene_rand_unit(st);
        if (w0 + w1 > 1.0) {
            w0 = 1.0 - w0;
            w1 = 1.0 - w1;
        }
        if (kind == 2) {
            const int vtx = (int)(scene_rand_next(st) % 3);
            w0 = vtx == 1;
            w1 = vtx == 2;
        }
        for (int a = 0; a < 3; a++) {
            const float target = (float)(tri[a] + w0 * (tri[3 + a] - tri[a]) + w1 * (tri[6 + a] - tri[a]));
            ray.dir[a] = target - ray.org[a];
        }
        break;
    }
    case 3: { /* axis-aligned, origin on a vertex's coordinates in the other axes */
        const int axis = (int)(scene_rand_next(st) % 3);
        for (int a = 0; a < 3; a++) {
            ray.dir[a] = scene_rand_next(st) % 2 ? 0.0f : -0.0f;
            if (a != axis)
                ray.org[a] = (float)tri[3 * (scene_rand_next(st) % 3) + a];
        }
        ray.dir[axis] = scene_rand_next(st) % 2 ? 1.0f : -1.0f;
        break;
    }
    default: { /* short segment with tmin > 0 towards a triangle */
        for (int a = 0; a < 3; a++)
            ray.dir[a] = (float)((tri[a] + tri[3 + a] + tri[6 + a]) / 3.0) - ray.org[a];
        ray.tmin = (float)(0.5 * scene_rand_unit(st));
        ray.tmax = ray.tmin + (float)scene_rand_unit(st);
        break;
    }
    }
    if (ray.dir[0] == 0 && ray.dir[1] == 0 && ray.dir[2] == 0)
        ray.dir[0] = 1.0f;
    return ray;
}
