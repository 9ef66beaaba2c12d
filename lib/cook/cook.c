/* cook.c: the cooker's entry points: argument and option checks, the phases in order, statistics, timing. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "common/alloc.h"
#include "layout/encodings.h"
#include "common/error.h"
#include "common/format.h"
#include "common/struct_size.h"
#include "common/os.h"
#include "cook/cook_internal.h"

#define OPTIONS_SIZE_MIN CBVH_STRUCT_SIZE_MIN(cbvh_cook_options, max_leaf_size)
#define STATS_SIZE_MIN CBVH_STRUCT_SIZE_MIN(cbvh_cook_stats, input_triangles)

/* The defaults of cbvh.h, in a whole struct of this library's size. */
static void default_options(cbvh_cook_options *o)
{
    memset(o, 0, sizeof *o);
    o->struct_size = sizeof *o;
    /* Fewer, larger leaves: each node skipped is a dependent cache miss saved,
     * and a leaf's triangles sit together in memory (measurements in cbvh.h). */
    o->max_leaf_size = 16;
    o->sah_bins = 32;
    o->traversal_cost = 4.0f;
    o->intersection_cost = 1.0f;
    o->vertex_format = CBVH_VERTEX_FLOAT32;
    o->compress_level = 0;
    o->keep_remap = 1;
    o->keep_materials = 1;
    o->layout = CBVH_LAYOUT_WIDE4;
}

/* struct_size is recorded even when out of range, so that cbvh_cook can explain a bad one. */
CBVH_API cbvh_result cbvh_cook_options_init(cbvh_cook_options *options, size_t struct_size)
{
    if (!cbvh_struct_size_record(options, struct_size, OPTIONS_SIZE_MIN, sizeof *options))
        return CBVH_ERROR_INVALID_ARGUMENT;
    cbvh_cook_options defaults;
    default_options(&defaults);
    defaults.struct_size = struct_size;
    memcpy(options, &defaults, struct_size);
    return CBVH_OK;
}

CBVH_API cbvh_result cbvh_cook_stats_init(cbvh_cook_stats *stats, size_t struct_size)
{
    if (!cbvh_struct_size_record(stats, struct_size, STATS_SIZE_MIN, sizeof *stats))
        return CBVH_ERROR_INVALID_ARGUMENT;
    memset((uint8_t *)stats + sizeof stats->struct_size, 0, struct_size - sizeof stats->struct_size);
    return CBVH_OK;
}

CBVH_API void cbvh_buffer_free(const cbvh_allocator *allocator, void *data)
{
    cbvh_allocator a = cbvh_allocator_resolve(allocator);
    cbvh_free(&a, data);
}

/* The error for a caller's struct `name` (of type `type`, filled by `init`) whose struct_size is out of
 * range. */
static cbvh_result check_struct_size(const char *name, const char *type, const char *init, size_t size,
                                     size_t smallest, size_t largest, cbvh_error *err)
{
    if (cbvh_struct_size_ok(size, smallest, largest))
        return CBVH_OK;
    if (size > largest)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT,
                         "%s->struct_size is %zu, larger than this library's %s (%zu bytes): the program was "
                         "built against a newer cbvh.h than the library it runs with",
                         name, size, type, largest);
    return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT,
                     "%s->struct_size is %zu; it must be %zu to %zu: fill the struct with %s(%s, sizeof *%s)",
                     name, size, smallest, largest, init, name, name);
}

/* The caller's options over the defaults, as far as its struct_size reaches. */
static cbvh_result read_options(const cbvh_cook_options *user, cbvh_cook_options *o, cbvh_error *err)
{
    default_options(o);
    if (!user)
        return CBVH_OK;
    cbvh_result r = check_struct_size("options", "cbvh_cook_options", "cbvh_cook_options_init",
                                      user->struct_size, OPTIONS_SIZE_MIN, sizeof *o, err);
    if (r == CBVH_OK)
        memcpy(o, user, user->struct_size);
    return r;
}

