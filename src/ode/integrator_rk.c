/* Integrator "rk": adaptive embedded Runge–Kutta pairs from GSL odeiv2.
 *
 * Keys (besides the common ones, see integrator.c): variant = rkf45 | rkck |
 * rk8pd (default rkck).  The step/control/evolve objects are used directly
 * rather than through gsl_odeiv2_driver so that each component can carry its
 * own absolute tolerance (atol * abs_scale[i]; components with abs_scale 0
 * get an astronomically loose one and so never limit the step) and so that
 * the step bounds and step budget are ours to enforce.
 *
 * The step-size controller is GSL's standard rule (shrink by at most 5 when
 * the largest scaled error exceeds 1.1, grow by at most 5 below 0.5) written
 * here as a GSL control type, so that under MPI (gs_ode.reduce_max) the
 * largest error is taken over all ranks and every rank takes the same steps.
 *
 * A linear decay -k y of the first components that the system leaves out
 * of f (gs_ode.ndecay: a compartment's outflow under per-compartment steps)
 * is stepped as the key `outflow` says (the registered gs_rk_outflow types
 * below): `exponential`, an integrating-factor step (Lawson 1967) in the
 * form of Krogstad (2005): over a step from s, GSL's pair integrates u with
 * y = e^{-k (t - s)} u + (1 - e^{-k (t - s)}) g0 / k, g0 = f at s, whose
 * rate (f - g0) e^{k (t - s)} has no stiffness from k and vanishes where
 * f stays at g0, so the decay sets no stability bound on the step, and the
 * state is re-based (u = y) after every accepted step; or `explicit`,
 * f - k y integrated as it is.  Either way GSL also
 * integrates W' = f for those components (excluded from the error control),
 * and what the decay removed is booked by the balance y0 + W - y1, which
 * the caller hands on exactly (gs_ode.decayed).
 *
 * No GSL error handler is installed here (it is process-wide state); the
 * calls below are arranged never to hit GSL's argument-error paths. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include "cfg/nearest.h"
#include "gransim/integrator.h"
#include "ode/integrator_interval.h"
#include "ode/stiffness.h"

int gs_integrator_common_keys(gs_cfg_node *solver, double *rtol, double *atol,
                              double *initial_step, double *min_step, double *max_step,
                              long *max_steps, gs_error *err);

/* Tolerance scale for components excluded from error control: large enough
 * that atol * scale dwarfs any error, small enough to stay finite. */
#define GS_RK_EXCLUDED_SCALE 1e300
/* The longest step of the exponential treatment, in units of 1/k: e^{k h}
 * stays far from overflow (e^500 ~ 1e217), and a step that long has
 * emptied what it started with to below any tolerance anyway. */
#define GS_RK_MAX_KH 500.0

/* How the decay a system leaves out of f is stepped (key `outflow`). */
typedef struct gs_rk_outflow {
  const char *name;
  const char *summary;
  int exponential; /* 1: by the integrating factor e^{k (t - s)}; 0: with f, explicitly */
  int follow;      /* exponential: the frame also follows the system's forcing (gs_ode.forcing) */
} gs_rk_outflow;

static const gs_rk_outflow gs_rk_outflow_exponential = {
    .name = "exponential",
    .summary = "the outflow and the inflow's curve stepped exactly: neither bounds the step",
    .exponential = 1,
    .follow = 1,
};
static const gs_rk_outflow gs_rk_outflow_held = {
    .name = "integrating_factor",
    .summary = "the outflow stepped exactly with the rates held at the step's start; a changing "
               "inflow bounds the step near k h ~ 1",
    .exponential = 1,
};
static const gs_rk_outflow gs_rk_outflow_explicit = {
    .name = "explicit",
    .summary = "the outflow a rate like any other (stable while k h < 3.7 with rkck)",
    .exponential = 0,
};
static const gs_rk_outflow *const gs_rk_outflows[] = {
    &gs_rk_outflow_exponential, &gs_rk_outflow_held, &gs_rk_outflow_explicit, NULL};

typedef struct {
  size_t n;
  /* the decay left out of f (gs_ode.ndecay, decay) and how it is stepped;
   * m = n + nd: GSL's state is the caller's, then W, the integral of f over
   * the step for the nd decaying components (yx; nbuf: the state f sees) */
  size_t nd, m;
  double k;
  const gs_rk_outflow *outflow;
  double *yx, *nbuf;
  /* exponential: f of the decaying components at the start of the step
   * (g0), taken from the next evaluation when g0_pending; plain: rates as
   * f - k y in the state as it is (the first step's size estimate) */
  double *g0;
  int g0_pending, plain;
  /* exponential with follow: the forcing of the step tried (gs_ode.forcing,
   * NULL: none) and the step it was given for */
  const double *fc;
  double fh;
  double rtol, atol;
  double h_min, h_max;
  long max_steps;
  const char *variant;
  gsl_odeiv2_step *step;
  gsl_odeiv2_control *control;
  gsl_odeiv2_evolve *evolve;
  double *scale; /* per-component absolute-tolerance scale, as given to GSL */
  double h;      /* step proposed for the next advance; <= 0 until chosen */
  gs_interval interval; /* the output interval in progress */
  const gs_ode *ode; /* the system of the advance() in progress */
  int rhs_failed; /* 1: f returned an error; 2: f gave a non-finite value */
  /* under MPI, the step's one agreement (in the controller) was reached,
   * and it found a non-finite state on some rank */
  int agreed, agreed_nonfinite;
  /* the start of the step being tried (gs_ode.trying) */
  double try_t0;
  /* the last try rejected, its size and scaled error (0: none since the
   * last accepted step) */
  double rejected_h, rejected_error;
  size_t fail_index;
  double fail_t, fail_value;
  gs_integrator_stats stats;
  gs_stiffness est; /* allocated at the first look for stiffness */
  int stiff_said;   /* the run was told that it is stiff */
} gs_rk;

