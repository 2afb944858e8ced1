/* Subcommands implemented in their own files. */
#ifndef GRANSIM_CLI_COMMANDS_H
#define GRANSIM_CLI_COMMANDS_H
int gs_cmd_validate(int argc, char **argv);
#endif
