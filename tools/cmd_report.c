/* cmd_report.c: `cbvh report`: every precision and layout choice of the format, error and run time side by
 * side. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench_input.h"
#include "bench_run.h"
#include "cli.h"
#include "commands.h"
#include "json.h"
#include "progress.h"
#include "report.h"
#include "cbvh_internal.h"
#include "support/rays.h"
#include "support/reference.h"

static const char usage[] =
    "Usage: cbvh report [OPTIONS] MESH...\n"
    "\n"
    "For each MESH (a mesh file assimp reads, or gen:SPEC; --gen SPEC adds a generated scene)\n"
    "cooks every precision and layout choice the format offers and measures error and run\n"
    "time side by side:\n"
    "  - node boxes: exact float boxes (an in-memory reference layout of the same tree) against\n"
    "    the file's 16-bit quantized boxes;\n"
    "  - vertices: lossless float against 16-bit quantized;\n"
    "  - sections: raw against zlib-compressed (file size and open time);\n"
    "  - node layouts: wide4 (the default) and binary;\n"
    "  - leaf sizes (most triangles per leaf) 1, 2, 4 and the default (16, which a wide4 leaf\n"
    "    holds as 8); quantized vertices and zlib sections at the default; the binary layout\n"
    "    at leaf sizes 8 and 16;\n"
    "  - traversals, on each layout at the default leaf size: sorted by the precomputed child\n"
    "    order, unsorted, distance-sorted at run time, stackless (binary only), batched streams,\n"
    "    and expanded (sorted, the triangles copied by cbvh_file_expand_triangles: its bytes count).\n"
    "Error columns: box inflation (surface area over the exact box, mean and worst), extra nodes\n"
    "and triangles visited per ray against the exact-float reference, hit/miss flips and wrong\n"
    "triangles against a double-precision brute force on a sample of the rays, distance error\n"
    "(max and RMS of |t - t_ref| over the scene diagonal), vertex error, and rays leaked through\n"
    "shared edges and vertices (rays from inside a closed mesh aimed exactly at its vertices and\n"
    "edge midpoints that miss; closed meshes only). Run time: MRays/s closest and any hit on\n"
    "incoherent rays (one thread; each row timed in turns with the default cook's sorted walk,\n"
    "slice by slice, and given as its speed relative to that walk times the walk's median\n"
    "speed over the mesh's rows, so that a slow spell of a shared machine does not move one row\n"
    "against another), open time, bytes per triangle.\n"
    "A markdown table goes to stdout, with a recommendation per mesh: the fastest configuration\n"
    "that answers exactly like the brute force (the default when within the timing noise), and\n"
    "what smaller files and lossy choices cost.\n"
    "\n"
    "Options:\n"
    "  --gen SPEC      add a generated scene (sphere:N, terrain:N, soup:N, cube, demo)\n"
    "  --rays N        timed incoherent rays per configuration (default 200000)\n"
    "  --sample N      of which the first N are checked by brute force (default 2000)\n"
    "  --seed S        ray generator seed (default 1)\n"
    "  --reps R        timed rounds, the median is reported (default 3)\n"
    "  --out DIR       write report.md, report.json, report.svg, report.html and the cooked files\n"
    "                  into DIR\n"
    "  --cpu-time      time with CPU clocks instead of the wall clock (steadier on a busy machine)\n"
    "  --json FILE     write the figures as JSON to FILE\n"
    "  --svg FILE      write the plots of error against run time to FILE (one SVG picture)\n"
    "  --html FILE     write one self-contained page to FILE: per mesh the recommendation, a plot\n"
    "                  per error measure against run time (point per configuration, Pareto front,\n"
    "                  details on hover or keyboard focus) and the summary table\n"
    "  --quiet         no progress display\n"
    "  -h, --help      show this help\n"
    "\n"
    "Exit status: 0 done, 1 an input is not a usable mesh, 2 usage or I/O error.\n";

enum {
    OPT_GEN = 1,
    OPT_RAYS,
    OPT_SAMPLE,
    OPT_SEED,
    OPT_REPS,
    OPT_CPU,
    OPT_OUT,
    OPT_JSON,
    OPT_SVG,
    OPT_HTML,
    OPT_QUIET
};

static const cli_option options[] = {
    {"gen", CLI_ARG_REQUIRED, OPT_GEN},       {"rays", CLI_ARG_REQUIRED, OPT_RAYS},
    {"sample", CLI_ARG_REQUIRED, OPT_SAMPLE}, {"seed", CLI_ARG_REQUIRED, OPT_SEED},
    {"reps", CLI_ARG_REQUIRED, OPT_REPS},     {"cpu-time", CLI_ARG_NONE, OPT_CPU},
    {"out", CLI_ARG_REQUIRED, OPT_OUT},       {"json", CLI_ARG_REQUIRED, OPT_JSON},
    {"svg", CLI_ARG_REQUIRED, OPT_SVG},       {"html", CLI_ARG_REQUIRED, OPT_HTML},
    {"quiet", CLI_ARG_NONE, OPT_QUIET},       {NULL, 0, 0},
};

/* Vertices and edge midpoints aimed at by the leak test, at most, each. */
#define LEAK_TARGETS 5000

/* The cooks of one mesh: every leaf size with lossless vertices, then at the
 * default leaf size (cbvh_cook_options_init's) quantized vertices, zlib
 * sections (smaller files, a slower open, the same queries) and each other
 * node layout. A new choice of the format is one more line here. */
