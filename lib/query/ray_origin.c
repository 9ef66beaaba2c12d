/* ray_origin.c: far ray origins: moved next to the file's bounds (triangle test precision), axes whose box
 * test needs half scale. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include "query/raycast.h"

/* a + b as s + *err exactly (Knuth's two-sum). */
static double two_sum(double a, double b, double *err)
{
    const double s = a + b, bb = s - a;
    *err = (a - (s - bb)) + (b - bb);
    return s;
}

/* org + t * dir with one rounding (fma and two_sum), on the ray's line to double precision. */
static double advance(double org, double t, double dir)
{
    const double p = t * dir, pe = fma(t, dir, -p);
    double se;
    const double s = two_sum(org, p, &se);
    return s + (se + pe);
}

/* Entry t of the line org + t * dir into the box [lo, hi]; 0 when the line misses it. */
static int line_entry(const double org[3], const float dir[3], const float lo[3], const float hi[3],
                      double *entry)
{
    double tn = -INFINITY, tf = INFINITY;
    for (int a = 0; a < 3; a++) {
        if (dir[a] == 0.0f) {
            if (org[a] < lo[a] || org[a] > hi[a])
                return 0;
            continue;
        }
        double t1 = ((double)lo[a] - org[a]) / dir[a], t2 = ((double)hi[a] - org[a]) / dir[a];
        if (t1 > t2) {
            const double tmp = t1;
            t1 = t2;
            t2 = tmp;
        }
        tn = t1 > tn ? t1 : tn;
        tf = t2 < tf ? t2 : tf;
    }
    *entry = tn;
    return tn <= tf;
}

/* Moves the origin along the ray to about one extent before the bounds (two steps in double-double, then
 * rounded to float once) and makes t and the range relative to it: t' = t - base, the range rounded
 * inwards. A ray whose line misses the bounds, or points away from them, is left alone. */
static void move_origin(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray, const float lo[3], const float hi[3],
                        float ext)
{
    const float *dir = ray->dir;
    double o[3] = {ray->org[0], ray->org[1], ray->org[2]}, base = 0.0;
    const double dmax = fmax(fabs(dir[0]), fmax(fabs(dir[1]), fabs(dir[2])));
    const double margin = (double)ext / dmax;
    for (int step = 0; step < 2; step++) {
        double entry;
        if (!line_entry(o, dir, lo, hi, &entry))
            break;
        const double dt = entry - margin;
        if (step == 0 && !(dt > 0.0))
            return;
        for (int a = 0; a < 3; a++)
            o[a] = advance(o[a], dt, dir[a]);
        base += dt;
    }
    if (!(base > 0.0))
        return;
    float org[3] = {(float)o[0], (float)o[1], (float)o[2]};
    cbvh_origin_flush(org);
    const double tmin = (double)ctx->tmin - base;
    ctx->tmin = tmin > 0.0 ? cbvh_float_rounded(tmin, 1) : 0.0f;
    ctx->tmax =
        cbvh_float_rounded((double)ctx->tmax - base, 0); /* below tmin when the ray ends before the mesh */
    ctx->t_frame.base = base;
    cbvh_shear_setup(&ctx->shear, org, dir);
}

/* Sets box_halve on the axes where a grid end minus the origin overflows (then some plane - org can). */
static void mark_box_overflow(struct cbvh_ray_ctx *ctx, const struct cbvh_file *f)
{
    for (int a = 0; a < 3; a++) {
        const float o = ctx->shear.org[a], g0 = f->grid_origin[a];
        const float g1 = cbvh_dequantize(CBVH_Q_MAX, g0, f->grid_scale[a]);
        if (isinf(g1 - o) || isinf(o - g0))
            ctx->box_halve |= 1u << a;
    }
}

void cbvh_ray_place_origin(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray, const struct cbvh_file *f)
{
    const float *lo = f->info.bounds_min, *hi = f->info.bounds_max, ext = f->bounds_extent;
    float dist = 0.0f; /* how far outside the bounds, on the farthest axis */
    for (int a = 0; a < 3; a++) {
        const float below = lo[a] - ray->org[a], above = ray->org[a] - hi[a];
        dist = below > dist ? below : dist;
        dist = above > dist ? above : dist;
    }
    /* Ordered compare: an extent near FLT_MAX gives an infinite product and no move. */
    if (dist > CBVH_FAR_FACTOR * ext)
        move_origin(ctx, ray, lo, hi, ext);
    /* below FLT_MAX / 4 for both, every plane - org is at most about FLT_MAX / 2 */
    if (dist > 0.25f * FLT_MAX || ext > 0.25f * FLT_MAX)
        mark_box_overflow(ctx, f);
}
