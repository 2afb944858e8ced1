/* gransim sensitivity: Sobol' indices or Morris screening of a case's
 * outputs over ranges of its keys, the runs done as one sweep
 * (src/study/sensitivity.c, gransim/study.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/study.h"

static const char *const SENS_HELP =
    "usage: gransim sensitivity CASE --range KEY=LO:HI[:log] [--range ...] --outputs A,B,...\n"
    "                           --method sobol:N | morris:R [options] --out DIR\n\n"
    "Global sensitivity of the case's outputs at the final time to its dotted KEYs\n"
    "(as in gransim sweep) over their ranges.  All runs are one sweep into DIR\n"
    "(parallel, resumable; DIR/sweep.csv holds every run).\n\n"
    "  --range KEY=LO:HI     a key and its range (LO < HI); :log samples log(value)\n"
    "  --outputs A,B,...     sweep output columns: M0, M1_<coordinate>, d10_c<j>,\n"
    "                        d50_c<j>, d90_c<j>, M2_c<j>, mean_<coordinate>_c<j>, ...;\n"
    "                        with one compartment also without _c1 (d50)\n"
    "  --method sobol:N      Sobol' first-order (S1) and total (ST) indices from a\n"
    "                        Saltelli sample: N (k + 2) runs for k keys, N >= 16\n"
    "                        (Saltelli et al. 2010 for S1, Jansen 1999 for ST), with\n"
    "                        percentile bootstrap intervals\n"
    "  --method morris:R     Morris screening: R trajectories, R (k + 1) runs, R >= 2;\n"
    "                        mu, mu* (mean |elementary effect|) and sigma per unit of\n"
    "                        each range (Morris 1991)\n"
    "  --levels P            Morris grid levels (even, default 4)\n"
    "  --bootstrap B         Sobol bootstrap resamples (default 500)\n"
    "  --conf C              interval level (default 0.95)\n"
    "  --seed S              sample shift, bootstrap, trajectories (default 1)\n"
    "  --out DIR             DIR/sensitivity.csv and the sweep's files\n"
    "  --resume              continue a killed analysis (same options)\n"
    "  --threads N           runs at once (default: all cores)\n"
    "  --quiet, --progress   as gransim sweep\n\n"
    "DIR/sensitivity.csv: output,key,S1 [1],S1_lo [1],S1_hi [1],ST [1],ST_lo [1],ST_hi [1]\n"
    "(sobol) or output,key,mu [unit],mu_star [unit],sigma [unit],unit (morris: in the\n"
    "output's unit, the row's unit), a row per output and key.  docs/studies.md\n";

static int usage_error(const char *fmt, const char *a) {
  fprintf(stderr, "gransim sensitivity: ");
  fprintf(stderr, fmt, a);
  fprintf(stderr, " (see gransim sensitivity --help)\n");
  return 2;
}

/* a non-negative integer option; -1 when it is none */
static long count_of(const char *v) {
  char *end;
  long n = strtol(v, &end, 10);
  return *v && !*end && n >= 0 ? n : -1;
}

