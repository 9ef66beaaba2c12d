/* sah_build.c: binned SAH BVH builder, with median splits to stay within the format's depth limit. */
#include <float.h>
#include <stdatomic.h>
#include <string.h>

#include "common/compiler.h"
#if defined(CBVH_SSE2)
#include <emmintrin.h>
#define COOK_SSE2 1 /* box and centroid operations four lanes at once; results equal the scalar code's */
#endif

#include "common/alloc.h"
#include "common/error.h"
#include "common/format.h"
#include "common/os.h"
#include "cook/cook_internal.h"

#define MAX_BINS 256

/* A triangle's box and id; 32 bytes so the partitions move whole cache-friendly records.
 * Lane 3 of lo holds the id's bits, lane 3 of hi is 0; box operations ignore lane 3. */
typedef struct prim_ref {
    _Alignas(16) float lo[4];
    float hi[4];
} prim_ref;

/* Lane 3 unused: four lanes let box operations run as single SSE instructions. */
typedef struct box {
    _Alignas(16) float lo[4];
    float hi[4];
} box;

static inline uint32_t prim_id(const prim_ref *r)
{
    uint32_t id;
    memcpy(&id, &r->lo[3], sizeof id);
    return id;
}

/* A node still to split: its prims are refs[begin, end), depth counts nodes from the root (1). */
typedef struct task {
    uint32_t node, begin, end, depth;
    box cent; /* bounds of the prims' centroids */
} task;

typedef struct workspace {
    box bins[3][MAX_BINS];
    uint32_t counts[3][MAX_BINS];
    box right_box[MAX_BINS];
    uint32_t right_count[MAX_BINS];
} workspace;

typedef struct split {
    int axis;     /* -1: none found */
    uint32_t bin; /* prims in bins below go left */
    double cost;  /* sum of area x count over both sides */
    uint32_t left_count;
    box left, right;
} split;

static inline float centroid(const prim_ref *r, int a)
{
    /* Halves first: lo + hi could overflow near FLT_MAX. */
    return r->lo[a] * 0.5f + r->hi[a] * 0.5f;
}

/* The three centroids at once, each computed exactly as centroid() does. c: 16-byte aligned. */
static inline void centroid3(const prim_ref *r, float *restrict c)
{
#ifdef COOK_SSE2
    /* The id's bits in lane 3 are cleared first: as a denormal they would slow the multiply. */
    const __m128 keep = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)), half = _mm_set1_ps(0.5f);
    __m128 lo = _mm_and_ps(_mm_load_ps(r->lo), keep), hi = _mm_load_ps(r->hi);
    _mm_store_ps(c, _mm_add_ps(_mm_mul_ps(lo, half), _mm_mul_ps(hi, half)));
#else
    for (int a = 0; a < 3; a++)
        c[a] = centroid(r, a);
    c[3] = 0.0f;
#endif
}

static void box_empty(box *b)
{
    for (int a = 0; a < 4; a++) {
        b->lo[a] = FLT_MAX;
        b->hi[a] = -FLT_MAX;
    }
}

/* The builder's innermost operation. All pointers 16-byte aligned. MINPS/MAXPS pick like
 * the scalar code (the second operand unless the first is strictly beyond it), so both paths
 * give the same bits. */
static inline void box_grow(box *restrict b, const float *restrict lo, const float *restrict hi)
{
#ifdef COOK_SSE2
    _mm_store_ps(b->lo, _mm_min_ps(_mm_load_ps(lo), _mm_load_ps(b->lo)));
    _mm_store_ps(b->hi, _mm_max_ps(_mm_load_ps(hi), _mm_load_ps(b->hi)));
#else
    const float l0 = lo[0], l1 = lo[1], l2 = lo[2], h0 = hi[0], h1 = hi[1], h2 = hi[2];
    b->lo[0] = l0 < b->lo[0] ? l0 : b->lo[0];
    b->lo[1] = l1 < b->lo[1] ? l1 : b->lo[1];
    b->lo[2] = l2 < b->lo[2] ? l2 : b->lo[2];
    b->hi[0] = h0 > b->hi[0] ? h0 : b->hi[0];
    b->hi[1] = h1 > b->hi[1] ? h1 : b->hi[1];
    b->hi[2] = h2 > b->hi[2] ? h2 : b->hi[2];
#endif
}

