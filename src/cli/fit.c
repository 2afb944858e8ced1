/* gransim fit: case parameters fitted to measured summary quantities
 * (src/study/fit.c, gransim/study.h). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli/commands.h"
#include "cli/options.h"
#include "gransim/study.h"

static const char *const FIT_HELP =
    "usage: gransim fit CASE --data MEASURED.csv --params KEY=LO:HI[:log] [--params ...]\n\n"
    "Fits the values of the case's dotted KEYs (as in gransim sweep, e.g.\n"
    "mechanisms.0.kernel.beta0) within [LO, HI] so that the case's outputs match\n"
    "MEASURED.csv: a header 'time,NAME,...' and a row per time, NAME being a sweep\n"
    "output column (M0, M1_<coordinate>, d10_c<j>, d50_c<j>, d90_c<j>, M2_c<j>,\n"
    "mean_<coordinate>_c<j>, total_<coordinate>_c<j>; with one compartment also\n"
    "without _c1: d50, M2).  Every data time must be an\n"
    "output time of the case (list them in output.times).  Least squares with GSL's\n"
    "multifit_nlinear (Levenberg-Marquardt); residuals are scaled by each column's\n"
    "RMS; the parameters are kept in their ranges by a logistic map (in log with\n"
    ":log).  Prints the estimates with standard errors from the Jacobian, their\n"
    "correlations and R^2.  docs/studies.md\n";

int gs_cmd_fit(int argc, char **argv) {
  const char *path = NULL, *data_path = NULL;
  gs_study_axis *params = calloc((size_t)argc + 1, sizeof *params);
  size_t np = 0;
  gs_error err = {0};
  gs_fit_data data = {0};
  gs_fit_result res = {0};
  gs_cfg *cfg = NULL;
  int rc = params ? 0 : 1;
  static const struct option opts[] = {{"help", no_argument, NULL, GS_CLI_HELP},
                                       {"params", required_argument, NULL, 'p'},
                                       {"data", required_argument, NULL, 'd'},
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
    default: rc = 2;
    }
  for (int i = optind; !rc && i < argc; i++)
    if (!path) path = argv[i];
    else {
      fprintf(stderr, "gransim fit: unexpected '%s' (see gransim fit --help)\n", argv[i]);
      rc = 2;
    }
  if (!rc && (!path || !data_path || !np)) {
    fprintf(stderr, "gransim fit: needs CASE, --data FILE and --params KEY=LO:HI (see gransim fit --help)\n");
    rc = 2;
  }
  if (rc) goto done;
  if (gs_fit_data_read(data_path, &data, &err) || !(cfg = gs_cfg_load_file(path, &err)) ||
      gs_fit_run(cfg, params, np, &data, &res, &err)) {
    fprintf(stderr, "gransim fit: %s\n", err.msg);
    rc = 1;
    goto done;
  }
  printf("%-32s %24s %12s  range\n", "parameter", "estimate", "std_error");
  for (size_t k = 0; k < np; k++)
    printf("%-32s %24.17g %12.4g  [%g, %g]%s\n", params[k].key, res.x[k], res.stderr_x[k],
           params[k].lo, params[k].hi, params[k].log ? " log" : "");
  printf("correlations:\n");
  for (size_t k = 0; k < np; k++) {
    printf("  %-30s", params[k].key);
    for (size_t q = 0; q < np; q++) printf(" %7.4f", res.corr[k * np + q]);
    printf("\n");
  }
  printf("R^2 = %.10g; %zu values (%zu times x %zu columns), chi^2 = %.4g (residuals scaled by "
         "each column's RMS); %zu iterations, %ld model runs%s\n",
         res.r2, res.nresid, data.ntimes, data.ncols, res.chi2, res.iterations, res.runs,
         res.converged ? "" : "; NOT CONVERGED (iteration limit or no progress)");
done:
  for (size_t k = 0; params && k < np; k++) gs_study_axis_free(&params[k]);
  free(params);
  gs_fit_data_free(&data);
  gs_fit_result_free(&res);
  gs_cfg_free(cfg);
  return rc;
}
