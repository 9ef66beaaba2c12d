/* cmd_cook.c: `cbvh cook`: import a mesh file (or generate a scene), cook it, write the .cbvh file
 * atomically. */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "depfile.h"
#include "import_assimp.h"
#include "import_child.h"
#include "json.h"
#include "material_map.h"
#include "progress.h"
#include "support/scene_gen.h"

static const char usage[] =
    "Usage: cbvh cook [OPTIONS] IN OUT\n"
    "       cbvh cook [OPTIONS] --output-dir DIR IN...\n"
    "       cbvh cook [OPTIONS] --manifest FILE [--output-dir DIR] [IN...]\n"
    "\n"
    "Cooks the triangles of IN into the cbvh file OUT. IN is any mesh file assimp reads\n"
    "(OBJ, PLY, STL, glTF/GLB, FBX, DAE, 3DS, IFC, ...; NAME.EXT.gz is inflated first) or a\n"
    "generated scene: gen:sphere:N, gen:terrain:N, gen:soup:N, gen:cube, gen:demo.\n"
    "All meshes of the scene are merged with their node transforms applied, depth-first over\n"
    "the node hierarchy (a node's meshes in order, then its children in order), triangles in\n"
    "mesh order: that order gives the original triangle ids that queries report. The material\n"
    "id of a triangle is its mesh's assimp material index (or the --material-map id of its\n"
    "name); the names of the materials used are stored too (cbvh info lists them). A side file\n"
    "the asset names but that is not there (a .mtl) is warned about: the asset's materials\n"
    "then change. Points and lines are dropped.\n"
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
    "  --no-materials          do not store material ids and names\n"
    "  --material-map FILE     material ids by name: lines NAME<TAB>ID (ID 0..4294967295),\n"
    "                          '*<TAB>ID' for every other name, # comments; a material the\n"
    "                          map does not name fails the cook (exit status 1)\n"
    "  --quiet                 nothing on success: no progress display (shown only on a\n"
    "                          terminal anyway) and no summary; warnings and errors still go\n"
    "                          to standard error\n"
    "  --force                 replace an OUT that is read-only (in a Perforce workspace: a\n"
    "                          file not checked out), which is refused otherwise\n"
    "  --json                  print statistics (and warnings) as JSON on stdout; a failed\n"
    "                          cook prints\n"
    "                          {\"input\", \"output\", \"error\": {\"status\", \"message\"}}\n"
    "  --select PATTERN        cook only the nodes whose names match the shell pattern\n"
    "                          (with their subtrees), e.g. 'UCX_*' for collision meshes\n"
    "  --scale S               multiply every position by S (units: 0.01 turns cm into m)\n"
    "  --up-axis AXIS          x, y (default) or z: turn the scene so that its up axis,\n"
    "                          +Y as assimp imports every format, becomes +AXIS (z for\n"
    "                          Z-up engines), by a right-handed rotation\n"
    "  --depfile FILE          write a Makefile rule 'OUT: IN SIDE-FILES...' naming every\n"
    "                          file the import opened or looked for (.mtl, .bin ...) and the\n"
    "                          material map, with an empty rule for each (as gcc -MP), for\n"
    "                          make and ninja; written before OUT is replaced, and neither\n"
    "                          changes when either fails; FILE must not be IN or OUT\n"
    "  --depfiles              write the rule to OUT.d (for each asset of a batch)\n"
    "  --output-dir DIR        batch: cook each IN into DIR/STEM.cbvh (STEM: IN's file name\n"
    "                          without its extension)\n"
    "  --manifest FILE         batch: the assets of FILE (- for standard input), one a line:\n"
    "                          IN (into --output-dir) or IN<TAB>OUT; # starts a comment line;\n"
    "                          relative paths are relative to the current folder\n"
    "  -j, --jobs N            batch: cook N assets at once (default 1), each in a process of\n"
    "                          its own; one JSON line per asset on stdout (as --json, on one\n"
    "                          line, in the order they finish), messages on stderr; exit\n"
    "                          status 0 when every asset cooked, else 1; stopped by SIGINT,\n"
    "                          SIGTERM or SIGHUP, it passes the signal to the running cooks\n"
    "                          and waits for them (no unfinished output is written)\n"
    "  --max-memory MB         stop an import or cook that would hold more than MB megabytes\n"
    "                          of address space (exit status 1); default 1024 + 64 x the\n"
    "                          input file's size in MB; 0: no limit\n"
    "  --import-timeout S      stop an import that runs longer than S seconds (exit status\n"
    "                          1); default 120 + 1 per MB of the input file; 0: no limit\n"
    "  -h, --help              show this help\n"
    "\n"
    "OUT must not be IN itself (also through a link): that is refused, exit status 2. An OUT\n"
    "that is a device, a FIFO or a folder is refused likewise; an OUT that is a symbolic link\n"
    "is replaced by the new file, and the file it pointed to stays as it was. A new OUT gets\n"
    "mode 0666 less the umask; a replaced one keeps its mode. Interrupted (SIGINT, SIGTERM,\n"
    "SIGHUP), a cook leaves no temporary file behind.\n"
    "\n"
    "An asset is untrusted input: assimp reads it in a child process, and whatever happens\n"
    "there (a crash, an abort, a hang, a reader looping at the end of a truncated file) ends\n"
    "as exit status 1 with a message naming the file and the reason; in a batch, as that\n"
    "asset's failure while the others cook.\n"
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
    OPT_MAX_MEMORY,
    OPT_OUTPUT_DIR,
    OPT_MANIFEST,
    OPT_JOBS,
    OPT_SELECT,
    OPT_SCALE,
    OPT_UP_AXIS,
    OPT_DEPFILE,
    OPT_MATERIAL_MAP,
    OPT_IMPORT_TIMEOUT,
    OPT_DEPFILES,
    OPT_FORCE
};

