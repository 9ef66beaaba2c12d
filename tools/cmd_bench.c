/* cmd_bench.c: `cbvh bench`: cbvh's cook, open and query speed beside Embree, Bullet, tinybvh and Jolt on the
 * same rays and shapes. */
#include "config.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_input.h"
#include "bench_judge.h"
#include "bench_run.h"
#include "cbvh_internal.h"
#include "cli.h"
#include "commands.h"
#include "json.h"
#include "peers/peers.h"
#include "progress.h"
#include "support/rays.h"
#include "support/shapes.h"

static const char usage[] =
    "Usage: cbvh bench [OPTIONS] INPUT\n"
    "       cbvh bench [OPTIONS] --gen SPEC\n"
    "\n"
    "Measures cbvh on INPUT: a mesh file assimp reads (cooked on the fly with the default\n"
    "options), a cooked .cbvh file, or a generated scene (--gen sphere:N, terrain:N, soup:N,\n"
    "cube, demo; or INPUT = gen:SPEC). Reports cook time and rate, open time, file bytes per\n"
    "triangle, and MRays/s for closest and any hit on four ray sets (incoherent, coherent\n"
    "camera tiles, shadow rays, short rays: 1% of the diagonal long from just off the surface,\n"
    "as games cast) for every traversal (sorted, unsorted, stackless, distance, batched stream\n"
    "in batches of 1024, and expanded: sorted on the file with cbvh_file_expand_triangles's\n"
    "copy), each the median of the repetitions, with nodes and triangles visited\n"
    "per ray from a separate counted pass. The engines of a row group (a ray set, query and\n"
    "thread count; a shape set and thread count) are timed in turns: each round cuts every\n"
    "engine's queries into the same number of slices (up to 16, of at least 1024 queries) and\n"
    "runs the engines in turn slice by slice, each after reading 64 MiB of other memory (the\n"
    "caches then hold no engine's structure, whichever ran before), first on another slice\n"
    "untimed (its own structure back in the caches), then on its timed slice, a few\n"
    "milliseconds each (on more than one thread, whole sets in turns), so a slow spell of a\n"
    "shared machine moves them all and their ratios hold. The peers\n"
    "found at configure time (Embree 3 single rays and 16-ray packets, default and robust;\n"
    "Bullet 3 quantized BVH; tinybvh's BVH8_CPU and BVH4_CPU single rays, built with BuildHQ,\n"
    "with configure --with-tinybvh=DIR, on CPUs with AVX2 and FMA; Jolt Physics's MeshShape, with\n"
    "configure --with-jolt=PREFIX) run on the same triangles\n"
    "and rays: build time, memory per triangle, MRays/s, the ratio cbvh/peer, and ray-by-ray\n"
    "agreement with cbvh's answers (disagreements decided against the reference, as below).\n"
    "A peer the build or the CPU lacks gets one line saying so.\n"
    "Then shape queries as games ask them near a surface (shapes about 1% of the diagonal\n"
    "across, capsules along random directions): sphere, capsule, box and oriented box (turned\n"
    "by a uniform rotation) sweeps moving 1.5% of the diagonal, and sphere, capsule and box\n"
    "overlaps, every triangle with its contact (cbvh_contacts_*: depth, normal and point, as\n"
    "the peers' narrow phases compute them) and the first hit (whether the shape touches any:\n"
    "each engine stops at the first triangle; Bullet cannot), beside Bullet (convex casts and its\n"
    "per-triangle narrow phase, margins 0 on boxes and triangles) and Jolt (CastShape and\n"
    "CollideShape, back faces colliding, boxes of convex radius 0): microseconds per query,\n"
    "queries per second, the ratio cbvh/peer, and agreement query by query (the same first\n"
    "triangle or t within 1e-4 of the diagonal for sweeps, the same triangle set for\n"
    "overlaps). Up to 200 disagreements per set (fewer once checking them took the budget)\n"
    "are decided against a double-precision brute force, which sides with cbvh, with the peer,\n"
    "with both or with neither (within 1e-5 of the diagonal).\n"
    "The cooked file is read as a game loading it from disk reads it: its pages are dropped\n"
    "from the system's cache before the first open (where the system has posix_fadvise), so\n"
    "its mapping gets 2 MiB pages where the kernel gives them (cbvh_open_path).\n"
    "Markdown tables go to stdout, progress to stderr (on a terminal).\n"
    "\n"
    "Options:\n"
    "  --gen SPEC      benchmark a generated scene instead of INPUT\n"
    "  --rays N        rays per ray set (default 1000000)\n"
    "  --shapes N      queries per shape set (default 100000; 0: no shape queries)\n"
    "  --seed S        ray and shape generator seed (default 1)\n"
    "  --threads LIST  thread counts, comma-separated (default 1,2): every figure at the first,\n"
    "                  cbvh sorted, each peer's main variant and the shape queries at every\n"
    "                  count, the queries split in contiguous slices; Embree builds with the\n"
    "                  largest\n"
    "  --reps R        timed repetitions per figure, the median is reported (default 5)\n"
    "  --budget S      stop repeating a figure once its runs took S seconds in all (default 2;\n"
    "                  0: never), so the slowest peer does not dominate the run time; also\n"
    "                  ends the checks of a shape set's disagreements\n"
    "  --cpu-time      time with CPU clocks instead of the wall clock (the slowest thread's CPU\n"
    "                  time for queries, the process's CPU time for cook, build and open): steadier\n"
    "                  on a machine busy with other work\n"
    "  --json FILE     also write every figure as JSON to FILE\n"
    "  --no-peers      measure cbvh only (and the baseline, when given)\n"
    "  --baseline LIB  also time LIB, another build of libcbvh (its libcbvh.so: a checkout of an\n"
    "                  earlier commit, or other configure options), on the same cooked file and\n"
    "                  rays, in turns with this build: rows 'baseline sorted' and 'baseline\n"
    "                  stream', whose ratios are this build's speed over the other's; a library\n"
    "                  that cannot be loaded or refuses the file is an error (exit status 2)\n"
    "  --quiet         no progress display\n"
    "  -h, --help      show this help\n"
    "\n"
    "Exit status: 0 done, 1 the input is not a usable mesh or cbvh file, 2 usage or I/O error.\n";

enum {
    OPT_GEN = 1,
    OPT_RAYS,
    OPT_SHAPES,
    OPT_SEED,
    OPT_THREADS,
    OPT_REPS,
    OPT_BUDGET,
    OPT_CPU,
    OPT_JSON,
    OPT_NO_PEERS,
    OPT_BASELINE,
    OPT_QUIET
};

static const cli_option options[] = {
    {"gen", CLI_ARG_REQUIRED, OPT_GEN},
    {"rays", CLI_ARG_REQUIRED, OPT_RAYS},
    {"seed", CLI_ARG_REQUIRED, OPT_SEED},
    {"threads", CLI_ARG_REQUIRED, OPT_THREADS},
    {"reps", CLI_ARG_REQUIRED, OPT_REPS},
    {"budget", CLI_ARG_REQUIRED, OPT_BUDGET},
    {"cpu-time", CLI_ARG_NONE, OPT_CPU},
    {"json", CLI_ARG_REQUIRED, OPT_JSON},
    {"no-peers", CLI_ARG_NONE, OPT_NO_PEERS},
    {"quiet", CLI_ARG_NONE, OPT_QUIET},
    {"shapes", CLI_ARG_REQUIRED, OPT_SHAPES},
    {"baseline", CLI_ARG_REQUIRED, OPT_BASELINE},
    {NULL, 0, 0},
};

/* Rays or shape queries a peer runs first, to see whether all fit in the time budget; a shape query takes
 * a peer tens of microseconds on a large mesh, so fewer of them tell as much. */
#define BENCH_PROBE_QUERIES 65536
#define BENCH_PROBE_SHAPES 4096

/* Ray answers compared with a tolerance of this fraction of the scene diagonal. */
#define AGREE_TOLERANCE 1e-5
/* Sweeps agree on the same first triangle, or on t within this fraction of the diagonal (t times the length
 * of the motion) when the triangles differ (a shared edge or vertex). t alone would not do: Bullet's
 * conservative advancement stops once the gap is below 0.001 in the mesh's units (a constant in
 * btContinuousConvexCollision), so its t comes early by that much over the cosine of the approach angle, on
 * every mesh, whatever its scale; the table shows how far the t of the same triangle lie apart. */
#define SWEEP_AGREE_TOLERANCE 1e-4

/* Shape disagreements a set has checked against the double-precision reference, at most (each check is a
 * brute force over every triangle; the budget also ends the checks). Overlaps are judged with the ray
 * tolerance (a triangle within it of the region's boundary may be reported or not), sweeps by the sweep
 * agreement rule. */
#define BENCH_JUDGE_QUERIES 200

#define MAX_THREAD_COUNTS 8

/* ------------------------------------------------------------------ */
/* Engines: each runs a slice of rays for bench_run.                   */
/* ------------------------------------------------------------------ */

/* A peer's slice of rays: closest hits into hits, or any hits into occluded (hits NULL). */
#define PEER_RAY_KERNEL(name, raycast, occluded_fn)                                                          \
    static void name(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits,                 \
                     uint8_t *occluded, cbvh_query_stats *stats)                                             \
    {                                                                                                        \
        (void)stats;                                                                                         \
        if (hits)                                                                                            \
            raycast(engine, rays, count, hits);                                                              \
        else                                                                                                 \
            occluded_fn(engine, rays, count, occluded);                                                      \
    }
