/* `gransim dem` writes the wall-impact table of the PBM's `dem_impact`
 * breakage selection: particles of two classes fly at prescribed speeds
 * (drawn from lognormals) and obliquely into a floor (small class) and a
 * ceiling (large class) without gravity, each hitting once.  The impact speed
 * U = |v - v_wall| at the start of the contact is the prescribed speed, so the
 * fitted mu and sigma of impact_table.csv must be the mean and sample sd of
 * ln U of those speeds, the rate one impact per particle per window, and the
 * per-wall tables must hold only their own wall's impacts.  Finally
 * `gransim check` accepts a PBM case whose breakage selection reads the table. */
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <gsl/gsl_statistics_double.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "dem/dem_case.h"
#include "gransim/dem.h"

#define NS 25 /* small particles, onto the floor */
#define NL 20 /* large particles, onto the ceiling */
#define DURATION 0.02

/* rows rate, mu, sigma of a 2-class impact table */
static int read_table(const char *path, double rate[2], double mu[2], double sigma[2]) {
  FILE *fp = fopen(path, "r");
  if (!fp) return -1;
  char line[4096];
  int row = -1;
  double *rows[3] = {rate, mu, sigma};
  while (fgets(line, sizeof line, fp)) {
    if (line[0] == '#') continue;
    if (!strncmp(line, "edges", 5)) {
      row = 0;
      continue;
    }
    if (row < 0 || row > 2 || sscanf(line, "%lf , %lf", &rows[row][0], &rows[row][1]) != 2) {
      fclose(fp);
      return -1;
    }
    row++;
  }
  fclose(fp);
  return row == 3 ? 0 : -1;
}

