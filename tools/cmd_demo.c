/* cmd_demo.c: `cbvh demo`: cook, open and query the built-in scene with every query kind; check answers by
 * brute force. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "temp_cleanup.h"
#include "commands.h"
#include "json.h"
#include "support/reference.h"
#include "support/scene_gen.h"

static const char usage[] =
    "Usage: cbvh demo [--quiet] [--json]\n"
    "\n"
    "Runs the whole pipeline on the built-in scene (a terrain with spheres, several materials),\n"
    "with no input files: generates it, cooks it into a temporary file (removed afterwards),\n"
    "opens it, and runs every query kind on generated queries: closest-hit and any-hit raycasts\n"
    "with the sorted, stackless and stream traversals, raycasts culling back faces and reporting\n"
    "all hits, a placed instance (query options), sphere, capsule and box sweeps, box, sphere and\n"
    "capsule overlaps, sphere contacts. The traversals and options are compared with each other ray\n"
    "by ray, and a sample of\n"
    "each kind against a double-precision brute-force loop over all triangles (sweeps by sampling\n"
    "the motion). Prints what it did, counts, hits and speed.\n"
    "\n"
    "Options:\n"
    "  --quiet      print only the final line\n"
    "  --json       print only {\"ok\", \"failed_checks\", \"triangles\"} (a failure to run:\n"
    "               {\"command\", \"error\": {\"status\", \"file\", \"message\"}})\n"
    "  -h, --help   show this help\n"
    "\n"
    "Exit status: 0 when everything worked and agreed, 1 when an answer disagreed, 2 on an\n"
    "I/O error (e.g. no writable temporary folder; set TMPDIR).\n";

#define DEMO_RAYS 200000
#define DEMO_SHAPES 20000
#define DEMO_RAY_SAMPLE 400
#define DEMO_SHAPE_SAMPLE 50
#define DEMO_SWEEP_STEPS 24
#define DEMO_OVERLAP_CAP 65536
#define DEMO_OVERLAP_PAGE 256 /* the paged box overlaps' page */

/* The opened scene plus its triangles in double precision for the brute-force checks. */
typedef struct demo {
    const cbvh_file *file;
    uint32_t tri_count; /* original ids are below it */
    double *tris;       /* 9 per original id */
    uint8_t *valid;     /* 0 for ids the cooker dropped (degenerate) */
    float lo[3], hi[3];
    double diag, tol;
    int failures;
    int quiet;
    uint64_t rng;
} demo;

static double unit(demo *d)
{
    return scene_rand_unit(&d->rng);
}
static float in_range(demo *d, float a, float b)
{
    return a + (b - a) * (float)unit(d);
}

static void random_direction(demo *d, float dir[3])
{
    double z = 2 * unit(d) - 1, phi = 6.283185307179586 * unit(d), r = sqrt(1 - z * z);
    dir[0] = (float)(r * cos(phi));
    dir[1] = (float)(r * sin(phi));
    dir[2] = (float)z;
}

static void to_double(double out[3], const float in[3])
{
    out[0] = in[0];
    out[1] = in[1];
    out[2] = in[2];
}

/* Prints the first mismatch of a check on stderr (the table row says how many there were). */
static void report_failure(const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 1, 2)))
#endif
    ;
static void report_failure(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, "cbvh demo: mismatch: ");
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

static void print_row(const demo *d, const char *what, size_t count, size_t hits, double seconds,
                      const char *unit_name, const char *check)
{
    if (d->quiet)
        return;
    double rate = seconds > 0 ? count / seconds : 0;
    if (!strcmp(unit_name, "MRays/s"))
        printf("  %-26s %8zu %8zu %10.2f %-10s %s\n", what, count, hits, rate / 1e6, unit_name, check);
    else
        printf("  %-26s %8zu %8zu %10.0f %-10s %s\n", what, count, hits, rate, unit_name, check);
}

/* A table row for a query kind whose sample of `sample` answers had `bad` disagreements. */
static void sample_row(demo *d, const char *what, size_t count, size_t hits, double seconds,
                       const char *unit_name, int sample, int bad)
{
    char check[64];
    snprintf(check, sizeof check, "%d of %d vs brute force: %s", sample - bad, sample, bad ? "FAILED" : "ok");
    d->failures += bad != 0;
    print_row(d, what, count, hits, seconds, unit_name, check);
}

/* ---- raycasts ---- */

/* Half incoherent rays (origins in the bounds, uniform directions), half rays from above the
 * scene towards random ground points. */
static void make_rays(demo *d, cbvh_ray *rays, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        cbvh_ray *r = &rays[i];
        if (i % 2 == 0) {
            for (int a = 0; a < 3; a++)
                r->org[a] = in_range(d, d->lo[a], d->hi[a]);
            random_direction(d, r->dir);
        } else {
            float target[3] = {in_range(d, d->lo[0], d->hi[0]), d->lo[1], in_range(d, d->lo[2], d->hi[2])};
            r->org[0] = in_range(d, d->lo[0], d->hi[0]);
            r->org[1] = d->hi[1] + 0.25f * (float)d->diag;
            r->org[2] = in_range(d, d->lo[2], d->hi[2]);
            for (int a = 0; a < 3; a++)
                r->dir[a] = target[a] - r->org[a];
        }
        r->tmin = 0;
        r->tmax = INFINITY;
    }
}

