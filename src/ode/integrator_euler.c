/* Integrator "euler": the adaptive explicit Euler of Sampat et al. (2018), kept so that
 * old results can be reproduced and as a first-order reference.
 *
 * Each step evaluates f once and picks dt from the fastest relative
 * depletion among the number densities,
 *   m = max over i < npositive, y_i > 0 of (-f_i / y_i),
 * doubling dt while m < safety / dt (and 2 dt <= max_step) and halving it
 * while m > safety / dt (and dt / 2 >= min_step).  dt is remembered between
 * calls and only the step that would pass t_out is shortened.
 *
 * Keys: safety (default 0.1); initial_step (default (t_out - t) / 100 of the
 * first call); min_step (default initial_step / 1024); max_step (default the
 * span t_out - t of each call).  rtol and atol are accepted and ignored.
 *
 * The step is checked before it is applied: if a density would go below
 * -1e-12 * max density, the call fails and y, t keep the last good state. */
#include <float.h>
#include <math.h>
#include <stdlib.h>

#include "gransim/integrator.h"
#include "ode/integrator_interval.h"

int gs_integrator_common_keys(gs_cfg_node *solver, double *rtol, double *atol,
                              double *initial_step, double *min_step, double *max_step,
                              long *max_steps, gs_error *err);

/* Densities below -GS_EULER_NEG_TOL * max density count as negative. */
#define GS_EULER_NEG_TOL 1e-12

typedef struct {
  size_t n;
  double h_init, h_min, h_max; /* as configured; NAN = default */
  double safety;
  long max_steps;
  double dt;      /* step carried between calls; 0 until the first call */
  double dt_min;  /* resolved min_step */
  gs_interval interval;  /* the output interval in progress */
  double interval_h_max; /* and its step bound (max_step, else its length) */
  double *f;
  gs_integrator_stats stats;
} gs_euler;

/* The derivative vector; what gs_euler_carry reads stays. */
static void gs_euler_release(void *vself) {
  gs_euler *self = vself;
  free(self->f);
  self->f = NULL;
}

static void gs_euler_free(void *vself) {
  if (!vself) return;
  gs_euler_release(vself);
  free(vself);
}

/* The settings: a gs_euler with its keys filled in and nothing allocated. */
static int gs_euler_read(gs_cfg_node *solver, void **out, gs_error *err) {
  gs_euler *set = gs_calloc(1, sizeof *set, err);
  if (!set) return GS_ENOMEM;
  double rtol, atol;
  int rc = gs_integrator_common_keys(solver, &rtol, &atol, &set->h_init, &set->h_min,
                                     &set->h_max, &set->max_steps, err);
  if (!rc) rc = gs_cfg_double_range(solver, "safety", 0, 0.1, 0, 1, HUGE_VAL, 0, &set->safety, err);
  if (rc) {
    free(set);
    return rc;
  }
  *out = set;
  return GS_OK;
}

static int gs_euler_create(const void *settings, const gs_ode *ode, void **out, gs_error *err) {
  gs_euler *self = gs_malloc(sizeof *self, err);
  if (!self) return GS_ENOMEM;
  *self = *(const gs_euler *)settings;
  self->n = ode->n;
  gs_interval_init(&self->interval);
  if (!(self->f = gs_malloc(self->n * sizeof *self->f, err))) {
    gs_euler_free(self);
    return GS_ENOMEM;
  }
  *out = self;
  return GS_OK;
}

/* Fastest relative depletion rate among the positive densities; -inf when
 * none is positive (then nothing limits the step). */
static double gs_euler_rate(const double *y, const double *f, size_t npositive) {
  double m = -HUGE_VAL;
  for (size_t i = 0; i < npositive; i++)
    if (y[i] > 0) m = fmax(m, -f[i] / y[i]);
  return m;
}

static void gs_euler_adapt(gs_euler *self, double m, double h_max) {
  double dt = self->dt;
  while (m < self->safety / dt && dt * 2 <= h_max) dt *= 2;
  while (m > self->safety / dt && dt / 2 >= self->dt_min) dt /= 2;
  self->dt = dt;
}

/* Would y + h f leave a density below the tolerance, or anything non-finite?
 * Checked before the update so a failing step leaves y untouched. */
static int gs_euler_check(const gs_euler *self, size_t npositive, double t, double h,
                          const double *y, gs_error *err) {
  const double *f = self->f;
  double ymax = 0, ymin = 0;
  for (size_t i = 0; i < self->n; i++) {
    double v = y[i] + h * f[i];
    if (!isfinite(v))
      return gs_error_set(err, GS_ENUMERIC,
                          "integrator euler: y[%zu] becomes %g in the step from t = %.9g (dt = %g)",
                          i, v, t, h);
    if (i < npositive) {
      ymax = fmax(ymax, fabs(v));
      ymin = fmin(ymin, v);
    }
  }
  if (ymin >= -GS_EULER_NEG_TOL * ymax) return GS_OK;
  size_t i = 0;
  while (!(y[i] + h * f[i] < -GS_EULER_NEG_TOL * ymax)) i++;
  return gs_error_set(err, GS_ENUMERIC,
                      "integrator euler: negative number density y[%zu] = %g in the step from "
                      "t = %.9g (dt = %g); lower safety or min_step",
                      i, y[i] + h * f[i], t, h);
}

