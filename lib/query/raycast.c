/* raycast.c: the public single-ray entry points, cbvh_raycast and cbvh_occluded. */
#ifdef HAVE_CONFIG_H
#include "config.h"
#endif

#include <math.h>
#include <string.h>

#include "common/struct_size.h"
#include "query/placement.h"
#include "query/raycast.h"

int cbvh_hit_output(const struct cbvh_file *f, const struct cbvh_best_hit *best,
                    const struct cbvh_t_frame *frame, cbvh_hit *hit)
{
    if (best->tri == UINT32_MAX) {
        if (hit)
            hit->tri = CBVH_NO_HIT;
        return 0;
    }
    if (hit) {
        hit->tri = cbvh_original_id(f, best->tri);
        hit->t = cbvh_t_frame_out(frame, best->t);
        hit->u = best->u;
        hit->v = best->v;
    }
    return 1;
}

/* Named traversals; an unknown one is a miss. */
static int known_traversal(cbvh_traversal traversal)
{
    return traversal == CBVH_TRAVERSAL_SORTED || traversal == CBVH_TRAVERSAL_UNSORTED ||
           traversal == CBVH_TRAVERSAL_STACKLESS || traversal == CBVH_TRAVERSAL_DISTANCE;
}

/* A NULL file or ray, an unknown traversal and an invalid ray are all misses. */
CBVH_API int cbvh_raycast(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal, cbvh_hit *hit,
                          cbvh_query_stats *stats)
{
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    struct cbvh_ray_ctx ctx;
    if (file && ray && known_traversal(traversal) &&
        cbvh_ray_prepare(&ctx, ray, file, stats ? &stats->nodes_visited : NULL))
        cbvh_closest(file, &ctx, traversal, &best, stats);
    return cbvh_hit_output(file, &best, &ctx.t_frame, hit);
}

CBVH_API int cbvh_occluded(const cbvh_file *file, const cbvh_ray *ray, cbvh_traversal traversal,
                           cbvh_query_stats *stats)
{
    struct cbvh_ray_ctx ctx;
    if (!file || !ray || !known_traversal(traversal) ||
        !cbvh_ray_prepare(&ctx, ray, file, stats ? &stats->nodes_visited : NULL))
        return 0;
    return cbvh_any(file, &ctx, traversal, stats);
}

#define QUERY_OPTIONS_SIZE_MIN CBVH_STRUCT_SIZE_MIN(cbvh_query_options, traversal)

static void query_options_defaults(cbvh_query_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    o->traversal = CBVH_TRAVERSAL_SORTED;
    o->cull = CBVH_CULL_NONE;
}

CBVH_API cbvh_result cbvh_query_options_init(cbvh_query_options *options, size_t struct_size)
{
    if (!cbvh_struct_size_record(options, struct_size, QUERY_OPTIONS_SIZE_MIN, sizeof *options))
        return CBVH_ERROR_INVALID_ARGUMENT;
    cbvh_query_options defaults;
    query_options_defaults(&defaults);
    defaults.struct_size = struct_size;
    memcpy(options, &defaults, struct_size);
    return CBVH_OK;
}

cbvh_result cbvh_query_options_read(const cbvh_query_options *options, cbvh_query_options *o)
{
    query_options_defaults(o);
    if (options) {
        if (!cbvh_struct_size_ok(options->struct_size, QUERY_OPTIONS_SIZE_MIN, sizeof *options))
            return CBVH_ERROR_INVALID_ARGUMENT;
        memcpy(o, options, options->struct_size);
    }
    const int known_cull =
        o->cull == CBVH_CULL_NONE || o->cull == CBVH_CULL_BACK || o->cull == CBVH_CULL_FRONT;
    return known_traversal(o->traversal) && known_cull ? CBVH_OK : CBVH_ERROR_INVALID_ARGUMENT;
}

/* The record of cooked triangle k hit at the kernels' t: the normal from the edges in double, scaled by
 * their largest component first so that neither tiny nor huge coordinates underflow or overflow it. */