/* Closest hit over all triangles in double precision; returns the id or CBVH_NO_HIT. */
static uint32_t brute_raycast(const demo *d, const cbvh_ray *r, double *t_out, double *margin_out)
{
    double best = INFINITY, best_margin = 1;
    uint32_t best_tri = CBVH_NO_HIT;
    for (uint32_t i = 0; i < d->tri_count; i++) {
        double t, u, v, margin;
        /* margin: how far inside the triangle, in barycentrics (the library reports u, v too) */
        if (d->valid[i] && ref_ray_triangle(d->tris + 9 * (size_t)i, r, &t, &u, &v, &margin) && margin >= 0 &&
            t < best) {
            best = t;
            best_tri = i;
            best_margin = fmin(fmin(u, v), 1.0 - u - v);
        }
    }
    *t_out = best;
    *margin_out = best_margin;
    return best_tri;
}

/* ---- raycasts with options ---- */

/* The nearest of every hit a ray makes (cbvh_raycast_with's filter, rejecting each). */
typedef struct all_hits {
    size_t count;
    cbvh_hit_record nearest;
} all_hits;

static cbvh_filter_result collect_hit(void *user, const cbvh_hit_record *hit)
{
    all_hits *all = user;
    if (all->count++ == 0 || hit->t < all->nearest.t ||
        (hit->t == all->nearest.t && hit->tri < all->nearest.tri))
        all->nearest = *hit;
    return CBVH_FILTER_REJECT;
}

/* The rotation matrix of quaternion q (x, y, z, w), normalized in double. */
static void quaternion_matrix(const float q[4], double m[3][3])
{
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double k = 2.0 / (x * x + y * y + z * z + w * w);
    const double r[3][3] = {{1 - k * (y * y + z * z), k * (x * y - z * w), k * (x * z + y * w)},
                            {k * (x * y + z * w), 1 - k * (x * x + z * z), k * (y * z - x * w)},
                            {k * (x * z - y * w), k * (y * z + x * w), 1 - k * (x * x + y * y)}};
    memcpy(m, r, sizeof r);
}

/* A placed instance (cbvh_query_options.transform): the scene turned 30 degrees about (1, 2, 2) / 3, scaled
 * by 2 and moved; each ray is placed the same way (in double, rounded to float) and cast in the world. The
 * answers are the scene's own: the same triangle and t, but for rays within 1e-4 (barycentric) of an edge,
 * where the rounding of the placed ray may pick the neighbour. */
static void demo_placed(demo *d, const cbvh_ray *rays, const cbvh_hit *ref, size_t n)
{
    const double half = 0.2617993877991494, sn = sin(half); /* 30 degrees / 2 */
    const double axis[3] = {1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0};
    const cbvh_transform tr = {
        {(float)(sn * axis[0]), (float)(sn * axis[1]), (float)(sn * axis[2]), (float)cos(half)},
        {5.0f, -3.0f, 2.0f},
        2.0f};
    double m[3][3];
    quaternion_matrix(tr.rotation, m);
    cbvh_query_options q;
    cbvh_query_options_init(&q, sizeof q);
    q.transform = &tr;
    cbvh_ray *world = malloc(n * sizeof *world);
    if (!world) {
        d->failures++;
        fprintf(stderr, "cbvh demo: out of memory\n");
        return;
    }
    for (size_t i = 0; i < n; i++) {
        world[i] = rays[i];
        for (int a = 0; a < 3; a++) {
            const float *o = rays[i].org, *dv = rays[i].dir;
            world[i].org[a] =
                (float)(tr.translation[a] + tr.scale * (m[a][0] * o[0] + m[a][1] * o[1] + m[a][2] * o[2]));
            world[i].dir[a] = (float)(tr.scale * (m[a][0] * dv[0] + m[a][1] * dv[1] + m[a][2] * dv[2]));
        }
    }
    size_t h = 0, differ = 0;
    const double t0 = cli_now();
    for (size_t i = 0; i < n; i++) {
        cbvh_hit_record placed;
        cbvh_raycast_with(d->file, &world[i], &q, &placed, NULL);
        h += placed.tri != CBVH_NO_HIT;
    }
    const double sec = cli_now() - t0;
    for (size_t i = 0; i < n; i++) { /* again, untimed, against the scene's own hits */
        cbvh_hit_record placed;
        cbvh_raycast_with(d->file, &world[i], &q, &placed, NULL);
        const double edge =
            ref[i].tri == CBVH_NO_HIT ? 1.0 : fmin(fmin(ref[i].u, ref[i].v), 1.0 - ref[i].u - ref[i].v);
        const int same =
            placed.tri == ref[i].tri &&
            (placed.tri == CBVH_NO_HIT || fabs(placed.t - ref[i].t) <= 1e-4 * fmax(1.0, ref[i].t));
        if (!same && edge >= 1e-4 && differ++ == 0)
            report_failure("placed raycast: ray %zu: triangle %u at t %g, in the scene's frame %u at t %g", i,
                           (unsigned)placed.tri, placed.t, (unsigned)ref[i].tri, ref[i].t);
    }
    free(world);
    d->failures += differ != 0;
    print_row(d, "raycast, placed instance", n, h, sec, "MRays/s",
              differ ? "DIFFERS from the scene's frame" : "= the scene's own hits, all rays");
}

/* Back-face culling and all hits, on the same rays: the culled answer is the plain one when that is a
 * front face, else a front face no nearer; the nearest of all hits is the plain hit. */
