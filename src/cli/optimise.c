/* gransim optimise: case controls chosen so that its outputs come closest
 * to a target over time (src/study/optimise.c, gransim/study.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/study.h"

static const char *const OPT_HELP =
    "usage: gransim optimise CASE --target TARGET.csv --controls KEY=LO:HI[:log] [--controls ...]\n"
    "                        [--weights NAME=W,...] [--method nelder-mead|bounded]\n\n"
    "Chooses the values of the case's dotted KEYs (as in gransim sweep) within\n"
    "[LO, HI] that minimise sum_j w_j sum_t ((output_j(t) - target_j(t)) / RMS_j)^2\n"
    "over the target's times t and columns j.  TARGET.csv is as gransim fit's\n"
    "--data: a header 'time,NAME,...' (NAME a sweep output column: M0, d50_c1,\n"
    "total_liquid_c1, ...; with one compartment also without _c1) and a row per\n"
    "time; every time must be an output time of the case (output.times).  RMS_j is\n"
    "the target column's RMS, so that columns of different units weigh alike.\n\n"
    "  --controls KEY=LO:HI  a control and its range (LO < HI); :log in log(value)\n"
    "  --weights NAME=W,...  weights w_j >= 0 of target columns (default 1 each)\n"
    "  --method nelder-mead  GSL's simplex (nmsimplex2; Nelder & Mead 1965) over a\n"
    "                        logistic map of each range (the default)\n"
    "  --method bounded      NLopt's BOBYQA (Powell 2009) inside the ranges\n"
    "  --max-runs N          model runs at most (default 4000)\n"
    "  --tol T               stop at steps below T in units of the ranges (default 1e-9)\n\n"
    "The start is the case's own value of each key where it lies inside the range,\n"
    "else the range's middle.  Prints the controls found and the objective at the\n"
    "start and the end.  docs/studies.md\n";

static int usage_error(const char *fmt, const char *a) {
  fprintf(stderr, "gransim optimise: ");
  fprintf(stderr, fmt, a);
  fprintf(stderr, " (see gransim optimise --help)\n");
  return 2;
}

/* --weights NAME=W,...: w[j] for the target's column NAME */
static int parse_weights(const char *text, const gs_fit_data *t, double *w) {
  char *copy = strdup(text), *save = NULL;
  int rc = copy ? 0 : 1;
  for (char *s = copy ? strtok_r(copy, ",", &save) : NULL; s && !rc; s = strtok_r(NULL, ",", &save)) {
    char *eq = strchr(s, '='), *end;
    if (!eq) {
      rc = usage_error("--weights: expected NAME=W, got '%s'", s);
      break;
    }
    *eq = '\0';
    double v = strtod(eq + 1, &end);
    size_t j = 0;
    while (j < t->ncols && strcmp(t->names[j], s)) j++;
    if (j == t->ncols) rc = usage_error("--weights: '%s' is no column of the target", s);
    else if (end == eq + 1 || *end || !(v >= 0) || !isfinite(v))
      rc = usage_error("--weights: the weight must be a number >= 0, got '%s'", eq + 1);
    else w[j] = v;
  }
  free(copy);
  return rc;
}

int gs_cmd_optimise(int argc, char **argv) {
  const char *path = NULL, *target_path = NULL, *weights = NULL;
  gs_study_axis *ctl = calloc((size_t)argc + 1, sizeof *ctl);
  size_t nc = 0;
  gs_opt_options opt = {.method = GS_OPT_NELDER_MEAD};
  gs_error err = {0};
  gs_fit_data target = {0};
  gs_opt_result res = {0};
  gs_cfg *cfg = NULL;
  double *w = NULL;
  int rc = ctl ? 0 : 1;
  static const struct option opts[] = {
      {"help", no_argument, NULL, GS_CLI_HELP},    {"controls", required_argument, NULL, 'c'},
      {"target", required_argument, NULL, 'T'},   {"weights", required_argument, NULL, 'w'},
      {"method", required_argument, NULL, 'm'},   {"max-runs", required_argument, NULL, 'n'},
      {"tol", required_argument, NULL, 't'},      {0}};
  gs_cli_begin();
  for (int o; !rc && (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: fputs(OPT_HELP, stdout); goto done;
    case 'c':
      if (gs_study_parse_range(optarg, &ctl[nc++], &err)) {
        fprintf(stderr, "gransim optimise: %s\n", err.msg);
        rc = 2;
      }
      break;
    case 'T': target_path = optarg; break;
    case 'w': weights = optarg; break;
    case 'm':
      if (!strcmp(optarg, "nelder-mead")) opt.method = GS_OPT_NELDER_MEAD;
      else if (!strcmp(optarg, "bounded")) opt.method = GS_OPT_BOUNDED;
      else rc = usage_error("--method: expected nelder-mead or bounded, got '%s'", optarg);
      break;
    case 'n': {
      char *end;
      long n = strtol(optarg, &end, 10);
      if (*end || n < 1) rc = usage_error("--max-runs needs a positive integer, got '%s'", optarg);
      opt.max_runs = (size_t)(n < 1 ? 1 : n);
      break;
    }
    case 't': {
      char *end;
      opt.tol = strtod(optarg, &end);
      if (*end || !(opt.tol > 0)) rc = usage_error("--tol needs a positive number, got '%s'", optarg);
      break;
    }
    default: rc = 2;
    }
  for (int i = optind; !rc && i < argc; i++)
    if (!path) path = argv[i];
    else rc = usage_error("unexpected argument '%s'", argv[i]);
  if (!rc && (!path || !target_path || !nc))
    rc = usage_error("%s", "needs CASE, --target FILE and --controls KEY=LO:HI");
  if (rc) goto done;
  if (gs_fit_data_read(target_path, &target, &err)) {
    fprintf(stderr, "gransim optimise: %s\n", err.msg);
    rc = 1;
    goto done;
  }
  if (weights) {
    w = malloc(target.ncols * sizeof *w);
    for (size_t j = 0; w && j < target.ncols; j++) w[j] = 1;
    if (!w || (rc = parse_weights(weights, &target, w))) goto done;
    opt.weights = w;
  }
  if (!(cfg = gs_cfg_load_file(path, &err)) ||
      gs_optimise_run(cfg, ctl, nc, &target, &opt, &res, &err)) {
    fprintf(stderr, "gransim optimise: %s\n", err.msg);
    rc = err.code == GS_EINPUT ? 2 : 1;
    goto done;
  }
  printf("%-32s %24s  range\n", "control", "value");
  for (size_t k = 0; k < nc; k++)
    printf("%-32s %24.17g  [%g, %g]%s\n", ctl[k].key, res.x[k], ctl[k].lo, ctl[k].hi,
           ctl[k].log ? " log" : "");
  printf("objective %.6g (start %.6g); %zu times x %zu columns; %s; %ld model runs%s%s\n",
         res.objective, res.start_objective, target.ntimes, target.ncols,
         opt.method == GS_OPT_BOUNDED ? "bounded (NLopt BOBYQA)" : "nelder-mead (GSL nmsimplex2)",
         res.runs, res.converged ? "" : "; NOT CONVERGED: ", res.converged ? "" : res.stop);
  if (res.failed_runs)
    printf("%ld trial runs failed (not taken); the first: %s\n", res.failed_runs,
           res.first_failure.msg);
done:
  for (size_t k = 0; ctl && k < nc; k++) gs_study_axis_free(&ctl[k]);
  free(ctl);
  free(w);
  gs_fit_data_free(&target);
  gs_opt_result_free(&res);
  gs_cfg_free(cfg);
  return rc;
}
