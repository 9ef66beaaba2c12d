/* cmd_info.c: `cbvh info`: header, sections, tree statistics and quantization error of a .cbvh file. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "cbvh_internal.h"
#include "commands.h"
#include "json.h"

static const char usage[] =
    "Usage: cbvh info [--json] FILE\n"
    "\n"
    "Opens FILE (fully validated, as cbvh verify does) and describes it: format version and\n"
    "flags; each section's type, offset, size, stored size, codec, encoding and CRC32;\n"
    "triangle, vertex and node counts; depth; the histogram of leaf sizes; the SAH cost of the\n"
    "tree (node visit and triangle test both cost 1, relative to the root's surface area) with\n"
    "the dequantized boxes and with exact boxes; bytes per triangle by section; and the error\n"
    "of the 16-bit node boxes: the mean and worst surface-area inflation of each node's\n"
    "dequantized box over the exact float box of the triangles below it (the worst one\n"
    "named by its node, and with wide4 its child slot: a wide4 node holds its children's\n"
    "boxes); the material\n"
    "ids (per triangle, one for all, or none) and the material names the file stores.\n"
    "\n"
    "Options:\n"
    "  --json       print the same as JSON on stdout\n"
    "  -h, --help   show this help\n"
    "\n"
    "Exit status: 0 success, 1 corrupt or unsupported file, 2 usage or I/O error.\n";

/* How the file stores material ids, as info prints it: "per-triangle", "uniform" or "none". */
static const char *materials_kind(cbvh_material_storage storage)
{
    return storage == CBVH_MATERIALS_NONE      ? "none"
           : storage == CBVH_MATERIALS_UNIFORM ? "uniform"
                                               : "per-triangle";
}

/* How far cost lies above base, in percent (0 when base is not positive). */
static double percent_over(double cost, double base)
{
    return base > 0 ? 100.0 * (cost / base - 1.0) : 0.0;
}

static void json_vec3(json_writer *w, const char *key, const float v[3])
{
    json_begin_array(w, key);
    for (int a = 0; a < 3; a++)
        json_float(w, NULL, v[a]);
    json_end_array(w);
}

