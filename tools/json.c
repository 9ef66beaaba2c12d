/* json.c: a tiny streaming JSON writer with correct string escaping and finite-number handling. */
#include <assert.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "json.h"

void json_init(json_writer *w, FILE *out)
{
    w->out = out;
    w->depth = 0;
    w->count[0] = 0;
}

static void json_indent(json_writer *w)
{
    fputc('\n', w->out);
    for (int i = 0; i < w->depth; i++)
        fputs("  ", w->out);
}

/* Strings go through here: escapes per RFC 8259, invalid UTF-8 replaced. */
static void json_write_string(FILE *out, const char *s)
{
    static const char hex[] = "0123456789abcdef";
    const unsigned char *p = (const unsigned char *)s;
    fputc('"', out);
    while (*p) {
        unsigned char c = *p;
        if (c == '"' || c == '\\') {
            fputc('\\', out);
            fputc(c, out);
            p++;
        } else if (c < 0x20) {
            switch (c) {
            case '\n':
                fputs("\\n", out);
                break;
            case '\r':
                fputs("\\r", out);
                break;
            case '\t':
                fputs("\\t", out);
                break;
            case '\b':
                fputs("\\b", out);
                break;
            case '\f':
                fputs("\\f", out);
                break;
            default:
                fprintf(out, "\\u00%c%c", hex[c >> 4], hex[c & 15]);
                break;
            }
            p++;
        } else if (c < 0x80) {
            fputc(c, out);
            p++;
        } else {
            /* Multi-byte UTF-8: copy a well-formed sequence (no overlongs, no surrogates,
             * at most U+10FFFF); anything else becomes U+FFFD, one byte at a time. */
            int n = c >= 0xF0 ? 3 : c >= 0xE0 ? 2 : c >= 0xC2 ? 1 : 0;
            uint32_t cp = c & (0x3Fu >> n);
            int ok = n > 0 && c <= 0xF4;
            for (int i = 1; ok && i <= n; i++) {
                if ((p[i] & 0xC0) != 0x80)
                    ok = 0;
                else
                    cp = (cp << 6) | (p[i] & 0x3Fu);
            }
            if (ok && ((n == 2 && (cp < 0x800 || (cp >= 0xD800 && cp <= 0xDFFF))) ||
                       (n == 3 && (cp < 0x10000 || cp > 0x10FFFF))))
                ok = 0;
            if (ok) {
                fwrite(p, 1, (size_t)n + 1, out);
                p += n + 1;
            } else {
                fputs("\xEF\xBF\xBD", out);
                p++;
            }
        }
    }
    fputc('"', out);
}

/* Comma, newline and indentation before a value, then "key": when inside an object. */
static void json_prefix(json_writer *w, const char *key)
{
    if (w->depth > 0) {
        if (w->count[w->depth]++)
            fputc(',', w->out);
        json_indent(w);
    }
    if (key) {
        json_write_string(w->out, key);
        fputs(": ", w->out);
    }
}

static void json_open(json_writer *w, const char *key, char bracket)
{
    json_prefix(w, key);
    fputc(bracket, w->out);
    assert(w->depth + 1 < JSON_MAX_DEPTH);
    w->count[++w->depth] = 0;
}

static void json_close(json_writer *w, char bracket)
{
    assert(w->depth > 0);
    int had_members = w->count[w->depth] > 0;
    w->depth--;
    if (had_members)
        json_indent(w);
    fputc(bracket, w->out);
}

void json_begin_object(json_writer *w, const char *key)
{
    json_open(w, key, '{');
}
void json_end_object(json_writer *w)
{
    json_close(w, '}');
}
void json_begin_array(json_writer *w, const char *key)
{
    json_open(w, key, '[');
}
void json_end_array(json_writer *w)
{
    json_close(w, ']');
}

void json_string(json_writer *w, const char *key, const char *s)
{
    json_prefix(w, key);
    if (s)
        json_write_string(w->out, s);
    else
        fputs("null", w->out);
}

void json_uint(json_writer *w, const char *key, uint64_t v)
{
    json_prefix(w, key);
    fprintf(w->out, "%" PRIu64, v);
}

void json_int(json_writer *w, const char *key, int64_t v)
{
    json_prefix(w, key);
    fprintf(w->out, "%" PRId64, v);
}

/* The shortest %.Ng that reads back exactly (as a float when `single`); %g never prints
 * "inf"/"nan" for finite values, and its output ("1e-05", "0.5", "3") is valid JSON. */
static void json_number(json_writer *w, const char *key, double v, int single)
{
    json_prefix(w, key);
    if (!isfinite(v)) {
        fputs("null", w->out);
        return;
    }
    char buf[64];
    for (int prec = 1; prec <= 17; prec++) {
        snprintf(buf, sizeof buf, "%.*g", prec, v);
        if (single ? strtof(buf, NULL) == (float)v : strtod(buf, NULL) == v)
            break;
    }
    /* %g writes 50 as "5e+01": numbers a reader expects in plain notation get the fewest decimals that
     * read back exactly */
    if (strchr(buf, 'e') && fabs(v) >= 1e-4 && fabs(v) < 1e15) {
        for (int decimals = 0; decimals <= 20; decimals++) {
            snprintf(buf, sizeof buf, "%.*f", decimals, v);
            if (single ? strtof(buf, NULL) == (float)v : strtod(buf, NULL) == v)
                break;
        }
    }
    fputs(buf, w->out);
}

void json_double(json_writer *w, const char *key, double v)
{
    json_number(w, key, v, 0);
}
void json_float(json_writer *w, const char *key, float v)
{
    json_number(w, key, v, 1);
}

void json_bool(json_writer *w, const char *key, int v)
{
    json_prefix(w, key);
    fputs(v ? "true" : "false", w->out);
}

void json_null(json_writer *w, const char *key)
{
    json_prefix(w, key);
    fputs("null", w->out);
}

void json_finish(json_writer *w)
{
    assert(w->depth == 0);
    fputc('\n', w->out);
}