void cbvh_hit_record_fill(const struct cbvh_file *f, uint32_t k, const struct cbvh_t_frame *frame, float t,
                          float u, float v, const float dir[3], cbvh_hit_record *r)
{
    float p[3][3];
    cbvh_triangle_vertices(f, k, p[0], p[1], p[2]);
    double e1[3], e2[3], big = 0.0;
    for (int a = 0; a < 3; a++) {
        e1[a] = (double)p[1][a] - p[0][a];
        e2[a] = (double)p[2][a] - p[0][a];
        big = fmax(big, fmax(fabs(e1[a]), fabs(e2[a])));
    }
    double n[3] = {0.0, 0.0, 0.0}, len = 0.0, facing = 0.0;
    if (big > 0.0) {
        for (int a = 0; a < 3; a++) {
            e1[a] /= big;
            e2[a] /= big;
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    for (int a = 0; a < 3; a++) {
        r->normal[a] = len > 0.0 ? (float)(n[a] / len) : 0.0f;
        facing += n[a] * dir[a];
    }
    r->tri = cbvh_original_id(f, k);
    r->t = cbvh_t_frame_out(frame, t);
    r->u = u;
    r->v = v;
    r->front = facing < 0.0;
    r->material = cbvh_cooked_material(f, k);
}

/* A record of the mesh's frame rotated into the world of a query transform (t, u, v, front stay). */
static void record_place(const struct cbvh_hit_gate *gate, cbvh_hit_record *r)
{
    if (!gate->placed)
        return;
    double n[3];
    for (int i = 0; i < 3; i++)
        n[i] = gate->rotation[i][0] * r->normal[0] + gate->rotation[i][1] * r->normal[1] +
               gate->rotation[i][2] * r->normal[2];
    for (int i = 0; i < 3; i++)
        r->normal[i] = (float)n[i];
}

/* The gate's check (leaf.h): culling first, then the caller's filter. */
static int gate_check(const struct cbvh_hit_gate *gate, const struct cbvh_file *f, uint32_t k, float t,
                      float u, float v)
{
    cbvh_hit_record r;
    cbvh_hit_record_fill(f, k, &gate->t_frame, t, u, v, gate->dir, &r);
    record_place(gate, &r);
    if ((gate->cull == CBVH_CULL_BACK && !r.front) || (gate->cull == CBVH_CULL_FRONT && r.front))
        return CBVH_FILTER_REJECT;
    if (!gate->filter)
        return CBVH_FILTER_ACCEPT;
    const cbvh_filter_result verdict = gate->filter(gate->user, &r);
    return verdict == CBVH_FILTER_REJECT || verdict == CBVH_FILTER_STOP ? (int)verdict : CBVH_FILTER_ACCEPT;
}

void cbvh_hit_gate_init(struct cbvh_hit_gate *gate, cbvh_cull cull, cbvh_hit_filter_fn filter, void *user,
                        const double (*rotation)[3], const float dir[3], const struct cbvh_t_frame *frame)
{
    gate->check = gate_check;
    gate->cull = cull;
    gate->filter = filter;
    gate->user = user;
    gate->t_frame = *frame;
    for (int a = 0; a < 3; a++)
        gate->dir[a] = dir[a];
    gate->placed = rotation != NULL;
    if (rotation)
        memcpy(gate->rotation, rotation, sizeof gate->rotation);
}

/* The ray `world` taken into the mesh's frame of placement p: local = R^T (world - translation) / scale, in
 * double, rounded to float once. Returns 0 for a local ray that overflows float. */
static int place_ray(const struct cbvh_placement *p, const cbvh_ray *world, cbvh_ray *local)
{
    const cbvh_v3 org = cbvh_point_to_mesh(p, v3_from_f(world->org));
    const cbvh_v3 dir = cbvh_vector_to_mesh(p, v3_from_f(world->dir));
    *local = *world;
    v3_to_f(org, local->org);
    v3_to_f(dir, local->dir);
    return cbvh_all_finite(local->org, 3) && cbvh_all_finite(local->dir, 3);
}

/* A query with options: the closest hit into *hit or, hit NULL, occlusion into *occluded, the ray taken into
 * the mesh's frame and walked with the options' gate (without culling or filter every hit counts: the plain
 * walk; a transform only rotates the answer). */
static cbvh_result query_with(const cbvh_file *file, const cbvh_ray *world, const cbvh_query_options *options,
                              cbvh_hit_record *hit, int *occluded, cbvh_query_stats *stats)
{
    cbvh_query_options o;
    if (cbvh_query_options_read(options, &o) != CBVH_OK)
        return CBVH_ERROR_INVALID_ARGUMENT;
    cbvh_ray local;
    const cbvh_ray *ray = world;
    struct cbvh_placement placement;
    const struct cbvh_placement *p; /* NULL by default, and for a caller whose struct ends before transform */
    if (!cbvh_placement_of_option(o.transform, &placement, &p) ||
        (p && (!world || !place_ray(p, world, &local))))
        return CBVH_ERROR_INVALID_ARGUMENT;
    if (p)
        ray = &local;
    if (!file || !ray || !cbvh_ray_valid(ray))
        return CBVH_ERROR_INVALID_ARGUMENT;
    struct cbvh_ray_ctx ctx;
    struct cbvh_hit_gate gate;
    const int walk = cbvh_ray_prepare(&ctx, ray, file, stats ? &stats->nodes_visited : NULL);
    cbvh_hit_gate_init(&gate, o.cull, o.filter, o.filter_user, p ? p->rotation : NULL, ray->dir,
                       &ctx.t_frame);
    ctx.gate = o.cull != CBVH_CULL_NONE || o.filter ? &gate : NULL;
    if (occluded) {
        *occluded = walk && cbvh_any(file, &ctx, o.traversal, stats);
        return CBVH_OK;
    }
    struct cbvh_best_hit best = {UINT32_MAX, 0.0f, 0.0f, 0.0f};
    if (walk)
        cbvh_closest(file, &ctx, o.traversal, &best, stats);
    if (best.tri != UINT32_MAX) {
        cbvh_hit_record_fill(file, best.tri, &ctx.t_frame, best.t, best.u, best.v, gate.dir, hit);
        record_place(&gate, hit);
    }
    return CBVH_OK;
}

CBVH_API cbvh_result cbvh_raycast_with(const cbvh_file *file, const cbvh_ray *ray,
                                       const cbvh_query_options *options, cbvh_hit_record *hit,
                                       cbvh_query_stats *stats)
{
    if (!hit)
        return CBVH_ERROR_INVALID_ARGUMENT;
    memset(hit, 0, sizeof *hit);
    hit->tri = CBVH_NO_HIT;
    return query_with(file, ray, options, hit, NULL, stats);
}

CBVH_API cbvh_result cbvh_occluded_with(const cbvh_file *file, const cbvh_ray *ray,
                                        const cbvh_query_options *options, int *occluded,
                                        cbvh_query_stats *stats)
{
    if (!occluded)
        return CBVH_ERROR_INVALID_ARGUMENT;
    *occluded = 0;
    return query_with(file, ray, options, NULL, occluded, stats);
}