#ifdef HAVE_EMBREE
PEER_RAY_KERNEL(embree_kernel, embree_peer_raycast, embree_peer_occluded)
PEER_RAY_KERNEL(embree16_kernel, embree_peer_raycast16, embree_peer_occluded16)
#endif
#ifdef HAVE_TINYBVH
PEER_RAY_KERNEL(tinybvh_kernel, tinybvh_peer_raycast, tinybvh_peer_occluded)
#endif
#ifdef HAVE_BULLET
PEER_RAY_KERNEL(bullet_kernel, bullet_peer_raycast, bullet_peer_occluded)
#endif
#ifdef HAVE_JOLT
PEER_RAY_KERNEL(jolt_kernel, jolt_peer_raycast, jolt_peer_occluded)
#endif
#ifdef HAVE_DLOPEN
PEER_RAY_KERNEL(baseline_kernel, baseline_peer_raycast, baseline_peer_occluded)
PEER_RAY_KERNEL(baseline_stream_kernel, baseline_peer_raycast_stream, baseline_peer_occluded_stream)
#endif
#undef PEER_RAY_KERNEL

/* One way to answer the queries: a cbvh traversal or a peer configuration. */
typedef struct method {
    const char *engine;  /* "cbvh", "embree", "embree-robust", "bullet", "tinybvh-bvh8", "tinybvh-bvh4",
                          * "jolt", "baseline" */
    const char *variant; /* "sorted", "stream", "single", "packet16", "quantized" ... */
    bench_kernel kernel;
    const void *state;
    int counted; /* cbvh: nodes and triangles per ray are measured */
    int main;    /* measured at every thread count, not only the first */
} method;

/* What a shape set asks: a sweep's first contact, every triangle an overlap touches, or an overlap's first
 * hit (whether the shape touches any triangle: the engine stops at the first it finds). */
typedef enum shape_question { SHAPE_SWEEP, SHAPE_OVERLAP, SHAPE_FIRST_HIT } shape_question;
#define SHAPE_QUESTION_COUNT 3
static const char *const shape_question_names[SHAPE_QUESTION_COUNT] = {"sweep", "overlap", "first-hit"};

/* A shape query engine: answers queries[0..count) of one kind and question. */
typedef void (*shape_kernel)(const void *engine, shape_kind kind, shape_question question,
                             const shape_query *queries, size_t count, shape_answer *out);

/* Marks in j the triangles an engine reports for overlap query q (bench_judge_mark: side 0 for cbvh, 1 for
 * a peer). */
typedef void (*shape_marker)(const void *engine, shape_kind kind, const shape_query *q, bench_judge *j);

typedef struct shape_method {
    const char *engine; /* "cbvh", "bullet", "jolt" */
    shape_kernel kernel;
    shape_marker mark;
    const void *state;
    const char *no_first_hit; /* why it answers no first-hit overlaps (its rows left out), or NULL */
} shape_method;

/* A slice of shape queries for bench_run's threads. */
typedef struct shape_job {
    const shape_method *m;
    shape_kind kind;
    shape_question question;
    const shape_query *queries;
    shape_answer *answers;
} shape_job;

/* ------------------------------------------------------------------ */
/* Shape engines                                                       */
/* ------------------------------------------------------------------ */

/* cbvh's overlap query q, its triangles passed to callback(user, tri). */
static void cbvh_overlap_each(const cbvh_file *f, shape_kind kind, const shape_query *q,
                              cbvh_overlap_fn callback, void *user)
{
    if (kind == SHAPE_BOX) {
        float lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = q->p0[k] - q->size[k];
            hi[k] = q->p0[k] + q->size[k];
        }
        cbvh_overlap_box(f, lo, hi, callback, user, NULL, 0);
    } else if (kind == SHAPE_SPHERE) {
        cbvh_overlap_sphere(f, q->p0, q->size[0], callback, user, NULL, 0);
    } else {
        cbvh_overlap_capsule(f, q->p0, q->p1, q->size[0], callback, user, NULL, 0);
    }
}

/* The page of contacts cbvh_contacts_each reads at a time. */
#define BENCH_CONTACT_PAGE 256

/* cbvh's contacts (depth, normal and point, what the peers' narrow phases compute too) with every triangle
 * query q overlaps, read a page at a time: each contact's triangle is added to the answer a. */
static void cbvh_contacts_each(const cbvh_file *f, shape_kind kind, const shape_query *q, shape_answer *a)
{
    cbvh_contact page[BENCH_CONTACT_PAGE];
    cbvh_shape box;
    if (kind == SHAPE_BOX) {
        memset(&box, 0, sizeof box);
        box.kind = CBVH_SHAPE_BOX;
        memcpy(box.center, q->p0, sizeof box.center);
        memcpy(box.half_extent, q->size, sizeof box.half_extent);
        box.rotation[3] = 1.0f;
    }
    size_t first = 0;
    int more = 1;
    while (more) {
        size_t n = 0;
        if (kind == SHAPE_SPHERE)
            n = cbvh_contacts_sphere(f, q->p0, q->size[0], first, page, BENCH_CONTACT_PAGE, &more);
        else if (kind == SHAPE_CAPSULE)
            n = cbvh_contacts_capsule(f, q->p0, q->p1, q->size[0], first, page, BENCH_CONTACT_PAGE, &more);
        else if (cbvh_contacts_with(f, &box, NULL, first, page, BENCH_CONTACT_PAGE, &n, &more) != CBVH_OK)
            more = 0;
        for (size_t i = 0; i < n; i++)
            shape_answer_add(a, page[i].tri);
        first += n;
    }
}

/* Keeps the first triangle an overlap reports and stops the query. */
static int first_overlap(void *user, uint32_t tri)
{
    shape_answer *a = user;
    a->tri = tri;
    a->count = 1;
    return 1;
}

/* cbvh's answer to one shape query; the engine is the opened file. */
static void cbvh_shape_query(const cbvh_file *f, shape_kind kind, shape_question question,
                             const shape_query *q, shape_answer *a)
{
    memset(a, 0, sizeof *a);
    a->tri = CBVH_NO_HIT;
    a->t = INFINITY;
    const int sweep = question == SHAPE_SWEEP;
    if (sweep && kind == SHAPE_ORIENTED_BOX) {
        cbvh_shape box;
        memset(&box, 0, sizeof box);
        box.kind = CBVH_SHAPE_BOX;
        memcpy(box.center, q->p0, sizeof box.center);
        memcpy(box.half_extent, q->size, sizeof box.half_extent);
        memcpy(box.rotation, q->rotation, sizeof box.rotation);
        cbvh_sweep_record record;
        if (cbvh_sweep_with(f, &box, q->delta, NULL, &record) == CBVH_OK && record.tri != CBVH_NO_HIT) {
            a->tri = record.tri;
            a->t = record.t;
        }
    } else if (sweep) {
        cbvh_sweep_hit h;
        int hit = kind == SHAPE_SPHERE ? cbvh_sweep_sphere(f, q->p0, q->size[0], q->delta, &h)
                  : kind == SHAPE_BOX  ? cbvh_sweep_box(f, q->p0, q->size, q->delta, &h)
                                       : cbvh_sweep_capsule(f, q->p0, q->p1, q->size[0], q->delta, &h);
        if (hit) {
            a->tri = h.tri;
            a->t = h.t;
        }
    } else if (question == SHAPE_OVERLAP) {
        cbvh_contacts_each(f, kind, q, a);
    } else {
        cbvh_overlap_each(f, kind, q, first_overlap, a);
    }
}

static int mark_cbvh(void *judge, uint32_t tri)
{
    bench_judge_mark(judge, 0, tri);
    return 0;
}

static void cbvh_shape_mark(const void *engine, shape_kind kind, const shape_query *q, bench_judge *j)
{
    cbvh_overlap_each(engine, kind, q, mark_cbvh, j);
}

static void cbvh_shape_kernel(const void *engine, shape_kind kind, shape_question question,
                              const shape_query *queries, size_t count, shape_answer *out)
{
    for (size_t i = 0; i < count; i++)
        cbvh_shape_query(engine, kind, question, &queries[i], &out[i]);
}

#if defined(HAVE_BULLET) || defined(HAVE_JOLT)
static void mark_peer(void *judge, uint32_t tri)
{
    bench_judge_mark(judge, 1, tri);
}
#endif

#ifdef HAVE_JOLT
static void jolt_shape_kernel(const void *engine, shape_kind kind, shape_question question,
                              const shape_query *queries, size_t count, shape_answer *out)
{
    if (question == SHAPE_SWEEP)
        jolt_peer_sweep(engine, kind, queries, count, out);
    else if (question == SHAPE_OVERLAP)
        jolt_peer_overlap(engine, kind, queries, count, out);
    else
        jolt_peer_overlap_first(engine, kind, queries, count, out);
}

static void jolt_shape_mark(const void *engine, shape_kind kind, const shape_query *q, bench_judge *j)
{
    jolt_peer_overlap_each(engine, kind, q, mark_peer, j);
}
#endif

#ifdef HAVE_BULLET
static void bullet_shape_kernel(const void *engine, shape_kind kind, shape_question question,
                                const shape_query *queries, size_t count, shape_answer *out)
{
    if (question == SHAPE_SWEEP)
        bullet_peer_sweep(engine, kind, queries, count, out);
    else
        bullet_peer_overlap(engine, kind, queries, count, out);
}

static void bullet_shape_mark(const void *engine, shape_kind kind, const shape_query *q, bench_judge *j)
{
    bullet_peer_overlap_each(engine, kind, q, mark_peer, j);
}
#endif

/* A bench_range_fn over a shape_job. */
static void shape_range(const void *job, size_t begin, size_t end, cbvh_query_stats *stats)
{
    const shape_job *j = job;
    (void)stats;
    j->m->kernel(j->m->state, j->kind, j->question, j->queries + begin, end - begin, j->answers + begin);
}

/* A built engine's cost. */
typedef struct build_row {
    const char *engine;
    double seconds;      /* cook or build */
    double open_seconds; /* cbvh only, else negative */
    uint64_t bytes;      /* file size, or acceleration structure + shared mesh arrays */
    uint64_t structure_bytes;
    uint64_t traversed_bytes;   /* tinybvh: the blocks its queries read; else 0 */
    uint64_t dropped_triangles; /* Jolt: the triangles it left out of its shape; else 0 */
    uint64_t id_bytes;          /* Jolt: the part of bytes holding each triangle's index; else 0 */
} build_row;

