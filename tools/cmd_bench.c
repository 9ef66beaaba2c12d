/* cmd_bench.c: `cbvh bench`: cook, open and query speed of cbvh against Embree and Bullet on the same triangles and rays. */
#include "config.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_input.h"
#include "bench_run.h"
#include "cli.h"
#include "commands.h"
#include "json.h"
#include "peers/peers.h"
#include "progress.h"
#include "support/rays.h"

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
    "in batches of 1024), each the median of the repetitions, with nodes and triangles visited\n"
    "per ray from a separate counted pass. The peers found at configure time (Embree 3 single\n"
    "rays and 16-ray packets, default and robust; Bullet 3 quantized BVH) run on the same\n"
    "triangles and rays: build time, memory per triangle, MRays/s, the ratio cbvh/peer, and\n"
    "ray-by-ray agreement with cbvh's answers.\n"
    "Markdown tables go to stdout, progress to stderr (on a terminal).\n"
    "\n"
    "Options:\n"
    "  --gen SPEC      benchmark a generated scene instead of INPUT\n"
    "  --rays N        rays per ray set (default 1000000)\n"
    "  --seed S        ray generator seed (default 1)\n"
    "  --threads T     split the rays across T threads (default 1); Embree builds with T threads\n"
    "  --reps R        timed repetitions per figure, the median is reported (default 5)\n"
    "  --budget S      stop repeating a figure once its runs took S seconds in all (default 2;\n"
    "                  0: never), so the slowest peer does not dominate the run time\n"
    "  --cpu-time      time with CPU clocks instead of the wall clock (the slowest thread's CPU\n"
    "                  time for queries, the process's CPU time for cook, build and open): steadier\n"
    "                  on a machine busy with other work\n"
    "  --json FILE     also write every figure as JSON to FILE\n"
    "  --no-peers      measure cbvh only\n"
    "  --quiet         no progress display\n"
    "  -h, --help      show this help\n"
    "\n"
    "Exit status: 0 done, 1 the input is not a usable mesh or cbvh file, 2 usage or I/O error.\n";

enum { OPT_GEN = 1, OPT_RAYS, OPT_SEED, OPT_THREADS, OPT_REPS, OPT_BUDGET, OPT_CPU, OPT_JSON, OPT_NO_PEERS, OPT_QUIET };

static const cli_option options[] = {
    { "gen", CLI_ARG_REQUIRED, OPT_GEN },       { "rays", CLI_ARG_REQUIRED, OPT_RAYS },
    { "seed", CLI_ARG_REQUIRED, OPT_SEED },     { "threads", CLI_ARG_REQUIRED, OPT_THREADS },
    { "reps", CLI_ARG_REQUIRED, OPT_REPS },     { "budget", CLI_ARG_REQUIRED, OPT_BUDGET },
    { "cpu-time", CLI_ARG_NONE, OPT_CPU },      { "json", CLI_ARG_REQUIRED, OPT_JSON },
    { "no-peers", CLI_ARG_NONE, OPT_NO_PEERS }, { "quiet", CLI_ARG_NONE, OPT_QUIET },
    { NULL, 0, 0 },
};

/* Rays a peer runs first, to see whether all rays fit in the time budget. */
#define BENCH_PROBE_RAYS 65536

/* Answers compared with a tolerance of this fraction of the scene diagonal. */
#define AGREE_TOLERANCE 1e-5

/* ------------------------------------------------------------------ */
/* Engines: each runs a slice of rays for bench_run.                   */
/* ------------------------------------------------------------------ */

#ifdef HAVE_EMBREE
static void embree_kernel(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits, uint8_t *occluded,
                          cbvh_query_stats *stats)
{
    if (hits)
        embree_peer_raycast(engine, rays, count, hits);
    else
        embree_peer_occluded(engine, rays, count, occluded);
}

static void embree16_kernel(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                            uint8_t *occluded, cbvh_query_stats *stats)
{
    if (hits)
        embree_peer_raycast16(engine, rays, count, hits);
    else
        embree_peer_occluded16(engine, rays, count, occluded);
}
#endif

