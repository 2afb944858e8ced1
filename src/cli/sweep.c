/* gransim sweep: many runs of one case over a grid or a Latin hypercube of
 * variations (src/study, gransim/study.h). */
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/parallel.h"
#include "gransim/study.h"

static const char *const SWEEP_HELP =
    "usage: gransim sweep CASE --set KEY=V1,V2,... [--set ...] --out DIR [options]\n"
    "       gransim sweep CASE --design lhs:N --range KEY=LO:HI[:log] [--range ...]\n"
    "                     [--seed S] --out DIR [options]\n\n"
    "Runs CASE once per variation and gathers one row per run into DIR/sweep.csv.\n"
    "KEY is a dotted path into the case file: map keys and list indices from 0,\n"
    "e.g. mechanisms.0.kernel.beta0, solver.rtol, output.end.  The key must exist in\n"
    "the case file, and every variation is checked by the case reader before any\n"
    "run starts.\n\n"
    "  --set KEY=V1,V2,...   values of KEY; several --set give every combination\n"
    "                        (the first --set varies slowest)\n"
    "  --design lhs:N        a Latin hypercube of N runs over the --range keys: each\n"
    "                        range cut into N equal strata, each stratum used once\n"
    "  --range KEY=LO:HI     the range of KEY (LO < HI); KEY=LO:HI:log strata in log\n"
    "  --seed S              seed of the hypercube's random pairing (default 1)\n"
    "  --out DIR             DIR/base-case.yaml (the case as read; a --resume with\n"
    "                        another case is refused), DIR/runs.csv (a row per run as\n"
    "                        it finishes), and at the end DIR/sweep.csv (all rows in\n"
    "                        run order) and DIR/sweep.h5 (the same table in HDF5)\n"
    "  --outputs A,B,...     more summary columns per compartment at the final time\n"
    "                        (M0 M1 M2 d10 d50 d90 mean_<axis> total_<axis>, porosity,\n"
    "                        liquid_content, a mechanism's column such as bed_temperature)\n"
    "  --at T1,T2,...        the outputs also at these output times of the case [s]:\n"
    "                        columns NAME@T (e.g. d50_c1@60 [m]) after the final ones\n"
    "  --resume              continue a killed sweep: skip the runs DIR/runs.csv has\n"
    "  --threads N           runs at once (default: OMP_NUM_THREADS or all cores);\n"
    "                        each run is single-threaded\n"
    "  --quiet, --progress   no progress line / one even when stderr is no terminal\n\n"
    "Columns: run (from 1), status (ok or error), the varied keys, M0 and\n"
    "M1_<coordinate> (all compartments), d10_c<j> d50_c<j> d90_c<j> per compartment j,\n"
    "the --outputs columns NAME_c<j>, and error (the message of a failed run, whose\n"
    "outputs are nan); each key and output named with its SI unit, d50_c1 [m]\n"
    "([case]: the unit the case file gives the key).  A failed run does not stop\n"
    "the others.  docs/studies.md\n";

static int usage_error(const char *fmt, const char *a) {
  fprintf(stderr, "gransim sweep: ");
  fprintf(stderr, fmt, a);
  fprintf(stderr, " (see gransim sweep --help)\n");
  return 2;
}

/* Under MPI every rank reads the same command line and checks the same
 * design, so rank 0 alone speaks. */
static int quiet_rank(void) { return gs_parallel_rank() > 0; }

