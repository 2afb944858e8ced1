/* `gransim couple`: run a coupled PBM-DEM case (docs/case-files.md, "Coupled cases"). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "gransim/couple.h"
#include "gransim/parallel.h"

static void couple_usage(FILE *fp) {
  fprintf(fp,
          "usage: gransim couple CASE --out DIR [--resume] [--quiet] [--threads N]\n"
          "       gransim couple --check CASE\n\n"
          "Runs a coupled case (PBM keys, a `dem:` section and `coupling: {mode: one_way, ...}`):\n"
          "the DEM with size classes derived from the PBM grid until its steady-state detector\n"
          "fires, then the PBM with the DEM's tables as its `table` kernel and `dem_impact`\n"
          "selection.  Writes into DIR:\n"
          "  dem/                 the DEM stage: case.yaml (as run), its tables and time series,\n"
          "                       steady.csv (the detector's figures); dem.partial/ until complete\n"
          "  result.h5, summary.csv  the PBM run\n"
          "--resume skips a complete DEM stage and resumes the PBM from its partial files.\n"
          "--check validates CASE (derived classes, DEM case, PBM case) without running it.\n"
          "--threads sets the OpenMP threads of both stages (default: OMP_NUM_THREADS or all).\n");
}

int gs_cmd_couple_check(const char *path) {
  gs_error err = {0};
  char desc[1024];
  if (gs_couple_check(path, desc, sizeof desc, &err)) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    return 1;
  }
  printf("%s: valid. %s\n", path, desc);
  return 0;
}

int gs_cmd_couple(int argc, char **argv) {
  const char *path = NULL;
  gs_couple_options opt = {.progress = 1};
  int check = 0;
  for (int i = 0; i < argc; i++) {
    if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      couple_usage(stdout);
      return 0;
    } else if (!strcmp(argv[i], "--out") && i + 1 < argc) opt.out_dir = argv[++i];
    else if (!strcmp(argv[i], "--check")) check = 1;
    else if (!strcmp(argv[i], "--resume")) opt.resume = 1;
    else if (!strcmp(argv[i], "--quiet")) opt.progress = 0;
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      int n = atoi(argv[++i]);
      if (n < 1) {
        fprintf(stderr, "gransim couple: --threads needs a positive integer, got '%s'\n", argv[i]);
        return 2;
      }
      omp_set_num_threads(n);
    }
    else if (argv[i][0] == '-') {
      fprintf(stderr, "gransim couple: unknown option '%s' (see gransim couple --help)\n", argv[i]);
      return 2;
    } else if (!path) path = argv[i];
    else {
      fprintf(stderr, "gransim couple: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
  }
  if (!path || (!opt.out_dir && !check)) {
    couple_usage(stderr);
    return 2;
  }
  if (check) return gs_cmd_couple_check(path);
  /* each rank would run its own DEM stage into the same folder */
  if (gs_parallel_size() > 1) {
    if (gs_parallel_rank() == 0)
      fprintf(stderr, "gransim couple: runs on one process (not under mpirun with several ranks); its stages use "
              "OpenMP threads (--threads)\n");
    return 2;
  }
  gs_error err = {0};
  if (gs_couple_run(path, &opt, &err)) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    return 1;
  }
  return 0;
}
