/* cmd_raycast.c: `cbvh raycast`: rays from stdin (text lines or binary records), hits to stdout. */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"

static const char usage[] =
    "Usage: cbvh raycast [OPTIONS] FILE\n"
    "\n"
    "Casts the rays read from standard input against the cbvh file FILE and writes one result\n"
    "per ray to standard output, in input order.\n"
    "\n"
    "Text input: one ray per line, 6 or 8 numbers separated by blanks:\n"
    "    ox oy oz dx dy dz [tmin tmax]\n"
    "  tmin defaults to 0 and tmax to inf. Blank lines are skipped (they get no result). A line\n"
    "  with another number of fields or a field that\n"
    "  is not a number is an error (\"line N: ...\", exit status 1); the results of the lines\n"
    "  before it have been written. A ray the library calls invalid (NaN, zero direction,\n"
    "  tmin > tmax, ...) is a miss.\n"
    "Text output: 'TRI T U V' for a hit (original triangle id, distance in units of the\n"
    "  direction, barycentrics; %.9g) or '-1' for a miss. With --any: '1' (occluded) or '0'.\n"
    "\n"
    "Binary input (--binary): records of 8 little-endian binary32 floats:\n"
    "    ox oy oz tmin dx dy dz tmax         (32 bytes per ray)\n"
    "Binary output: per ray a little-endian u32 triangle id (0xFFFFFFFF for a miss) and\n"
    "  binary32 t, u, v (16 bytes); with --any one byte per ray, 1 or 0. Input that is not a\n"
    "  whole number of records is an error (exit status 1) after the whole records are answered.\n"
    "\n"
    "Options:\n"
    "  --any                   any-hit (occlusion) queries instead of closest hit\n"
    "  --traversal KIND        sorted (default: nearer child by the precomputed sort byte),\n"
    "                          stackless (escape links), unsorted, distance (nearer child by\n"
    "                          box distance at run time), stream (each 4096 rays read\n"
    "                          go to cbvh_raycast_stream_scratch, batches of up to 1024)\n"
    "  --binary                binary records in and out, see above\n"
    "  --json                  text output as one JSON object a line: {\"hit\": true,\n"
    "                          \"triangle\", \"t\", \"u\", \"v\"} or {\"hit\": false}; with --any\n"
    "                          {\"occluded\": true|false}; a failure prints {\"command\",\n"
    "                          \"error\": {\"status\", \"file\", \"message\"}}\n"
    "  --expand-triangles      copy the triangles into the form the ray test reads first\n"
    "                          (cbvh_file_expand_triangles: 36 bytes a triangle; same answers)\n"
    "  -h, --help              show this help\n"
    "\n"
    "Exit status: 0 success, 1 corrupt file or bad ray input, 2 usage or I/O error.\n";

#define RAYCAST_BATCH 4096
#define RAYCAST_STREAM_BATCH 1024
#define TRAVERSAL_STREAM (-1)

typedef struct raycast_job {
    const cbvh_file *file;
    int traversal; /* cbvh_traversal, or TRAVERSAL_STREAM */
    int any;
    int binary;
    int json; /* text output as one JSON object per ray */
    cbvh_ray rays[RAYCAST_BATCH];
    cbvh_hit hits[RAYCAST_BATCH];
    uint8_t occluded[RAYCAST_BATCH];
    void *scratch; /* the stream's batch memory (NULL: the library's own, smaller batch on its stack) */
    size_t scratch_size;
} raycast_job;

static void put_u32le(uint8_t *b, uint32_t v)
{
    b[0] = (uint8_t)v;
    b[1] = (uint8_t)(v >> 8);
    b[2] = (uint8_t)(v >> 16);
    b[3] = (uint8_t)(v >> 24);
}