#ifdef HAVE_BULLET
static void bullet_kernel(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits, uint8_t *occluded,
                          cbvh_query_stats *stats)
{
    if (hits)
        bullet_peer_raycast(engine, rays, count, hits);
    else
        bullet_peer_occluded(engine, rays, count, occluded);
}
#endif

/* One way to answer the queries: a cbvh traversal or a peer configuration. */
typedef struct method {
    const char *engine;  /* "cbvh", "embree", "embree-robust", "bullet" */
    const char *variant; /* "sorted", "stream", "single", "packet16", "quantized" ... */
    bench_kernel kernel;
    const void *state;
    int counted; /* cbvh: nodes and triangles per ray are measured */
} method;

/* A built engine's cost. */
typedef struct build_row {
    const char *engine;
    double seconds;      /* cook or build */
    double open_seconds; /* cbvh only, else negative */
    uint64_t bytes;      /* file size, or acceleration structure + shared mesh arrays */
    uint64_t structure_bytes;
} build_row;

typedef struct result_row {
    ray_kind set;
    int any;
    const method *m;
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
} agree_row;

#define MAX_METHODS 16
#define MAX_BUILDS 4

typedef struct bench_state {
    const char *command;
    size_t rays;
    uint64_t seed;
    unsigned threads, reps;
    float budget;
    int cpu_clock;
    const char *json_path;
    int no_peers;
    progress prog;

    bench_mesh mesh;
    double diagonal;
    cbvh_file *file;
    cbvh_cook_stats cook;
    int cooked;
    char temp_path[512];

    bench_cbvh cbvh_engines[BENCH_CBVH_VARIANTS];
    method methods[MAX_METHODS];
    int method_count;
    build_row builds[MAX_BUILDS];
    int build_count;
    result_row *results;
    int result_count;
    agree_row *agreements;
    int agree_count;
#ifdef HAVE_EMBREE
    embree_peer *embree[2];
#endif
#ifdef HAVE_BULLET
    bullet_peer *bullet;
#endif
} bench_state;

static void add_method(bench_state *s, const char *engine, const char *variant, bench_kernel kernel, const void *state,
                       int counted)
{
    method *m = &s->methods[s->method_count++];
    m->engine = engine;
    m->variant = variant;
    m->kernel = kernel;
    m->state = state;
    m->counted = counted;
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
    s->build_count = 1;
    return 0;
}

static void add_cbvh_methods(bench_state *s)
{
    for (int k = 0; k < BENCH_CBVH_VARIANTS; k++) {
        bench_cbvh *e = &s->cbvh_engines[k];
        bench_cbvh_variant(e, s->file, k);
        add_method(s, "cbvh", e->name, bench_cbvh_kernel, e, 1);
    }
}

