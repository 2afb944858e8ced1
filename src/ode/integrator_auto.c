/* Integrator "auto" (the default): the explicit "rk" while the case is not
 * stiff, CVODE's BDF ("cvode") while it is.
 *
 * Stiff here means that the explicit method's steps are held down by its
 * stability limit rather than by the accuracy asked for: an explicit step h
 * is stable only while h * rho <= beta, rho the spectral radius of the
 * Jacobian of f and beta the method's stability boundary on the negative
 * real axis (about 3.3 for the Runge-Kutta pairs of "rk"), so over a span T
 * it needs at least T * rho / beta steps whatever the tolerances, while a
 * BDF method's steps follow the solution alone.
 *
 * The rule (docs/models.md, "Choosing the integrator"):
 *   - rho is estimated at (t, y) by a power iteration on difference
 *     quotients of f (src/ode/stiffness.c: GS_STIFFNESS_POWER_ITERATIONS + 1
 *     evaluations, counted with rk's, the system's
 *     discrete choices held);
 *   - stiff means: rk's last step h is at its stability limit (1 <= h rho
 *     <= 2 beta) and the limit would cost rk more than GS_AUTO_STIFF_STEPS
 *     steps to the end of the advance;
 *   - at the start of every advance (each output interval, and each piece of
 *     it between two rate switches) the advance is CVODE's when stiff, rk's
 *     otherwise (and always rk's before rk has taken a step);
 *   - while rk advances, every GS_AUTO_CHECK_EVERY of its steps the test is
 *     made again at the state reached, and when stiff at two looks in a row
 *     CVODE takes the rest of the advance.
 * Each decision is a function of the state where it is made, of the span
 * and of rk's last step, so a run resumed at an output time with rk's state
 * restored makes the same decisions; CVODE
 * keeps its history from one advance to the next when it took both.
 *
 * Under MPI (gs_ode.reduce_max) and per-compartment steps (gs_ode.trying),
 * which CVODE cannot serve, "auto" is "rk".  The keys are those of rk and
 * cvode together (each reads its own). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/integrator.h"
#include "ode/stiffness.h"

int gs_integrator_common_keys(gs_cfg_node *solver, double *rtol, double *atol,
                              double *initial_step, double *min_step, double *max_step,
                              long *max_steps, gs_error *err);

extern const gs_integrator_type gs_integrator_rk, gs_integrator_cvode;

#define GS_AUTO_STIFF_STEPS 500.0 /* steps the stability limit may cost rk in one advance */
#define GS_AUTO_CHECK_EVERY 50    /* rk steps between two estimates within an advance */

typedef struct {
  void *rk_settings, *cvode_settings;
  double rtol, atol;
} gs_auto_settings;

typedef struct {
  double rtol, atol; /* the settings are the caller's only until create returns */
  size_t n;
  gs_integrator rk, cvode; /* cvode: none where it cannot serve (gs_auto_advance) */
  const gs_ode *ode;       /* the caller's system, in the advance in progress */
  gs_ode wrapped;          /* it, with between_steps ours (ctx = this) */
  long steps_in_advance, check_at;
  int using_cvode;         /* the advance in progress is CVODE's */
  double resumed_step;     /* rk's last step at the output time resumed from (mark) */
  /* the decisions, for the message (describe) */
  long stiff_advances;
  double first_t, first_rho, first_cost; /* the first switch to CVODE */
  gs_stiffness est;        /* the spectral radius's estimator */
  long est_evals;          /* its evaluations of f */
  gs_integrator_stats done; /* rk's and cvode's counters are summed */
} gs_auto;

static void gs_auto_free(void *vself) {
  gs_auto *self = vself;
  if (!self) return;
  gs_integrator_free(&self->rk);
  gs_integrator_free(&self->cvode);
  gs_stiffness_free(&self->est);
  free(self);
}

static int gs_auto_read(gs_cfg_node *solver, void **out, gs_error *err) {
  gs_auto_settings *set = gs_calloc(1, sizeof *set, err);
  if (!set) return GS_ENOMEM;
  double h0, hmin, hmax;
  long max_steps;
  int rc = gs_integrator_common_keys(solver, &set->rtol, &set->atol, &h0, &hmin, &hmax,
                                     &max_steps, err);
  if (!rc) rc = gs_integrator_rk.read(solver, &set->rk_settings, err);
  if (!rc) rc = gs_integrator_cvode.read(solver, &set->cvode_settings, err);
  if (rc) {
    free(set->rk_settings);
    free(set);
    return rc;
  }
  *out = set;
  return GS_OK;
}