typedef struct result_row {
    ray_kind set;
    int any;
    const method *m;
    unsigned threads;
    double seconds;
    size_t count; /* rays timed: all, or a prefix for an engine too slow for the budget */
    unsigned runs;
    cbvh_query_stats stats;
} result_row;

typedef struct agree_row {
    ray_kind set;
    const method *m;
    bench_agreement closest;
    uint64_t any_disagree;
    size_t closest_count, any_count; /* rays compared */
    uint64_t checked[2];  /* [0] closest, [1] any hit: disagreements decided against the reference */
    uint64_t sides[2][4]; /* how many it decided for each bench_side */
} agree_row;

/* A shape set's time with one engine and thread count. */
typedef struct shape_row {
    shape_kind kind;
    shape_question question;
    const shape_method *m;
    unsigned threads;
    double seconds;
    size_t count; /* queries timed */
    unsigned runs;
    uint64_t found; /* over the queries timed: sweeps, first hits: queries that hit; overlaps: triangles */
} shape_row;

/* A peer's answers against cbvh's, query by query. */
typedef struct shape_agree_row {
    shape_kind kind;
    shape_question question;
    const shape_method *m;
    bench_agreement sweeps;                   /* sweeps: t compared as a distance along the motion */
    uint64_t same_set, both_empty, other_set; /* overlaps; first hits: both hit, neither, one */
    uint64_t ref_triangles, other_triangles;  /* overlaps: triangles reported by each; first hits: hits */
    uint64_t ref_start_touching, other_start_touching; /* sweeps: t = 0 answers */
    double t_distance_max; /* sweeps, both hit: the largest |t - t_cbvh| * |delta| */
    double t_distance_sum; /* sweeps, the same triangle: the sum of |t - t_cbvh| * |delta| */
    size_t count;
    uint64_t checked;  /* disagreements decided against the reference (bench_judge.h) */
    uint64_t sides[4]; /* how many it decided for each bench_side */
} shape_agree_row;

#define MAX_METHODS 20
#define MAX_BUILDS 8
#define MAX_SHAPE_METHODS 3

typedef struct bench_state {
    const char *command;
    size_t rays, shapes;
    uint64_t seed;
    unsigned thread_counts[MAX_THREAD_COUNTS];
    int thread_count_n;
    unsigned reps;
    float budget;
    int cpu_clock;
    const char *json_path;
    int no_peers;
    const char *baseline_path; /* --baseline: another build's libcbvh, or NULL */
    progress prog;

    bench_mesh mesh;
    double diagonal;
    cbvh_file *file;
    cbvh_file *expanded; /* the file opened again, its triangles expanded (the "expanded" variant) */
    cbvh_cook_stats cook;
    int cooked;
    char temp_path[512];
    const char *cbvh_path; /* the cooked file the queries run on: INPUT, or temp_path */

    bench_cbvh cbvh_engines[BENCH_CBVH_VARIANTS];
    method methods[MAX_METHODS];
    int method_count;
    build_row builds[MAX_BUILDS];
    int build_count;
    result_row *results;
    int result_count;
    agree_row *agreements;
    int agree_count;
    shape_method shape_methods[MAX_SHAPE_METHODS];
    int shape_method_count;
    shape_row *shape_results;
    int shape_result_count;
    shape_agree_row *shape_agreements;
    int shape_agree_count;
    bench_judge judge;
    int judge_state; /* 0 not read yet, 1 ready, -1 out of memory */
#ifdef HAVE_EMBREE
    embree_peer *embree[2];
#endif
#ifdef HAVE_BULLET
    bullet_peer *bullet;
#endif
#ifdef HAVE_TINYBVH
    tinybvh_peer *tinybvh[2];
    int tinybvh_cpu_lacks; /* the CPU has no AVX2 or FMA: tinybvh not run */
#endif
#ifdef HAVE_JOLT
    jolt_peer *jolt;
    int jolt_cpu_lacks; /* Jolt was built for AVX2 and FMA, which the CPU lacks: Jolt not run */
#endif
#ifdef HAVE_DLOPEN
    baseline_peer *baseline;
#endif
} bench_state;

static void add_method(bench_state *s, const char *engine, const char *variant, bench_kernel kernel,
                       const void *state, int counted, int main)
{
    method *m = &s->methods[s->method_count++];
    m->engine = engine;
    m->variant = variant;
    m->kernel = kernel;
    m->state = state;
    m->counted = counted;
    m->main = main;
}

static void add_shape_method(bench_state *s, const char *engine, shape_kernel kernel, shape_marker mark,
                             const void *state, const char *no_first_hit)
{
    shape_method *m = &s->shape_methods[s->shape_method_count++];
    m->engine = engine;
    m->kernel = kernel;
    m->mark = mark;
    m->state = state;
    m->no_first_hit = no_first_hit;
}

/* The largest thread count asked for. */
static unsigned max_threads(const bench_state *s)
{
    unsigned n = 1;
    for (int i = 0; i < s->thread_count_n; i++)
        n = s->thread_counts[i] > n ? s->thread_counts[i] : n;
    return n;
}

/* ------------------------------------------------------------------ */
/* Cook, open, peers                                                   */
/* ------------------------------------------------------------------ */

static int prepare_cbvh(bench_state *s)
{
    const char *path = s->mesh.cbvh_path;
    if (!s->mesh.is_cbvh) {
        cbvh_cook_options opt;
        cbvh_cook_options_init(&opt, sizeof opt);
        opt.progress = progress_cook_callback;
        opt.progress_user = &s->prog;
        cbvh_mesh view = bench_mesh_view(&s->mesh);
        void *data = NULL;
        size_t size = 0;
        cbvh_error err;
        double start = bench_clock(s->cpu_clock);
        cbvh_cook_stats_init(&s->cook, sizeof s->cook);
        cbvh_result r = cbvh_cook(&view, &opt, NULL, &data, &size, &s->cook, &err);
        double seconds = bench_clock(s->cpu_clock) - start;
        progress_done(&s->prog);
        if (r != CBVH_OK)
            return cli_report(s->command, s->mesh.name, &err);
        s->cooked = 1;
        s->builds[0].seconds = seconds;
        int status = bench_write_temp(s->command, data, size, s->temp_path, sizeof s->temp_path);
        cbvh_buffer_free(NULL, data);
        if (status)
            return status;
        path = s->temp_path;
    }
    s->cbvh_path = path;
    /* Open time: the median over the repetitions of opening the file on disk. */
    int status = 0;
    build_row *b = &s->builds[0];
    b->engine = "cbvh";
    b->open_seconds = bench_open_median(s->command, path, s->reps, s->cpu_clock, &s->file, &status);
    if (status)
        return status;
    cbvh_file_info info;
    cbvh_file_get_info(s->file, &info, sizeof info);
    b->bytes = info.file_size;
    b->structure_bytes = info.file_size;
    if (!s->cooked)
        b->seconds = -1.0;
    /* The expanded variant's file: its open time adds the expansion's, its bytes the copy's. */
    build_row *x = &s->builds[1];
    x->engine = "cbvh expanded";
    x->seconds = -1.0;
    const double expand_seconds = bench_open_expanded(s->command, path, s->cpu_clock, &s->expanded, &status);
    x->open_seconds = b->open_seconds + expand_seconds;
    if (status)
        return status;
    cbvh_file_get_info(s->expanded, &info, sizeof info);
    x->bytes = info.file_size + info.expanded_bytes;
    x->structure_bytes = x->bytes;
    s->build_count = 2;
    return 0;
}

static void add_cbvh_methods(bench_state *s)
{
    for (int k = 0; k < BENCH_CBVH_VARIANTS; k++) {
        bench_cbvh *e = &s->cbvh_engines[k];
        bench_cbvh_variant(e, s->file, s->expanded, k);
        add_method(s, "cbvh", e->name, bench_cbvh_kernel, e, 1, k == 0);
    }
    add_shape_method(s, "cbvh", cbvh_shape_kernel, cbvh_shape_mark, s->file, NULL);
}

/* The build row of a peer just built. */
static void add_peer_build(bench_state *s, const char *engine, const peer_build_info *info)
{
    build_row *b = &s->builds[s->build_count++];
    b->engine = engine;
    b->seconds = s->cpu_clock ? info->cpu_seconds : info->seconds;
    b->open_seconds = -1.0;
    b->bytes = info->memory_bytes + info->mesh_bytes;
    b->structure_bytes = info->memory_bytes;
    b->traversed_bytes = info->traversed_bytes;
    b->dropped_triangles = info->dropped_triangles;
    b->id_bytes = info->id_bytes;
}

