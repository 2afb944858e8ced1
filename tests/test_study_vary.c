/* Case variations and the sweep (src/cfg gs_cfg_copy/find/set, src/study):
 * the setter and its errors; a run's case built from the varied tree equals,
 * bit for bit, the case of a file that says the same; the sweep gathers
 * exactly those outputs, records a failing run without stopping the others,
 * refuses a bad variation before running, and resumes a killed sweep
 * running only the runs not yet journaled. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gransim/run.h"
#include "gransim/study.h"
#include "study/study_internal.h"

static int has(const gs_error *e, const char *sub) {
  if (strstr(e->msg, sub)) return 1;
  fprintf(stderr, "  message \"%s\"\n  lacks \"%s\"\n", e->msg, sub);
  return 0;
}

/* A case whose 4-cell axis loses mass past its end by t = 1 when beta0 is
 * large (checks.max_loss fails the run); tiny beta0 keeps it. */
#define CASE_FMT                                                                                   \
  "title: sweep test\n"                                                                            \
  "grid:\n"                                                                                        \
  "  axes:\n"                                                                                      \
  "    - {name: solid, type: linear, min: 0, max: 4, cells: 4}\n"                                  \
  "initial: {type: cell, index: 1, number: 10}\n"                                                  \
  "mechanisms:\n"                                                                                  \
  "  - type: aggregation\n"                                                                        \
  "    redistribution: fixed_pivot\n"                                                              \
  "    kernel: {type: constant, beta0: %s}\n"                                                      \
  "solver: {rtol: %s}\n"                                                                           \
  "output: {end: 2, count: 3}\n"

static char *case_text(const char *beta0, const char *rtol) {
  static char buf[1024];
  snprintf(buf, sizeof buf, CASE_FMT, beta0, rtol);
  return buf;
}

static void test_setter(void) {
  gs_error e = {0};
  gs_cfg *cfg = gs_cfg_load_string(case_text("1", "1e-8"), "case.yaml", &e);
  CHECK(cfg);
  gs_cfg *copy = gs_cfg_copy(cfg, &e);
  CHECK(copy && !strcmp(gs_cfg_name(copy), "case.yaml") && !strcmp(gs_cfg_dir(copy), "."));
  CHECK(!strcmp(gs_cfg_source(copy), gs_cfg_source(cfg)));
  CHECK(gs_cfg_set(copy, "mechanisms.0.kernel.beta0", "2.5", &e) == GS_OK);
  CHECK(!strcmp(gs_cfg_scalar(gs_cfg_find(copy, "mechanisms.0.kernel.beta0", &e)), "2.5"));
  /* the original is untouched */
  CHECK(!strcmp(gs_cfg_scalar(gs_cfg_find(cfg, "mechanisms.0.kernel.beta0", &e)), "1"));
  CHECK(!strcmp(gs_cfg_scalar(gs_cfg_find(copy, "grid.axes.0.cells", &e)), "4"));
  /* a copy of a varied case keeps its values (optimise starts from them) */
  CHECK(gs_cfg_set_scalar(gs_cfg_find(copy, "solver", &e), "atol", "1e-3", &e) == GS_OK);
  gs_cfg *again = gs_cfg_copy(copy, &e);
  CHECK(again && !strcmp(gs_cfg_scalar(gs_cfg_find(again, "mechanisms.0.kernel.beta0", &e)), "2.5"));
  CHECK(again && !strcmp(gs_cfg_scalar(gs_cfg_find(again, "solver.atol", &e)), "1e-3"));
  gs_cfg_free(again);

  static const struct {
    const char *key, *msg;
  } bad[] = {
      {"mechanisms.0.kernel.beta1", "no 'beta1' in mechanisms[0].kernel (it has: type, beta0)"},
      {"mechanisms.1.kernel.beta0", "mechanisms has 1 entry (indices from 0), no 1"},
      {"mechanisms.x", "mechanisms is a list; expected an index"},
      {"solver.rtol.x", "solver.rtol is a value ('1e-8'), not a map or list"},
      {"solver..rtol", "empty part"},
      {"solver.", "empty part"},
      {"", "empty key"},
      {"nosuch", "no 'nosuch' in the top level"},
      {"mechanisms.0.kernel", "mechanisms[0].kernel is a map, not a single value"},
      {"grid.axes", "grid.axes is a list, not a single value"},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    gs_error b = {0};
    CHECK(gs_cfg_set(copy, bad[i].key, "1", &b) == GS_EINPUT);
    CHECK(has(&b, bad[i].msg));
  }
  gs_cfg_free(copy);
  gs_cfg_free(cfg);
}

