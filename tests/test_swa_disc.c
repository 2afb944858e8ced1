/* The discretisation report and the resource limits of SWA cases
 * (src/swa/disc.c, src/swa/resources.c):
 *  - the moments of a distribution's draws (gs_swa_spec_moments), on which
 *    the stated sampling error rests, against 4e5 draws of a gamma and of
 *    `diameters` with equal and variable weights;
 *  - fixed seed: point entries are held exactly (sigma 0), every run's
 *    initial particles are counted, a feed is sampled as stated;
 *  - an ensemble of 12.6 million particles is compared on 10^7 draws;
 *  - statistical: over 400 seeds, the represented volume of an exponential
 *    entry deviates from the requested one by the stated standard error
 *    (mean of z = error / sigma near 0, variance near 1);
 *  - refusals: initial entries left without particles (a distortion
 *    sampling does not explain), memory and output above `limits`. */
#include <gsl/gsl_rng.h>
#include <math.h>

#include "check.h"
#include "swa/sim.h"
#include "swa/spec.h"
#include "test_swa.h"

static const char *GRID =
    "grid:\n  compartments: 1\n  axes:\n    - {name: solid, type: geometric, min: 1e-15, max: 1e-6, cells: 20}\n";

/* ---- moments against draws ---- */
static void check_moments(const char *spec_yaml, int coord) {
  gs_swa_case c;
  sw_case(sw_fmt("%ssolver: {method: swa, particles: 64, runs: 1}\ninitial:\n  - %s\noutput: {end: 1, count: 2}\n",
                 GRID, spec_yaml),
          &c);
  const char *key;
  const gs_swa_spec *sp = gs_swa_case_initial(&c, 0, &key);
  gs_swa_moments mo;
  gs_swa_spec_moments(sp, &mo);
  gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
  gsl_rng_set(r, 7);
  const double n = 4e5;
  double sw = 0, sw2 = 0, swx = 0, sw2x = 0, sw2x2 = 0;
  for (double i = 0; i < n; i++) {
    double x[GS_SWA_MAX_COORD], w;
    gs_swa_spec_sample(sp, r, x, &w);
    sw += w;
    sw2 += w * w;
    swx += w * x[coord];
    sw2x += w * w * x[coord];
    sw2x2 += w * w * x[coord] * x[coord];
  }
  gsl_rng_free(r);
  /* the first moments within 5 standard errors; the second moments (whose
   * estimates are heavy-tailed) within 5 % */
  const double mu = mo.mu[coord];
  CHECK(fabs(sw / n - 1) <= 5 * sqrt(fmax(mo.ew2 - 1, 1e-30) / n) + 1e-15);
  CHECK(fabs(swx / n / mu - 1) <= 5 * sqrt((mo.ew2x2[coord] / (mu * mu) - 1) / n));
  CHECK_REL(sw2 / n, mo.ew2, 0.05);
  CHECK_REL(sw2x / n, mo.ew2x[coord], 0.05);
  CHECK_REL(sw2x2 / n, mo.ew2x2[coord], 0.05);
  gs_swa_case_free(&c);
}

#define Q3 "q3: [0.05, 0.1, 0.2, 0.3, 0.2, 0.1, 0.05]"

static void test_moments(void) {
  check_moments("{type: gamma, number: 1e6, mean: 2e-12, shape: 3}", 0);
  check_moments("{type: diameters, number: 1e6, coordinate: solid, min: 1e-5, max: 1e-4, weighting: equal, " Q3 "}", 0);
  check_moments("{type: diameters, number: 1e6, coordinate: solid, min: 1e-5, max: 1e-4, weighting: variable, " Q3 "}", 0);
}

