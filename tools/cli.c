/* cli.c: option parsing, error messages and exit codes shared by the cbvh subcommands. */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"

void cli_init(cli_parser *p, const char *command, const char *usage, int argc, char **argv)
{
    p->command = command;
    p->usage = usage;
    p->argc = argc;
    p->argv = argv;
    p->index = 1;
    p->only_positional = 0;
}

int cli_next(cli_parser *p, const cli_option *options, const char **value)
{
    *value = NULL;
    if (p->index >= p->argc)
        return CLI_END;
    const char *arg = p->argv[p->index++];
    if (p->only_positional || arg[0] != '-' || arg[1] == '\0') {
        *value = arg;
        return CLI_POSITIONAL;
    }
    if (!strcmp(arg, "--")) {
        p->only_positional = 1;
        return cli_next(p, options, value);
    }
    if (!strcmp(arg, "-h") || !strcmp(arg, "--help")) {
        fputs(p->usage, stdout);
        return CLI_DONE;
    }
    if (!strcmp(arg, "--version")) {
        cli_print_version();
        return CLI_DONE;
    }
    if (arg[1] != '-') {
        cli_usage_error(p->command, "unknown option '%s'", arg);
        return CLI_ERROR;
    }
    const char *name = arg + 2;
    const char *eq = strchr(name, '=');
    size_t len = eq ? (size_t)(eq - name) : strlen(name);
    for (const cli_option *o = options; o && o->name; o++) {
        if (strlen(o->name) != len || strncmp(o->name, name, len))
            continue;
        if (o->arg == CLI_ARG_NONE && eq) {
            cli_usage_error(p->command, "option '--%s' takes no value", o->name);
            return CLI_ERROR;
        }
        if (eq) {
            *value = eq + 1;
        } else if (o->arg == CLI_ARG_REQUIRED) {
            if (p->index >= p->argc) {
                cli_usage_error(p->command, "option '--%s' needs a value", o->name);
                return CLI_ERROR;
            }
            *value = p->argv[p->index++];
        }
        return o->id;
    }
    cli_usage_error(p->command, "unknown option '%s'", arg);
    return CLI_ERROR;
}

void cli_print_version(void)
{
    printf("cbvh %s (library %s, file format %d)\n", CBVH_VERSION_STRING, CBVH_VERSION_STRING,
           CBVH_FORMAT_VERSION);
}

static char last_message[1024], last_file[1024];
static int json_error_printed;

static void cli_vmessage(const char *command, const char *file, const char *fmt, va_list ap)
{
    va_list copy;
    va_copy(copy, ap);
    vsnprintf(last_message, sizeof last_message, fmt, copy);
    va_end(copy);
    snprintf(last_file, sizeof last_file, "%s", file ? file : "");
    fprintf(stderr, "cbvh %s: ", command);
    if (file)
        fprintf(stderr, "%s: ", file);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
}

const char *cli_last_message(void)
{
    return last_message;
}

const char *cli_last_file(void)
{
    return last_file;
}

void cli_json_error_printed(void)
{
    json_error_printed = 1;
}

int cli_json_error_was_printed(void)
{
    return json_error_printed;
}

void cli_error(const char *command, const char *file, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cli_vmessage(command, file, fmt, ap);
    va_end(ap);
}

int cli_usage_error(const char *command, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cli_vmessage(command, NULL, fmt, ap);
    va_end(ap);
    fprintf(stderr, "Try 'cbvh %s --help' for more information.\n", command);
    return CLI_EXIT_USAGE;
}

int cli_parse_u32(const char *command, const char *option, const char *text, uint32_t min, uint32_t max,
                  uint32_t *out)
{
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 10);
    /* strtoull accepts a sign; a leading '-' would wrap around, so refuse it. */
    if (!text[0] || text[0] == '-' || text[0] == '+' || *end || errno || v < min || v > max) {
        cli_usage_error(command, "--%s: '%s' is not an integer from %u to %u", option, text, (unsigned)min,
                        (unsigned)max);
        return 0;
    }
    *out = (uint32_t)v;
    return 1;
}

int cli_parse_float(const char *command, const char *option, const char *text, float min, float max,
                    float *out)
{
    char *end = NULL;
    errno = 0;
    float v = strtof(text, &end);
    if (!text[0] || *end || errno || !isfinite(v) || v < min || v > max) {
        cli_usage_error(command, "--%s: '%s' is not a number from %g to %g", option, text, (double)min,
                        (double)max);
        return 0;
    }
    *out = v;
    return 1;
}

int cli_exit_for(cbvh_result result)
{
    switch (result) {
    case CBVH_OK:
        return CLI_EXIT_OK;
    case CBVH_ERROR_CORRUPT:
    case CBVH_ERROR_UNSUPPORTED:
    case CBVH_ERROR_BAD_MESH:
    case CBVH_ERROR_EMPTY_MESH:
    case CBVH_ERROR_LIMIT:
        return CLI_EXIT_BAD_INPUT;
    default:
        return CLI_EXIT_USAGE;
    }
}

int cli_report(const char *command, const char *file, const cbvh_error *err)
{
    const char *what = cbvh_result_string(err->code);
    const char *message = err->message;
    /* The loader may already name the file; say it once. */
    size_t len = file ? strlen(file) : 0;
    if (len && !strncmp(message, file, len) && message[len] == ':')
        message += len + (message[len + 1] == ' ' ? 2 : 1);
    if (message[0])
        cli_error(command, file, "%s: %s", what, message);
    else
        cli_error(command, file, "%s", what);
    return cli_exit_for(err->code);
}

int cli_open(const char *command, const char *path, cbvh_file **out)
{
    cbvh_error err;
    *out = NULL;
    if (cbvh_open_path(path, NULL, out, &err) != CBVH_OK)
        return cli_report(command, path, &err);
    return CLI_EXIT_OK;
}

const char *cli_section_name(uint32_t type)
{
    static const char *const names[] = {"unknown", "nodes", "triangles", "vertices", "remap", "materials"};
    if (type < sizeof names / sizeof names[0])
        return names[type];
    if ((type | 0x80000000u) == CBVH_SECTION_MATERIAL_NAMES) /* its type, or its number in cook stats */
        return "material-names";
    return (type & 0x80000000u) ? "ancillary" : "unknown";
}

double cli_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
