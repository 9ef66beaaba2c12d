/* test_stiff.c: stiff and extreme numerical cases: watertightness at shared edges and vertices, far and
 * tiny/huge meshes, degenerate meshes, extreme rays and sweeps, against double-precision references. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "cbvh.h"
#include "common/file.h"
#include "layout/triangle_encodings.h"
#include "layout/tree.h"
#include "support/reference.h"
#include "support/scene_gen.h"
#include "support/layouts.h"

/* ------------------------------------------------------------------ */
/* Helpers                                                            */
/* ------------------------------------------------------------------ */

static cbvh_cook_options options(int quantized, int level)
{
    cbvh_cook_options o;
    test_options_init(&o);
    o.vertex_format = quantized ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
    o.compress_level = level;
    return o;
}

static double vec_len(const float v[3])
{
    return sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
}

/* Magnitude of the coordinates a ray against fixture fx works with. */
static double magnitude(const ref_fixture *fx, const cbvh_ray *r)
{
    double m = 0;
    for (int a = 0; a < 3; a++)
        m = fmax(m, fmax(fabs((double)r->org[a]), fmax(fabs(fx->lo[a]), fabs(fx->hi[a]))));
    return m;
}

/* Bound on hit disagreements with the double reference, stated in
 * ROBUSTNESS.md: with tol = HIT_TOL x the mesh's diagonal + 8 float steps at
 * the magnitude of the coordinates (mesh bounds and ray origin), a triangle
 * clearly hit (the ray's line at least tol inside its edges) is never
 * missed, no hit lies more than tol before the closest triangle within tol
 * along the ray, and every hit lies within tol of its triangle's plane. */
#define HIT_TOL 1e-5
#define FLOAT_STEP 1.1920929e-7

typedef struct agree_stats {
    size_t rays, clear_hits, missed, early, off_plane, disagree_paths;
    uint64_t nodes;
} agree_stats;

/* One ray against the reference and across every traversal and the stream. */
static void check_against_reference(const ref_fixture *fx, const cbvh_ray *r, double rel_tol, agree_stats *st)
{
    double tol = rel_tol * fx->diag + 8 * FLOAT_STEP * magnitude(fx, r), dlen = vec_len(r->dir);
    ref_ray_hit clear, loose;
    int has_clear = ref_ray_closest(&fx->tris, r, -tol, &clear);
    ref_ray_closest(&fx->tris, r, tol, &loose);
    cbvh_hit h[4], sh;
    int got[4];
    cbvh_query_stats qs = {0, 0};
    for (int t = 0; t < 4; t++)
        got[t] = cbvh_raycast(fx->file, r, (cbvh_traversal)t, &h[t], t == 0 ? &qs : NULL);
    cbvh_raycast_stream(fx->file, r, 1, &sh, NULL);
    int occ = cbvh_occluded(fx->file, r, CBVH_TRAVERSAL_STACKLESS, NULL);
    st->rays++;
    st->nodes += qs.nodes_visited;
    for (int t = 1; t < 4; t++)
        if (got[t] != got[0] || (got[0] && h[t].t != h[0].t))
            st->disagree_paths++;
    if ((sh.tri != CBVH_NO_HIT) != got[0] || (got[0] && sh.t != h[0].t) || occ != got[0])
        st->disagree_paths++;
    if (has_clear) {
        st->clear_hits++;
        if (!got[0])
            st->missed++;
    }
    if (got[0]) {
        /* no hit before the closest triangle that could be hit at all */
        if (loose.index != (size_t)-1 && (loose.t - h[0].t) * dlen > tol)
            st->early++;
        size_t k = fx->index_of_id[h[0].tri];
        if (k == (size_t)-1) {
            st->off_plane++;
        } else {
            const double *v = fx->tris.v + 9 * k;
            double e1[3], e2[3], n[3], p[3];
            for (int a = 0; a < 3; a++) {
                e1[a] = v[3 + a] - v[a];
                e2[a] = v[6 + a] - v[a];
                p[a] = (double)r->org[a] + (double)h[0].t * r->dir[a] - v[a];
            }
            n[0] = e1[1] * e2[2] - e1[2] * e2[1];
            n[1] = e1[2] * e2[0] - e1[0] * e2[2];
            n[2] = e1[0] * e2[1] - e1[1] * e2[0];
            double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (nl > 0 && fabs(p[0] * n[0] + p[1] * n[1] + p[2] * n[2]) / nl > tol)
                st->off_plane++;
        }
    }
}

static void assert_agreement(const char *what, const agree_stats *st)
{
    if (st->missed || st->early || st->off_plane || st->disagree_paths)
        fail_msg(
            "%s: %zu rays, %zu clear hits: %zu missed, %zu early, %zu off the plane, %zu path disagreements",
            what, st->rays, st->clear_hits, st->missed, st->early, st->off_plane, st->disagree_paths);
}

/* Every box of the subtree r (dequantized exactly as the traversal does,
 * through the layout interface) contains every vertex of every triangle
 * below it; `box` is r's own (CBVH_NO_BOX for a root without one). Fills the
 * subtree's vertex bounds and returns the number of boxes checked. */
static size_t check_conservative(const cbvh_file *f, cbvh_ref r, uint32_t box, float lo_out[3],
                                 float hi_out[3], size_t *bad)
{
    float sub_lo[3] = {INFINITY, INFINITY, INFINITY}, sub_hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    size_t checked = 0;
    if (cbvh_tree_is_leaf(f, f->layout, r)) {
        uint32_t first, count;
        cbvh_tree_leaf(f, f->layout, r, &first, &count);
        for (uint32_t t = first; t < first + count; t++) {
            float v[3][3];
            cbvh_triangle_vertices(f, t, v[0], v[1], v[2]);
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++) {
                    sub_lo[a] = fminf(sub_lo[a], v[k][a]);
                    sub_hi[a] = fmaxf(sub_hi[a], v[k][a]);
                }
        }
    } else {
        struct cbvh_child c[CBVH_TREE_WIDTH];
        const uint32_t n = cbvh_tree_children(f, f->layout, r, CBVH_NO_OCTANT, c);
        for (uint32_t k = 0; k < n; k++) {
            float c_lo[3], c_hi[3];
            checked += check_conservative(f, c[k].ref, c[k].box, c_lo, c_hi, bad);
            for (int a = 0; a < 3; a++) {
                sub_lo[a] = fminf(sub_lo[a], c_lo[a]);
                sub_hi[a] = fmaxf(sub_hi[a], c_hi[a]);
            }
        }
    }
    if (box != CBVH_NO_BOX) {
        float lo[3], hi[3];
        cbvh_tree_box(f, f->layout, box, lo, hi);
        checked++;
        for (int a = 0; a < 3; a++)
            if (!(lo[a] <= sub_lo[a] && hi[a] >= sub_hi[a]))
                (*bad)++;
    }
    memcpy(lo_out, sub_lo, sizeof sub_lo);
    memcpy(hi_out, sub_hi, sizeof sub_hi);
    return checked;
}

