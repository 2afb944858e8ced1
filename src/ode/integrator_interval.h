/* The output interval an integrator's advance() works on, kept across calls:
 * when gs_ode.between_steps ends an advance early, the next call with the
 * same t_out continues the interval (same step budget, and for euler the
 * same step bound) instead of starting a new one, so that the steps are those
 * of an uninterrupted advance.  Shared by the rk and euler integrators, which
 * carry it over to a rebuilt integrator with the rest of their state. */
#ifndef GRANSIM_PBM_INTEGRATOR_INTERVAL_H
#define GRANSIM_PBM_INTEGRATOR_INTERVAL_H

#include <math.h>

#include "gransim/error.h"
#include "gransim/integrator.h"

typedef struct {
  double end; /* t_out of the interval in progress; NaN before the first */
  long steps; /* steps taken in it */
} gs_interval;

static inline void gs_interval_init(gs_interval *iv) {
  iv->end = NAN;
  iv->steps = 0;
}

/* 1 when t_out starts a new interval (its step count restarts), 0 when it
 * is the rest of the one in progress. */
static inline int gs_interval_begin(gs_interval *iv, double t_out) {
  if (t_out == iv->end) return 0;
  iv->end = t_out;
  iv->steps = 0;
  return 1;
}

/* Before a step: max_steps_per_output counts the steps of the interval. */
static inline int gs_interval_budget(const gs_interval *iv, long max_steps, const char *name,
                                     double t, gs_error *err) {
  if (iv->steps < max_steps) return GS_OK;
  return gs_error_set(err, GS_ENUMERIC,
                      "integrator %s: max_steps_per_output = %ld steps taken at t = %.9g before "
                      "reaching %.9g",
                      name, max_steps, t, iv->end);
}

/* After an accepted step: count it; 1 when the caller asks advance() to
 * return now (gs_ode.between_steps). */
static inline int gs_interval_step_done(gs_interval *iv, const gs_ode *ode) {
  iv->steps++;
  return ode->between_steps && ode->between_steps(ode->ctx);
}

#endif
