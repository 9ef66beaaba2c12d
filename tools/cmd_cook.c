/* cmd_cook.c: `cbvh cook`: import a mesh file (or generate a scene), cook it, write the .cbvh file atomically. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include "cli.h"
#include "common/format.h"
#include "commands.h"
#include "import_assimp.h"
#include "json.h"
#include "progress.h"
#include "support/scene_gen.h"

static const char usage[] =
    "Usage: cbvh cook [OPTIONS] IN OUT\n"
    "\n"
    "Cooks the triangles of IN into the cbvh file OUT. IN is any mesh file assimp reads\n"
    "(OBJ, PLY, STL, glTF/GLB, FBX, DAE, 3DS, IFC, ...; NAME.EXT.gz is inflated first) or a\n"
    "generated scene: gen:sphere:N, gen:terrain:N, gen:soup:N, gen:cube, gen:demo.\n"
    "All meshes of the scene are merged with their node transforms applied, depth-first over\n"
    "the node hierarchy (a node's meshes in order, then its children in order), triangles in\n"
    "mesh order: that order gives the original triangle ids that queries report. The material\n"
    "id of a triangle is its mesh's assimp material index. Points and lines are dropped.\n"
    "OUT is written through a temporary file renamed into place: an existing OUT is replaced\n"
    "only by a complete file, and nothing is left behind on failure.\n"
    "\n"
    "Options:\n"
    "  --layout KIND           node layout: wide4 (4 children per 64-byte node, tested with\n"
    "                          SIMD; the default) or binary (2 children per 16-byte node,\n"
    "                          escape links for the stackless walk)\n"
    "  --leaf-size N           at most N triangles per leaf, 1..16 (default 16); a wide4\n"
    "                          leaf holds at most 8, so there N > 8 acts as 8\n"
    "  --bins N                SAH bins per axis, 4..256 (default 32)\n"
    "  --traversal-cost C      SAH cost of a node visit (default 4)\n"
    "  --intersection-cost C   SAH cost of a triangle test (default 1)\n"
    "  --compress[=LEVEL]      zlib-compress the sections, LEVEL 1..9 (default 6)\n"
    "  --quantize-vertices     store vertices as 16-bit grid coordinates (lossy; the error\n"
    "                          is reported)\n"
    "  --no-remap              do not store original triangle ids: queries report cooked ids\n"
    "  --no-materials          do not store material ids\n"
    "  --quiet                 no progress display (it is shown only on a terminal anyway)\n"
    "  --json                  print statistics as JSON on stdout; a failed cook prints\n"
    "                          {\"input\", \"output\", \"error\": {\"status\", \"message\"}}\n"
    "  --max-memory MB         stop an import or cook that would hold more than MB megabytes\n"
    "                          of address space (exit status 1); default 1024 + 64 x the\n"
    "                          input file's size in MB; 0: no limit\n"
    "  -h, --help              show this help\n"
    "\n"
    "OUT must not be IN itself (also through a link): that is refused, exit status 2. An OUT\n"
    "that is a device, a FIFO or a folder is refused likewise; an OUT that is a symbolic link\n"
    "is replaced by the new file, and the file it pointed to stays as it was. A new OUT gets\n"
    "mode 0666 less the umask; a replaced one keeps its mode. Interrupted (SIGINT, SIGTERM,\n"
    "SIGHUP), a cook leaves no temporary file behind.\n"
    "\n"
    "Exit status: 0 cooked, 1 the input is not a usable mesh, 2 usage or I/O error.\n";

enum {
    OPT_LEAF = 1,
    OPT_LAYOUT,
    OPT_BINS,
    OPT_TCOST,
    OPT_ICOST,
    OPT_COMPRESS,
    OPT_QUANTIZE,
    OPT_NO_REMAP,
    OPT_NO_MATERIALS,
    OPT_QUIET,
    OPT_JSON,
    OPT_MAX_MEMORY
};

static const cli_option options[] = {
    { "leaf-size", CLI_ARG_REQUIRED, OPT_LEAF },
    { "layout", CLI_ARG_REQUIRED, OPT_LAYOUT },
    { "bins", CLI_ARG_REQUIRED, OPT_BINS },
    { "traversal-cost", CLI_ARG_REQUIRED, OPT_TCOST },
    { "intersection-cost", CLI_ARG_REQUIRED, OPT_ICOST },
    { "compress", CLI_ARG_OPTIONAL, OPT_COMPRESS },
    { "quantize-vertices", CLI_ARG_NONE, OPT_QUANTIZE },
    { "no-remap", CLI_ARG_NONE, OPT_NO_REMAP },
    { "no-materials", CLI_ARG_NONE, OPT_NO_MATERIALS },
    { "quiet", CLI_ARG_NONE, OPT_QUIET },
    { "json", CLI_ARG_NONE, OPT_JSON },
    { "max-memory", CLI_ARG_REQUIRED, OPT_MAX_MEMORY },
    { NULL, 0, 0 },
};

/* The mesh to cook, whichever way it was obtained. */
typedef struct cook_input {
    imported_mesh mesh;
    int generated;
} cook_input;

