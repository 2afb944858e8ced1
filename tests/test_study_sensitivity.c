/* Global sensitivity (src/study/sensitivity.c) on the Ishigami function
 * (a = 7, b = 0.1, x in [-pi, pi]^3), whose indices are known analytically:
 * the Sobol estimates lie within 0.05 of them and their bootstrap intervals
 * hold them; Morris ranks x1 and x2 above x3 in mu*; the same seed gives the
 * same numbers; bad input is refused. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "gransim/study.h"

static int ishigami(void *ctx, size_t n, size_t nin, const double *x, size_t nout, double *y,
                    gs_error *err) {
  (void)ctx, (void)err, (void)nin;
  for (size_t j = 0; j < n; j++) {
    const double *p = x + 3 * j;
    y[j * nout] = sin(p[0]) + 7 * pow(sin(p[1]), 2) + 0.1 * pow(p[2], 4) * sin(p[0]);
    if (nout > 1) y[j * nout + 1] = p[1]; /* a second output: all of it x2 */
  }
  return GS_OK;
}

static int failing(void *ctx, size_t n, size_t nin, const double *x, size_t nout, double *y,
                   gs_error *err) {
  (void)ctx, (void)n, (void)nin, (void)x, (void)nout, (void)y;
  return gs_error_set(err, GS_ENUMERIC, "model broke");
}

int main(void) {
  gs_study_axis ax[3];
  gs_error e = {0};
  const char *ranges[] = {"x1=-3.141592653589793:3.141592653589793",
                          "x2=-3.141592653589793:3.141592653589793",
                          "x3=-3.141592653589793:3.141592653589793"};
  for (int k = 0; k < 3; k++) CHECK(gs_study_parse_range(ranges[k], &ax[k], &e) == GS_OK);

  const double S1[3] = {0.3139, 0.4424, 0}, ST[3] = {0.5576, 0.4424, 0.2437};
  gs_sens_options so = {.method = GS_SENS_SOBOL, .n = 8192, .seed = 3};
  gs_sens_result r;
  CHECK(gs_sensitivity(ax, 3, 2, ishigami, NULL, &so, &r, &e) == GS_OK);
  CHECK(r.runs == 8192 * 5 && r.nin == 3 && r.nout == 2);
  for (int k = 0; r.s1 && k < 3; k++) {
    printf("x%d: S1 %.4f [%.4f, %.4f] (exact %.4f)  ST %.4f [%.4f, %.4f] (exact %.4f)\n", k + 1,
           r.s1[k], r.s1_lo[k], r.s1_hi[k], S1[k], r.st[k], r.st_lo[k], r.st_hi[k], ST[k]);
    CHECK(fabs(r.s1[k] - S1[k]) < 0.05 && fabs(r.st[k] - ST[k]) < 0.05);
    CHECK(r.s1_lo[k] <= S1[k] && S1[k] <= r.s1_hi[k]);
    CHECK(r.st_lo[k] <= ST[k] && ST[k] <= r.st_hi[k]);
    CHECK(r.s1_lo[k] <= r.s1[k] && r.s1[k] <= r.s1_hi[k]);
  }
  /* output 2 is x2 alone */
  CHECK(r.s1 && fabs(r.s1[3 + 1] - 1) < 0.01 && fabs(r.st[3 + 0]) < 1e-12 && fabs(r.st[3 + 2]) < 1e-12);
  /* the seed fixes the sample and the bootstrap */
  gs_sens_result again;
  CHECK(gs_sensitivity(ax, 3, 2, ishigami, NULL, &so, &again, &e) == GS_OK);
  CHECK(again.s1 && r.s1 && again.s1[0] == r.s1[0] && again.s1_lo[1] == r.s1_lo[1]);
  gs_sens_result_free(&again);
  gs_sens_result_free(&r);

  gs_sens_options mo = {.method = GS_SENS_MORRIS, .n = 100, .seed = 5};
  CHECK(gs_sensitivity(ax, 3, 1, ishigami, NULL, &mo, &r, &e) == GS_OK);
  CHECK(r.runs == 100 * 4);
  for (int k = 0; r.mu_star && k < 3; k++)
    printf("x%d: mu %.4f mu* %.4f sigma %.4f\n", k + 1, r.mu[k], r.mu_star[k], r.sigma[k]);
  CHECK(r.mu_star && r.mu_star[0] > r.mu_star[2] && r.mu_star[1] > r.mu_star[2]);
  /* x2 enters as 7 sin^2: its effects cancel on average, not in |.| */
  CHECK(r.mu_star && fabs(r.mu[1]) < r.mu_star[1]);
  gs_sens_result_free(&r);

  /* bad input */
  gs_sens_options small = {.method = GS_SENS_SOBOL, .n = 8};
  CHECK(gs_sensitivity(ax, 3, 1, ishigami, NULL, &small, &r, &e) == GS_EINPUT &&
        strstr(e.msg, "N >= 16"));
  gs_sens_options one = {.method = GS_SENS_MORRIS, .n = 1};
  CHECK(gs_sensitivity(ax, 3, 1, ishigami, NULL, &one, &r, &e) == GS_EINPUT &&
        strstr(e.msg, "R >= 2"));
  gs_sens_options odd = {.method = GS_SENS_MORRIS, .n = 4, .levels = 5};
  CHECK(gs_sensitivity(ax, 3, 1, ishigami, NULL, &odd, &r, &e) == GS_EINPUT &&
        strstr(e.msg, "even"));
  CHECK(gs_sensitivity(ax, 0, 1, ishigami, NULL, &so, &r, &e) == GS_EINPUT);
  CHECK(gs_sensitivity(ax, 3, 1, failing, NULL, &so, &r, &e) == GS_ENUMERIC &&
        strstr(e.msg, "model broke"));
  for (int k = 0; k < 3; k++) gs_study_axis_free(&ax[k]);
  TEST_EXIT();
}
