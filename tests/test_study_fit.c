/* Fitting (src/study/fit.c): parameters recovered from noise-free synthetic
 * data (made by the same case at known values, 17 digits) to 1e-4 relative
 * from a distant start, inside log and linear ranges; and the data errors
 * (header, a time the case does not output, an unknown column).  Two
 * batches of different recipes measured as sieve fractions (written by an
 * observer of their own, gs_sieve_fractions at the true values) give the
 * true values back to 1e-4 relative too. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gransim/run.h"
#include "gransim/study.h"

static int has(const gs_error *e, const char *sub) {
  if (strstr(e->msg, sub)) return 1;
  fprintf(stderr, "  message \"%s\"\n  lacks \"%s\"\n", e->msg, sub);
  return 0;
}

/* 1-D constant-kernel aggregation; tight tolerances so that finite
 * differences of the outputs are smooth in the parameters */
static gs_cfg *fit_case(const char *beta0, const char *number, const char *times) {
  char text[1024];
  snprintf(text, sizeof text,
           "title: fit test\n"
           "grid:\n"
           "  axes:\n"
           "    - {name: solid, type: geometric, min: 1.0e-3, ratio: 1.5, cells: 30, zero_first: true}\n"
           "initial: {type: exponential, number: %s, mean: 0.01}\n"
           "mechanisms:\n"
           "  - type: aggregation\n"
           "    kernel: {type: constant, beta0: %s}\n"
           "solver: {rtol: 1.0e-12, atol: 1.0e-20}\n"
           "output: {times: [%s]}\n",
           number, beta0, times);
  gs_error e = {0};
  gs_cfg *cfg = gs_cfg_load_string(text, "fit.yaml", &e);
  CHECK(cfg);
  return cfg;
}

static void write_file(const char *path, const char *text) {
  FILE *f = fopen(path, "w");
  fputs(text, f);
  fclose(f);
}

/* The sieve fractions of a run at its output times, into a data file:
 * time,sieve_<lo>_<hi>,... (edges in micrometres). */
typedef struct {
  const gs_case *c;
  FILE *f;
  const double *edges; /* m */
  size_t nclass;
} sieve_writer;

static int sieve_output(void *self, const gs_run_view *run, double t, const double *Y, int *stop,
                        gs_error *err) {
  (void)run, (void)stop, (void)err;
  sieve_writer *w = self;
  if (t == 0) return GS_OK;
  double frac[8];
  gs_sieve_fractions(&w->c->model, Y, 0, w->edges, w->nclass, frac);
  fprintf(w->f, "%.17g", t);
  for (size_t k = 0; k < w->nclass; k++) fprintf(w->f, ",%.17g", frac[k]);
  fprintf(w->f, "\n");
  return GS_OK;
}

static void write_sieves(const gs_cfg *cfg, const char *key, const char *value, const char *path,
                         const double *edges, size_t nclass) {
  char *keys[1] = {(char *)key}, *values[1] = {(char *)value};
  gs_design d = {.nkeys = 1, .nruns = 1, .keys = keys, .values = values};
  gs_case c;
  gs_error e = {0};
  CHECK(gs_study_case(cfg, &d, 0, &c, &e) == GS_OK);
  sieve_writer w = {.c = &c, .f = fopen(path, "w"), .edges = edges, .nclass = nclass};
  CHECK(w.f != NULL);
  fprintf(w.f, "time [s]");
  for (size_t k = 0; k < nclass; k++) fprintf(w.f, ",sieve_%.17g_%.17g", edges[k] * 1e6, edges[k + 1] * 1e6);
  fprintf(w.f, "\n");
  static const gs_observer_type type = {.name = "sieves", .output = sieve_output};
  gs_observer ob = {.type = &type, .self = &w};
  gs_run_options opt = {.observers = &ob, .nobservers = 1};
  gs_run_report rep;
  CHECK(gs_case_run(&c, &opt, NULL, &rep, &e) == GS_OK);
  fclose(w.f);
  gs_case_free(&c);
}

/* Two batches of different initial numbers (their recipes), measured on
 * four sieves at 1, 2 and 4: beta0 and the initial mean size recovered. */