static void demo_options(demo *d, const cbvh_ray *rays, const cbvh_hit *ref, size_t n)
{
    cbvh_query_options q;
    cbvh_query_options_init(&q, sizeof q);
    q.cull = CBVH_CULL_BACK;
    size_t h = 0, differ = 0;
    double t0 = cli_now();
    for (size_t i = 0; i < n; i++) {
        cbvh_hit_record culled;
        cbvh_raycast_with(d->file, &rays[i], &q, &culled, NULL);
        h += culled.tri != CBVH_NO_HIT;
    }
    double sec = cli_now() - t0;
    for (size_t i = 0; i < n; i++) { /* again, untimed, beside the plain record */
        cbvh_hit_record culled, plain;
        cbvh_raycast_with(d->file, &rays[i], &q, &culled, NULL);
        if (ref[i].tri == CBVH_NO_HIT) {
            differ += culled.tri != CBVH_NO_HIT;
            continue;
        }
        cbvh_raycast_with(d->file, &rays[i], NULL, &plain, NULL);
        const int ok = plain.front ? culled.tri == plain.tri
                                   : culled.tri == CBVH_NO_HIT || (culled.front && culled.t >= plain.t);
        if (!ok && differ++ == 0)
            report_failure(
                "back-face culled raycast: ray %zu: triangle %u (front %d) against the plain hit %u "
                "(front %d)",
                i, (unsigned)culled.tri, culled.front, (unsigned)plain.tri, plain.front);
    }
    d->failures += differ != 0;
    print_row(d, "raycast culling back faces", n, h, sec, "MRays/s",
              differ ? "DIFFERS from closest" : "front faces of closest, all rays");

    cbvh_query_options_init(&q, sizeof q);
    q.filter = collect_hit;
    size_t total = 0;
    differ = 0;
    t0 = cli_now();
    for (size_t i = 0; i < n; i++) {
        all_hits all = {0, {CBVH_NO_HIT, 0, 0, 0, {0, 0, 0}, 0, 0}};
        cbvh_hit_record none;
        q.filter_user = &all;
        cbvh_raycast_with(d->file, &rays[i], &q, &none, NULL);
        total += all.count;
        const int ok = none.tri == CBVH_NO_HIT && (all.count == 0) == (ref[i].tri == CBVH_NO_HIT) &&
                       (all.count == 0 || (all.nearest.tri == ref[i].tri && all.nearest.t == ref[i].t));
        if (!ok && differ++ == 0)
            report_failure(
                "all-hits raycast: ray %zu: nearest of %zu hits is triangle %u at t %g, the closest hit "
                "%u at t %g",
                i, all.count, (unsigned)all.nearest.tri, all.nearest.t, (unsigned)ref[i].tri, ref[i].t);
    }
    sec = cli_now() - t0;
    d->failures += differ != 0;
    print_row(d, "raycast all hits", n, total, sec, "MRays/s",
              differ ? "DIFFERS from closest" : "nearest = closest hit, all rays");
    demo_placed(d, rays, ref, n);
}

/* Compares a library hit with the brute force; grazing hits (near an edge) may go either way. */
static int ray_agrees(const demo *d, const cbvh_ray *r, const cbvh_hit *h)
{
    const double graze = 1e-4;
    double t_bf, margin;
    uint32_t tri = brute_raycast(d, r, &t_bf, &margin);
    double lib_margin = fmin(fmin(h->u, h->v), 1.0 - h->u - h->v);
    if (tri == CBVH_NO_HIT)
        return h->tri == CBVH_NO_HIT || lib_margin < graze;
    if (h->tri == CBVH_NO_HIT)
        return margin < graze;
    if (fabs(h->t - t_bf) <= 1e-4 * fmax(1.0, t_bf))
        return 1;
    /* A different triangle: acceptable only when one of the two hits grazes an edge. */
    return margin < graze || lib_margin < graze;
}

static int same_hit(const cbvh_hit *a, const cbvh_hit *b)
{
    if (a->tri == CBVH_NO_HIT || b->tri == CBVH_NO_HIT)
        return a->tri == b->tri;
    return a->tri == b->tri || fabs(a->t - b->t) <= 1e-5f * fmaxf(1.0f, a->t);
}

