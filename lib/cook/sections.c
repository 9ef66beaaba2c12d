/* sections.c: section payloads in the narrowest encoding the spec allows (section 4), little-endian. */
#include <stdlib.h>
#include <string.h>

#include "common/alloc.h"
#include "layout/encodings.h"
#include "layout/triangle_encodings.h"
#include "common/endian.h"
#include "common/error.h"
#include "common/format.h"
#include "cook/cook_internal.h"

static inline void put_u16(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}

/* A new section of `count` elements of `encoding`, appended to `out`; NULL when out of memory. */
static uint8_t *section_alloc(const cbvh_allocator *a, cook_sections *out, uint32_t type, uint32_t encoding,
                              size_t count)
{
    const size_t elem = cbvh_element_size(type, encoding);
    cook_section *s = &out->s[out->count];
    s->data = cbvh_alloc_array(a, count, elem, 64);
    if (!s->data)
        return NULL;
    s->type = type;
    s->encoding = encoding;
    s->size = (uint64_t)count * elem;
    out->count++;
    return s->data;
}

/* Wide4 nodes are laid out in their file bytes already: the section takes them over. Binary ones are
 * serialized here. */
static int encode_nodes(cook_layout *l, const cbvh_allocator *a, cook_sections *out)
{
    if (l->layout == CBVH_LAYOUT_WIDE4) {
        cook_section *s = &out->s[out->count++];
        s->type = CBVH_SECTION_NODES;
        s->encoding = CBVH_NODES_W4;
        s->data = l->nodes;
        s->size = (uint64_t)l->node_count * cbvh_element_size(CBVH_SECTION_NODES, CBVH_NODES_W4);
        l->nodes = NULL;
        return 1;
    }
    const size_t elem = cbvh_element_size(CBVH_SECTION_NODES, CBVH_NODES_Q16);
    uint8_t *p = section_alloc(a, out, CBVH_SECTION_NODES, CBVH_NODES_Q16, l->node_count);
    if (!p)
        return 0;
    for (uint32_t i = 0; i < l->node_count; i++, p += elem) {
        const cbvh_node *n = (const cbvh_node *)l->nodes + i;
        for (int k = 0; k < 3; k++) {
            put_u16(p + 2 * k, n->qmin[k]);
            put_u16(p + 6 + 2 * k, n->qmax[k]);
        }
        cbvh_write_u32(p + 12, n->word);
    }
    return 1;
}

/* The triangles in the encoding the layout chose (layout.c: the fewest bytes). */
static int encode_triangles(const cook_layout *l, const cbvh_allocator *a, cook_sections *out)
{
    const uint32_t enc = l->triangle_encoding;
    const cbvh_encoding *e = cbvh_encoding_of(CBVH_SECTION_TRIANGLES, enc);
    const size_t elem = e->element_size;
    uint8_t *p = section_alloc(a, out, CBVH_SECTION_TRIANGLES, enc, cbvh_elements_for(e, l->triangle_count));
    if (!p)
        return 0;
    const uint32_t *t = l->triangles;
    if (enc == CBVH_TRIS_LOCAL8) { /* the numbering keeps a block's ids within CBVH_LOCAL8_WINDOW */
        for (uint32_t b = 0; b < l->triangle_count; b += CBVH_LOCAL8_BLOCK, p += elem) {
            const uint32_t n =
                l->triangle_count - b < CBVH_LOCAL8_BLOCK ? l->triangle_count - b : CBVH_LOCAL8_BLOCK;
            cbvh_local8_encode_block(p, t + 3 * (size_t)b, n);
        }
        return 1;
    }
    for (uint32_t i = 0; i < l->triangle_count; i++, t += 3, p += elem) {
        if (enc == CBVH_TRIS_U16)
            cbvh_u16_encode(p, t);
        else if (enc == CBVH_TRIS_U32)
            cbvh_u32_encode(p, t);
        else /* the numbering's copies make every triangle's deltas fit */
            cbvh_delta16_encode(p, t);
    }
    return 1;
}

