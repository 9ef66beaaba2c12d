/* commands.h: the entry points of the cbvh subcommands; argv[0] is the subcommand name. Each returns an exit
 * status (tools/cli.h). */
#ifndef CBVH_TOOLS_COMMANDS_H
#define CBVH_TOOLS_COMMANDS_H

int cmd_cook(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_verify(int argc, char **argv);
int cmd_raycast(int argc, char **argv);
int cmd_demo(int argc, char **argv);
int cmd_bench(int argc, char **argv);
int cmd_report(int argc, char **argv);

#endif
