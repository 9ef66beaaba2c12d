/* file_edit.h: takes a valid cbvh file apart into sections and lays it out again (re-encoded, reordered,
 * recompressed), for seed corpora and corruption tests. */
#ifndef CBVH_FILE_EDIT_H
#define CBVH_FILE_EDIT_H

#include <stddef.h>
#include <stdint.h>

typedef struct edit_section {
    uint32_t type, codec, encoding;
    uint8_t *data; /* decoded payload (malloc'd) */
    size_t size;
} edit_section;

typedef struct edit_file {
    uint8_t header[128];
    uint32_t count;
    edit_section s[16];
} edit_file;

/* Splits a file the cooker wrote (zlib sections are inflated). Returns 0 on
 * anything it does not understand. */
int edit_parse(edit_file *e, const uint8_t *bytes, size_t size);

/* Writes the sections in table order, each at the next 64-byte boundary,
 * compressing those with codec 1, and sets section_count, file_size and
 * every CRC. Returns a malloc'd file and its size in *size. */
uint8_t *edit_build(const edit_file *e, size_t *size);

/* Index of the section of `type`, or -1. */
int edit_find(const edit_file *e, uint32_t type);

/* Replaces section i's payload (takes ownership of `data`). */
void edit_replace(edit_file *e, int i, uint8_t *data, size_t size, uint32_t encoding);

void edit_free(edit_file *e);

#endif