static int encode_vertices(const cook_layout *l, const cook_mesh *m, const uint16_t *quantized,
                           const cbvh_allocator *a, cook_sections *out)
{
    const uint32_t enc = quantized ? CBVH_VERTS_Q16 : CBVH_VERTS_F32;
    const size_t elem = cbvh_element_size(CBVH_SECTION_VERTICES, enc);
    uint8_t *p = section_alloc(a, out, CBVH_SECTION_VERTICES, enc, l->vertex_count);
    if (!p)
        return 0;
    for (uint32_t v = 0; v < l->vertex_count; v++, p += elem) {
        const size_t src = 3 * (size_t)l->vertex_source[v];
        for (int k = 0; k < 3; k++) {
            if (quantized)
                put_u16(p + 2 * k, quantized[src + (size_t)k]);
            else
                cbvh_write_f32(p + 4 * k, m->positions[src + (size_t)k]);
        }
    }
    return 1;
}

/* The narrowest per-triangle encoding of an id section (REMAP, MATERIALS) that holds `largest`. */
static uint32_t id_encoding(uint32_t type, uint32_t largest)
{
    uint32_t best = 0, best_size = UINT32_MAX;
    for (uint32_t enc = 0; enc < CBVH_MAX_ENCODINGS; enc++) {
        const cbvh_encoding *e = cbvh_encoding_of(type, enc);
        if (e && !e->uniform && e->max_value >= largest && e->element_size < best_size) {
            best = enc;
            best_size = e->element_size;
        }
    }
    return best;
}

/* `count` ids as a section of `type` in the narrowest encoding that holds `largest`. */
static int encode_ids(const cbvh_allocator *a, cook_sections *out, uint32_t type, uint32_t largest,
                      const uint32_t *values, uint32_t count)
{
    const uint32_t enc = id_encoding(type, largest);
    const size_t elem = cbvh_element_size(type, enc);
    uint8_t *p = section_alloc(a, out, type, enc, count);
    if (!p)
        return 0;
    for (uint32_t i = 0; i < count; i++, p += elem) {
        if (elem == 1) {
            *p = (uint8_t)values[i];
        } else if (elem == 2) {
            put_u16(p, values[i]);
        } else if (elem == 3) {
            put_u16(p, values[i]);
            p[2] = (uint8_t)(values[i] >> 16);
        } else {
            cbvh_write_u32(p, values[i]);
        }
    }
    return 1;
}

/* REMAP: cooked triangle -> input id. Left out when asked, or when it would be the identity. */
static int encode_remap(const cook_layout *l, const cook_mesh *m, const cbvh_cook_options *o,
                        uint32_t *scratch, const cbvh_allocator *a, cook_sections *out)
{
    out->original_triangle_count = l->triangle_count;
    if (!o->keep_remap)
        return 1;
    int identity = m->input_triangle_count == l->triangle_count;
    for (uint32_t t = 0; t < l->triangle_count; t++) {
        scratch[t] = cbvh_cook_original_id(m, l->triangle_source[t]);
        identity &= scratch[t] == t;
    }
    if (identity)
        return 1;
    out->original_triangle_count = m->input_triangle_count;
    return encode_ids(a, out, CBVH_SECTION_REMAP, m->input_triangle_count - 1, scratch, l->triangle_count);
}

/* MATERIALS: left out when not given, not wanted, or all 0; one uniform id when all are equal; else u8, u16
 * or u32 by the largest id. */
static int encode_materials(const cook_layout *l, const cook_mesh *m, const cbvh_mesh *input,
                            const cbvh_cook_options *o, uint32_t *scratch, const cbvh_allocator *a,
                            cook_sections *out)
{
    if (!input->material_ids || !o->keep_materials)
        return 1;
    uint32_t largest = 0;
    int all_equal = 1;
    for (uint32_t t = 0; t < l->triangle_count; t++) {
        scratch[t] = input->material_ids[cbvh_cook_original_id(m, l->triangle_source[t])];
        largest = scratch[t] > largest ? scratch[t] : largest;
        all_equal &= scratch[t] == scratch[0];
    }
    if (all_equal && largest == 0)
        return 1;
    if (all_equal) {
        uint8_t *p = section_alloc(a, out, CBVH_SECTION_MATERIALS, CBVH_MATS_UNIFORM, 1);
        if (p)
            cbvh_write_u32(p, largest);
        return p != NULL;
    }
    return encode_ids(a, out, CBVH_SECTION_MATERIALS, largest, scratch, l->triangle_count);
}