/* check_conservative over the whole tree. */
static size_t check_tree_conservative(const cbvh_file *f, float lo[3], float hi[3], size_t *bad)
{
    return check_conservative(f, cbvh_tree_root(f, f->layout), cbvh_tree_root_box(f, f->layout), lo, hi, bad);
}

/* ------------------------------------------------------------------ */
/* Watertightness                                                     */
/* ------------------------------------------------------------------ */

typedef struct leak_stats {
    size_t rays, leaks[6]; /* sorted, stackless, unsorted, distance, stream, occluded */
} leak_stats;

/* A ray from `org` at a point of the surface (t = 1 there) must hit at t <= 1
 * on every path: anything else went through a crack. The slack covers the
 * target's rounding (a few float steps) seen at the crossing angle. */
static void shoot_at(const cbvh_file *f, const float org[3], const float target[3], double cosine,
                     leak_stats *st)
{
    cbvh_ray r = {{org[0], org[1], org[2]},
                  0.0f,
                  {target[0] - org[0], target[1] - org[1], target[2] - org[2]},
                  INFINITY};
    double mag = 0;
    for (int a = 0; a < 3; a++)
        mag = fmax(mag, fmax(fabs((double)target[a]), fabs((double)org[a])));
    const float limit = (float)(1.0 + 4 * FLOAT_STEP + 8 * FLOAT_STEP * mag / (vec_len(r.dir) * cosine));
    for (int t = 0; t < 4; t++) {
        cbvh_hit h;
        if (!cbvh_raycast(f, &r, (cbvh_traversal)t, &h, NULL) || h.t > limit)
            st->leaks[t]++;
    }
    cbvh_hit sh;
    cbvh_raycast_stream(f, &r, 1, &sh, NULL);
    if (sh.tri == CBVH_NO_HIT || sh.t > limit)
        st->leaks[4]++;
    r.tmax = limit;
    if (!cbvh_occluded(f, &r, CBVH_TRAVERSAL_STACKLESS, NULL))
        st->leaks[5]++;
    st->rays++;
}

/* The file's own topology (welded vertex indices of the cooked triangles):
 * edges sorted by their vertex pair, triangles around each vertex. */
typedef struct edge_ref {
    uint64_t key;
    uint32_t tri;
} edge_ref;
typedef struct topology {
    uint32_t tris, verts;
    edge_ref *edges;      /* 3 per triangle, sorted by key */
    uint32_t *vert_start; /* verts + 1 offsets into vert_tris */
    uint32_t *vert_tris;
    uint8_t *border; /* vertex on an edge not shared by exactly two triangles */
} topology;

static int cmp_edge(const void *a, const void *b)
{
    uint64_t x = ((const edge_ref *)a)->key, y = ((const edge_ref *)b)->key;
    return (x > y) - (x < y);
}

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

static void topology_build(const cbvh_file *f, topology *tp)
{
    tp->tris = f->info.triangle_count;
    tp->verts = f->info.vertex_count;
    tp->edges = malloc(3 * (size_t)tp->tris * sizeof *tp->edges);
    tp->vert_start = calloc((size_t)tp->verts + 1, sizeof(uint32_t));
    tp->vert_tris = malloc(3 * (size_t)tp->tris * sizeof(uint32_t));
    tp->border = calloc(tp->verts, 1);
    assert_true(tp->edges && tp->vert_start && tp->vert_tris && tp->border);
    for (uint32_t t = 0; t < tp->tris; t++) {
        uint32_t idx[3];
        cbvh_triangle_indices(f, t, idx);
        for (int k = 0; k < 3; k++) {
            tp->edges[3 * t + k] = (edge_ref){edge_key(idx[k], idx[(k + 1) % 3]), t};
            tp->vert_start[idx[k] + 1]++;
        }
    }
    for (uint32_t v = 0; v < tp->verts; v++)
        tp->vert_start[v + 1] += tp->vert_start[v];
    uint32_t *fill = calloc(tp->verts, sizeof(uint32_t));
    for (uint32_t t = 0; t < tp->tris; t++) {
        uint32_t idx[3];
        cbvh_triangle_indices(f, t, idx);
        for (int k = 0; k < 3; k++)
            tp->vert_tris[tp->vert_start[idx[k]] + fill[idx[k]]++] = t;
    }
    free(fill);
    qsort(tp->edges, 3 * (size_t)tp->tris, sizeof *tp->edges, cmp_edge);
    for (size_t i = 0, n = 3 * (size_t)tp->tris; i < n;) {
        size_t j = i;
        while (j < n && tp->edges[j].key == tp->edges[i].key)
            j++;
        if (j - i != 2) {
            tp->border[tp->edges[i].key >> 32] = 1;
            tp->border[(uint32_t)tp->edges[i].key] = 1;
        }
        i = j;
    }
}

static void topology_free(topology *tp)
{
    free(tp->edges);
    free(tp->vert_start);
    free(tp->vert_tris);
    free(tp->border);
}

/* The smallest |cosine| between the ray and the listed triangles' normals
 * when the ray crosses all of them from the same side, not grazing any
 * (then the surface around the target is pierced, not touched on a
 * silhouette, and a watertight test must report a hit); else 0. */
static double pierces(const cbvh_file *f, const uint32_t *tris, size_t n, const float dir[3])
{
    int sign = 0;
    double least = 1;
    double dl = vec_len(dir);
    for (size_t i = 0; i < n; i++) {
        float v[3][3];
        cbvh_triangle_vertices(f, tris[i], v[0], v[1], v[2]);
        double e1[3], e2[3];
        for (int a = 0; a < 3; a++) {
            e1[a] = (double)v[1][a] - v[0][a];
            e2[a] = (double)v[2][a] - v[0][a];
        }
        double nx = e1[1] * e2[2] - e1[2] * e2[1], ny = e1[2] * e2[0] - e1[0] * e2[2],
               nz = e1[0] * e2[1] - e1[1] * e2[0];
        double nl = sqrt(nx * nx + ny * ny + nz * nz);
        if (!(nl > 0))
            return 0;
        double c = (nx * dir[0] + ny * dir[1] + nz * dir[2]) / (nl * dl);
        int sg = c > 1e-3 ? 1 : c < -1e-3 ? -1 : 0;
        if (sg == 0 || (sign && sg != sign))
            return 0;
        sign = sg;
        least = fmin(least, fabs(c));
    }
    return least;
}

/* Targets: every vertex (when no border edge touches it) and the points at
 * 1/2, 1/4, 3/4, 7/8 of every shared edge that are exact floats on the
 * edge, of every `stride`-th cooked triangle; origins on a sphere around the
 * mesh, kept when target - origin is exact (the ray's line passes exactly
 * through the target) and the ray pierces the surface there (pierces()). */
