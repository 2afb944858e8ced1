/* The fit's 95 % intervals hold the truth at their stated rate.  Data: M0
 * and d50 of a cheap 1-D aggregation case at four times (beta0 = 0.7, 1.3
 * initial granules), with Gaussian noise of 1 % of each column's RMS added
 * (GSL mt19937, fixed seed), fitted DRAWS times.  With 8 values and 2
 * parameters the intervals are x -+ t(0.975, 6) s.e.; of the 2 DRAWS
 * (parameter, draw) pairs the count inside must be no more than 3.5
 * binomial standard deviations below 0.95 of them, and at most 2 DRAWS - 2
 * (a true rate of 0.95 puts 199 or 200 inside with probability 4e-4):
 * intervals half as wide (coverage ~0.74) fail the first, intervals twice
 * as wide (coverage ~1) the second. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

#include "check.h"
#include "gransim/study.h"

#define DRAWS 100

static gs_cfg *cheap_case(void) {
  const char *text = "title: coverage\n"
                     "grid:\n"
                     "  axes:\n"
                     "    - {name: solid, type: geometric, min: 1.0e-3, ratio: 1.6, cells: 22, "
                     "zero_first: true}\n"
                     "initial: {type: exponential, number: 1.3, mean: 0.01}\n"
                     "mechanisms:\n"
                     "  - type: aggregation\n"
                     "    kernel: {type: constant, beta0: 0.7}\n"
                     "solver: {rtol: 1.0e-11, atol: 1.0e-20}\n"
                     "output: {times: [0.5, 1, 2, 4]}\n";
  gs_error e = {0};
  gs_cfg *cfg = gs_cfg_load_string(text, "coverage.yaml", &e);
  CHECK(cfg);
  return cfg;
}

int main(void) {
  static const char *const names[] = {"M0", "d50"};
  double times[4] = {0.5, 1, 2, 4}, truth[8], values[8];
  size_t lines[4] = {2, 3, 4, 5};
  gs_fit_data data = {.ntimes = 4, .ncols = 2, .times = times, .names = (char **)names,
                      .values = values, .path = "coverage", .lines = lines};
  gs_fit_batch b = {.name = "draw", .where = "draw", .data = data};
  gs_fit_batches bs = {.n = 1, .batch = &b};
  gs_cfg *cfg = cheap_case();
  gs_error e = {0};
  gs_fit_eval ev;
  CHECK(gs_fit_evaluate(cfg, NULL, 0, (double[1]){0}, &bs, &ev, &e) == GS_OK);
  if (e.code) {
    fprintf(stderr, "%s\n", e.msg);
    TEST_EXIT();
  }
  memcpy(truth, ev.model, sizeof truth);
  gs_fit_eval_free(&ev);
  double rms[2] = {0, 0};
  for (int t = 0; t < 4; t++)
    for (int j = 0; j < 2; j++) rms[j] += truth[2 * t + j] * truth[2 * t + j] / 4;
  for (int j = 0; j < 2; j++) rms[j] = sqrt(rms[j]);

  gs_study_axis p[2];
  CHECK(!gs_study_parse_range("mechanisms.0.kernel.beta0=0.01:100:log", &p[0], &e));
  CHECK(!gs_study_parse_range("initial.number=0.1:10", &p[1], &e));
  const double want[2] = {0.7, 1.3};
  gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
  gsl_rng_set(rng, 20261126);
  int inside = 0, fits = 0;
  long runs = 0;
  for (int draw = 0; draw < DRAWS; draw++) {
    for (int q = 0; q < 8; q++) values[q] = truth[q] + gsl_ran_gaussian(rng, 0.01 * rms[q % 2]);
    gs_fit_result r;
    if (gs_fit_run(cfg, p, 2, &data, &r, &e)) {
      fprintf(stderr, "draw %d: %s\n", draw, e.msg);
      CHECK(0);
      continue;
    }
    fits++;
    runs += r.runs;
    for (int k = 0; k < 2; k++) inside += r.ci_lo[k] <= want[k] && want[k] <= r.ci_hi[k];
    gs_fit_result_free(&r);
  }
  const double n = 2.0 * fits, mean = 0.95 * n, sd = sqrt(n * 0.95 * 0.05);
  printf("95 %% intervals: %d of %.0f hold the truth (expected %.1f +- %.1f); %ld model runs\n",
         inside, n, mean, sd, runs);
  CHECK(fits == DRAWS);
  CHECK(inside >= mean - 3.5 * sd && inside <= n - 2);
  gsl_rng_free(rng);
  for (int k = 0; k < 2; k++) gs_study_axis_free(&p[k]);
  gs_cfg_free(cfg);
  TEST_EXIT();
}