static const char *const gs_rk_variants[] = {"rkf45", "rkck", "rk8pd", NULL};

static const gsl_odeiv2_step_type *gs_rk_step_type(int variant) {
  switch (variant) {
  case 0: return gsl_odeiv2_step_rkf45;
  case 2: return gsl_odeiv2_step_rk8pd;
  default: return gsl_odeiv2_step_rkck;
  }
}

/* The frame of the exponential treatment over a step from s (the start of
 * the step tried), at t: y = phi u + psi g0 with phi = e^{-k (t - s)} and
 * psi = (1 - phi) / k, the exact solution of y' = -k y + g0 from u(s); so
 * u' = (f - g0) / phi, which vanishes where f stays at g0 (a compartment
 * whose inflow and outflow balance).  The step's re-basing evaluates them
 * at the very time its last stage was evaluated at, so that both give the
 * same state.  Explicit (or plain): phi = 1, psi = 0. */
static int gs_rk_expo(const gs_rk *self) { return self->outflow->exponential && !self->plain; }
static double gs_rk_phi(const gs_rk *self, double t) {
  return gs_rk_expo(self) ? exp(-self->k * (t - self->try_t0)) : 1.0;
}
static double gs_rk_psi(const gs_rk *self, double t) {
  return gs_rk_expo(self) ? -expm1(-self->k * (t - self->try_t0)) / self->k : 0.0;
}

/* phi_0 .. phi_T (T = GS_ODE_FORCING_TERMS) at z <= 0: phi_0 = e^z and
 * phi_{j+1}(z) = (phi_j(z) - 1/j!) / z, by their series sum_i z^i / (i + j)!
 * where that recurrence would cancel (|z| < 1). */
static void gs_rk_phis(double z, double *ph) {
  if (fabs(z) < 1.0) {
    double inv_fact = 1.0; /* 1 / j! */
    for (int j = 0; j <= GS_ODE_FORCING_TERMS; j++) {
      double term = inv_fact, sum = 0.0;
      for (int i = 0; i < 40 && fabs(term) > 1e-20 * fabs(sum); i++) {
        sum += term;
        term *= z / (double)(i + j + 1);
      }
      ph[j] = sum;
      inv_fact /= (double)(j + 1);
    }
    return;
  }
  ph[0] = exp(z);
  double fact = 1.0; /* j! */
  for (int j = 0; j < GS_ODE_FORCING_TERMS; j++) {
    ph[j + 1] = (ph[j] - 1.0 / fact) / z;
    fact *= (double)(j + 1);
  }
}

/* The frame at t of the step tried from s: y = phi u + psi g0 + the response
 * to the forcing's terms of degree >= 1 (c_m theta^m, theta = (t - s) / h:
 * tau m! theta^m phi_{m+1}(-k tau), tau = t - s, weights ws), so that u' =
 * (f - g0 - sum_m c_m theta^m) / phi (weights wq) vanishes where f is g0
 * plus the forcing's change: a compartment whose inflow only passes
 * through.  Without a forcing: phi and psi alone. */
typedef struct {
  double phi, psi;
  int on;
  double ws[GS_ODE_FORCING_TERMS], wq[GS_ODE_FORCING_TERMS];
} gs_rk_frame;

static void gs_rk_frame_at(const gs_rk *self, double t, gs_rk_frame *fr) {
  fr->phi = gs_rk_phi(self, t);
  fr->psi = gs_rk_psi(self, t);
  fr->on = gs_rk_expo(self) && self->fc;
  if (!fr->on) return;
  const double tau = t - self->try_t0, th = tau / self->fh;
  double ph[GS_ODE_FORCING_TERMS + 1], thm = 1.0, fact = 1.0;
  gs_rk_phis(-self->k * tau, ph);
  for (int m = 1; m < GS_ODE_FORCING_TERMS; m++) {
    thm *= th;
    fact *= (double)m;
    fr->wq[m] = thm;
    fr->ws[m] = tau * fact * thm * ph[m + 1];
  }
}

/* Decaying component i of the caller's state from GSL's u in frame fr. */
static double gs_rk_frame_y(const gs_rk *self, const gs_rk_frame *fr, size_t i, double u) {
  double y = fr->phi * u + fr->psi * self->g0[i];
  if (fr->on)
    for (int m = 1; m < GS_ODE_FORCING_TERMS; m++) y += fr->ws[m] * self->fc[(size_t)m * self->nd + i];
  return y;
}

/* With a forcing: the correction to the transient's amplitude A in the
 * record's bound (gs_rk_control_hadjust).  There the rates' change over the
 * step, (g1 - g0) / h, stands for f' in the slow solution g / k - g' / k^2
 * + ...; the forcing's part of it is a known quartic, whose slow solution
 * is exact: sum_j (-1)^j g^(j)(0) / k^(j+1), g^(j)(0) = j! c_j / h^j.  So
 * the forcing's terms leave the slope and enter by all their derivatives
 * (a sharp front, where the first derivative alone misses much). */