static void watertight_file(const cbvh_file *f, uint32_t stride, int origins_per_target, leak_stats *st,
                            size_t *skipped)
{
    topology tp;
    topology_build(f, &tp);
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    double rad = 0;
    for (int a = 0; a < 3; a++) {
        rad += ((double)info.bounds_max[a] - info.bounds_min[a]) *
               ((double)info.bounds_max[a] - info.bounds_min[a]);
    }
    rad = sqrt(rad);
    double unit_len = exp2(floor(log2(rad / 64)));
    uint64_t rng = 12345;
    static const int along[] = {2, 4, 4, 8}; /* points i/n of an edge, n = 2, 4, 4, 8 with i = 1, 1, 3, 7 */
    static const int step[] = {1, 1, 3, 7};
    for (uint32_t t = 0; t < tp.tris; t += stride) {
        uint32_t idx[3];
        float v[3][3];
        cbvh_triangle_indices(f, t, idx);
        cbvh_triangle_vertices(f, t, v[0], v[1], v[2]);
        for (int j = 0; j < 3 + 3 * 4; j++) {
            float target[3];
            const uint32_t *around;
            size_t n_around;
            uint32_t pair[2];
            if (j < 3) { /* the vertex itself */
                if (tp.border[idx[j]])
                    continue;
                memcpy(target, v[j], sizeof target);
                around = tp.vert_tris + tp.vert_start[idx[j]];
                n_around = tp.vert_start[idx[j] + 1] - tp.vert_start[idx[j]];
            } else { /* a point of edge i */
                int i = (j - 3) / 4, k = (j - 3) % 4;
                edge_ref key = {edge_key(idx[i], idx[(i + 1) % 3]), 0};
                edge_ref *e = bsearch(&key, tp.edges, 3 * (size_t)tp.tris, sizeof key, cmp_edge);
                while (e > tp.edges && e[-1].key == key.key)
                    e--;
                if (e + 1 >= tp.edges + 3 * (size_t)tp.tris || e[1].key != key.key ||
                    (e + 2 < tp.edges + 3 * (size_t)tp.tris && e[2].key == key.key))
                    continue; /* a border or non-manifold edge */
                pair[0] = e[0].tri;
                pair[1] = e[1].tri;
                around = pair;
                n_around = 2;
                /* only points exactly on the edge: n * P == (n - i) * a + i * b holds exactly in double */
                int exact = 1;
                for (int a = 0; a < 3; a++) {
                    double pa = v[i][a], pb = v[(i + 1) % 3][a];
                    target[a] = (float)(((along[k] - step[k]) * pa + step[k] * pb) / along[k]);
                    exact &= (double)target[a] * along[k] == (along[k] - step[k]) * pa + step[k] * pb;
                }
                if (!exact) {
                    (*skipped)++;
                    continue;
                }
            }
            for (int o = 0; o < origins_per_target; o++) {
                /* a direction of small integers times a power of two, so that
                 * org = target - dir is usually exact; any origin works: a
                 * ray that pierces the surface at t = 1 must hit by then */
                float org[3], d[3];
                for (int a = 0; a < 3; a++) {
                    d[a] = (float)((double)((int)(scene_rand_unit(&rng) * 129) - 64) * unit_len);
                    org[a] = target[a] - d[a];
                }
                float dir[3] = {target[0] - org[0], target[1] - org[1], target[2] - org[2]};
                double cosine = pierces(f, around, n_around, dir);
                /* the ray's line must pass exactly through the target */
                for (int a = 0; a < 3; a++)
                    if ((double)dir[a] != (double)target[a] - (double)org[a])
                        cosine = 0;
                if (cosine == 0) {
                    (*skipped)++;
                    continue;
                }
                shoot_at(f, org, target, cosine, st);
            }
        }
    }
    topology_free(&tp);
}

static void report_leaks(const char *what, const leak_stats *st, size_t skipped)
{
    printf("watertight %-30s %7zu rays (%zu inexact or grazing skipped): leaks sorted %zu stackless %zu "
           "unsorted %zu distance %zu stream %zu "
           "occluded %zu\n",
           what, st->rays, skipped, st->leaks[0], st->leaks[1], st->leaks[2], st->leaks[3], st->leaks[4],
           st->leaks[5]);
    assert_true(st->rays > 0);
    for (int i = 0; i < 6; i++)
        assert_int_equal(st->leaks[i], 0);
}

static void watertight_scene(const char *name, const scene *s, int origins)
{
    for (int q = 0; q < 2; q++) {
        cbvh_cook_options o = options(q, 0);
        void *buf = NULL;
        size_t size = 0;
        cbvh_file *f = NULL;
        cbvh_mesh m = {s->positions, s->vertex_count, 0, s->indices, s->triangle_count, NULL};
        assert_int_equal(cbvh_cook(&m, &o, NULL, &buf, &size, NULL, NULL), CBVH_OK);
        assert_int_equal(cbvh_open_memory(buf, size, NULL, &f, NULL), CBVH_OK);
        leak_stats st;
        size_t skipped = 0;
        memset(&st, 0, sizeof st);
        watertight_file(f, 1, (int)test_reps(origins), &st, &skipped);
        char what[128];
        snprintf(what, sizeof what, "%s, %s", name, q ? "quantized" : "lossless");
        report_leaks(what, &st, skipped);
        cbvh_close(f);
        cbvh_buffer_free(NULL, buf);
    }
}

static void test_watertight(void **state)
{
    (void)state;
    scene s;
    float c[3] = {0.3f, -0.2f, 0.1f}, lo[3] = {-1, -2, -3}, hi[3] = {1.5f, 2.5f, 0.5f};
    assert_true(scene_sphere(&s, 3000, c, 1.0f));
    watertight_scene("sphere 3000", &s, 3);
    scene_free(&s);
    assert_true(scene_cube(&s, lo, hi));
    watertight_scene("cube", &s, 400);
    scene_free(&s);
    /* far away: the float spacing of the vertices is coarse */
    float far_c[3] = {1e5f, -3e5f, 2e5f};
    assert_true(scene_sphere(&s, 3000, far_c, 10.0f));
    watertight_scene("sphere 3000 at 1e5", &s, 3);
    scene_free(&s);
}

/* A cooked file's own vertices and triangles cooked again with 16-bit
 * quantized vertices: the same vertex indices, so every shared edge stays
 * shared (identical positions quantize identically). */
static cbvh_file *requantized(const cbvh_file *f, void **buffer)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    float *pos = calloc(3 * (size_t)info.vertex_count, sizeof(float));
    uint32_t *idx = malloc(3 * (size_t)info.triangle_count * sizeof(uint32_t));
    assert_non_null(pos);
    assert_non_null(idx);
    for (uint32_t t = 0; t < info.triangle_count; t++) {
        float v[3][3];
        cbvh_triangle_indices(f, t, idx + 3 * (size_t)t);
        cbvh_triangle_vertices(f, t, v[0], v[1], v[2]);
        for (int k = 0; k < 3; k++)
            memcpy(pos + 3 * (size_t)idx[3 * (size_t)t + k], v[k], sizeof v[k]);
    }
    cbvh_cook_options o = options(1, 0);
    cbvh_mesh m = {pos, info.vertex_count, 0, idx, info.triangle_count, NULL};
    size_t size = 0;
    cbvh_file *q = NULL;
    assert_int_equal(cbvh_cook(&m, &o, NULL, buffer, &size, NULL, NULL), CBVH_OK);
    assert_int_equal(cbvh_open_memory(*buffer, size, NULL, &q, NULL), CBVH_OK);
    free(pos);
    free(idx);
    return q;
}