#define DEFAULT_LEAF_SIZE 0 /* cbvh_cook_options_init's max_leaf_size */
static const struct {
    cbvh_layout layout;
    uint32_t leaf; /* max_leaf_size, or DEFAULT_LEAF_SIZE */
    int quantized_vertices;
    int compress; /* zlib level, 0 for raw sections */
} cook_configs[] = {
    {CBVH_LAYOUT_WIDE4, 1, 0, 0},
    {CBVH_LAYOUT_WIDE4, 2, 0, 0},
    {CBVH_LAYOUT_WIDE4, 4, 0, 0},
    {CBVH_LAYOUT_WIDE4, DEFAULT_LEAF_SIZE, 0, 0},
    {CBVH_LAYOUT_WIDE4, DEFAULT_LEAF_SIZE, 1, 0},
    {CBVH_LAYOUT_WIDE4, DEFAULT_LEAF_SIZE, 0, 6},
    {CBVH_LAYOUT_BINARY, 8, 0, 0},
    {CBVH_LAYOUT_BINARY, DEFAULT_LEAF_SIZE, 0, 0},
};
/* Names of the layouts, by cbvh_layout value (as `cbvh cook --layout` spells them). */
static const char *const layout_names[] = {"binary", "wide4"};
#define COOK_COUNT (sizeof cook_configs / sizeof cook_configs[0])
/* measure() calls a mesh makes at most: each cook's exact reference and its traversals. */
#define REPORT_MAX_MEASURES (COOK_COUNT * (BENCH_CBVH_VARIANTS + 1u))

typedef struct report_state {
    const char *command;
    size_t rays, sample;
    uint64_t seed;
    unsigned reps;
    int cpu_clock;
    const char *out_dir, *json_path, *svg_path, *html_path;
    progress prog;
    report_row *rows;
    size_t row_count, row_capacity;
} report_state;

/* What one mesh's rows are measured with. */
typedef struct mesh_ctx {
    bench_mesh mesh;
    const char *label; /* short name for the plot */
    double diagonal;
    cbvh_ray *rays; /* rays incoherent rays; the first `sample` are checked by brute force */
    cbvh_hit *hits;
    uint8_t *occluded;
    uint32_t *ref_tri; /* brute-force answers for the sample */
    double *ref_t;
    int closed;
    cbvh_ray *leak;
    size_t leak_count;
    /* The default cook's sorted walk, timed in turns with every row (measure): rows are timed as ratios to
     * it, and its median time gives them their MRays/s (report_mesh), so that a slow spell of a shared
     * machine does not move one row against another. */
    cbvh_file *reference;
    bench_cbvh reference_engine;
    double reference_seconds[2][REPORT_MAX_MEASURES]; /* closest, any: each measure's */
    size_t measures;
} mesh_ctx;

/* ------------------------------------------------------------------ */
/* Double-precision brute force                                        */
/* ------------------------------------------------------------------ */

/* The mesh as the reference takes it: every triangle in double, ids = indices. */
static int reference_triangles(const bench_mesh *m, ref_tris *out)
{
    out->count = m->triangle_count;
    out->v = malloc(9 * m->triangle_count * sizeof *out->v);
    out->id = malloc(m->triangle_count * sizeof *out->id);
    if (!out->v || !out->id) {
        ref_tris_free(out);
        return 0;
    }
    for (size_t t = 0; t < m->triangle_count; t++) {
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++)
                out->v[9 * t + 3 * k + a] = m->positions[3 * (size_t)m->indices[3 * t + k] + a];
        out->id[t] = (uint32_t)t;
    }
    return 1;
}

typedef struct brute_engine {
    const ref_tris *tris;
    const cbvh_ray *base; /* the sample: answers go to the same index in ref_tri / ref_t */
    uint32_t *ref_tri;
    double *ref_t;
} brute_engine;

/* A bench_kernel over helper C's double-precision brute force, so it runs on every core. */
static void brute_kernel(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                         uint8_t *occluded, cbvh_query_stats *stats)
{
    const brute_engine *e = engine;
    for (size_t k = 0; k < count; k++) {
        size_t i = (size_t)(&rays[k] - e->base);
        ref_ray_hit hit;
        ref_ray_closest(e->tris, &rays[k], 0.0, &hit);
        e->ref_tri[i] = hit.tri;
        e->ref_t[i] = hit.t;
    }
}

/* ------------------------------------------------------------------ */
/* Closed meshes: rays aimed at shared vertices and edges from inside  */
/* ------------------------------------------------------------------ */

static const float *sort_positions; /* qsort has no user pointer */

