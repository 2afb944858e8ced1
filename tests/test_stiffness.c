/* The spectral radius estimate behind solver auto's choice and rk's warning
 * (src/ode/stiffness.c): exact on a diagonal Jacobian to the power
 * iteration's convergence, blind to components that are exactly zero and
 * uncoupled, between rho and 2 rho on the upwind transfer of growth, its
 * evaluations counted, 0 when f fails. */
#include <math.h>
#include <stdlib.h>

#include "check.h"
#include "ode/stiffness.h"

#define N 40

typedef struct {
  double lambda[N];
  int upwind; /* f_i = k (y_{i-1} - y_i) with k = lambda[0] */
  int fail;
  long calls;
} sys_t;

static int sys_f(void *ctx, double t, const double *y, double *f) {
  (void)t;
  sys_t *s = ctx;
  s->calls++;
  if (s->fail) return 1;
  for (int i = 0; i < N; i++)
    f[i] = s->upwind ? s->lambda[0] * ((i ? y[i - 1] : 0.0) - y[i]) : -s->lambda[i] * y[i];
  return 0;
}

static double estimate(sys_t *s, const double *y, long *evals) {
  gs_error err = {0};
  gs_stiffness est;
  gs_ode ode = {.n = N, .f = sys_f, .ctx = s};
  CHECK(gs_stiffness_init(&est, N, &err) == GS_OK);
  const double rho = gs_stiffness_radius(&est, &ode, 1e-6, 1e-3, 0.0, y, evals);
  gs_stiffness_free(&est);
  return rho;
}

int main(void) {
  sys_t s = {0};
  double y[N];
  for (int i = 0; i < N; i++) {
    s.lambda[i] = pow(10.0, i / 8.0); /* 1 ... 7.5e4, neighbours 1.33x apart */
    y[i] = 1.0 + 0.1 * i;
  }
  long evals = 0;
  double rho = estimate(&s, y, &evals);
  CHECK_REL(rho, s.lambda[N - 1], 2e-3);
  CHECK(rho <= s.lambda[N - 1] * (1 + 1e-9)); /* a Rayleigh-type quotient of a normal J */
  CHECK(evals == GS_STIFFNESS_POWER_ITERATIONS + 1);
  CHECK(s.calls == evals);

  /* the stiffest component empty and uncoupled: rk never sees its mode */
  y[N - 1] = 0;
  rho = estimate(&s, y, NULL);
  CHECK_REL(rho, s.lambda[N - 2], 2e-3);

  /* nothing held at all: nothing to estimate */
  double zero[N] = {0};
  CHECK(estimate(&s, zero, NULL) == 0.0);

  /* growth's upwind transfer: every eigenvalue is -k (one Jordan block), and
   * ||J v|| / ||v|| lies between k and 2k */
  s.upwind = 1;
  s.lambda[0] = 1e4;
  for (int i = 0; i < N; i++) y[i] = 1.0;
  rho = estimate(&s, y, NULL);
  CHECK(rho >= 1e4 && rho <= 2e4);

  /* f failing: no estimate, and the caller is told by 0 */
  s.fail = 1;
  CHECK(estimate(&s, y, NULL) == 0.0);

  /* the tests built on it */
  CHECK(gs_stiffness_held(1.0 / 1e4, 1e4) && gs_stiffness_held(6.0 / 1e4, 1e4));
  CHECK(!gs_stiffness_held(0.5 / 1e4, 1e4) && !gs_stiffness_held(7.0 / 1e4, 1e4));
  CHECK_REL(gs_stiffness_cost(1e4, 1.0, 2.0), 1e4 / GS_STIFFNESS_BETA, 1e-15);
  TEST_EXIT();
}
