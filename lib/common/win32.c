/* win32.c: the operating-system calls of os.h on Windows (file mapping, threads, MoveFileEx), above the
 * allocator. */
#define WIN32_LEAN_AND_MEAN
#include <windows.h>
#include <process.h>
#include <stdio.h>
#include <string.h>

#include "common/alloc.h"
#include "common/error.h"
#include "common/os.h"

/* The system's text for an error code, without its trailing period and line break. */
static const char *system_message(DWORD code, char *buf, size_t size)
{
    DWORD n = FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, NULL, code, 0, buf,
                             (DWORD)size, NULL);
    while (n > 0 && (buf[n - 1] == '\r' || buf[n - 1] == '\n' || buf[n - 1] == '.' || buf[n - 1] == ' '))
        n--;
    if (n == 0)
        snprintf(buf, size, "Windows error %lu", (unsigned long)code);
    else
        buf[n] = '\0';
    return buf;
}

/* The UTF-16 form of a UTF-8 path, from `a`. */
static cbvh_result wide_path(const char *path, const cbvh_allocator *a, wchar_t **out, cbvh_error *err)
{
    int n = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, path, -1, NULL, 0);
    if (n <= 0)
        return cbvh_fail(err, CBVH_ERROR_INVALID_ARGUMENT, "%s: the path is not valid UTF-8", path);
    *out = cbvh_alloc_array(a, (size_t)n, sizeof(wchar_t), sizeof(wchar_t));
    if (!*out)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "%s: cannot allocate the path's UTF-16 form", path);
    MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, path, -1, *out, n);
    return CBVH_OK;
}

static cbvh_result fail_system(cbvh_error *err, const char *path, const char *what)
{
    char text[160];
    return cbvh_fail(err, CBVH_ERROR_IO, "%s: %s: %s", path, what,
                     system_message(GetLastError(), text, sizeof text));
}

/* The whole file into a 64-byte aligned buffer from `a`. */
static cbvh_result read_all(HANDLE h, const char *path, const cbvh_allocator *a,
                            struct cbvh_os_file_bytes *out, cbvh_error *err)
{
    uint8_t *buffer = cbvh_alloc(a, out->size, 64);
    if (!buffer)
        return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "%s: cannot allocate %zu bytes to read it into", path,
                         out->size);
    size_t done = 0;
    while (done < out->size) {
        size_t left = out->size - done;
        DWORD want = left > 0x40000000u ? 0x40000000u : (DWORD)left, got = 0;
        if (!ReadFile(h, buffer + done, want, &got, NULL) || got == 0) {
            char text[160];
            cbvh_result r = cbvh_fail(err, CBVH_ERROR_IO, "%s: read failed at byte %zu: %s", path, done,
                                      got == 0 ? "unexpected end of file"
                                               : system_message(GetLastError(), text, sizeof text));
            cbvh_free(a, buffer);
            return r;
        }
        done += got;
    }
    out->bytes = buffer;
    return CBVH_OK;
}

static cbvh_result map_or_read(HANDLE h, const char *path, int map, const cbvh_allocator *a,
                               struct cbvh_os_file_bytes *out, cbvh_error *err)
{
    LARGE_INTEGER size;
    if (GetFileType(h) != FILE_TYPE_DISK)
        return cbvh_fail(err, CBVH_ERROR_IO, "%s: not a regular file", path);
    if (!GetFileSizeEx(h, &size))
        return fail_system(err, path, "cannot get the size");
    if ((unsigned long long)size.QuadPart > SIZE_MAX)
        return cbvh_fail(err, CBVH_ERROR_IO, "%s: %lld bytes do not fit in the address space", path,
                         (long long)size.QuadPart);
    out->size = (size_t)size.QuadPart;
    if (out->size == 0)
        return CBVH_OK; /* nothing to map (Windows cannot map an empty file); the header check reports it */
    if (map) {
        /* The view keeps the mapping object alive after its handle is closed. */
        HANDLE m = CreateFileMappingW(h, NULL, PAGE_READONLY, 0, 0, NULL);
        if (m) {
            const void *p = MapViewOfFile(m, FILE_MAP_READ, 0, 0, 0);
            CloseHandle(m);
            if (p) {
                out->bytes = p;
                out->mapped = 1;
                return CBVH_OK;
            }
        }
    }
    return read_all(h, path, a, out, err);
}

cbvh_result cbvh_os_read_file(const char *path, int map, const cbvh_allocator *a,
                              struct cbvh_os_file_bytes *out, cbvh_error *err)
{
    memset(out, 0, sizeof *out);
    wchar_t *wide;
    cbvh_result r = wide_path(path, a, &wide, err);
    if (r != CBVH_OK)
        return r;
    DWORD attributes = GetFileAttributesW(wide);
    if (attributes != INVALID_FILE_ATTRIBUTES && (attributes & FILE_ATTRIBUTE_DIRECTORY)) {
        cbvh_free(a, wide);
        return cbvh_fail(err, CBVH_ERROR_IO, "%s: not a regular file", path);
    }
    /* Others may read, rename or delete the file meanwhile, not write it while this handle is open. */
    HANDLE h = CreateFileW(wide, GENERIC_READ, FILE_SHARE_READ | FILE_SHARE_DELETE, NULL, OPEN_EXISTING,
                           FILE_ATTRIBUTE_NORMAL | FILE_FLAG_SEQUENTIAL_SCAN, NULL);
    cbvh_free(a, wide);
    if (h == INVALID_HANDLE_VALUE)
        return fail_system(err, path, "cannot open");
    r = map_or_read(h, path, map, a, out, err);
    CloseHandle(h);
    return r;
}

