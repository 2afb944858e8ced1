/* Insertion from DEM case files (src/dem/case_dem.c, insertion.c, run_dem.c):
 *  - lognormal radii (GSL, fixed seed, 30,000 particles): without min/max
 *    truncated to median * gsd^(-/+3), the sample median and geometric sd of
 *    the radius match the (truncated) distribution within 4 standard errors;
 *    with min/max, every radius lies in the range and the mean of ln r is the
 *    truncated normal's; mass fractions split the mass between a lognormal and
 *    another lognormal class as asked (the truncated third moment);
 *  - feeds: a mass rate and a number rate over a time window insert
 *    rate x window to within one particle's mass (exactly, for numbers), and
 *    only inside the window. */
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_sort.h>
#include <gsl/gsl_statistics_double.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dem_testlib.h"
#include "gransim/dem.h"

/* Load and run a case in the scratch directory (NULL when it does not load). */
static gs_dem_case *run_case(const char *name, const char *yaml) {
  gs_dem_case *c = dt_load(name, yaml);
  if (c) dt_run(c, name);
  return c;
}

static const char *LOGN =
    "dem:\n"
    "  time_step: 2.0e-6\n"
    "  duration: 2.0e-6\n"
    "  gravity: [0, 0, 0]\n"
    "  seed: 11\n"
    "  box: {lo: [-0.01, -0.01, -0.01], hi: [0.16, 0.16, 0.16]}\n"
    "materials:\n"
    "  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}\n"
    "classes:\n"
    "  - {name: free, radius: {type: lognormal, median: 1.0e-3, gsd: 1.4}, material: g}\n"
    "  - {name: cut, radius: {type: lognormal, median: 2.0e-3, gsd: 1.5, min: 1.8e-3, max: 4.0e-3}, material: g}\n"
    "fill:\n"
    "  - {region: {box: {lo: [0, 0, 0], hi: [0.15, 0.15, 0.15]}}, count: 30000, fractions: [0.5, 0.5],"
    " fractions_by: mass}\n";

static void test_lognormal(void) {
  gs_dem_case *c = run_case("logn", LOGN);
  if (!c) return;
  gs_dem_view v;
  gs_dem_get_view(c->dem, &v);
  CHECK(v.n == 30000);
  double *ln[2];
  size_t n[2] = {0, 0};
  double mass[2] = {0, 0}, rlo[2] = {HUGE_VAL, HUGE_VAL}, rhi[2] = {0, 0};
  ln[0] = malloc(v.n * sizeof(double));
  ln[1] = malloc(v.n * sizeof(double));
  for (size_t i = 0; i < v.n; i++) {
    int k = gs_dem_type_class(c->dem, v.type[i]);
    ln[k][n[k]++] = log(v.r[i]);
    mass[k] += v.m[i];
    rlo[k] = fmin(rlo[k], v.r[i]);
    rhi[k] = fmax(rhi[k], v.r[i]);
  }
  /* class 'free': ln r ~ N(ln 1 mm, ln 1.4) truncated at +-3 sd */
  const double mu0 = log(1e-3), s0 = log(1.4);
  const double sd_trunc = s0 * sqrt(1 - 6 * gsl_ran_ugaussian_pdf(3) / (2 * gsl_cdf_ugaussian_P(3) - 1));
  gsl_sort(ln[0], 1, n[0]);
  double med = gsl_stats_median_from_sorted_data(ln[0], 1, n[0]);
  double sd = gsl_stats_sd(ln[0], 1, n[0]);
  double se_med = 1.2533 * sd_trunc / sqrt((double)n[0]), se_sd = sd_trunc / sqrt(2.0 * n[0]);
  fprintf(stderr, "lognormal (median 1 mm, gsd 1.4), %zu particles: median %.5g mm (%.2f se off), gsd %.5f "
          "(truncated: %.5f; %.2f se off), radii %.4g..%.4g mm\n", n[0], 1e3 * exp(med), (med - mu0) / se_med,
          exp(sd), exp(sd_trunc), (sd - sd_trunc) / se_sd, 1e3 * rlo[0], 1e3 * rhi[0]);
  CHECK(fabs(med - mu0) < 4 * se_med);
  CHECK(fabs(sd - sd_trunc) < 4 * se_sd);
  CHECK(rlo[0] >= 1e-3 / pow(1.4, 3) && rhi[0] <= 1e-3 * pow(1.4, 3));
  /* class 'cut': truncated to [1.8, 4] mm; mean of ln r of the truncated normal */
  const double mu1 = log(2e-3), s1 = log(1.5);
  const double a = (log(1.8e-3) - mu1) / s1, b = (log(4e-3) - mu1) / s1;
  const double Z = gsl_cdf_ugaussian_P(b) - gsl_cdf_ugaussian_P(a);
  const double pa = gsl_ran_ugaussian_pdf(a), pb = gsl_ran_ugaussian_pdf(b);
  const double mean_t = mu1 + s1 * (pa - pb) / Z;
  const double sd_t = s1 * sqrt(1 + (a * pa - b * pb) / Z - (pa - pb) * (pa - pb) / (Z * Z));
  double m1 = gsl_stats_mean(ln[1], 1, n[1]), se1 = sd_t / sqrt((double)n[1]);
  fprintf(stderr, "lognormal (median 2 mm, gsd 1.5) in [1.8, 4] mm, %zu particles: radii %.4g..%.4g mm, mean ln r "
          "%.5f (truncated normal %.5f, %.2f se off), sd %.4f (%.4f)\n", n[1], 1e3 * rlo[1], 1e3 * rhi[1], m1, mean_t,
          (m1 - mean_t) / se1, gsl_stats_sd(ln[1], 1, n[1]), sd_t);
  CHECK(rlo[1] >= 1.8e-3 && rhi[1] <= 4e-3);
  CHECK(fabs(m1 - mean_t) < 4 * se1);
  /* mass fractions 1:1: number fractions from E[r^3] of each truncated
   * lognormal (here by quadrature over ln r); a crowded region must not
   * favour the small class (sd of the number fraction sqrt(p(1-p)/N), of the
   * mass fraction about 0.0065 for these distributions) */
  double m3[2];
  const double mus[2] = {mu0, mu1}, sgs[2] = {s0, s1};
  const double lo[2] = {-3, a}, hi[2] = {3, b};
  for (int k = 0; k < 2; k++) {
    double num = 0, den = 0, h = (hi[k] - lo[k]) / 20000;
    for (int q = 0; q < 20000; q++) {
      double z = lo[k] + (q + 0.5) * h, w = gsl_ran_ugaussian_pdf(z);
      num += w * exp(3 * (mus[k] + sgs[k] * z));
      den += w;
    }
    m3[k] = num / den;
  }
  double p0 = (0.5 / m3[0]) / (0.5 / m3[0] + 0.5 / m3[1]), got0 = (double)n[0] / (double)v.n;
  double share = mass[0] / (mass[0] + mass[1]), sd_p = sqrt(p0 * (1 - p0) / (double)v.n);
  fprintf(stderr, "mass fractions asked 0.5 / 0.5, got %.4f / %.4f; number fraction of 'free' %.4f (want %.4f, "
          "%.2f sd off)\n", share, 1 - share, got0, p0, (got0 - p0) / sd_p);
  CHECK(fabs(share - 0.5) < 0.02);
  CHECK(fabs(got0 - p0) < 3 * sd_p);
  free(ln[0]);
  free(ln[1]);
  gs_dem_case_free(c);
}