static inline void box_grow_point(box *restrict b, const float *restrict p)
{
    box_grow(b, p, p);
}

/* Half the surface area, in double: float products could overflow for huge meshes. */
static double half_area(const float lo[3], const float hi[3])
{
    double dx = (double)hi[0] - lo[0], dy = (double)hi[1] - lo[1], dz = (double)hi[2] - lo[2];
    return dx * dy + dy * dz + dz * dx;
}

/* Fewest levels (nodes on a path) a subtree of m prims needs with balanced splits. */
static uint32_t levels_needed(uint64_t m, uint32_t leaf_size)
{
    uint64_t leaves = (m + leaf_size - 1) / leaf_size, reach = 1;
    uint32_t levels = 1;
    while (reach < leaves) {
        reach *= 2;
        levels++;
    }
    return levels;
}

/* The bin of a centroid; the partition must use exactly this to agree with the bin counts. */
static inline uint32_t bin_of(float c, float c_lo, float scale, uint32_t bins)
{
    float k = (c - c_lo) * scale;
    return k >= (float)bins ? bins - 1 : (uint32_t)k;
}

/* Per axis, bins / centroid extent. 0 puts every prim in bin 0, so no plane is found on an axis
 * whose extent is zero or too small for a finite float scale. */
static void bin_scales(const box *cent, uint32_t bins, float scale[4])
{
    for (int a = 0; a < 3; a++) {
        double extent = (double)cent->hi[a] - (double)cent->lo[a];
        double s = extent > 0.0 ? (double)bins / extent : 0.0;
        scale[a] = s < (double)FLT_MAX ? (float)s : 0.0f;
    }
    scale[3] = 0.0f;
}

/* bin_of on the three axes at once. min(k, bins - 1) then truncation equals bin_of's test
 * (k >= 0 always), so both paths give the same bins. Arrays 16-byte aligned. */
static inline void bins_of3(const float *restrict c, const float *restrict c_lo, const float *restrict scale,
                            uint32_t bins, uint32_t out[4])
{
#ifdef COOK_SSE2
    __m128 k = _mm_mul_ps(_mm_sub_ps(_mm_load_ps(c), _mm_load_ps(c_lo)), _mm_load_ps(scale));
    k = _mm_min_ps(k, _mm_set1_ps((float)(bins - 1)));
    _mm_storeu_si128((__m128i *)(void *)out, _mm_cvttps_epi32(k));
#else
    for (int a = 0; a < 3; a++)
        out[a] = bin_of(c[a], c_lo[a], scale[a], bins);
#endif
}