/* The dragon (871K triangles, a real scan with borders): a sample of its
 * shared edges and interior vertices, from a cooked file named by
 * CBVH_DRAGON, as cooked (lossless) and cooked again with quantized vertices. */
static void test_watertight_dragon(void **state)
{
    (void)state;
    const char *path = getenv("CBVH_DRAGON");
    if (!path || !*path) {
        printf("CBVH_DRAGON not set (path of a cooked dragon, e.g. `cbvh cook dragon_vrip.ply dragon.cbvh`): "
               "skipped\n");
        skip();
    }
    cbvh_file *f = NULL;
    cbvh_error err;
    if (cbvh_open_path(path, NULL, &f, &err) != CBVH_OK)
        fail_msg("CBVH_DRAGON=%s: %s", path, err.message);
    void *buf = NULL;
    cbvh_file *q = requantized(f, &buf);
    const cbvh_file *files[2] = {f, q};
    const long stride = test_reps_stride(37);
    for (int k = 0; k < 2; k++) {
        leak_stats st;
        size_t skipped = 0;
        memset(&st, 0, sizeof st);
        watertight_file(files[k], (uint32_t)stride, 1, &st, &skipped);
        char what[64];
        snprintf(what, sizeof what, "dragon, %s (every %ldth)", k ? "quantized" : "lossless", stride);
        report_leaks(what, &st, skipped);
    }
    cbvh_close(q);
    cbvh_buffer_free(NULL, buf);
    cbvh_close(f);
}

/* ------------------------------------------------------------------ */
/* Far from the origin and at every scale                             */
/* ------------------------------------------------------------------ */

static void transformed(const scene *s, double scale, double offset, float *out)
{
    for (size_t i = 0; i < 3 * s->vertex_count; i++)
        out[i] = (float)((double)s->positions[i] * scale + offset * (i % 3 == 1 ? -0.5 : 1.0));
}

static void test_scales(void **state)
{
    (void)state;
    scene base;
    float c[3] = {0, 0, 0};
    assert_true(scene_sphere(&base, 2000, c, 1000.0f)); /* a 2 km object: still resolved at 1e7 */
    float *pos = malloc(3 * base.vertex_count * sizeof(float));
    static const struct {
        double scale, offset;
    } cases[] = {
        {1, 0},    {1, 1e3},  {1, -1e3}, {1, 1e5},  {1, -1e5},   {1, 1e7},
        {1, -1e7}, {1e-6, 0}, {1e9, 0},  {1e-6, 1}, {1e9, 1e10},
    };
    uint64_t nodes_at_origin[2] = {0, 0};
    printf("%-8s %-8s %-9s %6s %6s %6s %6s %6s %6s %9s %8s\n", "scale", "offset", "vertices", "rays", "clear",
           "missed", "early", "offpl", "paths", "nodes/ray", "vs orig");
    for (size_t ci = 0; ci < sizeof cases / sizeof cases[0]; ci++) {
        transformed(&base, cases[ci].scale, cases[ci].offset, pos);
        for (int q = 0; q < 2; q++) {
            cbvh_cook_options o = options(q, 0);
            ref_fixture fx;
            assert_int_equal(
                ref_fixture_open(&fx, pos, base.vertex_count, base.indices, base.triangle_count, &o),
                CBVH_OK);
            size_t bad = 0, checked;
            float lo[3], hi[3];
            checked = check_tree_conservative(fx.file, lo, hi, &bad);
            if (bad)
                fail_msg("scale %g offset %g: %zu of %zu node boxes not conservative", cases[ci].scale,
                         cases[ci].offset, bad, checked);
            agree_stats st;
            memset(&st, 0, sizeof st);
            uint64_t rng = 777; /* the same rays relative to the mesh in every case */
            for (int i = 0; i < test_reps(1000); i++) {
                cbvh_ray r = ref_make_ray(&fx, &rng, i % REF_RAY_KINDS);
                check_against_reference(&fx, &r, HIT_TOL, &st);
            }
            if (ci == 0)
                nodes_at_origin[q] = st.nodes;
            double ratio = (double)st.nodes / (double)nodes_at_origin[q];
            printf("%-8g %-8g %-9s %6zu %6zu %6zu %6zu %6zu %6zu %9.2f %8.2f\n", cases[ci].scale,
                   cases[ci].offset, q ? "quantized" : "lossless", st.rays, st.clear_hits, st.missed,
                   st.early, st.off_plane, st.disagree_paths, (double)st.nodes / (double)st.rays, ratio);
            char what[96];
            snprintf(what, sizeof what, "scale %g offset %g %s", cases[ci].scale, cases[ci].offset,
                     q ? "quantized" : "lossless");
            assert_agreement(what, &st);
            if (ratio > 2.0)
                fail_msg("%s: %.2fx the node visits of the mesh at the origin", what, ratio);
            ref_fixture_close(&fx);
        }
    }
    free(pos);
    scene_free(&base);
}

/* Finding F1 (notes/findings.md, fixed in 8c211da): coordinates beyond ~1e12
 * used to overflow the float triangle test and every ray missed. */
static void test_huge_extent(void **state)
{
    (void)state;
    printf("huge extents (tetrahedron of edge s, 200 rays through a face):");
    for (int e = 9; e <= 30; e += 3) {
        float s = powf(10.0f, (float)e);
        float p[12] = {0, 0, 0, s, 0, 0, 0, s, 0, 0, 0, s};
        uint32_t idx[12] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
        cbvh_mesh m = {p, 4, 0, idx, 4, NULL};
        void *buf = NULL;
        size_t n = 0;
        cbvh_result r = cbvh_cook(&m, test_options(), NULL, &buf, &n, NULL, NULL);
        if (r != CBVH_OK) {
            printf(" 1e%d: cook %s;", e, cbvh_result_string(r));
            continue;
        }
        cbvh_file *f = NULL;
        assert_int_equal(cbvh_open_memory(buf, n, NULL, &f, NULL), CBVH_OK);
        int miss = 0;
        for (int i = 0; i < 200; i++) {
            float a = (float)(i % 10 + 0.5) / 20, b = (float)(i / 10 % 10 + 0.5) / 20;
            cbvh_ray ray = {{a * s, b * s, -s}, 0, {0, 0, 1}, INFINITY};
            if (i >= 100)
                ray = (cbvh_ray){{a * s - s, b * s - 2 * s, -s}, 0, {s, 2 * s, s}, INFINITY};
            cbvh_hit h;
            miss += !cbvh_raycast(f, &ray, CBVH_TRAVERSAL_SORTED, &h, NULL);
        }
        printf(" 1e%d: %d missed;", e, miss);
        assert_int_equal(miss, 0);
        cbvh_close(f);
        cbvh_buffer_free(NULL, buf);
    }
    printf("\n");
}

/* ------------------------------------------------------------------ */
/* The exact range (cbvh.h: CBVH_COORDINATE_MAX and _MIN)             */
/* ------------------------------------------------------------------ */

