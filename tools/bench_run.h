/* bench_run.h: timing a batch of ray queries split across threads, the median of repetitions, and answer
 * agreement. */
#ifndef CBVH_TOOLS_BENCH_RUN_H
#define CBVH_TOOLS_BENCH_RUN_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"

/* Runs rays[0..count) through one engine: closest hits into hits[], or any-hit
 * flags into occluded[] (the other pointer is NULL). stats is NULL on timed
 * runs; counted runs pass one per thread. */
typedef void (*bench_kernel)(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                             uint8_t *occluded, cbvh_query_stats *stats);

/* Runs queries [begin, end) of a job of another kind (shape queries): `job` is bench_job.range_job. */
typedef void (*bench_range_fn)(const void *job, size_t begin, size_t end, cbvh_query_stats *stats);

typedef struct bench_job {
    bench_kernel kernel; /* rays, or NULL for a job `range` runs */
    const void *engine;
    const cbvh_ray *rays;
    size_t count;
    cbvh_hit *hits;    /* closest hit queries, else NULL */
    uint8_t *occluded; /* any-hit queries, else NULL */
    int cpu_clock;     /* time with the threads' CPU clocks instead of the wall clock */
    bench_range_fn range;
    const void *range_job;
    size_t first; /* the job's queries are [first, first + count): rays[first...], hits[first...] */
} bench_job;

/* Seconds on the wall clock, or with cpu nonzero the CPU time of the whole
 * process: on a loaded machine it leaves out the time other programs ran. */
double bench_clock(int cpu);

/* Runs the job once with its queries split into `threads` contiguous slices, one
 * thread each (inline when threads is 1). Returns the wall time in seconds (with
 * job->cpu_clock, the CPU time of the slowest thread), or a negative value when
 * a thread cannot be started. With stats non-NULL the
 * kernel counts and the per-thread counters are summed into *stats. */
double bench_run_once(const bench_job *job, unsigned threads, cbvh_query_stats *stats);

/* Times *jobs[0..n) in turns on `threads` threads: up to `reps` rounds (reps >= 1), each cutting every job's
 * queries into the same slices (up to BENCH_SLICES, of at least BENCH_SLICE_QUERIES queries; one, the whole
 * job, on more than one thread) and running the jobs in turn slice by slice, each after reading
 * BENCH_EVICT_BYTES of other memory (caches holding no job's structure), first on another slice untimed
 * (its own structure back in the caches), then on its timed slice; job k
 * times slice i + k, so that two jobs in a row never run the same queries (a traversal after another of the
 * same file on the same rays finds them in the caches). A job leaves the rounds once its rounds took `budget`
 * seconds (0: no limit). seconds[k] receives the median of job k's rounds, runs[k] their number. The jobs so
 * share the same stretches of time at a grain of milliseconds: a slow spell of a shared machine moves all of
 * them, and their ratios hold. Returns 0, -1 when a thread cannot be started, -2 out of memory. */
#define BENCH_SLICE_QUERIES 1024u
#define BENCH_SLICES 16u
/* More memory than a last-level cache holds. */
#define BENCH_EVICT_BYTES ((size_t)64 << 20)
int bench_time_in_turns(const bench_job *const *jobs, int n, unsigned threads, unsigned reps, double budget,
                        double *seconds, unsigned *runs);

/* Sorts values[0..n) and returns their median (n >= 1). */
double bench_median(double *values, unsigned n);

/* Opens and closes the cbvh file at `path` `reps` times (a failure is reported
 * as "cbvh COMMAND: PATH: ..." and its exit status stored in *status, else 0).
 * Returns the median seconds of an open (bench_clock(cpu_clock)). With keep
 * non-NULL the file of the last open stays open in *keep. */
double bench_open_median(const char *command, const char *path, unsigned reps, int cpu_clock,
                         cbvh_file **keep, int *status);

/* cbvh as an engine: one traversal of an opened file, or its batched streams. */
typedef struct bench_cbvh {
    const cbvh_file *file;
    cbvh_traversal traversal;
    int stream;
    const char *name; /* "sorted", "unsorted", "stackless", "distance", "stream", "expanded" */
} bench_cbvh;

#define BENCH_CBVH_VARIANTS 6
/* Rays per batch of the stream variant (cbvh_raycast_stream_scratch). */
#define BENCH_STREAM_BATCH 1024

/* Sets *e to variant k (0 <= k < BENCH_CBVH_VARIANTS; 0 is sorted, the default traversal) of file; the
 * "expanded" variant is the sorted traversal of `expanded`, the same file opened again and expanded
 * (cbvh_file_expand_triangles, bench_open_expanded). */
void bench_cbvh_variant(bench_cbvh *e, const cbvh_file *file, const cbvh_file *expanded, int k);

/* Opens path again and expands its triangles: returns the seconds (bench_clock) of the expansion alone and
 * leaves the file in *out; on failure reports it and sets *status (CLI_EXIT_*). */
double bench_open_expanded(const char *command, const char *path, int cpu_clock, cbvh_file **out,
                           int *status);

/* A bench_kernel whose engine is a bench_cbvh. */
void bench_cbvh_kernel(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                       uint8_t *occluded, cbvh_query_stats *stats);

/* How a peer's (or variant's) answers compare with the reference answers, ray by ray. */
typedef struct bench_agreement {
    uint64_t same_triangle; /* both hit the same triangle at t within the tolerance */
    uint64_t both_miss;
    uint64_t t_close;  /* both hit, other triangles, t within the tolerance (a shared edge or vertex) */
    uint64_t disagree; /* hit against miss, or t apart by more than the tolerance */
} bench_agreement;

/* Adds one comparison: whether each answer hit, the triangles, and how far apart the two hits' t lie as a
 * distance (ignored unless both hit). */
void bench_agree_one(bench_agreement *a, uint32_t tri_ref, uint32_t tri_other, double distance,
                     double tolerance);

#endif