int gs_cmd_sweep(int argc, char **argv) {
  if (quiet_rank() && !freopen("/dev/null", "w", stderr)) return 1;
  const char *path = NULL, *design = NULL;
  gs_sweep_options opt = {.progress = -1};
  gs_study_axis *axes = calloc((size_t)argc + 1, sizeof *axes);
  const char **outputs = calloc((size_t)argc + 1, sizeof *outputs);
  char *outputs_text = NULL;
  double *at = NULL;
  size_t naxes = 0, nsets = 0, nranges = 0;
  unsigned long seed = 1;
  gs_error err = {0};
  gs_design d = {0};
  gs_cfg *cfg = NULL;
  int rc = 0;
  if (!axes || !outputs) {
    fprintf(stderr, "gransim sweep: out of memory\n");
    rc = 1;
    goto done;
  }
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP}, {"set", required_argument, NULL, 'S'},
      {"range", required_argument, NULL, 'R'}, {"design", required_argument, NULL, 'd'},
      {"seed", required_argument, NULL, 's'},  {"out", required_argument, NULL, 'o'},
      {"outputs", required_argument, NULL, 'O'}, {"at", required_argument, NULL, 'a'},
      {"resume", no_argument, NULL, 'r'},
      {"quiet", no_argument, NULL, 'q'},       {"progress", no_argument, NULL, 'p'},
      {"threads", required_argument, NULL, 't'}, {0}};
  gs_cli_begin();
  for (int o; !rc && (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: fputs(SWEEP_HELP, stdout); goto done;
    case 'S':
      if (gs_study_parse_set(optarg, &axes[naxes++], &err)) rc = 2;
      nsets++;
      break;
    case 'R':
      if (gs_study_parse_range(optarg, &axes[naxes++], &err)) rc = 2;
      nranges++;
      break;
    case 'd': design = optarg; break;
    case 's': {
      char *end;
      seed = strtoul(optarg, &end, 10);
      if (!*optarg || *end) rc = usage_error("--seed needs a non-negative integer, got '%s'", optarg);
      break;
    }
    case 'o': opt.out_dir = optarg; break;
    case 'O':
      free(outputs_text);
      outputs_text = strdup(optarg);
      opt.noutputs = 0;
      for (char *s = outputs_text ? strtok(outputs_text, ",") : NULL; s; s = strtok(NULL, ",")) outputs[opt.noutputs++] = s;
      break;
    case 'a': {
      free(at);
      at = calloc(strlen(optarg) / 2 + 2, sizeof *at);
      opt.nat = 0;
      if (!at) {
        rc = usage_error("%s", "out of memory");
        break;
      }
      for (const char *p = optarg; !rc;) {
        char *end;
        at[opt.nat] = strtod(p, &end);
        if (end == p || (*end && *end != ',') || !isfinite(at[opt.nat]) || at[opt.nat] < 0)
          rc = usage_error("--at: expected output times T1,T2,... [s] >= 0, got '%s'", optarg);
        opt.nat++;
        if (!*end) break;
        p = end + 1;
      }
      break;
    }
    case 'r': opt.resume = 1; break;
    case 'q': opt.progress = 0; break;
    case 'p': opt.progress = 1; break;
    case 't':
      if (gs_cli_positive("sweep", "threads", optarg, &opt.threads)) rc = 2;
      break;
    default: rc = 2;
    }
  for (int i = optind; !rc && i < argc; i++)
    if (!path) path = argv[i];
    else rc = usage_error("unexpected argument '%s'", argv[i]);
  if (rc) {
    if (err.msg[0]) fprintf(stderr, "gransim sweep: %s\n", err.msg);
    goto done;
  }
  if (!path || !opt.out_dir) {
    rc = usage_error("%s", "needs a CASE and --out DIR");
    goto done;
  }
  opt.outputs = outputs;
  opt.at = at;
  if (design) {
    char *end;
    long n = strncmp(design, "lhs:", 4) ? 0 : strtol(design + 4, &end, 10);
    if (strncmp(design, "lhs:", 4) || end == design + 4 || *end)
      rc = usage_error("--design: expected lhs:N, got '%s'", design);
    else if (n < 1) rc = usage_error("--design %s: N must be at least 1", design);
    else if (nsets) rc = usage_error("%s", "--design lhs takes --range keys, not --set");
    else if (!nranges) rc = usage_error("%s", "--design lhs needs at least one --range KEY=LO:HI");
    else if (gs_design_lhs(axes, naxes, (size_t)n, seed, &d, &err)) rc = 2;
  } else if (nranges) rc = usage_error("%s", "--range needs --design lhs:N (a grid takes --set lists)");
  else if (!nsets) rc = usage_error("%s", "nothing to vary: give --set KEY=V1,V2,... or --design lhs:N --range ...");
  else if (gs_design_grid(axes, naxes, &d, &err)) rc = 2;
  if (rc) {
    if (err.msg[0]) fprintf(stderr, "gransim sweep: %s\n", err.msg);
    goto done;
  }
  /* a gransim without MPI under mpirun: every rank would run the whole
   * sweep into the same files */
  const char *ranks = getenv("OMPI_COMM_WORLD_SIZE") ? getenv("OMPI_COMM_WORLD_SIZE") : getenv("PMI_SIZE");
  if (!gs_parallel_have_mpi() && ranks && atoi(ranks) > 1) {
    fprintf(stderr, "gransim sweep: started by mpirun with %s ranks, but this gransim was built "
                    "without MPI; start it without mpirun (it uses all cores) or build with "
                    "-DGRANSIM_MPI=ON\n", ranks);
    rc = 2;
    goto done;
  }
  char context[1024];
  snprintf(context, sizeof context, "sweep of %s, results in %s: the runs finished before the error are kept in %s/runs.csv; continue with the same command and --resume", path, opt.out_dir, opt.out_dir);
  gs_parallel_context(context);
  cfg = gs_cfg_load_file(path, &err);
  gs_sweep_report rep;
  if (!cfg || gs_sweep_run(cfg, &d, &opt, &rep, &err)) {
    fprintf(stderr, "gransim sweep: %s\n", err.msg);
    rc = 1;
    goto done;
  }
  fprintf(stderr,
          "gransim sweep: %s: %zu runs: %zu run now, %zu finished before (--resume); %zu ok, %zu "
          "failed; results in %s/sweep.csv\n",
          path, rep.runs, rep.ran, rep.skipped, rep.runs - rep.failed, rep.failed, opt.out_dir);
done:
  for (size_t k = 0; axes && k < naxes; k++) gs_study_axis_free(&axes[k]);
  free(axes);
  free(outputs);
  free(outputs_text);
  free(at);
  gs_design_free(&d);
  gs_cfg_free(cfg);
  return rc;
}