static int compare_vertex(const void *a, const void *b)
{
    const float *p = sort_positions + 3 * (size_t) * (const uint32_t *)a,
                *q = sort_positions + 3 * (size_t) * (const uint32_t *)b;
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

static int compare_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Sorted edges (lower vertex id in the high half) of the mesh with equal positions
 * welded, degenerate triangles left out; *closed says whether every edge has
 * exactly two triangles. Returns the unique edges (caller frees) or NULL. */
static uint64_t *closed_edges(const bench_mesh *m, size_t *unique_count, int *closed)
{
    size_t nv = m->vertex_count, nt = m->triangle_count;
    uint32_t *order = malloc(nv * sizeof *order), *canon = malloc(nv * sizeof *canon);
    uint64_t *edges = malloc(3 * nt * sizeof *edges);
    if (!order || !canon || !edges) {
        free(order);
        free(canon);
        free(edges);
        return NULL;
    }
    for (size_t i = 0; i < nv; i++)
        order[i] = (uint32_t)i;
    sort_positions = m->positions;
    qsort(order, nv, sizeof *order, compare_vertex);
    for (size_t i = 0; i < nv; i++)
        canon[order[i]] =
            i > 0 && compare_vertex(&order[i - 1], &order[i]) == 0 ? canon[order[i - 1]] : order[i];
    free(order);
    size_t n = 0;
    for (size_t t = 0; t < nt; t++) {
        uint32_t v[3];
        for (int k = 0; k < 3; k++)
            v[k] = canon[m->indices[3 * t + k]];
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            edges[n++] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        }
    }
    free(canon);
    qsort(edges, n, sizeof *edges, compare_u64);
    size_t u = 0;
    *closed = n > 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && edges[j] == edges[i])
            j++;
        if (j - i != 2)
            *closed = 0;
        edges[u++] = edges[i];
        i = j;
    }
    *unique_count = u;
    return edges;
}

/* A point inside a closed mesh: halfway between where a ray from outside
 * first enters the mesh and where it next crosses the surface. */
static int interior_point(const ref_tris *tris, const float lo[3], const float hi[3], double diagonal,
                          float out[3])
{
    static const double tries[][3] = {{0.5773, 0.5774, 0.5773},  {-0.2673, 0.5345, 0.8018},
                                      {0.8729, -0.2182, 0.4364}, {-0.4082, -0.4082, 0.8165},
                                      {0.1, 0.98, -0.17},        {-0.9, 0.3, -0.316}};
    for (size_t k = 0; k < sizeof tries / sizeof tries[0]; k++) {
        double n = sqrt(tries[k][0] * tries[k][0] + tries[k][1] * tries[k][1] + tries[k][2] * tries[k][2]);
        cbvh_ray r;
        for (int a = 0; a < 3; a++) {
            r.dir[a] = (float)(tries[k][a] / n);
            r.org[a] = (float)(0.5 * ((double)lo[a] + hi[a]) - r.dir[a] * diagonal);
        }
        r.tmin = 0.0f;
        r.tmax = (float)(4.0 * diagonal);
        ref_ray_hit first, next;
        if (!ref_ray_closest(tris, &r, 0.0, &first))
            continue;
        r.tmin = (float)(first.t + 1e-7 * diagonal);
        if (!ref_ray_closest(tris, &r, 0.0, &next) || next.t - first.t < 1e-4 * diagonal)
            continue;
        for (int a = 0; a < 3; a++)
            out[a] = (float)(r.org[a] + 0.5 * (first.t + next.t) * r.dir[a]);
        return 1;
    }
    return 0;
}

static void leak_ray(cbvh_ray *r, const float from[3], const float to[3])
{
    for (int a = 0; a < 3; a++) {
        r->org[a] = from[a];
        r->dir[a] = to[a] - from[a];
    }
    r->tmin = 0.0f;
    r->tmax = INFINITY;
}

/* Rays from inside a closed mesh at its vertices and edge midpoints: every one must hit. */
static int make_leak_rays(mesh_ctx *c, const ref_tris *tris, const float lo[3], const float hi[3])
{
    size_t edge_count;
    uint64_t *edges = closed_edges(&c->mesh, &edge_count, &c->closed);
    if (!edges)
        return 0;
    float inside[3];
    if (!c->closed || !interior_point(tris, lo, hi, c->diagonal, inside)) {
        c->closed = 0;
        free(edges);
        return 1;
    }
    size_t nv = edge_count < LEAK_TARGETS ? edge_count : LEAK_TARGETS;
    c->leak = malloc(2 * nv * sizeof *c->leak);
    if (!c->leak) {
        free(edges);
        return 0;
    }
    size_t n = 0;
    for (size_t k = 0; k < nv; k++) {
        uint64_t e = edges[k * edge_count / nv];
        const float *a = c->mesh.positions + 3 * (size_t)(e >> 32),
                    *b = c->mesh.positions + 3 * (size_t)(uint32_t)e;
        float mid[3];
        for (int i = 0; i < 3; i++)
            mid[i] = a[i] + (b[i] - a[i]) * 0.5f;
        leak_ray(&c->leak[n++], inside, a); /* a vertex (each edge's lower end: spread over the mesh) */
        leak_ray(&c->leak[n++], inside, mid);
    }
    c->leak_count = n;
    free(edges);
    return 1;
}

/* ------------------------------------------------------------------ */
/* Measuring one configuration                                         */
/* ------------------------------------------------------------------ */

/* The exact-float reference layout as a bench engine. */
static void exact_kernel(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                         uint8_t *occluded, cbvh_query_stats *stats)
{
    if (hits)
        for (size_t i = 0; i < count; i++)
            cbvh_exact_raycast(engine, &rays[i], &hits[i], stats);
    else
        for (size_t i = 0; i < count; i++)
            occluded[i] = (uint8_t)cbvh_exact_occluded(engine, &rays[i], stats);
}

/* Counts the work of closest and any hit, compares the answers with the brute force and the leak test, then
 * times both in turns with the mesh's reference (its times go to c->reference_seconds): the row's MRays/s
 * are set as ratios to the reference's, which report_mesh scales. */
