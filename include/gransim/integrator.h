/* gransim — time integrators for the sectional ODE system.
 *
 * An integrator advances y' = f(t, y) from t to t_out.  Integrators are
 * registered types chosen by name in the case file's `solver.method`:
 *   "auto"   (default) rk while the case is not stiff, cvode while rk's steps
 *            would be held down by its stability limit (integrator_auto.c)
 *   "rk"     adaptive embedded Runge–Kutta from GSL odeiv2 (variant
 *            rkf45 | rkck | rk8pd, key `variant`, default rkck; a decay the
 *            system leaves out of f stepped as key `outflow` says,
 *            exponential | explicit, default exponential)
 *   "cvode"  SUNDIALS CVODE BDF for stiff cases (linear solver dense or gmres)
 *   "euler"  the adaptive explicit Euler of Sampat et al. (2018): dt doubled or halved so
 *            that dt * max(-f_i / y_i) stays below `safety` (default 0.1),
 *            within [min_step, max_step].
 * Components i with abs_scale[i] = 0 take part in the integration but not in
 * the error control (integrals nothing feeds back on, such as the volumes a
 * compartment discharged and received under per-compartment steps). */
#ifndef GRANSIM_INTEGRATOR_H
#define GRANSIM_INTEGRATOR_H

#include <stddef.h>
#include "gransim/cfg.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The default of the key atol.  A system whose numbers are far from 1 scales
 * its abs_scale instead (src/case/case.c: a case without solver.atol). */
#define GS_INTEGRATOR_ATOL 1e-12

/* The ODE system. */
typedef struct gs_ode {
  size_t n;
  /* Writes f(t, y) into dydt; returns 0, or non-zero to abort (err filled by caller context). */
  int (*f)(void *ctx, double t, const double *y, double *dydt);
  void *ctx;
  const double *abs_scale; /* n entries: 1 = normal error control, 0 = excluded; NULL = all 1 */
  /* Number of leading components that are number densities (must stay >= 0);
   * the Euler controller looks only at these. */
  size_t npositive;
  /* Optional preconditioner for implicit integrators: approximately solve
   * (I - gamma J) z = r, J the Jacobian of f at (t, y).  Returns 0, or
   * non-zero when it cannot.  NULL: none. */
  int (*psolve)(void *ctx, double t, const double *y, double gamma, const double *r, double *z);
  /* Optional: hold(ctx, 1) asks f to keep the discrete choices it made at
   * its last evaluation (e.g. which cells take part in aggregation) until
   * hold(ctx, 0), so that a difference quotient (f(y + s v) - f(y)) / s is a
   * derivative and not a jump.  NULL: f makes no such choices. */
  void (*hold)(void *ctx, int on);
  /* Optional, for a state distributed over MPI ranks (the rk and euler
   * integrators support it; cvode refuses it): each rank integrates its own
   * part of the state (f exchanges what it needs inside), and
   * reduce_max(ctx, v) returns the maximum of v over all ranks, so that
   * every rank accepts, rejects and sizes the same steps and fails on the
   * same evaluation.  NULL: a single process. */
  double (*reduce_max)(void *ctx, double v);
  /* 1: f itself fails (returns non-zero) rather than return a non-finite
   * rate, so the integrator need not scan every rate again (the run driver's
   * f does; it also says where).  0: the integrator checks. */
  int rates_checked;
  /* Optional (rk and euler call it): after every accepted step; non-zero
   * asks advance to return at once with *t short of t_out, and the caller
   * calls advance again for the rest of the interval, which takes the very
   * steps an uninterrupted advance would (the MPI run driver moves
   * compartments between ranks there).  NULL: never. */
  int (*between_steps)(void *ctx);
  /* 1 when f jumps at the time the next advance starts from (a rate
   * switched on or off there): derivatives an integrator kept from before
   * (the last step's end-of-step derivative, a multistep history) do not
   * hold there and are evaluated afresh.  The caller sets it per advance. */
  int jumped;
  /* Optional (rk calls it): the step about to be tried, from t0 over h,
   * before f is evaluated for it (also before a retry with a smaller h, and
   * with the span to t_out before the first step's size is estimated).  A
   * forcing that f interpolates per step, with an integral over [t0, t0 + h]
   * that the Runge-Kutta weights reproduce exactly, needs it (per-compartment
   * steps, src/run/compartment_steps.c).  NULL: f does not depend on it. */
  void (*trying)(void *ctx, double t0, double h);
  /* Optional (per-compartment steps' outflow; integrators with
   * per_compartment set serve it): the first ndecay components also decay
   * at -decay * y, a term f leaves out.  The integrator steps it as its
   * settings say (rk's `outflow`: exactly, by an integrating factor, or
   * explicitly with f), and after every accepted step, before
   * between_steps, writes into decayed[0..ndecay) what the decay removed in
   * that step, defined by the balance y0 + h sum_i b_i f_i - y1 (f_i the
   * stages' rates without the decay), so that the caller can book it
   * exactly.  ndecay 0: none. */
  size_t ndecay;
  double decay;
  double *decayed;
  /* Optional (rk's `outflow: exponential` follows it): after trying(ctx,
   * t0, h), the part of f over that step that is a known polynomial in
   * time for the ndecay decaying components (a compartment's inflow):
   * f_i(t) = sum_m c[m * ndecay + i] ((t - t0) / h)^m + the rest, m <
   * GS_ODE_FORCING_TERMS, or NULL when there is none for this step.  The
   * integrator then steps that part exactly with the decay, so that a
   * compartment which only passes its inflow on sets no bound on the step. */
  const double *(*forcing)(void *ctx);
  /* Optional (cvode's dense Jacobian calls it): restore in v, a direction of
   * the state (a column of a difference-quotient Jacobian), the linear
   * invariants that f keeps (the volume ledger), by recomputing the entries
   * that follow from the others.  Differences of f carry its round-off
   * divided by the increment, ~1e-8 of a column; a Newton system built from
   * them would move the invariants by that much at every step. */
  void (*conserve)(void *ctx, double *v);
} gs_ode;
#define GS_ODE_FORCING_TERMS 5 /* a quartic */

