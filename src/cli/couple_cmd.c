/* `gransim couple`: run a coupled PBM-DEM case (docs/case-files.md, "Coupled cases"). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/couple.h"
#include "gransim/parallel.h"

static void couple_usage(FILE *fp) {
  fprintf(fp,
          "usage: gransim couple CASE --out DIR [--resume] [--quiet] [--threads N]\n"
          "                      [--ranks N] [--launcher CMD]\n"
          "       gransim couple --check CASE [--ranks N] [--launcher CMD]\n\n"
          "Runs a coupled case (PBM keys, a `dem:` section and `coupling: {mode: one_way, ...}`):\n"
          "the DEM with size classes derived from the PBM grid until its steady-state detector\n"
          "fires, then the PBM with the DEM's tables as its `table` kernel and `dem_impact`\n"
          "selection.  Writes into DIR:\n"
          "  dem/                 the DEM stage: case.yaml (as run), its tables and time series,\n"
          "                       steady.csv (the detector's figures); dem.partial/ until complete\n"
          "  result.h5, summary.csv  the PBM run\n"
          "--resume skips a complete DEM stage and resumes the PBM from its partial files.\n"
          "--check validates CASE (derived classes, DEM case, PBM case) without running it.\n"
          "--threads sets the OpenMP threads of both stages (default: OMP_NUM_THREADS or all).\n"
          "With `engine: liggghts` in the DEM section every DEM stage runs `mpirun -np N liggghts`\n"
          "in its folder's liggghts/ (--ranks N, default the machine's cores; --launcher CMD\n"
          "replaces `mpirun -np N`, e.g. \"srun -n 64\"), as `gransim dem` does; with the embedded\n"
          "engine --ranks and --launcher are refused.\n");
}

static int couple_check(const char *path, const gs_couple_options *opt) {
  gs_error err = {0};
  char desc[1024];
  if (gs_couple_check_options(path, opt, desc, sizeof desc, &err)) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    return 1;
  }
  printf("%s: valid. %s\n", path, desc);
  return 0;
}

int gs_cmd_couple_check(const char *path) { return couple_check(path, NULL); }

int gs_cmd_couple(int argc, char **argv) {
  const char *path = NULL;
  gs_couple_options opt = {.progress = 1};
  int check = 0;
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP}, {"out", required_argument, NULL, 'o'},
      {"check", no_argument, NULL, 'c'},        {"resume", no_argument, NULL, 'r'},
      {"quiet", no_argument, NULL, 'q'},        {"threads", required_argument, NULL, 't'},
      {"ranks", required_argument, NULL, 'n'},  {"launcher", required_argument, NULL, 'l'},
      {0}};
  gs_cli_begin();
  for (int o, n; (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: couple_usage(stdout); return 0;
    case 'o': opt.out_dir = optarg; break;
    case 'c': check = 1; break;
    case 'r': opt.resume = 1; break;
    case 'q': opt.progress = 0; break;
    case 'l': opt.launcher = optarg; break;
    case 'n':
      if (gs_cli_positive("couple", "ranks", optarg, &opt.ranks)) return 2;
      break;
    case 't':
      if (gs_cli_positive("couple", "threads", optarg, &n)) return 2;
      omp_set_num_threads(n);
      break;
    default: return 2;
    }
  for (int i = optind; i < argc; i++) {
    if (path) {
      fprintf(stderr, "gransim couple: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
    path = argv[i];
  }
  if (!path || (!opt.out_dir && !check)) {
    couple_usage(stderr);
    return 2;
  }
  if (check) return couple_check(path, &opt);
  /* each rank would run its own DEM stage into the same folder */
  if (gs_parallel_size() > 1) {
    if (gs_parallel_rank() == 0)
      fprintf(stderr, "gransim couple: runs on one process (not under mpirun with several ranks); its stages use "
              "OpenMP threads (--threads)\n");
    return 2;
  }
  gs_error err = {0};
  char context[1024];
  snprintf(context, sizeof context, "coupled case %s, results in %s: continue with `gransim couple %s --out %s --resume`", path, opt.out_dir, path, opt.out_dir);
  gs_parallel_context(context);
  if (gs_couple_run(path, &opt, &err)) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    return 1;
  }
  return 0;
}