static cbvh_result check_options(const cbvh_cook_options *o, cbvh_error *err)
{
    const cbvh_result bad = CBVH_ERROR_INVALID_ARGUMENT;
    if (o->layout != CBVH_LAYOUT_BINARY && o->layout != CBVH_LAYOUT_WIDE4)
        return cbvh_fail(err, bad,
                         "options->layout is %d; it must be CBVH_LAYOUT_BINARY (0) or CBVH_LAYOUT_WIDE4 (1)",
                         (int)o->layout);
    if (o->max_leaf_size < 1 || o->max_leaf_size > CBVH_MAX_LEAF_SIZE)
        return cbvh_fail(err, bad, "options->max_leaf_size is %u; it must be 1 to %u", o->max_leaf_size,
                         CBVH_MAX_LEAF_SIZE);
    if (o->sah_bins < 4 || o->sah_bins > 256)
        return cbvh_fail(err, bad, "options->sah_bins is %u; it must be 4 to 256", o->sah_bins);
    if (!isfinite(o->traversal_cost) || !(o->traversal_cost >= 0.0f))
        return cbvh_fail(err, bad, "options->traversal_cost is %g; it must be finite and >= 0",
                         (double)o->traversal_cost);
    if (!isfinite(o->intersection_cost) || !(o->intersection_cost > 0.0f))
        return cbvh_fail(err, bad, "options->intersection_cost is %g; it must be finite and > 0",
                         (double)o->intersection_cost);
    if (o->vertex_format != CBVH_VERTEX_FLOAT32 && o->vertex_format != CBVH_VERTEX_QUANTIZED16)
        return cbvh_fail(err, bad,
                         "options->vertex_format is %d; it must be CBVH_VERTEX_FLOAT32 (0) or "
                         "CBVH_VERTEX_QUANTIZED16 (1)",
                         (int)o->vertex_format);
    if (o->compress_level < 0 || o->compress_level > 9)
        return cbvh_fail(err, bad, "options->compress_level is %d; it must be 0 (raw) to 9",
                         o->compress_level);
    if (o->keep_remap != 0 && o->keep_remap != 1)
        return cbvh_fail(err, bad, "options->keep_remap is %d; it must be 0 or 1", o->keep_remap);
    if (o->keep_materials != 0 && o->keep_materials != 1)
        return cbvh_fail(err, bad, "options->keep_materials is %d; it must be 0 or 1", o->keep_materials);
    if (o->material_name_count > 0 && !o->material_names)
        return cbvh_fail(err, bad, "options->material_names is NULL but material_name_count is %u",
                         o->material_name_count);
    for (uint32_t i = 0; i < o->material_name_count; i++)
        if (!o->material_names[i].name)
            return cbvh_fail(err, bad, "options->material_names[%u].name (material id %u) is NULL", i,
                             o->material_names[i].id);
    if (o->material_name_count > 0 && cbvh_cook_material_names_size(o) > CBVH_MAX_MATERIAL_NAME_BYTES)
        return cbvh_fail(err, bad,
                         "options->material_names: %u names take %llu bytes in the file, more than the "
                         "%u a file holds",
                         o->material_name_count, (unsigned long long)cbvh_cook_material_names_size(o),
                         CBVH_MAX_MATERIAL_NAME_BYTES);
    return CBVH_OK;
}

static cbvh_result check_mesh(const cbvh_mesh *m, cbvh_error *err)
{
    const cbvh_result bad = CBVH_ERROR_INVALID_ARGUMENT;
    if (!m)
        return cbvh_fail(err, bad, "mesh is NULL");
    if (!m->positions && m->vertex_count > 0)
        return cbvh_fail(err, bad, "mesh->positions is NULL but vertex_count is %zu", m->vertex_count);
    if (!m->indices && m->triangle_count > 0)
        return cbvh_fail(err, bad, "mesh->indices is NULL but triangle_count is %zu", m->triangle_count);
    if (m->position_stride != 0 && m->position_stride < 3 * sizeof(float))
        return cbvh_fail(err, bad, "mesh->position_stride is %zu; it must be 0 (packed) or at least 12",
                         m->position_stride);
    const size_t stride = m->position_stride ? m->position_stride : 3 * sizeof(float);
    if (m->vertex_count > 0 && m->vertex_count - 1 > (SIZE_MAX - 3 * sizeof(float)) / stride)
        return cbvh_fail(err, bad,
                         "mesh->vertex_count %zu times position_stride %zu overflows the address space",
                         m->vertex_count, stride);
    if (m->triangle_count > SIZE_MAX / 3)
        return cbvh_fail(err, bad, "mesh->triangle_count %zu overflows the address space", m->triangle_count);
    return CBVH_OK;
}

/* Everything a cook owns between phases, freed in one place. */
typedef struct cook_state {
    cbvh_meter meter; /* counts what the cook holds; its inner allocator is the caller's */
    cbvh_allocator a; /* allocates through the meter */
    cook_mesh mesh;
    uint16_t *quantized;
    cook_grid grid;
    cook_tree tree;
    cook_layout layout;
    cook_sections sections;
} cook_state;

