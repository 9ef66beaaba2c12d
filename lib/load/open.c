/* open.c: opening a file from a path (mapped, or read into memory) or from memory, and closing it. */
#include <string.h>

#include "common/alloc.h"
#include "common/error.h"
#include "common/os.h"
#include "load/load.h"

/* Frees what the file owns, unmaps its bytes and frees the handle itself. */
static void release(struct cbvh_file *f)
{
    cbvh_allocator a = f->allocator;
    for (uint32_t i = 0; i < f->owned_count; i++)
        cbvh_free(&a, f->owned[i]);
    if (f->mapped)
        cbvh_os_unmap(f->bytes, f->size);
    cbvh_free(&a, f);
}

/* Checks the arguments every open takes (clearing *out_file first) and allocates the zeroed handle. */
static cbvh_result new_file(const void *source, const char *what, const cbvh_allocator *allocator,
                            cbvh_file **out_file, struct cbvh_file **f, cbvh_error *err)
{
    if (!out_file)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT, "out_file is NULL");
    *out_file = NULL;
    if (!source)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT, "%s is NULL", what);
    cbvh_allocator a = cbvh_allocator_resolve(allocator);
    *f = cbvh_alloc(&a, sizeof **f, 64);
    if (!*f)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "cannot allocate the file handle");
    memset(*f, 0, sizeof **f);
    (*f)->allocator = a;
    return CBVH_OK;
}

/* Validates f and hands it to the caller, or releases it. */
static cbvh_result finish(struct cbvh_file *f, cbvh_file **out_file, cbvh_error *err)
{
    cbvh_result r = cbvh_load(f, err);
    if (r != CBVH_OK) {
        release(f);
        return r;
    }
    cbvh_error_clear(err);
    *out_file = f;
    return CBVH_OK;
}

cbvh_result cbvh_open_memory(const void *data, size_t size, const cbvh_allocator *allocator,
                             cbvh_file **out_file, cbvh_error *err)
{
    struct cbvh_file *f;
    static const uint8_t nothing;
    cbvh_result r = new_file(data || size > 0 ? data : &nothing, "data", allocator, out_file, &f, err);
    if (r != CBVH_OK)
        return r;
    f->bytes = data;
    f->size = size;
    return finish(f, out_file, err);
}

/* Opens path mapped (map = 1, falling back to reading when it cannot be mapped) or read into memory. */
static cbvh_result open_path(const char *path, int map, const cbvh_allocator *allocator, cbvh_file **out_file,
                             cbvh_error *err)
{
    struct cbvh_file *f;
    cbvh_result r = new_file(path, "path", allocator, out_file, &f, err);
    if (r != CBVH_OK)
        return r;
    struct cbvh_os_file_bytes file;
    r = cbvh_os_read_file(path, map, &f->allocator, &file, err);
    if (r != CBVH_OK) {
        release(f);
        return r;
    }
    f->bytes = file.bytes;
    f->size = file.size;
    f->mapped = file.mapped;
    if (file.bytes && !file.mapped)
        cbvh_file_own(f, (void *)file.bytes);
    return finish(f, out_file, err);
}

cbvh_result cbvh_open_path(const char *path, const cbvh_allocator *allocator, cbvh_file **out_file,
                           cbvh_error *err)
{
    return open_path(path, 1, allocator, out_file, err);
}

cbvh_result cbvh_open_path_read(const char *path, const cbvh_allocator *allocator, cbvh_file **out_file,
                                cbvh_error *err)
{
    return open_path(path, 0, allocator, out_file, err);
}

void cbvh_close(cbvh_file *file)
{
    if (file)
        release(file);
}