/* ---- fixed seed ---- */
static void test_fixed_seed(void) {
  gs_swa_case c;
  sw_case(sw_fmt("%ssolver: {method: swa, particles: 64, runs: 3, seed: 5}\n"
                 "initial:\n  - {type: point, number: 3e6, at: [2e-12]}\n"
                 "  - {type: exponential, number: 1e6, mean: [5e-12]}\n"
                 "mechanisms:\n  - {type: feed, rate: 100, start: 0, end: 2,\n"
                 "     distribution: {type: gamma, mean: [1e-12], shape: [4]}}\n"
                 "output: {end: 4, count: 2}\n",
                 GRID),
          &c);
  CHECK(c.ndisc == 3);
  /* 48 particles: 36 for the point entry, 12 for the exponential, per run */
  const gs_swa_disc *p = &c.disc[0], *e = &c.disc[1], *f = &c.disc[2];
  CHECK(strstr(p->key, "swa.yaml:7: initial[0]") != NULL);
  CHECK_REL(p->number[1], 3e6, 1e-14);
  CHECK_REL(p->volume[0][1], 6e-6, 1e-14);
  CHECK(p->particles == 3 * 36 && p->sigma[0] == 0 && p->sigma[1] == 0);
  CHECK(e->particles == 3 * 12);
  CHECK_REL(e->number[1], 1e6, 1e-14); /* equal weights: the number is exact */
  CHECK_REL(e->sigma[1], 1 / sqrt(36.0), 1e-12);
  CHECK(fabs(e->volume[0][1] / 5e-6 - 1) < 5 * e->sigma[1]);
  /* the feed: rate 100 for 2 s, sample volume 48 / 4e6, 3 runs */
  CHECK(strstr(f->key, "mechanisms[0].distribution") != NULL);
  CHECK(f->particles == ceil(100 * 2 * 48 / 4e6 * 3));
  CHECK_REL(f->number[0], 100, 1e-15);
  CHECK_REL(f->sigma[1], sqrt(0.25 / f->particles), 1e-12);
  CHECK(fabs(f->volume[0][1] / 1e-10 - 1) <= 5 * f->sigma[1]);
  char line[2048];
  gs_swa_disc_format(&c, e, line, sizeof line);
  CHECK(strstr(line, "the particles hold number 1e+06 (asked 1e+06), volume of 'solid' ") != NULL);
  CHECK(strstr(line, "expected from sampling 0.17 (one standard error of 36 particles), above the tolerance") != NULL);
  gs_swa_case_free(&c);
}

/* ---- the report is the runs' initial ensemble ---- */
static void test_is_the_run(void) {
  gs_swa_case c;
  sw_case(sw_fmt("%ssolver: {method: swa, particles: 64, runs: 3, seed: 9}\n"
                 "initial: {type: gamma, number: 1e6, mean: [5e-12], shape: [2]}\noutput: {end: 1, count: 2}\n",
                 GRID),
          &c);
  sw_result r;
  CHECK(sw_run(&c, &r) == 0);
  /* M0 and M1 at the first output time (t = 0), means over the runs */
  CHECK_REL(sw_col(&c, &r, r.mean, 0, 0, 0), c.disc[0].number[1], 1e-12);
  CHECK_REL(sw_col(&c, &r, r.mean, 0, 0, 1), c.disc[0].volume[0][1], 1e-12);
  CHECK(fabs(c.disc[0].volume[0][1] / 5e-6 - 1) > 1e-6); /* a sample, not the request */
  sw_free(&r);
  gs_swa_case_free(&c);
}

/* ---- an ensemble too large to draw at check time: a sample of it ---- */
static void test_large(void) {
  gs_swa_case c;
  /* 0.75 x 2^24 = 12.6 million particles in one run: compared on 10^7 draws */
  sw_case(sw_fmt("%ssolver: {method: swa, particles: 16777216, runs: 1}\n"
                 "initial: {type: exponential, number: 1e9, mean: [5e-12]}\noutput: {end: 1, count: 2}\n",
                 GRID),
          &c);
  CHECK(c.disc[0].particles == 1e7);
  CHECK_REL(c.disc[0].number[1], 1e9, 1e-12);
  CHECK_REL(c.disc[0].sigma[1], 1 / sqrt(1e7), 1e-9);
  CHECK(fabs(c.disc[0].volume[0][1] / 5e-3 - 1) < 5 * c.disc[0].sigma[1]);
  gs_swa_case_free(&c);
}

