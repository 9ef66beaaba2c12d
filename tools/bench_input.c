/* bench_input.c: loads the meshes `cbvh bench` and `cbvh report` measure (generated, mesh file or cooked cbvh
 * file). */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bench_input.h"
#include "temp_cleanup.h"
#include "cli.h"
#include "fd_io.h"
#include "cbvh_internal.h"
#include "import_assimp.h"
#include "support/scene_gen.h"

/* Takes over positions and indices, adding the padding float. */
static int adopt(bench_mesh *out, float *positions, size_t vertex_count, uint32_t *indices,
                 size_t triangle_count)
{
    float *padded = realloc(positions, (3 * vertex_count + 1) * sizeof(float));
    if (!padded) {
        free(positions);
        free(indices);
        return 0;
    }
    padded[3 * vertex_count] = 0.0f;
    out->positions = padded;
    out->vertex_count = vertex_count;
    out->indices = indices;
    out->triangle_count = triangle_count;
    return 1;
}

static int is_cbvh_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return 0;
    char magic[CBVH_MAGIC_BYTES];
    size_t n = fread(magic, 1, sizeof magic, f);
    fclose(f);
    return cbvh_has_magic(magic, n);
}

/* Drops the file's pages from the system's cache (written back first), so that the next open reads it from
 * disk, as a game loading a cooked file does: a mapping then gets what such a load gets (2 MiB pages where
 * the kernel gives them, cbvh_open_path), not the small pages a file just written sits in. Timings are
 * taken from later opens. Best effort: nothing where the system has no such advice. */
static void drop_cached_pages(int fd)
{
#ifdef POSIX_FADV_DONTNEED
    (void)fsync(fd);
    (void)posix_fadvise(fd, 0, 0, POSIX_FADV_DONTNEED);
#else
    (void)fd;
#endif
}

/* Rebuilds the indexed mesh a cooked file holds, ids as its queries report them. */
static int load_cbvh(const char *command, const char *path, bench_mesh *out)
{
    cbvh_file *file = NULL;
    cbvh_error err;
    const int fd = open(path, O_RDONLY);
    if (fd >= 0) {
        drop_cached_pages(fd);
        close(fd);
    }
    cbvh_result r = cbvh_open_path(path, NULL, &file, &err);
    if (r != CBVH_OK)
        return cli_report(command, path, &err);
    cbvh_file_info info;
    cbvh_file_get_info(file, &info, sizeof info);
    size_t nv = info.vertex_count, nt = info.original_triangle_count;
    float *positions = malloc((3 * nv + 1) * sizeof(float));
    uint32_t *indices = calloc(3 * nt, sizeof(uint32_t)); /* ids never stored stay (0,0,0): zero area */
    if (!positions || !indices) {
        free(positions);
        free(indices);
        cbvh_close(file);
        cli_error(command, path, "out of memory");
        return CLI_EXIT_USAGE;
    }
    cbvh_file_mesh(file, positions, indices);
    cbvh_close(file);
    if (!adopt(out, positions, nv, indices, nt)) {
        cli_error(command, path, "out of memory");
        return CLI_EXIT_USAGE;
    }
    out->is_cbvh = 1;
    out->cbvh_path = path;
    return 0;
}

int bench_mesh_load(const char *command, const char *source, int generated, bench_mesh *out)
{
    memset(out, 0, sizeof *out);
    out->name = source;
    if (!generated && !strncmp(source, "gen:", 4)) { /* the spelling `cbvh cook` accepts */
        source += 4;
        generated = 1;
    }
    if (generated) {
        scene s;
        if (!scene_from_spec(&s, source)) {
            cli_error(command, source,
                      "not a generated scene (expected sphere:N, terrain:N, cube, soup:N or demo), or out of "
                      "memory");
            return CLI_EXIT_USAGE;
        }
        free(s.material_ids);
        if (!adopt(out, s.positions, s.vertex_count, s.indices, s.triangle_count)) {
            cli_error(command, source, "out of memory");
            return CLI_EXIT_USAGE;
        }
        return 0;
    }
    if (is_cbvh_file(source))
        return load_cbvh(command, source, out);
    imported_mesh m;
    char message[512];
    int status = import_assimp(source, NULL, &m, message, sizeof message);
    if (status != 0) {
        cli_error(command, source, "%s", message);
        return status == 1 ? CLI_EXIT_BAD_INPUT : CLI_EXIT_USAGE;
    }
    free(m.material_ids);
    m.material_ids = NULL;
    if (m.triangle_count == 0) {
        imported_mesh_free(&m);
        cli_error(command, source, "the file holds no triangles");
        return CLI_EXIT_BAD_INPUT;
    }
    if (!adopt(out, m.positions, m.vertex_count, m.indices, m.triangle_count)) {
        cli_error(command, source, "out of memory");
        return CLI_EXIT_USAGE;
    }
    return 0;
}

void bench_mesh_free(bench_mesh *mesh)
{
    free(mesh->positions);
    free(mesh->indices);
    memset(mesh, 0, sizeof *mesh);
}

cbvh_mesh bench_mesh_view(const bench_mesh *mesh)
{
    cbvh_mesh m;
    memset(&m, 0, sizeof m);
    m.positions = mesh->positions;
    m.vertex_count = mesh->vertex_count;
    m.indices = mesh->indices;
    m.triangle_count = mesh->triangle_count;
    return m;
}

int bench_write_temp(const char *command, const void *data, size_t size, char *path, size_t path_size)
{
    const char *dir = getenv("TMPDIR");
    if (!dir || !*dir)
        dir = "/tmp";
    if ((size_t)snprintf(path, path_size, "%s/cbvh-bench-XXXXXX", dir) >= path_size) {
        cli_error(command, dir, "temporary folder name too long");
        return CLI_EXIT_USAGE;
    }
    int fd = mkstemp(path);
    if (fd < 0) {
        cli_error(command, path, "cannot create a temporary file: %s", strerror(errno));
        return CLI_EXIT_USAGE;
    }
    temp_cleanup_add(path, NULL);
    if (fd_write_all(fd, data, size) != 0) {
        cli_error(command, path, "cannot write the temporary file: %s", strerror(errno));
        close(fd);
        bench_remove_temp(path);
        return CLI_EXIT_USAGE;
    }
    drop_cached_pages(fd);
    if (close(fd) != 0) {
        cli_error(command, path, "cannot write the temporary file: %s", strerror(errno));
        bench_remove_temp(path);
        return CLI_EXIT_USAGE;
    }
    return 0;
}

void bench_remove_temp(const char *path)
{
    unlink(path);
    temp_cleanup_done(path);
}
