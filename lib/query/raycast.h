/* raycast.h: the single-ray traversal kernels behind cbvh_raycast and cbvh_occluded. */
#ifndef CBVH_QUERY_RAYCAST_H
#define CBVH_QUERY_RAYCAST_H

#include <stdatomic.h>

#include "common/file.h"
#include "layout/tree.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/ray_setup.h"

/* For a validated ray, the closest hit into *best (cooked index, UINT32_MAX for none), or whether any
 * triangle occludes the ray, by the walk `traversal` names (unknown: sorted). A ray with box_halve takes the
 * sorted walk whatever the traversal (the tie rule makes the answers alike). stats may be NULL. */
void cbvh_closest(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
                  struct cbvh_best_hit *best, cbvh_query_stats *stats);
int cbvh_any(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
             cbvh_query_stats *stats);

/* The wide layout's walk kernels (the binary layout has one, scalar). The shape queries follow the choice
 * on either layout: sweeps (sweep_walk.c) one leaf triangle at a time with SCALAR, CBVH_LANES a vector
 * otherwise; overlaps and contacts (overlap.c) four with SCALAR and SSE2, eight with AVX2. */
enum cbvh_walk_kernel {
    CBVH_WALK_KERNEL_BEST,   /* the fastest the build and the CPU have: AVX2, else SSE2, else scalar */
    CBVH_WALK_KERNEL_SCALAR, /* child boxes and leaf triangles one at a time (builds without SIMD) */
    CBVH_WALK_KERNEL_SSE2,   /* four child boxes at once, leaf triangles through a four-lane filter */
    CBVH_WALK_KERNEL_AVX2    /* leaf triangles eight lanes at a time (CPUs with AVX2, BMI1, BMI2 and FMA) */
};

/* The wide layout's walk kernel once chosen (kernel_choice.c, or a test hook): BEST until the first walk. */
extern atomic_int cbvh_walk_kernel_chosen;

/* Chooses the best kernel the build and the CPU have for the wide layout's walks, and returns it. */
int cbvh_walk_kernel_choose_best(void);

/* The kernel the wide layout's walks take now (never BEST); the streams follow it. Threads racing through
 * the first walk choose the same kernel. */
static inline int cbvh_walk_kernel(void)
{
    const int chosen = atomic_load_explicit(&cbvh_walk_kernel_chosen, memory_order_relaxed);
    return CBVH_LIKELY(chosen != CBVH_WALK_KERNEL_BEST) ? chosen : cbvh_walk_kernel_choose_best();
}

/* An origin farther than this many times the mesh's extent from its bounds is moved next to them, so that
 * coordinates relative to it keep their precision at the mesh. */
#define CBVH_FAR_FACTOR 16.0f
_Static_assert(4 * CBVH_NEAR_ORIGIN_FACTOR <= (int)CBVH_FAR_FACTOR,
               "the near-origin box (common/file.h) lies well inside the distance that moves an origin");

/* For a validated ray whose origin lies outside f's origin_near box: moves an origin farther than
 * CBVH_FAR_FACTOR extents from f's bounds next to them (ctx->t_frame.base: its t), and sets ctx->box_halve
 * on the axes where a node plane minus the origin can overflow. */
void cbvh_ray_place_origin(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray, const struct cbvh_file *f);

/* Whether the ray's origin lies in the box [lo, hi] (lane 3 is not looked at: the ray's load reads tmin). */
static inline int cbvh_origin_in(const cbvh_ray *ray, const float lo[4], const float hi[4])
{
#ifdef CBVH_HAVE_SIMD
    const __m128 o = _mm_loadu_ps(ray->org);
    return (_mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(o, _mm_load_ps(lo)), _mm_cmple_ps(o, _mm_load_ps(hi)))) &
            7) == 7;
#else
    return ray->org[0] >= lo[0] && ray->org[0] <= hi[0] && ray->org[1] >= lo[1] && ray->org[1] <= hi[1] &&
           ray->org[2] >= lo[2] && ray->org[2] <= hi[2];
#endif
}

/* Whether the ray (ctx as cbvh_ray_setup_boxes left it, origin org) enters f's top box by cbvh_slab_test,
 * lane for lane (MAXPS and MINPS skip a NaN distance as its compares do). Every box a walk tests lies in
 * the top box and rounding is monotonic, so a ray kept out of it hits nothing. For an origin next to the
 * mesh (no box_halve). */