static double gs_rk_forced_transient(const gs_rk *self, size_t i, double kh) {
  const size_t nd = self->nd;
  const double k = self->k, *c = self->fc;
  double sum = 0.0;
  for (int m = 1; m < GS_ODE_FORCING_TERMS; m++) sum += c[(size_t)m * nd + i];
  /* the forcing's change left the slope term: -sum / (k * kh); its exact
   * slow solution at 0 enters: + c1 / (k kh) - 2 c2 / (k (kh)^2) + 6 c3 / (k (kh)^3) - 24 c4 / (k (kh)^4) */
  double exact = 0.0, fact = 1.0, p = 1.0;
  for (int m = 1; m < GS_ODE_FORCING_TERMS; m++) {
    fact *= (double)m;
    p *= kh;
    exact += ((m & 1) ? 1.0 : -1.0) * fact * c[(size_t)m * nd + i] / p;
  }
  return (exact - sum / kh) / k;
}

/* The step about to be tried (gs_ode.trying), and the forcing f has over it. */
static void gs_rk_announce(gs_rk *self, double t0, double h) {
  const gs_ode *ode = self->ode;
  if (ode->trying) ode->trying(ode->ctx, t0, h);
  self->fc = self->nd && self->outflow->follow && ode->forcing && h > 0 ? ode->forcing(ode->ctx) : NULL;
  self->fh = h;
}

/* The rates of GSL's state from f's (without the decay) of the state nbuf:
 * u' = (f - g0) / phi (exponential) or f - k y (explicit) for the decaying
 * components, and W' = f. */
static void gs_rk_decay_rates(gs_rk *self, const gs_rk_frame *fr, double *dydt) {
  const size_t n = self->n, nd = self->nd;
  const double k = self->k, phi = fr->phi;
  if (gs_rk_expo(self)) {
    if (self->g0_pending) { /* the step's first evaluation, at its start */
      memcpy(self->g0, dydt, nd * sizeof *dydt);
      self->g0_pending = 0;
    }
    for (size_t i = 0; i < nd; i++) {
      double g = self->g0[i];
      if (fr->on)
        for (int m = 1; m < GS_ODE_FORCING_TERMS; m++) g += fr->wq[m] * self->fc[(size_t)m * nd + i];
      dydt[n + i] = dydt[i];
      dydt[i] = (dydt[i] - g) / phi;
    }
  } else {
    for (size_t i = 0; i < nd; i++) {
      dydt[n + i] = dydt[i];
      dydt[i] -= k * self->nbuf[i];
    }
  }
}

/* GSL calling convention -> gs_ode.  GSL_EBADFUNC makes evolve return at
 * once instead of retrying with a smaller step.  Non-finite derivatives are
 * caught here because GSL's error control never rejects NaN. */
static int gs_rk_rhs(double t, const double y[], double dydt[], void *params) {
  gs_rk *self = params;
  const gs_ode *ode = self->ode;
  self->stats.rhs_evals++;
  self->fail_t = t;
  const double *state = y;
  gs_rk_frame fr = {.phi = 1.0};
  if (self->nd) { /* the decaying components as f sees them */
    gs_rk_frame_at(self, t, &fr);
    for (size_t i = 0; i < self->nd; i++) self->nbuf[i] = gs_rk_frame_y(self, &fr, i, y[i]);
    memcpy(self->nbuf + self->nd, y + self->nd, (self->n - self->nd) * sizeof *y);
    state = self->nbuf;
  }
  if (ode->f(ode->ctx, t, state, dydt)) self->rhs_failed = 1;
  if (self->nd && !self->rhs_failed) gs_rk_decay_rates(self, &fr, dydt);
  for (size_t i = 0; !self->rhs_failed && !ode->rates_checked && i < self->n; i++) {
    if (!isfinite(dydt[i])) {
      self->rhs_failed = 2;
      self->fail_index = i;
      self->fail_value = dydt[i];
    }
  }
  if (!self->rhs_failed) return GSL_SUCCESS;
  if (!ode->reduce_max) return GSL_EBADFUNC;
  /* Under MPI every rank must make the same calls: a failed evaluation gives
   * zero rates and the step goes on; gs_rk_agree() then rolls it back on
   * every rank (one agreement per step rather than per evaluation). */
  memset(dydt, 0, self->m * sizeof *dydt);
  return GSL_SUCCESS;
}

/* Under MPI: did f fail on any rank since the last call?  (3: on another.) */
static int gs_rk_agree(gs_rk *self) {
  const gs_ode *ode = self->ode;
  if (ode->reduce_max && ode->reduce_max(ode->ctx, self->rhs_failed ? 1.0 : 0.0) > 0 && !self->rhs_failed)
    self->rhs_failed = 3;
  return self->rhs_failed;
}

/* ---- step-size control --------------------------------------------------- */

typedef struct {
  double atol, rtol;
  const double *scale; /* per-component absolute-tolerance scale */
  gs_rk *rk;           /* for the ode of the advance in progress (reduce_max) */
} gs_rk_control;

/* Under MPI a step needs one agreement, in the controller: the largest
 * error, or a failure anywhere, which outranks any error (a failed f, then a
 * non-finite state).  Two agreements (error, then failures) had made a rank
 * that waited for the others at the first wait again at the second. */
#define GS_RK_AGREED_RHS_FAILED 4e300
#define GS_RK_AGREED_NONFINITE 2e300
#define GS_RK_ERROR_CAP 1e300
/* a rejected try whose error exceeds what the accepted retry predicts for
 * it by this factor marks f as not smooth there (gs_rk_control_hadjust) */
#define GS_RK_ROUGH 100.0

static int gs_rk_all_finite(const double *y, size_t n);

static void *gs_rk_control_alloc(void) { return calloc(1, sizeof(gs_rk_control)); }

