/* Stiffness of a system for the explicit "rk": the spectral radius of its
 * Jacobian, estimated by a power iteration on difference quotients of f, and
 * the test whether rk's steps are held by its stability limit.  Used by
 * "auto" to choose its integrator and by "rk" to say when a run crawls. */
#ifndef GRANSIM_ODE_STIFFNESS_H
#define GRANSIM_ODE_STIFFNESS_H

#include <stddef.h>

#include "gransim/error.h"
#include "gransim/integrator.h"

#define GS_STIFFNESS_BETA 3.3 /* stability boundary of rk on the negative real axis */
#define GS_STIFFNESS_POWER_ITERATIONS 10

typedef struct {
  size_t n;
  double *f0, *v, *w, *yp; /* work, n each */
} gs_stiffness;

int gs_stiffness_init(gs_stiffness *s, size_t n, gs_error *err);
void gs_stiffness_free(gs_stiffness *s);

/* rho at (t, y), in the norm of the tolerances (rtol, atol); 0 when it
 * cannot be estimated (f failed). *evals counts the evaluations of f. */
double gs_stiffness_radius(gs_stiffness *s, const gs_ode *ode, double rtol, double atol, double t,
                           const double *y, long *evals);

/* Steps the stability limit alone costs rk from t to t_out. */
static inline double gs_stiffness_cost(double rho, double t, double t_out) {
  return (t_out - t) * rho / GS_STIFFNESS_BETA;
}

/* rk's step h sits at its stability limit: 1 <= h rho <= 2 beta.  A step
 * far beyond it that rk took without blowing up says that the estimate of
 * rho is not the Jacobian's (e.g. where f is not smooth at an empty cell). */
static inline int gs_stiffness_held(double h, double rho) {
  const double hr = h * rho;
  return hr >= 1.0 && hr <= 2.0 * GS_STIFFNESS_BETA;
}

#endif