/* Coordinates as the cooker stores them: below CBVH_COORDINATE_MIN in magnitude, 0. */
static void flush_below_range(float *pos, size_t count)
{
    for (size_t i = 0; i < count; i++)
        pos[i] = fabsf(pos[i]) < CBVH_COORDINATE_MIN ? 0.0f : pos[i];
}

static int hit_all_paths(const cbvh_file *f, const cbvh_ray *r, cbvh_hit *out);

/* The same ray with its direction scaled by 2^k (k from -100 to 100) answers at t scaled by 2^-k exactly,
 * and every path agrees (where the scaled direction and t are normal floats and t at most FLT_MAX / 2). */
static void check_direction_scales(const cbvh_file *f, const cbvh_ray *r)
{
    cbvh_hit h0;
    const int got0 = cbvh_raycast(f, r, CBVH_TRAVERSAL_SORTED, &h0, NULL);
    static const int ks[] = {-100, -60, -30, -8, 8, 30, 60, 100};
    for (size_t i = 0; i < sizeof ks / sizeof ks[0]; i++) {
        cbvh_ray s = *r; /* the same segment: its range scaled as its t */
        for (int a = 0; a < 3; a++)
            s.dir[a] = ldexpf(r->dir[a], ks[i]);
        s.tmin = ldexpf(r->tmin, -ks[i]);
        s.tmax = ldexpf(r->tmax, -ks[i]);
        if (!ref_ray_valid(&s) || !(fabsf(s.dir[0]) + fabsf(s.dir[1]) + fabsf(s.dir[2]) > 0.0f))
            continue;
        int finite = 1; /* every component kept exactly (no overflow, no underflow) */
        for (int a = 0; a < 3; a++)
            finite &= ldexpf(s.dir[a], -ks[i]) == r->dir[a];
        /* and t stays a normal float no larger than the largest t a ray reports (FLT_MAX / 2) */
        const double t_scaled = got0 ? ldexp(h0.t, -ks[i]) : 1.0;
        if (!finite || !(t_scaled <= 0x1.fffffep126 && (t_scaled == 0.0 || t_scaled >= 0x1p-126)))
            continue;
        cbvh_hit h;
        const int got = hit_all_paths(f, &s, &h);
        if (got != got0 || (got && (h.tri != h0.tri || h.t != ldexpf(h0.t, -ks[i]))))
            fail_msg("direction times 2^%d: %s t %g, unscaled %s t %g", ks[i], got ? "hit" : "miss",
                     got ? h.t : 0.0, got0 ? "hit" : "miss", got0 ? h0.t : 0.0);
    }
}

/* Meshes at the edges of the exact range: the largest accepted coordinates (a sphere just inside
 * CBVH_COORDINATE_MAX, its triangles 32 float steps across there) and the smallest accepted features (a
 * sphere of radius 2^-30 at the origin, its coordinates below CBVH_COORDINATE_MIN stored as 0, alone and
 * together with a triangle at CBVH_COORDINATE_MAX: the widest dynamic range a file can hold). Each against
 * the double reference on every path, watertight, and its rays with scaled directions exact; the large
 * sphere one float step past the range is refused with the limit named. */
static void test_exact_range(void **state)
{
    (void)state;
    /* the largest: 2^40 - 2^26 - 2^22 at most, float steps of 2^16 there */
    const float edge = 0x1p40f - 0x1p26f;
    float big_c[3] = {edge - 0x1p22f, -(edge - 0x1p22f), edge - 0x1p22f};
    scene big;
    assert_true(scene_sphere(&big, 2000, big_c, 0x1p21f));
    watertight_scene("sphere at the range's edge", &big, 3);
    for (int q = 0; q < 2; q++) {
        cbvh_cook_options o = options(q, 0);
        ref_fixture fx;
        assert_int_equal(
            ref_fixture_open(&fx, big.positions, big.vertex_count, big.indices, big.triangle_count, &o),
            CBVH_OK);
        agree_stats st;
        memset(&st, 0, sizeof st);
        uint64_t rng = 91;
        for (int i = 0; i < test_reps(1000); i++) {
            cbvh_ray r = ref_make_ray(&fx, &rng, i % REF_RAY_KINDS);
            check_against_reference(&fx, &r, HIT_TOL, &st);
            if (i % 50 == 0)
                check_direction_scales(fx.file, &r);
        }
        assert_agreement(q ? "range's edge, quantized" : "range's edge", &st);
        ref_fixture_close(&fx);
    }
    /* one float step past the range: refused, naming the limit */
    float far[9] = {0, 0, 0, nextafterf(CBVH_COORDINATE_MAX, INFINITY), 0, 0, 0, 1, 0};
    const uint32_t tri[3] = {0, 1, 2};
    cbvh_mesh past = {far, 3, 0, tri, 1, NULL};
    cbvh_error err;
    void *buf = NULL;
    size_t size = 0;
    assert_int_equal(cbvh_cook(&past, NULL, NULL, &buf, &size, NULL, &err), CBVH_ERROR_BAD_MESH);
    assert_non_null(strstr(err.message, "vertex 1: x coordinate"));
    assert_non_null(strstr(err.message, "2^40"));

    /* the smallest features, alone and beside a triangle at the range's edge */
    const float small_c[3] = {0, 0, 0};
    scene small, mixed;
    assert_true(scene_sphere(&small, 2000, small_c, 0x1p-30f));
    flush_below_range(small.positions, 3 * small.vertex_count);
    watertight_scene("sphere of radius 2^-30", &small, 3);
    const float big_tri[9] = {
        CBVH_COORDINATE_MAX, CBVH_COORDINATE_MAX, 0, CBVH_COORDINATE_MAX, 0, CBVH_COORDINATE_MAX, 0,
        CBVH_COORDINATE_MAX, CBVH_COORDINATE_MAX};
    const uint32_t big_idx[3] = {0, 1, 2};
    const scene far_tri = {(float *)big_tri, (uint32_t *)big_idx, NULL, 3, 1};
    memset(&mixed, 0, sizeof mixed);
    assert_true(scene_append(&mixed, &small, 0) && scene_append(&mixed, &far_tri, 0));
    for (int m = 0; m < 2; m++) {
        const scene *sc = m ? &mixed : &small;
        for (int q = 0; q < 2; q++) {
            cbvh_cook_options o = options(q, 0);
            cbvh_cook_stats stats;
            cbvh_cook_stats_init(&stats, sizeof stats);
            ref_fixture fx;
            assert_int_equal(
                ref_fixture_open(&fx, sc->positions, sc->vertex_count, sc->indices, sc->triangle_count, &o),
                CBVH_OK);
            /* judged on the small sphere's scale: its bounds and diagonal, rays from a few radii away */
            ref_fixture local = fx;
            for (int a = 0; a < 3; a++) {
                local.lo[a] = -0x1p-30;
                local.hi[a] = 0x1p-30;
            }
            local.diag = 0x1p-30 * 2 * sqrt(3.0);
            agree_stats st;
            memset(&st, 0, sizeof st);
            uint64_t rng = 17;
            for (int i = 0; i < test_reps(1000); i++) {
                const size_t t = (size_t)(scene_rand_next(&rng) % small.triangle_count);
                const double wb = 0.05 + 0.45 * scene_rand_unit(&rng),
                             wc = 0.05 + 0.45 * scene_rand_unit(&rng);
                /* t about 1 at the target; the range ends long before the triangle at 2^40, whose hits are
                 * judged at its own scale, not the sphere's */
                cbvh_ray r = {{0, 0, 0}, 0, {0, 0, 0}, 64.0f};
                for (int a = 0; a < 3; a++) {
                    const float *v0 = small.positions + 3 * small.indices[3 * t],
                                *v1 = small.positions + 3 * small.indices[3 * t + 1],
                                *v2 = small.positions + 3 * small.indices[3 * t + 2];
                    const double target = (1 - wb - wc) * v0[a] + wb * v1[a] + wc * v2[a];
                    r.org[a] = (float)(target + 0x1p-28 * (2 * scene_rand_unit(&rng) - 1));
                    r.dir[a] = (float)(target - r.org[a]);
                }
                if (i % 3 == 0) /* an origin coordinate below the range, subnormal included */
                    r.org[i % 2] = i % 4 ? 0x1p-149f : -0x1p-70f;
                check_against_reference(&local, &r, HIT_TOL, &st);
                if (i % 50 == 0)
                    check_direction_scales(fx.file, &r);
            }
            char what[64];
            snprintf(what, sizeof what, "radius 2^-30%s%s", m ? " beside 2^40" : "", q ? ", quantized" : "");
            printf("%s: %zu rays, %zu clear hits\n", what, st.rays, st.clear_hits);
            assert_agreement(what, &st);
            /* quantized on a grid of 2^40 / 65535, the small sphere collapses (its triangles dropped): the
             * clear hits are the lossless and alone cases' */
            if (!(m && q))
                assert_true(st.clear_hits > st.rays / 2);
            ref_fixture_close(&fx);
        }
    }
    scene_free(&mixed);
    scene_free(&small);
    scene_free(&big);
}

