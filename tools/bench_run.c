/* bench_run.c: timing a batch of ray queries split across threads, the median of repetitions, and answer
 * agreement. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_run.h"
#include "cli.h"

#define BENCH_MAX_THREADS 256

static volatile unsigned bench_evict_sink;
static unsigned char bench_evict_buffer[BENCH_EVICT_BYTES];
static int bench_evict_written;

/* Reads one byte of every cache line of BENCH_EVICT_BYTES of memory no job uses. The first call writes it,
 * so that its pages are the process's own rather than the shared zero page. Called on one thread. */
static void bench_evict(void)
{
    if (!bench_evict_written) {
        memset(bench_evict_buffer, 1, sizeof bench_evict_buffer);
        bench_evict_written = 1;
    }
    unsigned sum = 0;
    for (size_t i = 0; i < sizeof bench_evict_buffer; i += 64)
        sum += bench_evict_buffer[i];
    bench_evict_sink = sum;
}

typedef struct slice {
    const bench_job *job;
    size_t begin, end;
    cbvh_query_stats *stats;
    double cpu_seconds; /* CPU time of the thread that ran the slice */
} slice;

static double clock_seconds(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double bench_clock(int cpu)
{
    return cpu ? clock_seconds(CLOCK_PROCESS_CPUTIME_ID) : cli_now();
}

static void run_slice(slice *s)
{
    const bench_job *j = s->job;
    double start = clock_seconds(CLOCK_THREAD_CPUTIME_ID);
    if (j->range)
        j->range(j->range_job, s->begin, s->end, s->stats);
    else
        j->kernel(j->engine, j->rays + s->begin, s->end - s->begin, j->hits ? j->hits + s->begin : NULL,
                  j->occluded ? j->occluded + s->begin : NULL, s->stats);
    s->cpu_seconds = clock_seconds(CLOCK_THREAD_CPUTIME_ID) - start;
}

static void *slice_thread(void *arg)
{
    run_slice(arg);
    return NULL;
}

double bench_run_once(const bench_job *job, unsigned threads, cbvh_query_stats *stats)
{
    if (threads < 1)
        threads = 1;
    if (threads > BENCH_MAX_THREADS)
        threads = BENCH_MAX_THREADS;
    slice slices[BENCH_MAX_THREADS];
    cbvh_query_stats counters[BENCH_MAX_THREADS];
    pthread_t ids[BENCH_MAX_THREADS];
    memset(counters, 0, sizeof(counters[0]) * threads);
    for (unsigned k = 0; k < threads; k++) {
        slices[k].job = job;
        slices[k].begin = job->first + job->count * k / threads;
        slices[k].end = job->first + job->count * (k + 1) / threads;
        slices[k].stats = stats ? &counters[k] : NULL;
    }
    double start = cli_now();
    if (threads == 1) {
        run_slice(&slices[0]);
    } else {
        unsigned started = 0;
        for (; started < threads; started++)
            if (pthread_create(&ids[started], NULL, slice_thread, &slices[started]) != 0)
                break;
        for (unsigned k = 0; k < started; k++)
            pthread_join(ids[k], NULL);
        if (started < threads)
            return -1.0;
    }
    double seconds = cli_now() - start;
    if (job->cpu_clock) {
        seconds = 0.0;
        for (unsigned k = 0; k < threads; k++)
            seconds = slices[k].cpu_seconds > seconds ? slices[k].cpu_seconds : seconds;
    }
    if (stats)
        for (unsigned k = 0; k < threads; k++) {
            stats->nodes_visited += counters[k].nodes_visited;
            stats->triangles_tested += counters[k].triangles_tested;
        }
    return seconds;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double bench_median(double *values, unsigned n)
{
    qsort(values, n, sizeof *values, compare_double);
    return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

int bench_time_in_turns(const bench_job *const *jobs, int n, unsigned threads, unsigned reps, double budget,
                        double *seconds, unsigned *runs)
{
    reps = reps < 1 ? 1 : reps;
    double *times = malloc((size_t)n * (reps + 2u) * sizeof *times);
    if (!times)
        return -2;
    double *round = times + (size_t)n * reps, *total = round + n; /* round: negative once out */
    size_t fewest = SIZE_MAX;
    for (int k = 0; k < n; k++) {
        runs[k] = 0;
        total[k] = 0.0;
        fewest = jobs[k]->count < fewest ? jobs[k]->count : fewest;
    }
    /* on more than one thread each job runs whole: a slice would add a thread start and join, and the wait
     * for the slower half of each slice (Wuson, two threads, wall clock: 15% fewer MRays/s for cbvh and
     * Embree) */
    const size_t slices = threads > 1u || fewest / BENCH_SLICE_QUERIES < 1 ? 1
                          : fewest / BENCH_SLICE_QUERIES > BENCH_SLICES    ? BENCH_SLICES
                                                                           : fewest / BENCH_SLICE_QUERIES;
    int status = 0;
    for (unsigned r = 0; r < reps && status == 0; r++) {
        for (int k = 0; k < n; k++)
            round[k] = r > 0 && budget > 0.0 && total[k] > budget ? -1.0 : 0.0;
        for (size_t i = 0; i < slices && status == 0; i++)
            for (size_t j = 0; j < (size_t)n && status == 0; j++) {
                const size_t k = (j + i) % (size_t)n, timed = (i + k) % slices;
                if (round[k] < 0.0)
                    continue;
                /* the caches emptied of every structure, then another slice first, untimed: each job's timed
                 * slice finds its own structure as far as one slice brings it back, after any job */
                const bench_job *job = jobs[k];
                if (slices > 1u)
                    bench_evict();
                bench_job part = *job;
                const size_t warm = (timed + slices / 2u) % slices;
                part.first = job->first + job->count * warm / slices;
                part.count = job->first + job->count * (warm + 1u) / slices - part.first;
                double x = slices > 1u ? bench_run_once(&part, threads, NULL) : 0.0;
                part.first = job->first + job->count * timed / slices;
                part.count = job->first + job->count * (timed + 1u) / slices - part.first;
                if (x >= 0.0)
                    x = bench_run_once(&part, threads, NULL);
                if (x < 0.0)
                    status = -1;
                else
                    round[k] += x;
            }
        for (int k = 0; k < n && status == 0; k++)
            if (round[k] >= 0.0) {
                times[(size_t)k * reps + runs[k]++] = round[k];
                total[k] += round[k];
            }
    }
    for (int k = 0; k < n && status == 0; k++)
        seconds[k] = bench_median(times + (size_t)k * reps, runs[k]);
    free(times);
    return status;
}

double bench_open_median(const char *command, const char *path, unsigned reps, int cpu_clock,
                         cbvh_file **keep, int *status)
{
    double times[64];
    unsigned n = reps < 1 ? 1 : reps > 64 ? 64 : reps;
    for (unsigned r = 0; r < n; r++) {
        cbvh_file *f = NULL;
        double start = bench_clock(cpu_clock);
        *status = cli_open(command, path, &f);
        times[r] = bench_clock(cpu_clock) - start;
        if (*status)
            return 0.0;
        if (keep && r + 1 == n)
            *keep = f;
        else
            cbvh_close(f);
    }
    return bench_median(times, n);
}

double bench_open_expanded(const char *command, const char *path, int cpu_clock, cbvh_file **out, int *status)
{
    *status = cli_open(command, path, out);
    if (*status)
        return 0.0;
    cbvh_error err;
    const double start = bench_clock(cpu_clock);
    if (cbvh_file_expand_triangles(*out, &err) != CBVH_OK) {
        *status = cli_report(command, path, &err);
        cbvh_close(*out);
        *out = NULL;
        return 0.0;
    }
    return bench_clock(cpu_clock) - start;
}

void bench_cbvh_variant(bench_cbvh *e, const cbvh_file *file, const cbvh_file *expanded, int k)
{
    static const struct {
        const char *name;
        cbvh_traversal traversal;
        int stream, expanded;
    } variants[BENCH_CBVH_VARIANTS] = {
        {"sorted", CBVH_TRAVERSAL_SORTED, 0, 0},       {"unsorted", CBVH_TRAVERSAL_UNSORTED, 0, 0},
        {"stackless", CBVH_TRAVERSAL_STACKLESS, 0, 0}, {"distance", CBVH_TRAVERSAL_DISTANCE, 0, 0},
        {"stream", CBVH_TRAVERSAL_SORTED, 1, 0},       {"expanded", CBVH_TRAVERSAL_SORTED, 0, 1},
    };
    e->file = variants[k].expanded ? expanded : file;
    e->traversal = variants[k].traversal;
    e->stream = variants[k].stream;
    e->name = variants[k].name;
}

void bench_cbvh_kernel(const void *engine, const cbvh_ray *rays, size_t count, cbvh_hit *hits,
                       uint8_t *occluded, cbvh_query_stats *stats)
{
    const bench_cbvh *e = engine;
    if (e->stream) {
        /* batches of BENCH_STREAM_BATCH rays in scratch of this call's own (threads run calls at once); the
         * plain cbvh_raycast_stream batches 24 rays on its stack */
        const size_t size = cbvh_stream_scratch_size(BENCH_STREAM_BATCH);
        void *scratch = malloc(size);
        if (hits)
            cbvh_raycast_stream_scratch(e->file, rays, count, hits, stats, scratch, scratch ? size : 0);
        else
            cbvh_occluded_stream_scratch(e->file, rays, count, occluded, stats, scratch, scratch ? size : 0);
        free(scratch);
        return;
    }
    if (hits)
        for (size_t i = 0; i < count; i++)
            cbvh_raycast(e->file, &rays[i], e->traversal, &hits[i], stats);
    else
        for (size_t i = 0; i < count; i++)
            occluded[i] = (uint8_t)cbvh_occluded(e->file, &rays[i], e->traversal, stats);
}

void bench_agree_one(bench_agreement *a, uint32_t tri_ref, uint32_t tri_other, double distance,
                     double tolerance)
{
    int hit_ref = tri_ref != CBVH_NO_HIT, hit_other = tri_other != CBVH_NO_HIT;
    if (!hit_ref && !hit_other)
        a->both_miss++;
    else if (hit_ref != hit_other || !(distance <= tolerance))
        a->disagree++;
    else if (tri_ref == tri_other)
        a->same_triangle++;
    else
        a->t_close++;
}
