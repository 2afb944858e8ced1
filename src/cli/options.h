/* Command-line options of the subcommands, parsed by getopt_long: every
 * option is long, given as `--key value` or `--key=value`, in any order with
 * the positional arguments; -h is --help. */
#ifndef GRANSIM_CLI_OPTIONS_H
#define GRANSIM_CLI_OPTIONS_H

#include <getopt.h>

/* The value of the help option in every table (`{"help", no_argument, NULL, 'h'}`). */
#define GS_CLI_HELP 'h'

/* Start parsing a subcommand's arguments: argv[0] is the subcommand's name
 * ("run"), used in messages. */
void gs_cli_begin(void);
/* The next option's val (optarg holds its value), -1 when the options are
 * done (the positional arguments are then argv[optind..argc), getopt having
 * moved them there), or '?' after printing what was wrong on stderr:
 *   gransim run: unknown option '--ot'; did you mean '--out'? (see gransim run --help)
 *   gransim run: option '--out' needs a value (see gransim run --help) */
int gs_cli_next(int argc, char **argv, const struct option *opts);
/* A positive integer option value into *out; prints
 * "gransim CMD: --NAME needs a positive integer, got 'V'" and returns 2 otherwise. */
int gs_cli_positive(const char *cmd, const char *name, const char *value, int *out);

#endif