static void sieve_batches(const char *dir) {
  gs_cfg *truth = fit_case("0.7", "1.3", "0.5, 1, 2, 4");
  const double edges[5] = {0, 0.2, 0.3, 0.4, INFINITY};
  char a[300], b[300], yaml[300];
  snprintf(a, sizeof a, "%s/a.csv", dir);
  snprintf(b, sizeof b, "%s/b.csv", dir);
  write_sieves(truth, "initial.number", "1.3", a, edges, 4);
  write_sieves(truth, "initial.number", "2.5", b, edges, 4);
  gs_cfg_free(truth);
  snprintf(yaml, sizeof yaml, "%s/batches.yaml", dir);
  write_file(yaml, "sieves: [0, 0.2, 0.3, 0.4, .inf]\n"
                   "batches:\n"
                   "  - {name: A, data: a.csv, set: {initial.number: 1.3}}\n"
                   "  - {name: B, data: b.csv, set: {initial.number: 2.5}}\n");
  gs_error e = {0};
  gs_fit_batches bs;
  CHECK(gs_fit_batches_read(yaml, &bs, &e) == GS_OK);
  if (e.code) fprintf(stderr, "%s\n", e.msg);
  CHECK(bs.n == 2 && bs.nsieves == 5 && isinf(bs.sieves[4]) && bs.batch[1].data.ncols == 4);
  gs_cfg *start = fit_case("3", "1", "0.5, 1, 2, 4");
  gs_study_axis p[2];
  CHECK(!gs_study_parse_range("mechanisms.0.kernel.beta0=0.01:100:log", &p[0], &e));
  CHECK(!gs_study_parse_range("initial.mean=0.002:0.05:log", &p[1], &e));
  gs_fit_result res;
  CHECK(gs_fit_run_batches(start, p, 2, &bs, NULL, &res, &e) == GS_OK);
  if (e.code) fprintf(stderr, "%s\n", e.msg);
  if (res.x) {
    printf("sieve batches: beta0 %.10g, initial.mean %.10g; %ld runs\n", res.x[0], res.x[1], res.runs);
    CHECK_REL(res.x[0], 0.7, 1e-4);
    CHECK_REL(res.x[1], 0.01, 1e-4);
    CHECK(res.nresid == 32 && !res.unidentified[0] && !res.unidentified[1]);
  }
  gs_fit_result_free(&res);
  gs_fit_batches_free(&bs);
  for (int i = 0; i < 2; i++) gs_study_axis_free(&p[i]);
  gs_cfg_free(start);
}