static void state_free(cook_state *s)
{
    cbvh_cook_sections_free(&s->a, &s->sections);
    cbvh_cook_layout_free(&s->a, &s->layout);
    cbvh_cook_tree_free(&s->a, &s->tree);
    cbvh_free(&s->a, s->quantized);
    cbvh_cook_mesh_free(&s->a, &s->mesh);
}

/* Grid from the kept mesh's bounds; with quantized vertices the positions move onto it, and
 * the tree is then built from what readers decode, so every box stays conservative. */
static cbvh_result make_grid(cook_state *s, const cbvh_cook_options *o, cbvh_cook_stats *st, cbvh_error *err)
{
    cbvh_result r = cbvh_cook_grid_init(&s->grid, s->mesh.bounds_min, s->mesh.bounds_max, err);
    if (r != CBVH_OK || o->vertex_format != CBVH_VERTEX_QUANTIZED16)
        return r;
    s->quantized = cbvh_alloc_array(&s->a, s->mesh.vertex_count, 3 * sizeof(uint16_t), 64);
    if (!s->quantized)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while quantizing %u vertices",
                         s->mesh.vertex_count);
    st->vertex_max_error =
        cbvh_cook_quantize_vertices(&s->grid, s->mesh.positions, s->quantized, s->mesh.vertex_count);
    s->mesh.positions_for_build = 1;
    /* A triangle smaller than the grid step can lose its area on the grid: readers
     * would hold a segment that no ray and no overlap can report, so it goes. */
    r = cbvh_cook_drop_collapsed(&s->mesh, &s->a, err);
    if (r != CBVH_OK)
        return r;
    if (s->mesh.triangle_count == 0)
        return cbvh_fail(
            err, CBVH_ERROR_EMPTY_MESH,
            "all triangles collapsed to zero area on the 16-bit vertex grid (quantized vertices)");
    return cbvh_cook_mesh_bounds(&s->mesh, err);
}

static void fill_stats(const cook_state *s, cbvh_cook_stats *st)
{
    st->input_triangles = s->mesh.input_triangle_count;
    st->dropped_degenerate = s->mesh.dropped_degenerate;
    st->flushed_coordinates = s->mesh.flushed_coordinates;
    st->triangles = s->layout.triangle_count;
    st->vertices = s->layout.vertex_count;
    st->nodes = s->layout.node_count;
    st->leaves = s->layout.leaf_count;
    st->depth = s->layout.depth;
    st->sah_cost = s->layout.sah_cost;
}

/* Encodes the sections, then frees the mesh and the layout before the file is put together, so the
 * cook never holds them and the file at once. */
static cbvh_result write_file(cook_state *s, const cbvh_mesh *mesh, const cbvh_cook_options *o,
                              const cook_progress *progress, uint8_t **out, size_t *out_size,
                              cbvh_cook_stats *st, cbvh_error *err)
{
    cbvh_result r =
        cbvh_cook_sections_encode(&s->layout, &s->mesh, s->quantized, mesh, o, &s->a, &s->sections, err);
    if (r != CBVH_OK)
        return r;
    cook_header h;
    memset(&h, 0, sizeof h);
    h.triangle_count = s->layout.triangle_count;
    h.vertex_count = s->layout.vertex_count;
    h.incompat_flags = s->layout.layout == CBVH_LAYOUT_WIDE4 ? CBVH_INCOMPAT_W4_DEPTH_FIRST : 0;
    h.node_count = s->layout.node_count;
    h.depth = s->layout.depth;
    h.max_leaf_size = s->layout.max_leaf_count;
    h.original_triangle_count = s->sections.original_triangle_count;
    memcpy(h.grid_origin, s->grid.origin, sizeof h.grid_origin);
    memcpy(h.grid_scale, s->grid.scale, sizeof h.grid_scale);
    memcpy(h.bounds_min, s->mesh.bounds_min, sizeof h.bounds_min);
    memcpy(h.bounds_max, s->mesh.bounds_max, sizeof h.bounds_max);
    fill_stats(s, st);
    cbvh_cook_layout_free(&s->a, &s->layout);
    cbvh_free(&s->a, s->quantized);
    s->quantized = NULL;
    cbvh_cook_mesh_free(&s->a, &s->mesh);
    return cbvh_cook_write_file(&h, &s->sections, o->compress_level, &s->meter, progress, out, out_size,
                                st->section_stored_size, st->section_size, err);
}