/* Defaults that depend on the first interval. */
static void gs_euler_first_call(gs_euler *self, double span) {
  double h0 = isnan(self->h_init) ? span / 100 : self->h_init;
  self->dt_min = isnan(self->h_min) ? h0 / 1024 : self->h_min;
  /* min_step: 0 must not let the halving loop reach dt = 0 (from which the
   * doubling loop could never climb back). */
  self->dt_min = fmax(self->dt_min, DBL_MIN);
  self->dt = h0;
}

static int gs_euler_step(gs_euler *self, const gs_ode *ode, double *t, double t_out,
                         double h_max, double *y, gs_error *err) {
  self->stats.rhs_evals++;
  const int failed = ode->f(ode->ctx, *t, y, self->f) != 0;
  if (failed && !ode->reduce_max)
    return gs_error_set(err, GS_ENUMERIC, "integrator euler: right-hand side failed at t = %.9g",
                        *t);
  double m = failed ? 0 : gs_euler_rate(y, self->f, ode->npositive);
  if (ode->reduce_max) { /* one step for all ranks; a failed f anywhere shows as +inf */
    m = ode->reduce_max(ode->ctx, failed ? HUGE_VAL : m);
    if (m == HUGE_VAL)
      return gs_error_set(err, GS_ENUMERIC, "integrator euler: right-hand side failed at t = %.9g%s", *t,
                          failed ? "" : " on another MPI rank (or a depletion rate overflowed)");
  }
  gs_euler_adapt(self, m, h_max);
  int final = *t + self->dt >= t_out;
  double h = final ? t_out - *t : self->dt;
  if (!final && *t + h == *t)
    return gs_error_set(err, GS_ENUMERIC,
                        "integrator euler: step size underflow at t = %.9g (dt = %g)", *t, h);
  int rc = gs_euler_check(self, ode->npositive, *t, h, y, err);
  /* a rank that fails must not leave the others waiting in the next reduction */
  if (ode->reduce_max && ode->reduce_max(ode->ctx, rc ? 1.0 : 0.0) > 0 && !rc)
    rc = gs_error_set(err, GS_ENUMERIC, "integrator euler: the step from t = %.9g failed on another MPI rank", *t);
  if (rc) return rc;
  for (size_t i = 0; i < self->n; i++) y[i] += h * self->f[i];
  *t = final ? t_out : *t + h;
  self->stats.steps++;
  self->stats.last_step = h;
  return GS_OK;
}

static int gs_euler_advance(void *vself, const gs_ode *ode, double *t, double t_out, double *y,
                            gs_error *err) {
  gs_euler *self = vself;
  if (ode->n != self->n || !(t_out >= *t))
    return gs_error_set(err, GS_EINPUT,
                        "integrator euler: bad call (n = %zu for %zu, t = %g to %g)", ode->n,
                        self->n, *t, t_out);
  if (t_out == *t) return GS_OK;
  if (self->dt <= 0) gs_euler_first_call(self, t_out - *t);
  if (gs_interval_begin(&self->interval, t_out))
    self->interval_h_max = isnan(self->h_max) ? t_out - *t : self->h_max;
  while (*t < t_out) {
    int rc = gs_interval_budget(&self->interval, self->max_steps, "euler", *t, err);
    if (!rc) rc = gs_euler_step(self, ode, t, t_out, self->interval_h_max, y, err);
    if (rc) return rc;
    if (gs_interval_step_done(&self->interval, ode)) return GS_OK;
  }
  return GS_OK;
}

static void gs_euler_stats(const void *vself, gs_integrator_stats *stats) {
  const gs_euler *self = vself;
  *stats = self->stats;
}

static void gs_euler_carry(void *vto, const void *vfrom) {
  gs_euler *to = vto;
  const gs_euler *from = vfrom;
  to->dt = from->dt;
  to->dt_min = from->dt_min;
  to->stats = from->stats;
  to->interval = from->interval;
  to->interval_h_max = from->interval_h_max;
}

/* At an output time: the step and its lower bound (set from the first
 * output interval) are all the steps after it depend on. */
static void gs_euler_mark(void *vself, double *state) {
  const gs_euler *self = vself;
  state[0] = self->dt;
  state[1] = self->dt_min;
  state[2] = state[3] = 0;
}

static void gs_euler_resume(void *vself, const double *state) {
  gs_euler *self = vself;
  if (!(state[0] > 0)) return; /* the start time: a fresh integrator's */
  self->dt = state[0];
  self->dt_min = state[1];
}

const gs_integrator_type gs_integrator_euler = {
    .name = "euler",
    .summary = "adaptive explicit Euler of Sampat et al. (2018), dt kept below safety / max(-f_i / y_i)",
    .read = gs_euler_read,
    .create = gs_euler_create,
    .advance = gs_euler_advance,
    .get_stats = gs_euler_stats,
    .free = gs_euler_free,
    .carry = gs_euler_carry,
    .release = gs_euler_release,
    .mark = gs_euler_mark,
    .resume = gs_euler_resume,
    .ranks = 1,
    .exact_invariants = 1,
};