int main(void) {
  char dir[] = "/tmp/gransim-test-impacts-XXXXXX";
  if (!mkdtemp(dir)) {
    CHECK(!"mkdtemp");
    TEST_EXIT();
  }
  char path[1024], out[512];
  snprintf(path, sizeof path, "%s/impacts.yaml", dir);
  snprintf(out, sizeof out, "%s/out", dir);
  FILE *fp = fopen(path, "w");
  fprintf(fp,
          "dem:\n"
          "  time_step: 2.0e-6\n"
          "  duration: %g\n"
          "  gravity: [0, 0, 0]\n"
          "  box: {lo: [-0.2, -0.2, -0.01], hi: [0.2, 0.2, 0.04]}\n"
          "materials:\n"
          "  - {name: g, E: 8.0e6, nu: 0.2, e: 0.4, mu_s: 0.5, mu_r: 0.1, density: 500}\n"
          "classes:\n"
          "  - {name: small, radius: 1.0e-3, material: g}\n"
          "  - {name: large, radius: 1.5e-3, material: g}\n"
          "walls:\n"
          "  - {name: floor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: g}\n"
          "  - {name: ceiling, plane: {point: [0, 0, 0.03], normal: [0, 0, -1]}, material: g}\n"
          "statistics: {sample_every: 0.002}\n",
          DURATION);
  fclose(fp);
  gs_error err = {0};
  gs_dem_case *c = gs_dem_case_load(path, &err);
  CHECK(c != NULL);
  if (!c) {
    fprintf(stderr, "%s\n", err.msg);
    TEST_EXIT();
  }
  /* speeds from lognormals; 30 degrees off the wall normal, in the x-z plane;
   * one particle per y, so none of them ever meet */
  gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
  gsl_rng_set(rng, 5);
  double lnu_s[NS], lnu_l[NL];
  const double gap = 1e-3, sn = sin(M_PI / 6), cs = cos(M_PI / 6);
  for (int k = 0; k < NS + NL; k++) {
    int large = k >= NS;
    double u = large ? gsl_ran_lognormal(rng, 0.0, 0.3) : gsl_ran_lognormal(rng, log(0.5), 0.6);
    if (large) lnu_l[k - NS] = log(u);
    else lnu_s[k] = log(u);
    double r = large ? 1.5e-3 : 1.0e-3;
    double x[3] = {-0.1, -0.19 + 0.008 * k, large ? 0.03 - r - gap : r + gap};
    double v[3] = {u * sn, 0, large ? u * cs : -u * cs};
    CHECK(gs_dem_add_particle(c->dem, c->cls[large].type, r, x, v, NULL, &err) >= 0);
  }
  gsl_rng_free(rng);
  int rc = gs_dem_case_run(c, out, 0, &err);
  CHECK(rc == 0);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  gs_dem_view view;
  gs_dem_get_view(c->dem, &view);
  CHECK(view.n == NS + NL); /* nothing lost: N_i constant */

  double want_mu[2] = {gsl_stats_mean(lnu_s, 1, NS), gsl_stats_mean(lnu_l, 1, NL)};
  double want_sd[2] = {gsl_stats_sd(lnu_s, 1, NS), gsl_stats_sd(lnu_l, 1, NL)};
  double rate[2], mu[2], sigma[2];
  char tp[600];
  snprintf(tp, sizeof tp, "%s/impact_table.csv", out);
  CHECK(read_table(tp, rate, mu, sigma) == 0);
  for (int i = 0; i < 2; i++) {
    fprintf(stderr, "class %d, all walls: rate %.6g /s (want %.6g), mu %.12g (want %.12g), sigma %.12g (want "
            "%.12g)\n", i + 1, rate[i], 1 / DURATION, mu[i], want_mu[i], sigma[i], want_sd[i]);
    CHECK_REL(rate[i], 1 / DURATION, 1e-9);
    CHECK_ABS(mu[i], want_mu[i], 1e-9);
    CHECK_REL(sigma[i], want_sd[i], 1e-9);
  }
  /* each wall alone: its own class's impacts; the other class has none and
   * takes the pooled fit of the wall (= the one class that hit it) */
  const char *walls[2] = {"floor", "ceiling"};
  for (int w = 0; w < 2; w++) {
    snprintf(tp, sizeof tp, "%s/impact_table_%s.csv", out, walls[w]);
    CHECK(read_table(tp, rate, mu, sigma) == 0);
    fprintf(stderr, "%s: rates %.6g, %.6g /s; mu %.9g, %.9g\n", walls[w], rate[0], rate[1], mu[0], mu[1]);
    CHECK_REL(rate[w], 1 / DURATION, 1e-9);
    CHECK(rate[1 - w] == 0);
    CHECK_ABS(mu[w], want_mu[w], 1e-9);
    CHECK_ABS(mu[1 - w], want_mu[w], 1e-9);
    CHECK_REL(sigma[1 - w], want_sd[w], 1e-9);
  }
  gs_dem_case_free(c);

  /* the PBM reads it: breakage selection dem_impact, classes by diameter */
  snprintf(path, sizeof path, "%s/pbm.yaml", out);
  fp = fopen(path, "w");
  fprintf(fp, "title: DEM impacts as the breakage selection\n"
              "grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-11, max: 2.0e-7, cells: 20, zero_first: true}\n"
              "initial: {type: exponential, number: 1, mean: 5.0e-9}\n"
              "mechanisms:\n"
              "  - type: breakage\n"
              "    selection: {type: dem_impact, file: impact_table.csv, measure: diameter, u_break: 0.5}\n"
              "    daughters: {type: halves}\n"
              "output: {end: 1, count: 2}\n");
  fclose(fp);
  const char *bin = getenv("GRANSIM_BIN");
  CHECK(bin != NULL);
  if (bin) {
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "\"%s\" check \"%s\" > \"%s/check.log\" 2>&1", bin, path, out);
    int st = system(cmd);
    fprintf(stderr, "gransim check of a dem_impact case reading impact_table.csv: status %d\n", st);
    if (st) {
      snprintf(cmd, sizeof cmd, "cat \"%s/check.log\" >&2", out);
      CHECK(system(cmd) == 0);
    }
    CHECK(st == 0);
  }
  char cmd[600];
  snprintf(cmd, sizeof cmd, "rm -rf \"%s\"", dir);
  CHECK(system(cmd) == 0);
  TEST_EXIT();
}