CBVH_API cbvh_result cbvh_cook(const cbvh_mesh *mesh, const cbvh_cook_options *options,
                               const cbvh_allocator *allocator, void **out_data, size_t *out_size,
                               cbvh_cook_stats *stats, cbvh_error *err)
{
    cbvh_error_clear(err);
    if (!out_data || !out_size)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT, "out_data and out_size must not be NULL");
    *out_data = NULL;
    *out_size = 0;
    cbvh_cook_options options_read;
    const cbvh_cook_options *o = &options_read;
    cbvh_result r = check_mesh(mesh, err);
    if (r == CBVH_OK)
        r = read_options(options, &options_read, err);
    if (r == CBVH_OK)
        r = check_options(o, err);
    if (r == CBVH_OK && stats)
        r = check_struct_size("stats", "cbvh_cook_stats", "cbvh_cook_stats_init", stats->struct_size,
                              STATS_SIZE_MIN, sizeof *stats, err);
    if (r != CBVH_OK)
        return r;

    cbvh_cook_stats st;
    memset(&st, 0, sizeof st);
    st.input_vertices = mesh->vertex_count;
    cook_state s;
    memset(&s, 0, sizeof s);
    s.meter.inner = cbvh_allocator_resolve(allocator);
    s.a = cbvh_meter_allocator(&s.meter);
    cook_progress progress = {o->progress, o->progress_user, CBVH_PHASE_PREPARE};
    /* a wide4 leaf holds at most 8 triangles: a larger limit acts as 8 */
    const uint32_t max_leaf = o->layout == CBVH_LAYOUT_WIDE4 && o->max_leaf_size > CBVH_W4_MAX_LEAF
                                  ? CBVH_W4_MAX_LEAF
                                  : o->max_leaf_size;
    const cook_build_params params = {max_leaf, o->sah_bins, o->traversal_cost, o->intersection_cost};
    uint8_t *file = NULL;
    size_t file_size = 0;

    double t0 = cbvh_os_seconds();
    cook_report(&progress, 0.0);
    r = cbvh_cook_prepare(mesh, &s.a, &progress, &s.mesh, err);
    if (r == CBVH_OK)
        r = make_grid(&s, o, &st, err);
    double t1 = cbvh_os_seconds();
    st.seconds[CBVH_PHASE_PREPARE] = t1 - t0;
    if (r == CBVH_OK) {
        progress.phase = CBVH_PHASE_BUILD;
        cook_report(&progress, 0.0);
        r = cbvh_cook_build(&s.mesh, &params, &s.a, &progress, &s.tree, err);
    }
    double t2 = cbvh_os_seconds();
    st.seconds[CBVH_PHASE_BUILD] = t2 - t1;
    if (r == CBVH_OK) {
        progress.phase = CBVH_PHASE_LAYOUT;
        cook_report(&progress, 0.0);
        /* The reported SAH cost uses unit costs whatever the build's costs, so trees cooked
         * with different options compare (and `cbvh info` computes the same figure). */
        const uint32_t vertex_size =
            cbvh_element_size(CBVH_SECTION_VERTICES,
                              o->vertex_format == CBVH_VERTEX_QUANTIZED16 ? CBVH_VERTS_Q16 : CBVH_VERTS_F32);
        r = cbvh_cook_layout_place(&s.tree, s.mesh.triangle_count, &s.grid, o->layout, 1.0f, 1.0f, &s.a,
                                   &s.layout, err);
        cbvh_cook_tree_free(&s.a, &s.tree);
        if (r == CBVH_OK)
            r = cbvh_cook_mesh_restore_triangles(&s.mesh, mesh, &s.a, err);
        if (r == CBVH_OK)
            r = cbvh_cook_layout_number(&s.mesh, vertex_size, &s.a, &s.layout, err);
        /* From here on the layout holds the triangles. */
        cbvh_free(&s.a, s.mesh.indices);
        s.mesh.indices = NULL;
        if (r == CBVH_OK)
            cook_report(&progress, 1.0);
    }
    double t3 = cbvh_os_seconds();
    st.seconds[CBVH_PHASE_LAYOUT] = t3 - t2;
    if (r == CBVH_OK) {
        progress.phase = CBVH_PHASE_WRITE;
        cook_report(&progress, 0.0);
        r = write_file(&s, mesh, o, &progress, &file, &file_size, &st, err);
    }
    st.seconds[CBVH_PHASE_WRITE] = cbvh_os_seconds() - t3;

    st.peak_memory = s.meter.peak;
    if (r == CBVH_OK) {
        st.file_size = file_size;
        *out_data = file;
        *out_size = file_size;
    }
    state_free(&s);
    if (stats) {
        st.struct_size = stats->struct_size;
        memcpy(stats, &st, stats->struct_size);
    }
    return r;
}