static const cli_option options[] = {
    {"leaf-size", CLI_ARG_REQUIRED, OPT_LEAF},
    {"layout", CLI_ARG_REQUIRED, OPT_LAYOUT},
    {"bins", CLI_ARG_REQUIRED, OPT_BINS},
    {"traversal-cost", CLI_ARG_REQUIRED, OPT_TCOST},
    {"intersection-cost", CLI_ARG_REQUIRED, OPT_ICOST},
    {"compress", CLI_ARG_OPTIONAL, OPT_COMPRESS},
    {"quantize-vertices", CLI_ARG_NONE, OPT_QUANTIZE},
    {"no-remap", CLI_ARG_NONE, OPT_NO_REMAP},
    {"no-materials", CLI_ARG_NONE, OPT_NO_MATERIALS},
    {"quiet", CLI_ARG_NONE, OPT_QUIET},
    {"json", CLI_ARG_NONE, OPT_JSON},
    {"max-memory", CLI_ARG_REQUIRED, OPT_MAX_MEMORY},
    {"output-dir", CLI_ARG_REQUIRED, OPT_OUTPUT_DIR},
    {"manifest", CLI_ARG_REQUIRED, OPT_MANIFEST},
    {"jobs", CLI_ARG_REQUIRED, OPT_JOBS},
    {"select", CLI_ARG_REQUIRED, OPT_SELECT},
    {"scale", CLI_ARG_REQUIRED, OPT_SCALE},
    {"up-axis", CLI_ARG_REQUIRED, OPT_UP_AXIS},
    {"depfile", CLI_ARG_REQUIRED, OPT_DEPFILE},
    {"material-map", CLI_ARG_REQUIRED, OPT_MATERIAL_MAP},
    {"import-timeout", CLI_ARG_REQUIRED, OPT_IMPORT_TIMEOUT},
    {"depfiles", CLI_ARG_NONE, OPT_DEPFILES},
    {"force", CLI_ARG_NONE, OPT_FORCE},
    {NULL, 0, 0},
};

/* The mesh to cook, whichever way it was obtained. */
typedef struct cook_input {
    imported_mesh mesh;
    int generated;
} cook_input;

/* The share of the asset the import has read, on the progress display. */
static void import_progress(void *user, int percent)
{
    progress_update((progress *)user, "import", percent / 100.0);
}

