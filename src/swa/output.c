/* SWA result files: see output.h. */
#include "swa/output.h"

#include <errno.h>
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "output/h5_setup.h"
#include "gransim/version.h"
#include "output/units.h"


static int mkdir_p(const char *dir, gs_error *err) {
  char buf[4096];
  snprintf(buf, sizeof buf, "%s", dir);
  for (char *p = buf + 1; *p; p++) {
    if (*p != '/') continue;
    *p = '\0';
    if (mkdir(buf, 0777) && errno != EEXIST) return gs_error_set(err, GS_EIO, "cannot create directory %s: %s", buf, strerror(errno));
    *p = '/';
  }
  if (mkdir(buf, 0777) && errno != EEXIST) return gs_error_set(err, GS_EIO, "cannot create directory %s: %s", buf, strerror(errno));
  struct stat st;
  if (stat(buf, &st) || !S_ISDIR(st.st_mode)) return gs_error_set(err, GS_EIO, "%s is not a directory", buf);
  return GS_OK;
}

/* The cause of the first failed HDF5 call of a write, taken at once: the
 * calls that follow (closing what was open) clear HDF5's error stack. */
static char first_cause[512];

static void note_cause(void) {
  if (!first_cause[0]) gs_h5_cause(first_cause, sizeof first_cause);
}