static void demo_raycasts(demo *d)
{
    size_t n = DEMO_RAYS;
    cbvh_ray *rays = malloc(n * sizeof *rays);
    cbvh_hit *ref = malloc(n * sizeof *ref), *hits = malloc(n * sizeof *hits);
    uint8_t *occ = malloc(n);
    if (!rays || !ref || !hits || !occ) {
        d->failures++;
        fprintf(stderr, "cbvh demo: out of memory\n");
        goto out;
    }
    make_rays(d, rays, n);

    /* Sorted closest hit is the reference the other traversals are compared with. */
    double t0 = cli_now();
    size_t hit_count = 0;
    for (size_t i = 0; i < n; i++)
        hit_count += (size_t)cbvh_raycast(d->file, &rays[i], CBVH_TRAVERSAL_SORTED, &ref[i], NULL);
    double sec = cli_now() - t0;
    int bad = 0;
    for (size_t i = 0; i < n; i += n / DEMO_RAY_SAMPLE)
        if (!ray_agrees(d, &rays[i], &ref[i]) && bad++ == 0)
            report_failure("sorted raycast: ray %zu: triangle %u at t %g disagrees with brute force", i,
                           (unsigned)ref[i].tri, ref[i].t);
    sample_row(d, "raycast closest sorted", n, hit_count, sec, "MRays/s", DEMO_RAY_SAMPLE, bad);

    static const struct {
        const char *name;
        int traversal; /* -1 = stream */
    } variants[] = {{"stackless", CBVH_TRAVERSAL_STACKLESS}, {"stream", -1}};
    for (size_t k = 0; k < 2; k++) {
        t0 = cli_now();
        if (variants[k].traversal < 0)
            cbvh_raycast_stream(d->file, rays, n, hits, NULL);
        else
            for (size_t i = 0; i < n; i++)
                cbvh_raycast(d->file, &rays[i], (cbvh_traversal)variants[k].traversal, &hits[i], NULL);
        sec = cli_now() - t0;
        size_t h = 0, differ = 0;
        for (size_t i = 0; i < n; i++) {
            h += hits[i].tri != CBVH_NO_HIT;
            if (!same_hit(&hits[i], &ref[i]) && differ++ == 0)
                report_failure("raycast %s: ray %zu: t %g differs from the sorted traversal's t %g",
                               variants[k].name, i, hits[i].t, ref[i].t);
        }
        d->failures += differ != 0;
        char name[40];
        snprintf(name, sizeof name, "raycast closest %s", variants[k].name);
        print_row(d, name, n, h, sec, "MRays/s", differ ? "DIFFERS from sorted" : "= sorted, all rays");
    }

    /* Any hit must agree with "the closest hit exists", traversal by traversal. */
    static const struct {
        const char *name;
        int traversal;
    } any[] = {{"sorted", CBVH_TRAVERSAL_SORTED}, {"stackless", CBVH_TRAVERSAL_STACKLESS}, {"stream", -1}};
    for (size_t k = 0; k < 3; k++) {
        t0 = cli_now();
        if (any[k].traversal < 0)
            cbvh_occluded_stream(d->file, rays, n, occ, NULL);
        else
            for (size_t i = 0; i < n; i++)
                occ[i] = (uint8_t)cbvh_occluded(d->file, &rays[i], (cbvh_traversal)any[k].traversal, NULL);
        sec = cli_now() - t0;
        size_t h = 0, differ = 0;
        for (size_t i = 0; i < n; i++) {
            h += occ[i] != 0;
            if ((occ[i] != 0) != (ref[i].tri != CBVH_NO_HIT) && differ++ == 0)
                report_failure("occluded %s: ray %zu: answer %d differs from the closest hit's", any[k].name,
                               i, occ[i]);
        }
        d->failures += differ != 0;
        char name[40];
        snprintf(name, sizeof name, "raycast any %s", any[k].name);
        print_row(d, name, n, h, sec, "MRays/s", differ ? "DIFFERS from closest" : "= closest hit, all rays");
    }
    demo_options(d, rays, ref, n);
out:
    free(rays);
    free(ref);
    free(hits);
    free(occ);
}

/* ---- sweeps and overlaps ---- */

typedef enum shape_kind { SHAPE_SPHERE, SHAPE_CAPSULE, SHAPE_BOX } shape_kind;

typedef struct shape {
    float center[3], axis[3]; /* capsule: segment center +- axis */
    float radius;             /* sphere, capsule */
    float half[3];            /* box */
    float delta[3];
} shape;

static void make_shape(demo *d, shape_kind kind, shape *s)
{
    float size = (float)d->diag;
    for (int a = 0; a < 3; a++)
        s->center[a] = in_range(d, d->lo[a], d->hi[a]);
    random_direction(d, s->delta);
    float len = in_range(d, 0.02f, 0.2f) * size;
    random_direction(d, s->axis);
    for (int a = 0; a < 3; a++) {
        s->delta[a] *= len;
        s->axis[a] *= 0.01f * size;
        s->half[a] = in_range(d, 0.002f, 0.015f) * size;
    }
    s->radius = in_range(d, 0.002f, 0.015f) * size;
    (void)kind;
}

/* Box around the shape over the motion fractions [f0, f1], grown by `margin`. */
static void shape_bounds(shape_kind kind, const shape *s, double f0, double f1, double margin, double lo[3],
                         double hi[3])
{
    for (int a = 0; a < 3; a++) {
        double ext =
            kind == SHAPE_BOX ? s->half[a] : s->radius + (kind == SHAPE_CAPSULE ? fabs(s->axis[a]) : 0);
        double c0 = s->center[a] + f0 * s->delta[a], c1 = s->center[a] + f1 * s->delta[a];
        lo[a] = fmin(c0, c1) - ext - margin;
        hi[a] = fmax(c0, c1) + ext + margin;
    }
}

/* Can triangle i touch the box [lo, hi]? (a quick reject before the exact tests) */
static int triangle_near(const demo *d, uint32_t i, const double lo[3], const double hi[3])
{
    const double *t9 = d->tris + 9 * (size_t)i;
    for (int a = 0; a < 3; a++)
        if (fmax(t9[a], fmax(t9[3 + a], t9[6 + a])) < lo[a] ||
            fmin(t9[a], fmin(t9[3 + a], t9[6 + a])) > hi[a])
            return 0;
    return d->valid[i];
}