/* Returns an exit status; on success `in` holds the mesh, else `message` says why. */
static int load_input(const char *path, cook_input *in, char *message, size_t message_size)
{
    memset(in, 0, sizeof *in);
    if (!strncmp(path, "gen:", 4)) {
        scene s;
        if (!scene_from_spec(&s, path + 4)) {
            snprintf(message, message_size, "not a generated scene (gen:sphere:N, gen:terrain:N, gen:soup:N, "
                                            "gen:cube, gen:demo)");
            return CLI_EXIT_USAGE;
        }
        in->generated = 1;
        in->mesh.positions = s.positions;
        in->mesh.vertex_count = s.vertex_count;
        in->mesh.indices = s.indices;
        in->mesh.material_ids = s.material_ids;
        in->mesh.triangle_count = s.triangle_count;
        in->mesh.mesh_instances = 1;
        return CLI_EXIT_OK;
    }
    return import_assimp(path, &in->mesh, message, message_size);
}

/* A failed cook: the message on standard error, and with --json also as JSON on standard output. */
static int report_failure(int json, const char *in, const char *out, const char *file, int status,
                          const char *message)
{
    cli_error("cook", file, "%s", message);
    if (json) {
        json_writer w;
        json_init(&w, stdout);
        json_begin_object(&w, NULL);
        json_string(&w, "input", in);
        json_string(&w, "output", out);
        json_begin_object(&w, "error");
        json_uint(&w, "status", (uint64_t)status);
        json_string(&w, "file", file);
        json_string(&w, "message", message);
        json_end_object(&w);
        json_end_object(&w);
        json_finish(&w);
    }
    return status;
}

/* Refuses an output that is the input itself (same device and inode, whatever the names and links). */
static int same_file(const char *in, const char *out)
{
    struct stat a, b;
    return stat(in, &a) == 0 && stat(out, &b) == 0 && a.st_dev == b.st_dev && a.st_ino == b.st_ino;
}

/* Caps the address space at `megabytes` (0: no cap); the default grows with the input file's size. */
static void limit_memory(const char *in, uint64_t megabytes, int given)
{
    struct stat st;
    if (!given)
        megabytes = 1024 + (stat(in, &st) == 0 ? 64 * ((uint64_t)st.st_size >> 20) : 0);
    if (megabytes == 0 || !strncmp(in, "gen:", 4))
        return;
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) != 0)
        return;
    rlim_t want = (rlim_t)(megabytes << 20);
    if (rl.rlim_max != RLIM_INFINITY && want > rl.rlim_max)
        want = rl.rlim_max;
    if (rl.rlim_cur == RLIM_INFINITY || want < rl.rlim_cur) {
        rl.rlim_cur = want;
        (void)setrlimit(RLIMIT_AS, &rl);
    }
}