/* Bins the prims on all three axes at once and sweeps each axis for the cheapest plane. */
static split find_split(workspace *restrict w, const prim_ref *restrict refs, const task *t, uint32_t bins)
{
    split best;
    best.axis = -1;
    best.cost = 0.0;
    _Alignas(16) float scale[4];
    bin_scales(&t->cent, bins, scale);
    for (int a = 0; a < 3; a++) {
        for (uint32_t b = 0; b < bins; b++)
            box_empty(&w->bins[a][b]);
        memset(w->counts[a], 0, bins * sizeof(uint32_t));
    }
    for (uint32_t i = t->begin; i < t->end; i++) {
        const prim_ref *r = &refs[i];
        _Alignas(16) float c[4];
        uint32_t k[4];
        centroid3(r, c);
        bins_of3(c, t->cent.lo, scale, bins, k);
        const uint32_t b0 = k[0], b1 = k[1], b2 = k[2];
        w->counts[0][b0]++;
        w->counts[1][b1]++;
        w->counts[2][b2]++;
        box_grow(&w->bins[0][b0], r->lo, r->hi);
        box_grow(&w->bins[1][b1], r->lo, r->hi);
        box_grow(&w->bins[2][b2], r->lo, r->hi);
    }
    for (int a = 0; a < 3; a++) {
        if (scale[a] == 0.0f)
            continue;
        const box *restrict bin = w->bins[a];
        const uint32_t *restrict count = w->counts[a];
        /* Empty bins change no box and add no prim, so they are skipped: a plane after an
         * empty bin splits like the plane before it, which was tried first and wins ties. */
        box acc;
        box_empty(&acc);
        uint32_t n = 0;
        for (uint32_t b = bins; b-- > 1;) {
            if (count[b]) {
                box_grow(&acc, bin[b].lo, bin[b].hi);
                n += count[b];
            }
            w->right_box[b] = acc;
            w->right_count[b] = n;
        }
        box_empty(&acc);
        n = 0;
        for (uint32_t b = 1; b < bins && w->right_count[b] > 0; b++) {
            if (!count[b - 1])
                continue;
            box_grow(&acc, bin[b - 1].lo, bin[b - 1].hi);
            n += count[b - 1];
            double cost = half_area(acc.lo, acc.hi) * n +
                          half_area(w->right_box[b].lo, w->right_box[b].hi) * w->right_count[b];
            /* Strictly cheaper only: ties keep the lowest axis and plane, deterministically. */
            if (best.axis < 0 || cost < best.cost) {
                best.axis = a;
                best.bin = b;
                best.cost = cost;
                best.left_count = n;
                best.left = acc;
                best.right = w->right_box[b];
            }
        }
    }
    return best;
}

/* Moves the prims of bins below s.bin to the front; returns the first right prim. */
static uint32_t partition_bins(prim_ref *restrict refs, const task *t, const split *s, uint32_t bins,
                               box *left_cent, box *right_cent)
{
    _Alignas(16) float scale[4];
    bin_scales(&t->cent, bins, scale);
    const int a = s->axis;
    const float c_lo = t->cent.lo[a];
    const float sc = scale[a];
    const uint32_t split_bin = s->bin;
    box_empty(left_cent);
    box_empty(right_cent);
    uint32_t i = t->begin, j = t->end;
    while (i < j) {
        _Alignas(16) float c[4];
        centroid3(&refs[i], c);
        if (bin_of(c[a], c_lo, sc, bins) < split_bin) {
            box_grow_point(left_cent, c);
            i++;
        } else {
            box_grow_point(right_cent, c);
            j--;
            prim_ref tmp = refs[i];
            refs[i] = refs[j];
            refs[j] = tmp;
        }
    }
    return i;
}

/* Nodes this small try every split exactly instead of binning: most nodes are small, and
 * enumerating their few partitions is both cheaper and better than binning them. */
#define SMALL_NODE 4

/* Every split into two nonempty sets, prim 0 always on the left; bin holds the left set's mask. */
static split find_split_small(const prim_ref *restrict refs, const task *t)
{
    split best;
    best.axis = -1;
    best.cost = 0.0;
    const uint32_t n = t->end - t->begin;
    const prim_ref *r = refs + t->begin;
    for (uint32_t m = 1; m < (1u << n) - 1; m += 2) {
        box l, rb;
        box_empty(&l);
        box_empty(&rb);
        uint32_t nl = 0;
        for (uint32_t i = 0; i < n; i++) {
            if ((m >> i) & 1) {
                box_grow(&l, r[i].lo, r[i].hi);
                nl++;
            } else {
                box_grow(&rb, r[i].lo, r[i].hi);
            }
        }
        double cost = half_area(l.lo, l.hi) * nl + half_area(rb.lo, rb.hi) * (n - nl);
        if (best.axis < 0 || cost < best.cost) {
            best.axis = 0;
            best.bin = m;
            best.cost = cost;
            best.left_count = nl;
            best.left = l;
            best.right = rb;
        }
    }
    return best;
}