static inline int cbvh_ray_enters_top_box(const struct cbvh_ray_ctx *ctx, const float org[3],
                                          const struct cbvh_file *f)
{
#ifdef CBVH_HAVE_SIMD
    const __m128 o = cbvh_load3(org), rcp = cbvh_load3(ctx->rcp);
    const __m128 t_lo = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f->top_lo), o), rcp);
    const __m128 t_hi = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(f->top_hi), o), rcp);
    /* the near plane is the high one where rcp's sign bit is set (the octant's rule, -0 included) */
    const __m128 negative = _mm_castsi128_ps(_mm_srai_epi32(_mm_castps_si128(rcp), 31));
    const __m128 t_near = _mm_or_ps(_mm_and_ps(negative, t_hi), _mm_andnot_ps(negative, t_lo));
    const __m128 t_far = _mm_or_ps(_mm_and_ps(negative, t_lo), _mm_andnot_ps(negative, t_hi));
    const __m128 enter = _mm_max_ps(t_near, _mm_set1_ps(ctx->tmin)); /* lane 3 (0 * 0) taken out below */
    const __m128 leave = _mm_min_ps(t_far, _mm_set1_ps(ctx->tmax));
    const __m128 enter_x =
        _mm_max_ss(enter, _mm_max_ss(_mm_shuffle_ps(enter, enter, 1), _mm_movehl_ps(enter, enter)));
    const __m128 leave_x =
        _mm_min_ss(leave, _mm_min_ss(_mm_shuffle_ps(leave, leave, 1), _mm_movehl_ps(leave, leave)));
    return _mm_cvtss_f32(enter_x) <= _mm_cvtss_f32(leave_x) * CBVH_BOX_PAD;
#else
    const struct cbvh_slab_select s = cbvh_slab_select_of(ctx->octant);
    const float planes[6] = {f->top_lo[0], f->top_lo[1], f->top_lo[2],
                             f->top_hi[0], f->top_hi[1], f->top_hi[2]};
    float entry;
    return cbvh_slab_test(planes[s.near_x], planes[s.near_y], planes[s.near_z], planes[s.far_x],
                          planes[s.far_y], planes[s.far_z], org, ctx->rcp, ctx->tmin, ctx->tmax, &entry);
#endif
}

/* The set-up of a ray cast into file f (cbvh_ray_setup's), a far origin moved (cbvh_ray_place_origin) and
 * any_flip set for an origin inside the bounds. Returns 0 when there is nothing to walk: an invalid ray, or
 * one from next to the mesh that misses its top box (shear left unset). *boxes_tested, unless NULL, counts
 * the top box when it was tested. */
static inline int cbvh_ray_prepare(struct cbvh_ray_ctx *ctx, const cbvh_ray *caller_ray,
                                   const struct cbvh_file *f, uint64_t *boxes_tested)
{
    cbvh_ray clean;
    const cbvh_ray *ray = cbvh_ray_setup_boxes(ctx, caller_ray, &clean);
    if (!ray)
        return 0;
    /* most origins lie next to the mesh (origin_near); one outside keeps any_flip 0 */
    if (CBVH_LIKELY(cbvh_origin_in(ray, f->origin_near_lo, f->origin_near_hi))) {
        /* from outside the bounds, the top box first; from inside, walked without the test */
        const int among_triangles = cbvh_origin_in(ray, f->bounds_lo, f->bounds_hi);
        if (!among_triangles) {
            if (boxes_tested)
                ++*boxes_tested;
            if (!cbvh_ray_enters_top_box(ctx, ray->org, f))
                return 0;
        }
        ctx->any_flip = among_triangles ? 7u : 0u;
        cbvh_shear_setup(&ctx->shear, ray->org, ray->dir);
        return 1;
    }
    cbvh_shear_setup(&ctx->shear, ray->org, ray->dir);
    cbvh_ray_place_origin(ctx, ray, f);
    return 1;
}

/* A kernel's best hit in the public form (original id, t on the caller's ray). Returns 1 on a hit. */
int cbvh_hit_output(const struct cbvh_file *f, const struct cbvh_best_hit *best,
                    const struct cbvh_t_frame *frame, cbvh_hit *hit);

/* Reads the caller's options (NULL: the defaults) into *o: CBVH_ERROR_INVALID_ARGUMENT when struct_size is
 * out of range or traversal or cull is not one of its enum's values. */
cbvh_result cbvh_query_options_read(const cbvh_query_options *options, cbvh_query_options *o);

/* The hit record of cooked triangle k hit at the kernels' t (on the caller's ray: cbvh_t_frame_out) with
 * barycentrics u, v by a ray of direction dir (the mesh's frame): unit face normal, front, material. */
void cbvh_hit_record_fill(const struct cbvh_file *f, uint32_t k, const struct cbvh_t_frame *frame, float t,
                          float u, float v, const float dir[3], cbvh_hit_record *r);

/* Fills a gate (leaf.h) for `cull` and `filter` (NULL: none), records rotated by `rotation` unless NULL,
 * for a ray of direction dir whose kernels' t maps to the caller's by frame. */
void cbvh_hit_gate_init(struct cbvh_hit_gate *gate, cbvh_cull cull, cbvh_hit_filter_fn filter, void *user,
                        const double (*rotation)[3], const float dir[3], const struct cbvh_t_frame *frame);

#endif
