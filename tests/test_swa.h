/* Shared helpers for the SWA tests: build an SWA case from YAML, run it to a
 * temporary directory and read the ensemble distribution back from
 * result.h5.  Header-only; every function is static. */
#ifndef GRANSIM_TEST_SWA_H
#define GRANSIM_TEST_SWA_H

#include <hdf5.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gransim/swa.h"
#include "pbm_testlib.h"

#define SW_FN static __attribute__((unused))

/* printf into a malloc'ed string: the shared helper of the sectional tests */
#define sw_fmt tl_fmt

/* Build (must succeed: aborts the test otherwise); takes over yaml. */
SW_FN void sw_case(char *yaml, gs_swa_case *c) {
  gs_error e = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "swa.yaml", &e);
  free(yaml);
  if (!cfg || gs_swa_case_from_cfg(cfg, c, &e)) {
    fprintf(stderr, "case failed: %s\n", e.msg);
    exit(1);
  }
}

/* Build expecting failure; returns the message (static). */
SW_FN const char *sw_case_error(const char *yaml) {
  static gs_error e;
  memset(&e, 0, sizeof e);
  gs_swa_case c;
  gs_cfg *cfg = gs_cfg_load_string(yaml, "bad.yaml", &e);
  if (!cfg) return e.msg;
  int rc = gs_swa_case_from_cfg(cfg, &c, &e);
  gs_swa_case_free(&c);
  return rc ? e.msg : NULL;
}

typedef struct sw_result {
  double *mean, *ci;      /* [time][comp][col] */
  double *hist, *hist_ci; /* [time][comp][cell] */
  gs_swa_report rep;
  int ncol;
} sw_result;

static double *sw_read(const char *path, const char *name, size_t n) {
  double *v = calloc(n, sizeof(double));
  hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  if (f < 0 || d < 0 || H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0) {
    fprintf(stderr, "cannot read %s from %s\n", name, path);
    exit(1);
  }
  H5Dclose(d);
  H5Fclose(f);
  return v;
}

/* Run the case into a temporary directory; fills r (free with sw_free). */
SW_FN int sw_run(gs_swa_case *c, sw_result *r) {
  memset(r, 0, sizeof *r);
  r->ncol = gs_swa_ncolumns(&c->model);
  size_t nobs = c->ntimes * c->model.ncomp * (size_t)r->ncol;
  size_t nh = c->ntimes * c->model.ncomp * c->grid.ncells;
  r->mean = calloc(nobs, sizeof(double));
  r->ci = calloc(nobs, sizeof(double));
  char dir[] = "/tmp/gransim-swa-XXXXXX";
  if (!mkdtemp(dir)) return -1;
  gs_error e = {0};
  int rc = gs_swa_case_run(c, dir, 0, r->mean, r->ci, &r->rep, &e);
  if (rc) {
    fprintf(stderr, "run failed: %s\n", e.msg);
    return rc;
  }
  char p[256];
  snprintf(p, sizeof p, "%s/result.h5", dir);
  r->hist = sw_read(p, "number", nh);
  r->hist_ci = sw_read(p, "number_ci", nh);
  remove(p);
  snprintf(p, sizeof p, "%s/summary.csv", dir);
  remove(p);
  rmdir(dir);
  return 0;
}

SW_FN void sw_free(sw_result *r) {
  free(r->mean);
  free(r->ci);
  free(r->hist);
  free(r->hist_ci);
  gs_swa_report_free(&r->rep);
}

SW_FN double sw_col(const gs_swa_case *c, const sw_result *r, const double *v, size_t t, size_t z,
                    int col) {
  return v[(t * c->model.ncomp + z) * (size_t)r->ncol + (size_t)col];
}
#endif