static uint32_t get_u32le(const uint8_t *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float get_f32le(const uint8_t *b)
{
    uint32_t u = get_u32le(b);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static void put_f32le(uint8_t *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    put_u32le(b, u);
}

/* Answers rays[0..count) and writes the results. */
static void raycast_batch(raycast_job *job, size_t count)
{
    if (count == 0)
        return;
    if (job->traversal == TRAVERSAL_STREAM) {
        if (job->any)
            cbvh_occluded_stream_scratch(job->file, job->rays, count, job->occluded, NULL, job->scratch,
                                         job->scratch_size);
        else
            cbvh_raycast_stream_scratch(job->file, job->rays, count, job->hits, NULL, job->scratch,
                                        job->scratch_size);
    } else {
        cbvh_traversal tr = (cbvh_traversal)job->traversal;
        for (size_t i = 0; i < count; i++) {
            if (job->any)
                job->occluded[i] = (uint8_t)(cbvh_occluded(job->file, &job->rays[i], tr, NULL) != 0);
            else
                cbvh_raycast(job->file, &job->rays[i], tr, &job->hits[i], NULL);
        }
    }
    for (size_t i = 0; i < count; i++) {
        const cbvh_hit *h = &job->hits[i];
        if (job->binary && job->any) {
            putchar(job->occluded[i]);
        } else if (job->binary) {
            uint8_t rec[16];
            put_u32le(rec, h->tri);
            put_f32le(rec + 4, h->t);
            put_f32le(rec + 8, h->u);
            put_f32le(rec + 12, h->v);
            fwrite(rec, 1, sizeof rec, stdout);
        } else if (job->json && job->any) {
            puts(job->occluded[i] ? "{\"occluded\": true}" : "{\"occluded\": false}");
        } else if (job->json && h->tri == CBVH_NO_HIT) {
            puts("{\"hit\": false}");
        } else if (job->json) {
            printf("{\"hit\": true, \"triangle\": %u, \"t\": %.9g, \"u\": %.9g, \"v\": %.9g}\n",
                   (unsigned)h->tri, h->t, h->u, h->v);
        } else if (job->any) {
            puts(job->occluded[i] ? "1" : "0");
        } else if (h->tri == CBVH_NO_HIT) {
            puts("-1");
        } else {
            printf("%u %.9g %.9g %.9g\n", (unsigned)h->tri, h->t, h->u, h->v);
        }
    }
}

/* Parses one text line into a ray; on error writes the reason to `why`. */
static int parse_ray_line(const char *line, cbvh_ray *ray, char *why, size_t why_size)
{
    float v[8] = {0, 0, 0, 0, 0, 0, 0, INFINITY};
    int n = 0;
    const char *s = line;
    for (;;) {
        while (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\n')
            s++;
        if (!*s)
            break;
        if (n == 8) {
            snprintf(why, why_size, "more than 8 fields (expected ox oy oz dx dy dz [tmin tmax])");
            return 0;
        }
        char *end;
        errno = 0;
        float x = strtof(s, &end);
        /* ERANGE for a denormal is fine (the value is still the nearest float); overflow to inf is
         * as the user wrote it. A field must end at a blank or the end of the line. */
        if (end == s || (*end && !isspace((unsigned char)*end))) {
            int len = 0;
            while (s[len] && !isspace((unsigned char)s[len]) && len < 40)
                len++;
            snprintf(why, why_size, "field %d '%.*s' is not a number", n + 1, len, s);
            return 0;
        }
        v[n++] = x;
        s = end;
    }
    if (n != 6 && n != 8) {
        snprintf(why, why_size, "%d field%s, expected 6 or 8 (ox oy oz dx dy dz [tmin tmax])", n,
                 n == 1 ? "" : "s");
        return 0;
    }
    ray->org[0] = v[0];
    ray->org[1] = v[1];
    ray->org[2] = v[2];
    ray->dir[0] = v[3];
    ray->dir[1] = v[4];
    ray->dir[2] = v[5];
    ray->tmin = n == 8 ? v[6] : 0.0f;
    ray->tmax = n == 8 ? v[7] : INFINITY;
    return 1;
}

static int raycast_text(raycast_job *job)
{
    char *line = NULL;
    size_t cap = 0, count = 0, line_no = 0;
    int rc = CLI_EXIT_OK;
    for (;;) {
        errno = 0;
        ssize_t len = getline(&line, &cap, stdin);
        if (len < 0) {
            if (ferror(stdin)) {
                cli_error("raycast", "<stdin>", "read error: %s", strerror(errno));
                rc = CLI_EXIT_USAGE;
            }
            break;
        }
        line_no++;
        char why[128];
        if (strspn(line, " \t\r\n") == (size_t)len)
            continue; /* a blank line holds no ray (a trailing empty line, a separator) */
        if ((size_t)len != strlen(line)) {
            snprintf(why, sizeof why, "contains a NUL byte");
        } else if (parse_ray_line(line, &job->rays[count], why, sizeof why)) {
            if (++count == RAYCAST_BATCH) {
                raycast_batch(job, count);
                count = 0;
            }
            continue;
        }
        raycast_batch(job, count); /* the lines before the bad one still get their answers */
        count = 0;
        fflush(stdout);
        cli_error("raycast", "<stdin>", "line %zu: %s", line_no, why);
        rc = CLI_EXIT_BAD_INPUT;
        break;
    }
    raycast_batch(job, count);
    free(line);
    return rc;
}

static int raycast_binary(raycast_job *job)
{
    static uint8_t buf[RAYCAST_BATCH * 32];
    size_t have = 0;
    for (;;) {
        size_t n = fread(buf + have, 1, sizeof buf - have, stdin);
        have += n;
        if (n == 0 || have == sizeof buf) {
            size_t count = have / 32;
            for (size_t i = 0; i < count; i++) {
                const uint8_t *r = buf + 32 * i;
                cbvh_ray *ray = &job->rays[i];
                for (int a = 0; a < 3; a++) {
                    ray->org[a] = get_f32le(r + 4 * a);
                    ray->dir[a] = get_f32le(r + 16 + 4 * a);
                }
                ray->tmin = get_f32le(r + 12);
                ray->tmax = get_f32le(r + 28);
            }
            raycast_batch(job, count);
            have -= count * 32;
        }
        if (n == 0)
            break;
    }
    if (ferror(stdin)) {
        cli_error("raycast", "<stdin>", "read error: %s", strerror(errno));
        return CLI_EXIT_USAGE;
    }
    if (have) {
        fflush(stdout);
        cli_error("raycast", "<stdin>", "%zu trailing bytes: binary rays are records of 32 bytes", have);
        return CLI_EXIT_BAD_INPUT;
    }
    return CLI_EXIT_OK;
}

static int parse_traversal(const char *name, int *out)
{
    static const struct {
        const char *name;
        int value;
    } kinds[] = {{"sorted", CBVH_TRAVERSAL_SORTED},
                 {"stackless", CBVH_TRAVERSAL_STACKLESS},
                 {"unsorted", CBVH_TRAVERSAL_UNSORTED},
                 {"distance", CBVH_TRAVERSAL_DISTANCE},
                 {"stream", TRAVERSAL_STREAM}};
    for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++)
        if (!strcmp(name, kinds[i].name)) {
            *out = kinds[i].value;
            return 1;
        }
    return 0;
}

int cmd_raycast(int argc, char **argv)
{
    enum { OPT_ANY = 1, OPT_TRAVERSAL, OPT_BINARY, OPT_EXPAND, OPT_JSON };
    static const cli_option options[] = {
        {"any", CLI_ARG_NONE, OPT_ANY},       {"traversal", CLI_ARG_REQUIRED, OPT_TRAVERSAL},
        {"binary", CLI_ARG_NONE, OPT_BINARY}, {"expand-triangles", CLI_ARG_NONE, OPT_EXPAND},
        {"json", CLI_ARG_NONE, OPT_JSON},     {NULL, 0, 0},
    };
    static raycast_job job; /* large: keep it off the stack */
    job.traversal = CBVH_TRAVERSAL_SORTED;
    cli_parser p;
    cli_init(&p, "raycast", usage, argc, argv);
    const char *path = NULL, *value;
    int id, expand = 0;
    while ((id = cli_next(&p, options, &value)) != CLI_END) {
        switch (id) {
        case CLI_DONE:
            return CLI_EXIT_OK;
        case CLI_ERROR:
            return CLI_EXIT_USAGE;
        case OPT_ANY:
            job.any = 1;
            break;
        case OPT_BINARY:
            job.binary = 1;
            break;
        case OPT_EXPAND:
            expand = 1;
            break;
        case OPT_JSON:
            job.json = 1;
            break;
        case OPT_TRAVERSAL:
            if (!parse_traversal(value, &job.traversal))
                return cli_usage_error("raycast",
                                       "--traversal: '%s' is not one of sorted, stackless, unsorted, "
                                       "distance, stream",
                                       value);
            break;
        default:
            if (path)
                return cli_usage_error("raycast", "unexpected argument '%s'", value);
            path = value;
        }
    }
    if (!path)
        return cli_usage_error("raycast", "expected a file");
    if (job.json && job.binary)
        return cli_usage_error("raycast", "--json and --binary exclude each other");
    cbvh_file *file;
    int rc = cli_open("raycast", path, &file);
    if (rc)
        return rc;
    cbvh_error err;
    if (expand && cbvh_file_expand_triangles(file, &err) != CBVH_OK) {
        rc = cli_report("raycast", path, &err);
        cbvh_close(file);
        return rc;
    }
    job.file = file;
    if (job.traversal == TRAVERSAL_STREAM) {
        job.scratch_size = cbvh_stream_scratch_size(RAYCAST_STREAM_BATCH);
        job.scratch = malloc(job.scratch_size);
    }
    rc = job.binary ? raycast_binary(&job) : raycast_text(&job);
    free(job.scratch);
    cbvh_close(file);
    return rc;
}
