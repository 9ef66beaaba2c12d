/* raycast_loop.c: the C library's own throughput on a file of rays, for raycast_throughput.py: the rays
 * (cbvh_ray records) go through cbvh_raycast_stream_scratch in one call with batches of 1024, as
 * cbvh.File.raycast sends them. Prints the best of `repeats` runs in seconds of the process's CPU time and a
 * checksum of the hits. */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "cbvh.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: raycast_loop FILE.cbvh RAYS.bin REPEATS\n");
        return 2;
    }
    cbvh_file *file;
    cbvh_error err;
    if (cbvh_open_path_read(argv[1], NULL, &file, &err) != CBVH_OK) {
        fprintf(stderr, "%s: %s\n", argv[1], err.message);
        return 1;
    }
    FILE *f = fopen(argv[2], "rb");
    if (!f || fseek(f, 0, SEEK_END) != 0) {
        perror(argv[2]);
        return 1;
    }
    const size_t count = (size_t)ftell(f) / sizeof(cbvh_ray);
    rewind(f);
    cbvh_ray *rays = malloc(count * sizeof *rays);
    cbvh_hit *hits = malloc(count * sizeof *hits);
    const size_t scratch_size = cbvh_stream_scratch_size(1024);
    void *scratch = malloc(scratch_size);
    if (!rays || !hits || !scratch || fread(rays, sizeof *rays, count, f) != count) {
        fprintf(stderr, "%s: cannot read the rays\n", argv[2]);
        return 1;
    }
    fclose(f);
    double best = 1e300;
    for (int r = 0; r < atoi(argv[3]); r++) {
        const double t0 = now();
        cbvh_raycast_stream_scratch(file, rays, count, hits, NULL, scratch, scratch_size);
        const double seconds = now() - t0;
        best = seconds < best ? seconds : best;
    }
    unsigned long long sum = 0;
    for (size_t i = 0; i < count; i++)
        sum += hits[i].tri;
    printf("%.6f %llu\n", best, sum);
    free(rays);
    free(hits);
    free(scratch);
    cbvh_close(file);
    return 0;
}