static int put(hid_t loc, const char *name, int rank, const hsize_t *dims, const double *data) {
  hid_t sp = H5Screate_simple(rank, dims, NULL);
  hid_t ds = H5Dcreate2(loc, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  herr_t e = ds < 0 ? -1 : H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  if (e < 0) note_cause();
  if (ds >= 0 && H5Dclose(ds) < 0) {
    note_cause();
    e = -1;
  }
  H5Sclose(sp);
  return e < 0 ? -1 : 0;
}

/* Attributes as the sectional writer's (output/units.h): fixed-length UTF-8
 * strings, 64-bit integers, `units` and `dimensions` on every dataset. */
static int attr_str(hid_t loc, const char *name, const char *value) {
  herr_t e = gs_h5_str_attr(loc, name, value);
  if (e < 0) note_cause();
  return e < 0 ? -1 : 0;
}

static int attr_int(hid_t loc, const char *name, long long value) {
  herr_t e = gs_h5_i64_attr(loc, name, value);
  if (e < 0) note_cause();
  return e < 0 ? -1 : 0;
}

static int describe(hid_t loc, const char *path, const char *units, const char *dims) {
  herr_t e = gs_h5_describe(loc, path, units, dims);
  if (e < 0) note_cause();
  return e < 0 ? -1 : 0;
}

/* /discretisation: each distribution of the case as asked and as the
 * particles hold it (gransim/swa.h, gs_swa_disc): rows of the number, then
 * the volume of every coordinate. */
static int write_discretisation(hid_t f, const gs_swa_case *c) {
  const size_t n = c->ndisc, nc = (size_t)c->model.ncoord, w = 1 + nc;
  double *buf = calloc(5 * n * w + 2 * n + 1, sizeof *buf);
  size_t keys_len = 1;
  for (size_t i = 0; i < n; i++) keys_len += strlen(c->disc[i].key) + 1;
  char *keys = calloc(keys_len, 1);
  int bad = !buf || !keys;
  for (size_t i = 0; !bad && i < n; i++) {
    const gs_swa_disc *r = &c->disc[i];
    double *req = buf + i * w, *rep = buf + (n + i) * w, *sig = buf + (2 * n + i) * w;
    req[0] = r->number[0];
    rep[0] = r->number[1];
    sig[0] = r->sigma[0];
    for (size_t k = 0; k < nc; k++) {
      req[1 + k] = r->volume[k][0];
      rep[1 + k] = r->volume[k][1];
      sig[1 + k] = r->sigma[1 + k];
    }
    buf[3 * n * w + i] = gs_swa_disc_error(c, r);
    buf[3 * n * w + n + i] = r->particles;
    if (i) strcat(keys, "\n");
    strcat(keys, r->key);
  }
  if (bad) return -1;
  buf[3 * n * w + 2 * n] = c->disc_tolerance;
  hid_t g = H5Gcreate2(f, "discretisation", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) {
    note_cause();
    free(buf);
    free(keys);
    return -1;
  }
  hsize_t dims[2] = {n, w}, dn = n, one = 1;
  const char *layout = "1 (number; per unit time for feeds), m^3 (volume of each coordinate)";
  bad |= put(g, "requested", 2, dims, buf) | put(g, "represented", 2, dims, buf + n * w) |
         put(g, "sampling_error", 2, dims, buf + 2 * n * w) | put(g, "error", 1, &dn, buf + 3 * n * w) |
         put(g, "particles", 1, &dn, buf + 3 * n * w + n) | put(g, "tolerance", 1, &one, buf + 3 * n * w + 2 * n);
  bad |= describe(g, "requested", layout, "distribution,quantity") |
         describe(g, "represented", layout, "distribution,quantity") |
         describe(g, "sampling_error", "1", "distribution,quantity") | describe(g, "error", "1", "distribution") |
         describe(g, "particles", "1", "distribution") | describe(g, "tolerance", "1", "");
  bad |= attr_str(g, "keys", keys) |
         attr_str(g, "layout", "requested, represented and sampling_error (relative standard error of the "
                               "sample): per distribution (keys), its number, then the volume of every "
                               "coordinate; error: the largest relative error of number, volumes and "
                               "mean sizes; particles: the computational particles of the sample");
  if (H5Gclose(g) < 0) {
    note_cause();
    bad = 1;
  }
  free(buf);
  free(keys);
  return bad ? -1 : 0;
}

static int write_h5(const gs_swa_case *c, const char *path, const gs_swa_results *r) {
  const gs_grid *g = &c->grid;
  const gs_swa_model *m = &c->model;
  size_t nt = c->ntimes, nz = m->ncomp, ncol = (size_t)gs_swa_ncolumns(m);
  hid_t f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (f < 0) {
    note_cause();
    return -1;
  }
  int bad = 0;
  hid_t grid = H5Gcreate2(f, "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  for (int a = 0; a < g->dim; a++) {
    hid_t ax = H5Gcreate2(grid, g->axis[a].name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hsize_t ne = g->axis[a].n + 1, np = g->axis[a].n;
    bad |= put(ax, "edges", 1, &ne, g->axis[a].edges) | put(ax, "pivots", 1, &np, g->axis[a].pivots);
    bad |= describe(ax, "edges", "m^3", "edge") | describe(ax, "pivots", "m^3", "cell");
    H5Gclose(ax);
  }
  char axes[GS_MAX_DIM * GS_NAME_LEN + 8] = "", ndims[GS_MAX_DIM * GS_NAME_LEN + 40];
  for (int a = 0; a < g->dim; a++)
    snprintf(axes + strlen(axes), sizeof axes - strlen(axes), "%s%s", a ? "," : "", g->axis[a].name);
  snprintf(ndims, sizeof ndims, "time,compartment,%s", axes);
  bad |= attr_int(grid, "dim", g->dim) | attr_int(grid, "ncomp", (long long)nz) |
         attr_int(grid, "ncells", (long long)g->ncells) | attr_str(grid, "axis_names", axes);
  H5Gclose(grid);
  hsize_t d1 = nt;
  bad |= put(f, "time", 1, &d1, c->times) | describe(f, "time", "s", "time");
  hsize_t dims[2 + GS_MAX_DIM] = {nt, nz};
  for (int a = 0; a < g->dim; a++) dims[2 + a] = g->axis[a].n;
  bad |= put(f, "number", 2 + g->dim, dims, r->hist) | put(f, "number_ci", 2 + g->dim, dims, r->hist_ci);
  bad |= put(f, "outside", 2, dims, r->outside) | put(f, "particles", 2, dims, r->particles);
  bad |= describe(f, "number", "1", ndims) | describe(f, "number_ci", "1", ndims) |
         describe(f, "outside", "1", "time,compartment") | describe(f, "particles", "1", "time,compartment");
  hid_t sm = H5Gcreate2(f, "summary", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  hid_t sc = H5Gcreate2(f, "summary_ci", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  double *col = malloc(nt * nz * sizeof(double)), *cic = malloc(nt * nz * sizeof(double));
  for (size_t k = 0; col && cic && k < ncol; k++) {
    char name[GS_NAME_LEN + 16];
    gs_swa_column_name(m, (int)k, name, sizeof name);
    for (size_t i = 0; i < nt * nz; i++) {
      col[i] = r->mean[i * ncol + k];
      cic[i] = r->ci[i * ncol + k];
    }
    bad |= put(sm, name, 2, dims, col) | put(sc, name, 2, dims, cic);
    const char *u = gs_summary_unit(name);
    bad |= describe(sm, name, u ? u : "1", "time,compartment") | describe(sc, name, u ? u : "1", "time,compartment");
  }
  bad |= !col || !cic;
  free(col);
  free(cic);
  H5Gclose(sm);
  H5Gclose(sc);
  if (c->nsieve) {
    hid_t sg = H5Gcreate2(f, "sieve", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hsize_t ne = c->nsieve + 1, sd[3] = {nt, nz, c->nsieve};
    bad |= put(sg, "edges", 1, &ne, c->sieves) | put(sg, "mass_fraction", 3, sd, r->sieve) |
           put(sg, "mass_fraction_ci", 3, sd, r->sieve_ci);
    bad |= describe(sg, "edges", "m", "edge") | describe(sg, "mass_fraction", "1", "time,compartment,sieve_class") |
           describe(sg, "mass_fraction_ci", "1", "time,compartment,sieve_class");
    H5Gclose(sg);
  }
  bad |= write_discretisation(f, c);
  hid_t cs = H5Gcreate2(f, "case", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  bad |= attr_str(cs, "text", gs_cfg_source(c->cfg)) | attr_str(cs, "file", gs_cfg_name(c->cfg));
  H5Gclose(cs);
  bad |= attr_str(f, "gransim_version", gs_version()) | attr_str(f, "solver", "swa");
  bad |= attr_int(f, "runs", (long long)c->runs) | attr_int(f, "particles", (long long)m->nmax);
  bad |= attr_int(f, "seed", (long long)c->seed) | attr_int(f, "jumps", (long long)r->stats.jumps);
  bad |= attr_int(f, "fictitious", (long long)r->stats.fictitious) | attr_int(f, "ntimes", (long long)nt);
  bad |= attr_str(f, "status", "complete");
  if (H5Fclose(f) < 0) {
    note_cause();
    bad = 1;
  }
  return bad ? -1 : 0;
}

static int write_csv(const gs_swa_case *c, const char *path, const gs_swa_results *r) {
  const gs_swa_model *m = &c->model;
  size_t nz = m->ncomp, ncol = (size_t)gs_swa_ncolumns(m);
  FILE *fp = fopen(path, "w");
  if (!fp) return -1;
  char name[GS_NAME_LEN + 16];
  char head[GS_NAME_LEN + 48];
  fprintf(fp, "time [s],compartment");
  for (int ci = 0; ci < 2; ci++)
    for (size_t k = 0; k < ncol; k++) {
      gs_swa_column_name(m, (int)k, name + 3, sizeof name - 3);
      memcpy(name, "ci_", 3);
      gs_summary_header(ci ? name : name + 3, head, sizeof head);
      fprintf(fp, ",%s", head);
    }
  fprintf(fp, "\n");
  for (size_t t = 0; t < c->ntimes; t++)
    for (size_t z = 0; z < nz; z++) {
      const double *mu = r->mean + (t * nz + z) * ncol, *ci = r->ci + (t * nz + z) * ncol;
      fprintf(fp, "%.10g,%zu", c->times[t], z + 1);
      for (size_t k = 0; k < ncol; k++) fprintf(fp, ",%.10g", mu[k]);
      for (size_t k = 0; k < ncol; k++) fprintf(fp, ",%.10g", ci[k]);
      fprintf(fp, "\n");
    }
  return fclose(fp) ? -1 : 0;
}

int gs_swa_write(const gs_swa_case *c, const char *dir, const gs_swa_results *r, gs_error *err) {
  int rc = mkdir_p(dir, err);
  if (rc) return rc;
  char h5tmp[4200], h5[4200], csvtmp[4200], csv[4200];
  snprintf(h5tmp, sizeof h5tmp, "%s/.result.h5.partial", dir);
  snprintf(h5, sizeof h5, "%s/result.h5", dir);
  snprintf(csvtmp, sizeof csvtmp, "%s/.summary.csv.partial", dir);
  snprintf(csv, sizeof csv, "%s/summary.csv", dir);
  gs_h5_setup();
  first_cause[0] = '\0';
  if (write_h5(c, h5tmp, r)) {
    remove(h5tmp);
    return gs_error_set(err, GS_EIO, "cannot write %s%s%s", h5tmp, *first_cause ? ": " : "",
                        first_cause);
  }
  if (write_csv(c, csvtmp, r)) {
    remove(h5tmp);
    remove(csvtmp);
    return gs_error_set(err, GS_EIO, "cannot write %s: %s", csvtmp, strerror(errno));
  }
  if (rename(h5tmp, h5) || rename(csvtmp, csv))
    return gs_error_set(err, GS_EIO, "cannot rename the results into %s: %s", dir, strerror(errno));
  return GS_OK;
}