void cbvh_os_unmap(const uint8_t *bytes, size_t size)
{
    (void)size;
    UnmapViewOfFile(bytes);
}

/* "dir\name" -> "dir\.name.tmp-XXXXXXXX" with X hexadecimal: the same folder, so the rename stays on one
 * volume. */
static char *temp_name(const cbvh_allocator *a, const char *path, unsigned attempt)
{
    const char *name = path;
    for (const char *c = path; *c; c++)
        if (*c == '/' || *c == '\\' || *c == ':')
            name = c + 1;
    size_t len = strlen(path), dir_len = (size_t)(name - path);
    char *t = cbvh_alloc(a, len + 16, 1);
    if (!t)
        return NULL;
    unsigned tag =
        (unsigned)GetCurrentProcessId() * 2654435761u ^ (unsigned)GetTickCount() ^ attempt * 40503u;
    snprintf(t, len + 16, "%.*s.%s.tmp-%08x", (int)dir_len, path, name, tag);
    return t;
}

static int write_all(HANDLE h, const uint8_t *p, size_t size)
{
    while (size > 0) {
        DWORD want = size > 0x40000000u ? 0x40000000u : (DWORD)size, done = 0;
        if (!WriteFile(h, p, want, &done, NULL) || done == 0)
            return -1;
        p += done;
        size -= done;
    }
    return 0;
}

/* Creates a new temporary file beside `path`: its handle, with *temp and *wide_temp set; or an error. */
static cbvh_result create_temp(const char *path, const cbvh_allocator *a, char **temp, wchar_t **wide_temp,
                               HANDLE *h, cbvh_error *err)
{
    for (unsigned attempt = 0; attempt < 100; attempt++) {
        *temp = temp_name(a, path, attempt);
        if (!*temp)
            return cbvh_fail(err, CBVH_ERROR_OUT_OF_MEMORY, "out of memory for a temporary file name");
        cbvh_result r = wide_path(*temp, a, wide_temp, err);
        if (r != CBVH_OK) {
            cbvh_free(a, *temp);
            return r;
        }
        *h = CreateFileW(*wide_temp, GENERIC_WRITE, 0, NULL, CREATE_NEW, FILE_ATTRIBUTE_NORMAL, NULL);
        if (*h != INVALID_HANDLE_VALUE)
            return CBVH_OK;
        DWORD code = GetLastError();
        cbvh_free(a, *wide_temp);
        cbvh_free(a, *temp);
        if (code != ERROR_FILE_EXISTS && code != ERROR_ALREADY_EXISTS) {
            char text[160];
            return cbvh_fail(err, CBVH_ERROR_IO, "cannot create a temporary file beside '%s': %s", path,
                             system_message(code, text, sizeof text));
        }
    }
    return cbvh_fail(err, CBVH_ERROR_IO, "cannot create a temporary file beside '%s': 100 names were taken",
                     path);
}

cbvh_result cbvh_os_write_file_replacing(const char *path, const uint8_t *data, size_t size,
                                         const cbvh_allocator *a, cbvh_error *err)
{
    wchar_t *wide;
    cbvh_result r = wide_path(path, a, &wide, err);
    if (r != CBVH_OK)
        return r;
    char *temp;
    wchar_t *wide_temp;
    HANDLE h;
    r = create_temp(path, a, &temp, &wide_temp, &h, err);
    if (r != CBVH_OK) {
        cbvh_free(a, wide);
        return r;
    }
    const char *failed = NULL;
    DWORD code = 0;
    if (write_all(h, data, size) != 0)
        failed = "write";
    else if (!FlushFileBuffers(h))
        failed = "flush";
    if (failed)
        code = GetLastError();
    if (!CloseHandle(h) && !failed) {
        failed = "close";
        code = GetLastError();
    }
    /* MOVEFILE_WRITE_THROUGH returns once the rename is on disk. */
    if (!failed && !MoveFileExW(wide_temp, wide, MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH)) {
        failed = "rename into place";
        code = GetLastError();
    }
    if (failed) {
        char text[160];
        DeleteFileW(wide_temp);
        r = cbvh_fail(err, CBVH_ERROR_IO, "cannot %s the temporary file '%s' for '%s': %s", failed, temp,
                      path, system_message(code, text, sizeof text));
    }
    cbvh_free(a, wide_temp);
    cbvh_free(a, temp);
    cbvh_free(a, wide);
    return r;
}

static unsigned __stdcall thread_main(void *arg)
{
    struct cbvh_os_thread *t = arg;
    t->fn(t->arg);
    return 0;
}

int cbvh_os_thread_start(struct cbvh_os_thread *t, void (*fn)(void *arg), void *arg)
{
    t->fn = fn;
    t->arg = arg;
    /* _beginthreadex, not CreateThread: the C library's per-thread state is set up. */
    uintptr_t h = _beginthreadex(NULL, 0, thread_main, t, 0, NULL);
    if (h == 0)
        return -1;
    t->id = (HANDLE)h;
    return 0;
}

void cbvh_os_thread_join(struct cbvh_os_thread *t)
{
    WaitForSingleObject(t->id, INFINITE);
    CloseHandle(t->id);
}

double cbvh_os_seconds(void)
{
    LARGE_INTEGER now, frequency;
    QueryPerformanceCounter(&now);
    QueryPerformanceFrequency(&frequency);
    return (double)now.QuadPart / (double)frequency.QuadPart;
}
