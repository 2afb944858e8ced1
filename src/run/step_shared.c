/* Stepping strategy "shared": one process advances every compartment with
 * the same steps, through the case's own integrator on the full state.
 * Between output times it stops at every rate switch (spray windows,
 * feeds): an integrator cannot step over a jump in f to tolerance. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/parallel.h"
#include "run/run_internal.h"

typedef struct {
  gs_run *run;
  gs_ode ode;    /* the case's system, evaluated in the run's context and checked */
  double t_rhs;  /* seconds in the rates */
  double t_busy; /* seconds advancing */
  double switch_reached; /* the switch time the last advance ended at */
  int bad;       /* a rate was not finite: at bad_t, entry bad_index */
  double bad_t;
  size_t bad_index;
} shared_t;

/* The model's rates in the run's context, with a guard against non-finite
 * rates (the failure then names where). */
static int shared_rhs(void *ctx, double t, const double *y, double *dydt) {
  shared_t *s = ctx;
  gs_run *run = s->run;
  const gs_model *m = &run->c->model;
  const double start = gs_run_now();
  run->ev.in_integrator = 1;
  gs_model_rhs(m, &run->ev, t, y, dydt, dydt + m->nstate);
  run->ev.in_integrator = 0;
  s->t_rhs += gs_run_now() - start;
  gs_run_during(run, t);
  const size_t n = m->nstate + m->nledger, i = gs_run_first_nonfinite(dydt, n);
  if (i == n) return 0;
  s->bad = 1;
  s->bad_t = t;
  s->bad_index = i;
  return 1;
}

static int shared_psolve(void *ctx, double t, const double *y, double gamma, const double *r,
                         double *z) {
  shared_t *s = ctx;
  gs_model_precondition(&s->run->c->model, &s->run->ev, t, y, gamma, r, z);
  return 0;
}

static void shared_hold(void *ctx, int on) {
  shared_t *s = ctx;
  s->run->ev.hold = on;
}

static void shared_conserve(void *ctx, double *v) {
  shared_t *s = ctx;
  gs_model_conserve(&s->run->c->model, v);
}

static int shared_create(gs_run *run, void **self, gs_error *err) {
  gs_case *c = run->c;
  shared_t *s = gs_calloc(1, sizeof *s, err);
  if (!s) return GS_ENOMEM;
  s->run = run;
  s->switch_reached = NAN;
  s->ode = c->ode;
  s->ode.ctx = s;
  s->ode.f = shared_rhs;
  s->ode.rates_checked = 1; /* shared_rhs checks every rate */
  if (s->ode.psolve) s->ode.psolve = shared_psolve;
  if (s->ode.hold) s->ode.hold = shared_hold;
  if (s->ode.conserve) s->ode.conserve = shared_conserve;
  /* --timings: each compartment's rates, for the bound on what a split over
   * ranks could gain */
  if (run->opt->timings && c->model.grid.ncomp > 1 &&
      !(run->ev.comp_seconds = gs_calloc(c->model.grid.ncomp, sizeof(double), err))) {
    free(s);
    return GS_ENOMEM;
  }
  *self = s;
  return GS_OK;
}

static int shared_advance(void *self, gs_run *run, gs_error *err) {
  shared_t *s = self;
  gs_case *c = run->c;
  const gs_model *m = &c->model;
  gs_integrator *it = &c->integrator;
  int rc = GS_OK;
  for (size_t i = 0; !rc && i < c->ntimes; i++) {
    if (c->times[i] <= run->t) continue;
    const double advance_start = gs_run_now();
    while (!rc && run->t < c->times[i]) {
      const double next_switch = gs_model_next_switch(m, run->t);
      const double stop = fmin(c->times[i], next_switch);
      run->ev.switch_lo = run->t; /* windows decide once for the interval (gs_window_on) */
      run->ev.switch_hi = stop;
      s->ode.jumped = run->t == s->switch_reached;
      rc = it->type->advance(it->self, &s->ode, &run->t, stop, run->Y, err);
      run->ev.switch_lo = 1;
      run->ev.switch_hi = 0;
      if (!rc && run->t == next_switch) s->switch_reached = run->t;
    }
    const double outputs_start = gs_run_now();
    s->t_busy += outputs_start - advance_start;
    if (rc && s->bad) rc = gs_run_rate_failure(m, s->bad_t, s->bad_index, err);
    if (!rc) gs_run_mark(run, it, 0);
    if (!rc) rc = gs_run_output_time(run, run->t, run->Y, err);
    run->phase[GS_PH_OUTPUTS] += gs_run_now() - outputs_start;
    if (run->stop) break;
  }
  run->phase[GS_PH_RHS] = s->t_rhs;
  run->phase[GS_PH_INTEGRATOR] = s->t_busy - s->t_rhs;
  return rc;
}

static void shared_resume(void *self, gs_run *run) {
  (void)self;
  const gs_integrator *it = &run->c->integrator;
  it->type->resume(it->self, run->resume_state);
}

static void shared_stats(const void *self, gs_integrator_stats *st) {
  const shared_t *s = self;
  const gs_integrator *it = &s->run->c->integrator;
  it->type->get_stats(it->self, st);
}

/* The rates of each compartment (the model's clock of each, the rest of the
 * rate time shared evenly, as the MPI rebalancing counts them), and what
 * ranks owning contiguous blocks of compartments could gain at most
 * (gs_dist_speedup_bound), for 2-8 ranks and the powers of two above, up to
 * the compartments.  On several threads the clocks of compartments run side
 * by side and add up to more than the wall time: nothing is printed then. */
static void shared_print_timings(const void *self, const gs_run *run, FILE *f) {
  (void)self;
  const gs_model *m = &run->c->model;
  const double *comp_seconds = run->ev.comp_seconds, *mine = run->phase;
  const size_t n = m->grid.ncomp;
  if (!comp_seconds || n < 2) return;
  if (omp_get_max_threads() > 1) {
    fprintf(f, "  (the rates per compartment and what ranks could gain: with --threads 1)\n");
    return;
  }
  const double total = gs_run_now() - run->start;
  double measured = 0;
  for (size_t j = 0; j < n; j++) measured += comp_seconds[j];
  const double rest = fmax(0.0, mine[GS_PH_RHS] - measured) / (double)n;
  fprintf(f, "  rates per compartment (s):");
  for (size_t j = 0; j < n; j++) fprintf(f, " %.4f", comp_seconds[j] + rest);
  fprintf(f, "\n  speed-up at most, compartments split over ranks (free messages):");
  for (int nr = 2; (size_t)nr <= n; nr = nr < 8 ? nr + 1 : 2 * nr) {
    double largest;
    double bound = gs_dist_speedup_bound(comp_seconds, n, mine[GS_PH_RHS], mine[GS_PH_INTEGRATOR],
                                         mine[GS_PH_FINISH], total, nr, &largest);
    fprintf(f, "%s %d ranks %.2fx", nr > 2 ? "," : "", nr, bound);
  }
  fprintf(f, "\n");
}

static void shared_free(void *self) {
  shared_t *s = self;
  if (s) {
    free(s->run->ev.comp_seconds);
    s->run->ev.comp_seconds = NULL;
  }
  free(s);
}

const gs_strategy_type gs_step_shared = {
    .name = "shared",
    .create = shared_create,
    .advance = shared_advance,
    .resume = shared_resume,
    .stats = shared_stats,
    .print_timings = shared_print_timings,
    .free = shared_free,
};