static int gs_rk_control_init(void *state, double atol, double rtol, double a_y, double a_dydt) {
  (void)a_y;
  (void)a_dydt; /* tolerance rtol * |y_i| + atol * scale_i */
  gs_rk_control *c = state;
  c->atol = atol;
  c->rtol = rtol;
  return GSL_SUCCESS;
}

static int gs_rk_control_hadjust(void *state, size_t dim, unsigned int ord, const double y[],
                                 const double yerr[], const double yp[], double *h) {
  (void)yp;
  const gs_rk_control *c = state;
  const double S = 0.9, h_old = *h;
  gs_rk *rk = c->rk;
  /* decaying components: their error and value as y = phi u + psi g0, not
   * as u (otherwise the absolute tolerance would shrink by phi = e^{-k h}),
   * and the error of a quintic Hermite curve through the step's ends
   * (values, slopes, second derivatives: the record another compartment's
   * inflow is drawn from), which the exponential step does not see: where
   * f moves from g0 at the start to g1 at the end (W' there), y holds
   * e^{-k t} A, A = y0 - g0 / k + (g1 - g0) / (k^2 h), besides terms as
   * slow as f, and the curve misses it by at most |A| (k h)^6 / (6! 2^6)
   * (A, not y0 - g0 / k: a compartment that follows its inflow lags it by
   * f' / k^2, which is no exponential) */
  gs_rk_frame fr = {.phi = 1.0};
  if (rk->nd) gs_rk_frame_at(rk, rk->try_t0 + h_old, &fr);
  const double phi = fr.phi;
  const double kh = rk->k * h_old, hermite = gs_rk_expo(rk) ? pow(kh, 6) / 46080.0 : 0.0;
  const double *y0 = rk->evolve->y0, *g1 = rk->evolve->dydt_out + rk->n, k = rk->k;
  double rmax = DBL_MIN;
  for (size_t i = 0; i < dim; i++) {
    const int d = i < rk->nd;
    const double v = d ? gs_rk_frame_y(rk, &fr, i, y[i]) : y[i];
    double A = d ? y0[i] - rk->g0[i] / k + (g1[i] - rk->g0[i]) / (k * kh) : 0.0;
    if (d && fr.on && kh > 1e-2) A += gs_rk_forced_transient(rk, i, kh); /* below, (k h)^6 leaves nothing */
    const double e = d ? phi * fabs(yerr[i]) + hermite * fabs(A) : fabs(yerr[i]);
    double r = e / (c->rtol * fabs(v) + c->atol * c->scale[i]);
    if (r > rmax) rmax = r;
  }
  const gs_ode *ode = rk->ode;
  if (ode->reduce_max) {
    double mine = rk->rhs_failed                ? GS_RK_AGREED_RHS_FAILED
                  : !gs_rk_all_finite(y, dim)   ? GS_RK_AGREED_NONFINITE
                                                : fmin(rmax, GS_RK_ERROR_CAP);
    double all = ode->reduce_max(ode->ctx, mine);
    rk->agreed = 1;
    rk->agreed_nonfinite = all >= GS_RK_AGREED_NONFINITE && all < GS_RK_AGREED_RHS_FAILED;
    if (all >= GS_RK_AGREED_RHS_FAILED && !rk->rhs_failed) rk->rhs_failed = 3;
    /* a failure: take the step as it is; gs_rk_check_finite rolls it back */
    if (all >= GS_RK_AGREED_NONFINITE) return GSL_ODEIV_HADJ_NIL;
    rmax = all;
  }
  if (rmax > 1.1) { /* shrink, by at most 5, a fraction S more than the error suggests */
    *h = h_old * fmax(0.2, S / pow(rmax, 1.0 / ord));
    rk->rejected_h = h_old;
    rk->rejected_error = rmax;
    /* GSL's evolve retries from the same start with this h, unless it would
     * not move t by an ulp (then it keeps the step as it is) */
    if (*h < h_old && rk->try_t0 + *h != rk->try_t0) gs_rk_announce(rk, rk->try_t0, *h);
    return GSL_ODEIV_HADJ_DEC;
  }
  /* A step that needed a retry is not followed by a larger one when the
   * error of the rejected try was far above what the accepted one predicts
   * for it (error ~ h^ord): f is not smooth there.  Where a cell's wetness
   * switches aggregation on, the error of a step jumps by 1e6-1e10 once the
   * step reaches the switch; growing by 5 after each retry made the steps
   * alternate between rejected and accepted up to it.  Holding back after
   * every rejection (Hairer-Nørsett-Wanner's facmax = 1) would also hold
   * back the steps of smooth cases (docs/performance.md). */
  if (rk->rejected_h > 0) {
    const double predicted = fmax(rmax, DBL_MIN) * pow(rk->rejected_h / h_old, ord);
    const int rough = rk->rejected_error > GS_RK_ROUGH * predicted;
    rk->rejected_h = 0;
    if (rough) return GSL_ODEIV_HADJ_NIL;
  }
  if (rmax < 0.5) { /* grow, by at most 5, never shrink */
    *h = h_old * fmax(1.0, fmin(5.0, S / pow(rmax, 1.0 / (ord + 1.0))));
    return GSL_ODEIV_HADJ_INC;
  }
  return GSL_ODEIV_HADJ_NIL;
}

static int gs_rk_control_errlevel(void *state, const double y, const double dydt, const double h,
                                  const size_t ind, double *errlev) {
  (void)dydt;
  (void)h;
  const gs_rk_control *c = state;
  *errlev = c->rtol * fabs(y) + c->atol * c->scale[ind];
  return GSL_SUCCESS;
}

static int gs_rk_control_set_driver(void *state, const gsl_odeiv2_driver *d) {
  (void)state;
  (void)d;
  return GSL_SUCCESS;
}

