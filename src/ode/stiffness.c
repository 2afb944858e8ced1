/* Spectral radius of f's Jacobian for the stiffness tests; see stiffness.h. */
#include <math.h>
#include <stdlib.h>

#include "ode/stiffness.h"

int gs_stiffness_init(gs_stiffness *s, size_t n, gs_error *err) {
  s->n = n;
  s->f0 = gs_malloc(n * sizeof(double), err);
  s->v = gs_malloc(n * sizeof(double), err);
  s->w = gs_malloc(n * sizeof(double), err);
  s->yp = gs_malloc(n * sizeof(double), err);
  if (s->f0 && s->v && s->w && s->yp) return GS_OK;
  gs_stiffness_free(s);
  return GS_ENOMEM;
}

void gs_stiffness_free(gs_stiffness *s) {
  free(s->f0);
  free(s->v);
  free(s->w);
  free(s->yp);
  s->f0 = s->v = s->w = s->yp = NULL;
}

/* RMS of w_i v_i over the components in the error control. */
static double weighted_norm(const gs_stiffness *s, const double *v) {
  double sum = 0;
  for (size_t i = 0; i < s->n; i++) sum += (s->w[i] * v[i]) * (s->w[i] * v[i]);
  return sqrt(sum / (double)s->n);
}

/* Forward differences (J v ~ (f(y + e v) - f(y)) / e, e v one tolerance unit
 * in the RMS norm, as CVODE's own difference quotients), with the system's
 * discrete choices held, from a vector alternating over the components that
 * are not zero (it holds the fast modes of fine grids).  A component that
 * is exactly zero stays so under rk until f moves something into it, and
 * the iteration reaches it the same way; an alternating start over every
 * component also weighed empty cells that nothing reaches (the smallest
 * cells below a growing population), overestimating rho 2x there. */
double gs_stiffness_radius(gs_stiffness *s, const gs_ode *ode, double rtol, double atol, double t,
                           const double *y, long *evals) {
  const size_t n = s->n;
  for (size_t i = 0; i < n; i++) {
    const double scale = ode->abs_scale ? ode->abs_scale[i] : 1.0;
    s->w[i] = scale > 0 ? 1.0 / (atol * scale + rtol * fabs(y[i])) : 0.0;
    s->v[i] = s->w[i] > 0 && y[i] != 0 ? ((i & 1) ? -1.0 : 1.0) / s->w[i] : 0.0;
  }
  if (ode->hold) ode->hold(ode->ctx, 1);
  int rc = ode->f(ode->ctx, t, y, s->f0);
  long k_evals = 1;
  double rho = 0;
  for (int k = 0; !rc && k < GS_STIFFNESS_POWER_ITERATIONS; k++) {
    const double norm = weighted_norm(s, s->v);
    if (!(norm > 0) || !isfinite(norm)) break;
    const double e = 1.0 / norm;
    for (size_t i = 0; i < n; i++) s->yp[i] = y[i] + e * s->v[i];
    rc = ode->f(ode->ctx, t, s->yp, s->v); /* v = J v_old e + f0 */
    k_evals++;
    for (size_t i = 0; !rc && i < n; i++) s->v[i] = (s->v[i] - s->f0[i]) / e;
    if (!rc) rho = weighted_norm(s, s->v) / norm; /* ||J v|| / ||v|| */
  }
  if (ode->hold) ode->hold(ode->ctx, 0);
  if (evals) *evals += k_evals;
  return rc || !isfinite(rho) ? 0.0 : rho;
}