/* Puts the prims of the mask first, each side in its previous order. */
static uint32_t partition_small(prim_ref *restrict refs, const task *t, const split *s, box *left_cent,
                                box *right_cent)
{
    prim_ref tmp[SMALL_NODE];
    const uint32_t mask = s->bin;
    const uint32_t n = t->end - t->begin;
    memcpy(tmp, refs + t->begin, n * sizeof(prim_ref));
    box_empty(left_cent);
    box_empty(right_cent);
    uint32_t k = t->begin;
    for (int side = 1; side >= 0; side--)
        for (uint32_t i = 0; i < n; i++) {
            if (((mask >> i) & 1) != (uint32_t)side)
                continue;
            _Alignas(16) float c[4];
            centroid3(&tmp[i], c);
            box_grow_point(side ? left_cent : right_cent, c);
            refs[k++] = tmp[i];
        }
    return t->begin + s->left_count;
}

/* Total order for median splits: centroid on the axis, then triangle id. */
static inline int key_less(const prim_ref *x, const prim_ref *y, int a)
{
    float cx = centroid(x, a), cy = centroid(y, a);
    if (cx != cy)
        return cx < cy;
    return prim_id(x) < prim_id(y);
}

static inline void swap_refs(prim_ref *x, prim_ref *y)
{
    prim_ref tmp = *x;
    *x = *y;
    *y = tmp;
}

/* Quickselect: puts the k-th smallest prim of r[0, n) at k, smaller ones before it. The key is a
 * total order, so the two sides are the same sets on every run. */
static void select_nth(prim_ref *r, size_t n, size_t k, int a)
{
    size_t lo = 0, hi = n - 1;
    while (hi > lo) {
        size_t mid = lo + (hi - lo) / 2;
        if (key_less(&r[mid], &r[lo], a))
            swap_refs(&r[mid], &r[lo]);
        if (key_less(&r[hi], &r[lo], a))
            swap_refs(&r[hi], &r[lo]);
        if (key_less(&r[hi], &r[mid], a))
            swap_refs(&r[hi], &r[mid]);
        const prim_ref pivot = r[mid];
        size_t i = lo, j = hi;
        for (;;) {
            while (key_less(&r[i], &pivot, a))
                i++;
            while (key_less(&pivot, &r[j], a))
                j--;
            if (i >= j)
                break;
            swap_refs(&r[i], &r[j]);
            i++;
            j--;
        }
        /* Now r[lo, j] <= pivot <= r[j + 1, hi] (Hoare); recurse into the side holding k. */
        if (k <= j)
            hi = j;
        else
            lo = j + 1;
    }
}

static void bounds_of(const prim_ref *restrict refs, uint32_t begin, uint32_t end, box *b, box *cent)
{
    box_empty(b);
    box_empty(cent);
    for (uint32_t i = begin; i < end; i++) {
        box_grow(b, refs[i].lo, refs[i].hi);
        _Alignas(16) float c[4];
        centroid3(&refs[i], c);
        box_grow_point(cent, c);
    }
}

/* Object median along the widest centroid axis: halves the prims, so each level of the
 * remaining subtree halves its leaf count and the depth limit holds. */
static uint32_t split_median(prim_ref *refs, const task *t, box *left, box *right, box *left_cent,
                             box *right_cent)
{
    int axis = 0;
    float widest = t->cent.hi[0] - t->cent.lo[0];
    for (int a = 1; a < 3; a++)
        if (t->cent.hi[a] - t->cent.lo[a] > widest) {
            widest = t->cent.hi[a] - t->cent.lo[a];
            axis = a;
        }
    uint32_t n = t->end - t->begin, half = n / 2;
    select_nth(refs + t->begin, n, half, axis);
    uint32_t mid = t->begin + half;
    bounds_of(refs, t->begin, mid, left, left_cent);
    bounds_of(refs, mid, t->end, right, right_cent);
    return mid;
}