static void gs_auto_free_settings(void *settings) {
  gs_auto_settings *set = settings;
  if (!set) return;
  free(set->rk_settings);
  free(set->cvode_settings);
  free(set);
}

static int gs_auto_f(void *ctx, double t, const double *y, double *dydt) {
  const gs_auto *self = ctx;
  return self->ode->f(self->ode->ctx, t, y, dydt);
}

static void gs_auto_hold(void *ctx, int on) {
  const gs_auto *self = ctx;
  self->ode->hold(self->ode->ctx, on);
}

static int gs_auto_psolve(void *ctx, double t, const double *y, double gamma, const double *r,
                          double *z) {
  const gs_auto *self = ctx;
  return self->ode->psolve(self->ode->ctx, t, y, gamma, r, z);
}

static void gs_auto_conserve(void *ctx, double *v) {
  const gs_auto *self = ctx;
  self->ode->conserve(self->ode->ctx, v);
}

static int gs_auto_create(const void *settings, const gs_ode *ode, void **out, gs_error *err) {
  const gs_auto_settings *set = settings;
  gs_auto *self = gs_calloc(1, sizeof *self, err);
  if (!self) return GS_ENOMEM;
  self->rtol = set->rtol;
  self->atol = set->atol;
  self->n = ode->n;
  gs_integrator_setup rk = {.type = &gs_integrator_rk, .settings = set->rk_settings};
  gs_integrator_setup cv = {.type = &gs_integrator_cvode, .settings = set->cvode_settings};
  int rc = gs_integrator_create(&rk, ode, &self->rk, err);
  if (!rc && !ode->reduce_max && !ode->trying) {
    rc = gs_integrator_create(&cv, ode, &self->cvode, err);
    if (!rc) rc = gs_stiffness_init(&self->est, ode->n, err);
  }
  if (rc) {
    gs_auto_free(self);
    return rc;
  }
  *out = self;
  return GS_OK;
}

static double gs_auto_spectral_radius(gs_auto *self, double t, const double *y) {
  return gs_stiffness_radius(&self->est, self->ode, self->rtol, self->atol, t, y,
                             &self->est_evals);
}

/* Stiff: rk's last step h sits at its stability limit (gs_stiffness_held)
 * and that limit would cost rk more than GS_AUTO_STIFF_STEPS steps to the
 * end of the advance.  h = 0 (rk has taken no step): not known,
 * rk starts. */
static int gs_auto_stiff(const gs_auto *self, double rho, double cost) {
  gs_integrator_stats st;
  self->rk.type->get_stats(self->rk.self, &st);
  /* a resumed rk has taken no step yet: its last one is the marked one */
  const double h = st.steps > 0 ? st.last_step : self->resumed_step;
  return gs_stiffness_held(h, rho) && cost > GS_AUTO_STIFF_STEPS;
}

static void gs_auto_to_cvode(gs_auto *self, double t, double rho, double cost) {
  self->using_cvode = 1;
  if (!self->stiff_advances++) {
    self->first_t = t;
    self->first_rho = rho;
    self->first_cost = cost;
  }
}

static int gs_auto_between(void *ctx) {
  gs_auto *self = ctx;
  return ++self->steps_in_advance >= self->check_at;
}

static int gs_auto_cvode_advance(gs_auto *self, const gs_ode *ode, double *t, double t_out,
                                 double *y, gs_error *err) {
  return self->cvode.type->advance(self->cvode.self, ode, t, t_out, y, err);
}

