/* getopt_long for the subcommands: see options.h. */
#include "cli/options.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg/nearest.h"

void gs_cli_begin(void) {
  optind = 0; /* glibc: start over, with a fresh scan of this argv */
  opterr = 0; /* messages are ours, naming the subcommand */
}

int gs_cli_next(int argc, char **argv, const struct option *opts) {
  /* ':' first: a missing value is told apart from an unknown option */
  const int o = getopt_long(argc, argv, ":h", opts, NULL);
  if (o != '?' && o != ':') return o;
  const char *arg = optind > 0 && optind <= argc ? argv[optind - 1] : "";
  if (o == ':') {
    fprintf(stderr, "gransim %s: option '%s' needs a value (see gransim %s --help)\n", argv[0], arg, argv[0]);
    return '?';
  }
  char given[128];
  snprintf(given, sizeof given, "%s", arg + strspn(arg, "-"));
  given[strcspn(given, "=")] = '\0';
  const char *names[128];
  size_t n = 0;
  for (; opts[n].name && n < sizeof names / sizeof *names; n++) names[n] = opts[n].name;
  const char *near = gs_nearest_word(given, names, n);
  char hint[160] = "";
  if (near) snprintf(hint, sizeof hint, "; did you mean '--%s'?", near);
  /* an option that takes no value given one (--quiet=1) is not unknown */
  for (size_t i = 0; i < n && strchr(arg, '='); i++)
    if (!strcmp(names[i], given) && opts[i].has_arg == no_argument) {
      fprintf(stderr, "gransim %s: option '--%s' takes no value (see gransim %s --help)\n", argv[0], given, argv[0]);
      return '?';
    }
  fprintf(stderr, "gransim %s: unknown option '%s'%s (see gransim %s --help)\n", argv[0], arg, hint, argv[0]);
  return '?';
}

int gs_cli_positive(const char *cmd, const char *name, const char *value, int *out) {
  char *end;
  long n = strtol(value, &end, 10);
  if (!*value || *end || n < 1 || n > 1 << 20) {
    fprintf(stderr, "gransim %s: --%s needs a positive integer, got '%s'\n", cmd, name, value);
    return 2;
  }
  *out = (int)n;
  return 0;
}