/* ------------------------------------------------------------------ */
/* Degenerate meshes                                                  */
/* ------------------------------------------------------------------ */

typedef struct mesh_case {
    const char *name;
    size_t vertex_count, triangle_count;
    float pos[3 * 12];
    uint32_t idx[3 * 12];
    cbvh_result expect; /* cook result */
    size_t dropped;     /* triangles the cooker must drop */
    double tolerance;   /* relative to the diagonal */
} mesh_case;

static void test_degenerate_meshes(void **state)
{
    (void)state;
    static const mesh_case cases[] = {
        {"single triangle", 3, 1, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2}, CBVH_OK, 0, HIT_TOL},
        {"sliver 1e7:1", 3, 1, {0, 0, 0, 1e3f, 0, 0, 500, 1e-4f, 0}, {0, 1, 2}, CBVH_OK, 0, HIT_TOL},
        {"needle",
         4,
         2,
         {0, 0, 0, 0, 0, 1e3f, 1e-4f, 0, 0, 0, 1e-4f, 1e3f},
         {0, 1, 2, 1, 3, 2},
         CBVH_OK,
         0,
         HIT_TOL},
        {"zero-area + good",
         6,
         2,
         {0, 0, 0, 1, 1, 1, 2, 2, 2, 0, 0, 0, 1, 0, 0, 0, 1, 0},
         {0, 1, 2, 3, 4, 5},
         CBVH_OK,
         1,
         HIT_TOL},
        {"repeated vertex",
         4,
         2,
         {0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0},
         {0, 1, 3, 0, 2, 3},
         CBVH_OK,
         0,
         HIT_TOL},
        {"duplicated triangle", 3, 2, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2, 0, 1, 2}, CBVH_OK, 0, HIT_TOL},
        {"back-to-back", 3, 2, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 2, 0, 2, 1}, CBVH_OK, 0, HIT_TOL},
        {"flat (zero z extent)",
         4,
         2,
         {0, 0, 5, 1, 0, 5, 1, 1, 5, 0, 1, 5},
         {0, 1, 2, 0, 2, 3},
         CBVH_OK,
         0,
         HIT_TOL},
        {"line (zero y,z extent)",
         3,
         1,
         {0, 2, 2, 1, 2, 2, 3, 2, 2},
         {0, 1, 2},
         CBVH_ERROR_EMPTY_MESH,
         1,
         HIT_TOL},
        {"all vertices equal",
         3,
         2,
         {1, 1, 1, 1, 1, 1, 1, 1, 1},
         {0, 1, 2, 2, 1, 0},
         CBVH_ERROR_EMPTY_MESH,
         2,
         HIT_TOL},
        {"no triangles", 3, 0, {0}, {0}, CBVH_ERROR_EMPTY_MESH, 0, HIT_TOL},
        {"index out of range", 3, 1, {0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 1, 3}, CBVH_ERROR_BAD_MESH, 0, HIT_TOL},
        {"NaN coordinate", 3, 1, {0, 0, 0, NAN, 0, 0, 0, 1, 0}, {0, 1, 2}, CBVH_ERROR_BAD_MESH, 0, HIT_TOL},
        {"infinite coordinate",
         3,
         1,
         {0, 0, 0, INFINITY, 0, 0, 0, 1, 0},
         {0, 1, 2},
         CBVH_ERROR_BAD_MESH,
         0,
         HIT_TOL},
    };
    for (size_t ci = 0; ci < sizeof cases / sizeof cases[0]; ci++) {
        const mesh_case *mc = &cases[ci];
        for (int q = 0; q < 2; q++) {
            cbvh_mesh m = {mc->pos, mc->vertex_count, 0, mc->idx, mc->triangle_count, NULL};
            cbvh_cook_options o = options(q, 0);
            cbvh_cook_stats stats;
            cbvh_cook_stats_init(&stats, sizeof stats);
            cbvh_error err;
            void *buf = NULL;
            size_t n = 0;
            cbvh_result r = cbvh_cook(&m, &o, NULL, &buf, &n, &stats, &err);
            printf("mesh %-24s %-9s: %s%s%s\n", mc->name, q ? "quantized" : "lossless", cbvh_result_string(r),
                   r ? ": " : "", r ? err.message : "");
            if (r != mc->expect)
                fail_msg("%s: cook gave %s, expected %s (%s)", mc->name, cbvh_result_string(r),
                         cbvh_result_string(mc->expect), err.message);
            if (r != CBVH_OK) {
                assert_true(err.message[0] != 0);
                continue;
            }
            if (!q)
                assert_int_equal(stats.dropped_degenerate, mc->dropped);
            cbvh_buffer_free(NULL, buf);
            ref_fixture fx;
            assert_int_equal(
                ref_fixture_open(&fx, mc->pos, mc->vertex_count, mc->idx, mc->triangle_count, &o), CBVH_OK);
            size_t bad = 0;
            float lo[3], hi[3];
            check_tree_conservative(fx.file, lo, hi, &bad);
            assert_int_equal(bad, 0);
            agree_stats st;
            memset(&st, 0, sizeof st);
            uint64_t rng = 31;
            for (int i = 0; i < 4000; i++) {
                cbvh_ray ray = ref_make_ray(&fx, &rng, i % REF_RAY_KINDS);
                check_against_reference(&fx, &ray, mc->tolerance, &st);
            }
            assert_agreement(mc->name, &st);
            /* dropped triangles are never reported */
            for (uint32_t t = 0; t < mc->triangle_count; t++)
                if (fx.index_of_id[t] == (size_t)-1) {
                    float v[3][3];
                    assert_int_equal(cbvh_file_get_triangle(fx.file, t, v[0], v[1], v[2]), 0);
                }
            ref_fixture_close(&fx);
        }
    }
}

