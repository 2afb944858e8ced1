/* Result files: DIR/result.h5 and DIR/summary.csv (see include/gransim/output.h).
 *
 * Crash safety.  Everything is written under the partial names and renamed
 * only by gs_output_finish(ok = 1).  Without SWMR, HDF5 writes dirty metadata
 * and chunks to disk in no particular order, so no dataset's length can serve
 * as a commit mark (a killed run was seen to leave /time one row longer than
 * /ledger, or with rows whose data never reached the disk).  Hence a two-phase
 * commit: gs_output_write writes every dataset, flushes, and only then sets the
 * root attribute "ntimes" (complete output times) and flushes again.  Resume
 * trusts "ntimes" and drops any rows beyond it.  The CSV is written after the
 * HDF5 commit and resume regenerates it from /summary, so it always agrees
 * with result.h5. */
#include "gransim/output.h"

#include <errno.h>
#include <hdf5.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef GRANSIM_VERSION
#define GRANSIM_VERSION "unknown"
#endif

#define H5_PARTIAL ".result.h5.partial"
#define CSV_PARTIAL ".summary.csv.partial"
#define NCOL_FIXED 8                             /* time .. d90 */
#define NCOL_MAX (NCOL_FIXED + 2 * GS_MAX_DIM)   /* + mean_<axis>, total_<axis> */
#define RANK_MAX (2 + GS_MAX_DIM)                /* /number: time, comp, axes */
#define CHUNK_ROWS 64                            /* time rows per chunk of the small series */
#define CSV_BLOCK 65536                          /* values per column read when rebuilding the CSV */

struct gs_output {
  char *dir, *h5_tmp, *h5_final, *csv_tmp, *csv_final;
  hid_t file, d_time, d_number, d_ledger;
  hid_t d_sum[NCOL_MAX];
  char colname[NCOL_MAX][GS_NAME_LEN + 8];
  int ncol;
  FILE *csv;
  int created;     /* the partial files are ours to delete if open fails */
  hsize_t ntimes;  /* complete output times in the file */
  size_t ncomp, nstate, nledger;
  double *sbuf;    /* ncol * ncomp: one output time of every summary column */
};

/* ---- paths and directories ------------------------------------------------ */

static char *path_join(const char *dir, const char *name, gs_error *err) {
  size_t n = strlen(dir) + strlen(name) + 2;
  char *p = gs_malloc(n, err);
  if (p) snprintf(p, n, "%s/%s", dir, name);
  return p;
}

/* mkdir -p: create every missing component, then insist on a directory. */
static int mkdir_p(const char *dir, gs_error *err) {
  char *p = gs_malloc(strlen(dir) + 1, err);
  if (!p) return GS_ENOMEM;
  strcpy(p, dir);
  for (char *s = p + 1; *s; s++) {
    if (*s != '/') continue;
    *s = '\0';
    if (mkdir(p, 0777) && errno != EEXIST) break; /* the final check reports it */
    *s = '/';
  }
  int rc = mkdir(dir, 0777) && errno != EEXIST ? errno : 0;
  struct stat st;
  if (!rc && (stat(dir, &st) || !S_ISDIR(st.st_mode))) rc = errno ? errno : ENOTDIR;
  free(p);
  if (rc)
    return gs_error_set(err, GS_EIO, "cannot create output directory %s: %s", dir, strerror(rc));
  return GS_OK;
}

/* ---- HDF5 error reporting ------------------------------------------------- */

/* Innermost HDF5 error description (the one nearest the cause, e.g. the
 * operating-system message), captured before another API call clears it. */
static herr_t h5_walk_first(unsigned n, const H5E_error2_t *e, void *data) {
  if (n == 0 && e->desc) snprintf((char *)data, 512, "%s", e->desc);
  return 0;
}

/* "cannot <what> in <path>: <HDF5 detail>", always GS_EIO. */
static int h5_error(gs_error *err, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int h5_error(gs_error *err, const char *path, const char *fmt, ...) {
  char detail[512] = "", what[512];
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, h5_walk_first, detail);
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  return gs_error_set(err, GS_EIO, "cannot %s in %s%s%s", what, path, *detail ? ": " : "", detail);
}

/* The library reports through gs_error; HDF5's own stack dump on stderr would
 * only duplicate (and precede) our message. */
static void h5_quiet(void) { H5Eset_auto2(H5E_DEFAULT, NULL, NULL); }

/* ---- attributes ----------------------------------------------------------- */

/* Fixed-length UTF-8 string attribute; an existing one is replaced because a
 * fixed-length type cannot change size in place ("running" -> "complete"). */
static herr_t set_str_attr(hid_t loc, const char *name, const char *value) {
  if (H5Aexists(loc, name) > 0 && H5Adelete(loc, name) < 0) return -1;
  hid_t type = H5Tcopy(H5T_C_S1);
  if (type < 0) return -1;
  hid_t space = H5Screate(H5S_SCALAR), attr = H5I_INVALID_HID;
  herr_t st = -1;
  if (space >= 0 && H5Tset_size(type, strlen(value) + 1) >= 0 &&
      H5Tset_strpad(type, H5T_STR_NULLTERM) >= 0 && H5Tset_cset(type, H5T_CSET_UTF8) >= 0 &&
      (attr = H5Acreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT)) >= 0)
    st = H5Awrite(attr, type, value);
  if (attr >= 0 && H5Aclose(attr) < 0) st = -1;
  if (space >= 0) H5Sclose(space);
  H5Tclose(type);
  return st;
}

