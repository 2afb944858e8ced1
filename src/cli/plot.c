/* gransim plot DIR: the plots of a result folder, drawn by the installed
 * script gransim-plot (Python with Debian's matplotlib, h5py, pandas), which
 * this command runs in its place.  The script is looked for in
 * $GRANSIM_PLOT_SCRIPT, beside the installed command (../share/gransim, as
 * `cmake --install` lays it out) and in the source tree this binary was built
 * from, in that order. */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli/commands.h"

#ifndef GRANSIM_PLOT_SCRIPT_SRC
#define GRANSIM_PLOT_SCRIPT_SRC ""
#endif
#ifndef GRANSIM_PLOT_SCRIPT_REL
#define GRANSIM_PLOT_SCRIPT_REL "../share/gransim/gransim-plot"
#endif

/* The installed script's path, from this executable's folder. */
static int installed_script(char *buf, size_t n) {
  char exe[PATH_MAX];
  ssize_t len = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (len <= 0) return 0;
  exe[len] = '\0';
  char *slash = strrchr(exe, '/');
  if (!slash) return 0;
  *slash = '\0';
  return (size_t)snprintf(buf, n, "%s/%s", exe, GRANSIM_PLOT_SCRIPT_REL) < n;
}

int gs_cmd_plot(int argc, char **argv) {
  char path[PATH_MAX + 64];
  const char *env = getenv("GRANSIM_PLOT_SCRIPT");
  const char *tried[3] = {NULL, NULL, NULL};
  int nt = 0;
  if (env && *env) tried[nt++] = env;
  else {
    if (installed_script(path, sizeof path)) tried[nt++] = path;
    if (*GRANSIM_PLOT_SCRIPT_SRC) tried[nt++] = GRANSIM_PLOT_SCRIPT_SRC;
  }
  /* argv[0] is "plot", as for every subcommand; the script sees what follows
   * it (its own options, parsed by argparse) */
  argc--;
  argv++;
  char **args = calloc((size_t)argc + 2, sizeof *args);
  if (!args) {
    fprintf(stderr, "gransim plot: out of memory\n");
    return 1;
  }
  for (int i = 0; i < argc; i++) args[i + 1] = argv[i];
  for (int k = 0; k < nt; k++) {
    if (access(tried[k], X_OK)) continue;
    args[0] = (char *)tried[k];
    fflush(NULL);
    execv(tried[k], args);
    fprintf(stderr, "gransim plot: cannot run %s: %s\n", tried[k], strerror(errno));
    free(args);
    return 1;
  }
  fprintf(stderr, "gransim plot: the plotting script gransim-plot is not installed:");
  for (int k = 0; k < nt; k++) fprintf(stderr, "%s %s", k ? " nor" : "", tried[k]);
  fprintf(stderr, "%s; set GRANSIM_PLOT_SCRIPT to its path\n", nt ? " is not executable" : " none named");
  free(args);
  return 1;
}