static int measure(const report_state *s, mesh_ctx *c, bench_kernel kernel, const void *engine,
                   report_row *row)
{
    bench_job job = {.kernel = kernel,
                     .engine = engine,
                     .rays = c->rays,
                     .count = s->rays,
                     .hits = c->hits,
                     .cpu_clock = s->cpu_clock};
    cbvh_query_stats st = {0, 0};
    if (bench_run_once(&job, 1, &st) < 0.0 || c->measures == REPORT_MAX_MEASURES)
        return 0;
    row->nodes_per_ray = (double)st.nodes_visited / (double)s->rays;
    row->tris_per_ray = (double)st.triangles_tested / (double)s->rays;

    /* The counted pass left its answers in c->hits; the sample is its first rays. */
    double sum2 = 0.0, worst = 0.0;
    uint64_t both = 0;
    row->compared = s->sample;
    for (size_t i = 0; i < s->sample; i++) {
        const cbvh_hit *h = &c->hits[i];
        int hit = h->tri != CBVH_NO_HIT, ref = c->ref_tri[i] != CBVH_NO_HIT;
        if (hit != ref) {
            row->flips++;
            continue;
        }
        if (!hit)
            continue;
        const float *d = c->rays[i].dir;
        double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
        double err = fabs((double)h->t - c->ref_t[i]) * len / c->diagonal;
        if (h->tri != c->ref_tri[i] && err > REPORT_TIE_TOLERANCE)
            row->wrong_triangle++;
        sum2 += err * err;
        worst = fmax(worst, err);
        both++;
    }
    row->t_err_max = worst;
    row->t_err_rms = both ? sqrt(sum2 / (double)both) : 0.0;

    row->leaks = -1;
    if (c->closed) {
        bench_job leak = {
            .kernel = kernel, .engine = engine, .rays = c->leak, .count = c->leak_count, .hits = c->hits};
        bench_run_once(&leak, 1, NULL);
        row->leaks = 0;
        for (size_t i = 0; i < c->leak_count; i++)
            row->leaks += c->hits[i].tri == CBVH_NO_HIT;
        row->leak_rays = c->leak_count;
    }

    /* closest, then any hit, in turns with the reference (answers no longer read) */
    bench_job ref = job;
    ref.kernel = bench_cbvh_kernel;
    ref.engine = &c->reference_engine;
    double *mrays[2] = {&row->closest_mrays, &row->any_mrays};
    for (int any = 0; any < 2; any++) {
        if (any) {
            job.hits = ref.hits = NULL;
            job.occluded = ref.occluded = c->occluded;
        }
        const bench_job *pair[2] = {&job, &ref};
        double seconds[2];
        unsigned runs[2];
        if (bench_time_in_turns(pair, 2, 1, s->reps, 0.0, seconds, runs) < 0)
            return 0;
        *mrays[any] = seconds[1] / seconds[0]; /* scaled by report_mesh */
        c->reference_seconds[any][c->measures] = seconds[1];
    }
    c->measures++;
    return 1;
}

static report_row *new_row(report_state *s)
{
    if (s->row_count == s->row_capacity) {
        size_t cap = s->row_capacity ? 2 * s->row_capacity : 32;
        report_row *rows = realloc(s->rows, cap * sizeof *rows);
        if (!rows)
            return NULL;
        s->rows = rows;
        s->row_capacity = cap;
    }
    report_row *r = &s->rows[s->row_count++];
    memset(r, 0, sizeof *r);
    return r;
}

/* The largest leaf cook k allows: its max_leaf_size, which a wide4 leaf caps at CBVH_WIDE4_MAX_LEAF. */
static uint32_t leaf_size(size_t k)
{
    cbvh_cook_options defaults;
    cbvh_cook_options_init(&defaults, sizeof defaults);
    uint32_t leaf = cook_configs[k].leaf == DEFAULT_LEAF_SIZE ? defaults.max_leaf_size : cook_configs[k].leaf;
    return cook_configs[k].layout == CBVH_LAYOUT_WIDE4 && leaf > CBVH_WIDE4_MAX_LEAF ? CBVH_WIDE4_MAX_LEAF
                                                                                     : leaf;
}

/* A file name for the cooked file of a configuration: the mesh's base name without odd characters. */
static void cooked_path(const report_state *s, const mesh_ctx *c, size_t k, char *path, size_t size)
{
    const char *base = strrchr(c->mesh.name, '/');
    base = base ? base + 1 : c->mesh.name;
    char clean[96];
    size_t n = 0;
    for (; *base && n + 1 < sizeof clean; base++)
        clean[n++] = (isalnum((unsigned char)*base) || *base == '_' || *base == '-') ? *base : '_';
    clean[n] = '\0';
    snprintf(path, size, "%s/%s-%s-leaf%u%s%s.cbvh", s->out_dir, clean, layout_names[cook_configs[k].layout],
             (unsigned)leaf_size(k), cook_configs[k].quantized_vertices ? "-qverts" : "",
             cook_configs[k].compress ? "-zlib" : "");
}