static void init_refs(const cook_mesh *m, prim_ref *restrict refs, box *root, box *cent)
{
    const float *restrict pos = m->positions;
    const uint32_t *restrict idx = m->indices;
    box_empty(root);
    box_empty(cent);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        prim_ref *r = &refs[t];
        const float *p0 = pos + 3 * (size_t)idx[3 * (size_t)t];
        const float *p1 = pos + 3 * (size_t)idx[3 * (size_t)t + 1];
        const float *p2 = pos + 3 * (size_t)idx[3 * (size_t)t + 2];
        for (int a = 0; a < 3; a++) {
            float lo = p0[a] < p1[a] ? p0[a] : p1[a], hi = p0[a] > p1[a] ? p0[a] : p1[a];
            r->lo[a] = p2[a] < lo ? p2[a] : lo;
            r->hi[a] = p2[a] > hi ? p2[a] : hi;
        }
        memcpy(&r->lo[3], &t, sizeof t);
        r->hi[3] = 0.0f;
        box_grow(root, r->lo, r->hi);
        _Alignas(16) float c[4];
        centroid3(r, c);
        box_grow_point(cent, c);
    }
}

/* Build nodes are allocated a page at a time as the tree grows: the worst case, 2n - 1 nodes for n prims,
 * is several times what an SAH tree with leaves of several triangles takes, and would be the largest
 * buffer of a cook. */
#define NODE_PAGE_SHIFT 10 /* 1024 nodes, 32 KiB */

/* What both builders allocate pages from. While the worker runs, both may need a page at once, and the
 * caller's hooks (and the meter counting them) need not be thread-safe: one call at a time. */
typedef struct page_source {
    const cbvh_allocator *a;
    atomic_flag busy;
    atomic_bool failed; /* a page was refused: both builders stop */
} page_source;

/* A builder's nodes: page[i >> page_shift][i & (page_nodes - 1)]. */
typedef struct node_pages {
    cook_bnode **page; /* room for every page the worst case needs; page 0 shares its block */
    uint32_t page_count;
    uint32_t page_shift;
    uint32_t page_nodes; /* a power of two: 1 << NODE_PAGE_SHIFT, or the worst case's when smaller */
} node_pages;

static inline cook_bnode *node_at(const node_pages *p, uint32_t i)
{
    return &p->page[i >> p->page_shift][i & (p->page_nodes - 1)];
}

/* Room for the nodes of a subtree of `prims` prims: the table and the first page, in one block (one
 * allocation fewer to fail); 0 without memory. Called on the caller's thread while no worker runs. */
static int pages_init(node_pages *p, uint32_t prims, const cbvh_allocator *a)
{
    const uint32_t worst = 2 * prims - 1;
    for (p->page_shift = 0; p->page_shift < NODE_PAGE_SHIFT && (1u << p->page_shift) < worst; p->page_shift++)
        ;
    p->page_nodes = 1u << p->page_shift;
    const size_t table = ((((size_t)worst - 1) >> p->page_shift) + 1) * sizeof *p->page;
    const size_t table_size = (table + 63) & ~(size_t)63;
    p->page = cbvh_alloc(a, table_size + (size_t)p->page_nodes * sizeof(cook_bnode), 64);
    if (!p->page)
        return 0;
    p->page[0] = (cook_bnode *)(void *)((uint8_t *)p->page + table_size);
    p->page_count = 1;
    return 1;
}

static void pages_free(node_pages *p, const cbvh_allocator *a)
{
    for (uint32_t i = 1; i < p->page_count; i++)
        cbvh_free(a, p->page[i]);
    cbvh_free(a, p->page);
    memset(p, 0, sizeof *p);
}

/* Makes room for node `last` (at most one page past the end); 0 when a page was refused, now or by the
 * other builder. */
