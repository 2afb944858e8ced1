/* gransim fit: case parameters fitted to measured summary quantities
 * (src/study/fit.c, gransim/study.h). */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/study.h"

static const char *const FIT_HELP =
    "usage: gransim fit CASE (--data MEASURED.csv | --batches BATCHES.yaml)\n"
    "                    --params KEY=LO:HI[:log] [--params ...]\n"
    "                    [--global crs2|mlsl|isres[:RUNS]] [--seed S]\n"
    "                    [--porosity-tol EPS] [--max-runs N]\n"
    "                    [--predict HELDOUT.yaml] [--out DIR]\n\n"
    "Fits the values of the case's dotted KEYs (as in gransim sweep, e.g.\n"
    "mechanisms.0.kernel.beta0) within [LO, HI] so that the case's outputs match\n"
    "measured data: a CSV with a header 'time,NAME,...' and a row per time, NAME\n"
    "being a sweep output column (M0, M1_<coordinate>, d10_c<j>, d50_c<j>,\n"
    "d90_c<j>, M2_c<j>, mean_<coordinate>_c<j>, total_<coordinate>_c<j>,\n"
    "porosity_c<j>, moisture_c<j>; with one compartment also without _c1: d50)\n"
    "or a sieve class sieve_<LO>_<HI>[_c<j>] (volume fraction of the granules\n"
    "between LO and HI micrometres).  --data: one batch, the case as it is.\n"
    "--batches: a YAML file listing batches, each with its own recipe (key\n"
    "overrides) and data file, optionally the sieves the classes must match;\n"
    "all their residuals are one least-squares problem.  Every data time must\n"
    "be an output time of the case (output.times).  Least squares with GSL's\n"
    "multifit_nlinear (Levenberg-Marquardt); residuals are scaled by each\n"
    "column's RMS (one RMS for all sieve classes); the parameters are kept in\n"
    "their ranges by a logistic map (in log with :log).  Prints the estimates\n"
    "with standard errors from the Jacobian, their correlations, the\n"
    "parameters the data cannot identify, and R^2.  --global: an NLopt global\n"
    "search over the ranges (RUNS model runs, default 50 per parameter; --seed)\n"
    "gives the start.  --porosity-tol EPS: the epsilon-constraint: the other\n"
    "columns' squared residuals least subject to the porosity columns' RMS error\n"
    "<= EPS (NLopt COBYLA, at most --max-runs runs, default 2000).  --predict: runs the held-out\n"
    "batches of HELDOUT.yaml (the --batches format) at the estimates and reports\n"
    "their errors.  --out DIR: DIR/estimates.csv and DIR/fitted.csv (every\n"
    "measured value beside the model's), which gransim plot DIR draws.\n"
    "docs/studies.md\n";

/* A non-negative integer option. */
static int parse_count(const char *name, const char *text, unsigned long *out) {
  char *end;
  errno = 0;
  *out = strtoul(text, &end, 10);
  if (end == text || *end || errno || text[0] == '-') {
    fprintf(stderr, "gransim fit: %s needs a whole number >= 0, got '%s'\n", name, text);
    return 2;
  }
  return 0;
}

/* --global METHOD[:RUNS] */
static int parse_global(const char *text, char *method, size_t size, gs_fit_options *fo) {
  snprintf(method, size, "%s", text);
  char *colon = strchr(method, ':');
  unsigned long runs = 0;
  if (colon) {
    *colon = '\0';
    if (parse_count("--global's RUNS", colon + 1, &runs) || !runs) {
      if (!runs) fprintf(stderr, "gransim fit: --global %s: RUNS must be > 0\n", text);
      return 2;
    }
  }
  gs_error err = {0};
  if (gs_fit_global_check(method, &err)) {
    fprintf(stderr, "gransim fit: %s\n", err.msg);
    return 2;
  }
  fo->global = method;
  fo->global_runs = runs;
  return 0;
}

/* Per batch and column of ev: the RMS error in the column's unit and the
 * data's RMS; per batch chi^2 of the scaled residuals. */
