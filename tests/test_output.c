/* Result files: partial names until finish, HDF5 layout and contents, CSV,
 * abort, resume after a killed run (including a torn write and extra CSV
 * rows), resume refusals, output times written later in pieces
 * (deferred_output.h), large series with several output times per chunk;
 * 1-, 2- and 3-D grids. */
#include <hdf5.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "gransim/output.h"
#include "output/deferred_output.h"

static char base[64];

static int exists(const char *dir, const char *name) {
  char p[512];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  return access(p, F_OK) == 0;
}

/* Axes: solid (geometric, nsolid cells), liquid (4), gas (3). */
static void make_model(gs_model *m, int dim, size_t ncomp, size_t nsolid) {
  gs_error err;
  gs_axis ax[3];
  gs_grid g;
  /* ratio 1.5 up to 500 cells; beyond, a finer one keeps the last edge within
   * the 1e100 an axis may reach (1.5^4096 overflows) */
  CHECK(gs_axis_geometric(&ax[0], "solid", 1e-3, nsolid <= 500 ? 1.5 : 1.01, nsolid, 0, &err) == GS_OK);
  if (dim > 1) CHECK(gs_axis_linear(&ax[1], "liquid", 0.0, 1e-2, 4, &err) == GS_OK);
  if (dim > 2) CHECK(gs_axis_linear(&ax[2], "gas", 0.0, 5e-3, 3, &err) == GS_OK);
  CHECK(gs_grid_init(&g, ax, dim, ncomp, &err) == GS_OK);
  CHECK(gs_model_init(m, &g, &err) == GS_OK);
}

/* Distinct, recognisable values for output time k. */
static void fill(const gs_model *m, int k, double *y, double *ledger) {
  for (size_t i = 0; i < m->nstate; i++) y[i] = 1.0 + (double)i + 100.0 * k;
  for (size_t i = 0; i < m->nledger; i++) ledger[i] = 0.25 * (double)i - k;
}

static double time_of(int k) { return 0.5 * k; }

/* integrator state kept with each output time (in the journal only) */
#define NRES 3
static void fill_resume(int k, double *res) {
  for (int i = 0; i < NRES; i++) res[i] = k + 0.25 * i;
}

static void write_times(gs_output *o, const gs_model *m, int from, int to) {
  gs_error err;
  double *y = malloc(m->nstate * sizeof *y), *led = malloc(m->nledger * sizeof *led);
  for (int k = from; k < to; k++) {
    double res[NRES];
    fill(m, k, y, led);
    fill_resume(k, res);
    int rc = gs_output_write(o, m, time_of(k), y, led, res, &err);
    CHECK(rc == GS_OK);
    if (rc) fprintf(stderr, "%s\n", err.msg);
  }
  free(y);
  free(led);
}

/* Whole dataset as doubles; dims/rank returned. */
static double *read_all(hid_t f, const char *name, int *rank, hsize_t *dims) {
  hid_t d = H5Dopen2(f, name, H5P_DEFAULT);
  CHECK(d >= 0);
  if (d < 0) return NULL;
  hid_t s = H5Dget_space(d);
  *rank = H5Sget_simple_extent_ndims(s);
  H5Sget_simple_extent_dims(s, dims, NULL);
  hssize_t n = H5Sget_simple_extent_npoints(s);
  double *buf = malloc((size_t)(n ? n : 1) * sizeof *buf);
  CHECK(H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0);
  H5Sclose(s);
  H5Dclose(d);
  return buf;
}

static void read_str_attr(hid_t f, const char *obj, const char *attr, char *buf, size_t n) {
  buf[0] = '\0';
  hid_t a = H5Aopen_by_name(f, obj, attr, H5P_DEFAULT, H5P_DEFAULT);
  CHECK(a >= 0);
  if (a < 0) return;
  hid_t t = H5Aget_type(a);
  size_t size = H5Tget_size(t);
  char *tmp = calloc(size + 1, 1);
  CHECK(H5Aread(a, t, tmp) >= 0);
  snprintf(buf, n, "%s", tmp);
  free(tmp);
  H5Tclose(t);
  H5Aclose(a);
}

