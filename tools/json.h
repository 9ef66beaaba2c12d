/* json.h: a tiny streaming JSON writer (indented, correct string escaping, non-finite numbers as null). */
#ifndef CBVH_TOOLS_JSON_H
#define CBVH_TOOLS_JSON_H

#include <stdint.h>
#include <stdio.h>

#define JSON_MAX_DEPTH 32

/* Members are written in call order. `key` names an object member and must be NULL for array
 * elements and the top-level value. Nesting deeper than JSON_MAX_DEPTH is a programmer error. */
typedef struct json_writer {
    FILE *out;
    int depth;
    int count[JSON_MAX_DEPTH]; /* values written so far at each level, for commas */
} json_writer;

void json_init(json_writer *w, FILE *out);

void json_begin_object(json_writer *w, const char *key);
void json_end_object(json_writer *w);
void json_begin_array(json_writer *w, const char *key);
void json_end_array(json_writer *w);

/* `s` is any byte string: control characters, quotes and backslashes are escaped, bytes that are
 * not valid UTF-8 are written as U+FFFD so the output is always valid JSON. NULL writes null. */
void json_string(json_writer *w, const char *key, const char *s);
void json_uint(json_writer *w, const char *key, uint64_t v);
void json_int(json_writer *w, const char *key, int64_t v);
/* Shortest decimal that reads back to the same double; NaN and infinities become null. */
void json_double(json_writer *w, const char *key, double v);
/* The same for a binary32 value: the shortest decimal that reads back to the same float. */
void json_float(json_writer *w, const char *key, float v);
void json_bool(json_writer *w, const char *key, int v);
void json_null(json_writer *w, const char *key);

/* Ends the document with a newline. */
void json_finish(json_writer *w);

#endif