/* Builds every peer configure found; a peer that fails to build is reported and skipped. */
static void build_peers(bench_state *s)
{
    peer_mesh pm = { s->mesh.positions, s->mesh.vertex_count, s->mesh.indices, s->mesh.triangle_count };
    peer_build_info info;
    char err[256];
    (void)pm;
    (void)info;
    (void)err;
#ifdef HAVE_EMBREE
    static const char *const names[2] = { "embree", "embree-robust" };
    for (int robust = 0; robust < 2; robust++) {
        progress_update(&s->prog, robust ? "building embree (robust)" : "building embree", -1.0);
        s->embree[robust] = embree_peer_create(&pm, robust, (int)s->threads, &info, err, sizeof err);
        progress_done(&s->prog);
        if (!s->embree[robust]) {
            cli_error(s->command, NULL, "%s", err);
            continue;
        }
        build_row *b = &s->builds[s->build_count++];
        b->engine = names[robust];
        b->seconds = s->cpu_clock ? info.cpu_seconds : info.seconds;
        b->open_seconds = -1.0;
        b->bytes = info.memory_bytes + info.mesh_bytes;
        b->structure_bytes = info.memory_bytes;
        add_method(s, names[robust], "single", embree_kernel, s->embree[robust], 0);
        add_method(s, names[robust], "packet16", embree16_kernel, s->embree[robust], 0);
    }
#endif
#ifdef HAVE_BULLET
    progress_update(&s->prog, "building bullet", -1.0);
    s->bullet = bullet_peer_create(&pm, &info, err, sizeof err);
    progress_done(&s->prog);
    if (!s->bullet) {
        cli_error(s->command, NULL, "%s", err);
    } else {
        build_row *b = &s->builds[s->build_count++];
        b->engine = "bullet";
        b->seconds = s->cpu_clock ? info.cpu_seconds : info.seconds;
        b->open_seconds = -1.0;
        b->bytes = info.memory_bytes + info.mesh_bytes;
        b->structure_bytes = info.memory_bytes;
        add_method(s, "bullet", "quantized", bullet_kernel, s->bullet, 0);
    }
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

/* Measures every method on one ray set: method 0 (cbvh sorted) first, as the
 * reference every other method's answers are compared with. */
static int measure_set(bench_state *s, ray_kind set, buffers *b, int *step, int steps)
{
    char label[96];
    for (int any = 0; any < 2; any++)
        for (int k = 0; k < s->method_count; k++) {
            const method *m = &s->methods[k];
            snprintf(label, sizeof label, "%s %s: %s %s", rays_kind_name(set), any ? "any" : "closest", m->engine,
                     m->variant);
            progress_update(&s->prog, label, (double)(*step)++ / steps);
            bench_job job = { m->kernel, m->state, b->rays, s->rays, NULL, NULL, s->cpu_clock };
            if (any)
                job.occluded = k == 0 ? b->ref_occluded : b->occluded;
            else
                job.hits = k == 0 ? b->ref_hits : b->hits;
            result_row *r = &s->results[s->result_count++];
            memset(r, 0, sizeof *r);
            r->set = set;
            r->any = any;
            r->m = m;
            /* A separate counted pass for cbvh, so counting does not perturb the timing.
             * Every pass leaves the answers for the agreement check. A peer first runs
             * a prefix of the rays; when all of them would take longer than the budget
             * it is timed on the prefix the budget allows (Bullet's walk cannot stop
             * at the first hit, and takes minutes for a million rays on a large mesh). */
            double t = m->counted ? bench_run_once(&job, s->threads, &r->stats) : 0.0;
            if (!m->counted && s->budget > 0.0f && s->rays > BENCH_PROBE_RAYS) {
                job.count = BENCH_PROBE_RAYS;
                t = bench_run_once(&job, s->threads, NULL);
                double allowed = t > 0.0 ? (double)BENCH_PROBE_RAYS * s->budget / t : (double)s->rays;
                job.count = allowed >= (double)s->rays ? s->rays : allowed > BENCH_PROBE_RAYS ? (size_t)allowed
                                                                                             : BENCH_PROBE_RAYS;
            }
            r->count = job.count;
            if (t >= 0.0)
                t = bench_run_median(&job, s->threads, s->reps, s->budget, &r->runs);
            if (t < 0.0) {
                progress_done(&s->prog);
                cli_error(s->command, NULL, "cannot start %u threads", s->threads);
                return CLI_EXIT_USAGE;
            }
            r->seconds = t;
            if (k == 0)
                continue;
            agree_row *a = &s->agreements[any ? s->agree_count - (s->method_count - 1) + (k - 1) : s->agree_count++];
            if (!any) {
                memset(a, 0, sizeof *a);
                a->set = set;
                a->m = m;
                a->closest_count = job.count;
                bench_agree_closest(&a->closest, b->rays, b->ref_hits, b->hits, job.count,
                                    AGREE_TOLERANCE * s->diagonal);
            } else {
                a->any_count = job.count;
                a->any_disagree = bench_disagree_any(b->ref_occluded, b->occluded, job.count);
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

/* The cbvh sorted row of the same set and query: the reference of the ratio column. */
static const result_row *sorted_row(const bench_state *s, const result_row *r)
{
    for (int i = 0; i < s->result_count; i++)
        if (s->results[i].set == r->set && s->results[i].any == r->any && s->results[i].m == &s->methods[0])
            return &s->results[i];
    return r;
}

static void print_tables(const bench_state *s)
{
    double tris = (double)s->mesh.triangle_count;
    printf("## cbvh bench: %s\n\n", s->mesh.name);
    printf("%zu triangles, %zu rays per set, seed %llu, %u thread(s), median of up to %u runs per figure "
           "(fewer once a figure's runs took %.3g s), %s.\n\n",
           s->mesh.triangle_count, s->rays, (unsigned long long)s->seed, s->threads, s->reps, s->budget,
           s->cpu_clock ? "CPU time (process CPU for cook, build and open; slowest thread's CPU for queries)"
                        : "wall-clock time");
    const build_row *c = &s->builds[0];
    printf("| engine | build s | Mtris/s | open ms | bytes/tri | cbvh/this bytes | cbvh open / this build |\n");
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
    printf("\nbytes/tri: the cbvh file; for the peers their acceleration structure plus the shared vertex and index "
           "arrays they need.\n");
    if (!s->no_peers) {
#if !defined(HAVE_EMBREE)
        printf("Embree 3 was not found at configure time: no Embree figures.\n");
#endif
#if !defined(HAVE_BULLET)
        printf("Bullet 3 was not found at configure time: no Bullet figures.\n");
#endif
    }
    printf("\n");

    printf("| rays | query | engine | variant | MRays/s | MRays/s/thread | nodes/ray | tris/ray | cbvh sorted / this | runs x rays |\n");
    printf("|---|---|---|---|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < s->result_count; i++) {
        const result_row *r = &s->results[i];
        double speed = mrays(r), ref = mrays(sorted_row(s, r));
        printf("| %s | %s | %s | %s | %.3f | %.3f | ", rays_kind_name(r->set), r->any ? "any" : "closest",
               r->m->engine, r->m->variant, speed, speed / s->threads);
        if (r->m->counted)
            printf("%.1f | %.2f | ", (double)r->stats.nodes_visited / (double)s->rays,
                   (double)r->stats.triangles_tested / (double)s->rays);
        else
            printf("- | - | ");
        printf("%.3f | %u x %zu |\n", speed > 0.0 ? ref / speed : 0.0, r->runs, r->count);
    }

    printf("\nAgreement with cbvh sorted, ray by ray (t within %.0e of the scene diagonal):\n\n", AGREE_TOLERANCE);
    printf("| rays | engine | variant | same triangle | both miss | t close, other triangle | disagree | any-hit disagree | rays compared |\n");
    printf("|---|---|---|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < s->agree_count; i++) {
        const agree_row *a = &s->agreements[i];
        printf("| %s | %s | %s | %llu | %llu | %llu | %llu | %llu | %zu", rays_kind_name(a->set), a->m->engine,
               a->m->variant, (unsigned long long)a->closest.same_triangle, (unsigned long long)a->closest.both_miss,
               (unsigned long long)a->closest.t_close, (unsigned long long)a->closest.disagree,
               (unsigned long long)a->any_disagree, a->closest_count);
        if (a->any_count != a->closest_count)
            printf(" (any hit: %zu)", a->any_count);
        printf(" |\n");
    }
    fflush(stdout);
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
    json_uint(&w, "seed", s->seed);
    json_uint(&w, "threads", s->threads);
    json_uint(&w, "reps", s->reps);
    json_double(&w, "budget_seconds", s->budget);
    json_string(&w, "clock", s->cpu_clock ? "cpu" : "wall");
    json_double(&w, "agreement_tolerance", AGREE_TOLERANCE);
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
        json_double(&w, "seconds", r->seconds);
        json_uint(&w, "runs", r->runs);
        json_uint(&w, "rays_timed", r->count);
        json_double(&w, "mrays_per_s", speed);
        json_double(&w, "mrays_per_s_per_thread", speed / s->threads);
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
        json_uint(&w, "same_triangle", a->closest.same_triangle);
        json_uint(&w, "both_miss", a->closest.both_miss);
        json_uint(&w, "t_close_other_triangle", a->closest.t_close);
        json_uint(&w, "disagree", a->closest.disagree);
        json_uint(&w, "any_disagree", a->any_disagree);
        json_uint(&w, "closest_rays_compared", a->closest_count);
        json_uint(&w, "any_rays_compared", a->any_count);
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
    rays_mesh rm = { s->mesh.positions, s->mesh.vertex_count, s->mesh.indices, s->mesh.triangle_count };
    s->diagonal = rays_mesh_bounds(&rm, lo, hi);
    add_cbvh_methods(s);
    if (!s->no_peers)
        build_peers(s);

    buffers b;
    b.rays = malloc(s->rays * sizeof *b.rays);
    b.ref_hits = malloc(s->rays * sizeof *b.ref_hits);
    b.hits = malloc(s->rays * sizeof *b.hits);
    b.ref_occluded = malloc(s->rays);
    b.occluded = malloc(s->rays);
    s->results = calloc((size_t)RAYS_KIND_COUNT * 2 * s->method_count, sizeof *s->results);
    s->agreements = calloc((size_t)RAYS_KIND_COUNT * s->method_count, sizeof *s->agreements);
    if (!b.rays || !b.ref_hits || !b.hits || !b.ref_occluded || !b.occluded || !s->results || !s->agreements) {
        cli_error(s->command, NULL, "out of memory for %zu rays", s->rays);
        status = CLI_EXIT_USAGE;
    }
    int step = 0, steps = RAYS_KIND_COUNT * 2 * s->method_count;
    for (int set = 0; set < RAYS_KIND_COUNT && !status; set++) {
        rays_generate((ray_kind)set, &rm, s->seed, b.rays, s->rays);
        status = measure_set(s, (ray_kind)set, &b, &step, steps);
    }
    progress_done(&s->prog);
    free(b.rays);
    free(b.ref_hits);
    free(b.hits);
    free(b.ref_occluded);
    free(b.occluded);
    if (!status) {
        print_tables(s);
        if (s->json_path)
            status = write_json(s);
    }
    return status;
}

int cmd_bench(int argc, char **argv)
{
    bench_state s;
    memset(&s, 0, sizeof s);
    s.command = "bench";
    s.rays = 1000000;
    s.seed = 1;
    s.threads = 1;
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
        case CLI_DONE: return CLI_EXIT_OK;
        case CLI_ERROR: return CLI_EXIT_USAGE;
        case CLI_POSITIONAL:
            if (input)
                return cli_usage_error(s.command, "one input only (got '%s' and '%s')", input, value);
            input = value;
            break;
        case OPT_GEN: gen = value; break;
        case OPT_RAYS:
            if (!cli_parse_u32(s.command, "--rays", value, 1, 100000000u, &u))
                return CLI_EXIT_USAGE;
            s.rays = u;
            break;
        case OPT_SEED:
            if (!cli_parse_u32(s.command, "--seed", value, 0, UINT32_MAX, &u))
                return CLI_EXIT_USAGE;
            s.seed = u;
            break;
        case OPT_THREADS:
            if (!cli_parse_u32(s.command, "--threads", value, 1, 256, &s.threads))
                return CLI_EXIT_USAGE;
            break;
        case OPT_REPS:
            if (!cli_parse_u32(s.command, "--reps", value, 1, 1000, &s.reps))
                return CLI_EXIT_USAGE;
            break;
        case OPT_BUDGET:
            if (!cli_parse_float(s.command, "--budget", value, 0.0f, 1e6f, &s.budget))
                return CLI_EXIT_USAGE;
            break;
        case OPT_CPU: s.cpu_clock = 1; break;
        case OPT_JSON: s.json_path = value; break;
        case OPT_NO_PEERS: s.no_peers = 1; break;
        case OPT_QUIET: quiet = 1; break;
        }
    }
    if (!input == !gen)
        return cli_usage_error(s.command, gen ? "give either INPUT or --gen, not both" : "no input (give INPUT or --gen SPEC)");
    progress_init(&s.prog, quiet);
    int status = bench_mesh_load(s.command, gen ? gen : input, gen != NULL, &s.mesh);
    if (!status)
        status = run(&s);
    destroy_peers(&s);
    cbvh_close(s.file);
    if (s.temp_path[0])
        unlink(s.temp_path);
    free(s.results);
    free(s.agreements);
    bench_mesh_free(&s.mesh);
    return status;
}
