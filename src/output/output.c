/* Result files: DIR/result.h5 and DIR/summary.csv (see include/gransim/output.h).
 *
 * Crash safety.  Everything is written under the partial names and renamed
 * only by gs_output_finish(ok = 1); the skeleton (grid, case, empty datasets)
 * is built under DIR/.result.h5.new and renamed to .result.h5.partial once
 * complete.  What a resume trusts is not the HDF5 file: HDF5 without SWMR
 * rewrites its metadata in place and in no particular order, and a kill in
 * the middle of a flush can leave committed rows unreadable.  Every output
 * time also goes to the journal DIR/.result.journal (journal.h: append-only,
 * checksummed records, a commit record per commit), and gs_output_resume
 * builds fresh partial files from the journal's committed rows, written
 * again through the ordinary path.  The journal is removed only after both
 * final renames, so a kill while publishing leaves it, and a resume
 * publishes again.
 *
 * Commits still write every dataset, flush, raise the root attribute
 * "ntimes" and flush again, so that the partial file can be read while the
 * run goes on; then the journal's commit record is appended.
 *
 * Checkpoints.  Output times are committed together (two flushes for several
 * rows) once `checkpoint` seconds of
 * wall time have passed since the last commit, when the buffer is full
 * (PENDING_BYTES) and at the end: per-time writes and flushes cost more than
 * the integration of small cases such as the CoriMix example.  A killed run
 * loses at most the last interval,
 * which --resume recomputes.  checkpoint = 0 commits every output time.
 * The small series are kept in memory until the commit (one write of several
 * rows each); the large ones (/number, /carried), chunked by up to 64 KiB of
 * output times (a row a chunk when larger), are written chunk by chunk as
 * each fills (partly filled at a commit) and become part of the file only
 * when "ntimes" covers them.  The metadata cache does not evict (h5_create),
 * so the chunk index and extents reach the disk only at the flushes of a
 * commit. */
#include "gransim/output.h"

#include <errno.h>
#include <hdf5.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "gransim/distribution.h"
#include "gransim/version.h"
#include "output/chunk_writer.h"
#include "output/csv_number.h"
#include "output/units.h"
#include "output/h5_setup.h"
#include "output/journal.h"
#include "output/journal_header.h"


#define H5_PARTIAL ".result.h5.partial"
#define H5_NEW ".result.h5.new"
#define CSV_PARTIAL ".summary.csv.partial"
#define JOURNAL ".result.journal"
#define JOURNAL_NEW ".result.journal.new"
#define NCOL_FIXED 8                           /* time .. d90 */
#define NCOL_MECH 16                           /* the mechanisms' columns (gs_mech_type.columns), at most */
#define NCOL_MAX (NCOL_FIXED + 2 * GS_MAX_VOL + 2 + NCOL_MECH) /* + mean_<coordinate>, total_<coordinate>, porosity, liquid_content, mechanisms' */
#define NSERIES_MAX (4 + NCOL_MAX)             /* /time, /number, /ledger, /summary/<col>, /carried */
#define RANK_MAX (3 + GS_MAX_DIM)              /* /carried: time, comp, quantity, axes */
#define CHUNK_ROWS 64                          /* time rows per chunk of the small series */
#define PENDING_BYTES ((size_t)64 << 20)       /* output times held before a commit, at most */
#define PENDING_FIRST_BYTES ((size_t)64 << 10) /* the pending block's first size */
#define DEFLATE_LEVEL 1                        /* zlib level of the large series */

enum { S_TIME, S_NUMBER, S_LEDGER, S_SUMMARY };

struct gs_output {
  char *dir, *h5_new, *h5_tmp, *h5_final, *csv_tmp, *csv_final, *journal_path, *journal_new;
  gs_journal *journal; /* every output time, what a resume reads (journal.h) */
  size_t nresume;      /* integrator state values per output time, in the journal only */
  const char *h5_path; /* the name the open HDF5 file has now, for messages */
  int published;       /* the open file is .result.h5.partial (no longer .new) */
  hid_t file;
  int nseries, ncol, nmech_col; /* nmech_col: the mechanisms' columns, the last ones */
  int npore_col;                /* 2 (porosity, liquid_content) when there are liquid or gas, else 0 */
  const char *unit[NCOL_MAX];   /* of each summary column (NULL: an index, no unit) */
  hid_t ds[NSERIES_MAX];
  char sname[NSERIES_MAX][GS_NAME_LEN + 24]; /* "/summary/total_<axis>" */
  char axis_names[GS_MAX_DIM * GS_NAME_LEN + 8]; /* "a,b": the dimensions of /number */
  int rank[NSERIES_MAX];
  hsize_t rest[NSERIES_MAX][RANK_MAX - 1]; /* dimensions after time */
  size_t rowlen[NSERIES_MAX];              /* values per time row */
  /* the large series, written chunk by chunk (chunk_writer.h), and whether
   * their chunks are deflated */
  int direct[NSERIES_MAX], deflated[NSERIES_MAX];
  int indexed[NSERIES_MAX]; /* small series: written once (index_small_series) */
  /* large series whose rows are under BIG_CHUNK_BYTES: the chunk being
   * filled, several output times long (hold_row) */
  double *held[NSERIES_MAX];
  gs_chunk_writer *chunks;
  FILE *csv;
  hsize_t ntimes; /* committed output times */
  size_t ncomp, nstate, nnum;
  int s_carried; /* index of the /carried series, or -1 */
  double *sbuf; /* ncol * ncomp: one output time of every summary column */
  /* output times written but not yet committed (see Checkpoints above) */
  double *pending[NSERIES_MAX]; /* cap rows of each series, in one block: */
  double *pending_block;        /* one block: one mapping to free, not one per series */
  size_t cap, cap_max, npending; /* cap grows to cap_max (PENDING_BYTES) as rows come */
  int next_part; /* of the output time being written in parts (0: none begun) */
  double checkpoint, last_commit; /* seconds of wall time */
};

static const char *colname(const gs_output *o, int c) {
  return o->sname[S_SUMMARY + c] + strlen("/summary/");
}

/* ---- paths and directories ------------------------------------------------ */

static char *path_join(const char *dir, const char *name, gs_error *err) {
  size_t n = strlen(dir) + strlen(name) + 2;
  char *p = gs_malloc(n, err);
  if (p) snprintf(p, n, "%s%s%s", dir, *name ? "/" : "", name);
  return p;
}