/* Does the shape, moved by fraction f of its motion and shrunk by `shrink`, touch triangle i? */
static int shape_touches(const demo *d, shape_kind kind, const shape *s, double f, double shrink, uint32_t i)
{
    const double *t9 = d->tris + 9 * (size_t)i;
    double c[3];
    for (int a = 0; a < 3; a++)
        c[a] = s->center[a] + f * s->delta[a];
    if (kind == SHAPE_BOX) {
        double lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            double half = s->half[a] - shrink;
            if (half < 0)
                return 0;
            lo[a] = c[a] - half;
            hi[a] = c[a] + half;
        }
        return ref_triangle_box_overlap(t9, lo, hi, 0.0);
    }
    double r = s->radius - shrink;
    if (r < 0)
        return 0;
    if (kind == SHAPE_SPHERE)
        return ref_point_triangle_dist2(t9, c) <= r * r;
    double p0[3], p1[3];
    for (int a = 0; a < 3; a++) {
        p0[a] = c[a] - s->axis[a];
        p1[a] = c[a] + s->axis[a];
    }
    return ref_segment_triangle_dist(t9, p0, p1) <= r;
}

static int run_sweep(const demo *d, shape_kind kind, const shape *s, cbvh_sweep_hit *h)
{
    if (kind == SHAPE_SPHERE)
        return cbvh_sweep_sphere(d->file, s->center, s->radius, s->delta, h);
    if (kind == SHAPE_BOX)
        return cbvh_sweep_box(d->file, s->center, s->half, s->delta, h);
    float p0[3], p1[3];
    for (int a = 0; a < 3; a++) {
        p0[a] = s->center[a] - s->axis[a];
        p1[a] = s->center[a] + s->axis[a];
    }
    return cbvh_sweep_capsule(d->file, p0, p1, s->radius, s->delta, h);
}

/* A sweep's answer against sampling: no triangle is penetrated (beyond the tolerance) before the
 * reported contact (or anywhere along a missed motion), and the reported triangle is touched
 * at the contact (within the tolerance). */
static int sweep_agrees(const demo *d, shape_kind kind, const shape *s, int hit, const cbvh_sweep_hit *h)
{
    double end = hit ? h->t : 1.0, lo[3], hi[3];
    if (hit &&
        (h->tri >= d->tri_count || !d->valid[h->tri] || !shape_touches(d, kind, s, h->t, -d->tol, h->tri)))
        return 0;
    if (end == 0)
        return 1; /* overlapping at the start: the reported triangle touches, nothing else to check */
    shape_bounds(kind, s, 0, end, d->tol, lo, hi);
    for (uint32_t i = 0; i < d->tri_count; i++) {
        if (!triangle_near(d, i, lo, hi))
            continue;
        /* The contact itself is excluded: just before it nothing may be penetrated. */
        for (int k = 0; k < DEMO_SWEEP_STEPS + !hit; k++)
            if (shape_touches(d, kind, s, end * k / DEMO_SWEEP_STEPS, d->tol, i))
                return 0;
    }
    return 1;
}

static void demo_sweeps(demo *d)
{
    static const char *const names[] = {"sweep sphere", "sweep capsule", "sweep box"};
    shape *shapes = malloc(DEMO_SHAPES * sizeof *shapes);
    cbvh_sweep_hit *hits = malloc(DEMO_SHAPES * sizeof *hits);
    int *hit = malloc(DEMO_SHAPES * sizeof *hit);
    if (!shapes || !hits || !hit) {
        d->failures++;
        fprintf(stderr, "cbvh demo: out of memory\n");
        goto out;
    }
    for (int kind = SHAPE_SPHERE; kind <= SHAPE_BOX; kind++) {
        for (size_t i = 0; i < DEMO_SHAPES; i++)
            make_shape(d, (shape_kind)kind, &shapes[i]);
        double t0 = cli_now();
        size_t count = 0;
        for (size_t i = 0; i < DEMO_SHAPES; i++)
            count += (size_t)(hit[i] = run_sweep(d, (shape_kind)kind, &shapes[i], &hits[i]));
        double sec = cli_now() - t0;
        int bad = 0;
        for (size_t i = 0; i < DEMO_SHAPES; i += DEMO_SHAPES / DEMO_SHAPE_SAMPLE)
            if (!sweep_agrees(d, (shape_kind)kind, &shapes[i], hit[i], &hits[i]) && bad++ == 0)
                report_failure("%s: query %zu (hit %d, t %g) disagrees with sampling the motion", names[kind],
                               i, hit[i], hit[i] ? hits[i].t : 1.0);
        sample_row(d, names[kind], DEMO_SHAPES, count, sec, "queries/s", DEMO_SHAPE_SAMPLE, bad);
    }
out:
    free(shapes);
    free(hits);
    free(hit);
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Every triangle the shape clearly touches is reported, none it clearly misses is. */
static int overlap_agrees(const demo *d, shape_kind kind, const shape *s, uint32_t *found, size_t n)
{
    double lo[3], hi[3];
    shape_bounds(kind, s, 0, 0, d->tol, lo, hi);
    qsort(found, n, sizeof *found, cmp_u32);
    for (size_t k = 0; k < n; k++)
        if (found[k] >= d->tri_count || !d->valid[found[k]] || (k > 0 && found[k] == found[k - 1]))
            return 0;
    for (uint32_t i = 0; i < d->tri_count; i++) {
        if (!triangle_near(d, i, lo, hi))
            continue;
        int reported = bsearch(&i, found, n, sizeof *found, cmp_u32) != NULL;
        if (reported && !shape_touches(d, kind, s, 0, -d->tol, i))
            return 0;
        if (!reported && shape_touches(d, kind, s, 0, d->tol, i))
            return 0;
    }
    return 1;
}

/* A box overlap in one query, or (paged) in pages of DEMO_OVERLAP_PAGE through cbvh_overlap_box_from,
 * each continuing where the last one's output filled; a sphere or capsule overlap. */
static size_t run_overlap(const demo *d, shape_kind kind, int paged, const shape *s, uint32_t *found)
{
    if (kind == SHAPE_SPHERE)
        return cbvh_overlap_sphere(d->file, s->center, s->radius, NULL, NULL, found, DEMO_OVERLAP_CAP);
    if (kind == SHAPE_CAPSULE) {
        float p0[3], p1[3];
        for (int a = 0; a < 3; a++) {
            p0[a] = s->center[a] - s->axis[a];
            p1[a] = s->center[a] + s->axis[a];
        }
        return cbvh_overlap_capsule(d->file, p0, p1, s->radius, NULL, NULL, found, DEMO_OVERLAP_CAP);
    }
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = s->center[a] - s->half[a];
        hi[a] = s->center[a] + s->half[a];
    }
    if (!paged)
        return cbvh_overlap_box(d->file, lo, hi, NULL, NULL, found, DEMO_OVERLAP_CAP);
    size_t n = 0;
    for (int more = 1; more && n + DEMO_OVERLAP_PAGE <= DEMO_OVERLAP_CAP;)
        n += cbvh_overlap_box_from(d->file, lo, hi, n, found + n, DEMO_OVERLAP_PAGE, &more);
    return n;
}