/* Each dimension's value and the configuration's name, from the row's choices. */
static void describe_row(report_row *row, const char *layout)
{
    snprintf(row->value[REPORT_DIM_LAYOUT], sizeof row->value[0], "%s layout", layout);
    snprintf(row->value[REPORT_DIM_BOXES], sizeof row->value[0], "%s boxes",
             row->float_boxes ? "float" : "q16");
    snprintf(row->value[REPORT_DIM_VERTICES], sizeof row->value[0], "%s vertices",
             row->quantized_vertices ? "q16" : "float");
    snprintf(row->value[REPORT_DIM_LEAF], sizeof row->value[0], "leaf %u", (unsigned)row->leaf);
    snprintf(row->value[REPORT_DIM_TRAVERSAL], sizeof row->value[0], "%s", row->traversal);
    if (row->compress)
        snprintf(row->value[REPORT_DIM_SECTIONS], sizeof row->value[0], "zlib %d", row->compress);
    else
        snprintf(row->value[REPORT_DIM_SECTIONS], sizeof row->value[0], "raw sections");
    size_t n = 0;
    for (int d = 0; d < REPORT_DIM_COUNT; d++)
        n += (size_t)snprintf(row->config + n, n < sizeof row->config ? sizeof row->config - n : 0, "%s%s",
                              d ? ", " : "", row->value[d]);
}

/* Cooks the mesh with `opt` into `path`: when `keep`, the file path names (the output folder's), else a
 * temporary file whose name goes to path (the caller unlinks it). *stats receives the cook's. Returns 0, or
 * the exit status (reported). */
static int cook_into(const report_state *s, const mesh_ctx *c, const cbvh_cook_options *opt, int keep,
                     char *path, size_t size, cbvh_cook_stats *stats)
{
    cbvh_mesh view = bench_mesh_view(&c->mesh);
    cbvh_cook_stats_init(stats, sizeof *stats);
    cbvh_error err;
    if (keep)
        return cbvh_cook_to_path(&view, opt, NULL, path, stats, &err) == CBVH_OK
                   ? 0
                   : cli_report(s->command, path, &err);
    void *data = NULL;
    size_t bytes = 0;
    int status;
    if (cbvh_cook(&view, opt, NULL, &data, &bytes, stats, &err) != CBVH_OK)
        status = cli_report(s->command, c->mesh.name, &err);
    else
        status = bench_write_temp(s->command, data, bytes, path, size);
    cbvh_buffer_free(NULL, data);
    return status;
}

static int measure_cook(report_state *s, mesh_ctx *c, size_t k, int *step, int steps)
{
    uint32_t leaf = leaf_size(k);
    int qverts = cook_configs[k].quantized_vertices, compress = cook_configs[k].compress;
    cbvh_cook_options opt;
    cbvh_cook_options_init(&opt, sizeof opt);
    int is_default = cook_configs[k].leaf == DEFAULT_LEAF_SIZE && !qverts && !compress &&
                     cook_configs[k].layout == opt.layout;
    char label[128];
    snprintf(label, sizeof label, "%s: cook %s leaf %u%s%s", c->label, layout_names[cook_configs[k].layout],
             (unsigned)leaf, qverts ? ", quantized vertices" : "", compress ? ", zlib" : "");
    progress_update(&s->prog, label, (double)(*step)++ / steps);

    opt.layout = cook_configs[k].layout;
    opt.max_leaf_size = leaf;
    opt.vertex_format = qverts ? CBVH_VERTEX_QUANTIZED16 : CBVH_VERTEX_FLOAT32;
    opt.compress_level = compress;
    cbvh_cook_stats stats;
    char path[1024];
    if (s->out_dir)
        cooked_path(s, c, k, path, sizeof path);
    int status = cook_into(s, c, &opt, s->out_dir != NULL, path, sizeof path, &stats);
    if (status) {
        progress_done(&s->prog);
        return status;
    }
    uint64_t size = stats.file_size;
    cbvh_file *file = NULL;
    double open_seconds = bench_open_median(s->command, path, s->reps, s->cpu_clock, &file, &status);
    /* the expanded variant's file: opened again, then cbvh_file_expand_triangles */
    cbvh_file *expanded = NULL;
    double expand_seconds = 0.0;
    if (!status)
        expand_seconds = bench_open_expanded(s->command, path, s->cpu_clock, &expanded, &status);
    if (!s->out_dir)
        bench_remove_temp(path);
    if (status) {
        cbvh_close(file);
        return status;
    }

    cbvh_exact_tree exact = {0};
    cbvh_tree_stats ts;
    if (!cbvh_exact_tree_build(&exact, file) || !cbvh_tree_stats_compute(file, 1.0, 1.0, &ts)) {
        cbvh_exact_tree_free(&exact);
        cbvh_close(file);
        cbvh_close(expanded);
        cli_error(s->command, NULL, "out of memory");
        return CLI_EXIT_USAGE;
    }
    /* The exact-float reference of this very tree: the baseline of the extra work columns. */
    report_row base;
    memset(&base, 0, sizeof base);
    status = CLI_EXIT_USAGE;
    if (!measure(s, c, exact_kernel, &exact, &base))
        goto done;
    /* One row per traversal for each layout's cook at the default leaf size (but the stackless walk,
     * which only the binary layout has), the sorted traversal for the others, and the reference
     * layout itself for the default cook. */
    const int every_traversal = cook_configs[k].leaf == DEFAULT_LEAF_SIZE && !qverts && !compress;
    int variants = every_traversal ? BENCH_CBVH_VARIANTS : 1;
    for (int v = -1; v < variants; v++) {
        if (v < 0 && !is_default)
            continue;
        bench_cbvh engine;
        if (v >= 0) {
            bench_cbvh_variant(&engine, file, expanded, v);
            if (engine.traversal == CBVH_TRAVERSAL_STACKLESS && cook_configs[k].layout != CBVH_LAYOUT_BINARY)
                continue;
        }
        report_row *row = new_row(s);
        if (!row)
            goto done;
        if (v >= 0) {
            if (v > 0)
                (*step)++;
            snprintf(label, sizeof label, "%s: leaf %u%s, %s", c->label, (unsigned)leaf,
                     qverts ? " qverts" : "", engine.name);
            progress_update(&s->prog, label, (double)*step / steps);
            if (!measure(s, c, bench_cbvh_kernel, &engine, row))
                goto done;
        } else {
            *row = base;
        }
        row->mesh = c->mesh.name;
        row->triangles = c->mesh.triangle_count;
        row->leaf = leaf;
        row->quantized_vertices = qverts;
        row->compress = compress;
        row->float_boxes = v < 0;
        row->reference = v < 0;
        row->is_default = is_default && v == 0;
        row->traversal = v < 0 ? "sorted" : engine.name;
        describe_row(row, layout_names[cook_configs[k].layout]);
        const int is_expanded = v >= 0 && engine.file == expanded;
        cbvh_file_info xinfo;
        cbvh_file_get_info(expanded, &xinfo, sizeof xinfo);
        row->bytes_per_triangle =
            (double)(size + (is_expanded ? xinfo.expanded_bytes : 0u)) / (double)c->mesh.triangle_count;
        row->open_seconds = v < 0 ? -1.0 : open_seconds + (is_expanded ? expand_seconds : 0.0);
        row->extra_nodes = row->nodes_per_ray - base.nodes_per_ray;
        row->extra_tris = row->tris_per_ray - base.tris_per_ray;
        row->inflation_mean = v < 0 ? 0.0 : ts.inflation_mean;
        row->inflation_worst = v < 0 ? 0.0 : ts.inflation_max;
        row->vertex_error = stats.vertex_max_error / c->diagonal;
    }
    status = 0;
done:
    if (status)
        cli_error(s->command, NULL, "out of memory or cannot start a thread");
    cbvh_exact_tree_free(&exact);
    cbvh_close(file);
    cbvh_close(expanded);
    return status;
}

