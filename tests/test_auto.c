/* solver.method auto (src/ode/integrator_auto.c) and the case-scaled default
 * atol (src/case/case.c): a stiff problem goes to CVODE, keeps its accuracy
 * and costs a fraction of rk's steps; a non-stiff one stays with rk, step for
 * step; the default atol follows its documented formula. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "gransim/case.h"
#include "gransim/integrator.h"

static int make(const char *yaml, const gs_ode *ode, gs_integrator *it) {
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "test.yaml", &err);
  gs_integrator_setup setup;
  int rc = cfg ? gs_integrator_setup_read(gs_cfg_get(gs_cfg_root(cfg), "solver"), &setup, &err) : 1;
  gs_cfg_free(cfg);
  if (!rc) rc = gs_integrator_create(&setup, ode, it, &err);
  if (!rc) gs_integrator_setup_free(&setup); /* integrators keep nothing of it */
  if (rc) fprintf(stderr, "integrator: %s\n", err.msg);
  return rc;
}

/* Prothero-Robinson: y' = lambda (y - sin t) + cos t, y(0) = 0, exact y = sin t
 * whatever lambda; lambda = -1e5 makes it stiff.  Component 2: z' = -z. */
static int pr_f(void *ctx, double t, const double *y, double *f) {
  const double lambda = *(const double *)ctx;
  f[0] = lambda * (y[0] - sin(t)) + cos(t);
  f[1] = -y[1];
  return 0;
}

static void run(const char *yaml, double lambda, double t_end, double *y, gs_integrator_stats *st,
                int *described, char *note) {
  gs_ode ode = {.n = 2, .f = pr_f, .ctx = &lambda, .npositive = 0};
  gs_integrator it;
  y[0] = 0;
  y[1] = 1;
  *described = 0;
  if (make(yaml, &ode, &it)) {
    check_failures++;
    return;
  }
  double t = 0;
  gs_error err = {0};
  for (int k = 1; k <= 4; k++) { /* four output intervals */
    if (it.type->advance(it.self, &ode, &t, t_end * k / 4, y, &err)) {
      fprintf(stderr, "advance: %s\n", err.msg);
      check_failures++;
      break;
    }
  }
  it.type->get_stats(it.self, st);
  if (it.type->describe) *described = it.type->describe(it.self, note, 512);
  gs_integrator_free(&it);
}

static void test_stiff(void) {
  double y[2], yr[2];
  gs_integrator_stats st, sr;
  int said, said_rk;
  char note[512] = "", none[512] = "";
  const char *tol = "rtol: 1.0e-6, atol: 1.0e-9";
  char auto_yaml[128], rk_yaml[128];
  snprintf(auto_yaml, sizeof auto_yaml, "solver: {%s}\n", tol); /* auto: the default */
  snprintf(rk_yaml, sizeof rk_yaml, "solver: {method: rk, %s}\n", tol);
  run(auto_yaml, -1e5, 2.0, y, &st, &said, note);
  run(rk_yaml, -1e5, 2.0, yr, &sr, &said_rk, none);
  printf("stiff: auto %ld steps (%s), rk %ld steps\n", st.steps, note, sr.steps);
  CHECK_ABS(y[0], sin(2.0), 1e-5);
  CHECK_REL(y[1], exp(-2.0), 1e-4);
  CHECK(said && strstr(note, "stiff from t = ") && strstr(note, "CVODE"));
  /* rk needs ~ 2 * 1e5 / 3.3 steps for stability alone; auto a few hundred */
  CHECK(sr.steps > 50000);
  CHECK(st.steps < sr.steps / 20);
}

static void test_not_stiff(void) {
  double y[2], yr[2];
  gs_integrator_stats st, sr;
  int said, said_rk;
  char note[512] = "";
  run("solver: {rtol: 1.0e-8}\n", -1.0, 10.0, y, &st, &said, note);
  run("solver: {method: rk, rtol: 1.0e-8}\n", -1.0, 10.0, yr, &sr, &said_rk, note);
  CHECK(!said);
  /* rk's very steps: the same numbers */
  CHECK(y[0] == yr[0] && y[1] == yr[1]);
  CHECK(st.steps == sr.steps && st.rejected == sr.rejected);
  CHECK_ABS(y[0], sin(10.0), 1e-6);
}

/* The default atol: rtol x min over axes of (volume held or brought in) /
 * largest pivot; a given atol is kept. */
static void test_default_atol(void) {
  const char *grid = "grid:\n  axes:\n    - {name: solid, type: geometric, min: 1.0e-12, ratio: 2, cells: 20}\n"
                     "initial: {type: point, number: 3.0e8, at: [4.0e-12]}\n";
  char yaml[1024];
  snprintf(yaml, sizeof yaml, "%soutput: {end: 10}\n", grid);
  gs_error err = {0};
  gs_cfg *cfg = gs_cfg_load_string(yaml, "a.yaml", &err);
  gs_case c;
  CHECK(cfg && gs_case_from_cfg(cfg, &c, &err) == GS_OK);
  const gs_axis *ax = &c.model.grid.axis[0];
  double v = 0;
  for (size_t i = 0; i < c.model.nnum; i++) v += c.y0[i] * c.model.grid.x[i];
  const double want = 1e-6 * v / ax->pivots[ax->n - 1];
  printf("default atol %.6g (want %.6g, volume %.6g)\n", c.atol, want, v);
  CHECK_REL(c.atol, want, 1e-12);
  CHECK_REL(c.abs_scale[0], want / GS_INTEGRATOR_ATOL, 1e-12);
  CHECK_REL(c.atol, 1e-6 * 3.0e8 * 4.0e-12 / ax->pivots[ax->n - 1], 1e-3);
  gs_case_free(&c);
  snprintf(yaml, sizeof yaml, "%ssolver: {atol: 0.5, rtol: 1.0e-4}\noutput: {end: 10}\n", grid);
  cfg = gs_cfg_load_string(yaml, "b.yaml", &err);
  CHECK(cfg && gs_case_from_cfg(cfg, &c, &err) == GS_OK);
  CHECK(c.atol == 0.5 && c.abs_scale[0] == 1.0 && c.checks.negative_floor == 50);
  gs_case_free(&c);
}

int main(void) {
  test_stiff();
  test_not_stiff();
  test_default_atol();
  TEST_EXIT();
}