typedef struct gs_integrator_stats {
  long steps;      /* accepted steps */
  long rejected;   /* rejected steps */
  long rhs_evals;  /* right-hand-side evaluations */
  double last_step;
} gs_integrator_stats;

/* Values an integrator's mark (below) writes. */
#define GS_INTEGRATOR_MARK 4

typedef struct gs_integrator_type {
  const char *name;
  const char *summary;
  /* Read settings from the solver map (keys other than `method`) into one
   * malloc'ed block (freed with free); must mark every key it reads.  Common
   * keys all integrators accept: rtol, atol, initial_step, max_step,
   * min_step, max_steps_per_output. */
  int (*read)(gs_cfg_node *solver, void **settings, gs_error *err);
  /* An integrator of the system ode with those settings. */
  int (*create)(const void *settings, const gs_ode *ode, void **self, gs_error *err);
  /* Integrate from *t to t_out (exactly), updating y and *t.  On failure
   * returns GS_ENUMERIC with the time reached in the message. */
  int (*advance)(void *self, const gs_ode *ode, double *t, double t_out, double *y,
                 gs_error *err);
  void (*get_stats)(const void *self, gs_integrator_stats *stats);
  void (*free)(void *self);
  /* Optional: frees what read made (NULL: free(), one block). */
  void (*free_settings)(void *settings);
  /* Optional: a sentence on what it decided during the run, for the user
   * (auto: when and why it switched to CVODE); returns 0 when there is
   * nothing to say. */
  int (*describe)(const void *self, char *buf, size_t size);
  /* Optional: carry on where `from` (the same type, any n) stopped, with its
   * step size and counters, so that an integrator rebuilt on another part
   * of the state (MPI ranks taking over compartments) takes exactly the
   * steps the old one would have.  NULL: the type keeps more history, and a
   * run with it never moves compartments between ranks. */
  void (*carry)(void *to, const void *from);
  /* Optional, with carry: free the vectors of an integrator about to be
   * replaced, keeping what carry reads, so that its successor can reuse
   * that memory.  After it only carry and free may be called. */
  void (*release)(void *self);
  /* Exact resume.  mark is called at every output time, after the advance
   * that reached it: the integrator drops what it keeps beyond a few numbers
   * (GSL's end-of-step derivative; CVODE's whole history, restarted at the
   * next advance) and writes those numbers (its step size, its controller's
   * state; GS_INTEGRATOR_MARK values, 0 where unused) into state.  resume
   * gives them to an integrator created afresh, which then takes exactly the
   * steps the marked one takes from there (all zeros: a fresh integrator's,
   * as at the start time).  The result files keep them with every output
   * time, so a run killed and resumed gives the uninterrupted run's results
   * bit for bit.  Both required. */
  void (*mark)(void *self, double *state);
  void (*resume)(void *self, const double *state);
  /* Capabilities, which the run driver and the case reader consult instead
   * of names: */
  int ranks;            /* 1: integrates a state spread over MPI ranks (gs_ode.reduce_max) */
  int per_compartment;  /* 1: serves per-compartment steps (calls gs_ode.trying; its steps
                         * integrate a quartic forcing exactly; serves gs_ode.ndecay) */
  int exact_invariants; /* 1: linear invariants such as the volume ledger hold to round-off
                         * (0: implicit; its Newton systems keep them, through gs_ode.conserve
                         * and a conserving psolve, but round-off in its iterations can
                         * move them to ~1e-10) */
} gs_integrator_type;

const gs_integrator_type *gs_integrator_lookup(const char *name);
const gs_integrator_type *const *gs_integrator_types(void); /* NULL-terminated */

/* An integrator type with its settings, read from a case's solver map: what
 * a run driver needs to create integrators of any system, without reading
 * the case file again. */
typedef struct gs_integrator_setup {
  const gs_integrator_type *type;
  void *settings;
} gs_integrator_setup;

/* Read `method` (default "auto") then the type's keys from the solver map.
 * Unknown keys are not checked here: the caller reads its own keys of the
 * same map and then calls gs_cfg_check_unused.  solver may be NULL (all
 * defaults). */
int gs_integrator_setup_read(gs_cfg_node *solver, gs_integrator_setup *out, gs_error *err);
void gs_integrator_setup_free(gs_integrator_setup *setup);

typedef struct gs_integrator {
  const gs_integrator_type *type;
  void *self;
} gs_integrator;

/* An integrator of the system ode from a setup. */
int gs_integrator_create(const gs_integrator_setup *setup, const gs_ode *ode, gs_integrator *out,
                         gs_error *err);
void gs_integrator_free(gs_integrator *it);

#ifdef __cplusplus
}
#endif
#endif
