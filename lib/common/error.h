/* error.h: filling a caller's cbvh_error with a code and a formatted message. */
#ifndef CBVH_COMMON_ERROR_H
#define CBVH_COMMON_ERROR_H

#include "cbvh.h"
#include "common/compiler.h"

/* Sets err (if not NULL) and returns code, so callers write `return cbvh_fail(err, CODE, "...", ...)`. */
cbvh_result cbvh_fail(cbvh_error *err, cbvh_result code, const char *fmt, ...) CBVH_PRINTF(3, 4);

/* Clears err to CBVH_OK with an empty message. */
void cbvh_error_clear(cbvh_error *err);

#endif