static const gsl_odeiv2_control_type gs_rk_control_type = {
    .name = "gransim",
    .alloc = gs_rk_control_alloc,
    .init = gs_rk_control_init,
    .hadjust = gs_rk_control_hadjust,
    .errlevel = gs_rk_control_errlevel,
    .set_driver = gs_rk_control_set_driver,
    .free = free,
};

static int gs_rk_rhs_error(const gs_rk *self, gs_error *err) {
  if (self->rhs_failed == 3)
    return gs_error_set(err, GS_ENUMERIC,
                        "integrator rk: right-hand side failed on another MPI rank at t = %.9g",
                        self->fail_t);
  if (self->rhs_failed == 2)
    return gs_error_set(err, GS_ENUMERIC,
                        "integrator rk: right-hand side gave dydt[%zu] = %g at t = %.9g",
                        self->fail_index, self->fail_value, self->fail_t);
  return gs_error_set(err, GS_ENUMERIC, "integrator rk: right-hand side failed at t = %.9g",
                      self->fail_t);
}

/* GSL's objects and the tolerance scales; h, the counters and the interval
 * (what gs_rk_carry reads) stay. */
static void gs_rk_release(void *vself) {
  gs_rk *self = vself;
  if (self->evolve) gsl_odeiv2_evolve_free(self->evolve);
  if (self->control) gsl_odeiv2_control_free(self->control);
  if (self->step) gsl_odeiv2_step_free(self->step);
  free(self->scale);
  free(self->yx);
  free(self->nbuf);
  free(self->g0);
  self->yx = self->nbuf = self->g0 = NULL;
  self->evolve = NULL;
  self->control = NULL;
  self->step = NULL;
  self->scale = NULL;
}

static void gs_rk_free(void *vself) {
  if (!vself) return;
  gs_rk_release(vself);
  gs_stiffness_free(&((gs_rk *)vself)->est);
  free(vself);
}

static int gs_rk_alloc_gsl(gs_rk *self, int variant, const gs_ode *ode, gs_error *err) {
  self->scale = gs_malloc(self->m * sizeof *self->scale, err);
  if (!self->scale) return GS_ENOMEM;
  for (size_t i = 0; i < self->m; i++) {
    double s = i < self->n && ode->abs_scale ? ode->abs_scale[i] : 1.0;
    self->scale[i] = i < self->n && s > 0 ? s : GS_RK_EXCLUDED_SCALE; /* W: no error control */
  }
  if (self->nd && (!(self->yx = gs_calloc(self->m, sizeof(double), err)) ||
                   !(self->nbuf = gs_calloc(self->n, sizeof(double), err)) ||
                   !(self->g0 = gs_calloc(self->nd, sizeof(double), err))))
    return GS_ENOMEM;
  self->step = gsl_odeiv2_step_alloc(gs_rk_step_type(variant), self->m);
  /* a_y = 1, a_dydt = 0: tolerance rtol * |y_i| + atol * scale_i */
  self->control = gsl_odeiv2_control_alloc(&gs_rk_control_type);
  if (self->control) {
    gsl_odeiv2_control_init(self->control, self->atol, self->rtol, 1.0, 0.0);
    gs_rk_control *c = self->control->state;
    c->scale = self->scale;
    c->rk = self;
  }
  self->evolve = gsl_odeiv2_evolve_alloc(self->m);
  if (!self->step || !self->control || !self->evolve)
    return gs_error_set(err, GS_ENOMEM, "integrator rk: out of memory for %zu components", self->m);
  return GS_OK;
}

/* The key `outflow`: a registered treatment (default exponential). */
static int gs_rk_read_outflow(gs_cfg_node *solver, const gs_rk_outflow **out, gs_error *err) {
  const void *const *types = (const void *const *)gs_rk_outflows;
  const char *name = gs_rk_outflows[0]->name;
  int rc = solver ? gs_cfg_string_opt(solver, "outflow", name, &name, err) : GS_OK;
  if (rc) return rc;
  if ((*out = gs_registry_find(types, name))) return GS_OK;
  char known[128], hint[96] = "";
  gs_registry_names(types, known, sizeof known);
  const char *names[8];
  size_t count = 0;
  while (gs_rk_outflows[count] && count < 8) names[count] = gs_rk_outflows[count]->name, count++;
  const char *near = gs_nearest_word(name, names, count);
  if (near) snprintf(hint, sizeof hint, " (did you mean '%s'?)", near);
  return gs_cfg_fail(gs_cfg_get(solver, "outflow"), err, "unknown outflow treatment%s; expected one of: %s", hint, known);
}

/* The settings: a gs_rk with its keys filled in and nothing allocated. */
static int gs_rk_read(gs_cfg_node *solver, void **out, gs_error *err) {
  gs_rk *set = gs_calloc(1, sizeof *set, err);
  if (!set) return GS_ENOMEM;
  double h0;
  int variant = 1;
  int rc = gs_integrator_common_keys(solver, &set->rtol, &set->atol, &h0, &set->h_min,
                                     &set->h_max, &set->max_steps, err);
  if (!rc) rc = gs_cfg_enum_opt(solver, "variant", gs_rk_variants, 1, &variant, err);
  if (!rc) rc = gs_rk_read_outflow(solver, &set->outflow, err);
  if (rc) {
    free(set);
    return rc;
  }
  set->variant = gs_rk_variants[variant];
  set->h = isnan(h0) ? 0.0 : h0;
  if (isnan(set->h_min)) set->h_min = 0.0;
  if (isnan(set->h_max)) set->h_max = HUGE_VAL;
  *out = set;
  return GS_OK;
}