static void print_json(const char *in, const char *out, const cook_input *input, const cbvh_cook_stats *st,
                       double import_seconds, double total_seconds)
{
    static const char *const phase_names[] = { "prepare", "build", "layout", "write" };
    double per_tri = st->triangles ? 1.0 / (double)st->triangles : 0;
    json_writer w;
    json_init(&w, stdout);
    json_begin_object(&w, NULL);
    json_string(&w, "input", in);
    json_string(&w, "output", out);
    json_begin_object(&w, "triangles");
    json_uint(&w, "input", st->input_triangles);
    json_uint(&w, "kept", st->triangles);
    json_uint(&w, "dropped_degenerate", st->dropped_degenerate);
    json_uint(&w, "dropped_points", input->mesh.dropped_points);
    json_uint(&w, "dropped_lines", input->mesh.dropped_lines);
    json_end_object(&w);
    json_begin_object(&w, "vertices");
    json_uint(&w, "input", st->input_vertices);
    json_uint(&w, "kept", st->vertices);
    json_double(&w, "max_error", st->vertex_max_error);
    json_end_object(&w);
    json_begin_object(&w, "tree");
    json_uint(&w, "nodes", st->nodes);
    json_uint(&w, "leaves", st->leaves);
    json_uint(&w, "depth", st->depth);
    json_double(&w, "sah_cost", st->sah_cost);
    json_end_object(&w);
    json_uint(&w, "file_size", st->file_size);
    json_uint(&w, "peak_memory", st->peak_memory);
    json_double(&w, "bytes_per_triangle", (double)st->file_size * per_tri);
    json_begin_array(&w, "sections");
    for (uint32_t t = CBVH_SECTION_NODES; t <= CBVH_SECTION_MATERIALS; t++) {
        if (!st->section_size[t])
            continue;
        json_begin_object(&w, NULL);
        json_string(&w, "name", cli_section_name(t));
        json_uint(&w, "stored_bytes", st->section_stored_size[t]);
        json_uint(&w, "raw_bytes", st->section_size[t]);
        json_double(&w, "stored_bytes_per_triangle", (double)st->section_stored_size[t] * per_tri);
        json_double(&w, "raw_bytes_per_triangle", (double)st->section_size[t] * per_tri);
        json_end_object(&w);
    }
    json_end_array(&w);
    json_begin_object(&w, "seconds");
    json_double(&w, "import", import_seconds);
    for (int p = 0; p < 4; p++)
        json_double(&w, phase_names[p], st->seconds[p]);
    json_double(&w, "total", total_seconds);
    json_end_object(&w);
    json_end_object(&w);
    json_finish(&w);
}

static void print_summary(const char *in, const char *out, const cook_input *input, const cbvh_cook_stats *st,
                          double import_seconds, double total_seconds)
{
    double per_tri = st->triangles ? 1.0 / (double)st->triangles : 0;
    printf("%s -> %s: %llu triangles", in, out, (unsigned long long)st->triangles);
    uint64_t dropped = st->dropped_degenerate + input->mesh.dropped_points + input->mesh.dropped_lines;
    if (dropped)
        printf(" (dropped %llu degenerate, %llu points, %llu lines)", (unsigned long long)st->dropped_degenerate,
               (unsigned long long)input->mesh.dropped_points, (unsigned long long)input->mesh.dropped_lines);
    printf(", %llu vertices\n", (unsigned long long)st->vertices);
    printf("  tree: %llu nodes, %llu leaves, depth %u, SAH cost %.2f\n", (unsigned long long)st->nodes,
           (unsigned long long)st->leaves, (unsigned)st->depth, st->sah_cost);
    printf("  file: %llu bytes, %.2f bytes/triangle (", (unsigned long long)st->file_size,
           (double)st->file_size * per_tri);
    const char *sep = "";
    for (uint32_t t = CBVH_SECTION_NODES; t <= CBVH_SECTION_MATERIALS; t++) {
        if (!st->section_size[t])
            continue;
        printf("%s%s %.2f", sep, cli_section_name(t), (double)st->section_stored_size[t] * per_tri);
        sep = ", ";
    }
    printf(")\n");
    if (st->vertex_max_error > 0)
        printf("  vertex error: %.3g (worst coordinate)\n", st->vertex_max_error);
    printf("  time: import %.3f s, prepare %.3f s, build %.3f s, layout %.3f s, write %.3f s, total %.3f s\n",
           import_seconds, st->seconds[0], st->seconds[1], st->seconds[2], st->seconds[3], total_seconds);
    printf("  memory: cook peak %.1f MB, %.1f bytes/triangle (the imported mesh not included)\n",
           (double)st->peak_memory / 1e6, (double)st->peak_memory * per_tri);
}