static void print_json(const char *path, const cbvh_file *f, const cbvh_tree_stats *ts)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    const cbvh_file_info *in = &info;
    uint32_t uniform_id = 0;
    const cbvh_material_storage materials = cbvh_file_material_storage(f, &uniform_id);
    double per_tri = 1.0 / in->triangle_count;
    json_writer w;
    json_init(&w, stdout);
    json_begin_object(&w, NULL);
    json_string(&w, "file", path);
    json_uint(&w, "file_size", in->file_size);
    json_uint(&w, "format_version", in->format_version);
    json_uint(&w, "compat_flags", in->compat_flags);
    json_uint(&w, "incompat_flags", in->incompat_flags);
    json_uint(&w, "triangles", in->triangle_count);
    json_uint(&w, "original_triangles", in->original_triangle_count);
    json_uint(&w, "vertices", in->vertex_count);
    json_string(&w, "vertex_format",
                in->vertex_format == CBVH_VERTEX_QUANTIZED16 ? "quantized16" : "float32");
    json_string(&w, "layout", in->layout == CBVH_LAYOUT_WIDE4 ? "wide4" : "binary");
    json_bool(&w, "remap", (int)in->has_remap);
    json_bool(&w, "materials", (int)in->has_materials);
    json_string(&w, "material_ids", materials_kind(materials));
    if (materials == CBVH_MATERIALS_UNIFORM)
        json_uint(&w, "material_uniform_id", uniform_id);
    json_begin_array(&w, "material_names");
    for (uint32_t k = 0; k < in->material_name_count; k++) {
        uint32_t id;
        const char *name = cbvh_file_get_material_name(f, k, &id);
        json_begin_object(&w, NULL);
        json_uint(&w, "id", id);
        json_string(&w, "name", name);
        json_end_object(&w);
    }
    json_end_array(&w);
    json_vec3(&w, "bounds_min", in->bounds_min);
    json_vec3(&w, "bounds_max", in->bounds_max);
    json_vec3(&w, "grid_origin", in->grid_origin);
    json_vec3(&w, "grid_scale", in->grid_scale);
    json_double(&w, "bytes_per_triangle", (double)in->file_size * per_tri);
    json_begin_array(&w, "sections");
    for (uint32_t i = 0; i < in->section_count; i++) {
        cbvh_section_info s;
        if (!cbvh_file_get_section(f, i, &s))
            break;
        json_begin_object(&w, NULL);
        json_string(&w, "type", cli_section_name(s.type));
        json_uint(&w, "type_id", s.type);
        json_uint(&w, "offset", s.offset);
        json_uint(&w, "size", s.size);
        json_uint(&w, "stored_size", s.stored_size);
        json_string(&w, "codec", cbvh_codec_name(s.codec));
        json_string(&w, "encoding", cbvh_encoding_name(s.type, s.encoding));
        char crc[16];
        snprintf(crc, sizeof crc, "%08x", (unsigned)s.crc32);
        json_string(&w, "crc32", crc);
        json_double(&w, "stored_bytes_per_triangle", (double)s.stored_size * per_tri);
        json_end_object(&w);
    }
    json_end_array(&w);
    json_begin_object(&w, "tree");
    json_uint(&w, "nodes", ts->nodes);
    json_uint(&w, "leaves", ts->leaves);
    json_uint(&w, "depth", ts->depth);
    json_uint(&w, "max_leaf_size", in->max_leaf_size);
    json_double(&w, "mean_leaf_size", ts->mean_leaf_size);
    json_begin_object(&w, "leaf_histogram");
    for (uint32_t k = 1; k <= CBVH_MAX_LEAF_SIZE; k++) {
        if (!ts->leaf_histogram[k])
            continue;
        char key[8];
        snprintf(key, sizeof key, "%u", (unsigned)k);
        json_uint(&w, key, ts->leaf_histogram[k]);
    }
    json_end_object(&w);
    json_double(&w, "sah_cost", ts->sah_cost);
    json_double(&w, "sah_cost_exact", ts->sah_cost_exact);
    json_double(&w, "sah_cost_frame16", ts->sah_cost_frame16);
    json_double(&w, "sah_cost_frame8", ts->sah_cost_frame8);
    json_end_object(&w);
    json_begin_object(&w, "box_inflation");
    json_double(&w, "mean", ts->inflation_mean);
    json_double(&w, "max", ts->inflation_max);
    uint32_t node, slot;
    cbvh_tree_box_place(f, ts->inflation_max_box, &node, &slot);
    json_uint(&w, "max_node", node);
    if (in->layout == CBVH_LAYOUT_WIDE4)
        json_uint(&w, "max_slot", slot);
    json_double(&w, "leaf_mean", ts->leaf_inflation_mean);
    json_double(&w, "internal_mean", ts->internal_inflation_mean);
    json_end_object(&w);
    json_end_object(&w);
    json_finish(&w);
}