static int gs_rk_create(const void *settings, const gs_ode *ode, void **out, gs_error *err) {
  gs_rk *self = gs_malloc(sizeof *self, err);
  if (!self) return GS_ENOMEM;
  *self = *(const gs_rk *)settings;
  self->n = ode->n;
  self->nd = ode->ndecay;
  self->k = ode->decay;
  self->m = self->n + self->nd;
  gs_interval_init(&self->interval);
  int variant = 0;
  while (strcmp(gs_rk_variants[variant], self->variant)) variant++;
  int rc = gs_rk_alloc_gsl(self, variant, ode, err);
  if (rc) {
    gs_rk_free(self);
    return rc;
  }
  *out = self;
  return GS_OK;
}

/* The largest of |v| in tolerance units (scale of y), over the components
 * in the error control (agreed across MPI ranks). */
static double gs_rk_tol_norm(const gs_rk *self, const double *v, const double *y) {
  double d = 0;
  for (size_t i = 0; i < self->n; i++) {
    if (self->scale[i] >= GS_RK_EXCLUDED_SCALE) continue;
    d = fmax(d, fabs(v[i]) / (self->atol * self->scale[i] + self->rtol * fabs(y[i])));
  }
  return self->ode->reduce_max ? self->ode->reduce_max(self->ode->ctx, d) : d;
}

/* First step, after Hairer, Nørsett and Wanner (Solving ODEs I, II.4): h0 =
 * 0.01 |y| / |f| in the tolerance norm, or the time f needs to move y by
 * 0.01 of a tolerance unit when y is below atol; then the change of f over
 * an Euler step of h0 estimates y'' and gives h1 = (0.01 / max(|f|,
 * |y''|))^(1 / (order + 1)), the step whose leading error term is 0.01 of a
 * tolerance unit.  h = min(100 h0, h1), as they advise, except where y is
 * below atol everywhere (an empty compartment filling): there h0 says
 * nothing about the solution's scale, and the 100 h0 cap had made the run
 * start at 1e-11 s and take 16 steps growing by 5x before its first second
 * (the controller corrects a guess that is too large within a rejection or
 * two). */
static int gs_rk_initial_estimate(gs_rk *self, double t, double span, const double *y, double *f0,
                                  double *f1, gs_error *err);
static int gs_rk_initial_step(gs_rk *self, double t, double span, const double *y,
                              gs_error *err) {
  /* scratch: evolve computes its own afterwards (reset below) */
  double *f0 = self->evolve->dydt_out, *f1 = self->evolve->dydt_in;
  self->try_t0 = t;
  self->plain = 1; /* y' itself, decay included */
  int rc = gs_rk_initial_estimate(self, t, span, y, f0, f1, err);
  self->plain = 0;
  return rc;
}

static int gs_rk_initial_estimate(gs_rk *self, double t, double span, const double *y, double *f0,
                                  double *f1, gs_error *err) {
  const gs_ode *ode = self->ode;
  double *y1 = self->evolve->yerr;
  if (ode->trying) ode->trying(ode->ctx, t, 0.0); /* an evaluation at t only */
  if (gs_rk_rhs(t, y, f0, self) != GSL_SUCCESS || gs_rk_agree(self)) return gs_rk_rhs_error(self, err);
  const double d0 = gs_rk_tol_norm(self, y, y), d1 = gs_rk_tol_norm(self, f0, y);
  double h0 = (d1 > 0 && isfinite(d1)) ? 0.01 * fmax(d0, 1.0) / d1 : span;
  h0 = fmin(fmin(h0, span), self->h_max);
  double h = h0;
  if (d1 > 0 && isfinite(d1) && h0 < span) {
    for (size_t i = 0; i < self->n; i++) y1[i] = y[i] + h0 * f0[i];
    if (ode->trying) ode->trying(ode->ctx, t, h0);
    if (gs_rk_rhs(t + h0, y1, f1, self) != GSL_SUCCESS || gs_rk_agree(self))
      return gs_rk_rhs_error(self, err);
    for (size_t i = 0; i < self->n; i++) f1[i] -= f0[i];
    const double d2 = gs_rk_tol_norm(self, f1, y) / h0, big = fmax(d1, d2);
    const double h1 = pow(0.01 / big, 1.0 / (gsl_odeiv2_step_order(self->step) + 1.0));
    h = d0 < 1.0 ? h1 : fmin(100.0 * h0, h1);
  }
  gsl_odeiv2_evolve_reset(self->evolve);
  self->h = fmin(fmin(h, span), self->h_max);
  if (self->h < self->h_min) self->h = self->h_min;
  return GS_OK;
}

static int gs_rk_all_finite(const double *y, size_t n) {
  for (size_t i = 0; i < n; i++)
    if (!isfinite(y[i])) return 0;
  return 1;
}

/* Undo the failed step: evolve keeps the state it started from in y0. */
static int gs_rk_fail(gs_rk *self, int status, double t0, double h, double *t, double *y,
                      gs_error *err) {
  memcpy(y, self->evolve->y0, self->n * sizeof *y);
  *t = t0;
  gsl_odeiv2_step_reset(self->step); /* required by GSL after GSL_EBADFUNC */
  if (self->rhs_failed) return gs_rk_rhs_error(self, err);
  if (status == GSL_FAILURE)
    return gs_error_set(err, GS_ENUMERIC,
                        "integrator rk (%s): step size underflow at t = %.9g (h = %g): the "
                        "tolerances cannot be met",
                        self->variant, t0, h);
  return gs_error_set(err, GS_ENUMERIC, "integrator rk (%s): %s at t = %.9g", self->variant,
                      gsl_strerror(status), t0);
}

