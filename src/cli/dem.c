/* `gransim dem`: run a DEM case file (docs/case-files.md, "DEM cases"). */
#include <errno.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/cfd.h"
#include "gransim/dem.h"
#include "gransim/liggghts.h"
#include "gransim/parallel.h"

static void dem_usage(FILE *fp) {
  fprintf(fp,
          "usage: gransim dem CASE --out DIR [--quiet] [--threads N] [--engine embedded|liggghts]\n"
          "                  [--ranks N] [--launcher CMD] [--dry-run | --reduce]\n"
          "       gransim dem --check CASE [--engine embedded|liggghts]\n\n"
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
          "  spray.csv            with `spray:`: droplets and the liquid ledger (injected = on\n"
          "                       particles + airborne + on walls + left), checked at every output;\n"
          "                       spray_classes.csv: the liquid per size class at the end against\n"
          "                       the absorption law's shares\n"
          "  geometry/            generated walls (walls[].generate) as STL files\n"
          "  granulation*.csv     with `granulation:`: solid x liquid class populations, collisions\n"
          "                       and aggregations per update, the run's kernel table (measure: volume)\n"
          "  vtk/                 particles and meshes for ParaView (output.vtk_every): .vtp frames,\n"
          "                       .pvd series with their times\n"
          "  gas.csv, gas.pvd     with a `gas` section: the gas phase over time, and its fields\n"
          "                       (vtk/gas_*.vtr: void fraction, pressure, velocity)\n"
          "--check validates CASE (reads meshes) without running it.  --threads sets the OpenMP\n"
          "threads (default: OMP_NUM_THREADS or all).\n"
          "With `engine: liggghts` in the dem section the case runs in LIGGGHTS instead: gransim\n"
          "writes the deck and the initial bed into DIR/liggghts, runs `mpirun -np N liggghts -in\n"
          "in.gransim` there (--ranks N, default the machine's cores; --launcher CMD replaces\n"
          "`mpirun -np N`, e.g. \"srun -n 64\"; $GRANSIM_LIGGGHTS names another executable) and\n"
          "reduces its dumps into the same tables.  --engine overrides dem.engine.  --dry-run writes\n"
          "DIR/liggghts (deck, initial bed, meshes, run.sh) without running, for a cluster job;\n"
          "--reduce then writes the tables from the dumps of that finished run.\n");
}

int gs_cmd_dem(int argc, char **argv) {
  const char *path = NULL, *out = NULL;
  int check = 0, progress = 1, engine = -1;
  gs_lig_options lig = {.ranks = 0, .launcher = NULL, .binary = NULL, .progress = 1};
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP},    {"out", required_argument, NULL, 'o'},
      {"check", no_argument, NULL, 'c'},           {"quiet", no_argument, NULL, 'q'},
      {"launcher", required_argument, NULL, 'l'}, {"ranks", required_argument, NULL, 'r'},
      {"threads", required_argument, NULL, 't'},  {"engine", required_argument, NULL, 'e'},
      {"dry-run", no_argument, NULL, 'd'},        {"reduce", no_argument, NULL, 'R'},
      {0}};
  gs_cli_begin();
  for (int o, n; (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: dem_usage(stdout); return 0;
    case 'o': out = optarg; break;
    case 'c': check = 1; break;
    case 'q': progress = 0; break;
    case 'l': lig.launcher = optarg; break;
    case 'e':
      if (!strcmp(optarg, "embedded")) engine = 0;
      else if (!strcmp(optarg, "liggghts")) engine = 1;
      else {
        fprintf(stderr, "gransim dem: --engine '%s': expected embedded or liggghts\n", optarg);
        return 2;
      }
      break;
    case 'd': lig.dry_run = 1; break;
    case 'R': lig.reduce_only = 1; break;
    case 'r':
      if (gs_cli_positive("dem", "ranks", optarg, &lig.ranks)) return 2;
      break;
    case 't':
      if (gs_cli_positive("dem", "threads", optarg, &n)) return 2;
      omp_set_num_threads(n);
      break;
    default: return 2;
    }
  for (int i = optind; i < argc; i++) {
    if (path) {
      fprintf(stderr, "gransim dem: unexpected argument '%s'\n", argv[i]);
      return 2;
    }
    path = argv[i];
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
  if (engine >= 0) gs_dem_case_set_engine(c, engine);
  char desc[512];
  gs_dem_case_describe(c, desc, sizeof desc);
  int rc = 0;
  const int liggghts = gs_dem_case_engine(c) == 1;
  if ((lig.dry_run || lig.reduce_only) && (!liggghts || check || (lig.dry_run && lig.reduce_only))) {
    fprintf(stderr, "gransim dem: --dry-run and --reduce are for the LIGGGHTS engine (dem.engine: liggghts or "
            "--engine liggghts), one at a time, with --out\n");
    gs_dem_case_free(c);
    return 2;
  }
  lig.progress = progress;
  /* a `gas` section: the gas phase steps inside the DEM run (src/cfd) */
  gs_cfd *gas = NULL;
  if (gs_dem_case_gas(c)) {
    if (liggghts) {
      fprintf(stderr, "gransim: %s: a gas section needs the embedded DEM (engine: embedded)\n", path);
      gs_dem_case_free(c);
      return 1;
    }
    if (out && !check && mkdir(out, 0777) && errno != EEXIST) {
      fprintf(stderr, "gransim: %s: %s\n", out, strerror(errno));
      gs_dem_case_free(c);
      return 1;
    }
    if (!(gas = gs_cfd_case_create(c, check ? NULL : out, &err))) {
      fprintf(stderr, "gransim: %s\n", err.msg);
      gs_dem_case_free(c);
      return 1;
    }
    int n[3];
    double h[3];
    gs_cfd_dims(gas, n, h);
    size_t len = strlen(desc);
    snprintf(desc + len, sizeof desc - len, "; gas on %d x %d x %d cells", n[0], n[1], n[2]);
  }
  if (liggghts && (rc = gs_lig_check(c, &err))) fprintf(stderr, "gransim: %s\n", err.msg); /* FILE:LINE: key */
  else if (check) printf("%s: valid%s. %s\n", path, liggghts ? " (engine liggghts)" : "", desc);
  else {
    if (progress) fprintf(stderr, "gransim dem: %s: %s%s\n", path, desc, liggghts ? "; engine liggghts" : "");
    char context[1024]; /* for an MPI error in the gas phase's pressure solve (hypre) */
    snprintf(context, sizeof context, "DEM case %s, results in %s: run it again", path, out);
    gs_parallel_context(context);
    rc = liggghts ? gs_lig_case_run(c, out, &lig, &err) : gs_dem_case_run(c, out, progress, &err);
    if (rc) fprintf(stderr, "gransim: %s\n", err.msg);
    else if (progress && !lig.dry_run) fprintf(stderr, "gransim dem: results in %s\n", out);
  }
  gs_cfd_free(gas);
  gs_dem_case_free(c);
  return rc ? 1 : 0;
}
