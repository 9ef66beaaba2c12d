/* counting_alloc.c: an allocator for tests that counts live blocks and bytes and fails a chosen call. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "support/counting_alloc.h"

/* Each block starts PREFIX bytes into a 64-aligned allocation, after its size,
 * which keeps any alignment the library may ask for (at most 64). */
#define PREFIX 64

static void *counting_alloc_fn(void *user, size_t size, size_t align)
{
    counting_alloc *c = user;
    if (align < 1 || align > PREFIX || (align & (align - 1)) != 0)
        abort();
    const long n = c->calls++;
    if (n == c->fail_at || (c->fail_all && c->fail_at >= 0 && n > c->fail_at))
        return NULL;
    void *p = NULL;
    if (size > SIZE_MAX - PREFIX || posix_memalign(&p, PREFIX, size + PREFIX) != 0)
        return NULL;
    memcpy(p, &size, sizeof size);
    c->live++;
    c->peak_live = c->live > c->peak_live ? c->live : c->peak_live;
    c->live_bytes += size;
    return (uint8_t *)p + PREFIX;
}

static void counting_free_fn(void *user, void *ptr)
{
    counting_alloc *c = user;
    if (!ptr)
        return;
    if (c->live <= 0)
        abort();
    uint8_t *p = (uint8_t *)ptr - PREFIX;
    size_t size;
    memcpy(&size, p, sizeof size);
    c->live--;
    c->live_bytes -= size;
    free(p);
}

cbvh_allocator counting_allocator(counting_alloc *c, long fail_at, int fail_all)
{
    memset(c, 0, sizeof *c);
    c->fail_at = fail_at;
    c->fail_all = fail_all;
    cbvh_allocator a = {counting_alloc_fn, counting_free_fn, c};
    return a;
}