/* A step GSL accepted may still be unusable: NaN slips through its error
 * control (NaN never exceeds the tolerance), so roll such a step back. */
static int gs_rk_check_finite(gs_rk *self, double t0, double *t, double *y, gs_error *err) {
  int ok;
  const double *Y = self->nd ? self->yx : y; /* GSL's state */
  if (!self->ode->reduce_max) {
    ok = gs_rk_all_finite(Y, self->m);
  } else {
    /* failures anywhere: agreed in the controller with the error (GSL calls
     * it after every step it tries), otherwise here */
    double bad = self->agreed ? (self->rhs_failed ? 2.0 : self->agreed_nonfinite ? 1.0 : 0.0)
                              : self->ode->reduce_max(self->ode->ctx,
                                                      self->rhs_failed                  ? 2.0
                                                      : gs_rk_all_finite(Y, self->m) ? 0.0
                                                                                        : 1.0);
    if (bad == 2.0) {
      if (!self->rhs_failed) self->rhs_failed = 3;
      memcpy(y, self->evolve->y0, self->n * sizeof *y);
      *t = t0;
      return gs_rk_rhs_error(self, err);
    }
    ok = bad == 0.0;
  }
  if (ok) return GS_OK;
  memcpy(y, self->evolve->y0, self->n * sizeof *y);
  *t = t0;
  return gs_error_set(err, GS_ENUMERIC,
                      "integrator rk: state became NaN or infinite in the step from t = %.9g "
                      "(h = %g)",
                      t0, self->evolve->last_step);
}

/* GSL has no lower step bound; a (non-final) step below min_step fails. */
static int gs_rk_check_min_step(const gs_rk *self, double t, double t_out, gs_error *err) {
  double h = self->evolve->last_step;
  if (h >= self->h_min || t >= t_out) return GS_OK;
  return gs_error_set(err, GS_ENUMERIC,
                      "integrator rk: step size %g fell below min_step = %g at t = %.9g", h,
                      self->h_min, t);
}

/* After a step accepted from t0, for a system with a decay: the state
 * y1 = phi u1 + psi g0 in the caller's y (re-based: u = y from here on),
 * what the decay removed, y0 + W - y1, into gs_ode.decayed, W back to 0;
 * and for the exponential treatment the next step's g0, f at the end of
 * this one, which W' holds (the last evaluation was at the end of the
 * accepted step, at t0 + h: rkf45, rkck and rk8pd give it), with the
 * end-of-step rate that GSL reuses as the next step's first stage, u' = 0. */
static void gs_rk_rebase(gs_rk *self, double t0, double *y) {
  const size_t n = self->n, nd = self->nd;
  double *Y = self->yx, *dydt = self->evolve->dydt_out, *out = self->ode->decayed;
  const double *y0 = self->evolve->y0;
  gs_rk_frame fr;
  gs_rk_frame_at(self, t0 + self->evolve->last_step, &fr);
  const int expo = gs_rk_expo(self);
  for (size_t i = 0; i < nd; i++) {
    const double y1 = gs_rk_frame_y(self, &fr, i, Y[i]);
    out[i] = (y0[i] + Y[n + i]) - y1;
    Y[i] = y1;
    Y[n + i] = 0;
    if (expo) { /* f at the new start is g0 there, so u' = 0 */
      self->g0[i] = dydt[n + i];
      dydt[i] = 0;
    }
  }
  memcpy(y, Y, n * sizeof *y);
}

/* A case whose steps rk's stability limit holds down crawls without failing
 * for a long time (max_steps_per_output is 1e7).  After GS_RK_STIFF_LOOK
 * steps in one output interval, and at each doubling, the spectral radius
 * is estimated (src/ode/stiffness.c); when it holds the step and would
 * cost more than GS_RK_STIFF_LOOK further steps, the run is told once, with
 * the methods that step past it.  Not under MPI or per-compartment steps,
 * where f is not this process's or this integrator's alone, nor with the
 * exponential outflow, whose steps the outflow's rate does not hold. */
#define GS_RK_STIFF_LOOK 4096 /* a power of two */
static int gs_rk_look_for_stiffness(gs_rk *self, const gs_ode *ode, double t, double t_out,
                                    const double *y, gs_error *err) {
  const long s = self->interval.steps + 1; /* this step included */
  if (self->stiff_said || ode->reduce_max || ode->trying || self->nd || s < GS_RK_STIFF_LOOK ||
      (s & (s - 1)))
    return GS_OK;
  if (!self->est.f0) {
    int rc = gs_stiffness_init(&self->est, self->n, err);
    if (rc) return rc;
  }
  const double rho =
      gs_stiffness_radius(&self->est, ode, self->rtol, self->atol, t, y, &self->stats.rhs_evals);
  const double h = self->stats.last_step, cost = gs_stiffness_cost(rho, t, t_out);
  /* the band of gs_stiffness_held, twice as wide: the estimate is ||J v|| /
   * ||v||, which for the upwind transfer of growth (a bidiagonal J) tends
   * to up to twice its spectral radius; this costs a warning at most */
  if (!(h * rho >= 1.0 && h * rho <= 4.0 * GS_STIFFNESS_BETA) || !(cost > GS_RK_STIFF_LOOK))
    return GS_OK;
  self->stiff_said = 1;
  fprintf(stderr,
          "gransim: warning: solver rk: at t = %.6g s its steps (%.3g s) are held by its "
          "stability limit (Jacobian spectral radius %.3g /s): about %.3g more steps to t = "
          "%.6g s for stability alone; the case is stiff here, and method cvode (or auto) "
          "steps past it\n",
          t, h, rho, cost, t_out);
  return GS_OK;
}