/* Returns an exit status; on success `in` holds the mesh, else `message` says why. */
static int load_input(const char *path, import_options *io, unsigned timeout_seconds, cook_input *in,
                      char *message, size_t message_size)
{
    memset(in, 0, sizeof *in);
    if (!strncmp(path, "gen:", 4)) {
        scene s;
        if (!scene_from_spec(&s, path + 4)) {
            snprintf(message, message_size,
                     "not a generated scene (gen:sphere:N, gen:terrain:N, gen:soup:N, "
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
    return import_contained(path, io, timeout_seconds, &in->mesh, message, message_size);
}

/* A failed cook as JSON: input, output, error {status (the exit status), file (the one at fault), message}.
 */
static void report_json(FILE *to, const char *in, const char *out, const char *file, int status,
                        const char *message)
{
    json_writer w;
    json_init(&w, to);
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

/* A failed cook: the message on standard error, and with --json also as JSON on standard output. */
static int report_failure(int json, const char *in, const char *out, const char *file, int status,
                          const char *message)
{
    cli_error("cook", file, "%s", message);
    if (json) {
        report_json(stdout, in, out, file, status, message);
        cli_json_error_printed();
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

/* What a cook knew besides its statistics: the names it stored and the side files it missed. */
typedef struct cook_notes {
    const cbvh_material_name *names;
    uint32_t name_count;
    const path_list *missing;
} cook_notes;

static void print_json(const char *in, const char *out, const cook_input *input, const cbvh_cook_stats *st,
                       const cook_notes *notes, double import_seconds, double total_seconds)
{
    static const char *const phase_names[] = {"prepare", "build", "layout", "write"};
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
    json_uint(&w, "flushed_coordinates", st->flushed_coordinates);
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
    json_begin_array(&w, "material_names");
    for (uint32_t k = 0; k < notes->name_count; k++) {
        json_begin_object(&w, NULL);
        json_uint(&w, "id", notes->names[k].id);
        json_string(&w, "name", notes->names[k].name);
        json_end_object(&w);
    }
    json_end_array(&w);
    json_begin_array(&w, "missing_files");
    for (size_t k = 0; k < notes->missing->count; k++)
        json_string(&w, NULL, notes->missing->paths[k]);
    json_end_array(&w);
    json_begin_array(&w, "sections");
    for (uint32_t t = CBVH_SECTION_NODES; t < CBVH_STATS_SECTION_TYPES; t++) {
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
                          const cook_notes *notes, double import_seconds, double total_seconds)
{
    double per_tri = st->triangles ? 1.0 / (double)st->triangles : 0;
    printf("%s -> %s: %llu triangles", in, out, (unsigned long long)st->triangles);
    uint64_t dropped = st->dropped_degenerate + input->mesh.dropped_points + input->mesh.dropped_lines;
    if (dropped)
        printf(" (dropped %llu degenerate, %llu points, %llu lines)",
               (unsigned long long)st->dropped_degenerate, (unsigned long long)input->mesh.dropped_points,
               (unsigned long long)input->mesh.dropped_lines);
    printf(", %llu vertices", (unsigned long long)st->vertices);
    if (st->flushed_coordinates)
        printf(" (%llu coordinates below 2^-40 stored as 0)", (unsigned long long)st->flushed_coordinates);
    printf("\n");
    printf("  tree: %llu nodes, %llu leaves, depth %u, SAH cost %.2f\n", (unsigned long long)st->nodes,
           (unsigned long long)st->leaves, (unsigned)st->depth, st->sah_cost);
    printf("  file: %llu bytes, %.2f bytes/triangle (", (unsigned long long)st->file_size,
           (double)st->file_size * per_tri);
    const char *sep = "";
    for (uint32_t t = CBVH_SECTION_NODES; t < CBVH_STATS_SECTION_TYPES; t++) {
        if (!st->section_size[t])
            continue;
        printf("%s%s %.2f", sep, cli_section_name(t), (double)st->section_stored_size[t] * per_tri);
        sep = ", ";
    }
    printf(")\n");
    if (notes->name_count > 0) {
        printf("  material names:");
        for (uint32_t k = 0; k < notes->name_count; k++)
            printf("%s %u '%s'", k ? "," : "", (unsigned)notes->names[k].id, notes->names[k].name);
        printf("\n");
    }
    if (st->vertex_max_error > 0)
        printf("  vertex error: %.3g (worst coordinate)\n", st->vertex_max_error);
    printf("  time: import %.3f s, prepare %.3f s, build %.3f s, layout %.3f s, write %.3f s, total %.3f s\n",
           import_seconds, st->seconds[0], st->seconds[1], st->seconds[2], st->seconds[3], total_seconds);
    printf("  memory: cook peak %.1f MB, %.1f bytes/triangle (the imported mesh not included)\n",
           (double)st->peak_memory / 1e6, (double)st->peak_memory * per_tri);
}

/* How every asset of a run is cooked. */
typedef struct cook_settings {
    cbvh_cook_options opt;
    int quiet, json, memory_given, timeout_given;
    int depfiles; /* --depfiles: OUT.d for each output */
    int force;    /* --force: replace a read-only OUT */
    uint32_t max_memory;
    uint32_t import_timeout; /* seconds, 0: none; when not given, import_timeout_for picks one */
    const char *select, *depfile, *material_map_path;
    material_map map; /* read from material_map_path (when given) before anything cooks */
    double scale;
    char up_axis; /* 'x', 'y' or 'z' */
} cook_settings;

/* The import's time limit: as given, or 120 s plus a second per MB of the input file. */
static unsigned import_timeout_for(const cook_settings *c, const char *in)
{
    struct stat st;
    if (c->timeout_given)
        return c->import_timeout;
    return 120u + (stat(in, &st) == 0 ? (unsigned)((uint64_t)st.st_size >> 20) : 0u);
}

/* --scale and --up-axis on the imported positions, in double, rounded once. */
static void transform_positions(const cook_settings *c, imported_mesh *m)
{
    if (c->scale == 1.0 && c->up_axis == 'y')
        return;
    for (size_t v = 0; v < m->vertex_count; v++) {
        float *p = m->positions + 3 * v;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
            continue; /* refused by the cook, which names the file's axis */
        const double x = c->scale * p[0], y = c->scale * p[1], z = c->scale * p[2];
        /* +Y to +Z: a quarter turn about +X; +Y to +X: a quarter turn about -Z */
        const double out[3][3] = {{x, y, z}, {y, -x, z}, {x, -z, y}};
        const int k = c->up_axis == 'y' ? 0 : c->up_axis == 'x' ? 1 : 2;
        for (int a = 0; a < 3; a++)
            p[a] = (float)out[k][a];
    }
}

/* Cooks one asset whose paths were checked, writing `depfile` (NULL: none) too; returns its exit status. */
static int cook_checked(const cook_settings *c, const char *in, const char *out, const char *depfile)
{
    cbvh_cook_options opt = c->opt;
    const int json = c->json;
    limit_memory(in, c->max_memory, c->memory_given);

    progress prog;
    progress_init(&prog, c->quiet);
    double t0 = cli_now();
    progress_update(&prog, "import", -1);
    if (prog.enabled)
        import_contained_progress(import_progress, &prog);
    cook_input input;
    char message[640];
    import_options io;
    memset(&io, 0, sizeof io);
    io.select = c->select;
    int rc = load_input(in, &io, import_timeout_for(c, in), &input, message, sizeof message);
    import_contained_progress(NULL, NULL);
    progress_done(&prog);
    if (rc) {
        import_options_free(&io);
        if (strstr(message, "bad_alloc") || strstr(message, "out of memory"))
            snprintf(message + strlen(message), sizeof message - strlen(message),
                     " (the memory limit was reached: --max-memory MB raises it, 0 removes it)");
        return report_failure(json, in, out, in, rc, message);
    }
    double import_seconds = cli_now() - t0;
    transform_positions(c, &input.mesh);
    for (size_t k = 0; k < io.missing.count; k++)
        cli_error("cook", in,
                  "warning: the asset refers to '%s', which was not found: its materials may be "
                  "missing or numbered differently",
                  io.missing.paths[k]);
    cbvh_material_name *names = NULL;
    uint32_t name_count = 0;
    rc = material_names_prepare(&input.mesh, c->material_map_path ? &c->map : NULL, c->material_map_path,
                                &names, &name_count, message, sizeof message);
    if (rc) {
        import_options_free(&io);
        imported_mesh_free(&input.mesh);
        return report_failure(json, in, out, rc == 1 ? in : c->material_map_path, rc, message);
    }
    opt.material_names = names;
    opt.material_name_count = name_count;
    const cook_notes notes = {names, name_count, &io.missing};

    cbvh_mesh mesh = {input.mesh.positions, input.mesh.vertex_count,   0,
                      input.mesh.indices,   input.mesh.triangle_count, input.mesh.material_ids};
    opt.progress = progress_cook_callback;
    opt.progress_user = &prog;
    cbvh_cook_stats stats;
    cbvh_error err;
    cbvh_cook_stats_init(&stats, sizeof stats);
    /* The depfile goes in place first: a new OUT never stands beside an old list of its dependencies. */
    depfile_commit dc;
    memset(&dc, 0, sizeof dc);
    if (depfile && depfile_put(&dc, depfile, out, in, &io.opened, &io.missing, c->material_map_path) != 0) {
        snprintf(message, sizeof message, "cannot write the depfile: %s (nothing was changed)",
                 strerror(errno));
        rc = report_failure(json, in, out, depfile, CLI_EXIT_USAGE, message);
        free(names);
        import_options_free(&io);
        imported_mesh_free(&input.mesh);
        return rc;
    }
    cbvh_result res = cbvh_cook_to_path(&mesh, &opt, NULL, out, &stats, &err);
    depfile_finish(&dc, res == CBVH_OK);
    progress_done(&prog);
    double total_seconds = cli_now() - t0;
    if (res != CBVH_OK) {
        /* Mesh problems belong to the input, I/O problems to the output. */
        const char *culprit = (res == CBVH_ERROR_IO || res == CBVH_ERROR_INVALID_ARGUMENT) ? out : in;
        snprintf(
            message, sizeof message, "%s: %s%s", cbvh_result_string(err.code), err.message,
            !strncmp(err.message, "vertex ", 7) && !input.generated
                ? " (vertices counted from 0 in the imported mesh, after assimp joined identical ones: not "
                  "the file's numbering)"
                : "");
        rc = report_failure(json, in, out, culprit, cli_exit_for(err.code), message);
    } else if (json) {
        print_json(in, out, &input, &stats, &notes, import_seconds, total_seconds);
    } else if (!c->quiet) {
        print_summary(in, out, &input, &stats, &notes, import_seconds, total_seconds);
    }
    free(names);
    import_options_free(&io);
    imported_mesh_free(&input.mesh);
    return rc;
}

/* Refuses a depfile that would overwrite the asset or the output, or that is not a plain file; returns an
 * exit status. */
static int check_depfile(const cook_settings *c, const char *depfile, const char *in, const char *out)
{
    struct stat st;
    const char *what = NULL;
    if (paths_same_file(depfile, in))
        what = "is the input file itself: writing it would replace the asset";
    else if (paths_same_file(depfile, out))
        what = "is the output file itself: the depfile and the cooked file cannot share a name";
    else if (stat(depfile, &st) == 0 && !S_ISREG(st.st_mode))
        what = "is not a regular file (a device, a FIFO or a folder): refused as a depfile";
    return what ? report_failure(c->json, in, out, depfile, CLI_EXIT_USAGE, what) : CLI_EXIT_OK;
}

/* Cooks one asset; returns its exit status. */
static int cook_one(const cook_settings *c, const char *in, const char *out)
{
    const int json = c->json;
    if (same_file(in, out))
        return report_failure(
            json, in, out, out, CLI_EXIT_USAGE,
            "is the input file itself: cooking would replace the asset (choose another output)");
    struct stat st;
    if (!c->force && stat(out, &st) == 0 && S_ISREG(st.st_mode) &&
        (st.st_uid == geteuid() ? !(st.st_mode & S_IWUSR) : access(out, W_OK) != 0))
        return report_failure(json, in, out, out, CLI_EXIT_USAGE,
                              "is read-only (in a Perforce workspace: not checked out); --force replaces it");
    char *own_depfile = NULL;
    const char *depfile = c->depfile;
    if (c->depfiles) {
        size_t size = strlen(out) + 3;
        if ((own_depfile = malloc(size)) == NULL)
            return report_failure(json, in, out, out, CLI_EXIT_USAGE, "out of memory");
        snprintf(own_depfile, size, "%s.d", out);
        depfile = own_depfile;
    }
    int refused = depfile ? check_depfile(c, depfile, in, out) : CLI_EXIT_OK;
    if (refused) {
        free(own_depfile);
        return refused;
    }
    int rc = cook_checked(c, in, out, depfile);
    free(own_depfile);
    return rc;
}

/* One asset of a batch: its input and output paths (owned). */
typedef struct batch_item {
    char *in, *out;
} batch_item;

typedef struct batch {
    batch_item *items;
    size_t count, capacity;
} batch;

static int batch_add(batch *b, const char *in, const char *out_dir, const char *out)
{
    if (b->count == b->capacity) {
        size_t cap = b->capacity ? 2 * b->capacity : 64;
        batch_item *grown = realloc(b->items, cap * sizeof *grown);
        if (!grown)
            return 0;
        b->items = grown;
        b->capacity = cap;
    }
    batch_item *it = &b->items[b->count];
    it->in = strdup(in);
    if (out) {
        it->out = strdup(out);
    } else {
        /* DIR/STEM.cbvh, STEM: the input's file name without its extension (and without .gz) */
        const char *base = strrchr(in, '/');
        base = base ? base + 1 : in;
        size_t n = strlen(base);
        if (n > 3 && !strcmp(base + n - 3, ".gz"))
            n -= 3;
        const char *dot = NULL;
        for (size_t k = 1; k < n; k++)
            if (base[k] == '.')
                dot = base + k;
        if (dot)
            n = (size_t)(dot - base);
        size_t size = strlen(out_dir) + n + 8;
        it->out = malloc(size);
        if (it->out)
            snprintf(it->out, size, "%s/%.*s.cbvh", out_dir, (int)n, base);
    }
    if (!it->in || !it->out) {
        free(it->in);
        free(it->out);
        return 0;
    }
    b->count++;
    return 1;
}

static void batch_free(batch *b)
{
    for (size_t k = 0; k < b->count; k++) {
        free(b->items[k].in);
        free(b->items[k].out);
    }
    free(b->items);
}

/* Reads a manifest: a line per asset, "IN" (cooked into the output folder) or "IN<TAB>OUT"; blank lines
 * and lines starting with # are skipped. Returns an exit status. */
static int read_manifest(const char *path, const char *out_dir, batch *b)
{
    FILE *f = strcmp(path, "-") ? fopen(path, "r") : stdin;
    if (!f) {
        cli_error("cook", path, "cannot open the manifest: %s", strerror(errno));
        return CLI_EXIT_USAGE;
    }
    char line[8192];
    unsigned number = 0;
    int rc = CLI_EXIT_OK;
    while (rc == CLI_EXIT_OK && fgets(line, sizeof line, f)) {
        number++;
        size_t n = strlen(line);
        if (n == sizeof line - 1 && line[n - 1] != '\n') {
            cli_error("cook", path, "line %u: longer than %zu bytes", number, sizeof line - 2);
            rc = CLI_EXIT_USAGE;
            break;
        }
        while (n && (line[n - 1] == '\n' || line[n - 1] == '\r'))
            line[--n] = '\0';
        if (n == 0 || line[0] == '#')
            continue;
        char *tab = strchr(line, '\t');
        if (tab)
            *tab = '\0';
        if (!tab && !out_dir) {
            cli_error("cook", path,
                      "line %u: '%s' names no output (IN<TAB>OUT) and no --output-dir was given", number,
                      line);
            rc = CLI_EXIT_USAGE;
        } else if (!*line || (tab && !tab[1])) {
            cli_error("cook", path, "line %u: an empty input or output path", number);
            rc = CLI_EXIT_USAGE;
        } else if (!batch_add(b, line, out_dir, tab ? tab + 1 : NULL)) {
            cli_error("cook", path, "out of memory");
            rc = CLI_EXIT_USAGE;
        }
    }
    if (rc == CLI_EXIT_OK && ferror(f)) {
        cli_error("cook", path, "cannot read the manifest: %s", strerror(errno));
        rc = CLI_EXIT_USAGE;
    }
    if (f != stdin)
        fclose(f);
    return rc;
}

/* A cook child's JSON object on one line: the pretty printer's newlines and indentation go (strings hold
 * no raw newline: the writer escapes them). */
static void print_json_line(const char *text)
{
    for (const char *p = text; *p; p++) {
        if (*p == '\n') {
            while (p[1] == ' ')
                p++;
            continue;
        }
        putchar(*p);
    }
    putchar('\n');
    fflush(stdout);
}

/* A running child: its asset and the pipe its JSON comes through. */
typedef struct batch_child {
    pid_t pid;
    size_t item;
    int fd;
    char *text;
    size_t size, capacity;
} batch_child;

/* Reads what the child has written so far (the child may fill the pipe before it exits). */
static void child_drain(batch_child *c)
{
    for (;;) {
        if (c->capacity - c->size < 4096) {
            size_t cap = c->capacity ? 2 * c->capacity : 16384;
            char *grown = realloc(c->text, cap);
            if (!grown)
                return;
            c->text = grown;
            c->capacity = cap;
        }
        ssize_t n = read(c->fd, c->text + c->size, c->capacity - c->size - 1);
        if (n > 0) {
            c->size += (size_t)n;
            continue;
        }
        if (n < 0 && errno == EINTR)
            continue;
        break;
    }
    if (c->text)
        c->text[c->size] = '\0';
}

/* The signal that stops a batch (a build system ending the job), or 0. */
static volatile sig_atomic_t batch_stop;

static void batch_on_signal(int sig)
{
    batch_stop = sig;
}

static const int batch_signals[] = {SIGINT, SIGTERM, SIGHUP};

/* Catches (`on` 1) or restores (0) the signals that stop a batch; one the caller ignores stays ignored. */
static void batch_catch_signals(int on)
{
    for (int k = 0; k < 3; k++) {
        struct sigaction sa, old;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on ? batch_on_signal : SIG_DFL;
        sigemptyset(&sa.sa_mask);
        if (sigaction(batch_signals[k], NULL, &old) == 0 && old.sa_handler != SIG_IGN)
            sigaction(batch_signals[k], &sa, NULL);
    }
}

/* Stopped by `sig`: passes it to every running cook, waits for them (a cook interrupted writes no output),
 * then ends the process by the same signal. */
static void batch_stop_children(batch_child *running, uint32_t jobs, int sig)
{
    for (uint32_t k = 0; k < jobs; k++)
        if (running[k].pid)
            kill(running[k].pid, sig);
    for (uint32_t k = 0; k < jobs; k++)
        if (running[k].pid)
            while (waitpid(running[k].pid, NULL, 0) < 0 && errno == EINTR)
                continue;
    fflush(stdout);
    batch_catch_signals(0);
    raise(sig);
}

/* Cooks every asset of b, `jobs` at a time, each in a child process of its own (an importer that
 * crashes or exhausts its memory limit takes only its asset down). Prints one JSON line per asset, in
 * the order they finish; returns 0 when every asset cooked, else 1. */
static int run_batch(const cook_settings *c, const batch *b, uint32_t jobs)
{
    /* Two assets into one output would race: refuse before cooking anything. */
    for (size_t i = 0; i < b->count; i++)
        for (size_t k = i + 1; k < b->count; k++)
            if (!strcmp(b->items[i].out, b->items[k].out)) {
                cli_error("cook", b->items[k].out, "is the output of both '%s' and '%s'", b->items[i].in,
                          b->items[k].in);
                return CLI_EXIT_USAGE;
            }
    cli_json_error_printed(); /* each asset gets its JSON line, success or failure */
    batch_child *running = calloc(jobs, sizeof *running);
    if (!running) {
        cli_error("cook", NULL, "out of memory");
        return CLI_EXIT_USAGE;
    }
    cook_settings child_settings = *c;
    child_settings.json = 1;
    child_settings.quiet = 1;
    fflush(stdout);
    batch_stop = 0;
    batch_catch_signals(1);
    size_t next = 0, failed = 0, done = 0;
    uint32_t active = 0;
    while (done < b->count) {
        while (active < jobs && next < b->count && !batch_stop) {
            int fds[2];
            batch_child *slot = NULL;
            for (uint32_t k = 0; k < jobs && !slot; k++)
                if (!running[k].pid)
                    slot = &running[k];
            if (pipe(fds) != 0) {
                cli_error("cook", NULL, "cannot create a pipe: %s", strerror(errno));
                break;
            }
            pid_t pid = fork();
            if (pid == 0) {
                batch_catch_signals(0);
                close(fds[0]);
                dup2(fds[1], STDOUT_FILENO);
                close(fds[1]);
                const int status = cook_one(&child_settings, b->items[next].in, b->items[next].out);
                fflush(stdout);
                _exit(status);
            }
            close(fds[1]);
            if (pid < 0) {
                close(fds[0]);
                cli_error("cook", NULL, "cannot start a cook: %s", strerror(errno));
                break;
            }
            /* drained while other cooks run, and while a stop signal is checked: never block on it */
            fcntl(fds[0], F_SETFL, fcntl(fds[0], F_GETFL) | O_NONBLOCK);
            memset(slot, 0, sizeof *slot);
            slot->pid = pid;
            slot->item = next++;
            slot->fd = fds[0];
            active++;
        }
        if (batch_stop)
            batch_stop_children(running, jobs, batch_stop);
        if (active == 0) { /* nothing could start: the rest fail */
            failed += b->count - done;
            break;
        }
        /* Drain every pipe, then reap whichever child ended. */
        int status;
        pid_t pid;
        for (;;) {
            if (batch_stop)
                batch_stop_children(running, jobs, batch_stop);
            pid = waitpid(-1, &status, WNOHANG);
            if (pid != 0)
                break;
            for (uint32_t k = 0; k < jobs; k++)
                if (running[k].pid)
                    child_drain(&running[k]);
            struct timespec pause = {0, 2000000};
            nanosleep(&pause, NULL);
        }
        if (pid < 0)
            break;
        batch_child *ch = NULL;
        for (uint32_t k = 0; k < jobs && !ch; k++)
            if (running[k].pid == pid)
                ch = &running[k];
        if (!ch)
            continue;
        child_drain(ch);
        close(ch->fd);
        const batch_item *it = &b->items[ch->item];
        if (WIFEXITED(status) && ch->text && ch->size > 0) {
            print_json_line(ch->text);
            failed += WEXITSTATUS(status) != 0;
        } else {
            char message[128];
            if (WIFSIGNALED(status))
                snprintf(message, sizeof message, "the cook was ended by signal %d", WTERMSIG(status));
            else
                snprintf(message, sizeof message, "the cook ended with status %d and no report",
                         WIFEXITED(status) ? WEXITSTATUS(status) : -1);
            char *text = NULL;
            size_t size = 0;
            FILE *mem = open_memstream(&text, &size);
            if (mem) {
                report_json(mem, it->in, it->out, it->in, CLI_EXIT_BAD_INPUT, message);
                fclose(mem);
                print_json_line(text);
                free(text);
            }
            cli_error("cook", it->in, "%s", message);
            failed++;
        }
        free(ch->text);
        memset(ch, 0, sizeof *ch);
        active--;
        done++;
    }
    batch_catch_signals(0);
    free(running);
    return failed ? CLI_EXIT_BAD_INPUT : CLI_EXIT_OK;
}

static int cook_main(int argc, char **argv)
{
    cook_settings c;
    memset(&c, 0, sizeof c);
    cbvh_cook_options_init(&c.opt, sizeof c.opt);
    cbvh_cook_options *const o = &c.opt;
    c.scale = 1.0;
    c.up_axis = 'y';
    const char *out_dir = NULL, *manifest = NULL;
    uint32_t jobs = 1;
    int jobs_given = 0, compress_bare = 0;
    batch b;
    memset(&b, 0, sizeof b);
    const char **paths = calloc((size_t)argc + 1, sizeof *paths);
    int npaths = 0;
    if (!paths) {
        cli_error("cook", NULL, "out of memory");
        return CLI_EXIT_USAGE;
    }

    cli_parser p;
    cli_init(&p, "cook", usage, argc, argv);
    const char *value;
    int id, rc = CLI_EXIT_OK;
    while (rc == CLI_EXIT_OK && (id = cli_next(&p, options, &value)) != CLI_END) {
        int ok = 1;
        uint32_t level;
        switch (id) {
        case CLI_DONE:
            free(paths);
            return CLI_EXIT_OK;
        case CLI_ERROR:
            free(paths);
            return CLI_EXIT_USAGE;
        case CLI_POSITIONAL:
            paths[npaths++] = value;
            break;
        case OPT_LEAF:
            ok = cli_parse_u32("cook", "leaf-size", value, 1, CBVH_MAX_LEAF_SIZE, &o->max_leaf_size);
            break;
        case OPT_LAYOUT:
            if (strcmp(value, "binary") == 0)
                o->layout = CBVH_LAYOUT_BINARY;
            else if (strcmp(value, "wide4") == 0)
                o->layout = CBVH_LAYOUT_WIDE4;
            else
                rc = cli_usage_error("cook", "--layout '%s': expected binary or wide4", value);
            break;
        case OPT_BINS:
            ok = cli_parse_u32("cook", "bins", value, 4, 256, &o->sah_bins);
            break;
        case OPT_TCOST:
            ok = cli_parse_float("cook", "traversal-cost", value, 0.0f, 1e6f, &o->traversal_cost);
            break;
        case OPT_ICOST:
            ok = cli_parse_float("cook", "intersection-cost", value, 1e-6f, 1e6f, &o->intersection_cost);
            break;
        case OPT_COMPRESS:
            compress_bare = !value;
            level = 6;
            ok = !value || cli_parse_u32("cook", "compress", value, 1, 9, &level);
            o->compress_level = (int)level;
            break;
        case OPT_QUANTIZE:
            o->vertex_format = CBVH_VERTEX_QUANTIZED16;
            break;
        case OPT_NO_REMAP:
            o->keep_remap = 0;
            break;
        case OPT_NO_MATERIALS:
            o->keep_materials = 0;
            break;
        case OPT_QUIET:
            c.quiet = 1;
            break;
        case OPT_JSON:
            c.json = 1;
            break;
        case OPT_MAX_MEMORY:
            ok = cli_parse_u32("cook", "max-memory", value, 0, UINT32_MAX, &c.max_memory);
            c.memory_given = 1;
            break;
        case OPT_OUTPUT_DIR:
            out_dir = value;
            break;
        case OPT_MANIFEST:
            manifest = value;
            break;
        case OPT_JOBS:
            ok = cli_parse_u32("cook", "jobs", value, 1, 256, &jobs);
            jobs_given = 1;
            break;
        case OPT_SELECT:
            c.select = value;
            break;
        case OPT_DEPFILE:
            c.depfile = value;
            break;
        case OPT_DEPFILES:
            c.depfiles = 1;
            break;
        case OPT_FORCE:
            c.force = 1;
            break;
        case OPT_MATERIAL_MAP:
            c.material_map_path = value;
            break;
        case OPT_IMPORT_TIMEOUT:
            ok = cli_parse_u32("cook", "import-timeout", value, 0, 1000000, &c.import_timeout);
            c.timeout_given = 1;
            break;
        case OPT_SCALE: {
            char *end = NULL;
            c.scale = strtod(value, &end);
            if (!*value || *end || !(c.scale > 0.0) || c.scale > 1e30)
                rc = cli_usage_error("cook", "--scale '%s': expected a positive number", value);
            break;
        }
        case OPT_UP_AXIS:
            if ((value[0] == 'x' || value[0] == 'y' || value[0] == 'z') && !value[1])
                c.up_axis = value[0];
            else
                rc = cli_usage_error("cook", "--up-axis '%s': expected x, y or z", value);
            break;
        }
        if (!ok)
            rc = CLI_EXIT_USAGE;
    }
    char message[640];
    if (rc == CLI_EXIT_OK && c.material_map_path &&
        (rc = material_map_read(c.material_map_path, &c.map, message, sizeof message)) != 0)
        cli_error("cook", NULL, "%s", message);
    if (rc != CLI_EXIT_OK) {
        free(paths);
        return rc;
    }
    if (!out_dir && !manifest) {
        /* --compress takes its level only as --compress=LEVEL: a bare level is taken for a file name */
        const int level_as_path =
            compress_bare && npaths > 0 && paths[0][0] >= '1' && paths[0][0] <= '9' && !paths[0][1];
        if (npaths != 2 && level_as_path)
            rc = cli_usage_error("cook",
                                 "'%s' was taken for the input file: the level attaches with '=', "
                                 "--compress=%s",
                                 paths[0], paths[0]);
        else if (npaths != 2)
            rc = cli_usage_error("cook",
                                 "expected an input and an output file, got %d file name%s (or "
                                 "--output-dir DIR with inputs, or --manifest FILE)",
                                 npaths, npaths == 1 ? "" : "s");
        else if (jobs_given && !c.quiet)
            cli_error("cook", NULL,
                      "warning: --jobs cooks a batch (--output-dir or --manifest); one cook (IN "
                      "OUT) runs alone");
        if (npaths == 2)
            rc = cook_one(&c, paths[0], paths[1]);
        free(paths);
        material_map_free(&c.map);
        return rc;
    }
    /* A batch: the inputs named on the command line and in the manifest. */
    if (c.depfile) {
        free(paths);
        return cli_usage_error("cook",
                               "--depfile names one file: a batch writes one per asset with --depfiles "
                               "(OUT.d)");
    }
    struct stat st;
    if (out_dir && (stat(out_dir, &st) != 0 || !S_ISDIR(st.st_mode)))
        rc = cli_usage_error("cook", "--output-dir '%s': not an existing folder", out_dir);
    for (int k = 0; rc == CLI_EXIT_OK && k < npaths; k++)
        if (!strncmp(paths[k], "gen:", 4) || !batch_add(&b, paths[k], out_dir, NULL))
            rc = cli_usage_error("cook", "%s: %s", paths[k],
                                 strncmp(paths[k], "gen:", 4) ? "out of memory"
                                                              : "a batch cooks files, not generated scenes");
    if (rc == CLI_EXIT_OK && manifest)
        rc = read_manifest(manifest, out_dir, &b);
    if (rc == CLI_EXIT_OK && b.count == 0)
        rc = cli_usage_error("cook", "the batch names no input");
    if (rc == CLI_EXIT_OK)
        rc = run_batch(&c, &b, jobs);
    batch_free(&b);
    free(paths);
    material_map_free(&c.map);
    return rc;
}

/* make and ninja users type -j N (or -jN) for parallel jobs: it means --jobs N. */
int cmd_cook(int argc, char **argv)
{
    static char jobs_option[] = "--jobs";
    char **args = malloc((2 * (size_t)argc + 1) * sizeof *args);
    if (!args) {
        cli_error("cook", NULL, "out of memory");
        return CLI_EXIT_USAGE;
    }
    int count = 0, options_end = 0;
    for (int k = 0; k < argc; k++) {
        const char *arg = argv[k];
        options_end |= k > 0 && !strcmp(arg, "--");
        if (k > 0 && !options_end && arg[0] == '-' && arg[1] == 'j') {
            args[count++] = jobs_option;
            if (arg[2])
                args[count++] = argv[k] + 2;
        } else {
            args[count++] = argv[k];
        }
    }
    args[count] = NULL;
    int rc = cook_main(count, args);
    free(args);
    return rc;
}