static herr_t set_i64_attr(hid_t loc, const char *name, long long value) {
  hid_t space = H5Screate(H5S_SCALAR);
  if (space < 0) return -1;
  hid_t attr = H5Acreate2(loc, name, H5T_STD_I64LE, space, H5P_DEFAULT, H5P_DEFAULT);
  herr_t st = attr >= 0 ? H5Awrite(attr, H5T_NATIVE_LLONG, &value) : -1;
  if (attr >= 0 && H5Aclose(attr) < 0) st = -1;
  H5Sclose(space);
  return st;
}

/* Overwrites an existing integer attribute in place (same size, so the object
 * header is rewritten where it is, never moved). */
static herr_t put_i64_attr(hid_t loc, const char *name, long long value) {
  hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
  if (attr < 0) return -1;
  herr_t st = H5Awrite(attr, H5T_NATIVE_LLONG, &value);
  if (H5Aclose(attr) < 0) st = -1;
  return st;
}

static herr_t get_i64_attr(hid_t loc, const char *name, long long *value) {
  hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
  if (attr < 0) return -1;
  herr_t st = H5Aread(attr, H5T_NATIVE_LLONG, value);
  if (H5Aclose(attr) < 0) st = -1;
  return st;
}

/* Reads a string attribute of any fixed length into buf (truncated to n). */
static herr_t get_str_attr(hid_t loc, const char *name, char *buf, size_t n) {
  hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
  if (attr < 0) return -1;
  hid_t ftype = H5Aget_type(attr), mtype = H5I_INVALID_HID;
  herr_t st = -1;
  size_t size = ftype >= 0 ? H5Tget_size(ftype) : 0;
  char *tmp = size && H5Tis_variable_str(ftype) == 0 ? calloc(size + 1, 1) : NULL;
  if (tmp && (mtype = H5Tcopy(ftype)) >= 0 && H5Aread(attr, mtype, tmp) >= 0) {
    snprintf(buf, n, "%s", tmp);
    st = 0;
  }
  if (mtype >= 0) H5Tclose(mtype);
  if (ftype >= 0) H5Tclose(ftype);
  free(tmp);
  if (H5Aclose(attr) < 0) st = -1;
  return st;
}

/* ---- grid, case and summary-column descriptions -------------------------- */

/* Axis names become HDF5 group names and CSV column names. */
static int check_axis_names(const gs_grid *g, gs_error *err) {
  for (int k = 0; k < g->dim; k++) {
    const char *s = g->axis[k].name;
    if (!*s || strchr(s, '/') || strchr(s, ',') || !strcmp(s, "."))
      return gs_error_set(err, GS_EINPUT,
                          "axis name '%s' cannot be used in result files (no '/', ',' or '.')", s);
  }
  return GS_OK;
}

static void join_axis_names(const gs_grid *g, char *buf, size_t n) {
  size_t len = 0;
  buf[0] = '\0';
  for (int k = 0; k < g->dim && len < n; k++)
    len += (size_t)snprintf(buf + len, n - len, "%s%s", k ? "," : "", g->axis[k].name);
}

static void set_columns(gs_output *o, const gs_grid *g) {
  static const char *fixed[NCOL_FIXED] = {"time", "compartment", "M0", "M1",
                                          "M2",   "d10",         "d50", "d90"};
  size_t len = sizeof o->colname[0];
  for (int c = 0; c < NCOL_FIXED; c++) snprintf(o->colname[c], len, "%s", fixed[c]);
  for (int k = 0; k < g->dim; k++) {
    snprintf(o->colname[NCOL_FIXED + k], len, "mean_%s", g->axis[k].name);
    snprintf(o->colname[NCOL_FIXED + g->dim + k], len, "total_%s", g->axis[k].name);
  }
  o->ncol = NCOL_FIXED + 2 * g->dim;
}

static herr_t write_vector(hid_t loc, const char *name, const double *v, size_t n) {
  hsize_t dims = n;
  hid_t space = H5Screate_simple(1, &dims, NULL);
  if (space < 0) return -1;
  hid_t d = H5Dcreate2(loc, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  herr_t st = d >= 0 ? H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) : -1;
  if (d >= 0 && H5Dclose(d) < 0) st = -1;
  H5Sclose(space);
  return st;
}

static int write_axis(gs_output *o, hid_t grid, const gs_axis *ax, gs_error *err) {
  hid_t g = H5Gcreate2(grid, ax->name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) return h5_error(err, o->h5_tmp, "create group /grid/%s", ax->name);
  herr_t st = write_vector(g, "edges", ax->edges, ax->n + 1);
  if (st >= 0) st = write_vector(g, "pivots", ax->pivots, ax->n);
  int rc = st < 0 ? h5_error(err, o->h5_tmp, "write /grid/%s/edges and pivots", ax->name) : GS_OK;
  if (H5Gclose(g) < 0 && !rc) rc = h5_error(err, o->h5_tmp, "close group /grid/%s", ax->name);
  return rc;
}