static long long read_int_attr(hid_t f, const char *obj, const char *attr) {
  long long v = -1;
  hid_t a = H5Aopen_by_name(f, obj, attr, H5P_DEFAULT, H5P_DEFAULT);
  CHECK(a >= 0 && H5Aread(a, H5T_NATIVE_LLONG, &v) >= 0);
  if (a >= 0) H5Aclose(a);
  return v;
}

static size_t count_lines(const char *dir, const char *name, char *first, size_t n) {
  char p[512], line[4096];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "r");
  CHECK(f != NULL);
  if (!f) return 0;
  size_t count = 0;
  while (fgets(line, sizeof line, f)) {
    if (count == 0 && first) snprintf(first, n, "%s", line);
    count++;
  }
  fclose(f);
  return count;
}

static void expected_header(const gs_model *m, char *buf, size_t n) {
  size_t len = (size_t)snprintf(buf, n, "time [s],compartment,M0 [1],M1 [m^3],M2 [m^6],d10 [m],d50 [m],d90 [m]");
  for (int k = 0; k < m->grid.dim; k++)
    len += (size_t)snprintf(buf + len, n - len, ",mean_%s [m^3]", m->grid.axis[k].name);
  for (int k = 0; k < m->grid.dim; k++)
    len += (size_t)snprintf(buf + len, n - len, ",total_%s [m^3]", m->grid.axis[k].name);
  if (m->grid.dim > 1) /* a liquid axis: porosity and liquid content */
    len += (size_t)snprintf(buf + len, n - len, ",porosity [1],liquid_content [1]");
  snprintf(buf + len, n - len, "\n");
}

/* Checks result.h5 in dir holds output times 0..ntimes-1 as made by fill(). */
static void check_result(const char *dir, const gs_model *m, int ntimes) {
  char p[512], s[256];
  snprintf(p, sizeof p, "%s/result.h5", dir);
  hid_t f = H5Fopen(p, H5F_ACC_RDONLY, H5P_DEFAULT);
  CHECK(f >= 0);
  if (f < 0) return;
  const gs_grid *g = &m->grid;
  int rank;
  hsize_t dims[8];
  double *y = malloc(m->nstate * sizeof *y), *led = malloc(m->nledger * sizeof *led);

  double *t = read_all(f, "/time", &rank, dims);
  CHECK(rank == 1 && dims[0] == (hsize_t)ntimes);
  for (int k = 0; k < ntimes; k++) CHECK(t[k] == time_of(k));
  free(t);

  double *num = read_all(f, "/number", &rank, dims);
  CHECK(rank == 2 + g->dim && dims[0] == (hsize_t)ntimes && dims[1] == g->ncomp);
  for (int k = 0; k < g->dim; k++) CHECK(dims[2 + k] == g->axis[k].n);
  double *ledger = read_all(f, "/ledger", &rank, dims);
  CHECK(rank == 3 && dims[0] == (hsize_t)ntimes && dims[1] == g->ncomp &&
        dims[2] == 2 * (hsize_t)g->dim);
  double *m0 = read_all(f, "/summary/M0", &rank, dims);
  CHECK(rank == 2 && dims[0] == (hsize_t)ntimes && dims[1] == g->ncomp);
  snprintf(s, sizeof s, "/summary/total_%s", g->axis[g->dim - 1].name);
  double *tot = read_all(f, s, &rank, dims);
  double *stime = read_all(f, "/summary/time", &rank, dims);
  double *scomp = read_all(f, "/summary/compartment", &rank, dims);
  for (int k = 0; k < ntimes; k++) {
    fill(m, k, y, led);
    for (size_t i = 0; i < m->nstate; i++) CHECK(num[(size_t)k * m->nstate + i] == y[i]);
    for (size_t i = 0; i < m->nledger; i++) CHECK(ledger[(size_t)k * m->nledger + i] == led[i]);
    for (size_t j = 0; j < g->ncomp; j++) {
      gs_summary sum;
      gs_summarize(m, y, j, &sum);
      CHECK(m0[(size_t)k * g->ncomp + j] == sum.m0);
      CHECK(tot[(size_t)k * g->ncomp + j] == sum.total[g->dim - 1]);
      CHECK(stime[(size_t)k * g->ncomp + j] == time_of(k));
      CHECK(scomp[(size_t)k * g->ncomp + j] == (double)(j + 1)); /* 1-based */
    }
  }
  free(num), free(ledger), free(m0), free(tot), free(stime), free(scomp);

  CHECK(read_int_attr(f, "/grid", "dim") == g->dim);
  CHECK(read_int_attr(f, "/grid", "ncomp") == (long long)g->ncomp);
  CHECK(read_int_attr(f, "/grid", "ncells") == (long long)g->ncells);
  read_str_attr(f, "/grid", "axis_names", s, sizeof s);
  CHECK(!strcmp(s, g->dim == 1 ? "solid" : g->dim == 2 ? "solid,liquid" : "solid,liquid,gas"));
  for (int k = 0; k < g->dim; k++) {
    char name[64];
    snprintf(name, sizeof name, "/grid/%s/edges", g->axis[k].name);
    double *e = read_all(f, name, &rank, dims);
    CHECK(rank == 1 && dims[0] == g->axis[k].n + 1);
    for (size_t i = 0; i <= g->axis[k].n; i++) CHECK(e[i] == g->axis[k].edges[i]);
    free(e);
    snprintf(name, sizeof name, "/grid/%s/pivots", g->axis[k].name);
    e = read_all(f, name, &rank, dims);
    CHECK(rank == 1 && dims[0] == g->axis[k].n);
    for (size_t i = 0; i < g->axis[k].n; i++) CHECK(e[i] == g->axis[k].pivots[i]);
    free(e);
  }
  read_str_attr(f, "/", "status", s, sizeof s);
  CHECK(!strcmp(s, "complete"));
  read_str_attr(f, "/", "gransim_version", s, sizeof s);
  CHECK(strlen(s) > 0);
  read_str_attr(f, "/case", "file", s, sizeof s);
  CHECK(!strcmp(s, "case.yaml"));
  CHECK(H5Fclose(f) >= 0);
  free(y);
  free(led);
}