static int pages_reach(node_pages *p, uint32_t last, page_source *src)
{
    if (last >> p->page_shift < p->page_count)
        return 1;
    while (atomic_flag_test_and_set_explicit(&src->busy, memory_order_acquire))
        ;
    cook_bnode *page = atomic_load_explicit(&src->failed, memory_order_relaxed)
                           ? NULL
                           : cbvh_alloc_array(src->a, p->page_nodes, sizeof(cook_bnode), 64);
    if (!page)
        atomic_store_explicit(&src->failed, 1, memory_order_relaxed);
    atomic_flag_clear_explicit(&src->busy, memory_order_release);
    if (page)
        p->page[p->page_count++] = page;
    return page != NULL;
}

void cbvh_cook_tree_free(const cbvh_allocator *a, cook_tree *t)
{
    cbvh_free(a, t->nodes);
    cbvh_free(a, t->prims);
    memset(t, 0, sizeof *t);
}

static void set_box(cook_bnode *n, const box *b)
{
    memcpy(n->lo, b->lo, sizeof n->lo);
    memcpy(n->hi, b->hi, sizeof n->hi);
}

/* One builder per thread: its own nodes and bins; prim ranges of different builders never
 * overlap, so the two threads share nothing they write but the page source, under its lock. */
typedef struct builder {
    prim_ref *refs;
    workspace *w;
    node_pages nodes;
    page_source *pages;
    uint32_t node_count;
    uint32_t leaf_count;
    uint32_t leaf_size, bins;
    double ct, ci;
    _Atomic uint64_t done; /* prims placed in leaves, read by the reporting thread */
} builder;

enum split_outcome { MADE_LEAF, SPLIT, NO_PAGE };

/* Makes t's node a leaf or splits it, appending two children and filling lt, rt. */
static enum split_outcome split_node(builder *b, const task *t, task *lt, task *rt)
{
    prim_ref *refs = b->refs;
    cook_bnode *node = node_at(&b->nodes, t->node);
    const uint32_t n = t->end - t->begin;
    split s;
    s.axis = -1;
    /* A node of n prims fills at most n bins; fewer bins keep small nodes cheap. */
    const uint32_t node_bins = n < b->bins ? (n < 4 ? 4 : n) : b->bins;
    const int small = n <= SMALL_NODE;
    if (n > 1)
        s = small ? find_split_small(refs, t) : find_split(b->w, refs, t, node_bins);
    const double area = half_area(node->lo, node->hi);
    if (n <= b->leaf_size &&
        (s.axis < 0 || t->depth >= CBVH_MAX_DEPTH || b->ci * n * area <= b->ct * area + b->ci * s.cost)) {
        node->child = t->begin;
        node->count = n;
        b->leaf_count++;
        atomic_fetch_add_explicit(&b->done, n, memory_order_relaxed);
        return MADE_LEAF;
    }
    box left, right;
    uint32_t mid;
    const uint32_t budget = CBVH_MAX_DEPTH - t->depth;
    const uint32_t larger = s.left_count > n - s.left_count ? s.left_count : n - s.left_count;
    if (s.axis >= 0 && levels_needed(larger, b->leaf_size) <= budget) {
        mid = small ? partition_small(refs, t, &s, &lt->cent, &rt->cent)
                    : partition_bins(refs, t, &s, node_bins, &lt->cent, &rt->cent);
        left = s.left;
        right = s.right;
    } else {
        mid = split_median(refs, t, &left, &right, &lt->cent, &rt->cent);
    }
    const uint32_t child = b->node_count;
    if (!pages_reach(&b->nodes, child + 1, b->pages))
        return NO_PAGE;
    b->node_count += 2;
    node->child = child;
    node->count = 0;
    set_box(node_at(&b->nodes, child), &left);
    set_box(node_at(&b->nodes, child + 1), &right);
    lt->node = child;
    lt->begin = t->begin;
    lt->end = mid;
    lt->depth = t->depth + 1;
    rt->node = child + 1;
    rt->begin = mid;
    rt->end = t->end;
    rt->depth = t->depth + 1;
    return SPLIT;
}