/* Finding F2 (notes/findings.md, fixed in 8c211da): t used to drift on
 * slivers. Rays aimed inside a triangle of length 1000 and width
 * 1000/aspect: the hit point must lie on the plane within 1e-5 of the length. */
static void test_sliver_accuracy(void **state)
{
    (void)state;
    printf("sliver accuracy (triangle length 1000): aspect: worst hit distance from the plane, missed of "
           "inside rays\n");
    for (int e = 0; e <= 8; e++) {
        float w = 1e3f / powf(10.0f, (float)e);
        float pos[9] = {0, 0, 0, 1e3f, 0, 0, 500, w, 0};
        uint32_t idx[3] = {0, 1, 2};
        cbvh_cook_options o = options(0, 0);
        ref_fixture fx;
        assert_int_equal(ref_fixture_open(&fx, pos, 3, idx, 1, &o), CBVH_OK);
        uint64_t rng = 31;
        double worst = 0;
        int inside = 0, missed = 0;
        for (int i = 0; i < 5000; i++) {
            cbvh_ray r = ref_make_ray(&fx, &rng, 1);
            double t, u, v, m;
            /* inside by at least 8 float steps at the coordinates' magnitude */
            if (!ref_ray_triangle(fx.tris.v, &r, &t, &u, &v, &m) || m < 8 * 1e3 * 1.2e-7)
                continue;
            inside++;
            cbvh_hit h;
            if (!cbvh_raycast(fx.file, &r, CBVH_TRAVERSAL_SORTED, &h, NULL)) {
                missed++;
                continue;
            }
            worst = fmax(worst, fabs((double)r.org[2] + (double)h.t * r.dir[2]));
        }
        printf("  1e%d: %.3g, %d of %d\n", e, worst, missed, inside);
        assert_true(worst <= 1e-5 * 1e3);
        assert_int_equal(missed, 0);
        ref_fixture_close(&fx);
    }
}

/* ------------------------------------------------------------------ */
/* Extreme rays                                                       */
/* ------------------------------------------------------------------ */

static int hit_all_paths(const cbvh_file *f, const cbvh_ray *r, cbvh_hit *out)
{
    cbvh_hit h[4], sh;
    int got[4];
    for (int t = 0; t < 4; t++)
        got[t] = cbvh_raycast(f, r, (cbvh_traversal)t, &h[t], NULL);
    cbvh_raycast_stream(f, r, 1, &sh, NULL);
    int occ = cbvh_occluded(f, r, CBVH_TRAVERSAL_SORTED, NULL);
    for (int t = 1; t < 4; t++) {
        assert_int_equal(got[t], got[0]);
        if (got[0])
            assert_true(h[t].t == h[0].t);
    }
    assert_int_equal(sh.tri != CBVH_NO_HIT, got[0]);
    assert_int_equal(occ, got[0]);
    *out = h[0];
    return got[0];
}

static void test_extreme_rays(void **state)
{
    (void)state;
    /* a unit cube [0,1]^3: its faces lie on the node boxes' planes */
    scene s;
    float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    assert_true(scene_cube(&s, lo, hi));
    cbvh_cook_options o = options(0, 0);
    ref_fixture fx;
    assert_int_equal(ref_fixture_open(&fx, s.positions, s.vertex_count, s.indices, s.triangle_count, &o),
                     CBVH_OK);
    const cbvh_file *f = fx.file;
    cbvh_hit h;
    const float inf = INFINITY, nan = NAN, den = 1e-40f;
    static const char *const names[] = {
        "dir (0,0,1)",         "dir (-0,-0,1)",
        "dir (den,-den,1)",    "dir (1e30 scaled)",
        "unnormalized 1e-20",  "origin on a face",
        "origin on an edge",   "origin on a vertex",
        "origin on box plane", "in the face's plane",
        "tmin = tmax at face", "tmin > tmax",
        "zero direction",      "NaN origin",
        "inf origin",          "NaN direction",
        "inf direction",       "NaN tmax",
        "negative tmin",       "tmax = +inf, tmin inf",
    };
    const cbvh_ray rays[] = {
        {{0.5f, 0.5f, -1}, 0, {0, 0, 1}, inf},        {{0.5f, 0.5f, -1}, 0, {-0.0f, -0.0f, 1}, inf},
        {{0.5f, 0.5f, -1}, 0, {den, -den, 1}, inf},   {{0.5f, 0.5f, -1}, 0, {1e20f, 1e20f, 1e30f}, inf},
        {{0.25f, 0.75f, -1}, 0, {0, 0, 1e-20f}, inf}, {{0.5f, 0.5f, 0}, 0, {0, 0, 1}, inf},
        {{0.5f, 0, 0}, 0, {0, 0.3f, 1}, inf},         {{0, 0, 0}, 0, {0.3f, 0.4f, 1}, inf},
        {{0.5f, 0.5f, -1}, 0, {0, 0, 1}, inf}, /* origin on the plane x = 0.5? no: on y,z planes below */
        {{-1, 0.5f, 0}, 0, {1, 0, 0}, inf},           {{0.5f, 0.5f, -1}, 1, {0, 0, 1}, 1},
        {{0.5f, 0.5f, -1}, 2, {0, 0, 1}, 1},          {{0.5f, 0.5f, -1}, 0, {0, 0, 0}, inf},
        {{nan, 0.5f, -1}, 0, {0, 0, 1}, inf},         {{inf, 0.5f, -1}, 0, {0, 0, 1}, inf},
        {{0.5f, 0.5f, -1}, 0, {0, nan, 1}, inf},      {{0.5f, 0.5f, -1}, 0, {0, inf, 1}, inf},
        {{0.5f, 0.5f, -1}, 0, {0, 0, 1}, nan},        {{0.5f, 0.5f, -1}, -1, {0, 0, 1}, inf},
        {{0.5f, 0.5f, -1}, inf, {0, 0, 1}, inf},
    };
    cbvh_ray plane_ray = {{0, 0.5f, -1}, 0, {0, 0, 1}, inf}; /* origin on the box plane x = 0 */
    for (size_t i = 0; i < sizeof rays / sizeof rays[0]; i++) {
        cbvh_ray r = i == 8 ? plane_ray : rays[i];
        ref_ray_hit ref;
        int want = ref_ray_closest(&fx.tris, &r, 0, &ref);
        int got = hit_all_paths(f, &r, &h);
        printf("ray %-22s valid %d: reference %s t %-10g  cbvh %s t %g\n", names[i], ref_ray_valid(&r),
               want ? "hit " : "miss", want ? ref.t : 0.0, got ? "hit " : "miss", got ? h.t : 0.0);
        if (!ref_ray_valid(&r)) {
            assert_int_equal(got, 0); /* cbvh.h: invalid rays miss on every query */
            assert_int_equal(h.tri, CBVH_NO_HIT);
            continue;
        }
        if (i == 9)
            continue; /* in the plane of the x = 0 face: either answer, consistent across paths (checked
                         above) */
        assert_int_equal(got, want);
        if (got)
            assert_true(fabs((double)h.t - ref.t) <= 1e-6 * fmax(1.0, ref.t));
    }
    ref_fixture_close(&fx);
    scene_free(&s);
}