static int gs_rk_advance(void *vself, const gs_ode *ode, double *t, double t_out, double *y,
                         gs_error *err) {
  gs_rk *self = vself;
  if (ode->n != self->n || ode->ndecay != self->nd || (self->nd && !ode->decayed) ||
      !(t_out >= *t))
    return gs_error_set(err, GS_EINPUT, "integrator rk: bad call (n = %zu for %zu, t = %g to %g)",
                        ode->n, self->n, *t, t_out);
  if (t_out == *t) return GS_OK;
  self->ode = ode;
  self->rhs_failed = 0;
  gsl_odeiv2_system sys = {gs_rk_rhs, NULL, self->m, self};
  /* GSL's state: the caller's, then W (0 at every step's start) */
  double *Y = y;
  if (self->nd) {
    Y = self->yx;
    memcpy(Y, y, self->n * sizeof *y);
    memset(Y + self->n, 0, self->nd * sizeof *Y);
  }
  /* GSL reuses the last step's end-of-step derivative as the next step's
   * first stage; across a jump in f it is the rate from before the switch,
   * and every step size failed the error test (error growing with h) until
   * h shrank to ~1e-3 s */
  if (ode->jumped) gsl_odeiv2_evolve_reset(self->evolve);
  if (self->h <= 0) {
    int rc = gs_rk_initial_step(self, *t, t_out - *t, y, err);
    if (rc) return rc;
  }
  gs_interval_begin(&self->interval, t_out);
  while (*t < t_out) {
    int rc = gs_interval_budget(&self->interval, self->max_steps, "rk", *t, err);
    if (rc) return rc;
    double t0 = *t, h = fmin(self->h, self->h_max);
    if (self->nd && self->outflow->exponential) h = fmin(h, GS_RK_MAX_KH / self->k);
    self->agreed = 0;
    /* evolve shortens the step that would pass t_out and then sets t = t_out
     * exactly; it leaves h at the controller's proposal for later calls. */
    self->try_t0 = t0;
    gs_rk_announce(self, t0, fmin(h, t_out - t0));
    /* GSL evaluates f at the start only after a reset (otherwise it reuses
     * the end of the last step): g0 comes from that evaluation */
    self->g0_pending = self->nd && self->evolve->count == 0;
    int status = gsl_odeiv2_evolve_apply(self->evolve, self->control, self->step, &sys, t, t_out,
                                         &h, Y);
    self->stats.rejected += (long)self->evolve->failed_steps;
    self->evolve->failed_steps = 0;
    if (status != GSL_SUCCESS) return gs_rk_fail(self, status, t0, h, t, y, err);
    rc = gs_rk_check_finite(self, t0, t, y, err);
    if (rc) return rc;
    self->h = h;
    self->stats.steps++;
    self->stats.last_step = self->evolve->last_step;
    rc = gs_rk_check_min_step(self, *t, t_out, err);
    if (rc) return rc;
    if (self->nd) gs_rk_rebase(self, t0, y);
    rc = gs_rk_look_for_stiffness(self, ode, *t, t_out, y, err);
    if (rc) return rc;
    if (gs_interval_step_done(&self->interval, ode)) return GS_OK;
    if (self->nd) memcpy(Y, y, self->n * sizeof *y); /* as between_steps left it */
  }
  return GS_OK;
}

static void gs_rk_stats(const void *vself, gs_integrator_stats *stats) {
  const gs_rk *self = vself;
  *stats = self->stats;
}

/* Besides h and the counters, GSL's evolve keeps only f at the end of the
 * last step (reused as the next step's first stage); a fresh evolve
 * evaluates it again at the same (t, y), which gives the same numbers, so
 * the steps are the same and only the count of evaluations grows by one. */
static void gs_rk_carry(void *vto, const void *vfrom) {
  gs_rk *to = vto;
  const gs_rk *from = vfrom;
  to->h = from->h;
  to->rejected_h = from->rejected_h;
  to->rejected_error = from->rejected_error;
  to->stats = from->stats;
  to->interval = from->interval;
  to->stiff_said = from->stiff_said;
}

/* At an output time: the step size and the controller's memory of a
 * rejection stay; GSL's end-of-step derivative goes (the first step after a
 * resume evaluates f at (t, y) again, and so does this one now: at the end
 * of a step that derivative was taken at t0 + h, which may differ from the
 * output time by an ulp). */
static void gs_rk_mark(void *vself, double *state) {
  gs_rk *self = vself;
  gsl_odeiv2_evolve_reset(self->evolve);
  state[0] = self->h;
  state[1] = self->rejected_h;
  state[2] = self->rejected_error;
  state[3] = 0;
}

static void gs_rk_resume(void *vself, const double *state) {
  gs_rk *self = vself;
  if (state[0] > 0) self->h = state[0]; /* 0: the start time, a fresh integrator's */
  self->rejected_h = state[1];
  self->rejected_error = state[2];
}

const gs_integrator_type gs_integrator_rk = {
    .name = "rk",
    .summary = "adaptive embedded Runge-Kutta from GSL, variant rkf45 | rkck | rk8pd",
    .read = gs_rk_read,
    .create = gs_rk_create,
    .advance = gs_rk_advance,
    .get_stats = gs_rk_stats,
    .free = gs_rk_free,
    .carry = gs_rk_carry,
    .release = gs_rk_release,
    .mark = gs_rk_mark,
    .resume = gs_rk_resume,
    .ranks = 1,
    .per_compartment = 1,
    .exact_invariants = 1,
};
