/* alloc.c: allocation through the caller's hooks, with the C library as default. */
#include <stdint.h>
#include <string.h>

#include "common/alloc.h"
#include "common/os_memory.h"

static void *default_alloc(void *user, size_t size, size_t align)
{
    (void)user;
    return cbvh_os_aligned_alloc(size, align);
}

static void default_free(void *user, void *ptr)
{
    (void)user;
    cbvh_os_aligned_free(ptr);
}

cbvh_allocator cbvh_allocator_resolve(const cbvh_allocator *allocator)
{
    if (allocator && allocator->alloc && allocator->free)
        return *allocator;
    cbvh_allocator d = {default_alloc, default_free, NULL};
    return d;
}

void *cbvh_alloc(const cbvh_allocator *a, size_t size, size_t align)
{
    if (size == 0)
        return NULL;
    return a->alloc(a->user, size, align);
}

void *cbvh_alloc_walked(const cbvh_allocator *a, size_t size, size_t align)
{
    void *p = cbvh_alloc(a, size, align);
    if (p && a->alloc == default_alloc)
        cbvh_os_advise_large_pages(p, size);
    return p;
}

void cbvh_free(const cbvh_allocator *a, void *ptr)
{
    if (ptr)
        a->free(a->user, ptr);
}

void *cbvh_alloc_array(const cbvh_allocator *a, size_t count, size_t elem, size_t align)
{
    if (elem != 0 && count > SIZE_MAX / elem)
        return NULL;
    return cbvh_alloc(a, count * elem, align);
}

/* A metered block: the header holds the size asked for; the caller's bytes follow it. */
#define METER_HEADER 64u

void cbvh_meter_count(cbvh_meter *m, size_t size, int add)
{
    if (!add) {
        m->held -= size;
        return;
    }
    m->held += size;
    if (m->held > m->peak)
        m->peak = m->held;
}

static void *meter_alloc(void *user, size_t size, size_t align)
{
    cbvh_meter *m = user;
    (void)align; /* at most 64, which the header keeps */
    if (size > SIZE_MAX - METER_HEADER)
        return NULL;
    uint8_t *block = cbvh_alloc(&m->inner, size + METER_HEADER, METER_HEADER);
    if (!block)
        return NULL;
    memcpy(block, &size, sizeof size);
    cbvh_meter_count(m, size + METER_HEADER, 1);
    return block + METER_HEADER;
}

static void meter_free(void *user, void *ptr)
{
    cbvh_meter *m = user;
    uint8_t *block = (uint8_t *)ptr - METER_HEADER;
    size_t size;
    memcpy(&size, block, sizeof size);
    cbvh_meter_count(m, size + METER_HEADER, 0);
    cbvh_free(&m->inner, block);
}

cbvh_allocator cbvh_meter_allocator(cbvh_meter *m)
{
    cbvh_allocator a = {meter_alloc, meter_free, m};
    return a;
}
