/* Fitting (src/study/fit.c): parameters recovered from noise-free synthetic
 * data (made by the same case at known values, 17 digits) to 1e-4 relative
 * from a distant start, inside log and linear ranges; and the data errors
 * (header, a time the case does not output, an unknown column). */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
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
  CHECK(has(&e, "data time 1.5 is not an output time of the case"));
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
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT && has(&e, "column M0 = 'abc': expected a finite number"));
  write_file(data_path, "time,M0\n");
  CHECK(gs_fit_data_read(data_path, &data, &e) == GS_EINPUT && has(&e, "no data rows"));

  for (int i = 0; i < 2; i++) gs_study_axis_free(&p[i]);
  gs_cfg_free(start);
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  CHECK(system(cmd) == 0);
  TEST_EXIT();
}
