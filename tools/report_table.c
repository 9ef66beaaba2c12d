/* report_table.c: the report's summary table, one place for its columns: the markdown output and the HTML
 * page both print it. */
#include <stdio.h>

#include "report.h"

static const char *const titles[REPORT_COLUMN_COUNT] = {
    "mesh",           "configuration",      "bytes/tri",
    "open ms",        "closest MRays/s",    "any MRays/s",
    "nodes/ray",      "tris/ray",           "extra nodes/ray",
    "extra tris/ray", "box inflation mean", "box inflation worst",
    "flips",          "wrong tri",          "t err max",
    "t err RMS",      "vertex err",         "leaked rays",
};

const char *report_column_title(int column)
{
    return titles[column];
}

void report_cell(const report_row *r, int column, char *buf, size_t size)
{
    switch (column) {
    case 0:
        snprintf(buf, size, "%s", r->mesh);
        break;
    case 1:
        snprintf(buf, size, "%s", r->config);
        break;
    case 2:
        snprintf(buf, size, "%.2f", r->bytes_per_triangle);
        break;
    case 3:
        if (r->open_seconds >= 0.0)
            snprintf(buf, size, "%.3f", r->open_seconds * 1e3);
        else
            snprintf(buf, size, "-");
        break;
    case 4:
        snprintf(buf, size, "%.3f", r->closest_mrays);
        break;
    case 5:
        snprintf(buf, size, "%.3f", r->any_mrays);
        break;
    case 6:
        snprintf(buf, size, "%.1f", r->nodes_per_ray);
        break;
    case 7:
        snprintf(buf, size, "%.2f", r->tris_per_ray);
        break;
    case 8:
        snprintf(buf, size, "%+.2f", r->extra_nodes);
        break;
    case 9:
        snprintf(buf, size, "%+.3f", r->extra_tris);
        break;
    case 10:
        snprintf(buf, size, "%.4f", r->inflation_mean);
        break;
    case 11:
        snprintf(buf, size, "%.3f", r->inflation_worst);
        break;
    case 12:
        snprintf(buf, size, "%llu", (unsigned long long)r->flips);
        break;
    case 13:
        snprintf(buf, size, "%llu", (unsigned long long)r->wrong_triangle);
        break;
    case 14:
        snprintf(buf, size, "%.2e", r->t_err_max);
        break;
    case 15:
        snprintf(buf, size, "%.2e", r->t_err_rms);
        break;
    case 16:
        snprintf(buf, size, "%.2e", r->vertex_error);
        break;
    default:
        if (r->leaks >= 0)
            snprintf(buf, size, "%lld / %llu", (long long)r->leaks, (unsigned long long)r->leak_rays);
        else
            snprintf(buf, size, "n/a (not closed)");
    }
}
