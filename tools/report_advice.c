/* report_advice.c: the report's recommendation for one mesh, computed from its figures: the fastest exact
 * configuration, then what a smaller file or lossy choices cost. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "report.h"

/* Run times closer than this fraction count as equal, at least: the spread of repeated runs on a quiet
 * machine. */
#define TIMING_NOISE 0.03
/* The noise allowed for is this many times the gap measured between two runs of the same tree: one pair of
 * runs underestimates the spread. */
#define NOISE_MARGIN 2.0
/* A smaller file is worth a mention from this saving on. */
#define SIZE_SAVING 0.10

typedef struct text {
    char *buf;
    size_t size, len;
} text;

static void say(text *t, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(t->buf + t->len, t->len < t->size ? t->size - t->len : 0, fmt, ap);
    va_end(ap);
    if (n > 0)
        t->len = t->len + (size_t)n < t->size ? t->len + (size_t)n : t->size;
}

/* How the text names a configuration: as its plot label, in quotes, or "the default". */
static const char *name_of(const report_row *r, const report_row *def, char *buf, size_t size)
{
    if (r->is_default)
        return "the default";
    char label[96];
    report_short_label(r, def, label, sizeof label);
    snprintf(buf, size, "\"%s\"", label);
    return buf;
}

static double percent(double a, double b)
{
    return 100.0 * (a - b) / b;
}

