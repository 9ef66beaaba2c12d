/* cmd_verify.c: `cbvh verify`: full validation of a .cbvh file through the library's loader. */
#include <stdio.h>

#include "cli.h"
#include "commands.h"
#include "json.h"

static const char usage[] =
    "Usage: cbvh verify [--json] FILE\n"
    "\n"
    "Opens FILE with the library's loader, which checks everything a reader relies on: header,\n"
    "CRCs, section table and layout, compressed streams, every node link and box, leaf ranges,\n"
    "vertex indices and values, the remap table. Prints 'ok' when the file is valid.\n"
    "\n"
    "Options:\n"
    "  --json       print {\"file\", \"ok\": true} instead of 'ok'; a failure prints\n"
    "               {\"command\", \"error\": {\"status\", \"file\", \"message\"}}\n"
    "  -h, --help   show this help\n"
    "\n"
    "Exit status: 0 valid, 1 corrupt or unsupported (the reason is printed on stderr),\n"
    "2 usage error or the file cannot be read.\n";

int cmd_verify(int argc, char **argv)
{
    cli_parser p;
    cli_init(&p, "verify", usage, argc, argv);
    static const cli_option options[] = {{"json", CLI_ARG_NONE, 1}, {NULL, 0, 0}};
    const char *path = NULL, *value;
    int id, json = 0;
    while ((id = cli_next(&p, options, &value)) != CLI_END) {
        if (id == CLI_DONE)
            return CLI_EXIT_OK;
        if (id == CLI_ERROR)
            return CLI_EXIT_USAGE;
        if (id == 1) {
            json = 1;
            continue;
        }
        if (path)
            return cli_usage_error("verify", "unexpected argument '%s'", value);
        path = value;
    }
    if (!path)
        return cli_usage_error("verify", "expected a file");
    cbvh_file *file;
    int rc = cli_open("verify", path, &file);
    if (rc)
        return rc;
    cbvh_close(file);
    if (json) {
        json_writer w;
        json_init(&w, stdout);
        json_begin_object(&w, NULL);
        json_string(&w, "file", path);
        json_bool(&w, "ok", 1);
        json_end_object(&w);
        json_finish(&w);
    } else {
        puts("ok");
    }
    return CLI_EXIT_OK;
}