int gs_cmd_sensitivity(int argc, char **argv) {
  const char *path = NULL, *method = NULL;
  gs_sweep_options sw = {.progress = -1};
  gs_sens_options so = {.seed = 1};
  gs_study_axis *axes = calloc((size_t)argc + 1, sizeof *axes);
  const char **outputs = calloc((size_t)argc + 1, sizeof *outputs);
  char *outputs_text = NULL;
  size_t naxes = 0, nout = 0;
  gs_error err = {0};
  gs_sens_result res = {0};
  gs_cfg *cfg = NULL;
  int rc = axes && outputs ? 0 : 1;
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP},   {"range", required_argument, NULL, 'R'},
      {"outputs", required_argument, NULL, 'O'}, {"method", required_argument, NULL, 'm'},
      {"levels", required_argument, NULL, 'l'},  {"bootstrap", required_argument, NULL, 'b'},
      {"conf", required_argument, NULL, 'c'},    {"seed", required_argument, NULL, 's'},
      {"out", required_argument, NULL, 'o'},     {"resume", no_argument, NULL, 'r'},
      {"quiet", no_argument, NULL, 'q'},         {"progress", no_argument, NULL, 'p'},
      {"threads", required_argument, NULL, 't'}, {0}};
  gs_cli_begin();
  for (int o; !rc && (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: fputs(SENS_HELP, stdout); goto done;
    case 'R':
      if (gs_study_parse_range(optarg, &axes[naxes++], &err)) rc = 2;
      break;
    case 'O':
      free(outputs_text);
      outputs_text = strdup(optarg);
      nout = 0;
      for (char *s = outputs_text ? strtok(outputs_text, ",") : NULL; s; s = strtok(NULL, ",")) outputs[nout++] = s;
      break;
    case 'm': method = optarg; break;
    case 'l':
      so.levels = (int)count_of(optarg);
      if (so.levels < 0) rc = usage_error("--levels needs an even integer, got '%s'", optarg);
      break;
    case 'b': {
      long b = count_of(optarg);
      if (b < 1) rc = usage_error("--bootstrap needs a positive integer, got '%s'", optarg);
      so.nboot = (size_t)b;
      break;
    }
    case 'c': {
      char *end;
      so.conf = strtod(optarg, &end);
      if (*end || !(so.conf > 0 && so.conf < 1)) rc = usage_error("--conf needs a level in (0, 1), got '%s'", optarg);
      break;
    }
    case 's': {
      long sd = count_of(optarg);
      if (sd < 0) rc = usage_error("--seed needs a non-negative integer, got '%s'", optarg);
      so.seed = (unsigned long)sd;
      break;
    }
    case 'o': sw.out_dir = optarg; break;
    case 'r': sw.resume = 1; break;
    case 'q': sw.progress = 0; break;
    case 'p': sw.progress = 1; break;
    case 't':
      if (gs_cli_positive("sensitivity", "threads", optarg, &sw.threads)) rc = 2;
      break;
    default: rc = 2;
    }
  for (int i = optind; !rc && i < argc; i++)
    if (!path) path = argv[i];
    else rc = usage_error("unexpected argument '%s'", argv[i]);
  if (!rc && (!path || !sw.out_dir || !method || !naxes || !nout))
    rc = usage_error("%s", "needs CASE, --range KEY=LO:HI, --outputs COLS, --method sobol:N|morris:R and --out DIR");
  if (!rc) {
    const char *colon = strchr(method, ':');
    long n = colon ? count_of(colon + 1) : -1;
    if (!strncmp(method, "sobol:", 6)) so.method = GS_SENS_SOBOL;
    else if (!strncmp(method, "morris:", 7)) so.method = GS_SENS_MORRIS;
    if (!so.method || n < 0) rc = usage_error("--method: expected sobol:N or morris:R, got '%s'", method);
    so.n = (size_t)(n < 0 ? 0 : n);
  }
  if (rc) {
    if (err.msg[0]) fprintf(stderr, "gransim sensitivity: %s\n", err.msg);
    goto done;
  }
  /* under mpirun every rank would run the whole sample into the same DIR:
   * the analysis does not share its runs over ranks yet */
  const char *ranks = getenv("OMPI_COMM_WORLD_SIZE") ? getenv("OMPI_COMM_WORLD_SIZE") : getenv("PMI_SIZE");
  if (ranks && atoi(ranks) > 1) {
    fprintf(stderr, "gransim sensitivity: started by mpirun with %s ranks; it runs on the threads "
                    "of one process (--threads), start it without mpirun\n", ranks);
    rc = 2;
    goto done;
  }
  char csv[4200];
  snprintf(csv, sizeof csv, "%s/sensitivity.csv", sw.out_dir);
  if (!(cfg = gs_cfg_load_file(path, &err)) ||
      gs_sensitivity_case(cfg, axes, naxes, outputs, nout, &so, &sw, &res, &err) ||
      gs_sens_write_csv(csv, &res, axes, outputs, &err)) {
    fprintf(stderr, "gransim sensitivity: %s\n", err.msg);
    rc = err.code == GS_EINPUT ? 2 : 1;
    goto done;
  }
  for (size_t o = 0; o < nout; o++) {
    printf("%s:\n", outputs[o]);
    if (so.method == GS_SENS_SOBOL)
      printf("  %-36s %9s %21s %9s %21s\n", "key", "S1", "interval", "ST", "interval");
    else printf("  %-36s %12s %12s %12s\n", "key", "mu", "mu*", "sigma");
    for (size_t k = 0; k < naxes; k++) {
      const size_t i = o * naxes + k;
      if (so.method == GS_SENS_SOBOL)
        printf("  %-36s %9.4f [%9.4f, %9.4f] %9.4f [%9.4f, %9.4f]\n", axes[k].key, res.s1[i],
               res.s1_lo[i], res.s1_hi[i], res.st[i], res.st_lo[i], res.st_hi[i]);
      else
        printf("  %-36s %12.5g %12.5g %12.5g\n", axes[k].key, res.mu[i], res.mu_star[i], res.sigma[i]);
    }
  }
  printf("%zu runs; %s%s\n", res.runs, csv,
         so.method == GS_SENS_SOBOL ? "; intervals: percentile bootstrap" : "");
done:
  for (size_t k = 0; axes && k < naxes; k++) gs_study_axis_free(&axes[k]);
  free(axes);
  free(outputs);
  free(outputs_text);
  gs_sens_result_free(&res);
  gs_cfg_free(cfg);
  return rc;
}
