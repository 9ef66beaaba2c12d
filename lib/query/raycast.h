/* raycast.h: the single-ray traversal kernels behind cbvh_raycast and cbvh_occluded. */
#ifndef CBVH_QUERY_RAYCAST_H
#define CBVH_QUERY_RAYCAST_H

#include <stdatomic.h>

#include "common/file.h"
#include "layout/tree.h"
#include "query/leaf.h"
#include "query/ray_box.h"
#include "query/ray_setup.h"

/* Each kernel takes a validated ray; closest-hit kernels fill *best (cooked
 * index, UINT32_MAX for none). stats may be NULL. */

/* The closest hit, or whether any triangle occludes the ray, by the walk
 * `traversal` names (an unknown value walks sorted; the public entry points
 * reject it first). A ray with box_halve set (ray_setup.h) takes the sorted
 * walk with its box test at half scale on those axes, whatever the
 * traversal: the tie rule makes every traversal's answer the same, so no
 * other walk carries the rescaling. */
void cbvh_closest(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
                  struct cbvh_best_hit *best, cbvh_query_stats *stats);
int cbvh_any(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_traversal traversal,
             cbvh_query_stats *stats);

/* The wide layout's walk kernels (the binary layout has one, scalar). */
enum cbvh_walk_kernel {
    CBVH_WALK_KERNEL_BEST,   /* the fastest the build and the CPU have: AVX2, else SSE2, else scalar */
    CBVH_WALK_KERNEL_SCALAR, /* a node's children one box at a time, leaf triangles one at a time (the
                              * kernel of builds without SIMD) */
    CBVH_WALK_KERNEL_SSE2,   /* four child boxes at once, leaf triangles through a four-lane filter */
    CBVH_WALK_KERNEL_AVX2    /* SSE2's node test, leaf triangles eight lanes at a time (raycast_walks_avx2.c;
                              * CPUs with AVX2, BMI1, BMI2 and FMA) */
};

/* The wide layout's walk kernel (enum cbvh_walk_kernel) once chosen (kernel_choice.c): 0 (BEST) until the
 * first walk chooses it; in the tests' build, also what a test hook (test_hooks.h) set. */
extern atomic_int cbvh_walk_kernel_chosen;

/* Chooses the best kernel the build and the CPU have for the wide layout's walks, and returns it. */
int cbvh_walk_kernel_choose_best(void);

/* The kernel the wide layout's walks take now (never BEST); the streams follow it. Read once per ray: a
 * relaxed load and a predictable branch. Threads racing through the first walk choose the same kernel. */
static inline int cbvh_walk_kernel(void)
{
    const int chosen = atomic_load_explicit(&cbvh_walk_kernel_chosen, memory_order_relaxed);
    return CBVH_LIKELY(chosen != CBVH_WALK_KERNEL_BEST) ? chosen : cbvh_walk_kernel_choose_best();
}

/* Stackless walk over escape links (binary layout). */
void cbvh_closest_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray,
                            struct cbvh_best_hit *best, cbvh_query_stats *stats);
int cbvh_any_stackless(const struct cbvh_file *f, const struct cbvh_ray_ctx *ray, cbvh_query_stats *stats);

/* An origin farther than this many times the mesh's extent from its bounds
 * is moved: float coordinates relative to it would keep fewer than about
 * 20 of their 24 bits at the mesh (a unit mesh seen from 1e20 collapses to
 * a point), and the products of the triangle test would lose the rest. */
#define CBVH_FAR_FACTOR 16.0f
_Static_assert(4 * CBVH_NEAR_ORIGIN_FACTOR <= (int)CBVH_FAR_FACTOR,
               "the near-origin box (common/file.h) lies well inside the distance that moves an origin");

/* For a validated ray whose origin lies outside f's origin_near box (common/file.h): moves an origin
 * farther than CBVH_FAR_FACTOR extents from f's bounds next to them, making ctx's t and range relative to
 * the new origin (ctx->t_frame.base: its t), and sets ctx->box_halve on the axes where a
 * node plane minus the (moved) origin can overflow. Out of line: most rays never get here. See
 * ray_origin.c. */