static void demo_overlaps(demo *d)
{
    static const char *const names[] = {"overlap sphere", "overlap capsule", "overlap box",
                                        "overlap box, pages of 256"};
    uint32_t *found = malloc(DEMO_OVERLAP_CAP * sizeof *found);
    shape *shapes = malloc(DEMO_SHAPES * sizeof *shapes);
    if (!found || !shapes) {
        d->failures++;
        fprintf(stderr, "cbvh demo: out of memory\n");
        goto out;
    }
    for (int k = 0; k < 4; k++) {
        shape_kind kind = k == 0 ? SHAPE_SPHERE : k == 1 ? SHAPE_CAPSULE : SHAPE_BOX;
        const int paged = k == 3;
        for (size_t i = 0; i < DEMO_SHAPES; i++) {
            make_shape(d, kind, &shapes[i]);
            shapes[i].radius *= 4; /* a little larger than the swept shapes, to gather several triangles */
            for (int a = 0; a < 3; a++)
                shapes[i].half[a] *= 4;
        }
        double t0 = cli_now();
        size_t hits = 0;
        for (size_t i = 0; i < DEMO_SHAPES; i++)
            hits += run_overlap(d, kind, paged, &shapes[i], found) != 0;
        double sec = cli_now() - t0;
        int bad = 0;
        for (size_t i = 0; i < DEMO_SHAPES; i += DEMO_SHAPES / DEMO_SHAPE_SAMPLE) {
            size_t n = run_overlap(d, kind, paged, &shapes[i], found);
            if (n < DEMO_OVERLAP_CAP && !overlap_agrees(d, kind, &shapes[i], found, n) && bad++ == 0)
                report_failure("%s: query %zu (%zu triangles) disagrees with brute force", names[k], i, n);
        }
        sample_row(d, names[k], DEMO_SHAPES, hits, sec, "queries/s", DEMO_SHAPE_SAMPLE, bad);
    }
out:
    free(found);
    free(shapes);
}

/* Boxes turned by a random rotation (cbvh_sweep_with): the reported triangle is touched at the contact,
 * nothing is penetrated before it (sampling the motion, the box shrunk by the tolerance), and a box that
 * starts in contact, moved by its depth (+ tolerance) along the normal, is clear of the triangle. */