static int gs_auto_advance(void *vself, const gs_ode *ode, double *t, double t_out, double *y,
                           gs_error *err) {
  gs_auto *self = vself;
  const gs_integrator *rk = &self->rk;
  if (ode->reduce_max || ode->trying || !self->cvode.self) /* what CVODE cannot serve */
    return rk->type->advance(rk->self, ode, t, t_out, y, err);
  if (t_out <= *t) return rk->type->advance(rk->self, ode, t, t_out, y, err);
  self->ode = ode;
  double rho = gs_auto_spectral_radius(self, *t, y), cost = gs_stiffness_cost(rho, *t, t_out);
  self->using_cvode = 0;
  if (gs_auto_stiff(self, rho, cost)) {
    gs_auto_to_cvode(self, *t, rho, cost);
    return gs_auto_cvode_advance(self, ode, t, t_out, y, err);
  }
  /* rk, with a look every GS_AUTO_CHECK_EVERY of its steps */
  self->wrapped = *ode;
  self->wrapped.ctx = self;
  self->wrapped.f = gs_auto_f;
  self->wrapped.hold = ode->hold ? gs_auto_hold : NULL;
  self->wrapped.psolve = ode->psolve ? gs_auto_psolve : NULL;
  self->wrapped.conserve = ode->conserve ? gs_auto_conserve : NULL;
  self->wrapped.between_steps = gs_auto_between;
  self->steps_in_advance = 0;
  self->check_at = GS_AUTO_CHECK_EVERY;
  int stiff_looks = 0;
  while (*t < t_out) {
    int rc = rk->type->advance(rk->self, &self->wrapped, t, t_out, y, err);
    self->wrapped.jumped = 0; /* the jump, if any, was at the start */
    if (rc || *t >= t_out) return rc;
    self->check_at += GS_AUTO_CHECK_EVERY;
    rho = gs_auto_spectral_radius(self, *t, y);
    cost = gs_stiffness_cost(rho, *t, t_out);
    /* two looks in a row: rk's first steps, still growing, pass through the
     * stability limit once */
    stiff_looks = gs_auto_stiff(self, rho, cost) ? stiff_looks + 1 : 0;
    if (stiff_looks >= 2) {
      gs_auto_to_cvode(self, *t, rho, cost);
      return gs_auto_cvode_advance(self, ode, t, t_out, y, err);
    }
  }
  return GS_OK;
}

static void gs_auto_stats(const void *vself, gs_integrator_stats *stats) {
  const gs_auto *self = vself;
  self->rk.type->get_stats(self->rk.self, stats);
  stats->rhs_evals += self->est_evals;
  if (!self->cvode.self) return;
  gs_integrator_stats cv;
  self->cvode.type->get_stats(self->cvode.self, &cv);
  stats->steps += cv.steps;
  stats->rejected += cv.rejected;
  stats->rhs_evals += cv.rhs_evals;
  if (self->using_cvode) stats->last_step = cv.last_step;
}

/* Under MPI auto is rk: carry rk's state. */
static void gs_auto_carry(void *vto, const void *vfrom) {
  gs_auto *to = vto;
  const gs_auto *from = vfrom;
  to->rk.type->carry(to->rk.self, from->rk.self);
}

static void gs_auto_release(void *vself) {
  gs_auto *self = vself;
  self->rk.type->release(self->rk.self);
}

/* Exact resume: rk's marks (its step and controller; the fourth value, which
 * rk leaves 0, carries its last step, which the stiffness test reads), and
 * CVODE restarts at every output time anyway. */
static void gs_auto_mark(void *vself, double *state) {
  gs_auto *self = vself;
  gs_integrator_stats st;
  self->rk.type->get_stats(self->rk.self, &st);
  self->rk.type->mark(self->rk.self, state);
  state[GS_INTEGRATOR_MARK - 1] = st.steps > 0 ? st.last_step : self->resumed_step;
  if (self->cvode.self) {
    double unused[GS_INTEGRATOR_MARK];
    self->cvode.type->mark(self->cvode.self, unused);
  }
}

static void gs_auto_resume(void *vself, const double *state) {
  gs_auto *self = vself;
  self->rk.type->resume(self->rk.self, state);
  self->resumed_step = state[GS_INTEGRATOR_MARK - 1];
  if (self->cvode.self) self->cvode.type->resume(self->cvode.self, state);
}

static int gs_auto_describe(const void *vself, char *buf, size_t size) {
  const gs_auto *self = vself;
  if (!self->stiff_advances) return 0;
  snprintf(buf, size,
           "solver auto: stiff from t = %.6g s (Jacobian spectral radius %.3g /s: the explicit "
           "rk would need %.3g steps for stability alone to the next output or rate switch): "
           "CVODE BDF took %ld of the advances from there, rk the others",
           self->first_t, self->first_rho, self->first_cost, self->stiff_advances);
  return 1;
}

const gs_integrator_type gs_integrator_auto = {
    .name = "auto",
    .summary = "rk while not stiff, CVODE BDF while its steps would be held by stability (default)",
    .read = gs_auto_read,
    .create = gs_auto_create,
    .advance = gs_auto_advance,
    .get_stats = gs_auto_stats,
    .free = gs_auto_free,
    .free_settings = gs_auto_free_settings,
    .carry = gs_auto_carry,
    .release = gs_auto_release,
    .mark = gs_auto_mark,
    .resume = gs_auto_resume,
    .describe = gs_auto_describe,
    .ranks = 1,
    .per_compartment = 1,
    .exact_invariants = 0,
};