/* The varied run equals the run of the file that says the same, bit for bit. */
static void test_same_as_file(void) {
  gs_error e = {0};
  gs_cfg *base = gs_cfg_load_string(case_text("1", "1e-8"), "case.yaml", &e);
  gs_study_axis ax[2];
  CHECK(!gs_study_parse_set("mechanisms.0.kernel.beta0=0.01,0.002", &ax[0], &e));
  CHECK(!gs_study_parse_set("solver.rtol=1e-6,1e-9", &ax[1], &e));
  gs_design d;
  CHECK(gs_design_grid(ax, 2, &d, &e) == GS_OK && d.nruns == 4);
  gs_case c, f;
  gs_study_outputs o;
  CHECK(gs_study_case(base, &d, 3, &c, &e) == GS_OK);
  CHECK(gs_study_outputs_init(&o, &c.model, (const char *const[]){"M2", "mean_solid"}, 2, &e) ==
        GS_OK);
  CHECK(o.ncol == 1 + 1 + 3 + 2);
  CHECK(!strcmp(o.names[0], "M0") && !strcmp(o.names[1], "M1_solid") &&
        !strcmp(o.names[3], "d50_c1") && !strcmp(o.names[6], "mean_solid_c1"));
  /* every column's unit, summary.csv's for its statistic */
  static const char *const want_units[] = {"1", "m^3", "m", "m", "m", "m^6", "m^3"};
  for (size_t i = 0; i < 7; i++) CHECK(o.units[i] && !strcmp(o.units[i], want_units[i]));
  gs_cfg *fcfg = gs_cfg_load_string(case_text("0.002", "1e-9"), "case.yaml", &e);
  CHECK(gs_case_from_cfg(fcfg, &f, &e) == GS_OK);
  size_t n = c.model.nstate + c.model.nledger;
  double *yc = calloc(n, sizeof *yc), *yf = calloc(n, sizeof *yf), vc[8], vf[8];
  gs_run_options opt = {.progress = 0};
  gs_run_report rep;
  CHECK(gs_case_run(&c, &opt, yc, &rep, &e) == GS_OK);
  CHECK(gs_case_run(&f, &opt, yf, &rep, &e) == GS_OK);
  CHECK(memcmp(yc, yf, n * sizeof *yc) == 0);
  gs_study_outputs_eval(&o, &c.model, c.times[c.ntimes - 1], yc, vc);
  gs_study_outputs_eval(&o, &f.model, f.times[f.ntimes - 1], yf, vf);
  CHECK(memcmp(vc, vf, o.ncol * sizeof *vc) == 0);
  gs_summary s;
  gs_summarize(&f.model, yf, 0, &s);
  CHECK(vc[0] == s.m0 && vc[1] == s.total[0] && vc[3] == s.d50 && vc[5] == s.m2);
  free(yc);
  free(yf);
  gs_case_free(&c);
  gs_case_free(&f);
  gs_study_outputs_free(&o);

  /* --outputs with an unknown column */
  CHECK(gs_study_case(base, &d, 0, &c, &e) == GS_OK);
  CHECK(gs_study_outputs_init(&o, &c.model, (const char *const[]){"d51"}, 1, &e) == GS_EINPUT);
  CHECK(has(&e, "unknown summary column 'd51'; known: M0, M1, M2, d10, d50, d90, mean_solid"));
  gs_case_free(&c);
  gs_design_free(&d);
  for (int i = 0; i < 2; i++) gs_study_axis_free(&ax[i]);
  gs_cfg_free(base);
}

static char *slurp(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  static char buf[1 << 16];
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  buf[n] = '\0';
  fclose(f);
  return strdup(buf);
}

static int count_lines(const char *s) {
  int n = 0;
  for (; *s; s++) n += *s == '\n';
  return n;
}