static void demo_oriented_boxes(demo *d)
{
    shape *shapes = malloc(DEMO_SHAPES * sizeof *shapes);
    cbvh_shape *boxes = malloc(DEMO_SHAPES * sizeof *boxes);
    cbvh_sweep_record *recs = malloc(DEMO_SHAPES * sizeof *recs);
    if (!shapes || !boxes || !recs) {
        d->failures++;
        fprintf(stderr, "cbvh demo: out of memory\n");
        goto out;
    }
    for (size_t i = 0; i < DEMO_SHAPES; i++) {
        make_shape(d, SHAPE_BOX, &shapes[i]);
        memset(&boxes[i], 0, sizeof boxes[i]);
        boxes[i].kind = CBVH_SHAPE_BOX;
        float axis[3];
        random_direction(d, axis);
        const double half_angle = in_range(d, 0.0f, 3.14159265f) / 2.0;
        for (int a = 0; a < 3; a++) {
            boxes[i].center[a] = shapes[i].center[a];
            boxes[i].half_extent[a] = shapes[i].half[a];
            boxes[i].rotation[a] = (float)(sin(half_angle) * axis[a]);
        }
        boxes[i].rotation[3] = (float)cos(half_angle);
    }
    size_t count = 0;
    const double t0 = cli_now();
    for (size_t i = 0; i < DEMO_SHAPES; i++) {
        cbvh_sweep_with(d->file, &boxes[i], shapes[i].delta, NULL, &recs[i]);
        count += recs[i].tri != CBVH_NO_HIT;
    }
    const double sec = cli_now() - t0;
    int bad = 0;
    for (size_t i = 0; i < DEMO_SHAPES; i += DEMO_SHAPES / DEMO_SHAPE_SAMPLE) {
        const shape *s = &shapes[i];
        const cbvh_sweep_record *h = &recs[i];
        const int hit = h->tri != CBVH_NO_HIT;
        ref_shape box, shrunk;
        memset(&box, 0, sizeof box);
        box.kind = REF_BOX;
        box.rotated = 1;
        quaternion_matrix(boxes[i].rotation, box.axes);
        double reach = 0.0, lo[3], hi[3];
        const double delta[3] = {s->delta[0], s->delta[1], s->delta[2]}, zero[3] = {0, 0, 0};
        for (int a = 0; a < 3; a++) {
            box.p0[a] = box.p1[a] = s->center[a];
            box.half[a] = s->half[a];
            reach += (double)s->half[a] * s->half[a];
        }
        shrunk = box;
        for (int a = 0; a < 3; a++)
            shrunk.half[a] = fmax(0.0, box.half[a] - d->tol);
        const double end = hit ? h->t : 1.0;
        int ok = !hit || (h->tri < d->tri_count && d->valid[h->tri] &&
                          ref_shape_triangle_dist(&box, delta, end, d->tris + 9 * (size_t)h->tri) <= d->tol);
        if (ok && hit && h->t == 0.0f) {
            ref_shape clear = box;
            for (int a = 0; a < 3; a++)
                clear.p0[a] += (h->depth + d->tol) * h->normal[a];
            ok = ref_shape_triangle_dist(&clear, zero, 0.0, d->tris + 9 * (size_t)h->tri) > 0.0;
        }
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(s->center[a], s->center[a] + end * delta[a]) - sqrt(reach) - d->tol;
            hi[a] = fmax(s->center[a], s->center[a] + end * delta[a]) + sqrt(reach) + d->tol;
        }
        for (uint32_t k = 0; k < d->tri_count && ok && end > 0.0; k++)
            for (int step = 0; step < DEMO_SWEEP_STEPS + !hit && ok && triangle_near(d, k, lo, hi); step++)
                ok = ref_shape_triangle_dist(&shrunk, delta, end * step / DEMO_SWEEP_STEPS,
                                             d->tris + 9 * (size_t)k) > 0.0;
        if (!ok && bad++ == 0)
            report_failure("sweep oriented box: query %zu (hit %d, t %g) disagrees with sampling the motion",
                           i, hit, end);
    }
    sample_row(d, "sweep box, oriented", DEMO_SHAPES, count, sec, "queries/s", DEMO_SHAPE_SAMPLE, bad);
out:
    free(shapes);
    free(boxes);
    free(recs);
}

/* Contacts (penetration depth and separating direction) of balls with what they overlap: each depth is the
 * radius less the brute-force distance from the center to its triangle. */
static void demo_contacts(demo *d)
{
    shape *shapes = malloc(DEMO_SHAPES * sizeof *shapes);
    cbvh_contact *contacts = malloc(DEMO_OVERLAP_CAP * sizeof *contacts);
    if (!shapes || !contacts) {
        d->failures++;
        fprintf(stderr, "cbvh demo: out of memory\n");
        goto out;
    }
    for (size_t i = 0; i < DEMO_SHAPES; i++) {
        make_shape(d, SHAPE_SPHERE, &shapes[i]);
        shapes[i].radius *= 4;
    }
    size_t touched = 0;
    const double t0 = cli_now();
    for (size_t i = 0; i < DEMO_SHAPES; i++)
        touched += cbvh_contacts_sphere(d->file, shapes[i].center, shapes[i].radius, 0, contacts,
                                        DEMO_OVERLAP_CAP, NULL) != 0;
    const double sec = cli_now() - t0;
    int bad = 0;
    for (size_t i = 0; i < DEMO_SHAPES; i += DEMO_SHAPES / DEMO_SHAPE_SAMPLE) {
        const shape *s = &shapes[i];
        const size_t n =
            cbvh_contacts_sphere(d->file, s->center, s->radius, 0, contacts, DEMO_OVERLAP_CAP, NULL);
        for (size_t k = 0; k < n; k++) {
            const double c[3] = {s->center[0], s->center[1], s->center[2]};
            const double dist = sqrt(ref_point_triangle_dist2(d->tris + 9 * (size_t)contacts[k].tri, c));
            if (!(fabs(contacts[k].depth - (s->radius - dist)) <= d->tol) && bad++ == 0)
                report_failure("contacts sphere: query %zu, triangle %u: depth %g, radius less distance %g",
                               i, (unsigned)contacts[k].tri, (double)contacts[k].depth, s->radius - dist);
        }
    }
    sample_row(d, "contacts sphere (depth)", DEMO_SHAPES, touched, sec, "queries/s", DEMO_SHAPE_SAMPLE, bad);
out:
    free(shapes);
    free(contacts);
}

/* ---- the demo ---- */

static int demo_load(demo *d, const cbvh_file *f)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    d->file = f;
    d->tri_count = info.original_triangle_count;
    d->tris = malloc(9 * (size_t)d->tri_count * sizeof(double));
    d->valid = malloc(d->tri_count);
    if (!d->tris || !d->valid)
        return 0;
    for (uint32_t i = 0; i < d->tri_count; i++) {
        float v[3][3];
        d->valid[i] = (uint8_t)cbvh_file_get_triangle(f, i, v[0], v[1], v[2]);
        for (int k = 0; k < 3; k++)
            to_double(d->tris + 9 * (size_t)i + 3 * k, d->valid[i] ? v[k] : info.bounds_min);
    }
    double diag2 = 0;
    for (int a = 0; a < 3; a++) {
        d->lo[a] = info.bounds_min[a];
        d->hi[a] = info.bounds_max[a];
        diag2 += ((double)d->hi[a] - d->lo[a]) * ((double)d->hi[a] - d->lo[a]);
    }
    d->diag = sqrt(diag2);
    d->tol = 1e-4 * d->diag;
    return 1;
}

