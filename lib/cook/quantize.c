/* quantize.c: the file's 16-bit grid (spec section 6): grid from bounds, conservative node boxes, grid
 * vertices. */
#include <math.h>
#include <string.h>

#include "common/error.h"
#include "common/format.h"
#include "cook/cook_internal.h"

static float float_from_bits(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Every decision below uses cbvh_dequantize itself, the readers' arithmetic, so what the
 * cooker proves about a box holds for what a reader decodes. deq is nondecreasing in q
 * (and in scale): each rounding step is monotone. */
static inline float deq(const cook_grid *g, int axis, uint32_t q)
{
    return cbvh_dequantize(q, g->origin[axis], g->scale[axis]);
}

cbvh_result cbvh_cook_grid_init(cook_grid *g, const float bmin[3], const float bmax[3], cbvh_error *err)
{
    for (int a = 0; a < 3; a++) {
        g->origin[a] = bmin[a];
        /* Smallest non-negative float s with deq(65535) >= bmax: binary search over the bit
         * patterns of non-negative floats, which are ordered like the values. */
        uint32_t lo = 0, hi = 0x7F7FFFFFu;
        while (lo < hi) {
            uint32_t mid = lo + (hi - lo) / 2;
            if (cbvh_dequantize(CBVH_Q_MAX, bmin[a], float_from_bits(mid)) >= bmax[a])
                hi = mid;
            else
                lo = mid + 1;
        }
        g->scale[a] = float_from_bits(lo);
        float top = cbvh_dequantize(CBVH_Q_MAX, bmin[a], g->scale[a]);
        if (!isfinite(top) || !(top >= bmax[a]))
            return cbvh_fail(err, CBVH_ERROR_BAD_MESH,
                             "the mesh's bounds on axis %c (%g to %g) do not fit a finite 16-bit grid",
                             "xyz"[a], (double)bmin[a], (double)bmax[a]);
    }
    return CBVH_OK;
}

static inline int past(const cook_grid *g, int axis, uint32_t q, float v, int strict)
{
    float d = deq(g, axis, q);
    return strict ? d > v : d >= v;
}

/* Smallest q in [lo, 65535] with deq(q) >= v (strict: > v); 65536 when none. A few steps
 * from the real-valued estimate (v - origin) / scale usually find it; each step only keeps
 * a bound the monotone predicate proves, and a binary search finishes what they do not. */
static uint32_t smallest_past(const cook_grid *g, int axis, float v, uint32_t lo, int strict)
{
    uint32_t hi = CBVH_Q_MAX + 1; /* past(hi) holds (65536 stands for "none") */
    if (g->scale[axis] > 0.0f) {
        double e = ((double)v - (double)g->origin[axis]) / (double)g->scale[axis];
        if (e >= 0.0 && e <= (double)CBVH_Q_MAX) {
            uint32_t c = (uint32_t)e; /* ceil(e), e >= 0, without a libm call */
            c += (double)c < e;
            c = c < lo ? lo : c;
            for (int step = 0; step < 3 && lo < hi; step++) {
                if (past(g, axis, c, v, strict)) {
                    hi = c;
                    if (c == lo)
                        break;
                    c--;
                } else {
                    lo = c + 1;
                    if (c == CBVH_Q_MAX)
                        break;
                    c++;
                }
                if (lo == hi)
                    return lo;
            }
        }
    }
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (past(g, axis, mid, v, strict))
            hi = mid;
        else
            lo = mid + 1;
    }
    return lo;
}

/* Smallest q in [lo, 65535] with deq(q) >= v (one exists: deq(65535) >= bounds_max >= v). */
static uint32_t smallest_at_least(const cook_grid *g, int axis, float v, uint32_t lo)
{
    uint32_t q = smallest_past(g, axis, v, lo, 0);
    return q > CBVH_Q_MAX ? CBVH_Q_MAX : q;
}

/* Largest q with deq(q) <= v (deq(0) = origin <= v is a precondition). */
static uint32_t largest_at_most(const cook_grid *g, int axis, float v)
{
    uint32_t q = smallest_past(g, axis, v, 0, 1);
    return q > 0 ? q - 1 : 0;
}

void cbvh_cook_quantize_box(const cook_grid *g, const float lo[3], const float hi[3], uint16_t qmin[3],
                            uint16_t qmax[3])
{
    for (int a = 0; a < 3; a++) {
        /* qmax starts at qmin: where deq is flat (zero scale, or a grid far from the origin
         * whose steps are below one ulp) qmin can land past the smallest q reaching hi. */
        uint32_t q0 = largest_at_most(g, a, lo[a]);
        uint32_t q1 = smallest_at_least(g, a, hi[a], q0);
        qmin[a] = (uint16_t)q0;
        qmax[a] = (uint16_t)q1;
    }
}

double cbvh_cook_quantize_vertices(const cook_grid *g, float *positions, uint16_t *q, uint32_t count)
{
    double worst = 0.0;
    for (size_t i = 0; i < 3 * (size_t)count; i++) {
        const int a = (int)(i % 3);
        const float v = positions[i];
        uint32_t up = smallest_at_least(g, a, v, 0);
        uint32_t best = up;
        double err_up = (double)deq(g, a, up) - (double)v;
        if (up > 0) {
            double err_down = (double)v - (double)deq(g, a, up - 1);
            if (err_down < err_up)
                best = up - 1;
        }
        q[i] = (uint16_t)best;
        positions[i] = deq(g, a, best);
        double e = fabs((double)positions[i] - (double)v);
        worst = e > worst ? e : worst;
    }
    return worst;
}

double cbvh_cook_quantized_half_area(const cook_grid *g, const uint16_t qmin[3], const uint16_t qmax[3])
{
    double d[3];
    for (int a = 0; a < 3; a++)
        d[a] = (double)cbvh_dequantize(qmax[a], g->origin[a], g->scale[a]) -
               (double)cbvh_dequantize(qmin[a], g->origin[a], g->scale[a]);
    return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
}
