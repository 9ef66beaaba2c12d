/* bench_input.h: the meshes `cbvh bench` and `cbvh report` measure: a generated scene, a mesh file or a
 * cooked .cbvh file. */
#ifndef CBVH_TOOLS_BENCH_INPUT_H
#define CBVH_TOOLS_BENCH_INPUT_H

#include <stddef.h>
#include <stdint.h>

#include "cbvh.h"

/* An indexed mesh owned by the tool. Triangle i is the triangle cbvh queries
 * report as original id i. positions is padded by one float past the last
 * vertex (Embree reads vertices with 16-byte loads). */
typedef struct bench_mesh {
    float *positions;
    size_t vertex_count;
    uint32_t *indices;
    size_t triangle_count;
    const char *name; /* the spec or path it came from (not owned) */
    int is_cbvh;      /* loaded from a cooked file: cbvh_path is that file */
    const char *cbvh_path;
} bench_mesh;

/* Loads `source`: a generated scene spec (sphere:N, terrain:N, cube, soup:N, demo)
 * when `generated` is nonzero or source starts with "gen:", else a cooked cbvh file (recognized by its magic)
 * or any mesh file assimp reads. From a cbvh file the mesh is the decoded
 * triangles under their original ids (dropped degenerate ids become
 * zero-area triangles, which no engine hits). Reports errors as
 * "cbvh COMMAND: SOURCE: ..." and returns a cli exit status (0 on success). */
int bench_mesh_load(const char *command, const char *source, int generated, bench_mesh *out);

void bench_mesh_free(bench_mesh *mesh);

/* The mesh as cbvh_cook takes it. */
cbvh_mesh bench_mesh_view(const bench_mesh *mesh);

/* Writes `size` bytes to a new temporary file (in $TMPDIR or /tmp) and stores its
 * path in path[path_size], its pages dropped from the system's cache (read from disk at the first open,
 * as a game loading the file does). Returns 0 on success, else reports and returns an exit status. The file
 * is removed if SIGINT, SIGTERM or SIGHUP ends the command before bench_remove_temp does. */
int bench_write_temp(const char *command, const void *data, size_t size, char *path, size_t path_size);

/* Removes a file bench_write_temp made. */
void bench_remove_temp(const char *path);

#endif