int cmd_demo(int argc, char **argv)
{
    static const cli_option options[] = {{"quiet", CLI_ARG_NONE, 1}, {"json", CLI_ARG_NONE, 2}, {NULL, 0, 0}};
    int json = 0;
    demo d;
    memset(&d, 0, sizeof d);
    d.rng = 20240601;
    cli_parser p;
    cli_init(&p, "demo", usage, argc, argv);
    const char *value;
    int id;
    while ((id = cli_next(&p, options, &value)) != CLI_END) {
        if (id == CLI_DONE)
            return CLI_EXIT_OK;
        if (id == CLI_ERROR)
            return CLI_EXIT_USAGE;
        if (id == CLI_POSITIONAL)
            return cli_usage_error("demo", "unexpected argument '%s'", value);
        json |= id == 2;
        d.quiet = 1;
    }

    scene s;
    if (!scene_demo(&s)) {
        cli_error("demo", NULL, "out of memory generating the scene");
        return CLI_EXIT_USAGE;
    }
    uint32_t materials = 0;
    for (size_t i = 0; i < s.triangle_count; i++)
        if (s.material_ids && s.material_ids[i] + 1 > materials)
            materials = s.material_ids[i] + 1;

    const char *tmp = getenv("TMPDIR");
    char dir[4096], path[4200];
    snprintf(dir, sizeof dir, "%s/cbvh-demo-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        cli_error("demo", dir, "cannot create a temporary folder");
        scene_free(&s);
        return CLI_EXIT_USAGE;
    }
    snprintf(path, sizeof path, "%s/demo.cbvh", dir);
    temp_cleanup_add(dir, NULL);
    temp_cleanup_add(path, NULL);

    cbvh_mesh mesh = {s.positions, s.vertex_count, 0, s.indices, s.triangle_count, s.material_ids};
    cbvh_cook_options opt;
    cbvh_cook_options_init(&opt, sizeof opt);
    cbvh_cook_stats st;
    cbvh_cook_stats_init(&st, sizeof st);
    cbvh_error err;
    double t0 = cli_now();
    cbvh_result res = cbvh_cook_to_path(&mesh, &opt, NULL, path, &st, &err);
    double cook_sec = cli_now() - t0;
    scene_free(&s);
    int rc = CLI_EXIT_OK;
    cbvh_file *file = NULL;
    if (res != CBVH_OK) {
        rc = cli_report("demo", path, &err);
        goto out;
    }
    t0 = cli_now();
    res = cbvh_open_path(path, NULL, &file, &err);
    double open_sec = cli_now() - t0;
    if (res != CBVH_OK) {
        rc = cli_report("demo", path, &err);
        goto out;
    }
    if (!demo_load(&d, file)) {
        cli_error("demo", NULL, "out of memory");
        rc = CLI_EXIT_USAGE;
        goto out;
    }
    if (!d.quiet) {
        printf("cbvh demo: built-in scene (terrain and 12 spheres, %u materials): %llu triangles, %llu "
               "vertices\n",
               (unsigned)materials, (unsigned long long)st.triangles, (unsigned long long)st.vertices);
        printf("  cook  %8.3f s  %llu nodes, depth %u, SAH cost %.1f\n", cook_sec,
               (unsigned long long)st.nodes, (unsigned)st.depth, st.sah_cost);
        printf("  file  %8llu bytes, %.2f bytes/triangle\n", (unsigned long long)st.file_size,
               (double)st.file_size / (double)st.triangles);
        printf("  open  %8.3f ms (mapped and fully validated)\n\n", open_sec * 1e3);
        printf("  %-26s %8s %8s %10s %-10s %s\n", "query", "count", "hits", "speed", "", "check");
    }
    demo_raycasts(&d);
    demo_sweeps(&d);
    demo_oriented_boxes(&d);
    demo_overlaps(&d);
    demo_contacts(&d);
    if (json) {
        json_writer w;
        json_init(&w, stdout);
        json_begin_object(&w, NULL);
        json_bool(&w, "ok", d.failures == 0);
        json_uint(&w, "failed_checks", (uint64_t)d.failures);
        json_uint(&w, "triangles", st.triangles);
        json_end_object(&w);
        json_finish(&w);
        cli_json_error_printed();
        rc = d.failures ? CLI_EXIT_BAD_INPUT : CLI_EXIT_OK;
    } else if (d.failures) {
        printf("cbvh demo: FAILED: %d check%s disagreed (details on stderr)\n", d.failures,
               d.failures == 1 ? "" : "s");
        rc = CLI_EXIT_BAD_INPUT;
    } else {
        printf("cbvh demo: ok: every query kind ran and agreed with the brute-force checks\n");
    }
out:
    cbvh_close(file);
    free(d.tris);
    free(d.valid);
    unlink(path);
    rmdir(dir);
    temp_cleanup_done(path);
    temp_cleanup_done(dir);
    return rc;
}