typedef struct report_state {
    const cook_progress *progress;
    const builder *other; /* the worker's counter, or NULL */
    uint64_t total, next;
} report_state;

/* Builds the subtree of `root` (its node already holds its box), depth first; stops early when
 * either builder was refused a page. */
static void build_from(builder *b, const task *root, report_state *report)
{
    task stack[2 * CBVH_MAX_DEPTH + 2];
    uint32_t top = 0;
    stack[top++] = *root;
    while (top > 0) {
        const task t = stack[--top];
        task lt, rt;
        const enum split_outcome o = split_node(b, &t, &lt, &rt);
        if (o == NO_PAGE || atomic_load_explicit(&b->pages->failed, memory_order_relaxed))
            return;
        if (o == SPLIT) {
            stack[top++] = rt;
            stack[top++] = lt;
            continue;
        }
        if (!report)
            continue;
        uint64_t done = atomic_load_explicit(&b->done, memory_order_relaxed);
        if (report->other)
            done += atomic_load_explicit(&report->other->done, memory_order_relaxed);
        if (done >= report->next) {
            cook_report(report->progress, (double)done / (double)report->total);
            report->next = done + report->total / 64 + 1;
        }
    }
}

/* The second thread's share: a builder and the subtree it builds. */
typedef struct worker_job {
    builder b;
    task root;
} worker_job;

static void worker_main(void *arg)
{
    worker_job *job = arg;
    build_from(&job->b, &job->root, NULL);
}

static void worker_free(worker_job *job, const cbvh_allocator *a)
{
    cbvh_free(a, job->b.w);
    job->b.w = NULL;
    pages_free(&job->b.nodes, a);
}

/* Prepares a job for the subtree rt (all allocation here, on the calling thread: the
 * caller's allocator need not be thread-safe). Returns 0 without memory. */
static int worker_init(worker_job *job, const builder *main, const task *rt, const cbvh_allocator *a)
{
    memset(job, 0, sizeof *job);
    job->b.refs = main->refs;
    job->b.pages = main->pages;
    job->b.leaf_size = main->leaf_size;
    job->b.bins = main->bins;
    job->b.ct = main->ct;
    job->b.ci = main->ci;
    atomic_init(&job->b.done, 0);
    job->b.w = cbvh_alloc(a, sizeof(workspace), 64);
    if (!job->b.w || !pages_init(&job->b.nodes, rt->end - rt->begin, a)) {
        worker_free(job, a);
        return 0;
    }
    *node_at(&job->b.nodes, 0) = *node_at(&main->nodes, rt->node);
    job->b.node_count = 1;
    job->root = *rt;
    job->root.node = 0;
    return 1;
}

/* The tree's nodes in one array of the exact size: the main builder's, then the worker's (when there is
 * one) after them, its root replacing the main node `at`. Frees the pages as they are copied. */
static cook_bnode *flatten(builder *main, builder *worker, uint32_t at, const cbvh_allocator *a)
{
    const uint32_t count = main->node_count + (worker ? worker->node_count - 1 : 0);
    cook_bnode *out = cbvh_alloc_array(a, count, sizeof(cook_bnode), 64);
    if (!out)
        return NULL;
    for (uint32_t i = 0; i < main->node_count; i++)
        out[i] = *node_at(&main->nodes, i);
    pages_free(&main->nodes, a);
    if (!worker)
        return out;
    const uint32_t base = main->node_count - 1; /* worker node j >= 1 goes to base + j */
    for (uint32_t j = 0; j < worker->node_count; j++) {
        cook_bnode n = *node_at(&worker->nodes, j);
        if (n.count == 0)
            n.child += base;
        out[j ? base + j : at] = n;
    }
    pages_free(&worker->nodes, a);
    main->node_count = count;
    main->leaf_count += worker->leaf_count;
    return out;
}

/* Subtrees at least this large are worth a second thread. */
#define PARALLEL_MIN 32768

