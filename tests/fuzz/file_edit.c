/* file_edit.c: takes a valid cbvh file apart into sections and lays it out again, for seed corpora and
 * corruption tests. */
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "file_edit.h"
#include "fuzz_support.h"
#include "le_bytes.h"

int edit_parse(edit_file *e, const uint8_t *bytes, size_t size)
{
    memset(e, 0, sizeof *e);
    if (size < 128)
        return 0;
    memcpy(e->header, bytes, 128);
    e->count = le_get_u32(bytes + 24);
    if (e->count > 16 || 128 + 40 * (size_t)e->count > size)
        return 0;
    for (uint32_t i = 0; i < e->count; i++) {
        const uint8_t *t = bytes + 128 + 40 * i;
        uint64_t off = le_get_u64(t + 8), stored = le_get_u64(t + 16), full = le_get_u64(t + 24);
        edit_section *s = &e->s[i];
        s->type = le_get_u32(t);
        s->codec = le_get_u32(t + 4);
        s->encoding = le_get_u32(t + 36);
        if (off > size || stored > size - off || full > (1u << 30))
            goto fail;
        s->size = (size_t)full;
        s->data = malloc(full ? (size_t)full : 1);
        if (!s->data)
            goto fail;
        if (s->codec == 0) {
            memcpy(s->data, bytes + off, (size_t)full);
        } else {
            uLongf n = (uLongf)full;
            if (uncompress(s->data, &n, bytes + off, (uLong)stored) != Z_OK || n != full)
                goto fail;
            s->codec = 1;
        }
    }
    return 1;
fail:
    edit_free(e);
    return 0;
}

uint8_t *edit_build(const edit_file *e, size_t *size)
{
    uint8_t *stored[16] = {0};
    size_t stored_size[16];
    size_t total = (128 + 40 * (size_t)e->count + 63) & ~(size_t)63;
    for (uint32_t i = 0; i < e->count; i++) {
        const edit_section *s = &e->s[i];
        if (s->codec == 1) {
            uLongf n = compressBound((uLong)s->size);
            stored[i] = malloc(n);
            if (!stored[i] || compress2(stored[i], &n, s->data, (uLong)s->size, 6) != Z_OK)
                fuzz_fail("edit_build: compress failed");
            stored_size[i] = n;
        } else {
            stored[i] = s->data;
            stored_size[i] = s->size;
        }
        if (i + 1 < e->count)
            total = (total + stored_size[i] + 63) & ~(size_t)63;
        else
            total += stored_size[i];
    }
    uint8_t *out = calloc(1, total);
    if (!out)
        fuzz_fail("edit_build: out of memory");
    memcpy(out, e->header, 128);
    le_put_u32(out + 24, e->count);
    size_t off = (128 + 40 * (size_t)e->count + 63) & ~(size_t)63;
    for (uint32_t i = 0; i < e->count; i++) {
        uint8_t *t = out + 128 + 40 * i;
        le_put_u32(t, e->s[i].type);
        le_put_u32(t + 4, e->s[i].codec);
        le_put_u64(t + 8, off);
        le_put_u64(t + 16, stored_size[i]);
        le_put_u64(t + 24, e->s[i].size);
        le_put_u32(t + 36, e->s[i].encoding);
        memcpy(out + off, stored[i], stored_size[i]);
        off = (off + stored_size[i] + 63) & ~(size_t)63;
        if (e->s[i].codec == 1)
            free(stored[i]);
    }
    fuzz_repair_checksums(out, total);
    *size = total;
    return out;
}

int edit_find(const edit_file *e, uint32_t type)
{
    for (uint32_t i = 0; i < e->count; i++)
        if (e->s[i].type == type)
            return (int)i;
    return -1;
}

void edit_replace(edit_file *e, int i, uint8_t *data, size_t size, uint32_t encoding)
{
    free(e->s[i].data);
    e->s[i].data = data;
    e->s[i].size = size;
    e->s[i].encoding = encoding;
}

void edit_free(edit_file *e)
{
    for (uint32_t i = 0; i < e->count && i < 16; i++)
        free(e->s[i].data);
    memset(e, 0, sizeof *e);
}