const report_row *report_recommend(const report_row *rows, size_t count, char *buf, size_t size)
{
    text t = {buf, size, 0};
    if (size)
        buf[0] = '\0';
    const report_row *fastest = NULL, *second = NULL;
    for (size_t i = 0; i < count; i++) {
        const report_row *r = &rows[i];
        if (r->reference || !report_row_exact(r) || !isfinite(report_ns_per_ray(r)))
            continue;
        if (!fastest || report_ns_per_ray(r) < report_ns_per_ray(fastest)) {
            second = fastest;
            fastest = r;
        } else if (!second || report_ns_per_ray(r) < report_ns_per_ray(second)) {
            second = r;
        }
    }
    if (!fastest) {
        say(&t,
            "No configuration answered every checked ray like the double-precision reference, so the report "
            "recommends none; see the flips and leaks plot.");
        return NULL;
    }
    /* The timing noise of this run, measured: rows that differ from the default only in how sections are
     * stored run the very same tree in memory, so their run times differ by noise alone. */
    const report_row *pick = fastest, *def = report_default_row(rows, count), *twin = NULL;
    double twin_gap = 0.0;
    for (size_t i = 0; i < count && def; i++) {
        int same = !rows[i].is_default && !rows[i].reference;
        for (int d = 0; d < REPORT_DIM_COUNT && same; d++)
            same = d == REPORT_DIM_SECTIONS || strcmp(rows[i].value[d], def->value[d]) == 0;
        double a = report_ns_per_ray(&rows[i]), b = report_ns_per_ray(def),
               gap = fmax(a, b) / fmin(a, b) - 1.0;
        if (same && gap >= twin_gap) {
            twin_gap = gap;
            twin = &rows[i];
        }
    }
    double noise = fmax(TIMING_NOISE, NOISE_MARGIN * twin_gap);
    /* The default when it is exact and within the noise of the fastest: no reason to change anything. */
    int kept_default = 0;
    if (def && def != fastest && report_row_exact(def) &&
        report_ns_per_ray(def) <= report_ns_per_ray(fastest) * (1.0 + noise)) {
        pick = def;
        kept_default = 1;
    }
    char n1[128], n2[128];
    say(&t,
        "Recommended: %s (%s). It answers exactly like the double-precision reference (%llu of %llu sampled "
        "rays flipped or wrong",
        name_of(pick, def, n1, sizeof n1), pick->config,
        (unsigned long long)(pick->flips + pick->wrong_triangle), (unsigned long long)pick->compared);
    if (pick->leaks >= 0)
        say(&t, ", %lld of %llu rays aimed at shared edges and vertices leaked", (long long)pick->leaks,
            (unsigned long long)pick->leak_rays);
    say(&t, ") and takes %.0f ns per closest-hit ray (%.2f MRays/s), ", report_ns_per_ray(pick),
        pick->closest_mrays);
    char noise_text[256];
    if (twin)
        snprintf(noise_text, sizeof noise_text,
                 "the default and %s run the same tree and differ by %.0f %%, so "
                 "differences under %.0f %% count as noise",
                 name_of(twin, def, n2, sizeof n2), twin_gap * 100, noise * 100);
    else
        snprintf(noise_text, sizeof noise_text, "differences under %.0f %% count as noise", noise * 100);
    if (kept_default)
        say(&t,
            "within the timing noise of the fastest exact configuration, %s at %.0f ns, so nothing needs "
            "changing (%s). ",
            name_of(fastest, def, n2, sizeof n2), report_ns_per_ray(fastest), noise_text);
    else if (def && pick != def)
        say(&t,
            "the fastest of the exact configurations, %.0f %% faster than the default, more than the timing "
            "noise (%s). ",
            percent(report_ns_per_ray(def), report_ns_per_ray(pick)), noise_text);
    else if (second)
        say(&t, "the fastest of the exact configurations; the next, %s, is %.0f %% slower. ",
            name_of(second, def, n2, sizeof n2), percent(report_ns_per_ray(second), report_ns_per_ray(pick)));
    else
        say(&t, "the only exact configuration. ");

    /* A smaller exact file: the size against the open time. */
    const report_row *smallest = NULL;
    for (size_t i = 0; i < count; i++)
        if (!rows[i].reference && report_row_exact(&rows[i]) &&
            (!smallest || rows[i].bytes_per_triangle < smallest->bytes_per_triangle))
            smallest = &rows[i];
    if (smallest && smallest->bytes_per_triangle < pick->bytes_per_triangle * (1.0 - SIZE_SAVING)) {
        say(&t,
            "Where file size matters more, %s gives %.1f bytes per triangle instead of %.1f (%.0f %%) with "
            "the "
            "same answers",
            name_of(smallest, def, n2, sizeof n2), smallest->bytes_per_triangle, pick->bytes_per_triangle,
            percent(smallest->bytes_per_triangle, pick->bytes_per_triangle));
        /* Stored otherwise, the same tree runs the same once open: a gap between the two is noise, not a
         * cost. */
        int same_tree = 1;
        for (int d = 0; d < REPORT_DIM_COUNT; d++)
            same_tree &= d == REPORT_DIM_SECTIONS || strcmp(smallest->value[d], pick->value[d]) == 0;
        if (same_tree)
            say(&t,
                " and the same tree, so the same speed once open (its %.0f ns per ray against %.0f is timing "
                "noise)",
                report_ns_per_ray(smallest), report_ns_per_ray(pick));
        else
            say(&t, ", at %.0f ns per ray", report_ns_per_ray(smallest));
        say(&t, "; opening takes %.2f ms instead of %.2f ms. ", smallest->open_seconds * 1e3,
            pick->open_seconds * 1e3);
    }

    /* Lossy choices: what they save against the default they vary from, and what they break. */
    for (size_t i = 0; i < count; i++) {
        const report_row *r = &rows[i];
        if (r->reference || report_row_exact(r))
            continue;
        const report_row *base = def ? def : pick;
        double saved = -percent(r->bytes_per_triangle, base->bytes_per_triangle);
        say(&t, "%s ", name_of(r, def, n2, sizeof n2));
        if (saved > 0.5)
            say(&t, "saves %.0f %% of the file against %s but ", saved, name_of(base, def, n1, sizeof n1));
        say(&t,
            "is not exact: hits move by up to %.1e of the scene diagonal and %llu of %llu sampled rays flip "
            "or "
            "hit another triangle",
            r->t_err_max, (unsigned long long)(r->flips + r->wrong_triangle),
            (unsigned long long)r->compared);
        if (r->leaks > 0)
            say(&t, ", and %lld of %llu edge and vertex rays leak", (long long)r->leaks,
                (unsigned long long)r->leak_rays);
        say(&t, "; choose it only when that error is acceptable. ");
    }

    /* What the 16-bit boxes cost against exact float boxes: the reference row walks the default's tree in the
     * default's order, so the default's extra nodes are the boxes' price alone. */
    for (size_t i = 0; i < count && def; i++)
        if (rows[i].reference) {
            say(&t,
                "The 16-bit node boxes are %.1f %% larger in area than exact float boxes on average and cost "
                "%+.2f nodes per ray (%.1f against %.1f on the default's tree), the price of compact 16-bit "
                "boxes.",
                100.0 * def->inflation_mean, def->extra_nodes, def->nodes_per_ray, rows[i].nodes_per_ray);
            break;
        }
    /* trailing space off */
    while (t.len > 0 && t.len <= size && buf[t.len - 1] == ' ')
        buf[--t.len] = '\0';
    return pick;
}
