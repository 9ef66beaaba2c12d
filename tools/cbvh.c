/* cbvh.c: the cbvh command's main: global options and dispatch to the subcommands. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "json.h"
#include "commands.h"

typedef struct command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    {"cook", cmd_cook, "cook a mesh file (or a generated scene) into a .cbvh file"},
    {"info", cmd_info, "describe a .cbvh file: sections, tree statistics, quantization error"},
    {"verify", cmd_verify, "validate a .cbvh file completely"},
    {"raycast", cmd_raycast, "cast rays read from stdin, print hits on stdout"},
    {"demo", cmd_demo, "cook, open and query the built-in scene; check answers by brute force"},
    {"bench", cmd_bench, "measure cbvh against Embree and Bullet on the same triangles and rays"},
    {"report", cmd_report, "compare the format's precision and layout choices: error and run time"},
};

static const char usage[] = "Usage: cbvh COMMAND [ARGS...]\n"
                            "       cbvh COMMAND --help\n"
                            "       cbvh --version\n"
                            "\n"
                            "Cooks triangle meshes into quantized BVH files and queries them.\n"
                            "\n"
                            "Commands:\n";

static void print_usage(FILE *out)
{
    fputs(usage, out);
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(out, "  %-9s %s\n", commands[i].name, commands[i].summary);
    fputs("\n"
          "Exit status: 0 success, 1 invalid or corrupt input, 2 usage or I/O error.\n"
          "See cbvh(1) for details.\n",
          out);
}

/* Whether the command was asked for JSON on stdout: --json as a flag (bench and report take --json FILE). */
static int wants_json(const char *name, int argc, char **argv)
{
    if (!strcmp(name, "bench") || !strcmp(name, "report"))
        return 0;
    for (int k = 1; k < argc && strcmp(argv[k], "--"); k++)
        if (!strcmp(argv[k], "--json"))
            return 1;
    return 0;
}

/* A failed command's JSON when it printed none itself (usage errors, files that do not open):
 * {"command", "error": {"status", "file", "message"}}, as the stderr message says. */
static void print_json_error(const char *name, int status)
{
    json_writer w;
    json_init(&w, stdout);
    json_begin_object(&w, NULL);
    json_string(&w, "command", name);
    json_begin_object(&w, "error");
    json_uint(&w, "status", (uint64_t)status);
    json_string(&w, "file", cli_last_file());
    json_string(&w, "message", cli_last_message());
    json_end_object(&w);
    json_end_object(&w);
    json_finish(&w);
}

static const command *find_command(const char *name)
{
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(commands[i].name, name))
            return &commands[i];
    return NULL;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        print_usage(stderr);
        return CLI_EXIT_USAGE;
    }
    const char *name = argv[1];
    if (!strcmp(name, "--help") || !strcmp(name, "-h")) {
        print_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (!strcmp(name, "--version")) {
        cli_print_version();
        return CLI_EXIT_OK;
    }
    if (!strcmp(name, "help")) {
        /* "cbvh help COMMAND" is "cbvh COMMAND --help". */
        if (argc < 3) {
            print_usage(stdout);
            return CLI_EXIT_OK;
        }
        const command *c = find_command(argv[2]);
        if (!c) {
            fprintf(stderr, "cbvh: unknown command '%s'; try 'cbvh --help'\n", argv[2]);
            return CLI_EXIT_USAGE;
        }
        static char help_option[] = "--help";
        char *help_argv[] = {argv[2], help_option, NULL};
        return c->run(2, help_argv);
    }
    const command *c = find_command(name);
    if (!c) {
        fprintf(stderr, "cbvh: unknown command '%s'; try 'cbvh --help'\n", name);
        return CLI_EXIT_USAGE;
    }
    int status = c->run(argc - 1, argv + 1);
    if (status != CLI_EXIT_OK && wants_json(name, argc - 1, argv + 1) && !cli_json_error_was_printed())
        print_json_error(name, status);
    /* A full disk or a closed pipe shows up only when stdout is flushed. */
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "cbvh %s: error writing to standard output\n", name);
        return status ? status : CLI_EXIT_USAGE;
    }
    return status;
}
