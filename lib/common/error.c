/* error.c: result strings and error messages. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "common/error.h"

const char *cbvh_result_string(cbvh_result result)
{
    switch (result) {
    case CBVH_OK:
        return "success";
    case CBVH_ERROR_INVALID_ARGUMENT:
        return "invalid argument";
    case CBVH_ERROR_OUT_OF_MEMORY:
        return "out of memory";
    case CBVH_ERROR_IO:
        return "input/output error";
    case CBVH_ERROR_CORRUPT:
        return "corrupt file";
    case CBVH_ERROR_UNSUPPORTED:
        return "unsupported file (valid but newer)";
    case CBVH_ERROR_BAD_MESH:
        return "bad mesh";
    case CBVH_ERROR_EMPTY_MESH:
        return "empty mesh";
    case CBVH_ERROR_LIMIT:
        return "format limit exceeded";
    }
    return "unknown result code";
}

cbvh_result cbvh_fail(cbvh_error *err, cbvh_result code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        err->code = code;
        int n = vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
        /* a message cut to fit (a long path at its end) says so */
        if (n >= (int)sizeof err->message)
            memcpy(err->message + sizeof err->message - 4, "...", 4);
    }
    return code;
}

void cbvh_error_clear(cbvh_error *err)
{
    if (err) {
        err->code = CBVH_OK;
        err->message[0] = '\0';
    }
}