static cbvh_result out_of_memory(uint32_t tris, cbvh_error *err)
{
    return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while building the tree (%u triangles)",
                     tris);
}

cbvh_result cbvh_cook_build(cook_mesh *m, const cook_build_params *params, const cbvh_allocator *a,
                            const cook_progress *progress, cook_tree *out, cbvh_error *err)
{
    memset(out, 0, sizeof *out);
    const uint32_t tris = m->triangle_count;

    page_source pages = {a, ATOMIC_FLAG_INIT, 0};
    builder b;
    memset(&b, 0, sizeof b);
    b.pages = &pages;
    b.leaf_size = params->max_leaf_size;
    b.bins = params->bins;
    b.ct = params->traversal_cost;
    b.ci = params->intersection_cost;
    atomic_init(&b.done, 0);
    b.refs = cbvh_alloc_array(a, tris, sizeof(prim_ref), 64);
    if (!b.refs)
        return out_of_memory(tris, err);
    box root_box;
    task root;
    init_refs(m, b.refs, &root_box, &root.cent);
    cbvh_cook_mesh_shelve_triangles(m, a);
    b.w = cbvh_alloc(a, sizeof(workspace), 64);
    if (!b.w || !pages_init(&b.nodes, tris, a)) {
        cbvh_free(a, b.refs);
        cbvh_free(a, b.w);
        pages_free(&b.nodes, a);
        return out_of_memory(tris, err);
    }
    set_box(node_at(&b.nodes, 0), &root_box);
    root.node = 0;
    root.begin = 0;
    root.end = tris;
    root.depth = 1;
    b.node_count = 1;
    report_state report = {progress, NULL, tris, tris / 64 + 1};

    /* Large meshes: the root's second subtree is built on a second thread, into its own
     * nodes, then appended. The tree is the same as a one-thread build's (a subtree depends
     * only on its own prims; only node numbering differs, and layout orders nodes by the
     * tree alone), so the file is too. */
    worker_job job;
    memset(&job, 0, sizeof job);
    int threaded = 0;
    task lt, rt;
    memset(&rt, 0, sizeof rt);
    if (tris < 2 * PARALLEL_MIN) {
        build_from(&b, &root, &report);
    } else if (split_node(&b, &root, &lt, &rt) == SPLIT) {
        struct cbvh_os_thread thread;
        threaded = rt.end - rt.begin >= PARALLEL_MIN && worker_init(&job, &b, &rt, a);
        if (threaded) {
            report.other = &job.b;
            if (cbvh_os_thread_start(&thread, worker_main, &job) != 0) {
                report.other = NULL;
                worker_free(&job, a);
                threaded = 0;
            }
        }
        if (!threaded) /* no second thread (or no memory for one): the same work here */
            build_from(&b, &rt, &report);
        build_from(&b, &lt, &report);
        if (threaded)
            cbvh_os_thread_join(&thread);
    }
    cbvh_free(a, b.w);

    /* The prims in leaf order, then the nodes in one array: each allocated after the larger buffer
     * before it is freed. */
    int ok = !atomic_load_explicit(&pages.failed, memory_order_relaxed);
    if (ok)
        out->prims = cbvh_alloc_array(a, tris, sizeof(uint32_t), 64);
    ok = ok && out->prims;
    for (uint32_t i = 0; ok && i < tris; i++)
        out->prims[i] = prim_id(&b.refs[i]);
    cbvh_free(a, b.refs);
    if (ok)
        out->nodes = flatten(&b, threaded ? &job.b : NULL, rt.node, a);
    pages_free(&b.nodes, a);
    worker_free(&job, a);
    if (!ok || !out->nodes) {
        cbvh_cook_tree_free(a, out);
        return out_of_memory(tris, err);
    }
    out->node_count = b.node_count;
    out->leaf_count = b.leaf_count;
    cook_report(progress, 1.0);
    return CBVH_OK;
}