static void test_sweep(void) {
  char dir[] = "/tmp/gransim-test-study-XXXXXX";
  CHECK(mkdtemp(dir));
  char out[512], journal[600], result[600];
  snprintf(out, sizeof out, "%s/out", dir);
  snprintf(journal, sizeof journal, "%s/runs.csv", out);
  snprintf(result, sizeof result, "%s/sweep.csv", out);
  gs_error e = {0};
  gs_cfg *base = gs_cfg_load_string(case_text("1", "1e-8"), "case.yaml", &e);
  gs_study_axis ax;
  /* run 3 loses mass through the grid's end: a failed run among good ones */
  CHECK(!gs_study_parse_set("mechanisms.0.kernel.beta0=1e-4,2e-4,1,3e-4,5e-5", &ax, &e));
  gs_design d;
  CHECK(gs_design_grid(&ax, 1, &d, &e) == GS_OK);
  gs_sweep_options opt = {.out_dir = out, .threads = 2};
  gs_sweep_report rep;
  CHECK(gs_sweep_run(base, &d, &opt, &rep, &e) == GS_OK);
  CHECK(rep.runs == 5 && rep.ran == 5 && rep.skipped == 0 && rep.failed == 1);
  char *first = slurp(result);
  CHECK(first && count_lines(first) == 6);
  CHECK(first && strstr(first, "\n3,error,1,nan,nan,nan,nan,nan,\"at t = ") &&
        strstr(first, "checks.max_loss"));
  CHECK(first && strstr(first, "\n4,ok,3e-4,"));

  /* a sweep into a directory holding one needs --resume */
  CHECK(gs_sweep_run(base, &d, &opt, &rep, &e) == GS_EINPUT && has(&e, "add --resume"));

  /* a killed sweep: the journal holds the header, runs 1 and 2 and a torn row */
  char *j = slurp(journal);
  char *third = j;
  for (int i = 0; i < 3 && third; i++) third = strchr(third, '\n') + 1;
  FILE *f = fopen(journal, "w");
  fwrite(j, 1, (size_t)(third - j), f);
  fputs("3,ok,1,0.12", f);
  fclose(f);
  opt.resume = 1;
  CHECK(gs_sweep_run(base, &d, &opt, &rep, &e) == GS_OK);
  CHECK(rep.skipped == 2 && rep.ran == 3 && rep.failed == 1);
  char *second = slurp(result);
  CHECK(second && first && !strcmp(first, second));
  /* resuming a finished sweep runs nothing and writes the same table */
  CHECK(gs_sweep_run(base, &d, &opt, &rep, &e) == GS_OK);
  CHECK(rep.skipped == 5 && rep.ran == 0);

  /* a sweep killed while writing the journal's header starts over */
  f = fopen(journal, "w");
  fputs("run,stat", f);
  fclose(f);
  CHECK(gs_sweep_run(base, &d, &opt, &rep, &e) == GS_OK);
  CHECK(rep.skipped == 0 && rep.ran == 5);
  free(second);
  second = slurp(result);
  CHECK(second && first && !strcmp(first, second));

  /* resuming with another design is refused */
  gs_study_axis other;
  gs_design d2;
  CHECK(!gs_study_parse_set("mechanisms.0.kernel.beta0=1e-4,7e-4,1,3e-4,5e-5", &other, &e));
  CHECK(gs_design_grid(&other, 1, &d2, &e) == GS_OK);
  CHECK(gs_sweep_run(base, &d2, &opt, &rep, &e) == GS_EINPUT);
  CHECK(has(&e, "run 2 has another mechanisms.0.kernel.beta0 than this sweep's 7e-4"));
  gs_design_free(&d2);
  gs_study_axis_free(&other);

  /* a value the case reader rejects stops the sweep before any run, naming
   * the run, key and value */
  char out2[600];
  snprintf(out2, sizeof out2, "%s/bad", dir);
  gs_sweep_options opt2 = {.out_dir = out2};
  CHECK(!gs_study_parse_set("mechanisms.0.kernel.beta0=1e-4,-1", &other, &e));
  CHECK(gs_design_grid(&other, 1, &d2, &e) == GS_OK);
  CHECK(gs_sweep_run(base, &d2, &opt2, &rep, &e) == GS_EINPUT);
  CHECK(has(&e, "run 2 (mechanisms.0.kernel.beta0=-1): case.yaml:9: mechanisms[0].kernel.beta0 = '-1'"));
  CHECK(access(out2, F_OK) != 0); /* nothing written */
  gs_design_free(&d2);
  gs_study_axis_free(&other);

  free(first);
  free(second);
  free(j);
  char cmd[700];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0);
  gs_design_free(&d);
  gs_study_axis_free(&ax);
  gs_cfg_free(base);
}

/* The units of varied keys: from the key's last name that is not a list
 * index (docs/case-files.md's table); "case" where the model decides. */
static void test_key_units(void) {
  static const char *const want[][2] = {
      {"output.end", "s"},
      {"solver.rtol", "1"},
      {"output.times.0", "s"},
      {"mechanisms.2.sieves.1", "m"},
      {"materials.0.E", "Pa"},
      {"mechanisms.0.spray_heat_capacity", "J/(kg K)"},
      {"rotation.rpm", "rpm"},
      {"mechanisms.0.kernel.beta0", "case"},
      {"mechanisms.1.rate", "case"},
      {"grid.axes.0.max", "case"},
      {"e", "1"},
      {"0", "case"},
      {"", "case"},
  };
  for (size_t i = 0; i < sizeof want / sizeof *want; i++) {
    const char *u = gs_study_key_unit(want[i][0]);
    if (strcmp(u, want[i][1])) fprintf(stderr, "key '%s': unit '%s', expected '%s'\n", want[i][0], u, want[i][1]);
    CHECK(!strcmp(u, want[i][1]));
  }
  char h[64];
  gs_study_header("d50_c1", "m", h, sizeof h);
  CHECK(!strcmp(h, "d50_c1 [m]"));
}

int main(void) {
  test_key_units();
  test_setter();
  test_same_as_file();
  test_sweep();
  TEST_EXIT();
}
