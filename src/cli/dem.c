/* `gransim dem`: run a DEM case file (docs/case-files.md, "DEM cases"). */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "gransim/dem.h"
#include "gransim/liggghts.h"

static void dem_usage(FILE *fp) {
  fprintf(fp,
          "usage: gransim dem CASE --out DIR [--quiet] [--threads N] [--ranks N] [--launcher CMD]\n"
          "       gransim dem --check CASE\n\n"
          "Runs the DEM case CASE (spheres, STL walls, insertion, statistics) and writes into DIR:\n"
          "  timeseries.csv       hold-up, energies, contacts, collision and impact rates\n"
          "  collisions.csv       collision events per class pair, numbers per class, C_ij\n"
          "  collision_kernel.csv C_ij as a table for the PBM kernel `table` (measure: diameter)\n"
          "  impacts.csv, impact_velocity.csv  wall impacts per class, impact speeds\n"
          "  impact_table.csv     impacts per particle and second and lognormal fits of the impact\n"
          "                       speed per class, for the breakage selection `dem_impact`\n"
          "                       (measure: diameter); impact_table_WALL.csv: one wall alone\n"
          "  velocity.csv         speed and velocity components per class and axial compartment\n"
          "  residence.csv        residence-time distribution of particles leaving through outlets\n"
          "                       (residence_class.csv: per class)\n"
          "  vtk/                 particles and meshes for ParaView (output.vtk_every): .vtp frames,\n"
          "                       .pvd series with their times\n"
          "--check validates CASE (reads meshes) without running it.  --threads sets the OpenMP\n"
          "threads (default: OMP_NUM_THREADS or all).\n"
          "With `engine: liggghts` in the dem section the case runs in LIGGGHTS instead: gransim\n"
          "writes the deck and the initial bed into DIR/liggghts, runs `mpirun -np N liggghts -in\n"
          "in.gransim` there (--ranks N, default the machine's cores; --launcher CMD replaces\n"
          "`mpirun -np N`, e.g. \"srun -n 64\"; $GRANSIM_LIGGGHTS names another executable) and\n"
          "reduces its dumps into the same tables.\n");
}

int gs_cmd_dem(int argc, char **argv) {
  const char *path = NULL, *out = NULL;
  int check = 0, progress = 1;
  gs_lig_options lig = {.ranks = 0, .launcher = NULL, .binary = NULL, .progress = 1};
  for (int i = 0; i < argc; i++) {
    if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
      dem_usage(stdout);
      return 0;
    } else if (!strcmp(argv[i], "--out") && i + 1 < argc) out = argv[++i];
    else if (!strcmp(argv[i], "--check")) check = 1;
    else if (!strcmp(argv[i], "--quiet")) progress = 0;
    else if (!strcmp(argv[i], "--launcher") && i + 1 < argc) lig.launcher = argv[++i];
    else if (!strcmp(argv[i], "--ranks") && i + 1 < argc) {
      lig.ranks = atoi(argv[++i]);
      if (lig.ranks < 1) {
        fprintf(stderr, "gransim dem: --ranks needs a positive integer, got '%s'\n", argv[i]);
        return 2;
      }
    }
    else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
      int n = atoi(argv[++i]);
      if (n < 1) {
        fprintf(stderr, "gransim dem: --threads needs a positive integer, got '%s'\n", argv[i]);
        return 2;
      }
      omp_set_num_threads(n);
    } else if (argv[i][0] == '-') {
      fprintf(stderr, "gransim dem: unknown option '%s' (see gransim dem --help)\n", argv[i]);
      return 2;
    } else if (!path) path = argv[i];
    else {
      fprintf(stderr, "gransim dem: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
  }
  if (!path || (!out && !check)) {
    dem_usage(stderr);
    return 2;
  }
  gs_error err = {0};
  gs_dem_case *c = gs_dem_case_load(path, &err);
  if (!c) {
    fprintf(stderr, "gransim: %s\n", err.msg);
    return 1;
  }
  char desc[512];
  gs_dem_case_describe(c, desc, sizeof desc);
  int rc = 0;
  const int liggghts = gs_dem_case_engine(c) == 1;
  lig.progress = progress;
  if (liggghts && (rc = gs_lig_check(c, &err))) fprintf(stderr, "gransim: %s: %s\n", path, err.msg);
  else if (check) printf("%s: valid%s. %s\n", path, liggghts ? " (engine liggghts)" : "", desc);
  else {
    if (progress) fprintf(stderr, "gransim dem: %s: %s%s\n", path, desc, liggghts ? "; engine liggghts" : "");
    rc = liggghts ? gs_lig_case_run(c, out, &lig, &err) : gs_dem_case_run(c, out, progress, &err);
    if (rc) fprintf(stderr, "gransim: %s\n", err.msg);
    else if (progress) fprintf(stderr, "gransim dem: results in %s\n", out);
  }
  gs_dem_case_free(c);
  return rc ? 1 : 0;
}