static void print_text(const char *path, const cbvh_file *f, const cbvh_tree_stats *ts)
{
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    const cbvh_file_info *in = &info;
    uint32_t uniform_id = 0;
    const cbvh_material_storage materials = cbvh_file_material_storage(f, &uniform_id);
    double per_tri = 1.0 / in->triangle_count;
    printf("%s: cbvh format %u, %llu bytes, %.2f bytes/triangle\n", path, (unsigned)in->format_version,
           (unsigned long long)in->file_size, (double)in->file_size * per_tri);
    printf("flags: compatible 0x%08x, incompatible 0x%08x\n", (unsigned)in->compat_flags,
           (unsigned)in->incompat_flags);
    printf("triangles: %u (original ids below %u, %s), vertices: %u (%s)\n", (unsigned)in->triangle_count,
           (unsigned)in->original_triangle_count, in->has_remap ? "remapped" : "cooked order",
           (unsigned)in->vertex_count,
           in->vertex_format == CBVH_VERTEX_QUANTIZED16 ? "quantized16" : "float32");
    if (materials == CBVH_MATERIALS_UNIFORM)
        printf("materials: id %u for every triangle", (unsigned)uniform_id);
    else
        printf("materials: %s",
               materials != CBVH_MATERIALS_NONE ? "an id per triangle" : "none (every id is 0)");
    printf(", %u names\n", (unsigned)in->material_name_count);
    for (uint32_t k = 0; k < in->material_name_count; k++) {
        uint32_t id;
        const char *name = cbvh_file_get_material_name(f, k, &id);
        printf("  material %u: %s\n", (unsigned)id, name);
    }
    printf("layout: %s\n", in->layout == CBVH_LAYOUT_WIDE4 ? "wide4 (4 children per 64-byte node)"
                                                           : "binary (2 children per 16-byte node)");
    printf("bounds: [%g %g %g] - [%g %g %g]\n", in->bounds_min[0], in->bounds_min[1], in->bounds_min[2],
           in->bounds_max[0], in->bounds_max[1], in->bounds_max[2]);
    printf("grid: origin [%g %g %g], scale [%g %g %g]\n", in->grid_origin[0], in->grid_origin[1],
           in->grid_origin[2], in->grid_scale[0], in->grid_scale[1], in->grid_scale[2]);
    /* columns as wide as the longest names: material-names (14), id-name-table (13) */
    printf("\nsections:\n  %-14s %10s %12s %12s %-5s %-13s %-8s %9s\n", "type", "offset", "size", "stored",
           "codec", "encoding", "crc32", "bytes/tri");
    for (uint32_t i = 0; i < in->section_count; i++) {
        cbvh_section_info s;
        if (!cbvh_file_get_section(f, i, &s))
            break;
        printf("  %-14s %10llu %12llu %12llu %-5s %-13s %08x %9.2f\n", cli_section_name(s.type),
               (unsigned long long)s.offset, (unsigned long long)s.size, (unsigned long long)s.stored_size,
               cbvh_codec_name(s.codec), cbvh_encoding_name(s.type, s.encoding), (unsigned)s.crc32,
               (double)s.stored_size * per_tri);
    }
    printf("\ntree: %u nodes, %u leaves, depth %u, max leaf size %u, mean leaf size %.2f\n",
           (unsigned)ts->nodes, (unsigned)ts->leaves, (unsigned)ts->depth, (unsigned)in->max_leaf_size,
           ts->mean_leaf_size);
    printf("leaf sizes:");
    for (uint32_t k = 1; k <= CBVH_MAX_LEAF_SIZE; k++)
        if (ts->leaf_histogram[k])
            printf("  %u: %llu", (unsigned)k, (unsigned long long)ts->leaf_histogram[k]);
    printf("\nSAH cost: %.3f with the 16-bit boxes, %.3f with exact boxes (%+.2f%%)\n", ts->sah_cost,
           ts->sah_cost_exact, percent_over(ts->sah_cost, ts->sah_cost_exact));
    printf("SAH cost were the boxes stored on a frame per node (the parent's box) rather than the mesh grid: "
           "%.3f with 16 bits (%+.2f%%), %.3f with 8 bits (%+.2f%%)\n",
           ts->sah_cost_frame16, percent_over(ts->sah_cost_frame16, ts->sah_cost_exact), ts->sah_cost_frame8,
           percent_over(ts->sah_cost_frame8, ts->sah_cost_exact));
    uint32_t node, slot;
    cbvh_tree_box_place(f, ts->inflation_max_box, &node, &slot);
    printf("box inflation (surface area, 16-bit vs exact): mean %.3f%% (leaves %.3f%%, internal %.3f%%), "
           "worst %.3f%% at node %u",
           100.0 * ts->inflation_mean, 100.0 * ts->leaf_inflation_mean, 100.0 * ts->internal_inflation_mean,
           100.0 * ts->inflation_max, (unsigned)node);
    if (in->layout == CBVH_LAYOUT_WIDE4)
        printf(", child slot %u", (unsigned)slot);
    printf("\n");
}

int cmd_info(int argc, char **argv)
{
    static const cli_option options[] = {{"json", CLI_ARG_NONE, 1}, {NULL, 0, 0}};
    cli_parser p;
    cli_init(&p, "info", usage, argc, argv);
    const char *path = NULL, *value;
    int id, json = 0;
    while ((id = cli_next(&p, options, &value)) != CLI_END) {
        if (id == CLI_DONE)
            return CLI_EXIT_OK;
        if (id == CLI_ERROR)
            return CLI_EXIT_USAGE;
        if (id == 1) {
            json = 1;
        } else if (path) {
            return cli_usage_error("info", "unexpected argument '%s'", value);
        } else {
            path = value;
        }
    }
    if (!path)
        return cli_usage_error("info", "expected a file");
    cbvh_file *file;
    int rc = cli_open("info", path, &file);
    if (rc)
        return rc;
    cbvh_tree_stats ts;
    if (!cbvh_tree_stats_compute(file, 1.0, 1.0, &ts)) {
        cli_error("info", path, "out of memory computing tree statistics");
        cbvh_close(file);
        return CLI_EXIT_USAGE;
    }
    if (json)
        print_json(path, file, &ts);
    else
        print_text(path, file, &ts);
    cbvh_close(file);
    return CLI_EXIT_OK;
}
