/* test_os.c: the few operating-system calls the tests make, for POSIX and for Windows (MinGW-w64, run under
 * wine). */
#ifndef _WIN32
#define _DEFAULT_SOURCE 1 /* MAP_ANONYMOUS is not POSIX.1-2008 */
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "support/test_os.h"

#ifdef _WIN32
#define WIN32_LEAN_AND_MEAN
#include <direct.h>
#include <malloc.h>
#include <windows.h>
#else
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#endif

void *test_aligned_alloc(size_t size, size_t align)
{
    if (align < sizeof(void *))
        align = sizeof(void *);
#ifdef _WIN32
    return _aligned_malloc(size, align);
#else
    void *p = NULL;
    return posix_memalign(&p, align, size) == 0 ? p : NULL;
#endif
}

void test_aligned_free(void *ptr)
{
#ifdef _WIN32
    _aligned_free(ptr);
#else
    free(ptr);
#endif
}

int test_mkdir(const char *path)
{
#ifdef _WIN32
    return _mkdir(path) == 0 ? 0 : -1;
#else
    return mkdir(path, 0700) == 0 ? 0 : -1;
#endif
}

void test_temp_dir(char *dir, size_t size, const char *tag)
{
    const char *tmp = getenv("TMPDIR");
    if (!tmp || !*tmp)
        tmp = getenv("TEMP");
    if (!tmp || !*tmp)
        tmp = getenv("TMP");
    if (!tmp || !*tmp)
        tmp = "/tmp";
#ifdef _WIN32
    /* No mkdtemp: try names until one is new. */
    unsigned seed = (unsigned)GetCurrentProcessId() * 2654435761u ^ (unsigned)GetTickCount();
    for (unsigned attempt = 0; attempt < 1000; attempt++) {
        snprintf(dir, size, "%s/%s.%08x", tmp, tag, seed + attempt * 7919u);
        if (_mkdir(dir) == 0)
            return;
    }
#else
    snprintf(dir, size, "%s/%s.XXXXXX", tmp, tag);
    if (mkdtemp(dir))
        return;
#endif
    fprintf(stderr, "cannot create a temporary folder %s\n", dir);
    abort();
}

size_t test_page_size(void)
{
#ifdef _WIN32
    SYSTEM_INFO info;
    GetSystemInfo(&info);
    return info.dwPageSize;
#else
    return (size_t)sysconf(_SC_PAGESIZE);
#endif
}

void *test_pages_map(size_t size)
{
#ifdef _WIN32
    return VirtualAlloc(NULL, size, MEM_RESERVE | MEM_COMMIT, PAGE_READWRITE);
#else
    void *p = mmap(NULL, size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    return p == MAP_FAILED ? NULL : p;
#endif
}

int test_pages_protect_none(void *pages, size_t size)
{
#ifdef _WIN32
    DWORD old;
    return VirtualProtect(pages, size, PAGE_NOACCESS, &old) ? 0 : -1;
#else
    return mprotect(pages, size, PROT_NONE) == 0 ? 0 : -1;
#endif
}

void test_pages_unmap(void *pages, size_t size)
{
#ifdef _WIN32
    (void)size;
    VirtualFree(pages, 0, MEM_RELEASE);
#else
    munmap(pages, size);
#endif
}