/* mkdir -p: create every missing component, then insist on a directory. */
int gs_output_mkdir_p(const char *dir, gs_error *err) {
  char *p = path_join(dir, "", err);
  if (!p) return GS_ENOMEM;
  for (char *s = p + 1; *s; s++) {
    if (*s != '/') continue;
    *s = '\0';
    if (mkdir(p, 0777) && errno != EEXIST) break; /* the final check reports it */
    *s = '/';
  }
  free(p);
  int rc = mkdir(dir, 0777) && errno != EEXIST ? errno : 0;
  struct stat st;
  if (!rc && stat(dir, &st)) rc = errno;
  if (!rc && !S_ISDIR(st.st_mode)) rc = ENOTDIR;
  if (rc)
    return gs_error_set(err, GS_EIO, "cannot create output directory %s: %s", dir, strerror(rc));
  return GS_OK;
}

/* ---- HDF5 error reporting ------------------------------------------------- */

/* "cannot <what> in <path>: <HDF5 detail>", always GS_EIO. */
static int h5_error(gs_error *err, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int h5_error(gs_error *err, const char *path, const char *fmt, ...) {
  char detail[512], what[512];
  gs_h5_cause(detail, sizeof detail);
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(what, sizeof what, fmt, ap);
  va_end(ap);
  return gs_error_set(err, GS_EIO, "cannot %s in %s%s%s", what, path, *detail ? ": " : "", detail);
}

/* ---- attributes ----------------------------------------------------------- */

/* Strings are fixed-length UTF-8, an existing one replaced because a
 * fixed-length type cannot change size in place ("running" -> "complete");
 * integers 64-bit: gs_h5_str_attr, gs_h5_i64_attr (units.c), shared with the
 * stochastic solver's writer. */

/* Overwrites an existing integer attribute in place (same size, so the object
 * header is rewritten where it is, never moved). */
static herr_t put_i64_attr(hid_t loc, const char *name, long long value) {
  hid_t attr = H5Aopen(loc, name, H5P_DEFAULT);
  if (attr < 0) return -1;
  herr_t st = H5Awrite(attr, H5T_NATIVE_LLONG, &value);
  if (H5Aclose(attr) < 0) st = -1;
  return st;
}

/* ---- description of the datasets ------------------------------------------- */

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

static void set_series(gs_output *o, int i, const char *name, int rank, const hsize_t *rest) {
  snprintf(o->sname[i], sizeof o->sname[i], "%s", name);
  o->rank[i] = rank;
  o->rowlen[i] = 1;
  for (int r = 0; r + 1 < rank; r++) {
    o->rest[i][r] = rest[r];
    o->rowlen[i] *= (size_t)rest[r];
  }
}

/* Names and shapes of every time series, summary columns in CSV order. */
static void describe_series(gs_output *o, const gs_model *m) {
  static const char *fixed[NCOL_FIXED] = {"time", "compartment", "M0", "M1",
                                          "M2",   "d10",         "d50", "d90"};
  const gs_grid *g = &m->grid;
  const int nvol = m->nvol;
  hsize_t rest[RANK_MAX - 1] = {g->ncomp}, lrest[2] = {g->ncomp, 2 * (hsize_t)nvol};
  for (int k = 0; k < g->dim; k++) rest[1 + k] = g->axis[k].n;
  join_axis_names(g, o->axis_names, sizeof o->axis_names);
  set_series(o, S_TIME, "/time", 1, rest);
  set_series(o, S_NUMBER, "/number", 2 + g->dim, rest);
  set_series(o, S_LEDGER, "/ledger", 3, lrest);
  char name[sizeof o->sname[0]];
  int liquid, gas;
  o->npore_col = gs_model_pore_coordinates(m, &liquid, &gas) ? 2 : 0;
  o->nmech_col = gs_model_ncolumns(m);
  const int mech0 = NCOL_FIXED + 2 * nvol + o->npore_col; /* the first mechanism column */
  o->ncol = mech0 + o->nmech_col;
  for (int c = 0; c < o->ncol; c++) {
    if (c < NCOL_FIXED) snprintf(name, sizeof name, "/summary/%s", fixed[c]);
    else if (c < NCOL_FIXED + nvol)
      snprintf(name, sizeof name, "/summary/mean_%s", gs_model_vol_name(m, c - NCOL_FIXED));
    else if (c < NCOL_FIXED + 2 * nvol)
      snprintf(name, sizeof name, "/summary/total_%s", gs_model_vol_name(m, c - NCOL_FIXED - nvol));
    else if (c < mech0)
      snprintf(name, sizeof name, "/summary/%s", c == NCOL_FIXED + 2 * nvol ? "porosity" : "liquid_content");
    else snprintf(name, sizeof name, "/summary/%s", gs_model_column(m, c - mech0)->name);
    set_series(o, S_SUMMARY + c, name, 2, rest);
    o->unit[c] = c < mech0 ? gs_summary_unit(colname(o, c)) : gs_model_column(m, c - mech0)->unit;
  }
  o->nseries = S_SUMMARY + o->ncol;
  o->s_carried = -1;
  if (m->ncarried) { /* totals carried per cell: (time, comp, quantity, axes) */
    hsize_t crest[RANK_MAX - 1] = {g->ncomp, (hsize_t)m->ncarried};
    for (int k = 0; k < g->dim; k++) crest[2 + k] = g->axis[k].n;
    o->s_carried = o->nseries++;
    set_series(o, o->s_carried, "/carried", 3 + g->dim, crest);
  }
}

/* ---- writing the skeleton: grid, case, empty series ----------------------- */

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
  if (g < 0) return h5_error(err, o->h5_path, "create group /grid/%s", ax->name);
  herr_t st = write_vector(g, "edges", ax->edges, ax->n + 1);
  if (st >= 0) st = write_vector(g, "pivots", ax->pivots, ax->n);
  if (st >= 0) st = gs_h5_describe(g, "edges", "m^3", "edge");
  if (st >= 0) st = gs_h5_describe(g, "pivots", "m^3", "cell");
  int rc = st < 0 ? h5_error(err, o->h5_path, "write /grid/%s/edges and pivots", ax->name) : GS_OK;
  if (H5Gclose(g) < 0 && !rc) rc = h5_error(err, o->h5_path, "close group /grid/%s", ax->name);
  return rc;
}