static int write_grid(gs_output *o, const gs_grid *g, gs_error *err) {
  char names[GS_MAX_DIM * GS_NAME_LEN + 8];
  join_axis_names(g, names, sizeof names);
  hid_t grid = H5Gcreate2(o->file, "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (grid < 0) return h5_error(err, o->h5_tmp, "create group /grid");
  int rc = GS_OK;
  if (set_i64_attr(grid, "dim", g->dim) < 0 || set_i64_attr(grid, "ncomp", (long long)g->ncomp) < 0 ||
      set_i64_attr(grid, "ncells", (long long)g->ncells) < 0 ||
      set_str_attr(grid, "axis_names", names) < 0)
    rc = h5_error(err, o->h5_tmp, "write the attributes of /grid");
  for (int k = 0; k < g->dim && !rc; k++) rc = write_axis(o, grid, &g->axis[k], err);
  if (H5Gclose(grid) < 0 && !rc) rc = h5_error(err, o->h5_tmp, "close group /grid");
  return rc;
}

static int write_case(gs_output *o, const char *text, const char *name, gs_error *err) {
  hid_t c = H5Gcreate2(o->file, "case", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (c < 0) return h5_error(err, o->h5_tmp, "create group /case");
  int rc = GS_OK;
  if (set_str_attr(c, "text", text ? text : "") < 0 || set_str_attr(c, "file", name ? name : "") < 0)
    rc = h5_error(err, o->h5_tmp, "write the attributes text and file of /case");
  if (H5Gclose(c) < 0 && !rc) rc = h5_error(err, o->h5_tmp, "close group /case");
  if (!rc && (set_str_attr(o->file, "gransim_version", GRANSIM_VERSION) < 0 ||
              set_str_attr(o->file, "status", "running") < 0 ||
              set_i64_attr(o->file, "ntimes", 0) < 0))
    rc = h5_error(err, o->h5_tmp, "write the attributes gransim_version, status, ntimes of /");
  return rc;
}

/* ---- time series datasets -------------------------------------------------- */

/* gzip only where this HDF5 build can actually encode it. */
static int deflate_usable(void) {
  unsigned int info = 0;
  return H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0 &&
         H5Zget_filter_info(H5Z_FILTER_DEFLATE, &info) >= 0 &&
         (info & H5Z_FILTER_CONFIG_ENCODE_ENABLED);
}

/* Creates an empty float64 dataset (0, rest...) extendible along time. */
static hid_t create_series(gs_output *o, hid_t loc, const char *name, int rank, const hsize_t *rest,
                           hsize_t chunk_rows, int compress) {
  hsize_t dims[RANK_MAX] = {0}, maxdims[RANK_MAX] = {H5S_UNLIMITED}, chunk[RANK_MAX] = {chunk_rows};
  for (int i = 1; i < rank; i++) dims[i] = maxdims[i] = chunk[i] = rest[i - 1];
  hid_t space = H5Screate_simple(rank, dims, maxdims), d = H5I_INVALID_HID;
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  if (space >= 0 && dcpl >= 0 && H5Pset_chunk(dcpl, rank, chunk) >= 0 &&
      (!compress || H5Pset_deflate(dcpl, 1) >= 0))
    d = H5Dcreate2(loc, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  (void)o;
  return d;
}

static int create_all_series(gs_output *o, const gs_grid *g, gs_error *err) {
  hsize_t rest[RANK_MAX] = {g->ncomp};
  for (int k = 0; k < g->dim; k++) rest[1 + k] = g->axis[k].n;
  o->d_time = create_series(o, o->file, "time", 1, rest, 4 * CHUNK_ROWS, 0);
  if (o->d_time < 0) return h5_error(err, o->h5_tmp, "create dataset /time");
  o->d_number = create_series(o, o->file, "number", 2 + g->dim, rest, 1, deflate_usable());
  if (o->d_number < 0) return h5_error(err, o->h5_tmp, "create dataset /number");
  hsize_t lrest[2] = {g->ncomp, 2 * (hsize_t)g->dim};
  o->d_ledger = create_series(o, o->file, "ledger", 3, lrest, CHUNK_ROWS, 0);
  if (o->d_ledger < 0) return h5_error(err, o->h5_tmp, "create dataset /ledger");
  hid_t sg = H5Gcreate2(o->file, "summary", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (sg < 0) return h5_error(err, o->h5_tmp, "create group /summary");
  for (int c = 0; c < o->ncol; c++) {
    o->d_sum[c] = create_series(o, sg, o->colname[c], 2, rest, CHUNK_ROWS, 0);
    if (o->d_sum[c] < 0) {
      H5Gclose(sg);
      return h5_error(err, o->h5_tmp, "create dataset /summary/%s", o->colname[c]);
    }
  }
  if (H5Gclose(sg) < 0) return h5_error(err, o->h5_tmp, "close group /summary");
  return GS_OK;
}

/* Selects rows [start, start+count) of d in *fs and a matching flat memory
 * space in *ms; also returns the full extent in dims. */
static herr_t select_rows(hid_t d, hsize_t start, hsize_t count, hid_t *fs, hid_t *ms) {
  hsize_t dims[RANK_MAX], off[RANK_MAX] = {start}, cnt[RANK_MAX];
  *ms = H5I_INVALID_HID;
  *fs = H5Dget_space(d);
  int rank = *fs >= 0 ? H5Sget_simple_extent_ndims(*fs) : -1;
  if (rank < 1 || rank > RANK_MAX || H5Sget_simple_extent_dims(*fs, dims, NULL) < 0) return -1;
  if (start + count > dims[0]) return -1;
  hsize_t n = count;
  cnt[0] = count;
  for (int i = 1; i < rank; i++) {
    off[i] = 0;
    cnt[i] = dims[i];
    n *= dims[i];
  }
  if (H5Sselect_hyperslab(*fs, H5S_SELECT_SET, off, NULL, cnt, NULL) < 0) return -1;
  *ms = H5Screate_simple(1, &n, NULL);
  return *ms >= 0 ? 0 : -1;
}

static void close_spaces(hid_t fs, hid_t ms) {
  if (fs >= 0) H5Sclose(fs);
  if (ms >= 0) H5Sclose(ms);
}

/* Sets the time extent of d to n rows (grows or drops rows). */
static herr_t set_rows(hid_t d, hsize_t n) {
  hsize_t dims[RANK_MAX];
  hid_t fs = H5Dget_space(d);
  int rank = fs >= 0 ? H5Sget_simple_extent_ndims(fs) : -1;
  herr_t st = rank >= 1 && rank <= RANK_MAX ? H5Sget_simple_extent_dims(fs, dims, NULL) : -1;
  if (fs >= 0) H5Sclose(fs);
  if (st < 0) return -1;
  dims[0] = n;
  return H5Dset_extent(d, dims);
}

/* Writes row `row` of d, making it exactly row+1 long: a row torn by an
 * earlier failed write is simply overwritten. */
static int write_row(gs_output *o, hid_t d, const char *name, hsize_t row, const double *buf,
                     gs_error *err) {
  hid_t fs = H5I_INVALID_HID, ms = H5I_INVALID_HID;
  herr_t st = set_rows(d, row + 1);
  if (st >= 0) st = select_rows(d, row, 1, &fs, &ms);
  if (st >= 0) st = H5Dwrite(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, buf);
  close_spaces(fs, ms);
  return st < 0 ? h5_error(err, o->h5_tmp, "write dataset %s", name) : GS_OK;
}

static int read_rows(gs_output *o, hid_t d, const char *name, hsize_t start, hsize_t count,
                     double *buf, gs_error *err) {
  hid_t fs = H5I_INVALID_HID, ms = H5I_INVALID_HID;
  herr_t st = select_rows(d, start, count, &fs, &ms);
  if (st >= 0) st = H5Dread(d, H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, buf);
  close_spaces(fs, ms);
  return st < 0 ? h5_error(err, o->h5_tmp, "read dataset %s", name) : GS_OK;
}

/* ---- summary.csv ------------------------------------------------------------ */

static int csv_error(gs_output *o, gs_error *err) {
  return gs_error_set(err, GS_EIO, "cannot write %s: %s", o->csv_tmp, strerror(errno));
}

static int csv_header(gs_output *o, gs_error *err) {
  for (int c = 0; c < o->ncol; c++)
    if (fprintf(o->csv, "%s%s", c ? "," : "", o->colname[c]) < 0) return csv_error(o, err);
  if (fputc('\n', o->csv) == EOF) return csv_error(o, err);
  return GS_OK;
}

/* One row per compartment from sbuf laid out as [column][comp] with
 * column stride `stride` (ncomp for one time, more for a block). */
static int csv_rows(gs_output *o, const double *sbuf, size_t stride, size_t first, gs_error *err) {
  for (size_t j = 0; j < o->ncomp; j++) {
    for (int c = 0; c < o->ncol; c++)
      if (fprintf(o->csv, "%s%.10g", c ? "," : "", sbuf[(size_t)c * stride + first + j]) < 0)
        return csv_error(o, err);
    if (fputc('\n', o->csv) == EOF) return csv_error(o, err);
  }
  return GS_OK;
}

static int csv_flush(gs_output *o, gs_error *err) {
  return fflush(o->csv) ? csv_error(o, err) : GS_OK;
}

/* ---- construction and teardown --------------------------------------------- */

static void output_free(gs_output *o) {
  if (!o) return;
  free(o->dir);
  free(o->h5_tmp);
  free(o->h5_final);
  free(o->csv_tmp);
  free(o->csv_final);
  free(o->sbuf);
  free(o);
}

static gs_output *output_alloc(const char *dir, const gs_model *m, gs_error *err) {
  const gs_grid *g = &m->grid;
  if (check_axis_names(g, err)) return NULL;
  gs_output *o = gs_calloc(1, sizeof *o, err);
  if (!o) return NULL;
  o->file = o->d_time = o->d_number = o->d_ledger = H5I_INVALID_HID;
  for (int c = 0; c < NCOL_MAX; c++) o->d_sum[c] = H5I_INVALID_HID;
  o->ncomp = g->ncomp;
  o->nstate = g->ncomp * g->ncells;
  o->nledger = g->ncomp * 2 * (size_t)g->dim;
  set_columns(o, g);
  o->dir = gs_malloc(strlen(dir) + 1, err);
  if (o->dir) strcpy(o->dir, dir);
  o->h5_tmp = path_join(dir, H5_PARTIAL, err);
  o->h5_final = path_join(dir, "result.h5", err);
  o->csv_tmp = path_join(dir, CSV_PARTIAL, err);
  o->csv_final = path_join(dir, "summary.csv", err);
  o->sbuf = gs_malloc((size_t)o->ncol * g->ncomp * sizeof(double), err);
  if (!o->dir || !o->h5_tmp || !o->h5_final || !o->csv_tmp || !o->csv_final || !o->sbuf) {
    output_free(o);
    return NULL;
  }
  return o;
}

static herr_t close_id(hid_t *id, herr_t (*fn)(hid_t)) {
  herr_t st = *id >= 0 ? fn(*id) : 0;
  *id = H5I_INVALID_HID;
  return st;
}

/* Closes every handle; reports the first failure. */
static int output_close(gs_output *o, gs_error *err) {
  herr_t st = close_id(&o->d_time, H5Dclose);
  if (close_id(&o->d_number, H5Dclose) < 0) st = -1;
  if (close_id(&o->d_ledger, H5Dclose) < 0) st = -1;
  for (int c = 0; c < NCOL_MAX; c++)
    if (close_id(&o->d_sum[c], H5Dclose) < 0) st = -1;
  int rc = GS_OK;
  if (st < 0) rc = h5_error(err, o->h5_tmp, "close the datasets");
  if (close_id(&o->file, H5Fclose) < 0 && !rc) rc = h5_error(err, o->h5_tmp, "close the file");
  if (o->csv && fclose(o->csv) && !rc) rc = csv_error(o, err);
  o->csv = NULL;
  return rc;
}

/* HDF5 1.8 object formats: readable by every current tool, and they let the
 * case text attribute exceed 64 KiB (dense attribute storage). */
static hid_t make_fapl(void) {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
  if (fapl >= 0 && H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18) < 0) {
    H5Pclose(fapl);
    return H5I_INVALID_HID;
  }
  return fapl;
}

static int flush_h5(gs_output *o, gs_error *err) {
  return H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0 ? h5_error(err, o->h5_tmp, "flush the file")
                                                  : GS_OK;
}

/* Abandons a half-built output: closes what is open and removes the partials
 * it created (never those of another run that made H5Fcreate fail). */
static void output_abort(gs_output *o) {
  output_close(o, NULL);
  if (o->created) {
    unlink(o->h5_tmp);
    unlink(o->csv_tmp);
  }
  output_free(o);
}

/* ---- public API --------------------------------------------------------------- */

static int open_files(gs_output *o, gs_error *err) {
  hid_t fapl = make_fapl();
  if (fapl < 0) return h5_error(err, o->h5_tmp, "set up file access properties");
  o->file = H5Fcreate(o->h5_tmp, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  H5Pclose(fapl);
  if (o->file < 0) return h5_error(err, o->h5_tmp, "create the file");
  o->created = 1;
  o->csv = fopen(o->csv_tmp, "w");
  if (!o->csv) return gs_error_set(err, GS_EIO, "cannot create %s: %s", o->csv_tmp, strerror(errno));
  return GS_OK;
}

gs_output *gs_output_open(const char *dir, const gs_model *m, const char *case_text,
                          const char *case_name, gs_error *err) {
  h5_quiet();
  if (mkdir_p(dir, err)) return NULL;
  gs_output *o = output_alloc(dir, m, err);
  if (!o) return NULL;
  int rc = open_files(o, err);
  if (!rc) rc = write_grid(o, &m->grid, err);
  if (!rc) rc = write_case(o, case_text, case_name, err);
  if (!rc) rc = create_all_series(o, &m->grid, err);
  if (!rc) rc = csv_header(o, err);
  if (!rc) rc = csv_flush(o, err);
  if (!rc) rc = flush_h5(o, err);
  if (rc) {
    output_abort(o);
    return NULL;
  }
  return o;
}

/* Fills o->sbuf ([column][comp]) for output time t. */
static void summarize_all(gs_output *o, const gs_model *m, double t, const double *y) {
  size_t nc = o->ncomp;
  int dim = m->grid.dim;
  for (size_t j = 0; j < nc; j++) {
    gs_summary s;
    memset(&s, 0, sizeof s);
    gs_summarize(m, y, j, &s);
    double fixed[NCOL_FIXED] = {t, (double)j, s.m0, s.m1, s.m2, s.d10, s.d50, s.d90};
    for (int c = 0; c < NCOL_FIXED; c++) o->sbuf[(size_t)c * nc + j] = fixed[c];
    for (int k = 0; k < dim; k++) {
      o->sbuf[(size_t)(NCOL_FIXED + k) * nc + j] = s.mean[k];
      o->sbuf[(size_t)(NCOL_FIXED + dim + k) * nc + j] = s.total[k];
    }
  }
}

static int write_h5_time(gs_output *o, double t, const double *y, const double *ledger,
                         gs_error *err) {
  hsize_t row = o->ntimes;
  int rc = write_row(o, o->d_number, "/number", row, y, err);
  if (!rc) rc = write_row(o, o->d_ledger, "/ledger", row, ledger, err);
  for (int c = 0; c < o->ncol && !rc; c++) {
    char name[64];
    snprintf(name, sizeof name, "/summary/%s", o->colname[c]);
    rc = write_row(o, o->d_sum[c], name, row, o->sbuf + (size_t)c * o->ncomp, err);
  }
  if (!rc) rc = write_row(o, o->d_time, "/time", row, &t, err);
  if (!rc) rc = flush_h5(o, err);
  /* commit only once the rows are on disk (see the top of the file) */
  if (!rc && put_i64_attr(o->file, "ntimes", (long long)row + 1) < 0)
    rc = h5_error(err, o->h5_tmp, "write the attribute ntimes of /");
  if (!rc) rc = flush_h5(o, err);
  return rc;
}

int gs_output_write(gs_output *o, const gs_model *m, double t, const double *y,
                    const double *ledger, gs_error *err) {
  if (m->nstate != o->nstate || m->grid.ncomp != o->ncomp)
    return gs_error_set(err, GS_EINPUT, "output to %s: model does not match the open result file",
                        o->dir);
  summarize_all(o, m, t, y);
  int rc = write_h5_time(o, t, y, ledger, err);
  if (rc) return rc;
  o->ntimes++;
  rc = csv_rows(o, o->sbuf, o->ncomp, 0, err);
  return rc ? rc : csv_flush(o, err);
}

int gs_output_finish(gs_output *o, int ok, gs_error *err) {
  if (!o) return GS_OK;
  int rc = GS_OK;
  if (ok && set_str_attr(o->file, "status", "complete") < 0)
    rc = h5_error(err, o->h5_tmp, "write the attribute status of /");
  int crc = output_close(o, rc ? NULL : err);
  if (!rc) rc = crc;
  if (ok && !rc && rename(o->h5_tmp, o->h5_final))
    rc = gs_error_set(err, GS_EIO, "cannot rename %s to %s: %s", o->h5_tmp, o->h5_final,
                      strerror(errno));
  if (ok && !rc && rename(o->csv_tmp, o->csv_final))
    rc = gs_error_set(err, GS_EIO, "cannot rename %s to %s: %s", o->csv_tmp, o->csv_final,
                      strerror(errno));
  if (ok && rc) /* keep the partial files: the data may still be recoverable */
    gs_error_prefix(err, "result files left under their partial names in %s: ", o->dir);
  if (!ok) {
    if (unlink(o->h5_tmp) && errno != ENOENT)
      rc = gs_error_set(err, GS_EIO, "cannot remove %s: %s", o->h5_tmp, strerror(errno));
    if (unlink(o->csv_tmp) && errno != ENOENT && !rc)
      rc = gs_error_set(err, GS_EIO, "cannot remove %s: %s", o->csv_tmp, strerror(errno));
  }
  output_free(o);
  return rc;
}

/* ---- resume -------------------------------------------------------------------- */

static int grid_mismatch(gs_output *o, gs_error *err, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int grid_mismatch(gs_output *o, gs_error *err, const char *fmt, ...) {
  char why[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(why, sizeof why, fmt, ap);
  va_end(ap);
  return gs_error_set(err, GS_EINPUT, "cannot resume: %s was written for a different grid (%s)",
                      o->h5_tmp, why);
}

/* Edges are computed the same way on every run, so they agree to round-off;
 * the tolerance only absorbs libm differences between builds. */
static int same_value(double a, double b) {
  return fabs(a - b) <= 1e-12 * (fabs(a) > fabs(b) ? fabs(a) : fabs(b));
}

static herr_t read_vector(hid_t loc, const char *name, double *v, size_t n) {
  hid_t d = H5Dopen2(loc, name, H5P_DEFAULT);
  if (d < 0) return -1;
  hid_t fs = H5Dget_space(d);
  hssize_t np = fs >= 0 ? H5Sget_simple_extent_npoints(fs) : -1;
  herr_t st = np == (hssize_t)n ? H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) : -1;
  if (fs >= 0) H5Sclose(fs);
  if (H5Dclose(d) < 0) st = -1;
  return st;
}

static int check_axis(gs_output *o, hid_t grid, const gs_axis *ax, gs_error *err) {
  char dname[GS_NAME_LEN + 8];
  snprintf(dname, sizeof dname, "%s/edges", ax->name);
  if (H5Lexists(grid, ax->name, H5P_DEFAULT) <= 0)
    return grid_mismatch(o, err, "no axis '%s' in the file", ax->name);
  hid_t d = H5Dopen2(grid, dname, H5P_DEFAULT);
  hid_t fs = d >= 0 ? H5Dget_space(d) : H5I_INVALID_HID;
  hssize_t ne = fs >= 0 ? H5Sget_simple_extent_npoints(fs) : -1;
  if (fs >= 0) H5Sclose(fs);
  if (d >= 0) H5Dclose(d);
  if (ne < 2) return h5_error(err, o->h5_tmp, "read dataset /grid/%s", dname);
  if ((size_t)ne - 1 != ax->n)
    return grid_mismatch(o, err, "axis '%s' has %lld cells, case has %zu", ax->name,
                         (long long)ne - 1, ax->n);
  double *e = malloc((size_t)ne * sizeof(double));
  if (!e) return gs_error_set(err, GS_ENOMEM, "out of memory reading /grid/%s", dname);
  int rc = read_vector(grid, dname, e, (size_t)ne) < 0
               ? h5_error(err, o->h5_tmp, "read dataset /grid/%s", dname)
               : GS_OK;
  for (size_t i = 0; i <= ax->n && !rc; i++)
    if (!same_value(e[i], ax->edges[i]))
      rc = grid_mismatch(o, err, "axis '%s' edge %zu is %.10g, case has %.10g", ax->name, i, e[i],
                         ax->edges[i]);
  free(e);
  return rc;
}

static int check_grid_attrs(gs_output *o, hid_t grid, const gs_grid *g, gs_error *err) {
  long long dim, ncomp, ncells;
  char names[GS_MAX_DIM * GS_NAME_LEN + 8], want[GS_MAX_DIM * GS_NAME_LEN + 8];
  if (get_i64_attr(grid, "dim", &dim) < 0 || get_i64_attr(grid, "ncomp", &ncomp) < 0 ||
      get_i64_attr(grid, "ncells", &ncells) < 0 ||
      get_str_attr(grid, "axis_names", names, sizeof names) < 0)
    return h5_error(err, o->h5_tmp, "read the attributes of /grid");
  join_axis_names(g, want, sizeof want);
  if (dim != g->dim) return grid_mismatch(o, err, "%lld axes, case has %d", dim, g->dim);
  if (strcmp(names, want))
    return grid_mismatch(o, err, "axes '%s', case has '%s'", names, want);
  if (ncomp != (long long)g->ncomp)
    return grid_mismatch(o, err, "%lld compartments, case has %zu", ncomp, g->ncomp);
  for (int k = 0; k < g->dim; k++) {
    int rc = check_axis(o, grid, &g->axis[k], err);
    if (rc) return rc;
  }
  if (ncells != (long long)g->ncells) /* implied by the axes; a damaged file otherwise */
    return grid_mismatch(o, err, "%lld cells, case has %zu", ncells, g->ncells);
  return GS_OK;
}

static int check_grid(gs_output *o, const gs_grid *g, gs_error *err) {
  hid_t grid = H5Gopen2(o->file, "grid", H5P_DEFAULT);
  if (grid < 0) return h5_error(err, o->h5_tmp, "open group /grid");
  int rc = check_grid_attrs(o, grid, g, err);
  H5Gclose(grid);
  return rc;
}

/* Opens an existing series and checks its shape past the time axis, so a
 * damaged file cannot make us read into too small a buffer. */
static hid_t open_series(gs_output *o, const char *name, int rank, const hsize_t *rest,
                         hsize_t *rows, gs_error *err) {
  hsize_t dims[RANK_MAX];
  hid_t d = H5Dopen2(o->file, name, H5P_DEFAULT);
  hid_t fs = d >= 0 ? H5Dget_space(d) : H5I_INVALID_HID;
  int ok = fs >= 0 && H5Sget_simple_extent_ndims(fs) == rank &&
           H5Sget_simple_extent_dims(fs, dims, NULL) >= 0;
  for (int i = 1; ok && i < rank; i++) ok = dims[i] == rest[i - 1];
  if (fs >= 0) H5Sclose(fs);
  if (!ok) {
    if (d >= 0) H5Dclose(d);
    h5_error(err, o->h5_tmp, "open dataset %s with the expected shape", name);
    return H5I_INVALID_HID;
  }
  *rows = dims[0];
  return d;
}

/* Opens all series; each must hold at least the committed "ntimes" rows, and
 * rows beyond it (a write the kill interrupted) are dropped. */
static int open_all_series(gs_output *o, const gs_grid *g, gs_error *err) {
  hsize_t rest[RANK_MAX] = {g->ncomp}, lrest[2] = {g->ncomp, 2 * (hsize_t)g->dim}, rows;
  for (int k = 0; k < g->dim; k++) rest[1 + k] = g->axis[k].n;
  hid_t *ds[NCOL_MAX + 3] = {&o->d_time, &o->d_number, &o->d_ledger};
  char names[NCOL_MAX + 3][64] = {"/time", "/number", "/ledger"};
  int ranks[NCOL_MAX + 3] = {1, 2 + g->dim, 3};
  const hsize_t *rests[NCOL_MAX + 3] = {rest, rest, lrest};
  for (int c = 0; c < o->ncol; c++) {
    ds[3 + c] = &o->d_sum[c];
    snprintf(names[3 + c], sizeof names[0], "/summary/%s", o->colname[c]);
    ranks[3 + c] = 2;
    rests[3 + c] = rest;
  }
  for (int i = 0; i < o->ncol + 3; i++) {
    if ((*ds[i] = open_series(o, names[i], ranks[i], rests[i], &rows, err)) < 0) return GS_EIO;
    if (rows < o->ntimes)
      return gs_error_set(err, GS_EIO,
                          "cannot resume from %s: %s has %llu rows but %llu were committed",
                          o->h5_tmp, names[i], (unsigned long long)rows,
                          (unsigned long long)o->ntimes);
    if (rows > o->ntimes && set_rows(*ds[i], o->ntimes) < 0)
      return h5_error(err, o->h5_tmp, "drop the uncommitted rows of %s", names[i]);
  }
  return GS_OK;
}

static int read_committed(gs_output *o, gs_error *err) {
  long long n;
  if (get_i64_attr(o->file, "ntimes", &n) < 0 || n < 0)
    return h5_error(err, o->h5_tmp, "read the attribute ntimes of /");
  o->ntimes = (hsize_t)n;
  return GS_OK;
}

static int read_last(gs_output *o, double *t, double *y, double *ledger, gs_error *err) {
  hsize_t last = o->ntimes - 1;
  int rc = read_rows(o, o->d_time, "/time", last, 1, t, err);
  if (!rc) rc = read_rows(o, o->d_number, "/number", last, 1, y, err);
  if (!rc) rc = read_rows(o, o->d_ledger, "/ledger", last, 1, ledger, err);
  return rc;
}

/* Rewrites the CSV from /summary: whatever the kill left in it (missing or
 * extra rows, a half line), it then matches result.h5 exactly. */
static int rebuild_csv(gs_output *o, gs_error *err) {
  o->csv = fopen(o->csv_tmp, "w");
  if (!o->csv) return gs_error_set(err, GS_EIO, "cannot rewrite %s: %s", o->csv_tmp, strerror(errno));
  int rc = csv_header(o, err);
  hsize_t block = CSV_BLOCK / o->ncomp ? CSV_BLOCK / o->ncomp : 1;
  double *buf = rc ? NULL : gs_malloc((size_t)o->ncol * block * o->ncomp * sizeof(double), err);
  if (!rc && !buf) rc = GS_ENOMEM;
  for (hsize_t r0 = 0; r0 < o->ntimes && !rc; r0 += block) {
    hsize_t n = o->ntimes - r0 < block ? o->ntimes - r0 : block;
    size_t stride = (size_t)n * o->ncomp;
    for (int c = 0; c < o->ncol && !rc; c++) {
      char name[64];
      snprintf(name, sizeof name, "/summary/%s", o->colname[c]);
      rc = read_rows(o, o->d_sum[c], name, r0, n, buf + (size_t)c * stride, err);
    }
    for (hsize_t r = 0; r < n && !rc; r++) rc = csv_rows(o, buf, stride, (size_t)r * o->ncomp, err);
  }
  free(buf);
  return rc ? rc : csv_flush(o, err);
}

static int reopen_files(gs_output *o, gs_error *err) {
  if (access(o->h5_tmp, F_OK))
    return gs_error_set(err, GS_EIO, "nothing to resume in %s (no %s)", o->dir, H5_PARTIAL);
  hid_t fapl = make_fapl();
  if (fapl < 0) return h5_error(err, o->h5_tmp, "set up file access properties");
  o->file = H5Fopen(o->h5_tmp, H5F_ACC_RDWR, fapl);
  H5Pclose(fapl);
  if (o->file < 0) return h5_error(err, o->h5_tmp, "open the file for resuming");
  return GS_OK;
}

gs_output *gs_output_resume(const char *dir, const gs_model *m, double *t, double *y,
                            double *ledger, gs_error *err) {
  h5_quiet();
  gs_output *o = output_alloc(dir, m, err);
  if (!o) return NULL;
  int rc = reopen_files(o, err);
  if (!rc) rc = check_grid(o, &m->grid, err);
  if (!rc) rc = read_committed(o, err);
  if (!rc) rc = open_all_series(o, &m->grid, err);
  if (!rc && o->ntimes == 0)
    rc = gs_error_set(err, GS_EIO, "nothing to resume in %s (%s holds no output time yet)", dir,
                      H5_PARTIAL);
  if (!rc) rc = read_last(o, t, y, ledger, err);
  if (!rc) rc = flush_h5(o, err);
  if (!rc) rc = rebuild_csv(o, err);
  if (rc) {
    /* keep the partial files: they are the interrupted run's only copy */
    output_close(o, NULL);
    output_free(o);
    return NULL;
  }
  return o;
}