/* Builds every peer configure found; a peer that fails to build is reported and skipped. */
static void build_peers(bench_state *s)
{
    peer_mesh pm = {s->mesh.positions, s->mesh.vertex_count, s->mesh.indices, s->mesh.triangle_count};
    peer_build_info info;
    char err[256];
    (void)pm;
    (void)info;
    (void)err;
#ifdef HAVE_EMBREE
    static const char *const names[2] = {"embree", "embree-robust"};
    for (int robust = 0; robust < 2; robust++) {
        progress_update(&s->prog, robust ? "building embree (robust)" : "building embree", -1.0);
        memset(&info, 0, sizeof info);
        s->embree[robust] = embree_peer_create(&pm, robust, (int)max_threads(s), &info, err, sizeof err);
        progress_done(&s->prog);
        if (!s->embree[robust]) {
            cli_error(s->command, NULL, "%s", err);
            continue;
        }
        add_peer_build(s, names[robust], &info);
        add_method(s, names[robust], "single", embree_kernel, s->embree[robust], 0, !robust);
        add_method(s, names[robust], "packet16", embree16_kernel, s->embree[robust], 0, 0);
    }
#endif
#ifdef HAVE_TINYBVH
    static const char *const tinybvh_names[2] = {"tinybvh-bvh8", "tinybvh-bvh4"};
    s->tinybvh_cpu_lacks = !cbvh_cpu_has_avx2_fma();
    for (int k = 0; k < 2 && !s->tinybvh_cpu_lacks; k++) {
        progress_update(&s->prog, k ? "building tinybvh BVH4_CPU" : "building tinybvh BVH8_CPU", -1.0);
        memset(&info, 0, sizeof info);
        s->tinybvh[k] =
            tinybvh_peer_create(&pm, k ? TINYBVH_BVH4_CPU : TINYBVH_BVH8_CPU, &info, err, sizeof err);
        progress_done(&s->prog);
        if (!s->tinybvh[k]) {
            cli_error(s->command, NULL, "%s", err);
            continue;
        }
        add_peer_build(s, tinybvh_names[k], &info);
        add_method(s, tinybvh_names[k], "single", tinybvh_kernel, s->tinybvh[k], 0, k == 0);
    }
#endif
#ifdef HAVE_BULLET
    progress_update(&s->prog, "building bullet", -1.0);
    memset(&info, 0, sizeof info);
    s->bullet = bullet_peer_create(&pm, &info, err, sizeof err);
    progress_done(&s->prog);
    if (!s->bullet) {
        cli_error(s->command, NULL, "%s", err);
    } else {
        add_peer_build(s, "bullet", &info);
        add_method(s, "bullet", "quantized", bullet_kernel, s->bullet, 0, 1);
        add_shape_method(s, "bullet", bullet_shape_kernel, bullet_shape_mark, s->bullet,
                         "its processAllTriangles cannot stop at the first triangle");
    }
#endif
#ifdef HAVE_JOLT
#ifdef JOLT_NEEDS_AVX2_FMA
    s->jolt_cpu_lacks = !cbvh_cpu_has_avx2_fma();
#endif
    if (!s->jolt_cpu_lacks) {
        progress_update(&s->prog, "building jolt", -1.0);
        memset(&info, 0, sizeof info);
        s->jolt = jolt_peer_create(&pm, &info, err, sizeof err);
        progress_done(&s->prog);
        if (!s->jolt) {
            cli_error(s->command, NULL, "%s", err);
        } else {
            add_peer_build(s, "jolt", &info);
            add_method(s, "jolt", "meshshape", jolt_kernel, s->jolt, 0, 1);
            add_shape_method(s, "jolt", jolt_shape_kernel, jolt_shape_mark, s->jolt, NULL);
        }
    }
#endif
}

/* The other build of --baseline, on the same cooked file: its sorted single rays and its streams. A library
 * that cannot be loaded or refuses the file is an error the user is told of (it was asked for). */
static int add_baseline(bench_state *s)
{
#ifdef HAVE_DLOPEN
    char err[512];
    s->baseline = baseline_peer_open(s->baseline_path, s->cbvh_path, BENCH_STREAM_BATCH, err, sizeof err);
    if (!s->baseline) {
        cli_error(s->command, NULL, "%s", err);
        return CLI_EXIT_USAGE;
    }
    add_method(s, "baseline", "sorted", baseline_kernel, s->baseline, 0, 1);
    add_method(s, "baseline", "stream", baseline_stream_kernel, s->baseline, 0, 0);
    return 0;
#else
    return cli_usage_error(s->command, "--baseline needs dlopen, which this build of cbvh lacks");
#endif
}

static void destroy_peers(bench_state *s)
{
#ifdef HAVE_EMBREE
    embree_peer_destroy(s->embree[0]);
    embree_peer_destroy(s->embree[1]);
#endif
#ifdef HAVE_BULLET
    bullet_peer_destroy(s->bullet);
#endif
#ifdef HAVE_TINYBVH
    tinybvh_peer_destroy(s->tinybvh[0]);
    tinybvh_peer_destroy(s->tinybvh[1]);
#endif
#ifdef HAVE_JOLT
    jolt_peer_destroy(s->jolt);
#endif
#ifdef HAVE_DLOPEN
    baseline_peer_destroy(s->baseline);
#endif
    (void)s;
}

/* ------------------------------------------------------------------ */
/* Measurements                                                        */
/* ------------------------------------------------------------------ */

typedef struct buffers {
    cbvh_ray *rays;
    cbvh_hit *ref_hits, *hits;
    uint8_t *ref_occluded, *occluded;
} buffers;

/* A job timed beside others (time_jobs). */
typedef struct timed_job {
    bench_job job;
    int reference;           /* a whole counted pass first (cbvh) rather than a probe */
    cbvh_query_stats *stats; /* the reference pass's counters, or NULL */
    unsigned runs;           /* timed rounds */
} timed_job;

/* Called once the answer pass of jobs[k] (time_jobs) has left its answers (the jobs share answer buffers). */
typedef void (*answered_fn)(void *ctx, int k, const bench_job *job);

/* Times jobs[0..n) on `threads` threads, each the median of its rounds, into seconds[k]; returns 0, or
 * negative (reported) when the threads cannot start. First each job makes its set-up pass: a reference
 * engine (cbvh) a whole pass, counted into its stats when not NULL, so counting does not perturb the
 * timing; a peer a prefix of the queries, and when all of them would take longer than the budget it is
 * timed on the prefix the budget allows (job.count is cut to it): Bullet's ray walk cannot stop at the
 * first hit, and takes minutes for a million rays on a large mesh. When `answered` wants the answers,
 * each peer then runs once whole, untimed, and leaves them (the jobs share answer buffers). Then the jobs
 * are timed in turns, up to s->reps rounds, a job leaving them once its rounds took the budget
 * (bench_time_in_turns): the engines compared in a row of the tables share the same stretches of time, and
 * their ratios hold (two copies of the same walk, the sorted and stackless rows of a wide4 file, within
 * 1-5% of each other, where whole runs of the set in turn differed by up to 21%). */
static int time_jobs(bench_state *s, timed_job *jobs, int n, size_t probe, unsigned threads, double *seconds,
                     answered_fn answered, void *ctx)
{
    int status = 0;
    for (int k = 0; k < n && status == 0; k++) {
        timed_job *t = &jobs[k];
        const size_t all = t->job.count;
        double x = t->reference ? bench_run_once(&t->job, threads, t->stats) : 0.0;
        if (!t->reference && s->budget > 0.0f && all > probe) {
            t->job.count = probe;
            x = bench_run_once(&t->job, threads, NULL);
            double allowed = x > 0.0 ? (double)probe * s->budget / x : (double)all;
            t->job.count = allowed >= (double)all ? all : allowed > probe ? (size_t)allowed : probe;
        }
        /* the reference's counted pass left its answers */
        if (x >= 0.0 && answered && !t->reference)
            x = bench_run_once(&t->job, threads, NULL);
        if (x < 0.0)
            status = -1;
        else if (answered)
            answered(ctx, k, &t->job);
    }
    const bench_job *timed[MAX_METHODS > MAX_SHAPE_METHODS ? MAX_METHODS : MAX_SHAPE_METHODS] = {NULL};
    unsigned runs[sizeof timed / sizeof timed[0]];
    for (int k = 0; k < n; k++)
        timed[k] = &jobs[k].job;
    if (status == 0)
        status = bench_time_in_turns(timed, n, threads, s->reps, s->budget, seconds, runs);
    for (int k = 0; k < n && status == 0; k++)
        jobs[k].runs = runs[k];
    if (status < 0) {
        progress_done(&s->prog);
        if (status == -1)
            cli_error(s->command, NULL, "cannot start %u threads", threads);
        else
            cli_error(s->command, NULL, "out of memory for %u timings", s->reps);
    }
    return status;
}

/* Whether one more disagreement of a set may be decided against the reference: `checked` of them were, fewer
 * than BENCH_JUDGE_QUERIES, and the checks began (at *start, the first check's time, when negative) within
 * the budget; reads the reference at the first check. */
static int judge_ready(bench_state *s, uint64_t checked, double *start)
{
    if (checked >= BENCH_JUDGE_QUERIES || s->judge_state < 0)
        return 0;
    double now = bench_clock(s->cpu_clock);
    if (*start < 0.0)
        *start = now;
    else if (s->budget > 0.0f && now - *start > s->budget)
        return 0;
    if (s->judge_state == 0) {
        s->judge_state = bench_judge_init(&s->judge, s->file, (uint32_t)s->mesh.triangle_count,
                                          AGREE_TOLERANCE * s->diagonal, SWEEP_AGREE_TOLERANCE * s->diagonal)
                             ? 1
                             : -1;
        if (s->judge_state < 0) {
            cli_error(s->command, NULL, "out of memory for the reference: disagreements not checked");
            return 0;
        }
    }
    return 1;
}

/* What the agreement check of a ray set's methods needs (set_answered). */
typedef struct set_context {
    bench_state *s;
    ray_kind set;
    int any;
    buffers *b;
    const int *method_of; /* timed job k -> method index */
} set_context;

/* Compares the answers of method method_of[k], just timed, with the reference's (method 0's). */
static void set_answered(void *ctx, int k, const bench_job *job)
{
    set_context *c = ctx;
    bench_state *s = c->s;
    const int m = c->method_of[k];
    if (m == 0)
        return;
    agree_row *a =
        &s->agreements[c->any ? s->agree_count - (s->method_count - 1) + (m - 1) : s->agree_count++];
    const cbvh_ray *rays = c->b->rays;
    double start = -1.0;
    if (!c->any) {
        memset(a, 0, sizeof *a);
        a->set = c->set;
        a->m = &s->methods[m];
        a->closest_count = job->count;
        const cbvh_hit *x = c->b->ref_hits, *y = c->b->hits;
        for (size_t i = 0; i < job->count; i++) {
            const float *d = rays[i].dir;
            const double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
            const uint64_t before = a->closest.disagree;
            bench_agree_one(&a->closest, x[i].tri, y[i].tri, fabs((double)x[i].t - (double)y[i].t) * len,
                            AGREE_TOLERANCE * s->diagonal);
            if (a->closest.disagree != before && judge_ready(s, a->checked[0], &start)) {
                a->sides[0][bench_judge_ray(&s->judge, &rays[i], &x[i], &y[i])]++;
                a->checked[0]++;
            }
        }
    } else {
        a->any_count = job->count;
        const uint8_t *x = c->b->ref_occluded, *y = c->b->occluded;
        for (size_t i = 0; i < job->count; i++) {
            if ((x[i] != 0) == (y[i] != 0))
                continue;
            a->any_disagree++;
            if (judge_ready(s, a->checked[1], &start)) {
                a->sides[1][bench_judge_occluded(&s->judge, &rays[i], x[i], y[i])]++;
                a->checked[1]++;
            }
        }
    }
}

