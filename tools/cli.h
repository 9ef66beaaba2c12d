/* cli.h: what every cbvh subcommand shares: option parsing, error messages, exit codes, timing. */
#ifndef CBVH_TOOLS_CLI_H
#define CBVH_TOOLS_CLI_H

#include <stdint.h>

#include "cbvh.h"

/* Exit statuses of every subcommand. */
enum {
    CLI_EXIT_OK = 0,
    CLI_EXIT_BAD_INPUT = 1, /* invalid or corrupt input: bad mesh, corrupt cbvh file, bad ray line */
    CLI_EXIT_USAGE = 2      /* usage error, or an I/O error (unreadable input, unwritable output) */
};

/* How an option takes its value. */
enum { CLI_ARG_NONE = 0, CLI_ARG_REQUIRED = 1, CLI_ARG_OPTIONAL = 2 };

/* One long option ("--name", "--name=value", "--name value"); the table ends with a NULL name. */
typedef struct cli_option {
    const char *name;
    int arg;
    int id; /* > 0, returned by cli_next */
} cli_option;

/* What cli_next returns besides an option id. */
enum {
    CLI_END = 0,         /* no argument left */
    CLI_POSITIONAL = -1, /* a non-option argument, in *value */
    CLI_DONE = -2,       /* --help / -h or --version: already printed on stdout, exit 0 */
    CLI_ERROR = -3       /* unknown option or missing value; already reported on stderr, exit 2 */
};

typedef struct cli_parser {
    const char *command; /* subcommand name, for messages */
    const char *usage;   /* the subcommand's complete --help text */
    int argc;
    char **argv;
    int index;           /* next argument to read */
    int only_positional; /* after "--" */
} cli_parser;

/* Starts parsing argv[1..argc) of subcommand `command` (argv[0] is the subcommand itself);
 * `usage` is printed for --help. */
void cli_init(cli_parser *p, const char *command, const char *usage, int argc, char **argv);

/* Prints "cbvh VERSION (library VERSION, file format N)" on stdout. */
void cli_print_version(void);

/* Reads the next argument; sets *value to the option's value (NULL when it has none) or to
 * the positional argument. A lone "-" is positional (stdin/stdout in the usual convention). */
int cli_next(cli_parser *p, const cli_option *options, const char **value);

/* Prints "cbvh COMMAND: FILE: message" (or "cbvh COMMAND: message" when file is NULL) on stderr. */
void cli_error(const char *command, const char *file, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Reports a usage error plus a hint to run --help; returns CLI_EXIT_USAGE. */
int cli_usage_error(const char *command, const char *fmt, ...)
#ifdef __GNUC__
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Parses an option value; on error reports "--option: ..." and returns 0. */
int cli_parse_u32(const char *command, const char *option, const char *text, uint32_t min, uint32_t max,
                  uint32_t *out);
int cli_parse_float(const char *command, const char *option, const char *text, float min, float max,
                    float *out);

/* Exit status for a library result: 1 for bad input (corrupt, unsupported, bad or empty mesh,
 * limit), 2 for I/O, invalid arguments and out of memory. */
int cli_exit_for(cbvh_result result);

/* Reports a library error as "cbvh COMMAND: FILE: message" and returns cli_exit_for(code). */
int cli_report(const char *command, const char *file, const cbvh_error *err);

/* Opens and validates a .cbvh file; on failure reports it and returns the exit status (else 0). */
int cli_open(const char *command, const char *path, cbvh_file **out);

/* The last message cli_error, cli_usage_error or cli_report printed ("" when none) and the file it named
 * ("" when none): the JSON error object of a failed command (main prints it for --json). */
const char *cli_last_message(void);
const char *cli_last_file(void);

/* A command that printed its own JSON for a failure (or one line per asset of a batch) says so, and main
 * prints no other. */
void cli_json_error_printed(void);
int cli_json_error_was_printed(void);

/* Lower-case name of a section type ("nodes", "triangles", ...; "ancillary" or "unknown" otherwise). */
const char *cli_section_name(uint32_t type);

/* Monotonic clock in seconds. */
double cli_now(void);

#endif