static int write_grid(gs_output *o, const gs_grid *g, gs_error *err) {
  char names[GS_MAX_DIM * GS_NAME_LEN + 8];
  join_axis_names(g, names, sizeof names);
  hid_t grid = H5Gcreate2(o->file, "grid", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (grid < 0) return h5_error(err, o->h5_path, "create group /grid");
  int rc = GS_OK;
  if (gs_h5_i64_attr(grid, "dim", g->dim) < 0 ||
      gs_h5_i64_attr(grid, "ncomp", (long long)g->ncomp) < 0 ||
      gs_h5_i64_attr(grid, "ncells", (long long)g->ncells) < 0 ||
      gs_h5_str_attr(grid, "axis_names", names) < 0)
    rc = h5_error(err, o->h5_path, "write the attributes of /grid");
  for (int k = 0; k < g->dim && !rc; k++) rc = write_axis(o, grid, &g->axis[k], err);
  if (H5Gclose(grid) < 0 && !rc) rc = h5_error(err, o->h5_path, "close group /grid");
  return rc;
}

static int write_case(gs_output *o, const char *text, const char *name, gs_error *err) {
  hid_t c = H5Gcreate2(o->file, "case", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (c < 0) return h5_error(err, o->h5_path, "create group /case");
  int rc = GS_OK;
  if (gs_h5_str_attr(c, "text", text ? text : "") < 0 || gs_h5_str_attr(c, "file", name ? name : "") < 0)
    rc = h5_error(err, o->h5_path, "write the attributes text and file of /case");
  if (H5Gclose(c) < 0 && !rc) rc = h5_error(err, o->h5_path, "close group /case");
  if (!rc && (gs_h5_str_attr(o->file, "gransim_version", gs_version()) < 0 ||
              gs_h5_str_attr(o->file, "status", "running") < 0 ||
              gs_h5_str_attr(o->file, "solver", "sectional") < 0 ||
              gs_h5_i64_attr(o->file, "ntimes", 0) < 0))
    rc = h5_error(err, o->h5_path, "write the attributes gransim_version, status, ntimes of /");
  return rc;
}

/* /discretisation: each distribution of the case (initial, feeds) as asked
 * and as the grid holds it (distribution.h), so that a result file says
 * what its initial state and feeds stand for. */
static int write_discretisation(gs_output *o, const gs_model *m, gs_error *err) {
  const gs_disc_log *log = m->disc;
  const size_t n = log ? log->n : 0, w = 1 + (size_t)m->grid.dim;
  hid_t g = H5Gcreate2(o->file, "discretisation", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (g < 0) return h5_error(err, o->h5_path, "create group /discretisation");
  double *buf = gs_calloc(2 * n * w + n + 1, sizeof *buf, err);
  size_t keys_len = 1;
  for (size_t i = 0; i < n; i++) keys_len += strlen(log->r[i].key) + 1;
  char *keys = gs_calloc(keys_len, 1, err);
  int rc = buf && keys ? GS_OK : GS_ENOMEM;
  for (size_t i = 0; !rc && i < n; i++) {
    const gs_disc_report *r = &log->r[i];
    buf[i * w] = r->number[0];
    buf[(n + i) * w] = r->number[1];
    for (int k = 0; k < m->grid.dim; k++) {
      buf[i * w + 1 + (size_t)k] = r->volume[k][0];
      buf[(n + i) * w + 1 + (size_t)k] = r->volume[k][1];
    }
    buf[2 * n * w + i] = gs_disc_error(r);
    if (i) strcat(keys, "\n");
    strcat(keys, r->key);
  }
  if (!rc) buf[2 * n * w + n] = log ? log->tolerance : GS_DISC_TOLERANCE;
  if (!rc && (write_vector(g, "requested", buf, n * w) < 0 ||
              write_vector(g, "represented", buf + n * w, n * w) < 0 ||
              write_vector(g, "error", buf + 2 * n * w, n) < 0 ||
              write_vector(g, "tolerance", buf + 2 * n * w + n, 1) < 0 ||
              gs_h5_describe(g, "requested", "1 (number), m^3 (volume of each axis)", "entry (per distribution: number then volumes)") < 0 ||
              gs_h5_describe(g, "represented", "1 (number), m^3 (volume of each axis)", "entry (per distribution: number then volumes)") < 0 ||
              gs_h5_describe(g, "error", "1", "distribution") < 0 ||
              gs_h5_describe(g, "tolerance", "1", "") < 0 ||
              gs_h5_str_attr(g, "keys", keys) < 0 ||
              gs_h5_str_attr(g, "layout", "requested and represented: per distribution (keys), its "
                                         "number, then the volume of every axis; error: the largest "
                                         "relative error of number, volumes and mean sizes") < 0))
    rc = h5_error(err, o->h5_path, "write /discretisation");
  free(buf);
  free(keys);
  if (H5Gclose(g) < 0 && !rc) rc = h5_error(err, o->h5_path, "close group /discretisation");
  return rc;
}

/* gzip only where this HDF5 build can actually encode it. */
static int deflate_usable(void) {
  unsigned int info = 0;
  return H5Zfilter_avail(H5Z_FILTER_DEFLATE) > 0 &&
         H5Zget_filter_info(H5Z_FILTER_DEFLATE, &info) >= 0 &&
         (info & H5Z_FILTER_CONFIG_ENCODE_ENABLED);
}

/* Empty float64 series i, extendible along time.  /number and /carried are
 * chunked by up to 64 KiB of output times (chunk_rows), the rest by 64 rows.
 * Only rows of at least COMPRESS_MIN_VALUES are deflated: zlib sets up
 * ~256 KiB of state per chunk, which on small grids costs more than the
 * integration. */
#define COMPRESS_MIN_VALUES 8192
/* A large series' chunk holds as many output times as fit in
 * BIG_CHUNK_BYTES, at least one; only a row of COMPRESS_MIN_VALUES or more,
 * a chunk of its own, is deflated.  A chunk per output time makes many
 * small chunks on small grids: each write costs more, and a chunk index
 * that outgrows a node (a B-tree of up to 64 entries a node) stalls rank 0
 * at an output time, and with it the other ranks. */
#define BIG_CHUNK_BYTES ((size_t)64 << 10)
/* Time rows per chunk of series i. */
static hsize_t chunk_rows(const gs_output *o, int i) {
  if (i == S_NUMBER || i == o->s_carried) {
    const size_t row = o->rowlen[i] * sizeof(double);
    return o->rowlen[i] >= COMPRESS_MIN_VALUES || row >= BIG_CHUNK_BYTES ? 1 : BIG_CHUNK_BYTES / row;
  }
  return i == S_TIME ? 4 * CHUNK_ROWS : CHUNK_ROWS;
}

static int create_series(gs_output *o, int i, gs_error *err) {
  int rank = o->rank[i];
  hsize_t dims[RANK_MAX] = {0}, maxdims[RANK_MAX] = {H5S_UNLIMITED}, chunk[RANK_MAX];
  const int big = i == S_NUMBER || i == o->s_carried;
  chunk[0] = chunk_rows(o, i);
  hsize_t values = chunk[0];
  for (int r = 1; r < rank; r++) {
    dims[r] = maxdims[r] = chunk[r] = o->rest[i][r - 1];
    values *= chunk[r];
  }
  const int compress = big && o->rowlen[i] >= COMPRESS_MIN_VALUES && deflate_usable();
  o->direct[i] = big && o->chunks && gs_chunk_direct_ok();
  o->deflated[i] = compress;
  if (o->direct[i] && chunk[0] > 1 && !o->held[i] &&
      !(o->held[i] = gs_malloc((size_t)values * sizeof(double), err)))
    return GS_ENOMEM;
  hid_t space = H5Screate_simple(rank, dims, maxdims);
  hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  if (space >= 0 && dcpl >= 0 && H5Pset_chunk(dcpl, rank, chunk) >= 0 &&
      (!compress || H5Pset_deflate(dcpl, DEFLATE_LEVEL) >= 0))
    o->ds[i] = H5Dcreate2(o->file, o->sname[i], H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl,
                          H5P_DEFAULT);
  if (dcpl >= 0) H5Pclose(dcpl);
  if (space >= 0) H5Sclose(space);
  return o->ds[i] < 0 ? h5_error(err, o->h5_path, "create dataset %s", o->sname[i]) : GS_OK;
}

/* The units and dimension names of series i (units.h). */
static int describe_dataset(gs_output *o, int i, gs_error *err) {
  char dims[64 + GS_MAX_DIM * GS_NAME_LEN] = "time,compartment";
  const char *units = "m^3";
  if (i == S_TIME) snprintf(dims, sizeof dims, "time");
  else if (i == S_LEDGER) snprintf(dims, sizeof dims, "time,compartment,entry");
  else if (i == S_NUMBER || i == o->s_carried) {
    snprintf(dims, sizeof dims, "time,compartment%s,%s", i == S_NUMBER ? "" : ",quantity", o->axis_names);
    if (i == S_NUMBER) units = "1";
  } else if (i >= S_SUMMARY && i < S_SUMMARY + o->ncol) {
    const char *u = o->unit[i - S_SUMMARY];
    units = u ? u : "1";
  }
  if (i == S_TIME) units = "s";
  return gs_h5_describe(o->ds[i], ".", units, dims) < 0
             ? h5_error(err, o->h5_path, "write the attributes units and dimensions of %s", o->sname[i])
             : GS_OK;
}

static int create_all_series(gs_output *o, gs_error *err) {
  hid_t sg = H5Gcreate2(o->file, "summary", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (sg < 0 || H5Gclose(sg) < 0) return h5_error(err, o->h5_path, "create group /summary");
  int rc = GS_OK;
  for (int i = 0; i < o->nseries && !rc; i++) rc = create_series(o, i, err);
  for (int i = 0; i < o->nseries && !rc; i++) rc = describe_dataset(o, i, err);
  return rc;
}

/* ---- rows of the time series ------------------------------------------------ */

/* Selects rows [start, start+count) of d in *fs and a flat memory space *ms. */
static herr_t select_rows(hid_t d, hsize_t start, hsize_t count, hid_t *fs, hid_t *ms) {
  hsize_t dims[RANK_MAX], off[RANK_MAX] = {start}, cnt[RANK_MAX];
  *ms = H5I_INVALID_HID;
  *fs = H5Dget_space(d);
  int rank = *fs >= 0 ? H5Sget_simple_extent_ndims(*fs) : -1;
  if (rank < 1 || rank > RANK_MAX || H5Sget_simple_extent_dims(*fs, dims, NULL) < 0) return -1;
  if (start + count > dims[0]) return -1;
  hsize_t n = count;
  cnt[0] = count;
  for (int r = 1; r < rank; r++) {
    off[r] = 0;
    cnt[r] = dims[r];
    n *= dims[r];
  }
  if (H5Sselect_hyperslab(*fs, H5S_SELECT_SET, off, NULL, cnt, NULL) < 0) return -1;
  *ms = H5Screate_simple(1, &n, NULL);
  return *ms >= 0 ? 0 : -1;
}

static void close_spaces(hid_t fs, hid_t ms) {
  if (fs >= 0) H5Sclose(fs);
  if (ms >= 0) H5Sclose(ms);
}

/* Writes rows [start, start+count) of series i and makes it exactly that
 * long, so rows left over from an earlier failed write are dropped. */
static int write_rows(gs_output *o, int i, hsize_t start, hsize_t count, const double *buf,
                      gs_error *err) {
  hsize_t dims[RANK_MAX] = {start + count};
  for (int r = 1; r < o->rank[i]; r++) dims[r] = o->rest[i][r - 1];
  hid_t fs = H5I_INVALID_HID, ms = H5I_INVALID_HID;
  herr_t st = H5Dset_extent(o->ds[i], dims);
  const hsize_t rows = chunk_rows(o, i);
  o->indexed[i] = 1;
  if (st >= 0 && o->direct[i] && rows == 1)
    st = gs_chunk_write_rows(o->chunks, o->ds[i], start, count, o->rowlen[i], buf, o->deflated[i],
                             DEFLATE_LEVEL);
  else if (st >= 0 && o->chunks && start % rows == 0 && gs_chunk_direct_ok())
    st = gs_chunk_write_blocks(o->chunks, o->ds[i], start, count, rows, o->rowlen[i], buf);
  else if (st >= 0 && (st = select_rows(o->ds[i], start, count, &fs, &ms)) >= 0)
    st = H5Dwrite(o->ds[i], H5T_NATIVE_DOUBLE, ms, fs, H5P_DEFAULT, buf);
  close_spaces(fs, ms);
  return st < 0 ? h5_error(err, o->h5_path, "write dataset %s", o->sname[i]) : GS_OK;
}

/* ---- summary.csv ------------------------------------------------------------ */

static int csv_error(gs_output *o, gs_error *err) {
  return gs_error_set(err, GS_EIO, "cannot write %s: %s", o->csv_tmp, strerror(errno));
}

static int csv_header(gs_output *o, gs_error *err) {
  char name[GS_NAME_LEN + 40];
  for (int c = 0; c < o->ncol; c++) {
    if (o->unit[c]) snprintf(name, sizeof name, "%s [%s]", colname(o, c), o->unit[c]);
    else snprintf(name, sizeof name, "%s", colname(o, c));
    if (fprintf(o->csv, "%s%s", c ? "," : "", name) < 0) return csv_error(o, err);
  }
  return fputc('\n', o->csv) == EOF ? csv_error(o, err) : GS_OK;
}

/* The row of compartment j; the value of column c is sbuf[c * stride + first + j]. */
static int csv_row(gs_output *o, const double *sbuf, size_t stride, size_t first, size_t j,
                   gs_error *err) {
  char line[NCOL_MAX * GS_CSV_NUMBER_MAX + 1], *p = line;
  for (int c = 0; c < o->ncol; c++) {
    if (c) *p++ = ',';
    p += gs_csv_number(sbuf[(size_t)c * stride + first + j], p);
  }
  *p++ = '\n';
  return fwrite(line, 1, (size_t)(p - line), o->csv) == (size_t)(p - line) ? GS_OK : csv_error(o, err);
}

static int csv_flush(gs_output *o, gs_error *err) {
  return fflush(o->csv) ? csv_error(o, err) : GS_OK;
}

static int csv_create(gs_output *o, gs_error *err) {
  o->csv = fopen(o->csv_tmp, "w");
  if (!o->csv) return gs_error_set(err, GS_EIO, "cannot create %s: %s", o->csv_tmp, strerror(errno));
  /* rows are formatted at every output time: fewer, larger writes, since a
   * system call is costly (in a virtual machine especially) */
  setvbuf(o->csv, NULL, _IOFBF, (size_t)1 << 16);
  int rc = csv_header(o, err);
  return rc ? rc : csv_flush(o, err);
}

/* ---- construction and teardown --------------------------------------------- */

static void output_free(gs_output *o) {
  if (!o) return;
  free(o->dir);
  free(o->h5_new);
  free(o->h5_tmp);
  free(o->h5_final);
  free(o->csv_tmp);
  free(o->csv_final);
  free(o->journal_path);
  free(o->journal_new);
  gs_journal_close(o->journal, NULL);
  free(o->sbuf);
  free(o->pending_block);
  for (int i = 0; i < NSERIES_MAX; i++) free(o->held[i]);
  gs_chunk_writer_free(o->chunks);
  free(o);
}

static gs_output *output_alloc(const char *dir, const gs_model *m, size_t nresume, gs_error *err) {
  const gs_grid *g = &m->grid;
  if (check_axis_names(g, err)) return NULL;
  for (int q = 0; q < m->ncarried; q++)
    if (strchr(m->carried[q], '/') || strchr(m->carried[q], ','))
      return gs_error_set(err, GS_EINPUT, "carried name '%s' cannot be used in result files", m->carried[q]), NULL;
  if (gs_model_ncolumns(m) > NCOL_MECH)
    return gs_error_set(err, GS_EINPUT, "the mechanisms add %d summary columns, at most %d fit",
                        gs_model_ncolumns(m), NCOL_MECH), NULL;
  gs_output *o = gs_calloc(1, sizeof *o, err);
  if (!o) return NULL;
  o->file = H5I_INVALID_HID;
  for (int i = 0; i < NSERIES_MAX; i++) o->ds[i] = H5I_INVALID_HID;
  o->ncomp = g->ncomp;
  o->nstate = m->nstate;
  o->nnum = m->nnum;
  describe_series(o, m);
  o->dir = path_join(dir, "", err);
  o->h5_new = path_join(dir, H5_NEW, err);
  o->h5_tmp = path_join(dir, H5_PARTIAL, err);
  o->h5_final = path_join(dir, "result.h5", err);
  o->csv_tmp = path_join(dir, CSV_PARTIAL, err);
  o->csv_final = path_join(dir, "summary.csv", err);
  o->journal_path = path_join(dir, JOURNAL, err);
  o->journal_new = path_join(dir, JOURNAL_NEW, err);
  o->nresume = nresume;
  o->sbuf = gs_malloc((size_t)o->ncol * g->ncomp * sizeof(double), err);
  o->chunks = gs_chunk_writer_new(); /* without it, H5Dwrite does the same job slower */
  if (!o->dir || !o->h5_new || !o->h5_tmp || !o->h5_final || !o->csv_tmp || !o->csv_final ||
      !o->journal_path || !o->journal_new || !o->sbuf) {
    output_free(o);
    return NULL;
  }
  o->h5_path = o->h5_tmp;
  return o;
}

/* Closes every handle; reports the first failure. */
static int output_close(gs_output *o, gs_error *err) {
  int failed = 0;
  for (int i = 0; i < NSERIES_MAX; i++) {
    if (o->ds[i] >= 0 && H5Dclose(o->ds[i]) < 0) failed = 1;
    o->ds[i] = H5I_INVALID_HID;
  }
  int rc = failed ? h5_error(err, o->h5_path, "close the datasets") : GS_OK;
  if (o->file >= 0 && H5Fclose(o->file) < 0 && !rc)
    rc = h5_error(err, o->h5_path, "close the file");
  o->file = H5I_INVALID_HID;
  if (o->csv && fclose(o->csv) && !rc) rc = csv_error(o, err);
  o->csv = NULL;
  return rc;
}

/* Gives up on an output that failed to open or resume: the half-built .new
 * file goes, a published partial stays (it holds the run's data). */
static void output_discard(gs_output *o) {
  output_close(o, NULL);
  if (!o->published) unlink(o->h5_new);
  output_free(o);
}

/* HDF5 1.8 object formats: readable by every current tool, and they let the
 * case text attribute exceed 64 KiB (dense attribute storage). */
static hid_t h5_create(const char *path) {
  hid_t fapl = H5Pcreate(H5P_FILE_ACCESS), f = H5I_INVALID_HID;
  herr_t st = fapl >= 0 ? H5Pset_libver_bounds(fapl, H5F_LIBVER_V18, H5F_LIBVER_V18) : -1;
  if (st >= 0) {
    /* Dirty metadata reaches the disk only at flushes: with evictions the
     * cache may write a chunk index node between two commits (the large
     * series are written row by row), and someone reading the partial file
     * while the run goes on could meet a half-updated index.  (A resume
     * reads the journal, never this file.)  The cache then grows with the
     * metadata until the next flush, a few bytes per chunk. */
    H5AC_cache_config_t mdc;
    mdc.version = H5AC__CURR_CACHE_CONFIG_VERSION;
    st = H5Pget_mdc_config(fapl, &mdc);
    if (st >= 0) {
      mdc.evictions_enabled = 0;
      mdc.incr_mode = H5C_incr__off;
      mdc.flash_incr_mode = H5C_flash_incr__off;
      mdc.decr_mode = H5C_decr__off;
      st = H5Pset_mdc_config(fapl, &mdc);
    }
  }
  if (st >= 0) f = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  if (fapl >= 0) H5Pclose(fapl);
  return f;
}

static int flush_h5(gs_output *o, gs_error *err) {
  return H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0 ? h5_error(err, o->h5_path, "flush the file")
                                                  : GS_OK;
}

/* Builds grid, case and empty series in DIR/.result.h5.new. */
static int build_skeleton(gs_output *o, const gs_model *m, const char *text, const char *name,
                          gs_error *err) {
  o->h5_path = o->h5_new;
  o->file = h5_create(o->h5_new);
  if (o->file < 0) return h5_error(err, o->h5_path, "create the file");
  int rc = write_grid(o, &m->grid, err);
  if (!rc) rc = write_case(o, text, name, err);
  char notes[4096];
  if (!rc && gs_model_notes(m, notes, sizeof notes) > 0 && gs_h5_str_attr(o->file, "mechanism_notes", notes) < 0)
    rc = h5_error(err, o->h5_path, "write the attribute mechanism_notes of /");
  if (!rc) rc = write_discretisation(o, m, err);
  if (!rc) rc = create_all_series(o, err);
  return rc;
}

/* Flushes the finished .new file and renames it to .result.h5.partial (the
 * open handle follows the rename). */
static int publish(gs_output *o, gs_error *err) {
  int rc = flush_h5(o, err);
  if (rc) return rc;
  if (rename(o->h5_new, o->h5_tmp))
    return gs_error_set(err, GS_EIO, "cannot rename %s to %s: %s", o->h5_new, o->h5_tmp,
                        strerror(errno));
  o->h5_path = o->h5_tmp;
  o->published = 1;
  return GS_OK;
}

/* ---- public API: open, write, finish ------------------------------------------ */

/* A journal row: time, state, ledger, integrator state. */
static size_t journal_row_values(const gs_output *o) {
  return 1 + o->nstate + o->rowlen[S_LEDGER] + o->nresume;
}

/* The journal a resume reads, with the grid and the case echo in its header. */
static int journal_create(gs_output *o, const gs_model *m, const char *text, const char *name,
                          gs_error *err) {
  void *head;
  size_t nhead;
  int rc = gs_journal_header_encode(m, o->nresume, text, name, &head, &nhead, err);
  if (rc) return rc;
  o->journal = gs_journal_create(o->journal_new, o->journal_path, head, nhead, journal_row_values(o), err);
  free(head);
  return o->journal ? GS_OK : err->code;
}

gs_output *gs_output_open(const char *dir, const gs_model *m, const char *case_text,
                          const char *case_name, size_t nresume, gs_error *err) {
  gs_h5_setup();
  if (gs_output_mkdir_p(dir, err)) return NULL;
  gs_output *o = output_alloc(dir, m, nresume, err);
  if (!o) return NULL;
  int rc = build_skeleton(o, m, case_text, case_name, err);
  if (!rc) rc = csv_create(o, err);
  if (!rc) rc = journal_create(o, m, case_text, case_name, err);
  if (!rc) rc = publish(o, err);
  if (rc) {
    output_discard(o);
    return NULL;
  }
  return o;
}

/* Fills compartment j's entries of o->sbuf ([column][comp]) for output time t. */
static void summarize(gs_output *o, const gs_model *m, double t, const double *y, size_t j) {
  size_t nc = o->ncomp;
  int nvol = m->nvol;
  gs_summary s;
  memset(&s, 0, sizeof s);
  gs_summarize(m, y, j, &s);
  double fixed[NCOL_FIXED] = {t, (double)(j + 1) /* 1-based, as in case files */, s.m0, s.m1, s.m2, s.d10, s.d50, s.d90};
  for (int c = 0; c < NCOL_FIXED; c++) o->sbuf[(size_t)c * nc + j] = fixed[c];
  for (int k = 0; k < nvol; k++) {
    o->sbuf[(size_t)(NCOL_FIXED + k) * nc + j] = s.mean[k];
    o->sbuf[(size_t)(NCOL_FIXED + nvol + k) * nc + j] = s.total[k];
  }
  const int pore0 = NCOL_FIXED + 2 * nvol, mech0 = pore0 + o->npore_col;
  if (o->npore_col) {
    o->sbuf[(size_t)pore0 * nc + j] = s.porosity;
    o->sbuf[(size_t)(pore0 + 1) * nc + j] = s.liquid_content;
  }
  if (o->nmech_col) {
    double v[NCOL_MECH];
    gs_model_report(m, j, t, y, v);
    for (int k = 0; k < o->nmech_col; k++) o->sbuf[(size_t)(mech0 + k) * nc + j] = v[k];
  }
}

static double wall_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Room for one more pending output time: the block starts small and doubles
 * up to PENDING_BYTES.  Sized for PENDING_BYTES at once it would be a
 * 64 MiB mapping whose pages each series touches in its own region: fresh
 * pages during the run, and unmapping it in the final commit, after the last
 * step, lengthens the run's serial tail. */
static int pending_reserve(gs_output *o, gs_error *err) {
  if (o->npending < o->cap) return GS_OK;
  size_t row = 0;
  for (int i = 0; i < o->nseries; i++)
    if (!o->direct[i]) row += o->rowlen[i] * sizeof(double);
  if (!row) row = 1;
  o->cap_max = PENDING_BYTES / row ? PENDING_BYTES / row : 1;
  size_t cap = o->cap ? 2 * o->cap : PENDING_FIRST_BYTES / row;
  if (cap < o->npending + 1) cap = o->npending + 1;
  if (cap > o->cap_max) cap = o->cap_max > o->npending ? o->cap_max : o->npending + 1;
  double *block = gs_malloc(cap * row, err), *at = block;
  if (!block) return GS_ENOMEM;
  for (int i = 0; i < o->nseries; i++)
    if (!o->direct[i]) {
      if (o->npending) memcpy(at, o->pending[i], o->npending * o->rowlen[i] * sizeof(double));
      o->pending[i] = at;
      at += cap * o->rowlen[i];
    }
  free(o->pending_block);
  o->pending_block = block;
  o->cap = cap;
  return GS_OK;
}

/* Writes the pending rows of every series, then commits them (see the top
 * of the file), then flushes their summary.csv rows (formatted as they came:
 * the partial CSV may run ahead of the commits, and a resume rewrites it from
 * result.h5).  last: the file is closed next (which flushes), so the second
 * flush is left to the close. */
/* The chunk of large series i that holds row end - 1: its rows up to end
 * from the held buffer, the rest zeros (beyond the extent, where no reader
 * looks; the full chunk replaces them later). */
static int write_held(gs_output *o, int i, hsize_t end, gs_error *err) {
  const hsize_t k = chunk_rows(o, i), first = (end - 1) / k * k;
  const size_t len = o->rowlen[i];
  if (end - first < k)
    memset(o->held[i] + (size_t)(end - first) * len, 0, (size_t)(k - (end - first)) * len * sizeof(double));
  hsize_t dims[RANK_MAX] = {end}, offset[RANK_MAX] = {first};
  for (int r = 1; r < o->rank[i]; r++) dims[r] = o->rest[i][r - 1];
  herr_t st = H5Dset_extent(o->ds[i], dims);
  if (st >= 0)
    st = H5Dwrite_chunk(o->ds[i], H5P_DEFAULT, 0, offset, (size_t)k * len * sizeof(double), o->held[i]);
  return st < 0 ? h5_error(err, o->h5_path, "write dataset %s", o->sname[i]) : GS_OK;
}

/* Row `index` of a large series written chunk by chunk: a chunk of one row
 * goes to the file at once, a longer one when its last row comes, and
 * partly filled at each commit (write_held). */
static int hold_row(gs_output *o, int i, hsize_t index, const double *row, gs_error *err) {
  const hsize_t k = chunk_rows(o, i);
  if (k == 1) return write_rows(o, i, index, 1, row, err);
  memcpy(o->held[i] + (size_t)(index % k) * o->rowlen[i], row, o->rowlen[i] * sizeof(double));
  return index % k == k - 1 ? write_held(o, i, index + 1, err) : GS_OK;
}

static int commit(gs_output *o, int last, gs_error *err) {
  int rc = GS_OK;
  const hsize_t n = o->npending;
  if (!n) return GS_OK;
  for (int i = 0; i < o->nseries && !rc; i++) {
    if (!o->direct[i]) rc = write_rows(o, i, o->ntimes, n, o->pending[i], err);
    else if (o->held[i] && (o->ntimes + n) % chunk_rows(o, i)) rc = write_held(o, i, o->ntimes + n, err);
  }
  if (!rc) rc = flush_h5(o, err);
  if (!rc && put_i64_attr(o->file, "ntimes", (long long)(o->ntimes + n)) < 0)
    rc = h5_error(err, o->h5_path, "write the attribute ntimes of /");
  if (!rc && !last) rc = flush_h5(o, err);
  /* what a resume trusts: the journal's commit record (journal.h); the
   * attribute ntimes only describes the file */
  if (!rc && o->journal) rc = gs_journal_commit(o->journal, err);
  if (rc) return rc;
  o->ntimes += n;
  rc = csv_flush(o, err);
  o->npending = 0;
  o->last_commit = wall_seconds();
  return rc;
}

void gs_output_set_checkpoint(gs_output *o, double seconds) {
  if (!o) return;
  o->checkpoint = seconds > 0 ? seconds : 0;
  o->last_commit = wall_seconds();
}

/* Parts of an output time: a summary and CSV row per compartment, then a
 * row of each large series (into its held chunk, written when full), a
 * deflated row in pieces of PIECE_BYTES (a large row deflated in one piece
 * takes milliseconds, and holds up the other MPI ranks when rank 0 begins
 * it just before they arrive), then the rows of the small
 * series held for the commit, and the commit when it is due. */
#define PIECE_BYTES ((size_t)32 << 10)

static int row_pieces(const gs_output *o, int i) {
  if (!o->direct[i]) return 0;
  if (!o->deflated[i]) return 1;
  return (int)((o->rowlen[i] * sizeof(double) + PIECE_BYTES - 1) / PIECE_BYTES);
}

int gs_output_parts(const gs_output *o) {
  int pieces = 0;
  for (int i = 0; i < o->nseries; i++) pieces += row_pieces(o, i) + !o->direct[i];
  return (int)o->ncomp + pieces + 1;
}

/* A small series' first write, of the rows held so far: the first chunk of
 * a dataset creates its chunk index (about twice the cost of a later
 * write), so the commit at the end of a run, which comes after the
 * last step, would pay it for every series; written in the parts of an
 * output time, it falls in rank 0's waits under MPI.  The rows count only
 * once committed, like those of the large series. */
static int index_small_series(gs_output *o, int i, gs_error *err) {
  if (o->indexed[i] || !o->npending) return GS_OK;
  return write_rows(o, i, o->ntimes, o->npending, o->pending[i], err);
}

/* Piece p of np of the deflated row of series i for output time `index`:
 * the first extends the series, the last writes the chunk. */
static int write_row_piece(gs_output *o, int i, hsize_t index, const double *row, int p, int np,
                           gs_error *err) {
  const size_t bytes = o->rowlen[i] * sizeof(double), from = (size_t)p * PIECE_BYTES;
  const size_t n = bytes - from < PIECE_BYTES ? bytes - from : PIECE_BYTES;
  herr_t st = 0;
  if (p == 0) {
    hsize_t dims[RANK_MAX] = {index + 1};
    for (int r = 1; r < o->rank[i]; r++) dims[r] = o->rest[i][r - 1];
    st = H5Dset_extent(o->ds[i], dims);
    gs_chunk_row_begin(o->chunks, bytes, DEFLATE_LEVEL);
  }
  gs_chunk_row_feed(o->chunks, (const char *)row + from, n, p + 1 == np);
  if (st >= 0 && p + 1 == np) st = gs_chunk_row_write(o->chunks, o->ds[i], index, o->rowlen[i], row);
  return st < 0 ? h5_error(err, o->h5_path, "write dataset %s", o->sname[i]) : GS_OK;
}

/* Row of series i for output time t. */
static const double *series_row(const gs_output *o, int i, const double *t, const double *y,
                                const double *ledger) {
  return i == S_TIME         ? t
         : i == S_NUMBER     ? y
         : i == S_LEDGER     ? ledger
         : i == o->s_carried ? y + o->nnum
                             : o->sbuf + (size_t)(i - S_SUMMARY) * o->ncomp;
}

int gs_output_write_part(gs_output *o, const gs_model *m, double t, const double *y,
                         const double *ledger, const double *resume, int part, gs_error *err) {
  if (m->nstate != o->nstate || m->grid.ncomp != o->ncomp)
    return gs_error_set(err, GS_EINPUT, "output to %s: the model does not match the result file",
                        o->dir);
  if (part != o->next_part)
    return gs_error_set(err, GS_EINPUT, "output to %s: part %d of an output time written where part %d was due",
                        o->dir, part, o->next_part);
  o->next_part = part + 1 < gs_output_parts(o) ? part + 1 : 0;
  if ((size_t)part < o->ncomp) { /* compartment `part`: its summary and CSV row */
    summarize(o, m, t, y, (size_t)part);
    return csv_row(o, o->sbuf, o->ncomp, 0, (size_t)part, err);
  }
  const size_t r = o->npending;
  /* the large series go to the file at once (their rows count only once
   * committed): copies held until the commit would touch fresh memory, and
   * page faults are costly (docs/performance.md, "page faults") */
  int k = part - (int)o->ncomp;
  for (int i = 0; i < o->nseries; i++) {
    const int np = row_pieces(o, i) + !o->direct[i];
    if (k >= np) {
      k -= np;
      continue;
    }
    if (!o->direct[i]) return index_small_series(o, i, err);
    const double *row = series_row(o, i, &t, y, ledger);
    return o->deflated[i] ? write_row_piece(o, i, o->ntimes + r, row, k, np, err)
                          : hold_row(o, i, o->ntimes + r, row, err);
  }
  if (pending_reserve(o, err)) return GS_ENOMEM;
  for (int i = 0; i < o->nseries; i++)
    if (!o->direct[i])
      memcpy(o->pending[i] + r * o->rowlen[i], series_row(o, i, &t, y, ledger), o->rowlen[i] * sizeof(double));
  if (o->journal) {
    const double *pieces[4] = {&t, y, ledger, resume};
    const size_t lens[4] = {1, o->nstate, o->rowlen[S_LEDGER], o->nresume};
    int rc = gs_journal_append(o->journal, pieces, lens, o->nresume ? 4 : 3, err);
    if (rc) return rc;
  }
  o->npending++;
  if (o->npending < o->cap_max && wall_seconds() - o->last_commit < o->checkpoint) return GS_OK;
  return commit(o, 0, err);
}

int gs_output_write(gs_output *o, const gs_model *m, double t, const double *y,
                    const double *ledger, const double *resume, gs_error *err) {
  int rc = GS_OK;
  for (int part = 0; part < gs_output_parts(o) && !rc; part++)
    rc = gs_output_write_part(o, m, t, y, ledger, resume, part, err);
  return rc;
}

static int rename_final(const char *from, const char *to, gs_error *err) {
  if (!rename(from, to)) return GS_OK;
  return gs_error_set(err, GS_EIO, "cannot rename %s to %s: %s", from, to, strerror(errno));
}

static int remove_partial(const char *path, gs_error *err) {
  if (!unlink(path) || errno == ENOENT) return GS_OK;
  return gs_error_set(err, GS_EIO, "cannot remove %s: %s", path, strerror(errno));
}

int gs_output_commit_due(const gs_output *o) {
  return o && wall_seconds() - o->last_commit >= o->checkpoint;
}

int gs_output_finish(gs_output *o, int ok, gs_error *err) {
  if (!o) return GS_OK;
  int rc = GS_OK;
  /* a caller's bug: never publish half an output time (what was committed
   * stays resumable under the partial names) */
  if (ok && o->next_part)
    rc = gs_error_set(err, GS_EINPUT, "an output time was only partly written");
  if (ok && !rc) rc = commit(o, 1, err);
  if (!rc && ok && gs_h5_str_attr(o->file, "status", "complete") < 0)
    rc = h5_error(err, o->h5_path, "write the attribute status of /");
  int crc = output_close(o, rc ? NULL : err);
  if (!rc) rc = crc;
  int jrc = gs_journal_close(o->journal, rc ? NULL : err);
  o->journal = NULL;
  if (!rc) rc = jrc;
  if (ok) {
    /* the journal goes last: a kill between the renames leaves it, and a
     * resume rebuilds both files from it and renames them again */
    if (!rc) rc = rename_final(o->h5_tmp, o->h5_final, err);
    if (!rc) rc = rename_final(o->csv_tmp, o->csv_final, err);
    if (!rc) rc = remove_partial(o->journal_path, err);
    /* keep the partial files then: the data may still be recoverable */
    if (rc) gs_error_prefix(err, "result files left under their partial names in %s: ", o->dir);
  } else {
    rc = remove_partial(o->h5_tmp, err);
    int rc2 = remove_partial(o->csv_tmp, rc ? NULL : err);
    if (!rc) rc = rc2;
    rc2 = remove_partial(o->journal_path, rc ? NULL : err);
    if (!rc) rc = rc2;
  }
  output_free(o);
  return rc;
}

/* Commit what is pending and close, leaving the partial files and the
 * journal for a resume (a coupled run's PBM stretch that a trigger ended). */
int gs_output_hold(gs_output *o, gs_error *err) {
  if (!o) return GS_OK;
  int rc = o->next_part ? gs_error_set(err, GS_EINPUT, "an output time was only partly written") : GS_OK;
  if (!rc) rc = commit(o, 0, err);
  int crc = output_close(o, rc ? NULL : err);
  if (!rc) rc = crc;
  int jrc = gs_journal_close(o->journal, rc ? NULL : err);
  o->journal = NULL;
  if (!rc) rc = jrc;
  output_free(o);
  return rc;
}

/* ---- resume: the journal ----------------------------------------------------- */

/* Writes the journal's committed rows into o's fresh files through the
 * ordinary path (one commit at the end, none in between), and leaves the
 * last one in *t, y, ledger, resume. */
static int replay(gs_output *o, gs_journal *j, const gs_model *m, double *t, double *y,
                  double *ledger, double *resume, gs_error *err) {
  const uint64_t n = gs_journal_committed(j);
  double *row = gs_malloc(journal_row_values(o) * sizeof(double), err);
  if (!row) return GS_ENOMEM;
  const double *ry = row + 1, *rl = ry + o->nstate, *rr = rl + o->rowlen[S_LEDGER];
  o->checkpoint = HUGE_VAL; /* commits only when the buffer is full */
  int rc = GS_OK;
  for (uint64_t r = 0; r < n && !rc; r++) {
    rc = gs_journal_read(j, r, row, err);
    if (!rc) rc = gs_output_write(o, m, row[0], ry, rl, rr, err);
  }
  if (!rc) rc = commit(o, 0, err);
  if (!rc) {
    *t = row[0];
    memcpy(y, ry, o->nstate * sizeof *y);
    memcpy(ledger, rl, o->rowlen[S_LEDGER] * sizeof *ledger);
    if (o->nresume) memcpy(resume, rr, o->nresume * sizeof *resume);
  }
  free(row);
  o->checkpoint = 0;
  return rc;
}

gs_output *gs_output_resume(const char *dir, const gs_model *m, size_t nresume, double *t,
                            double *y, double *ledger, double *resume, gs_error *err) {
  gs_h5_setup();
  gs_output *o = output_alloc(dir, m, nresume, err);
  if (!o) return NULL;
  if (access(o->journal_path, F_OK)) {
    gs_error_set(err, GS_EIO, "nothing to resume in %s (no %s: the run finished, or was killed before it wrote anything)", dir, JOURNAL);
    output_free(o);
    return NULL;
  }
  void *head = NULL;
  size_t nhead = 0, row_values = 0;
  const char *text = NULL, *name = NULL;
  gs_journal *j = gs_journal_reopen(o->journal_path, &head, &nhead, &row_values, err);
  int rc = j ? gs_journal_header_check(head, nhead, m, nresume, o->journal_path, &text, &name, err)
             : err->code;
  if (!rc && row_values != journal_row_values(o))
    rc = gs_error_set(err, GS_EIO, "cannot resume: %s has rows of %zu values, %zu expected", o->journal_path,
                      row_values, journal_row_values(o));
  if (!rc && gs_journal_committed(j) == 0)
    rc = gs_error_set(err, GS_EIO, "nothing to resume in %s (%s holds no committed output time yet)",
                      dir, JOURNAL);
  /* fresh files, never the killed ones (HDF5 may have been torn mid-flush) */
  if (!rc) rc = build_skeleton(o, m, text, name, err);
  if (!rc) rc = csv_create(o, err);
  if (!rc) rc = replay(o, j, m, t, y, ledger, resume, err);
  if (!rc) rc = publish(o, err);
  free(head);
  if (rc) {
    gs_journal_close(j, NULL);
    output_discard(o);
    return NULL;
  }
  o->journal = j;
  o->last_commit = wall_seconds();
  return o;
}