/* ---- the stated error is the error ---- */
static void test_statistics(void) {
  const int seeds = 400;
  double sz = 0, szz = 0;
  for (int s = 1; s <= seeds; s++) {
    gs_swa_case c;
    sw_case(sw_fmt("%ssolver: {method: swa, particles: 64, runs: 1, seed: %d}\n"
                   "initial: {type: exponential, number: 1e6, mean: [5e-12]}\noutput: {end: 1, count: 2}\n"
                   "discretisation: {tolerance: 10}\n",
                   GRID, s),
            &c);
    const gs_swa_disc *r = &c.disc[0];
    double z = (r->volume[0][1] / r->volume[0][0] - 1) / r->sigma[1];
    sz += z;
    szz += z * z;
    gs_swa_case_free(&c);
  }
  double mean = sz / seeds, var = szz / seeds - mean * mean;
  /* 400 samples: the mean of z has standard error 0.05; its variance about 0.07
   * (the sum of 48 exponentials is Gamma(48), nearly normal) */
  CHECK(fabs(mean) < 0.2);
  CHECK(var > 0.75 && var < 1.3);
  if (!(fabs(mean) < 0.2) || !(var > 0.75 && var < 1.3)) fprintf(stderr, "z: mean %g, variance %g\n", mean, var);
}

/* ---- refusals ---- */
/* yaml (freed) must be refused with a message holding a and b */
static void refused(char *yaml, const char *a, const char *b) {
  const char *msg = sw_case_error(yaml);
  free(yaml);
  fprintf(stderr, "refusal: %s\n", msg ? msg : "(none)");
  CHECK(msg && strstr(msg, a) && strstr(msg, b));
}

static void test_refusals(void) {
  /* 20 entries in a compartment of 16 particles: the last 4 get none */
  char *yaml = sw_fmt("%ssolver: {method: swa, particles: 16, fill_fraction: 1}\ninitial:\n", GRID);
  for (int i = 0; i < 20; i++) {
    char *more = sw_fmt("%s  - {type: point, number: 1e3, at: [%de-12]}\n", yaml, i + 1);
    free(yaml);
    yaml = more;
  }
  char *full = sw_fmt("%soutput: {end: 1, count: 2}\n", yaml);
  free(yaml);
  refused(full, "bad.yaml:23: initial[16]: the computational particles hold this distribution with a "
                "number of 0 instead of the requested 1000",
          "> discretisation.tolerance = 0.01");
  /* limits */
  refused(sw_fmt("%ssolver: {method: swa, particles: 4096, runs: 100}\n"
                 "initial: {type: point, number: 1e6, at: [2e-12]}\noutput: {end: 1, count: 1000}\n"
                 "limits: {memory_gb: 0.01}\n", GRID),
          "bad.yaml:5: solver: a run of this case needs at least 0.024", "more than limits.memory_gb = 0.01 GB");
  refused(sw_fmt("%ssolver: {method: swa, particles: 64}\n"
                 "initial: {type: point, number: 1e6, at: [2e-12]}\noutput: {end: 1, count: 100000}\n"
                 "limits: {output_gb: 0.01}\n", GRID),
          "bad.yaml:7: output: 100000 output times of 1 compartments x 20 grid cells would write 0.079",
          "more than limits.output_gb = 0.01 GB");
  refused(sw_fmt("%ssolver: {method: swa, particles: 64}\n"
                 "initial: {type: point, number: 1e6, at: [2e-12]}\noutput: {end: 1, count: 2}\n"
                 "discretisation: {tolerance: -1}\n", GRID),
          "discretisation.tolerance = '-1': expected a number > 0", "");
}

int main(void) {
  test_moments();
  test_fixed_seed();
  test_is_the_run();
  test_large();
  test_statistics();
  test_refusals();
  TEST_EXIT();
}