static void mesh_ctx_free(mesh_ctx *c)
{
    cbvh_close(c->reference);
    free(c->rays);
    free(c->hits);
    free(c->occluded);
    free(c->ref_tri);
    free(c->ref_t);
    free(c->leak);
    bench_mesh_free(&c->mesh);
}

static int report_mesh(report_state *s, const char *source, int generated)
{
    mesh_ctx c;
    memset(&c, 0, sizeof c);
    int status = bench_mesh_load(s->command, source, generated, &c.mesh);
    if (status)
        return status;
    c.label = strrchr(source, '/') ? strrchr(source, '/') + 1 : source;
    rays_mesh rm = {c.mesh.positions, c.mesh.vertex_count, c.mesh.indices, c.mesh.triangle_count};
    float lo[3], hi[3];
    c.diagonal = rays_mesh_bounds(&rm, lo, hi);
    if (!(c.diagonal > 0.0)) {
        cli_error(s->command, source, "the mesh has no extent");
        mesh_ctx_free(&c);
        return CLI_EXIT_BAD_INPUT;
    }
    c.rays = malloc(s->rays * sizeof *c.rays);
    c.hits = malloc((s->rays > 2 * LEAK_TARGETS ? s->rays : 2 * LEAK_TARGETS) * sizeof *c.hits);
    c.occluded = malloc(s->rays);
    c.ref_tri = malloc(s->sample * sizeof *c.ref_tri);
    c.ref_t = malloc(s->sample * sizeof *c.ref_t);
    if (!c.rays || !c.hits || !c.occluded || !c.ref_tri || !c.ref_t) {
        mesh_ctx_free(&c);
        cli_error(s->command, NULL, "out of memory");
        return CLI_EXIT_USAGE;
    }
    rays_generate(RAYS_INCOHERENT, &rm, s->seed, c.rays, s->rays);

    char label[128];
    snprintf(label, sizeof label, "%s: brute force on %zu rays", c.label, s->sample);
    progress_update(&s->prog, label, -1.0);
    ref_tris tris;
    if (!reference_triangles(&c.mesh, &tris)) {
        mesh_ctx_free(&c);
        cli_error(s->command, NULL, "out of memory");
        return CLI_EXIT_USAGE;
    }
    brute_engine be = {&tris, c.rays, c.ref_tri, c.ref_t};
    bench_job job = {.kernel = brute_kernel, .engine = &be, .rays = c.rays, .count = s->sample};
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int ok = bench_run_once(&job, cores > 0 ? (unsigned)cores : 1u, NULL) >= 0.0 &&
             make_leak_rays(&c, &tris, lo, hi);
    ref_tris_free(&tris);
    if (!ok) {
        progress_done(&s->prog);
        mesh_ctx_free(&c);
        cli_error(s->command, NULL, "out of memory or cannot start a thread");
        return CLI_EXIT_USAGE;
    }
    /* the reference every row is timed beside: the default cook, sorted */
    snprintf(label, sizeof label, "%s: cook the timing reference (the default cook)", c.label);
    progress_update(&s->prog, label, -1.0);
    cbvh_cook_options opt;
    cbvh_cook_options_init(&opt, sizeof opt);
    char path[1024];
    cbvh_cook_stats stats;
    status = cook_into(s, &c, &opt, 0, path, sizeof path, &stats);
    if (!status) {
        status = cli_open(s->command, path, &c.reference);
        bench_remove_temp(path);
    }
    if (!status)
        bench_cbvh_variant(&c.reference_engine, c.reference, c.reference, 0);
    const size_t first_row = s->row_count;
    int step = 0, steps = (int)COOK_COUNT + 2 * (BENCH_CBVH_VARIANTS - 1);
    for (size_t k = 0; k < COOK_COUNT && !status; k++)
        status = measure_cook(s, &c, k, &step, steps);
    progress_done(&s->prog);
    if (!status && c.measures > 0) {
        /* the rows' ratios to the reference, times the reference's median speed */
        const double closest =
            (double)s->rays / bench_median(c.reference_seconds[0], (unsigned)c.measures) * 1e-6;
        const double any =
            (double)s->rays / bench_median(c.reference_seconds[1], (unsigned)c.measures) * 1e-6;
        for (size_t i = first_row; i < s->row_count; i++) {
            s->rows[i].closest_mrays *= closest;
            s->rows[i].any_mrays *= any;
        }
    }
    mesh_ctx_free(&c);
    return status;
}

