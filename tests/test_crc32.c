/* test_crc32.c: the CRC32 (carry-less multiply kernel plus zlib tail) against zlib's crc32 itself. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <cmocka.h>
#include <zlib.h>

#include "common/crc32.h"

static uint64_t rng_state = 0x1234567887654321ull;
static uint8_t next_byte(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (uint8_t)rng_state;
}

/* Every length up to 1 KiB at every alignment within 16 bytes, chained from several start values. */
static void test_every_length_and_alignment(void **state)
{
    (void)state;
    enum { MAX = 1024 + 16 };
    uint8_t *buf = malloc(MAX);
    assert_non_null(buf);
    for (size_t i = 0; i < MAX; i++)
        buf[i] = next_byte();
    static const uint32_t starts[] = {0u, 0xFFFFFFFFu, 0x12345678u};
    for (size_t s = 0; s < sizeof starts / sizeof starts[0]; s++)
        for (size_t align = 0; align < 16; align++)
            for (size_t len = 0; len <= 1024; len++) {
                uint32_t expect = (uint32_t)crc32(starts[s], buf + align, (uInt)len);
                uint32_t got = cbvh_crc32(starts[s], buf + align, len);
                if (got != expect)
                    fail_msg("length %zu, alignment %zu, start %08x: got %08x, zlib %08x", len, align,
                             starts[s], got, expect);
            }
    free(buf);
}

/* A large buffer in one call and in uneven pieces gives zlib's value. */
static void test_large_and_chained(void **state)
{
    (void)state;
    size_t size = (size_t)9 << 20;
    uint8_t *buf = malloc(size);
    assert_non_null(buf);
    for (size_t i = 0; i < size; i++)
        buf[i] = next_byte();
    uint32_t expect = (uint32_t)crc32(0, buf, (uInt)size);
    assert_int_equal(cbvh_crc32(0, buf, size), expect);
    uint32_t c = 0;
    size_t at = 0, piece = 1;
    while (at < size) {
        size_t n = piece < size - at ? piece : size - at;
        c = cbvh_crc32(c, buf + at, n);
        at += n;
        piece = piece * 3 + 7;
    }
    assert_int_equal(c, expect);
    free(buf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_length_and_alignment),
        cmocka_unit_test(test_large_and_chained),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
