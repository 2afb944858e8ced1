/* The sweep: every run of a design, OpenMP over runs, one journal row per
 * finished run, resumable (see gransim/study.h). */
#include "gransim/study.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>


#include "gransim/parallel.h"
#include "gransim/run.h"
#include "gransim/swa.h"
#include "study/study_internal.h"
#include "study/sweep_h5.h"

#define JOURNAL "runs.csv"
#define RESULT "sweep.csv"
#define BASE_CASE "base-case.yaml"

/* A growing text buffer (rows are built whole, then written with one write()). */
typedef struct {
  char *s;
  size_t n, cap;
} buf_t;

static int buf_add(buf_t *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int buf_add(buf_t *b, const char *fmt, ...) {
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    size_t room = b->cap - b->n;
    int w = vsnprintf(b->s ? b->s + b->n : NULL, room, fmt, ap);
    va_end(ap);
    if (w < 0) return -1;
    if ((size_t)w < room) {
      b->n += (size_t)w;
      return 0;
    }
    size_t cap = b->cap ? 2 * b->cap : 256;
    while (cap < b->n + (size_t)w + 1) cap *= 2;
    char *s = realloc(b->s, cap);
    if (!s) return -1;
    b->s = s;
    b->cap = cap;
  }
}

/* The error message as one CSV field: quoted, quotes doubled, one line. */
static int buf_add_quoted(buf_t *b, const char *msg) {
  if (buf_add(b, "\"")) return -1;
  for (const char *p = msg; *p; p++) {
    char c = *p == '\n' || *p == '\r' ? ' ' : *p;
    if (buf_add(b, c == '"' ? "\"\"" : "%c", c)) return -1;
  }
  return buf_add(b, "\"");
}

static int make_dir(const char *dir, gs_error *err) {
  char path[4096];
  snprintf(path, sizeof path, "%s", dir);
  for (char *p = path + 1;; p++) {
    if (*p == '/' || !*p) {
      char c = *p;
      *p = '\0';
      if (mkdir(path, 0777) && errno != EEXIST)
        return gs_error_set(err, GS_EIO, "cannot create directory '%s': %s", path, strerror(errno));
      *p = c;
      if (!c) break;
    }
  }
  return GS_OK;
}

/* The tables' header: each key and output with its unit, as summary.csv's
 * (run, status and error are a number and text). */
static int header_of(const gs_design *d, const gs_study_outputs *o, buf_t *h) {
  char field[512];
  int bad = buf_add(h, "run,status");
  for (size_t k = 0; k < d->nkeys; k++) {
    gs_study_header(d->keys[k], gs_study_key_unit(d->keys[k]), field, sizeof field);
    bad |= buf_add(h, ",%s", field);
  }
  for (size_t i = 0; i < o->ncol; i++) {
    gs_study_header(o->names[i], o->units[i], field, sizeof field);
    bad |= buf_add(h, ",%s", field);
  }
  return bad | buf_add(h, ",error\n");
}

/* The journal's rows: row[r] is run r's line (with its newline), NULL while
 * the run is not finished. */
typedef struct {
  char **row;
  size_t nruns;
} rows_t;

/* DIR/base-case.yaml: the case file the sweep started from, so that the
 * directory records what its rows vary and a resume with an edited case
 * (whose finished rows would no longer match) is refused. */
static int keep_case(const char *dir, const gs_cfg *base, int resume, gs_error *err) {
  char path[4096], tmp[4096];
  snprintf(path, sizeof path, "%s/" BASE_CASE, dir);
  const char *text = gs_cfg_source(base);
  FILE *f = resume ? fopen(path, "rb") : NULL;
  if (f) {
    size_t len = strlen(text), n = 0;
    char *buf = malloc(len + 2);
    if (buf) n = fread(buf, 1, len + 1, f);
    fclose(f);
    int same = buf && n == len && memcmp(buf, text, len) == 0;
    free(buf);
    return same ? GS_OK
                : gs_error_set(err, GS_EINPUT,
                               "cannot resume: the case file '%s' differs from '%s', the case "
                               "this sweep started from",
                               gs_cfg_name(base), path);
  }
  snprintf(tmp, sizeof tmp, "%s/." BASE_CASE ".partial", dir);
  f = fopen(tmp, "wb");
  int bad = !f;
  if (f) {
    bad = fputs(text, f) < 0;
    bad |= fclose(f) != 0;
  }
  if (!bad) bad = rename(tmp, path) != 0;
  if (bad) {
    int e = errno;
    remove(tmp);
    return gs_error_set(err, GS_EIO, "cannot write '%s': %s", path, strerror(e));
  }
  return GS_OK;
}