int cmd_cook(int argc, char **argv)
{
    cbvh_cook_options opt;
    cbvh_cook_options_init(&opt, sizeof opt);
    const char *paths[2] = { NULL, NULL };
    int npaths = 0, quiet = 0, json = 0, memory_given = 0;
    uint32_t max_memory = 0;

    cli_parser p;
    cli_init(&p, "cook", usage, argc, argv);
    const char *value;
    int id;
    while ((id = cli_next(&p, options, &value)) != CLI_END) {
        int ok = 1;
        uint32_t level;
        switch (id) {
        case CLI_DONE: return CLI_EXIT_OK;
        case CLI_ERROR: return CLI_EXIT_USAGE;
        case CLI_POSITIONAL:
            if (npaths == 2)
                return cli_usage_error("cook", "unexpected argument '%s'", value);
            paths[npaths++] = value;
            break;
        case OPT_LEAF:
            ok = cli_parse_u32("cook", "leaf-size", value, 1, CBVH_MAX_LEAF_SIZE, &opt.max_leaf_size);
            break;
        case OPT_LAYOUT:
            if (strcmp(value, "binary") == 0)
                opt.layout = CBVH_LAYOUT_BINARY;
            else if (strcmp(value, "wide4") == 0)
                opt.layout = CBVH_LAYOUT_WIDE4;
            else
                return cli_usage_error("cook", "--layout '%s': expected binary or wide4", value);
            break;
        case OPT_BINS: ok = cli_parse_u32("cook", "bins", value, 4, 256, &opt.sah_bins); break;
        case OPT_TCOST:
            ok = cli_parse_float("cook", "traversal-cost", value, 0.0f, 1e6f, &opt.traversal_cost);
            break;
        case OPT_ICOST:
            ok = cli_parse_float("cook", "intersection-cost", value, 1e-6f, 1e6f, &opt.intersection_cost);
            break;
        case OPT_COMPRESS:
            level = 6;
            ok = !value || cli_parse_u32("cook", "compress", value, 1, 9, &level);
            opt.compress_level = (int)level;
            break;
        case OPT_QUANTIZE: opt.vertex_format = CBVH_VERTEX_QUANTIZED16; break;
        case OPT_NO_REMAP: opt.keep_remap = 0; break;
        case OPT_NO_MATERIALS: opt.keep_materials = 0; break;
        case OPT_QUIET: quiet = 1; break;
        case OPT_JSON: json = 1; break;
        case OPT_MAX_MEMORY:
            ok = cli_parse_u32("cook", "max-memory", value, 0, UINT32_MAX, &max_memory);
            memory_given = 1;
            break;
        }
        if (!ok)
            return CLI_EXIT_USAGE;
    }
    if (npaths != 2)
        return cli_usage_error("cook", "expected an input and an output file");
    if (same_file(paths[0], paths[1]))
        return report_failure(json, paths[0], paths[1], paths[1], CLI_EXIT_USAGE,
                              "is the input file itself: cooking would replace the asset (choose another output)");
    limit_memory(paths[0], max_memory, memory_given);

    progress prog;
    progress_init(&prog, quiet);
    double t0 = cli_now();
    progress_update(&prog, "import", -1);
    cook_input input;
    char message[640];
    int rc = load_input(paths[0], &input, message, sizeof message);
    progress_done(&prog);
    if (rc) {
        if (strstr(message, "bad_alloc") || strstr(message, "out of memory"))
            snprintf(message + strlen(message), sizeof message - strlen(message),
                     " (the memory limit was reached: --max-memory MB raises it, 0 removes it)");
        return report_failure(json, paths[0], paths[1], paths[0], rc, message);
    }
    double import_seconds = cli_now() - t0;

    cbvh_mesh mesh = { input.mesh.positions, input.mesh.vertex_count, 0, input.mesh.indices,
                       input.mesh.triangle_count, input.mesh.material_ids };
    opt.progress = progress_cook_callback;
    opt.progress_user = &prog;
    cbvh_cook_stats stats;
    cbvh_error err;
    cbvh_cook_stats_init(&stats, sizeof stats);
    cbvh_result res = cbvh_cook_to_path(&mesh, &opt, NULL, paths[1], &stats, &err);
    progress_done(&prog);
    double total_seconds = cli_now() - t0;
    if (res != CBVH_OK) {
        /* Mesh problems belong to the input, I/O problems to the output. */
        const char *culprit = (res == CBVH_ERROR_IO || res == CBVH_ERROR_INVALID_ARGUMENT) ? paths[1] : paths[0];
        snprintf(message, sizeof message, "%s: %s", cbvh_result_string(err.code), err.message);
        rc = report_failure(json, paths[0], paths[1], culprit, cli_exit_for(err.code), message);
    } else if (json) {
        print_json(paths[0], paths[1], &input, &stats, import_seconds, total_seconds);
    } else {
        print_summary(paths[0], paths[1], &input, &stats, import_seconds, total_seconds);
    }
    imported_mesh_free(&input.mesh);
    return rc;
}