/* CSV: header, ntimes*ncomp rows, and one row's values against gs_summarize. */
static void check_csv(const char *dir, const char *name, const gs_model *m, int ntimes) {
  char first[4096], want[4096];
  expected_header(m, want, sizeof want);
  CHECK(count_lines(dir, name, first, sizeof first) == 1 + (size_t)ntimes * m->grid.ncomp);
  CHECK(!strcmp(first, want));
  /* last row: time ntimes-1, last compartment */
  char p[512], line[4096] = "";
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "r");
  if (!f) return;
  while (fgets(line, sizeof line, f)) {}
  fclose(f);
  double t, comp, m0, m1;
  CHECK(sscanf(line, "%lf,%lf,%lf,%lf", &t, &comp, &m0, &m1) == 4);
  double *y = malloc(m->nstate * sizeof *y), *led = malloc(m->nledger * sizeof *led);
  fill(m, ntimes - 1, y, led);
  gs_summary s;
  gs_summarize(m, y, m->grid.ncomp - 1, &s);
  CHECK(t == time_of(ntimes - 1));
  CHECK(comp == (double)m->grid.ncomp /* 1-based */);
  CHECK_REL(m0, s.m0, 1e-9);
  CHECK_REL(m1, s.m1, 1e-9);
  free(y);
  free(led);
}