int main(void) {
  char dir[] = "/tmp/gransim-test-fit-XXXXXX";
  CHECK(mkdtemp(dir));
  char data_path[256];
  snprintf(data_path, sizeof data_path, "%s/data.csv", dir);
  gs_error e = {0};

  /* the synthetic data: the true case's M0 and d50 at the output times,
   * gathered by a sweep of one run per output time (its steps differ from
   * the fitted case's, which stops at all four: by ~rtol) */
  gs_cfg *truth = fit_case("0.7", "1.3", "1");
  gs_study_axis end;
  CHECK(!gs_study_parse_set("output.times.0=0.5,1,2,4", &end, &e));
  gs_design d;
  CHECK(gs_design_grid(&end, 1, &d, &e) == GS_OK);
  char out[300];
  snprintf(out, sizeof out, "%s/truth", dir);
  gs_sweep_options so = {.out_dir = out, .threads = 1};
  gs_sweep_report rep;
  CHECK(gs_sweep_run(truth, &d, &so, &rep, &e) == GS_OK && rep.failed == 0);
  char sweep_csv[400], line[1024];
  snprintf(sweep_csv, sizeof sweep_csv, "%s/sweep.csv", out);
  FILE *f = fopen(sweep_csv, "r"), *g = fopen(data_path, "w");
  CHECK(f && g);
  if (!f || !g) TEST_EXIT();
  fprintf(g, "time,M0,d50_c1\n");
  CHECK(fgets(line, sizeof line, f) != NULL); /* header */
  while (fgets(line, sizeof line, f)) {
    char *field[12];
    size_t n = 0;
    for (char *p = strtok(line, ","); p && n < 12; p = strtok(NULL, ",")) field[n++] = p;
    /* run,status,output.times.0,M0,M1_solid,d10_c1,d50_c1,... */
    fprintf(g, "%s,%s,%s\n", field[2], field[3], field[6]);
  }
  fclose(f);
  fclose(g);
  gs_design_free(&d);
  gs_study_axis_free(&end);
  gs_cfg_free(truth);

  char sweep_path[300]; /* a copy of the good data */
  snprintf(sweep_path, sizeof sweep_path, "%s/good.csv", dir);
  {
    FILE *in = fopen(data_path, "r"), *out = fopen(sweep_path, "w");
    int ch;
    while (in && out && (ch = fgetc(in)) != EOF) fputc(ch, out);
    if (in) fclose(in);
    if (out) fclose(out);
  }
  gs_fit_data data;
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_OK);
  CHECK(data.ntimes == 4 && data.ncols == 2);
  gs_study_axis p[2];
  CHECK(!gs_study_parse_range("mechanisms.0.kernel.beta0=0.01:100:log", &p[0], &e));
  CHECK(!gs_study_parse_range("initial.number=0.1:10", &p[1], &e));
  gs_cfg *start = fit_case("3", "0.4", "0.5, 1, 2, 4");
  gs_fit_result res;
  CHECK(gs_fit_run(start, p, 2, &data, &res, &e) == GS_OK);
  if (res.x) {
    CHECK_REL(res.x[0], 0.7, 1e-4);
    CHECK_REL(res.x[1], 1.3, 1e-4);
    CHECK(res.stderr_x[0] < 1e-4 && res.stderr_x[1] < 1e-4);
    CHECK_REL(res.corr[0], 1, 1e-12);
    CHECK(fabs(res.corr[1]) <= 1 && res.corr[1] == res.corr[2]);
    CHECK(res.r2 > 1 - 1e-12 && res.converged);
  }
  gs_fit_result_free(&res);

  /* a data time the case does not output */
  data.times[1] = 1.5;
  CHECK(gs_fit_run(start, p, 2, &data, &res, &e) == GS_EINPUT);
  CHECK(has(&e, "data.csv:3: column 1 (time) = 1.5 is not an output time of the case"));
  gs_fit_result_free(&res);
  data.times[1] = 1;
  /* an unknown column */
  free(data.names[1]);
  data.names[1] = strdup("d55_c1");
  CHECK(gs_fit_run(start, p, 2, &data, &res, &e) == GS_EINPUT);
  CHECK(has(&e, "data column 'd55_c1' is no output of the case; known: M0, M1_solid, d10_c1"));
  gs_fit_result_free(&res);
  gs_fit_data_free(&data);
  /* a key the case lacks */
  gs_study_axis bad;
  CHECK(!gs_study_parse_range("mechanisms.0.kernel.beta=1:2", &bad, &e));
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_OK);
  CHECK(gs_fit_run(start, &bad, 1, &data, &res, &e) == GS_EINPUT);
  CHECK(has(&e, "no 'beta' in mechanisms[0].kernel"));
  gs_fit_data_free(&data);
  gs_study_axis_free(&bad);

  /* data files */
  write_file(data_path, "t,M0\n1,2\n");
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT && has(&e, "expected a header 'time,NAME,...'"));
  write_file(data_path, "time,M0\n1,2,3\n");
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT && has(&e, "data.csv:2: 3 fields, the header has 2"));
  write_file(data_path, "time,M0\n1,abc\n");
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT && has(&e, "data.csv:2: column 2 (M0) = 'abc': expected a finite number"));
  write_file(data_path, "time,M0\n");
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT && has(&e, "no data rows"));
  write_file(data_path, "time,M0\n1,2\nend,3\n4,5\n");
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT &&
        has(&e, "data.csv:4: a row after the time 'end' (line 3): end is the last"));
  write_file(data_path, "time,M0\n1,end\n");
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT &&
        has(&e, "data.csv:2: column 2 (M0) = 'end': expected a finite number"));

  /* the time 'end': the run's last output time (4 here) */
  {
    FILE *in = fopen(sweep_path, "r"), *out = fopen(data_path, "w");
    char row[512];
    int k = 0;
    while (in && out && fgets(row, sizeof row, in)) {
      if (k++ == 4) { /* the row at t = 4 */
        char *comma = strchr(row, ',');
        fprintf(out, "end%s", comma ? comma : "\n");
      } else {
        fputs(row, out);
      }
    }
    if (in) fclose(in);
    if (out) fclose(out);
    CHECK(gs_fit_data_read(data_path, &data, &e) == GS_OK && isinf(data.times[3]));
    gs_fit_result res_end;
    CHECK(gs_fit_run(start, p, 2, &data, &res_end, &e) == GS_OK);
    if (res_end.x) {
      CHECK_REL(res_end.x[0], 0.7, 1e-4);
      CHECK_REL(res_end.x[1], 1.3, 1e-4);
    }
    gs_fit_result_free(&res_end);
    gs_fit_data_free(&data);
  }

  for (int i = 0; i < 2; i++) gs_study_axis_free(&p[i]);
  gs_cfg_free(start);
  sieve_batches(dir);
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0);
  TEST_EXIT();
}