/* Orders names by id, then by their bytes (strcmp compares them as unsigned char), as the spec's table is. */
static int compare_names(const void *xp, const void *yp)
{
    const cbvh_material_name *x = *(const cbvh_material_name *const *)xp,
                             *y = *(const cbvh_material_name *const *)yp;
    if (x->id != y->id)
        return x->id < y->id ? -1 : 1;
    return strcmp(x->name, y->name);
}

uint64_t cbvh_cook_material_names_size(const cbvh_cook_options *o)
{
    uint64_t size = 4;
    for (uint32_t i = 0; i < o->material_name_count; i++)
        size += 8 + strlen(o->material_names[i].name) + 1;
    return size;
}

/* MATERIAL_NAMES: the caller's names sorted (the order is total, so the bytes do not depend on the order
 * given), exact repeats once; left out when there are none. */
static int encode_material_names(const cbvh_cook_options *o, const cbvh_allocator *a, cook_sections *out)
{
    if (!o->keep_materials || o->material_name_count == 0)
        return 1;
    const cbvh_material_name **sorted = cbvh_alloc_array(a, o->material_name_count, sizeof *sorted, 64);
    if (!sorted)
        return 0;
    for (uint32_t i = 0; i < o->material_name_count; i++)
        sorted[i] = &o->material_names[i];
    qsort(sorted, o->material_name_count, sizeof *sorted, compare_names);
    uint32_t n = 0;
    for (uint32_t i = 0; i < o->material_name_count; i++)
        if (n == 0 || compare_names(&sorted[n - 1], &sorted[i]) != 0)
            sorted[n++] = sorted[i];
    uint64_t size = 4 + 8 * (uint64_t)n;
    for (uint32_t i = 0; i < n; i++)
        size += strlen(sorted[i]->name) + 1;
    uint8_t *p = section_alloc(a, out, CBVH_SECTION_MATERIAL_NAMES, CBVH_NAMES_TABLE, (size_t)size);
    if (p) {
        cbvh_write_u32(p, n);
        uint8_t *names = p + 4 + 8 * (size_t)n, *at = names;
        for (uint32_t i = 0; i < n; i++) {
            const size_t len = strlen(sorted[i]->name) + 1;
            cbvh_write_u32(p + 4 + 8 * (size_t)i, sorted[i]->id);
            cbvh_write_u32(p + 8 + 8 * (size_t)i, (uint32_t)(at - names));
            memcpy(at, sorted[i]->name, len);
            at += len;
        }
    }
    cbvh_free(a, sorted);
    return p != NULL;
}

void cbvh_cook_sections_free(const cbvh_allocator *a, cook_sections *s)
{
    for (uint32_t i = 0; i < s->count; i++)
        cbvh_free(a, s->s[i].data);
    memset(s, 0, sizeof *s);
}

cbvh_result cbvh_cook_sections_encode(cook_layout *l, const cook_mesh *m, const uint16_t *quantized,
                                      const cbvh_mesh *input, const cbvh_cook_options *o,
                                      const cbvh_allocator *a, cook_sections *out, cbvh_error *err)
{
    memset(out, 0, sizeof *out);
    int ok = encode_nodes(l, a, out) && encode_triangles(l, a, out);
    cbvh_free(a, l->triangles);
    l->triangles = NULL;
    uint32_t *scratch = ok ? cbvh_alloc_array(a, l->triangle_count, sizeof(uint32_t), 64) : NULL;
    ok = scratch && encode_vertices(l, m, quantized, a, out) && encode_remap(l, m, o, scratch, a, out) &&
         encode_materials(l, m, input, o, scratch, a, out) && encode_material_names(o, a, out);
    cbvh_free(a, scratch);
    if (!ok) {
        cbvh_cook_sections_free(a, out);
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory while encoding the sections");
    }
    return CBVH_OK;
}
