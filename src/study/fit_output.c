/* A fit's files: the estimates and every measured value beside the model's
 * (gs_fit_write, gransim/study.h), which `gransim plot` draws. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "demdata/csv_meta.h"
#include "gransim/study.h"
#include "study/study_internal.h"

static int write_estimates(const char *dir, const gs_study_axis *params, size_t np,
                           const gs_fit_result *res, gs_error *err) {
  gs_csv_out t;
  FILE *f = gs_csv_open_in(&t, dir, "estimates.csv", err);
  if (!f) return err->code;
  fprintf(f, "# The estimates of gransim fit, in the units of their keys in the case file; "
             "std_error from the Jacobian at the estimates, ci95 the 95 %% interval "
             "estimate -+ t(0.975, n - p) std_error; identifiable 0 where the data cannot fix "
             "the parameter (docs/studies.md).\n");
  fprintf(f, "# unit: the parameter's SI unit (docs/case-files.md); \"" GS_STUDY_CASE_UNIT
             "\" where it depends on the model, as beta0's on the kernel: then the unit the case "
             "file gives the key.\n");
  fprintf(f, "parameter,estimate [unit],std_error [unit],ci95_lo [unit],ci95_hi [unit],"
             "range_lo [unit],range_hi [unit],log_range [1],identifiable [1],unit\n");
  for (size_t k = 0; k < np; k++)
    fprintf(f, "%s,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%d,%s\n", params[k].key, res->x[k],
            res->stderr_x[k], res->ci_lo[k], res->ci_hi[k], params[k].lo, params[k].hi,
            params[k].log, !res->unidentified[k], gs_study_key_unit(params[k].key));
  static const char *const units[] = {"estimate", "the row's unit", "std_error", "the row's unit",
                                      "ci95_lo", "the row's unit", "ci95_hi", "the row's unit",
                                      "range_lo", "the row's unit", "range_hi", "the row's unit",
                                      "log_range", "1", "identifiable", "1", NULL};
  return gs_csv_close(&t, "gransim fit", units, err);
}

static void write_values(FILE *f, const char *role, const gs_fit_batches *bs, const gs_fit_eval *ev) {
  size_t at = 0;
  for (size_t b = 0; b < bs->n; b++) {
    const gs_fit_data *d = &bs->batch[b].data;
    for (size_t i = 0; i < d->ntimes; i++)
      for (size_t j = 0; j < d->ncols; j++, at++) {
        double lo, hi;
        size_t comp;
        const int sieve = gs_fit_sieve_column(d->names[j], &lo, &hi, &comp) == 1;
        fprintf(f, "%s,%s,%.17g,%s,", role, bs->batch[b].name, d->times[i], d->names[j]);
        if (sieve) fprintf(f, "%.10g,%.10g,", lo * 1e6, hi * 1e6);
        else fprintf(f, ",,");
        fprintf(f, "%.17g,%.17g,%s\n", d->values[i * d->ncols + j], ev->model[at], ev->unit[at]);
      }
  }
}

int gs_fit_write(const char *dir, const gs_study_axis *params, size_t np, const gs_fit_result *res,
                 const gs_fit_batches *fit, const gs_fit_eval *fit_ev, const gs_fit_batches *pred,
                 const gs_fit_eval *pred_ev, gs_error *err) {
  if (mkdir(dir, 0777) && errno != EEXIST)
    return gs_error_set(err, GS_EIO, "cannot make folder '%s': %s", dir, strerror(errno));
  int rc = write_estimates(dir, params, np, res, err);
  if (rc) return rc;
  gs_csv_out t;
  FILE *f = gs_csv_open_in(&t, dir, "fitted.csv", err);
  if (!f) return err->code;
  fprintf(f, "# Every measured value of gransim fit's batches (role fit) and held-out batches "
             "(role predict, --predict) beside the case's value at the estimates; measured and "
             "model are in the unit of their column, the row's unit (d10/d50/d90 m, sieve "
             "classes, porosity and moisture 1, moments as in summary.csv); d_lo and d_hi are a "
             "sieve class's edges, empty for other columns.\n");
  fprintf(f, "role,batch,time [s],column,d_lo [um],d_hi [um],measured [unit],model [unit],unit\n");
  write_values(f, "fit", fit, fit_ev);
  if (pred) write_values(f, "predict", pred, pred_ev);
  static const char *const units[] = {"measured", "the row's unit", "model", "the row's unit",
                                      NULL};
  return gs_csv_close(&t, "gransim fit", units, err);
}