/* ------------------------------------------------------------------ */
/* Output                                                              */
/* ------------------------------------------------------------------ */

static void print_table(const report_state *s, FILE *out)
{
    fprintf(out, "## cbvh report\n\n");
    fprintf(out,
            "%zu incoherent rays per configuration (one thread, median of %u rounds timed in turns with the "
            "default cook's sorted walk, %s), %zu checked against a double-precision brute force; errors "
            "relative to the scene diagonal.\n\n",
            s->rays, s->reps, s->cpu_clock ? "CPU time" : "wall-clock time", s->sample);
    char cell[256];
    for (int c = 0; c < REPORT_COLUMN_COUNT; c++)
        fprintf(out, "| %s ", report_column_title(c));
    fputs("|\n", out);
    for (int c = 0; c < REPORT_COLUMN_COUNT; c++)
        fputs(c < 2 ? "|---" : "|---:", out);
    fputs("|\n", out);
    for (size_t i = 0; i < s->row_count; i++) {
        for (int c = 0; c < REPORT_COLUMN_COUNT; c++) {
            report_cell(&s->rows[i], c, cell, sizeof cell);
            fprintf(out, "| %s ", cell);
        }
        fputs("|\n", out);
    }
    char advice[2048];
    for (size_t i = 0; i < s->row_count;) {
        size_t n = report_mesh_rows(s->rows + i, s->row_count - i);
        report_recommend(s->rows + i, n, advice, sizeof advice);
        fprintf(out, "\n**%s.** %s\n", s->rows[i].mesh, advice);
        i += n;
    }
}

static int write_json(const report_state *s, const char *path)
{
    FILE *out = fopen(path, "w");
    if (!out) {
        cli_error(s->command, path, "cannot write: %s", strerror(errno));
        return CLI_EXIT_USAGE;
    }
    json_writer w;
    json_init(&w, out);
    json_begin_object(&w, NULL);
    json_string(&w, "command", "report");
    json_uint(&w, "rays", s->rays);
    json_uint(&w, "sample", s->sample);
    json_uint(&w, "seed", s->seed);
    json_uint(&w, "reps", s->reps);
    json_string(&w, "clock", s->cpu_clock ? "cpu" : "wall");
    json_double(&w, "tie_tolerance", REPORT_TIE_TOLERANCE);
    json_begin_array(&w, "rows");
    for (size_t i = 0; i < s->row_count; i++) {
        const report_row *r = &s->rows[i];
        json_begin_object(&w, NULL);
        json_string(&w, "mesh", r->mesh);
        json_string(&w, "configuration", r->config);
        json_bool(&w, "default", r->is_default);
        json_bool(&w, "reference", r->reference);
        json_string(&w, "layout", r->value[REPORT_DIM_LAYOUT]);
        json_uint(&w, "leaf_size", r->leaf);
        json_string(&w, "boxes", r->float_boxes ? "float" : "q16");
        json_string(&w, "vertices", r->quantized_vertices ? "q16" : "float");
        json_string(&w, "traversal", r->traversal);
        json_uint(&w, "zlib_level", (uint64_t)r->compress);
        json_double(&w, "bytes_per_triangle", r->bytes_per_triangle);
        if (r->open_seconds >= 0.0)
            json_double(&w, "open_seconds", r->open_seconds);
        else
            json_null(&w, "open_seconds");
        json_double(&w, "closest_mrays_per_s", r->closest_mrays);
        json_double(&w, "any_mrays_per_s", r->any_mrays);
        json_double(&w, "nodes_per_ray", r->nodes_per_ray);
        json_double(&w, "triangles_per_ray", r->tris_per_ray);
        json_double(&w, "extra_nodes_per_ray", r->extra_nodes);
        json_double(&w, "extra_triangles_per_ray", r->extra_tris);
        json_double(&w, "box_inflation_mean", r->inflation_mean);
        json_double(&w, "box_inflation_worst", r->inflation_worst);
        json_uint(&w, "compared_rays", r->compared);
        json_uint(&w, "hit_flips", r->flips);
        json_uint(&w, "wrong_triangle", r->wrong_triangle);
        json_double(&w, "t_error_max", r->t_err_max);
        json_double(&w, "t_error_rms", r->t_err_rms);
        json_double(&w, "vertex_error", r->vertex_error);
        if (r->leaks >= 0) {
            json_int(&w, "leaked_rays", r->leaks);
            json_uint(&w, "leak_test_rays", r->leak_rays);
        } else {
            json_null(&w, "leaked_rays");
        }
        json_end_object(&w);
    }
    json_end_array(&w);
    json_end_object(&w);
    json_finish(&w);
    if (ferror(out) | fclose(out)) {
        cli_error(s->command, path, "write failed");
        return CLI_EXIT_USAGE;
    }
    return 0;
}