static void print_errors(const char *what, const gs_fit_batches *bs, const gs_fit_eval *ev) {
  printf("%s:\n  %-16s %-24s %14s %14s %10s\n", what, "batch", "column", "rms_error", "rms_data",
         "relative");
  size_t at = 0;
  for (size_t b = 0; b < bs->n; b++) {
    const gs_fit_data *d = &bs->batch[b].data;
    double chi2 = 0;
    for (size_t j = 0; j < d->ncols; j++) {
      double se = 0, sd = 0;
      for (size_t i = 0; i < d->ntimes; i++) {
        const size_t q = i * d->ncols + j;
        se += pow(ev->model[at + q] - d->values[q], 2);
        sd += pow(d->values[q], 2);
        chi2 += pow(ev->resid[at + q], 2);
      }
      se = sqrt(se / (double)d->ntimes);
      sd = sqrt(sd / (double)d->ntimes);
      printf("  %-16s %-24s %14.6g %14.6g %10.4g\n", bs->batch[b].name, d->names[j], se, sd,
             sd > 0 ? se / sd : NAN);
    }
    printf("  %-16s chi^2 = %.6g over %zu values (scaled residuals)\n", bs->batch[b].name, chi2,
           d->ntimes * d->ncols);
    at += d->ntimes * d->ncols;
  }
}

/* --predict and --out: the batches at the estimates, their errors, the files. */
static int predict_and_write(const gs_cfg *cfg, const gs_study_axis *params, size_t np,
                             const gs_fit_result *res, const gs_fit_batches *bs, gs_fit_eval *fit_ev,
                             const gs_fit_batches *pred, gs_fit_eval *pred_ev, const char *out_dir) {
  gs_error err = {0};
  int rc = GS_OK;
  if (pred) {
    gs_fit_eval_free(pred_ev);
    rc = gs_fit_evaluate(cfg, params, np, res->x, pred, pred_ev, &err);
    if (!rc) {
      print_errors("held-out batches at the estimates (--predict)", pred, pred_ev);
      printf("held-out: chi^2 = %.6g over %zu values, R^2 = %.6g\n", pred_ev->chi2,
             pred_ev->nresid, pred_ev->r2);
    }
  }
  if (!rc && out_dir) {
    rc = gs_fit_evaluate(cfg, params, np, res->x, bs, fit_ev, &err);
    if (!rc) rc = gs_fit_write(out_dir, params, np, res, bs, fit_ev, pred, pred_ev, &err);
    if (!rc) printf("wrote %s/estimates.csv and %s/fitted.csv\n", out_dir, out_dir);
  }
  if (rc) fprintf(stderr, "gransim fit: %s\n", err.msg);
  return rc ? 1 : 0;
}