static void test_roundtrip(int dim) {
  char dir[256];
  snprintf(dir, sizeof dir, "%s/d%d/nested/out", base, dim);
  gs_model m;
  make_model(&m, dim, 2, 6);
  gs_error err;
  /* > 64 KiB: must still fit in an attribute */
  size_t nbig = dim == 1 ? 200000 : 10;
  char *text = malloc(nbig + 1);
  memset(text, 'x', nbig);
  text[nbig] = '\0';
  gs_output *o = gs_output_open(dir, &m, text, "case.yaml", NRES, &err);
  CHECK(o != NULL);
  if (!o) {
    fprintf(stderr, "%s\n", err.msg);
    return;
  }
  CHECK(exists(dir, ".result.h5.partial") && exists(dir, ".summary.csv.partial"));
  CHECK(exists(dir, ".result.journal") && !exists(dir, ".result.journal.new"));
  write_times(o, &m, 0, 3);
  CHECK(!exists(dir, "result.h5") && !exists(dir, "summary.csv"));
  check_csv(dir, ".summary.csv.partial", &m, 3); /* flushed after every write */
  CHECK(gs_output_finish(o, 1, &err) == GS_OK);
  CHECK(exists(dir, "result.h5") && exists(dir, "summary.csv"));
  CHECK(!exists(dir, ".result.h5.partial") && !exists(dir, ".summary.csv.partial"));
  CHECK(!exists(dir, ".result.journal"));
  check_result(dir, &m, 3);
  check_csv(dir, "summary.csv", &m, 3);

  char p[512], got[16];
  snprintf(p, sizeof p, "%s/result.h5", dir);
  hid_t f = H5Fopen(p, H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t a = H5Aopen_by_name(f, "/case", "text", H5P_DEFAULT, H5P_DEFAULT);
  hid_t t = H5Aget_type(a);
  CHECK(H5Tget_size(t) == nbig + 1);
  H5Tclose(t), H5Aclose(a);
  read_str_attr(f, "/case", "text", got, sizeof got);
  CHECK(!strncmp(got, "xxxx", 4));
  H5Fclose(f);
  free(text);
  gs_model_free(&m);
}

/* A model (make_model's arguments) and an output opened for it in
 * base/name, whose path goes to dir (256 bytes). */
static gs_output *open_in(const char *name, char *dir, gs_model *m, int dim, size_t ncomp,
                          size_t nsolid) {
  snprintf(dir, 256, "%s/%s", base, name);
  make_model(m, dim, ncomp, nsolid);
  gs_error err;
  gs_output *o = gs_output_open(dir, m, "", "case.yaml", NRES, &err);
  CHECK(o != NULL);
  if (!o) fprintf(stderr, "%s\n", err.msg);
  return o;
}

/* Many output times: the small series go to the file as whole chunks (64
 * rows, /time 256) when a commit starts on a chunk boundary, the last one
 * padded beyond the extent, and through H5Dwrite otherwise; read back the
 * same either way, committed once at the end or at every output time.
 * With many compartments a row of the small series is ~10 KB, and the
 * pending rows' block (64 KiB at first) grows six times on the way to 300
 * uncommitted output times, moving the rows held so far each time. */
/* Output times per chunk of dataset name. */
static hsize_t chunk_times(const char *dir, const char *name) {
  char p[512];
  snprintf(p, sizeof p, "%s/result.h5", dir);
  hid_t f = H5Fopen(p, H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t d = f >= 0 ? H5Dopen2(f, name, H5P_DEFAULT) : H5I_INVALID_HID;
  hid_t pl = d >= 0 ? H5Dget_create_plist(d) : H5I_INVALID_HID;
  hsize_t dims[8] = {0};
  if (pl < 0 || H5Pget_chunk(pl, 8, dims) < 1) dims[0] = 0;
  if (pl >= 0) H5Pclose(pl);
  if (d >= 0) H5Dclose(d);
  if (f >= 0) H5Fclose(f);
  return dims[0];
}

static void test_many_times(double checkpoint, size_t ncomp) {
  char dir[256], name[64];
  gs_model m;
  gs_error err;
  snprintf(name, sizeof name, "many-%g-%zu", checkpoint, ncomp);
  gs_output *o = open_in(name, dir, &m, 2, ncomp, 6);
  if (!o) {
    gs_model_free(&m);
    return;
  }
  gs_output_set_checkpoint(o, checkpoint);
  write_times(o, &m, 0, 300);
  CHECK(gs_output_finish(o, 1, &err) == GS_OK);
  check_result(dir, &m, 300);
  /* rows under 64 KiB share chunks, held until full and written partly
   * filled at each commit (3 compartments: 113 times a chunk, so the 300
   * end mid-chunk) */
  const hsize_t row = ncomp * 6 * 4 * sizeof(double), k = (64 << 10) / row;
  CHECK(k > 1 && chunk_times(dir, "/number") == k);
  gs_model_free(&m);
}

/* Rows of 8192 values and more are deflated (written chunk by chunk by
 * src/output/chunk_writer.c): HDF5 reads every value back through its filter. */
static void test_deflated(void) {
  char dir[256];
  gs_model m;
  gs_error err;
  gs_output *o = open_in("deflated", dir, &m, 1, 2, 4096);
  if (!o) {
    gs_model_free(&m);
    return;
  }
  write_times(o, &m, 0, 3);
  CHECK(gs_output_finish(o, 1, &err) == GS_OK);
  check_result(dir, &m, 3);
  char p[512];
  snprintf(p, sizeof p, "%s/result.h5", dir);
  hid_t f = H5Fopen(p, H5F_ACC_RDONLY, H5P_DEFAULT), d = H5Dopen2(f, "/number", H5P_DEFAULT);
  hid_t dcpl = H5Dget_create_plist(d);
  CHECK(H5Pget_nfilters(dcpl) == 1 && H5Pget_filter2(dcpl, 0, NULL, NULL, NULL, 0, NULL, NULL) == H5Z_FILTER_DEFLATE);
  CHECK(H5Dget_storage_size(d) < 3 * 8192 * sizeof(double)); /* the values compress */
  H5Pclose(dcpl);
  H5Dclose(d);
  H5Fclose(f);
  gs_model_free(&m);
}

/* The whole of a file, NUL-terminated (NULL if unreadable). */
static char *slurp(const char *dir, const char *name) {
  char p[512];
  snprintf(p, sizeof p, "%s/%s", dir, name);
  FILE *f = fopen(p, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *buf = calloc((size_t)n + 1, 1);
  if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) buf[0] = '\0';
  fclose(f);
  return buf;
}

/* Output times held by a deferred output and written in pieces, some while
 * later ones are pushed, some by the overflow of a full queue, the rest by
 * the drain, give the same files as gs_output_write: every value, and the
 * CSV byte for byte; with commits at every time and only at the end, and
 * with /number's chunks raw and deflated (nsolid 4096). */
static void test_deferred(size_t nsolid, double checkpoint) {
  const int ntimes = 9, depth = 3;
  char name[64], ref[256], dir[256];
  gs_model m, m2;
  gs_error err;
  snprintf(name, sizeof name, "deferred-ref-%zu-%g", nsolid, checkpoint);
  gs_output *o = open_in(name, ref, &m, 1, 3, nsolid);
  snprintf(name, sizeof name, "deferred-%zu-%g", nsolid, checkpoint);
  gs_output *od = open_in(name, dir, &m2, 1, 3, nsolid);
  if (!o || !od) return;
  gs_output_set_checkpoint(o, checkpoint);
  gs_output_set_checkpoint(od, checkpoint);
  /* a caller holding output times back drains them when a commit is due */
  CHECK(gs_output_commit_due(od) == (checkpoint == 0));
  write_times(o, &m, 0, ntimes);
  CHECK(gs_output_finish(o, 1, &err) == GS_OK);

  /* a summary and CSV row per compartment, a part per directly written
   * series (/number; no /carried here), or per 32 KiB piece of a deflated
   * row (3 x 4096 values: 3 pieces), the first write of each small series
   * (/time, /ledger and 10 summary columns), the pending rows */
  CHECK(gs_output_parts(od) == 3 + (nsolid == 4096 ? 3 : 1) + 12 + 1);
  gs_deferred_output *q = gs_deferred_output_create(od, &m2, NRES, depth, &err);
  CHECK(q != NULL);
  if (!q) return;
  CHECK(!gs_deferred_output_pending(q));
  CHECK(gs_deferred_output_work(q, &err) == GS_OK); /* nothing to do */
  double *y = malloc((m2.nstate + m2.nledger) * sizeof *y);
  int pieces = 0;
  for (int k = 0; k < ntimes; k++) {
    fill(&m2, k, y, y + m2.nstate);
    double res[NRES];
    fill_resume(k, res);
    CHECK(gs_deferred_output_push(q, time_of(k), y, res, &err) == GS_OK);
    /* the copy is what gets written, not the caller's buffer */
    memset(y, 0xff, (m2.nstate + m2.nledger) * sizeof *y);
    CHECK(gs_deferred_output_pending(q));
    for (int w = 0; w < k % 4; w++, pieces++) CHECK(gs_deferred_output_work(q, &err) == GS_OK);
  }
  CHECK(pieces > 0);
  CHECK(gs_deferred_output_drain(q, &err) == GS_OK);
  CHECK(!gs_deferred_output_pending(q));
  CHECK(gs_deferred_output_seconds(q) > 0);
  gs_deferred_output_free(q);
  CHECK(gs_output_finish(od, 1, &err) == GS_OK);
  check_result(dir, &m2, ntimes);
  char *a = slurp(ref, "summary.csv"), *b = slurp(dir, "summary.csv");
  CHECK(a && b && !strcmp(a, b));
  free(a), free(b), free(y);
  gs_model_free(&m);
  gs_model_free(&m2);
}

/* Parts out of order are refused, and an output time only partly written is
 * never published: the partial files stay, with what was committed. */
static void test_parts_misused(void) {
  char dir[256];
  gs_model m;
  gs_error err;
  gs_output *o = open_in("parts-misused", dir, &m, 1, 2, 6);
  if (!o) return;
  write_times(o, &m, 0, 2);
  double *y = calloc(m.nstate + m.nledger, sizeof *y);
  CHECK(gs_output_write_part(o, &m, 5.0, y, y + m.nstate, y, 1, &err) == GS_EINPUT);
  CHECK(strstr(err.msg, "part 1") && strstr(err.msg, "part 0 was due"));
  CHECK(gs_output_write_part(o, &m, 5.0, y, y + m.nstate, y, 0, &err) == GS_OK);
  CHECK(gs_output_finish(o, 1, &err) != GS_OK);
  CHECK(strstr(err.msg, "only partly written") != NULL);
  CHECK(!exists(dir, "result.h5") && exists(dir, ".result.h5.partial"));
  free(y);
  gs_model_free(&m);
}

static void test_abort(void) {
  char dir[256];
  gs_model m;
  gs_error err;
  gs_output *o = open_in("abort", dir, &m, 2, 1, 5);
  if (o) {
    write_times(o, &m, 0, 1);
    CHECK(gs_output_finish(o, 0, &err) == GS_OK);
  }
  CHECK(!exists(dir, "result.h5") && !exists(dir, "summary.csv"));
  CHECK(!exists(dir, ".result.h5.partial") && !exists(dir, ".summary.csv.partial"));
  CHECK(gs_output_finish(NULL, 0, &err) == GS_OK);
  gs_model_free(&m);
}

/* A child process writes two times, leaves a stray CSV row and is killed
 * without closing anything. */
static void killed_run(const char *dir, const gs_model *m) {
  pid_t pid = fork();
  if (pid == 0) {
    gs_error err;
    gs_output *o = gs_output_open(dir, m, "case", "case.yaml", NRES, &err);
    if (!o) _exit(2);
    write_times(o, m, 0, 2);
    char p[512];
    snprintf(p, sizeof p, "%s/.summary.csv.partial", dir);
    FILE *f = fopen(p, "a");
    if (f) fputs("1,0,5,5,5,5,5,5,5,5\n1,1,5,5", f), fclose(f);
    raise(SIGKILL);
    _exit(3);
  }
  int status = 0;
  CHECK(pid > 0 && waitpid(pid, &status, 0) == pid);
  CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
}

/* What a kill in the middle of an HDF5 flush may leave: a file HDF5 cannot
 * read any more.  The resume never reads it. */
static void tear_h5(const char *dir) {
  char p[512];
  snprintf(p, sizeof p, "%s/.result.h5.partial", dir);
  CHECK(truncate(p, 1000) == 0);
}

/* A kill while a row was being appended to the journal: half a record. */
static void tear_journal(const char *dir, size_t bytes) {
  char p[512];
  snprintf(p, sizeof p, "%s/.result.journal", dir);
  FILE *f = fopen(p, "ab");
  CHECK(f != NULL);
  if (!f) return;
  static const unsigned char junk[64] = {0x52, 0x4f, 0x57, 0, 1, 2, 3, 4, 2};
  CHECK(fwrite(junk, 1, bytes, f) == bytes);
  fclose(f);
}

static void check_refused(const char *dir, int dim, size_t ncomp, size_t nsolid, size_t nres,
                          const char *want) {
  gs_model m;
  make_model(&m, dim, ncomp, nsolid);
  double *y = calloc(m.nstate, sizeof *y), *led = calloc(m.nledger, sizeof *led), t = -1;
  double res[NRES + 1];
  gs_error err = {0, ""};
  gs_output *o = gs_output_resume(dir, &m, nres, &t, y, led, res, &err);
  CHECK(o == NULL);
  if (o) gs_output_finish(o, 0, &err);
  CHECK(strstr(err.msg, want) != NULL);
  if (!strstr(err.msg, want)) fprintf(stderr, "got: %s\nwant: %s\n", err.msg, want);
  CHECK(exists(dir, ".result.journal")); /* a refused resume keeps the run's data */
  free(y);
  free(led);
  gs_model_free(&m);
}

static void test_resume(void) {
  char dir[256], want[768];
  snprintf(dir, sizeof dir, "%s/resume", base);
  gs_model m;
  make_model(&m, 2, 2, 20);
  killed_run(dir, &m);
  CHECK(exists(dir, ".result.journal") && !exists(dir, "result.h5"));
  tear_h5(dir);
  tear_journal(dir, 9);

  snprintf(want, sizeof want,
           "cannot resume: %s/.result.journal was written for a different grid (axis 'solid' "
           "has 20 cells, case has 30)",
           dir);
  check_refused(dir, 2, 2, 30, NRES, want);
  check_refused(dir, 2, 3, 20, NRES, "(2 compartments, case has 3)");
  check_refused(dir, 3, 2, 20, NRES, "(2 axes, case has 3)");
  check_refused(dir, 2, 2, 20, NRES + 1, "keeping 3 integrator values per output time, this case keeps 4");

  gs_error err;
  double *y = calloc(m.nstate, sizeof *y), *led = calloc(m.nledger, sizeof *led), t = -1;
  double *wy = malloc(m.nstate * sizeof *wy), *wl = malloc(m.nledger * sizeof *wl);
  double res[NRES], wres[NRES];
  gs_output *o = gs_output_resume(dir, &m, NRES, &t, y, led, res, &err);
  CHECK(o != NULL);
  if (!o) {
    fprintf(stderr, "%s\n", err.msg);
    return;
  }
  fill(&m, 1, wy, wl);
  fill_resume(1, wres);
  CHECK(t == time_of(1));
  CHECK(!memcmp(y, wy, m.nstate * sizeof *y));
  CHECK(!memcmp(led, wl, m.nledger * sizeof *led));
  CHECK(!memcmp(res, wres, sizeof res));
  check_csv(dir, ".summary.csv.partial", &m, 2); /* stray rows gone */
  /* on past the end of the first chunk of /number (51 times) */
  write_times(o, &m, 2, 60);
  CHECK(gs_output_finish(o, 1, &err) == GS_OK);
  check_result(dir, &m, 60);
  check_csv(dir, "summary.csv", &m, 60);
  CHECK(!exists(dir, ".result.h5.partial") && !exists(dir, ".result.journal"));
  free(y), free(led), free(wy), free(wl);
  gs_model_free(&m);
}

/* Rows appended but never committed are not resumed: a journal whose first
 * commit record was torn holds nothing to resume. */
static void test_uncommitted(void) {
  char dir[256], p[512];
  snprintf(dir, sizeof dir, "%s/uncommitted", base);
  gs_model m;
  make_model(&m, 1, 1, 4);
  killed_run(dir, &m);
  snprintf(p, sizeof p, "%s/.result.journal", dir);
  struct stat st;
  CHECK(stat(p, &st) == 0);
  /* cut the last commit record (16 bytes) in half: only the first output
   * time stays committed */
  CHECK(truncate(p, st.st_size - 8) == 0);
  double y[4], led[2], res[NRES], t = -1;
  gs_error err;
  gs_output *o = gs_output_resume(dir, &m, NRES, &t, y, led, res, &err);
  CHECK(o != NULL && t == time_of(0));
  if (o) CHECK(gs_output_finish(o, 0, &err) == GS_OK);
  gs_model_free(&m);
}

/* A committed row whose bytes changed (a torn write that the commit record
 * after it survived, or a disk error) fails its checksum: the resume rolls
 * back to the commit before it. */
static void test_corrupt_row(void) {
  char dir[256], p[512];
  snprintf(dir, sizeof dir, "%s/corrupt", base);
  gs_model m;
  make_model(&m, 1, 1, 4);
  killed_run(dir, &m);
  snprintf(p, sizeof p, "%s/.result.journal", dir);
  struct stat st;
  CHECK(stat(p, &st) == 0);
  FILE *f = fopen(p, "r+b");
  CHECK(f != NULL);
  if (f) { /* a byte of the last row's values, just before its commit record */
    CHECK(fseek(f, st.st_size - 16 - 3, SEEK_SET) == 0);
    int c = fgetc(f);
    CHECK(fseek(f, st.st_size - 16 - 3, SEEK_SET) == 0);
    fputc(c ^ 0x10, f);
    fclose(f);
  }
  double y[4], led[2], res[NRES], t = -1;
  gs_error err;
  gs_output *o = gs_output_resume(dir, &m, NRES, &t, y, led, res, &err);
  CHECK(o != NULL && t == time_of(0));
  if (o) CHECK(gs_output_finish(o, 0, &err) == GS_OK);
  gs_model_free(&m);
}

static void test_nothing_to_resume(void) {
  char dir[256], want[512];
  snprintf(dir, sizeof dir, "%s/empty", base);
  CHECK(mkdir(dir, 0777) == 0);
  gs_model m;
  make_model(&m, 1, 1, 4);
  double y[4], led[2], res[NRES], t;
  gs_error err = {0, ""};
  CHECK(gs_output_resume(dir, &m, NRES, &t, y, led, res, &err) == NULL);
  CHECK(err.code == GS_EIO);
  snprintf(want, sizeof want, "nothing to resume in %s (no .result.journal", dir);
  CHECK(!strncmp(err.msg, want, strlen(want)));
  /* opened, nothing written yet */
  gs_output *o = gs_output_open(dir, &m, "", "c", NRES, &err);
  CHECK(o != NULL);
  CHECK(gs_output_resume(dir, &m, NRES, &t, y, led, res, &err) == NULL);
  CHECK(strstr(err.msg, "holds no committed output time yet") != NULL);
  if (o) gs_output_finish(o, 0, &err);
  gs_model_free(&m);
}

static void test_bad_dir(void) {
  char file[256], dir[300];
  snprintf(file, sizeof file, "%s/plainfile", base);
  FILE *f = fopen(file, "w");
  CHECK(f != NULL);
  if (f) fclose(f);
  snprintf(dir, sizeof dir, "%s/sub", file);
  gs_model m;
  make_model(&m, 1, 1, 4);
  gs_error err = {0, ""};
  CHECK(gs_output_open(dir, &m, "", "c", NRES, &err) == NULL);
  CHECK(err.code == GS_EIO && strstr(err.msg, dir) != NULL);
  gs_model_free(&m);
}

int main(void) {
  snprintf(base, sizeof base, "/tmp/gs_test_output.XXXXXX");
  if (!mkdtemp(base)) {
    perror("mkdtemp");
    return 1;
  }
  for (int dim = 1; dim <= 3; dim++) test_roundtrip(dim);
  test_deflated();
  test_many_times(1e9, 3);
  test_many_times(0, 3);
  test_many_times(1e9, 96);
  for (int deflated = 0; deflated < 2; deflated++) {
    test_deferred(deflated ? 4096 : 6, 0);
    test_deferred(deflated ? 4096 : 6, 1e9);
  }
  test_parts_misused();
  test_abort();
  test_resume();
  test_uncommitted();
  test_corrupt_row();
  test_nothing_to_resume();
  test_bad_dir();
  if (!check_failures && !getenv("GS_TEST_KEEP")) {
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", base);
    CHECK(system(cmd) == 0);
  } else {
    fprintf(stderr, "test files kept in %s\n", base);
  }
  TEST_EXIT();
}