/* Gathers a run's outputs at the study's earlier output times (--at). */
typedef struct {
  const gs_study_outputs *o;
  double *v; /* the row's values: slot k at v + k * nbase */
} at_obs;

static int at_obs_output(void *self, const gs_run_view *run, double t, const double *Y, int *stop,
                         gs_error *err) {
  (void)stop, (void)err;
  const at_obs *a = self;
  for (size_t k = 0; k < a->o->ntimes; k++)
    if (fabs(t - a->o->times[k]) <= 1e-12 * fmax(1, fabs(t)))
      gs_study_outputs_eval_slot(a->o, &run->c->model, k + 1, t, Y, a->v + (k + 1) * a->o->nbase);
  return GS_OK;
}

static const gs_observer_type at_obs_type = {.name = "sweep-at", .output = at_obs_output};

/* One run: build, run, gather; the row it leaves in *row (error rows too). */
static void run_one(const gs_cfg *base, const gs_design *d, size_t r, const gs_study_outputs *o,
                    buf_t *row) {
  gs_error err = {0};
  gs_case c;
  double *y = NULL, *v = NULL;
  int rc = gs_study_case(base, d, r, &c, &err);
  if (!rc) rc = gs_study_outputs_fit(o, &c.model, &err);
  if (!rc) rc = gs_study_outputs_times_fit(o, c.times, c.ntimes, &err);
  if (!rc) {
    y = gs_malloc((c.model.nstate + c.model.nledger) * sizeof *y, &err);
    v = gs_malloc(o->ncol * sizeof *v, &err);
    rc = y && v ? GS_OK : GS_ENOMEM;
  }
  for (size_t i = 0; v && i < o->ncol; i++) v[i] = NAN;
  at_obs at = {.o = o, .v = v};
  const gs_observer obs = {.type = &at_obs_type, .self = &at};
  gs_run_options ropt = {.out_dir = NULL, .progress = 0, .one_process = 1, .observers = &obs,
                         .nobservers = o->ntimes ? 1 : 0};
  gs_run_report rep;
  if (!rc) rc = gs_case_run(&c, &ropt, y, &rep, &err);
  if (!rc) gs_study_outputs_eval(o, &c.model, c.times[c.ntimes - 1], y, v);
  buf_add(row, "%zu,%s", r + 1, rc ? "error" : "ok");
  for (size_t k = 0; k < d->nkeys; k++) buf_add(row, ",%s", d->values[r * d->nkeys + k]);
  for (size_t i = 0; i < o->ncol; i++) {
    if (rc) buf_add(row, ",nan");
    else buf_add(row, ",%.17g", v[i]);
  }
  buf_add(row, ",");
  if (rc) buf_add_quoted(row, err.msg[0] ? err.msg : "failed");
  buf_add(row, "\n");
  free(y);
  free(v);
  gs_case_free(&c);
}

/* Every run's case must build before any runs: a bad value in run 900 should
 * not surface after hours.  The first bad run (lowest index) is reported. */
static int check_runs(const gs_cfg *base, const gs_design *d, const gs_study_outputs *o,
                      int threads, size_t *which, gs_error *err) {
  size_t first_bad = d->nruns;
  gs_error bad = {0};
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (size_t r = 1; r < d->nruns; r++) {
    gs_error e = {0};
    gs_case c;
    int rc = gs_study_case(base, d, r, &c, &e);
    if (!rc) rc = gs_study_outputs_fit(o, &c.model, &e);
    if (!rc) rc = gs_study_outputs_times_fit(o, c.times, c.ntimes, &e);
    gs_case_free(&c);
    if (rc) {
#pragma omp critical(gs_sweep_check)
      if (r < first_bad) {
        first_bad = r;
        bad = e;
      }
    }
  }
  if (first_bad == d->nruns) return GS_OK;
  *which = first_bad;
  *err = bad;
  return err->code ? err->code : GS_EINPUT;
}

/* The values of run r, "key=value, ..." for messages. */
static void describe_run(const gs_design *d, size_t r, char *buf, size_t size) {
  size_t at = 0;
  buf[0] = '\0';
  for (size_t k = 0; k < d->nkeys && at < size; k++)
    at += (size_t)snprintf(buf + at, size - at, "%s%s=%s", k ? ", " : "", d->keys[k],
                           d->values[r * d->nkeys + k]);
}