static const char *FEED =
    "dem:\n"
    "  time_step: 5.0e-6\n"
    "  duration: 0.03\n"
    "  gravity: [0, 0, 0]\n"
    "  box: {lo: [-0.01, -0.01, -0.01], hi: [0.11, 0.06, 0.06]}\n"
    "materials:\n"
    "  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, density: 500}\n"
    "classes:\n"
    "  - {name: a, radius: 1.0e-3, material: g}\n"
    "  - {name: b, radius: [1.0e-3, 1.4e-3], material: g}\n"
    "feed:\n"
    "  - {region: {box: {lo: [0, 0, 0], hi: [0.05, 0.05, 0.05]}}, mass_rate: 0.05, every: 0.002,"
    " start: 0.005, end: 0.025, fractions: [1, 0]}\n"
    "  - {region: {box: {lo: [0.055, 0, 0], hi: [0.1, 0.05, 0.05]}}, number_rate: 10000, every: 0.003,"
    " start: 0.004, end: 0.0235, fractions: [0, 1]}\n"
    "output: {every: 0.005}\n";

static void test_feed(void) {
  gs_dem_case *c = run_case("feed", FEED);
  if (!c) return;
  gs_dem_view v;
  gs_dem_get_view(c->dem, &v);
  double mass[2] = {0, 0}, t0[2] = {HUGE_VAL, HUGE_VAL}, t1[2] = {0, 0};
  long n[2] = {0, 0};
  for (size_t i = 0; i < v.n; i++) {
    int k = gs_dem_type_class(c->dem, v.type[i]);
    n[k]++;
    mass[k] += v.m[i];
    t0[k] = fmin(t0[k], v.t_in[i]);
    t1[k] = fmax(t1[k], v.t_in[i]);
  }
  const double m1 = 500 * 4.0 / 3 * M_PI * 1e-9; /* one class-a particle */
  fprintf(stderr, "mass feed 0.05 kg/s for 0.02 s: %ld particles, %.6g kg (want 1e-3 kg, within %.3g), inserted "
          "%.4f..%.4f s\n", n[0], mass[0], m1, t0[0], t1[0]);
  fprintf(stderr, "number feed 10000 /s for 0.0195 s: %ld particles (want 195), inserted %.4f..%.4f s\n", n[1],
          t0[1], t1[1]);
  CHECK(fabs(mass[0] - 1e-3) <= m1 * (1 + 1e-9));
  CHECK(n[1] == 195);
  CHECK(t0[0] >= 0.005 - 1e-9 && t1[0] < 0.025);
  CHECK(t0[1] >= 0.004 - 1e-9 && t1[1] < 0.0235);
  gs_dem_case_free(c);
}

int main(void) {
  if (dt_scratch_begin("test-dem-feed")) TEST_EXIT();
  test_lognormal();
  test_feed();
  dt_scratch_end();
  TEST_EXIT();
}
