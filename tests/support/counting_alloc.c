/* counting_alloc.c: an allocator for tests that counts live blocks and bytes and fails a chosen call; the
 * open failure loop. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "support/counting_alloc.h"
#include "support/test_os.h"

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
    if (size > SIZE_MAX - PREFIX || !(p = test_aligned_alloc(size + PREFIX, PREFIX)))
        return NULL;
    memcpy(p, &size, sizeof size);
    c->live++;
    c->peak_live = c->live > c->peak_live ? c->live : c->peak_live;
    c->live_bytes += size;
    c->peak_bytes = c->live_bytes > c->peak_bytes ? c->live_bytes : c->peak_bytes;
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
    test_aligned_free(p);
}

cbvh_allocator counting_allocator(counting_alloc *c, long fail_at, int fail_all)
{
    memset(c, 0, sizeof *c);
    c->fail_at = fail_at;
    c->fail_all = fail_all;
    cbvh_allocator a = {counting_alloc_fn, counting_free_fn, c};
    return a;
}

size_t counting_open_failures(const void *data, size_t size, const char *path,
                              void (*opened)(const cbvh_file *file))
{
    for (size_t n = 0;; n++) {
        counting_alloc c;
        cbvh_allocator a = counting_allocator(&c, (long)n, 0);
        cbvh_file *f = NULL;
        cbvh_error err;
        cbvh_result r =
            path ? cbvh_open_path(path, &a, &f, &err) : cbvh_open_memory(data, size, &a, &f, &err);
        if (r == CBVH_OK) {
            if (opened)
                opened(f);
            cbvh_close(f);
            if (c.live != 0 || c.live_bytes != 0)
                fail_msg("closing left %ld blocks (%zu bytes) live", c.live, c.live_bytes);
            return n;
        }
        if (r != CBVH_ERROR_OUT_OF_MEMORY)
            fail_msg("open with allocation %zu failing: %s (%s)", n, cbvh_result_string(r), err.message);
        assert_true(err.message[0] != 0);
        assert_null(f);
        if (c.live != 0)
            fail_msg("open with allocation %zu failing leaked %ld blocks", n, c.live);
        assert_true(n < 10000);
    }
}