static int write_result(const char *dir, const char *header, const rows_t *rows, gs_error *err) {
  char path[4096], tmp[4096];
  snprintf(path, sizeof path, "%s/%s", dir, RESULT);
  snprintf(tmp, sizeof tmp, "%s/.%s.partial", dir, RESULT);
  FILE *f = fopen(tmp, "w");
  if (!f) return gs_error_set(err, GS_EIO, "cannot write '%s': %s", tmp, strerror(errno));
  fputs(header, f);
  for (size_t r = 0; r < rows->nruns; r++)
    if (rows->row[r]) fputs(rows->row[r], f);
  if (fclose(f) || rename(tmp, path)) {
    remove(tmp);
    return gs_error_set(err, GS_EIO, "cannot write '%s': %s", path, strerror(errno));
  }
  return GS_OK;
}

int gs_sweep_run(const gs_cfg *base, const gs_design *d, const gs_sweep_options *opt,
                 gs_sweep_report *rep, gs_error *err) {
  memset(rep, 0, sizeof *rep);
  rep->runs = d->nruns;
  if (!opt->out_dir) return gs_error_set(err, GS_EINPUT, "a sweep needs an output directory");
  if (d->nruns == 0) return gs_error_set(err, GS_EINPUT, "the design has no runs");
  /* the keys first: a typo is named as such, not as some run's failure */
  gs_cfg *probe = gs_cfg_copy(base, err);
  if (!probe) return err->code;
  int rc = gs_swa_case_wanted(probe)
               ? gs_error_set(err, GS_EINPUT,
                              "%s: sweeps run sectional cases; solver.method: swa is not supported yet",
                              gs_cfg_name(base))
               : GS_OK;
  for (size_t k = 0; k < d->nkeys && !rc; k++)
    rc = gs_cfg_set(probe, d->keys[k], d->values[k], err);
  gs_cfg_free(probe);
  if (rc) return rc;

  const int threads = opt->threads > 0 ? opt->threads : omp_get_max_threads();
  /* each run single-threaded: runs are the parallel work; a run's own
   * parallel regions (rates over compartments) would only oversubscribe */
  omp_set_max_active_levels(1);
  gs_case c0;
  gs_study_outputs o;
  char what[1024];
  rc = gs_study_case(base, d, 0, &c0, err);
  if (rc) {
    describe_run(d, 0, what, sizeof what);
    gs_error_prefix(err, "run 1 (%s): ", what);
    return rc;
  }
  rc = gs_study_outputs_init(&o, &c0.model, opt->outputs, opt->noutputs, err);
  if (!rc) rc = gs_study_outputs_add_times(&o, opt->at, opt->nat, err);
  if (!rc) rc = gs_study_outputs_times_fit(&o, c0.times, c0.ntimes, err);
  if (rc && o.names) gs_study_outputs_free(&o);
  gs_case_free(&c0);
  if (rc) return rc;
  size_t r = 0;
  rc = check_runs(base, d, &o, threads, &r, err);
  if (rc) {
    /* the case reader's message names the key and value, not the run */
    describe_run(d, r, what, sizeof what);
    gs_error_prefix(err, "run %zu (%s): ", r + 1, what);
    gs_study_outputs_free(&o);
    return rc;
  }

  /* under MPI (gransim built with it, started by mpirun) the ranks share the
   * runs: rank 0 sets the journal up, every rank appends its own runs' rows,
   * and rank 0 writes the tables once all are done */
  const int rank = gs_parallel_rank(), size = gs_parallel_size();
  buf_t header = {0};
  rows_t rows = {.nruns = d->nruns, .row = calloc(d->nruns, sizeof(char *))};
  double *done = calloc(d->nruns, sizeof *done);
  char journal[4096];
  snprintf(journal, sizeof journal, "%s/" JOURNAL, opt->out_dir);
  if (header_of(d, &o, &header) || !rows.row || !done)
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  int fd = -1;
  if (rank == 0) {
    if (!rc) rc = make_dir(opt->out_dir, err);
    struct stat st;
    const int exists = !rc && stat(journal, &st) == 0;
    if (!rc && exists && !opt->resume)
      rc = gs_error_set(err, GS_EINPUT,
                        "'%s' holds the runs of an earlier sweep: add --resume to continue it, or "
                        "choose another --out",
                        journal);
    if (!rc) rc = keep_case(opt->out_dir, base, exists, err);
    if (!rc && exists) rc = gs_sweep_journal_read(journal, header.s, d, rows.row, &rep->skipped, err);
    if (!rc) {
      fd = open(journal, O_WRONLY | O_APPEND | O_CREAT, 0666);
      if (fd < 0) rc = gs_error_set(err, GS_EIO, "cannot open '%s': %s", journal, strerror(errno));
      /* a new journal, or one cut to nothing (killed while writing its header) */
      else if ((fstat(fd, &st) || st.st_size == 0) &&
               write(fd, header.s, header.n) != (ssize_t)header.n)
        rc = gs_error_set(err, GS_EIO, "cannot write '%s': %s", journal, strerror(errno));
    }
    for (size_t r = 0; !rc && r < d->nruns; r++) done[r] = rows.row[r] != NULL;
  }
  if (size > 1) {
    if (gs_parallel_max(rc) && !rc) rc = gs_error_set(err, GS_EIO, "the sweep failed on MPI rank 0");
    if (!rc) {
      gs_parallel_broadcast(done, d->nruns);
      if (rank && (fd = open(journal, O_WRONLY | O_APPEND)) < 0)
        rc = gs_error_set(err, GS_EIO, "cannot open '%s': %s", journal, strerror(errno));
    }
  }
  /* this rank's runs: every size-th of those not finished */
  size_t *mine = rc ? NULL : malloc(d->nruns * sizeof *mine), nmine = 0, npending = 0;
  if (!rc && !mine) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t r = 0; !rc && r < d->nruns; r++) {
    if (!done[r] && npending++ % (size_t)size == (size_t)rank) mine[nmine++] = r;
    if (done[r] && rank) rep->skipped++;
  }

  int io_failed = 0;
  if (!rc) {
    const int show = rank == 0 && (opt->progress >= 0 ? opt->progress : isatty(STDERR_FILENO));
    size_t nfailed = 0; /* of the runs run now, for the progress line */
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t i = 0; i < nmine; i++) {
      const size_t r = mine[i];
      buf_t row = {0};
      run_one(base, d, r, &o, &row);
#pragma omp critical(gs_sweep_journal)
      {
        /* one write() of the whole row: a kill leaves at most one torn row,
         * the last, which the resume cuts off */
        if (!row.s || write(fd, row.s, row.n) != (ssize_t)row.n) io_failed = errno ? errno : EIO;
        rows.row[r] = row.s;
        rep->ran++;
        if (show) {
          nfailed += row.s && strstr(row.s, ",error,") == strchr(row.s, ',');
          fprintf(stderr, "\rgransim sweep: %zu of %zu runs done (%zu failed%s)   ",
                  rep->skipped + rep->ran, d->nruns, nfailed, size > 1 ? ", MPI rank 0" : "");
          fflush(stderr);
        }
      }
    }
    if (show && rep->ran) fprintf(stderr, "\n");
  }
  if (fd >= 0) close(fd);
  free(mine);
  if (!rc && io_failed)
    rc = gs_error_set(err, GS_EIO, "cannot append to '%s': %s", journal, strerror(io_failed));
  if (size > 1) { /* also the barrier: every rank's rows are in the journal */
    double v[2] = {(double)rep->ran, (double)(rc != 0)};
    gs_parallel_sum(v, 2);
    rep->ran = (size_t)v[0];
    if (v[1] && !rc) rc = gs_error_set(err, GS_EIO, "the sweep failed on another MPI rank");
    if (!rc && rank == 0) { /* the other ranks' rows */
      size_t more = 0;
      rc = gs_sweep_journal_read(journal, header.s, d, rows.row, &more, err);
    }
  }
  if (!rc && rank == 0) {
    for (size_t r = 0; r < d->nruns; r++)
      if (rows.row[r] && strncmp(strchr(rows.row[r], ',') + 1, "error", 5) == 0) rep->failed++;
    rc = write_result(opt->out_dir, header.s, &rows, err);
    if (!rc) rc = gs_sweep_write_h5(opt->out_dir, d, &o, rows.row, err);
  }
  if (size > 1 && gs_parallel_max(rc) && !rc)
    rc = gs_error_set(err, GS_EIO, "the sweep failed on MPI rank 0");
  free(done);
  for (size_t r = 0; rows.row && r < d->nruns; r++) free(rows.row[r]);
  free(rows.row);
  free(header.s);
  gs_study_outputs_free(&o);
  return rc;
}