void cbvh_ray_place_origin(struct cbvh_ray_ctx *ctx, const cbvh_ray *ray, const struct cbvh_file *f);

/* Whether the ray's origin lies in the box [lo, hi] (lane 3 of each is not looked at; the ray's tmin follows
 * its origin, so one 16-byte load reads it). */
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

/* Whether the ray (ctx as cbvh_ray_setup_boxes left it, its origin org) enters f's top box (common/file.h)
 * by the box test of ray_box.h, cbvh_slab_test: lane for lane the same operations, MAXPS(t, acc) being t >
 * acc ? t : acc and MINPS(t, acc) t < acc ? t : acc, so that a NaN distance is skipped as there (in any
 * order: the result is the largest, or smallest, of the others). Every box a walk tests first lies in the
 * top box, and rounding is monotonic: a ray the test keeps out of it, the walk's test keeps out of those
 * (the walk's faster affine test, which enters every box the exact one enters, no fewer), so it hits
 * nothing. For an origin next to the mesh, whose box test needs no halving (ray_setup.h's box_halve). */
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

/* The set-up of a ray cast into file f (cbvh_ray_setup's): also moves an origin far from the file's bounds
 * next to them, so the triangle test keeps its precision (cbvh_ray_place_origin), and sets any_flip for an
 * origin inside the bounds. Returns 0 when there is nothing to walk: an invalid ray, or one from next to the
 * mesh that misses its top box (cbvh_ray_enters_top_box: it hits nothing), for which the shear is left
 * unset (a camera's rays past the mesh's silhouette box: half to two thirds of the bench's coherent rays).
 * *boxes_tested, unless NULL, counts the top box when it was tested. Inline: it runs once per ray. */
static inline int cbvh_ray_prepare(struct cbvh_ray_ctx *ctx, const cbvh_ray *caller_ray,
                                   const struct cbvh_file *f, uint64_t *boxes_tested)
{
    cbvh_ray clean;
    const cbvh_ray *ray = cbvh_ray_setup_boxes(ctx, caller_ray, &clean);
    if (!ray)
        return 0;
    /* Most origins lie next to the mesh (struct cbvh_file's origin_near box), where there is nothing to do;
     * one outside it (or any, when a huge mesh has no such box) keeps any_flip 0: nearest first */
    if (CBVH_LIKELY(cbvh_origin_in(ray, f->origin_near_lo, f->origin_near_hi))) {
        /* from outside the bounds, the top box first; an origin inside them is in it, and a ray from there
         * rarely misses it (its range would have to start past the box): walked without the test */
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

/* Converts a kernel's best hit into the public form (original id, t on the
 * caller's ray: cbvh_t_frame_out). Returns 1 on a hit. */
int cbvh_hit_output(const struct cbvh_file *f, const struct cbvh_best_hit *best,
                    const struct cbvh_t_frame *frame, cbvh_hit *hit);

/* Reads the caller's options (NULL: the defaults) into *o: CBVH_ERROR_INVALID_ARGUMENT when struct_size is
 * out of range or traversal or cull is not one of its enum's values. */
cbvh_result cbvh_query_options_read(const cbvh_query_options *options, cbvh_query_options *o);

/* The hit record of cooked triangle k hit at the kernels' t (on the caller's ray: cbvh_t_frame_out) with
 * barycentrics u, v by a ray of direction dir (the mesh's frame): unit face normal, front, material. */
void cbvh_hit_record_fill(const struct cbvh_file *f, uint32_t k, const struct cbvh_t_frame *frame, float t,
                          float u, float v, const float dir[3], cbvh_hit_record *r);

/* Fills a gate (leaf.h) for culling `cull` and `filter` (NULL: none), records rotated into the world by
 * `rotation` when it is not NULL, for a ray of direction dir whose kernels' t maps to the caller's by frame.
 */
void cbvh_hit_gate_init(struct cbvh_hit_gate *gate, cbvh_cull cull, cbvh_hit_filter_fn filter, void *user,
                        const double (*rotation)[3], const float dir[3], const struct cbvh_t_frame *frame);

#endif