/* Writes one of the pages (report_svg_write, report_html_write) to path. */
static int write_page(const report_state *s, const char *path,
                      int (*writer)(FILE *, const report_row *, size_t, const report_setup *))
{
    report_setup setup = {s->rays, s->sample, s->reps, s->cpu_clock};
    FILE *out = fopen(path, "w");
    if (!out) {
        cli_error(s->command, path, "cannot write: %s", strerror(errno));
        return CLI_EXIT_USAGE;
    }
    if ((writer(out, s->rows, s->row_count, &setup) != 0) | fclose(out)) {
        cli_error(s->command, path, "write failed (or out of memory)");
        return CLI_EXIT_USAGE;
    }
    return 0;
}

static int write_outputs(const report_state *s)
{
    print_table(s, stdout);
    fflush(stdout);
    char path[1024];
    int status = 0;
    if (s->out_dir) {
        snprintf(path, sizeof path, "%s/report.md", s->out_dir);
        FILE *md = fopen(path, "w");
        if (!md) {
            cli_error(s->command, path, "cannot write: %s", strerror(errno));
            return CLI_EXIT_USAGE;
        }
        print_table(s, md);
        if (ferror(md) | fclose(md)) {
            cli_error(s->command, path, "write failed");
            return CLI_EXIT_USAGE;
        }
    }
    const char *json = s->json_path, *svg = s->svg_path, *html = s->html_path;
    char json_default[1024], svg_default[1024], html_default[1024];
    if (s->out_dir && !json) {
        snprintf(json_default, sizeof json_default, "%s/report.json", s->out_dir);
        json = json_default;
    }
    if (s->out_dir && !svg) {
        snprintf(svg_default, sizeof svg_default, "%s/report.svg", s->out_dir);
        svg = svg_default;
    }
    if (s->out_dir && !html) {
        snprintf(html_default, sizeof html_default, "%s/report.html", s->out_dir);
        html = html_default;
    }
    if (json)
        status = write_json(s, json);
    if (!status && svg)
        status = write_page(s, svg, report_svg_write);
    if (!status && html)
        status = write_page(s, html, report_html_write);
    return status;
}

int cmd_report(int argc, char **argv)
{
    report_state s;
    memset(&s, 0, sizeof s);
    s.command = "report";
    s.rays = 200000;
    s.sample = 2000;
    s.seed = 1;
    s.reps = 3;
    int quiet = 0;
    /* Inputs in command-line order; a --gen spec is marked by its option. */
    const char **inputs = calloc((size_t)argc + 1, sizeof *inputs);
    int *generated = calloc((size_t)argc + 1, sizeof *generated);
    int count = 0, status = 0;
    if (!inputs || !generated) {
        free(inputs);
        free(generated);
        cli_error(s.command, NULL, "out of memory");
        return CLI_EXIT_USAGE;
    }
    cli_parser p;
    cli_init(&p, s.command, usage, argc, argv);
    const char *value;
    int id;
    uint32_t u;
    while (!status && (id = cli_next(&p, options, &value)) != CLI_END) {
        switch (id) {
        case CLI_DONE:
            status = -1;
            break;
        case CLI_ERROR:
            status = CLI_EXIT_USAGE;
            break;
        case CLI_POSITIONAL:
        case OPT_GEN:
            generated[count] = id == OPT_GEN;
            inputs[count++] = value;
            break;
        case OPT_RAYS:
            if (!cli_parse_u32(s.command, "rays", value, 1, 100000000u, &u))
                status = CLI_EXIT_USAGE;
            s.rays = u;
            break;
        case OPT_SAMPLE:
            if (!cli_parse_u32(s.command, "sample", value, 1, 10000000u, &u))
                status = CLI_EXIT_USAGE;
            s.sample = u;
            break;
        case OPT_SEED:
            if (!cli_parse_u32(s.command, "seed", value, 0, UINT32_MAX, &u))
                status = CLI_EXIT_USAGE;
            s.seed = u;
            break;
        case OPT_REPS:
            if (!cli_parse_u32(s.command, "reps", value, 1, 1000, &s.reps))
                status = CLI_EXIT_USAGE;
            break;
        case OPT_CPU:
            s.cpu_clock = 1;
            break;
        case OPT_OUT:
            s.out_dir = value;
            break;
        case OPT_JSON:
            s.json_path = value;
            break;
        case OPT_SVG:
            s.svg_path = value;
            break;
        case OPT_HTML:
            s.html_path = value;
            break;
        case OPT_QUIET:
            quiet = 1;
            break;
        }
    }
    if (!status && count == 0)
        status = cli_usage_error(s.command, "no mesh given (give MESH... or --gen SPEC)");
    if (!status && s.sample > s.rays)
        s.sample = s.rays;
    if (!status && s.out_dir && mkdir(s.out_dir, 0777) != 0 && errno != EEXIST) {
        cli_error(s.command, s.out_dir, "cannot create the folder: %s", strerror(errno));
        status = CLI_EXIT_USAGE;
    }
    progress_init(&s.prog, quiet);
    for (int i = 0; i < count && !status; i++)
        status = report_mesh(&s, inputs[i], generated[i]);
    if (!status)
        status = write_outputs(&s);
    free(inputs);
    free(generated);
    free(s.rows);
    return status < 0 ? CLI_EXIT_OK : status;
}