/* Measures every method on one ray set: method 0 (cbvh sorted) first, as the
 * reference every other method's answers are compared with, at the first thread
 * count (where the answers are compared); the main methods again at every other.
 * The methods of a query and thread count are timed together (time_jobs). */
static int measure_set(bench_state *s, ray_kind set, buffers *b, int *step, int steps)
{
    char label[96];
    for (int any = 0; any < 2; any++)
        for (int ti = 0; ti < s->thread_count_n; ti++) {
            const unsigned threads = s->thread_counts[ti];
            timed_job jobs[MAX_METHODS];
            result_row *rows[MAX_METHODS];
            int method_of[MAX_METHODS], n = 0;
            for (int k = 0; k < s->method_count; k++) {
                const method *m = &s->methods[k];
                if (ti > 0 && !m->main)
                    continue;
                (*step)++;
                result_row *r = &s->results[s->result_count++];
                memset(r, 0, sizeof *r);
                r->set = set;
                r->any = any;
                r->m = m;
                r->threads = threads;
                bench_job job = {.kernel = m->kernel,
                                 .engine = m->state,
                                 .rays = b->rays,
                                 .count = s->rays,
                                 .cpu_clock = s->cpu_clock};
                if (any)
                    job.occluded = k == 0 ? b->ref_occluded : b->occluded;
                else
                    job.hits = k == 0 ? b->ref_hits : b->hits;
                memset(&jobs[n], 0, sizeof jobs[n]);
                jobs[n].job = job;
                jobs[n].reference = m->counted;
                jobs[n].stats = m->counted ? &r->stats : NULL;
                rows[n] = r;
                method_of[n++] = k;
            }
            snprintf(label, sizeof label, "%s %s: %d methods, %u thread(s)", rays_kind_name(set),
                     any ? "any" : "closest", n, threads);
            progress_update(&s->prog, label, (double)*step / steps);
            set_context ctx = {s, set, any, b, method_of};
            double seconds[MAX_METHODS];
            if (time_jobs(s, jobs, n, BENCH_PROBE_QUERIES, threads, seconds, ti == 0 ? set_answered : NULL,
                          &ctx) < 0)
                return CLI_EXIT_USAGE;
            for (int k = 0; k < n; k++) {
                rows[k]->count = jobs[k].job.count;
                rows[k]->seconds = seconds[k];
                rows[k]->runs = jobs[k].runs;
            }
        }
    return 0;
}

/* Decides disagreement i of row a against the reference, while the checks are within their number and
 * the budget (started at *start, the first check's time, when negative). */
static void judge_shape(bench_state *s, shape_agree_row *a, const shape_query *q, const shape_answer *x,
                        const shape_answer *y, double *start)
{
    if (!judge_ready(s, a->checked, start))
        return;
    bench_side side;
    if (a->question == SHAPE_SWEEP) {
        side = bench_judge_sweep(&s->judge, a->kind, q, x, y);
    } else if (a->question == SHAPE_FIRST_HIT) {
        side = bench_judge_first_hit(&s->judge, a->kind, q, x, y);
    } else {
        s->shape_methods[0].mark(s->shape_methods[0].state, a->kind, q, &s->judge);
        a->m->mark(a->m->state, a->kind, q, &s->judge);
        side = bench_judge_overlap(&s->judge, a->kind, q);
    }
    a->checked++;
    a->sides[side]++;
}

static void agree_shapes(bench_state *s, shape_agree_row *a, const shape_query *queries,
                         const shape_answer *ref, const shape_answer *other, size_t count, double tolerance)
{
    double start = -1.0;
    a->count = count;
    for (size_t i = 0; i < count; i++) {
        const shape_answer *x = &ref[i], *y = &other[i];
        if (a->question != SHAPE_SWEEP) { /* a first hit's count is 0 or 1, its set_hash 0 */
            a->ref_triangles += x->count;
            a->other_triangles += y->count;
            if (x->count != y->count || x->set_hash != y->set_hash) {
                a->other_set++;
                judge_shape(s, a, &queries[i], x, y, &start);
            } else if (x->count == 0) {
                a->both_empty++;
            } else {
                a->same_set++;
            }
            continue;
        }
        const float *d = queries[i].delta;
        double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
        double distance = fabs((double)x->t - (double)y->t) * len;
        a->ref_start_touching += x->tri != CBVH_NO_HIT && x->t == 0.0f;
        a->other_start_touching += y->tri != CBVH_NO_HIT && y->t == 0.0f;
        if (x->tri != CBVH_NO_HIT && y->tri != CBVH_NO_HIT && distance > a->t_distance_max)
            a->t_distance_max = distance;
        /* the same first triangle agrees at any t: see SWEEP_AGREE_TOLERANCE */
        if (x->tri == y->tri && x->tri != CBVH_NO_HIT) {
            a->sweeps.same_triangle++;
            a->t_distance_sum += distance;
        } else {
            const uint64_t before = a->sweeps.disagree;
            bench_agree_one(&a->sweeps, x->tri, y->tri, distance, tolerance);
            if (a->sweeps.disagree != before)
                judge_shape(s, a, &queries[i], x, y, &start);
        }
    }
}

/* What a shape set's found counts and agreement check need (shapes_answered). */
typedef struct shape_context {
    bench_state *s;
    int check; /* compare the peers' answers (the first thread count) */
    shape_row **rows;
    const shape_query *queries;
    shape_answer *ref, *other;
} shape_context;

/* The triangles or hits shape engine k found, just timed, and at the first thread count its agreement with
 * the reference (engine 0). */
static void shapes_answered(void *ctx, int k, const bench_job *job)
{
    shape_context *c = ctx;
    shape_row *r = c->rows[k];
    const shape_answer *answers = k == 0 ? c->ref : c->other;
    for (size_t i = 0; i < job->count; i++)
        r->found += r->question == SHAPE_SWEEP ? answers[i].tri != CBVH_NO_HIT : answers[i].count;
    if (k == 0 || !c->check)
        return;
    shape_agree_row *a = &c->s->shape_agreements[c->s->shape_agree_count++];
    memset(a, 0, sizeof *a);
    a->kind = r->kind;
    a->question = r->question;
    a->m = r->m;
    agree_shapes(c->s, a, c->queries, c->ref, c->other, job->count, SWEEP_AGREE_TOLERANCE * c->s->diagonal);
}

/* Measures every shape engine on one shape set at every thread count, the engines of a thread count timed
 * together (time_jobs); cbvh (engine 0) first, as the reference, compared with each peer at the first
 * thread count. */
static int measure_shapes(bench_state *s, shape_kind kind, shape_question question,
                          const shape_query *queries, shape_answer *ref, shape_answer *other, int *step,
                          int steps)
{
    char label[96];
    for (int ti = 0; ti < s->thread_count_n; ti++) {
        const unsigned threads = s->thread_counts[ti];
        timed_job jobs[MAX_SHAPE_METHODS];
        shape_job sj[MAX_SHAPE_METHODS];
        shape_row *rows[MAX_SHAPE_METHODS];
        int n = 0;
        for (int e = 0; e < s->shape_method_count; e++) {
            (*step)++;
            const shape_method *m = &s->shape_methods[e];
            if (question == SHAPE_FIRST_HIT && m->no_first_hit)
                continue;
            const int k = n++;
            sj[k] = (shape_job){m, kind, question, queries, k == 0 ? ref : other};
            shape_row *r = &s->shape_results[s->shape_result_count++];
            memset(r, 0, sizeof *r);
            r->kind = kind;
            r->question = question;
            r->m = m;
            r->threads = threads;
            rows[k] = r;
            memset(&jobs[k], 0, sizeof jobs[k]);
            jobs[k].job = (bench_job){
                .count = s->shapes, .cpu_clock = s->cpu_clock, .range = shape_range, .range_job = &sj[k]};
            jobs[k].reference = k == 0;
        }
        snprintf(label, sizeof label, "%s %s: %d engines, %u thread(s)", shape_kind_name(kind),
                 shape_question_names[question], n, threads);
        progress_update(&s->prog, label, (double)*step / steps);
        shape_context ctx = {s, ti == 0, rows, queries, ref, other};
        double seconds[MAX_SHAPE_METHODS];
        if (time_jobs(s, jobs, n, BENCH_PROBE_SHAPES, threads, seconds, shapes_answered, &ctx) < 0)
            return CLI_EXIT_USAGE;
        for (int k = 0; k < n; k++) {
            rows[k]->seconds = seconds[k];
            rows[k]->count = jobs[k].job.count;
            rows[k]->runs = jobs[k].runs;
        }
    }
    return 0;
}

/* ------------------------------------------------------------------ */
/* Output                                                              */
/* ------------------------------------------------------------------ */

static double mrays(const result_row *r)
{
    return r->seconds > 0.0 ? (double)r->count / r->seconds * 1e-6 : 0.0;
}

/* The cbvh sorted row of the same set, query and thread count: the reference of the ratio column. */
static const result_row *sorted_row(const bench_state *s, const result_row *r)
{
    for (int i = 0; i < s->result_count; i++) {
        const result_row *x = &s->results[i];
        if (x->set == r->set && x->any == r->any && x->m == &s->methods[0] && x->threads == r->threads)
            return x;
    }
    return r;
}

static double queries_per_second(const shape_row *r)
{
    return r->seconds > 0.0 ? (double)r->count / r->seconds : 0.0;
}

/* Microseconds one query takes on one thread: every thread runs its slice for the time measured. */
static double micros_per_query(const shape_row *r)
{
    return r->count > 0 ? r->seconds * r->threads / (double)r->count * 1e6 : 0.0;
}