int gs_cmd_fit(int argc, char **argv) {
  const char *path = NULL, *data_path = NULL, *batches_path = NULL, *predict_path = NULL,
             *out_dir = NULL;
  gs_study_axis *params = calloc((size_t)argc + 1, sizeof *params);
  size_t np = 0;
  gs_error err = {0};
  gs_fit_batches bs = {0}, pred = {0};
  gs_fit_eval fit_ev = {0}, pred_ev = {0};
  gs_fit_options fo = {0};
  char global[32];
  gs_fit_result res = {0};
  gs_cfg *cfg = NULL;
  int rc = params ? 0 : 1;
  static const struct option opts[] = {{"help", no_argument, NULL, GS_CLI_HELP},
                                       {"params", required_argument, NULL, 'p'},
                                       {"data", required_argument, NULL, 'd'},
                                       {"batches", required_argument, NULL, 'b'},
                                       {"predict", required_argument, NULL, 'P'},
                                       {"out", required_argument, NULL, 'o'},
                                       {"global", required_argument, NULL, 'g'},
                                       {"seed", required_argument, NULL, 's'},
                                       {"porosity-tol", required_argument, NULL, 'e'},
                                       {"max-runs", required_argument, NULL, 'm'},
                                       {0}};
  gs_cli_begin();
  for (int o; !rc && (o = gs_cli_next(argc, argv, opts)) != -1;) switch (o) {
    case GS_CLI_HELP: fputs(FIT_HELP, stdout); goto done;
    case 'p':
      if (gs_study_parse_range(optarg, &params[np++], &err)) {
        fprintf(stderr, "gransim fit: %s\n", err.msg);
        rc = 2;
      }
      break;
    case 'd': data_path = optarg; break;
    case 'b': batches_path = optarg; break;
    case 'P': predict_path = optarg; break;
    case 'o': out_dir = optarg; break;
    case 'g': rc = parse_global(optarg, global, sizeof global, &fo); break;
    case 's': rc = parse_count("--seed", optarg, &fo.seed); break;
    case 'm': {
      unsigned long m;
      rc = parse_count("--max-runs", optarg, &m);
      fo.max_runs = m;
      break;
    }
    case 'e': {
      char *end;
      fo.porosity_tol = strtod(optarg, &end);
      if (end == optarg || *end || !(fo.porosity_tol > 0) || !isfinite(fo.porosity_tol)) {
        fprintf(stderr, "gransim fit: --porosity-tol needs a number > 0, got '%s'\n", optarg);
        rc = 2;
      }
      break;
    }
    default: rc = 2;
    }
  for (int i = optind; !rc && i < argc; i++)
    if (!path) path = argv[i];
    else {
      fprintf(stderr, "gransim fit: unexpected '%s' (see gransim fit --help)\n", argv[i]);
      rc = 2;
    }
  if (!rc && (!path || !(data_path || batches_path) || !np)) {
    fprintf(stderr, "gransim fit: needs CASE, --data FILE (or --batches FILE) and --params "
                    "KEY=LO:HI (see gransim fit --help)\n");
    rc = 2;
  }
  if (!rc && data_path && batches_path) {
    fprintf(stderr, "gransim fit: --data and --batches exclude each other: list the data file "
                    "as a batch (see gransim fit --help)\n");
    rc = 2;
  }
  if (rc) goto done;
  if ((data_path ? gs_fit_batches_single(data_path, &bs, &err)
                 : gs_fit_batches_read(batches_path, &bs, &err)) ||
      (predict_path && gs_fit_batches_read(predict_path, &pred, &err)) ||
      !(cfg = gs_cfg_load_file(path, &err)) ||
      /* the held-out batches are checked against the case before the fit runs */
      (predict_path && gs_fit_evaluate(cfg, params, np, NULL, &pred, &pred_ev, &err)) ||
      gs_fit_run_batches(cfg, params, np, &bs, &fo, &res, &err)) {
    fprintf(stderr, "gransim fit: %s\n", err.msg);
    rc = 1;
    goto done;
  }
  printf("%-32s %24s %12s  range\n", "parameter", "estimate", "std_error");
  size_t nunid = 0;
  for (size_t k = 0; k < np; k++) {
    nunid += (size_t)res.unidentified[k];
    if (res.unidentified[k])
      printf("%-32s %24.17g %12s  [%g, %g]%s\n", params[k].key, res.x[k], "-", params[k].lo,
             params[k].hi, params[k].log ? " log" : "");
    else
      printf("%-32s %24.17g %12.4g  [%g, %g]%s\n", params[k].key, res.x[k], res.stderr_x[k],
             params[k].lo, params[k].hi, params[k].log ? " log" : "");
  }
  printf("correlations:\n");
  for (size_t k = 0; k < np; k++) {
    printf("  %-30s", params[k].key);
    for (size_t q = 0; q < np; q++) printf(" %7.4f", res.corr[k * np + q]);
    printf("\n");
  }
  printf("singular values (Jacobian in fractions of the ranges):");
  for (size_t k = 0; k < np; k++) printf(" %.4g", res.sv[k]);
  printf("\n");
  if (nunid) {
    printf("NOT IDENTIFIABLE from these data (a direction of singular value below 1e-3 of the "
           "largest):");
    for (size_t k = 0; k < np; k++)
      if (res.unidentified[k]) printf(" %s", params[k].key);
    printf("\n");
  }
  if (bs.n == 1)
    printf("R^2 = %.10g; %zu values (%zu times x %zu columns)", res.r2, res.nresid,
           bs.batch[0].data.ntimes, bs.batch[0].data.ncols);
  else
    printf("R^2 = %.10g; %zu values in %zu batches", res.r2, res.nresid, bs.n);
  if (fo.porosity_tol > 0)
    printf(", chi^2 = %.4g (residuals scaled by each column's RMS); epsilon-constrained (COBYLA): "
           "porosity RMS error %.6g <= %g; %ld model runs",
           res.chi2, res.porosity_rms, fo.porosity_tol, res.runs);
  else
    printf(", chi^2 = %.4g (residuals scaled by each column's RMS); %zu iterations, %ld model "
           "runs%s",
           res.chi2, res.iterations, res.runs,
           res.converged ? "" : "; NOT CONVERGED (iteration limit or no progress)");
  if (fo.global) printf(" (%ld in the global start, %s)", res.global_runs, fo.global);
  printf("\n");
  if (predict_path || out_dir) rc = predict_and_write(cfg, params, np, &res, &bs, &fit_ev,
                                                      predict_path ? &pred : NULL, &pred_ev, out_dir);
done:
  gs_fit_eval_free(&fit_ev);
  gs_fit_eval_free(&pred_ev);
  gs_fit_batches_free(&pred);
  for (size_t k = 0; params && k < np; k++) gs_study_axis_free(&params[k]);
  free(params);
  gs_fit_batches_free(&bs);
  gs_fit_result_free(&res);
  gs_cfg_free(cfg);
  return rc;
}
