/* test_os.h: the few operating-system calls the tests make, for POSIX and for Windows (MinGW-w64, run under
 * wine). */
#ifndef CBVH_TEST_OS_H
#define CBVH_TEST_OS_H

#include <stddef.h>

/* `size` bytes aligned to `align` (a power of two), or NULL; freed by test_aligned_free. */
void *test_aligned_alloc(size_t size, size_t align);
void test_aligned_free(void *ptr);

/* Creates a fresh, empty folder "<tmp>/<tag>.<unique>" (tmp: TMPDIR, TEMP, TMP, else /tmp) and writes its
 * path to dir; aborts with a message when it cannot. */
void test_temp_dir(char *dir, size_t size, const char *tag);

/* mkdir with the default mode: 0 or -1. */
int test_mkdir(const char *path);

/* Whole pages of read-write memory (NULL on failure), and turning some of them into an inaccessible guard. */
size_t test_page_size(void);
void *test_pages_map(size_t size);
int test_pages_protect_none(void *pages, size_t size);
void test_pages_unmap(void *pages, size_t size);

#endif