/* cbvh's row of the same shape set and thread count: the reference of the ratio column. */
static const shape_row *cbvh_shape_row(const bench_state *s, const shape_row *r)
{
    for (int i = 0; i < s->shape_result_count; i++) {
        const shape_row *x = &s->shape_results[i];
        if (x->kind == r->kind && x->question == r->question && x->threads == r->threads &&
            x->m == &s->shape_methods[0])
            return x;
    }
    return r;
}

static double shape_ratio(const bench_state *s, const shape_row *r)
{
    double speed = queries_per_second(r);
    return speed > 0.0 ? queries_per_second(cbvh_shape_row(s, r)) / speed : 0.0;
}

/* The thread counts as written on the command line, for the headings. */
static void format_threads(const bench_state *s, char *text, size_t size)
{
    size_t n = 0;
    text[0] = '\0';
    for (int i = 0; i < s->thread_count_n && n < size; i++)
        n += (size_t)snprintf(text + n, size - n, "%s%u", i ? "," : "", s->thread_counts[i]);
}

/* The mean distance between the t of sweeps that hit the same first triangle, over the diagonal. */
static double t_apart_mean(const bench_state *s, const shape_agree_row *a)
{
    return a->sweeps.same_triangle ? a->t_distance_sum / (double)a->sweeps.same_triangle / s->diagonal : 0.0;
}

static void print_shape_tables(const bench_state *s)
{
    if (s->shape_result_count == 0)
        return;
    printf("\nShape queries near the surface, %zu per set (sizes and motions in `cbvh bench --help`); "
           "µs/query is "
           "the time one query takes on one thread, cbvh / this the ratio of queries per second at the same "
           "thread count:\n\n",
           s->shapes);
    printf(
        "| shape | query | engine | threads | µs/query | queries/s | queries/s/thread | hits or tris/query | "
        "cbvh / this | runs x queries |\n");
    printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < s->shape_result_count; i++) {
        const shape_row *r = &s->shape_results[i];
        double speed = queries_per_second(r);
        printf("| %s | %s | %s | %u | %.3f | %.0f | %.0f | %.3f | %.3f | %u x %zu |\n",
               shape_kind_name(r->kind), shape_question_names[r->question], r->m->engine, r->threads,
               micros_per_query(r), speed, speed / r->threads,
               r->count ? (double)r->found / (double)r->count : 0.0, shape_ratio(s, r), r->runs, r->count);
    }
    printf(
        "\nfirst-hit: the overlap queries again, each engine stopping at the first triangle it finds (hits: "
        "queries that touch one).\n");
    for (int k = 0; k < s->shape_method_count; k++)
        if (s->shape_methods[k].no_first_hit)
            printf("%s answers no first-hit overlap (%s): no %s first-hit rows.\n",
                   s->shape_methods[k].engine, s->shape_methods[k].no_first_hit, s->shape_methods[k].engine);
    if (s->shape_agree_count == 0)
        return;
#ifdef HAVE_JOLT
    if (s->jolt)
        printf(
            "\nJolt's tolerances are absolute, in the mesh's units whatever its size (its collision "
            "tolerance "
            "is 1e-4: its casts stop and its contacts count within about that distance of a triangle), and "
            "it answers without the triangles it left out (see above).\n");
#endif
    printf(
        "\nShape agreement with cbvh, query by query (sweeps: the same first triangle, or another one with t "
        "times the motion's length within %.0e of the scene diagonal; overlaps: the same set of triangles; "
        "first hits: both touch or neither, the same set column counting both touch). "
        "Bullet's casts stop 0.001 mesh units short of contact (its constant), so its t come early; the t "
        "apart "
        "columns say by how much, as a fraction of the diagonal. Up to %d disagreements per set (fewer "
        "once checking them took the budget) are decided against a double-precision brute force (the "
        "tests' reference): it sides with an engine whose answer it bears out (sweeps: by the rule "
        "above, a miss when the shape shrunk by %.0e of the diagonal misses too; overlaps: every triangle "
        "that surely overlaps and none surely apart, within %.0e of the diagonal; first hits: a triangle not "
        "surely apart, or none when none surely overlaps), with both, or with "
        "neither:\n\n",
        SWEEP_AGREE_TOLERANCE, BENCH_JUDGE_QUERIES, AGREE_TOLERANCE, AGREE_TOLERANCE);
    printf("| shape | query | engine | same triangle or set | both miss or none | t close, other triangle | "
           "disagree | checked | reference: cbvh / this / both / neither | start touching cbvh / this | "
           "same triangle: t apart mean | t apart max | tris cbvh / this | queries compared |\n");
    printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < s->shape_agree_count; i++) {
        const shape_agree_row *a = &s->shape_agreements[i];
        printf("| %s | %s | %s | ", shape_kind_name(a->kind), shape_question_names[a->question],
               a->m->engine);
        if (a->question == SHAPE_SWEEP)
            printf("%llu | %llu | %llu | %llu | ", (unsigned long long)a->sweeps.same_triangle,
                   (unsigned long long)a->sweeps.both_miss, (unsigned long long)a->sweeps.t_close,
                   (unsigned long long)a->sweeps.disagree);
        else
            printf("%llu | %llu | - | %llu | ", (unsigned long long)a->same_set,
                   (unsigned long long)a->both_empty, (unsigned long long)a->other_set);
        printf("%llu | %llu / %llu / %llu / %llu | ", (unsigned long long)a->checked,
               (unsigned long long)a->sides[BENCH_SIDE_CBVH], (unsigned long long)a->sides[BENCH_SIDE_PEER],
               (unsigned long long)a->sides[BENCH_SIDE_BOTH],
               (unsigned long long)a->sides[BENCH_SIDE_NEITHER]);
        if (a->question == SHAPE_SWEEP)
            printf("%llu / %llu | %.2e | %.2e | - | %zu |\n", (unsigned long long)a->ref_start_touching,
                   (unsigned long long)a->other_start_touching, t_apart_mean(s, a),
                   a->t_distance_max / s->diagonal, a->count);
        else
            printf("- | - | - | %llu / %llu | %zu |\n", (unsigned long long)a->ref_triangles,
                   (unsigned long long)a->other_triangles, a->count);
    }
}

static void print_tables(const bench_state *s)
{
    double tris = (double)s->mesh.triangle_count;
    printf("## cbvh bench: %s\n\n", s->mesh.name);
    char threads[64];
    format_threads(s, threads, sizeof threads);
    printf("%zu triangles, %zu rays per set, seed %llu, threads %s, median of up to %u runs per figure "
           "(fewer once a figure's runs took %.3g s), %s.\n\n",
           s->mesh.triangle_count, s->rays, (unsigned long long)s->seed, threads, s->reps, s->budget,
           s->cpu_clock ? "CPU time (process CPU for cook, build and open; slowest thread's CPU for queries)"
                        : "wall-clock time");
    const build_row *c = &s->builds[0];
    printf(
        "| engine | build s | Mtris/s | open ms | bytes/tri | cbvh/this bytes | cbvh open / this build |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < s->build_count; i++) {
        const build_row *b = &s->builds[i];
        printf("| %s | ", b->engine);
        if (b->seconds >= 0.0)
            printf("%.3f | %.2f | ", b->seconds, tris / b->seconds * 1e-6);
        else
            printf("- | - | ");
        if (b->open_seconds >= 0.0)
            printf("%.3f | ", b->open_seconds * 1e3);
        else
            printf("- | ");
        printf("%.2f | %.3f | ", (double)b->bytes / tris, (double)c->bytes / (double)b->bytes);
        if (i > 0 && b->seconds > 0.0)
            printf("%.4f |\n", c->open_seconds / b->seconds);
        else
            printf("- |\n");
    }
    printf("\nbytes/tri: the cbvh file (cbvh expanded: in memory, with the copy of "
           "cbvh_file_expand_triangles); for the peers their acceleration structure plus the shared vertex "
           "and index arrays they need.\n");
    for (int i = 0; i < s->build_count; i++)
        if (s->builds[i].traversed_bytes)
            printf(
                "%s keeps its build data (the trees it converted from): its queries read %.2f bytes/tri of "
                "its blocks, which hold their own copies of the triangles.\n",
                s->builds[i].engine, (double)s->builds[i].traversed_bytes / tris);
    for (int i = 0; i < s->build_count; i++)
        if (s->builds[i].id_bytes)
            printf("%s keeps its own compressed copy of the triangles (no shared arrays); %.2f bytes/tri of "
                   "it are "
                   "each triangle's index, its user data, which its answers need to name the mesh's "
                   "triangles (it "
                   "reorders them): %.2f bytes/tri without.\n",
                   s->builds[i].engine, (double)s->builds[i].id_bytes / tris,
                   (double)(s->builds[i].bytes - s->builds[i].id_bytes) / tris);
    for (int i = 0; i < s->build_count; i++)
        if (s->builds[i].dropped_triangles)
            printf("%s left out %llu of the %zu triangles (area below 5e-7 in the mesh's units, its absolute "
                   "degenerate test, or degenerate once quantized): it answers without them.\n",
                   s->builds[i].engine, (unsigned long long)s->builds[i].dropped_triangles,
                   s->mesh.triangle_count);
    if (!s->no_peers) {
#if !defined(HAVE_EMBREE)
        printf("Embree 3 was not found at configure time: no Embree figures.\n");
#endif
#if !defined(HAVE_BULLET)
        printf("Bullet 3 was not found at configure time: no Bullet figures.\n");
#endif
#if !defined(HAVE_TINYBVH)
        printf("tinybvh was not given at configure time (--with-tinybvh=DIR): no tinybvh figures.\n");
#else
        if (s->tinybvh_cpu_lacks)
            printf("tinybvh was built for AVX2 and FMA, which this CPU lacks: no tinybvh figures.\n");
#endif
#if !defined(HAVE_JOLT)
        printf("Jolt Physics was not given at configure time (--with-jolt=PREFIX): no Jolt figures.\n");
#else
        if (s->jolt_cpu_lacks)
            printf("Jolt was built for AVX2 and FMA, which this CPU lacks: no Jolt figures.\n");
#endif
    }
    printf("\n");

    printf("| rays | query | engine | variant | threads | MRays/s | MRays/s/thread | nodes/ray | tris/ray | "
           "cbvh sorted / this | runs x rays |\n");
    printf("|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < s->result_count; i++) {
        const result_row *r = &s->results[i];
        double speed = mrays(r), ref = mrays(sorted_row(s, r));
        printf("| %s | %s | %s | %s | %u | %.3f | %.3f | ", rays_kind_name(r->set),
               r->any ? "any" : "closest", r->m->engine, r->m->variant, r->threads, speed,
               speed / r->threads);
        if (r->m->counted)
            printf("%.1f | %.2f | ", (double)r->stats.nodes_visited / (double)s->rays,
                   (double)r->stats.triangles_tested / (double)s->rays);
        else
            printf("- | - | ");
        printf("%.3f | %u x %zu |\n", speed > 0.0 ? ref / speed : 0.0, r->runs, r->count);
    }

    printf(
        "\nAgreement with cbvh sorted, ray by ray (t within %.0e of the scene diagonal). Up to %d "
        "disagreements per set and query (fewer once checking them took the budget) are decided against the "
        "double-precision brute force: a miss is borne out when no triangle is surely crossed, a hit when "
        "its triangle is crossed at its t and no triangle surely before it, within %.0e of the diagonal:\n\n",
        AGREE_TOLERANCE, BENCH_JUDGE_QUERIES, AGREE_TOLERANCE);
    printf(
        "| rays | engine | variant | same triangle | both miss | t close, other triangle | disagree | "
        "any-hit disagree | rays compared | checked: closest + any | reference: cbvh / this / both / neither "
        "|\n");
    printf("|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < s->agree_count; i++) {
        const agree_row *a = &s->agreements[i];
        printf("| %s | %s | %s | %llu | %llu | %llu | %llu | %llu | %zu", rays_kind_name(a->set),
               a->m->engine, a->m->variant, (unsigned long long)a->closest.same_triangle,
               (unsigned long long)a->closest.both_miss, (unsigned long long)a->closest.t_close,
               (unsigned long long)a->closest.disagree, (unsigned long long)a->any_disagree,
               a->closest_count);
        if (a->any_count != a->closest_count)
            printf(" (any hit: %zu)", a->any_count);
        uint64_t sides[4];
        for (int k = 0; k < 4; k++)
            sides[k] = a->sides[0][k] + a->sides[1][k];
        printf(" | %llu + %llu | %llu / %llu / %llu / %llu |\n", (unsigned long long)a->checked[0],
               (unsigned long long)a->checked[1], (unsigned long long)sides[BENCH_SIDE_CBVH],
               (unsigned long long)sides[BENCH_SIDE_PEER], (unsigned long long)sides[BENCH_SIDE_BOTH],
               (unsigned long long)sides[BENCH_SIDE_NEITHER]);
    }
    print_shape_tables(s);
    fflush(stdout);
}