/* ------------------------------------------------------------------ */
/* Sweeps                                                             */
/* ------------------------------------------------------------------ */

static void test_extreme_sweeps(void **state)
{
    (void)state;
    scene s;
    float c[3] = {0, 0, 0};
    assert_true(scene_sphere(&s, 800, c, 1.0f));
    cbvh_cook_options o = options(0, 0);
    ref_fixture fx;
    assert_int_equal(ref_fixture_open(&fx, s.positions, s.vertex_count, s.indices, s.triangle_count, &o),
                     CBVH_OK);
    const cbvh_file *f = fx.file;
    uint64_t rng = 3;
    size_t zero_agree = 0, zero_total = 0;
    for (int i = 0; i < 500; i++) {
        cbvh_ray r = ref_make_ray(&fx, &rng, i % 3);
        float delta[3] = {r.dir[0] * 3, r.dir[1] * 3, r.dir[2] * 3}, zero[3] = {0, 0, 0};
        cbvh_ray seg = r;
        seg.dir[0] = delta[0];
        seg.dir[1] = delta[1];
        seg.dir[2] = delta[2];
        seg.tmax = 1;
        cbvh_hit rh;
        cbvh_sweep_hit sh, ch, bh;
        int rg = cbvh_raycast(f, &seg, CBVH_TRAVERSAL_SORTED, &rh, NULL);
        int sg = cbvh_sweep_sphere(f, r.org, 0.0f, delta, &sh);
        int cg = cbvh_sweep_capsule(f, r.org, r.org, 0.0f, delta, &ch);
        int bg = cbvh_sweep_box(f, r.org, zero, delta, &bh);
        zero_total++;
        /* radius 0 is the raycast: same contact and t (up to the sweep's own arithmetic) */
        if (sg == rg && cg == rg && bg == rg &&
            (!rg || (fabs((double)sh.t - rh.t) < 1e-5 && fabs((double)ch.t - rh.t) < 1e-5 &&
                     fabs((double)bh.t - rh.t) < 1e-5)))
            zero_agree++;
    }
    printf("sweeps of radius/half-extent 0 agreeing with the raycast: %zu of %zu\n", zero_agree, zero_total);
    assert_int_equal(zero_agree, zero_total);

    /* huge radius around the mesh: overlapping at the start, t = 0, unit normal */
    float center[3] = {0.1f, 0.2f, 0.3f}, delta[3] = {1, 0, 0}, half_big[3] = {1e6f, 1e6f, 1e6f};
    cbvh_sweep_hit h;
    assert_int_equal(cbvh_sweep_sphere(f, center, 1e6f, delta, &h), 1);
    assert_true(h.t == 0.0f && fabs(vec_len(h.normal) - 1) < 1e-4);
    assert_int_equal(cbvh_sweep_box(f, center, half_big, delta, &h), 1);
    assert_true(h.t == 0.0f && fabs(vec_len(h.normal) - 1) < 1e-4);
    float far_p1[3] = {0.1f, 0.2f, 1e6f};
    assert_int_equal(cbvh_sweep_capsule(f, center, far_p1, 1e5f, delta, &h), 1);
    assert_true(h.t == 0.0f && fabs(vec_len(h.normal) - 1) < 1e-4);

    /* overlapping at the start: small sphere straddling the surface */
    float on[3] = {0, 0, 1}, away[3] = {0, 0, 5};
    assert_int_equal(cbvh_sweep_sphere(f, on, 0.05f, away, &h), 1);
    assert_true(h.t == 0.0f && isfinite(h.normal[0]) && fabs(vec_len(h.normal) - 1) < 1e-4);

    /* exact touching contact on a flat face: a unit cube and a sphere whose
     * surface starts exactly on the face plane, moving away and along it */
    scene cube;
    float lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    assert_true(scene_cube(&cube, lo, hi));
    ref_fixture cx;
    assert_int_equal(
        ref_fixture_open(&cx, cube.positions, cube.vertex_count, cube.indices, cube.triangle_count, &o),
        CBVH_OK);
    float touch[3] = {0.5f, 0.5f, 1.25f}, up[3] = {0, 0, 1}, down[3] = {0, 0, -1}, side[3] = {0.1f, 0, 0};
    int touching = cbvh_sweep_sphere(cx.file, touch, 0.25f, up, &h);
    printf("sphere touching a face, moving away: %s", touching ? "contact" : "no contact");
    if (touching)
        printf(" at t %g normal (%g %g %g)", h.t, h.normal[0], h.normal[1], h.normal[2]);
    printf("\n");
    if (touching)
        assert_true(h.t == 0.0f && fabs(vec_len(h.normal) - 1) < 1e-4);
    assert_int_equal(cbvh_sweep_sphere(cx.file, touch, 0.25f, down, &h), 1);
    assert_true(h.t == 0.0f && h.normal[2] > 0.99f);
    assert_int_equal(cbvh_sweep_sphere(cx.file, touch, 0.25f, side, &h), touching);
    /* box resting on the face */
    float box_c[3] = {0.5f, 0.5f, 1.5f}, box_h[3] = {0.2f, 0.2f, 0.5f};
    assert_int_equal(cbvh_sweep_box(cx.file, box_c, box_h, down, &h), 1);
    assert_true(h.t == 0.0f && fabs(vec_len(h.normal) - 1) < 1e-4);
    /* approaching from 1 away: contact at t = 0.5 of a delta of 2 */
    float above[3] = {0.5f, 0.5f, 2.25f}, two_down[3] = {0, 0, -2};
    assert_int_equal(cbvh_sweep_sphere(cx.file, above, 0.25f, two_down, &h), 1);
    assert_true(fabs(h.t - 0.5) < 1e-6 && h.normal[2] > 0.999f);
    ref_fixture_close(&cx);
    scene_free(&cube);
    ref_fixture_close(&fx);
    scene_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_watertight),      cmocka_unit_test(test_watertight_dragon),
        cmocka_unit_test(test_scales),          cmocka_unit_test(test_huge_extent),
        cmocka_unit_test(test_sliver_accuracy), cmocka_unit_test(test_degenerate_meshes),
        cmocka_unit_test(test_extreme_rays),    cmocka_unit_test(test_extreme_sweeps),
        cmocka_unit_test(test_exact_range),
    };
    return TEST_RUN_LAYOUTS(tests, 0);
}
