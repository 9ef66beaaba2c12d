/* fuzz_open.c: libFuzzer target: open any bytes from memory (as given, and with checksums repaired) and query
 * what opens. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cbvh.h"
#include "fuzz_support.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Opens the guarded copy; an accepted file must describe itself consistently
 * and answer every query within bounds, a rejected one must say why. */
static void open_and_query(const guard_buffer *g, uint64_t seed)
{
    cbvh_file *f = (cbvh_file *)(uintptr_t)1; /* must be overwritten or left alone, never half set */
    cbvh_error err;
    memset(&err, 0, sizeof err);
    cbvh_result r = cbvh_open_memory(g->data, g->size, NULL, &f, &err);
    if (r != CBVH_OK) {
        fuzz_check_error(r, &err);
        return;
    }
    FUZZ_CHECK(f != NULL, "open succeeded with a NULL file");
    cbvh_file_info info;
    cbvh_file_get_info(f, &info, sizeof info);
    FUZZ_CHECK(info.file_size == g->size, "file_size %llu for %zu bytes", (unsigned long long)info.file_size,
               g->size);
    FUZZ_CHECK(info.format_version == CBVH_FORMAT_VERSION, "opened format version %u", info.format_version);
    FUZZ_CHECK(info.triangle_count >= 1 && info.node_count >= 1 && info.depth >= 1 && info.depth <= 64,
               "opened a file with %u triangles, %u nodes, depth %u", info.triangle_count, info.node_count,
               info.depth);
    for (uint32_t i = 0; i < info.section_count; i++) {
        cbvh_section_info s;
        FUZZ_CHECK(cbvh_file_get_section(f, i, &s), "section %u of %u not described", i, info.section_count);
        FUZZ_CHECK(s.offset <= g->size && s.stored_size <= g->size - s.offset, "section %u past the end", i);
    }
    cbvh_section_info none;
    FUZZ_CHECK(!cbvh_file_get_section(f, info.section_count, &none), "section past the count described");
    /* material names: each one readable, in (id, name) order, and found by its id */
    uint32_t prev_id = 0;
    const char *prev = NULL;
    for (uint32_t k = 0; k < info.material_name_count; k++) {
        uint32_t id;
        const char *name = cbvh_file_get_material_name(f, k, &id);
        FUZZ_CHECK(name != NULL, "material name %u of %u missing", k, info.material_name_count);
        FUZZ_CHECK(!prev || id > prev_id || (id == prev_id && strcmp(prev, name) < 0),
                   "material name %u out of (id, name) order", k);
        const char *first = cbvh_file_find_material_name(f, id);
        FUZZ_CHECK(first && (first == name || (prev && prev_id == id)), "material name %u not found by id %u",
                   k, id);
        prev = name;
        prev_id = id;
    }
    FUZZ_CHECK(!cbvh_file_get_material_name(f, info.material_name_count, NULL),
               "material name past the count");
    fuzz_check_queries(f, g->data, g->size, seed, 0);
    cbvh_close(f);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint64_t seed = size;
    for (size_t i = 0; i < size && i < 64; i++)
        seed = seed * 131 + data[i];

    guard_buffer g;
    guard_copy(&g, data, size);
    open_and_query(&g, seed);
    /* the same bytes with size and checksums repaired, so the structural
     * checks behind the CRCs see the mutation */
    fuzz_repair_checksums(g.data, size);
    if (size >= 128 && memcmp(g.data, data, size) != 0)
        open_and_query(&g, seed);
    guard_release(&g);
    return 0;
}