/* The members a closest-hit or sweep agreement shares. */
static void json_agreement(json_writer *w, const bench_agreement *a)
{
    json_uint(w, "same_triangle", a->same_triangle);
    json_uint(w, "both_miss", a->both_miss);
    json_uint(w, "t_close_other_triangle", a->t_close);
    json_uint(w, "disagree", a->disagree);
}

static int write_json(const bench_state *s)
{
    FILE *out = fopen(s->json_path, "w");
    if (!out) {
        cli_error(s->command, s->json_path, "cannot write: %s", strerror(errno));
        return CLI_EXIT_USAGE;
    }
    double tris = (double)s->mesh.triangle_count;
    json_writer w;
    json_init(&w, out);
    json_begin_object(&w, NULL);
    json_string(&w, "command", "bench");
    json_string(&w, "input", s->mesh.name);
    json_uint(&w, "triangles", s->mesh.triangle_count);
    json_uint(&w, "vertices", s->mesh.vertex_count);
    json_double(&w, "diagonal", s->diagonal);
    json_uint(&w, "rays", s->rays);
    json_uint(&w, "shapes", s->shapes);
    json_uint(&w, "seed", s->seed);
    json_begin_array(&w, "threads");
    for (int i = 0; i < s->thread_count_n; i++)
        json_uint(&w, NULL, s->thread_counts[i]);
    json_end_array(&w);
    json_uint(&w, "reps", s->reps);
    json_double(&w, "budget_seconds", s->budget);
    json_string(&w, "clock", s->cpu_clock ? "cpu" : "wall");
    json_double(&w, "agreement_tolerance", AGREE_TOLERANCE);
    json_double(&w, "sweep_agreement_tolerance", SWEEP_AGREE_TOLERANCE);
    json_begin_array(&w, "builds");
    for (int i = 0; i < s->build_count; i++) {
        const build_row *b = &s->builds[i];
        json_begin_object(&w, NULL);
        json_string(&w, "engine", b->engine);
        if (b->seconds >= 0.0) {
            json_double(&w, "build_seconds", b->seconds);
            json_double(&w, "build_mtris_per_s", tris / b->seconds * 1e-6);
        } else {
            json_null(&w, "build_seconds");
            json_null(&w, "build_mtris_per_s");
        }
        if (b->open_seconds >= 0.0)
            json_double(&w, "open_seconds", b->open_seconds);
        json_uint(&w, "bytes", b->bytes);
        json_uint(&w, "structure_bytes", b->structure_bytes);
        if (b->traversed_bytes)
            json_uint(&w, "traversed_bytes", b->traversed_bytes);
        if (b->dropped_triangles)
            json_uint(&w, "dropped_triangles", b->dropped_triangles);
        if (b->id_bytes)
            json_uint(&w, "id_bytes", b->id_bytes);
        json_double(&w, "bytes_per_triangle", (double)b->bytes / tris);
        json_double(&w, "cbvh_over_this_bytes", (double)s->builds[0].bytes / (double)b->bytes);
        if (i > 0 && b->seconds > 0.0)
            json_double(&w, "cbvh_open_over_this_build", s->builds[0].open_seconds / b->seconds);
        json_end_object(&w);
    }
    json_end_array(&w);
    if (s->cooked) {
        json_begin_object(&w, "cook");
        json_uint(&w, "triangles", s->cook.triangles);
        json_uint(&w, "nodes", s->cook.nodes);
        json_uint(&w, "depth", s->cook.depth);
        json_double(&w, "sah_cost", s->cook.sah_cost);
        json_end_object(&w);
    }
    json_begin_array(&w, "results");
    for (int i = 0; i < s->result_count; i++) {
        const result_row *r = &s->results[i];
        double speed = mrays(r), ref = mrays(sorted_row(s, r));
        json_begin_object(&w, NULL);
        json_string(&w, "rays", rays_kind_name(r->set));
        json_string(&w, "query", r->any ? "any" : "closest");
        json_string(&w, "engine", r->m->engine);
        json_string(&w, "variant", r->m->variant);
        json_uint(&w, "threads", r->threads);
        json_double(&w, "seconds", r->seconds);
        json_uint(&w, "runs", r->runs);
        json_uint(&w, "rays_timed", r->count);
        json_double(&w, "mrays_per_s", speed);
        json_double(&w, "mrays_per_s_per_thread", speed / r->threads);
        if (r->m->counted) {
            json_double(&w, "nodes_per_ray", (double)r->stats.nodes_visited / (double)s->rays);
            json_double(&w, "triangles_per_ray", (double)r->stats.triangles_tested / (double)s->rays);
        }
        json_double(&w, "cbvh_sorted_over_this", speed > 0.0 ? ref / speed : 0.0);
        json_end_object(&w);
    }
    json_end_array(&w);
    json_begin_array(&w, "agreement");
    for (int i = 0; i < s->agree_count; i++) {
        const agree_row *a = &s->agreements[i];
        json_begin_object(&w, NULL);
        json_string(&w, "rays", rays_kind_name(a->set));
        json_string(&w, "engine", a->m->engine);
        json_string(&w, "variant", a->m->variant);
        json_agreement(&w, &a->closest);
        json_uint(&w, "any_disagree", a->any_disagree);
        json_uint(&w, "closest_rays_compared", a->closest_count);
        json_uint(&w, "any_rays_compared", a->any_count);
        static const char *const questions[2] = {"closest", "any"};
        static const char *const side_names[4] = {"neither", "cbvh", "this", "both"};
        char key[64];
        for (int q = 0; q < 2; q++) {
            snprintf(key, sizeof key, "%s_disagreements_checked", questions[q]);
            json_uint(&w, key, a->checked[q]);
            for (int k = 0; k < 4; k++) {
                snprintf(key, sizeof key, "%s_reference_sides_%s", questions[q], side_names[k]);
                json_uint(&w, key, a->sides[q][k]);
            }
        }
        json_end_object(&w);
    }
    json_end_array(&w);
    json_begin_array(&w, "shape_results");
    for (int i = 0; i < s->shape_result_count; i++) {
        const shape_row *r = &s->shape_results[i];
        json_begin_object(&w, NULL);
        json_string(&w, "shape", shape_kind_name(r->kind));
        json_string(&w, "query", shape_question_names[r->question]);
        json_string(&w, "engine", r->m->engine);
        json_uint(&w, "threads", r->threads);
        json_double(&w, "seconds", r->seconds);
        json_uint(&w, "runs", r->runs);
        json_uint(&w, "queries_timed", r->count);
        json_double(&w, "us_per_query", micros_per_query(r));
        json_double(&w, "queries_per_s", queries_per_second(r));
        json_double(&w, "queries_per_s_per_thread", queries_per_second(r) / r->threads);
        json_double(&w, r->question == SHAPE_OVERLAP ? "triangles_per_query" : "hits_per_query",
                    r->count ? (double)r->found / (double)r->count : 0.0);
        json_double(&w, "cbvh_over_this", shape_ratio(s, r));
        json_end_object(&w);
    }
    json_end_array(&w);
    json_begin_array(&w, "shape_agreement");
    for (int i = 0; i < s->shape_agree_count; i++) {
        const shape_agree_row *a = &s->shape_agreements[i];
        json_begin_object(&w, NULL);
        json_string(&w, "shape", shape_kind_name(a->kind));
        json_string(&w, "query", shape_question_names[a->question]);
        json_string(&w, "engine", a->m->engine);
        if (a->question == SHAPE_SWEEP) {
            json_agreement(&w, &a->sweeps);
            json_uint(&w, "cbvh_start_touching", a->ref_start_touching);
            json_uint(&w, "this_start_touching", a->other_start_touching);
            json_double(&w, "same_triangle_t_distance_mean_over_diagonal", t_apart_mean(s, a));
            json_double(&w, "t_distance_max_over_diagonal", a->t_distance_max / s->diagonal);
        } else {
            json_uint(&w, "same_set", a->same_set);
            json_uint(&w, "both_empty", a->both_empty);
            json_uint(&w, "disagree", a->other_set);
            json_uint(&w, "cbvh_triangles", a->ref_triangles);
            json_uint(&w, "this_triangles", a->other_triangles);
        }
        json_uint(&w, "queries_compared", a->count);
        json_uint(&w, "disagreements_checked", a->checked);
        json_uint(&w, "reference_sides_cbvh", a->sides[BENCH_SIDE_CBVH]);
        json_uint(&w, "reference_sides_this", a->sides[BENCH_SIDE_PEER]);
        json_uint(&w, "reference_sides_both", a->sides[BENCH_SIDE_BOTH]);
        json_uint(&w, "reference_sides_neither", a->sides[BENCH_SIDE_NEITHER]);
        json_end_object(&w);
    }
    json_end_array(&w);
    json_end_object(&w);
    json_finish(&w);
    if (ferror(out) | fclose(out)) {
        cli_error(s->command, s->json_path, "write failed");
        return CLI_EXIT_USAGE;
    }
    return 0;
}

/* ------------------------------------------------------------------ */

static int run(bench_state *s)
{
    int status = prepare_cbvh(s);
    if (status)
        return status;
    float lo[3], hi[3];
    rays_mesh rm = {s->mesh.positions, s->mesh.vertex_count, s->mesh.indices, s->mesh.triangle_count};
    s->diagonal = rays_mesh_bounds(&rm, lo, hi);
    add_cbvh_methods(s);
    if (s->baseline_path && (status = add_baseline(s)) != 0)
        return status;
    if (!s->no_peers)
        build_peers(s);

    buffers b;
    b.rays = malloc(s->rays * sizeof *b.rays);
    b.ref_hits = malloc(s->rays * sizeof *b.ref_hits);
    b.hits = malloc(s->rays * sizeof *b.hits);
    b.ref_occluded = malloc(s->rays);
    b.occluded = malloc(s->rays);
    int main_methods = 0;
    for (int k = 0; k < s->method_count; k++)
        main_methods += s->methods[k].main;
    int ray_rows = s->method_count + (s->thread_count_n - 1) * main_methods;
    int shape_rows = s->shapes ? s->thread_count_n * s->shape_method_count : 0;
    s->results = calloc((size_t)RAYS_KIND_COUNT * 2 * ray_rows, sizeof *s->results);
    s->agreements = calloc((size_t)RAYS_KIND_COUNT * s->method_count, sizeof *s->agreements);
    const int shape_sets = SHAPE_SWEEP_KIND_COUNT + 2 * SHAPE_OVERLAP_KIND_COUNT;
    s->shape_results = calloc((size_t)shape_sets * shape_rows + 1, sizeof *s->shape_results);
    s->shape_agreements = calloc((size_t)shape_sets * s->shape_method_count, sizeof *s->shape_agreements);
    shape_query *queries = malloc(s->shapes * sizeof *queries + 1);
    shape_answer *ref = malloc(s->shapes * sizeof *ref + 1), *other = malloc(s->shapes * sizeof *other + 1);
    if (!b.rays || !b.ref_hits || !b.hits || !b.ref_occluded || !b.occluded || !s->results ||
        !s->agreements || !s->shape_results || !s->shape_agreements || !queries || !ref || !other) {
        cli_error(s->command, NULL, "out of memory for %zu rays and %zu shapes", s->rays, s->shapes);
        status = CLI_EXIT_USAGE;
    }
    int step = 0, steps = RAYS_KIND_COUNT * 2 * ray_rows + shape_sets * shape_rows;
    for (int set = 0; set < RAYS_KIND_COUNT && !status; set++) {
        rays_generate((ray_kind)set, &rm, s->seed, b.rays, s->rays);
        status = measure_set(s, (ray_kind)set, &b, &step, steps);
    }
    /* sweeps first, the kinds in order: sphere, capsule, box, oriented box; then the overlaps, then their
     * first hits (the same queries) */
    for (int set = 0; set < shape_sets && s->shapes && !status; set++) {
        const int overlap = set - SHAPE_SWEEP_KIND_COUNT;
        const shape_question question = overlap < 0                          ? SHAPE_SWEEP
                                        : overlap < SHAPE_OVERLAP_KIND_COUNT ? SHAPE_OVERLAP
                                                                             : SHAPE_FIRST_HIT;
        const shape_kind kind = (shape_kind)(overlap < 0 ? set : overlap % SHAPE_OVERLAP_KIND_COUNT);
        shapes_generate(kind, question == SHAPE_SWEEP, &rm, s->seed, queries, s->shapes);
        status = measure_shapes(s, kind, question, queries, ref, other, &step, steps);
    }
    progress_done(&s->prog);
    free(b.rays);
    free(b.ref_hits);
    free(b.hits);
    free(b.ref_occluded);
    free(b.occluded);
    free(queries);
    free(ref);
    free(other);
    if (!status) {
        print_tables(s);
        if (s->json_path)
            status = write_json(s);
    }
    return status;
}

/* --threads LIST: up to MAX_THREAD_COUNTS counts from 1 to 256, separated by commas. */
static int parse_thread_counts(bench_state *s, const char *list)
{
    char token[32];
    s->thread_count_n = 0;
    for (const char *p = list;; p++) {
        size_t n = strcspn(p, ",");
        if (s->thread_count_n == MAX_THREAD_COUNTS || n >= sizeof token) {
            cli_usage_error(s->command, "--threads takes up to %d counts separated by commas, not '%s'",
                            MAX_THREAD_COUNTS, list);
            return 0;
        }
        memcpy(token, p, n);
        token[n] = '\0';
        if (!cli_parse_u32(s->command, "threads", token, 1, 256, &s->thread_counts[s->thread_count_n++]))
            return 0;
        p += n;
        if (!*p)
            return 1;
    }
}

int cmd_bench(int argc, char **argv)
{
    bench_state s;
    memset(&s, 0, sizeof s);
    s.command = "bench";
    s.rays = 1000000;
    s.shapes = 100000;
    s.seed = 1;
    s.thread_counts[0] = 1;
    s.thread_counts[1] = 2;
    s.thread_count_n = 2;
    s.reps = 5;
    s.budget = 2.0f;
    const char *input = NULL, *gen = NULL;
    int quiet = 0;

    cli_parser p;
    cli_init(&p, s.command, usage, argc, argv);
    const char *value;
    int id;
    uint32_t u;
    while ((id = cli_next(&p, options, &value)) != CLI_END) {
        switch (id) {
        case CLI_DONE:
            return CLI_EXIT_OK;
        case CLI_ERROR:
            return CLI_EXIT_USAGE;
        case CLI_POSITIONAL:
            if (input)
                return cli_usage_error(s.command, "one input only (got '%s' and '%s')", input, value);
            input = value;
            break;
        case OPT_GEN:
            gen = value;
            break;
        case OPT_RAYS:
            if (!cli_parse_u32(s.command, "rays", value, 1, 100000000u, &u))
                return CLI_EXIT_USAGE;
            s.rays = u;
            break;
        case OPT_SEED:
            if (!cli_parse_u32(s.command, "seed", value, 0, UINT32_MAX, &u))
                return CLI_EXIT_USAGE;
            s.seed = u;
            break;
        case OPT_THREADS:
            if (!parse_thread_counts(&s, value))
                return CLI_EXIT_USAGE;
            break;
        case OPT_SHAPES:
            if (!cli_parse_u32(s.command, "shapes", value, 0, 100000000u, &u))
                return CLI_EXIT_USAGE;
            s.shapes = u;
            break;
        case OPT_REPS:
            if (!cli_parse_u32(s.command, "reps", value, 1, 1000, &s.reps))
                return CLI_EXIT_USAGE;
            break;
        case OPT_BUDGET:
            if (!cli_parse_float(s.command, "budget", value, 0.0f, 1e6f, &s.budget))
                return CLI_EXIT_USAGE;
            break;
        case OPT_CPU:
            s.cpu_clock = 1;
            break;
        case OPT_JSON:
            s.json_path = value;
            break;
        case OPT_NO_PEERS:
            s.no_peers = 1;
            break;
        case OPT_BASELINE:
            s.baseline_path = value;
            break;
        case OPT_QUIET:
            quiet = 1;
            break;
        }
    }
    if (!input == !gen)
        return cli_usage_error(s.command, gen ? "give either INPUT or --gen, not both"
                                              : "no input (give INPUT or --gen SPEC)");
    progress_init(&s.prog, quiet);
    int status = bench_mesh_load(s.command, gen ? gen : input, gen != NULL, &s.mesh);
    if (!status)
        status = run(&s);
    destroy_peers(&s);
    cbvh_close(s.file);
    cbvh_close(s.expanded);
    if (s.temp_path[0])
        bench_remove_temp(s.temp_path);
    free(s.results);
    free(s.agreements);
    free(s.shape_results);
    free(s.shape_agreements);
    if (s.judge_state > 0)
        bench_judge_free(&s.judge);
    bench_mesh_free(&s.mesh);
    return status;
}
