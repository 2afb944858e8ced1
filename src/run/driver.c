/* The run driver: a case's state through its output times, with one
 * stepping strategy and a list of observers (include/gransim/run.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "gransim/parallel.h"
#include "pbm/all_finite.h"
#include "run/run_internal.h"

double gs_run_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int gs_run_test_moves(void) {
  const char *e = getenv("GRANSIM_TEST_MOVE_COMPARTMENTS");
  return e && strcmp(e, "0") != 0;
}

void gs_run_describe_cell(const gs_model *m, size_t comp, size_t cell, char *buf, size_t len) {
  const gs_grid *g = &m->grid;
  size_t idx[GS_MAX_DIM];
  gs_grid_unindex(g, cell, idx);
  int w = snprintf(buf, len, "compartment %zu, cell (", comp + 1);
  for (int k = 0; k < g->dim && w < (int)len; k++)
    w += snprintf(buf + w, len - (size_t)w, "%s%zu", k ? ", " : "", idx[k] + 1);
  w += snprintf(buf + w, len - (size_t)w, ") [");
  for (int k = 0; k < g->dim && w < (int)len; k++)
    w += snprintf(buf + w, len - (size_t)w, "%s%s = %g", k ? ", " : "", g->axis[k].name,
                  g->x[cell * (size_t)g->dim + (size_t)k]);
  if (w < (int)len) snprintf(buf + w, len - (size_t)w, "]");
}

size_t gs_run_first_nonfinite(const double *f, size_t n) {
  if (gs_all_finite(f, n)) return n; /* the vectorised test; the search only when it fails */
  size_t i = 0;
  while (i < n && isfinite(f[i])) i++;
  return i;
}

int gs_run_rate_failure(const gs_model *m, double t, size_t idx, gs_error *err) {
  const gs_grid *g = &m->grid;
  char where[512];
  if (idx < m->nnum) gs_run_describe_cell(m, idx / g->ncells, idx % g->ncells, where, sizeof where);
  else if (idx < m->scalar_at) snprintf(where, sizeof where, "carried volume entry %zu", idx - m->nnum);
  else if (idx < m->nstate)
    snprintf(where, sizeof where, "scalar %zu of compartment %zu (a mechanism's state)",
             (idx - m->scalar_at) % m->nscalar + 1, (idx - m->scalar_at) / m->nscalar + 1);
  else snprintf(where, sizeof where, "volume ledger entry %zu", idx - m->nstate);
  return gs_error_set(err, GS_ENUMERIC,
                      "numerical failure at t = %g: %s: the rate of change is not finite (NaN or "
                      "infinity); check kernel and mechanism parameters",
                      t, where);
}

int gs_run_agree(gs_dist *d, int rc, gs_error *err) {
  if (d->size < 2) return rc;
  int worst = (int)gs_dist_max(d, (double)rc);
  if (worst && !rc) rc = gs_error_set(err, worst, "the run failed on another MPI rank");
  return rc;
}

void gs_run_stats(const gs_run *run, gs_integrator_stats *st) {
  memset(st, 0, sizeof *st);
  if (run->strategy_self) run->strategy->stats(run->strategy_self, st);
}

size_t gs_run_resume_size(const gs_case *c) {
  return (c->per_compartment ? c->model.grid.ncomp : 1) * (size_t)GS_INTEGRATOR_MARK;
}

void gs_run_mark(gs_run *run, const gs_integrator *it, size_t offset) {
  it->type->mark(it->self, run->resume_state + offset);
  run->ev.era++;
}

int gs_run_output_time(gs_run *run, double t, const double *Y, gs_error *err) {
  run->view.wall_seconds = gs_run_now() - run->start;
  for (size_t i = 0; i < run->nobs; i++) {
    const gs_observer *o = &run->obs[i];
    int stop = 0;
    int rc = o->type->output ? o->type->output(o->self, &run->view, t, Y, &stop, err) : GS_OK;
    if (rc) return rc;
    if (stop) run->stop = 1;
  }
  return GS_OK;
}

void gs_run_during(gs_run *run, double t) {
  if (!run->has_during) return;
  const double now = gs_run_now();
  if (now < run->next_during) return;
  run->next_during = now + GS_RUN_DURING_EVERY;
  run->view.wall_seconds = now - run->start;
  for (size_t i = 0; i < run->nobs; i++)
    if (run->obs[i].type->during) run->obs[i].type->during(run->obs[i].self, &run->view, t);
}

int gs_run_idle(gs_run *run) {
  int more = 0;
  for (size_t i = 0; i < run->nobs; i++)
    if (run->obs[i].type->idle && run->obs[i].type->idle(run->obs[i].self)) more = 1;
  return more;
}

/* The built-in observers this process runs (rank 0: all that apply; the
 * others: the collective timings), then the caller's. */
static int add_observers(gs_run *run, gs_error *err) {
  const gs_run_options *opt = run->opt;
  const int root = run->dist.rank == 0;
  const int show = root && (opt->progress >= 0 ? opt->progress : isatty(STDERR_FILENO));
  const struct {
    int on;
    const gs_builtin_observer *b;
  } builtin[] = {
      {root, &gs_observe_checks},
      {root && opt->out_dir, &gs_observe_output},
      {show, &gs_observe_progress},
      {opt->timings, &gs_observe_timings},
  };
  const size_t nb = sizeof builtin / sizeof builtin[0];
  run->obs = gs_calloc(nb + opt->nobservers, sizeof *run->obs, err);
  if (!run->obs) return GS_ENOMEM;
  for (size_t i = 0; i < nb; i++) {
    if (!builtin[i].on) continue;
    const gs_builtin_observer *b = builtin[i].b;
    gs_run **self = gs_calloc(1, b->size, err); /* its first member is the run */
    if (!self) return GS_ENOMEM;
    *self = run;
    int rc = b->init ? b->init(self, err) : GS_OK;
    if (rc) {
      b->type->free(self);
      return rc;
    }
    run->obs[run->nobs++] = (gs_observer){.type = b->type, .self = self};
  }
  run->nown = run->nobs;
  for (size_t i = 0; root && i < opt->nobservers; i++) run->obs[run->nobs++] = opt->observers[i];
  for (size_t i = 0; i < run->nobs; i++)
    if (run->obs[i].type->during) run->has_during = 1;
  return GS_OK;
}

static const gs_strategy_type *pick_strategy(const gs_run *run) {
  if (run->c->per_compartment) return &gs_step_compartments;
  return run->dist.size > 1 ? &gs_step_ranks : &gs_step_shared;
}

/* The observers' start (resume moves run->t and Y), agreed over the ranks,
 * and the start time handed to them. */
static int start_observers(gs_run *run, gs_error *err) {
  int rc = GS_OK;
  for (size_t i = 0; !rc && i < run->nobs; i++)
    if (run->obs[i].type->start)
      rc = run->obs[i].type->start(run->obs[i].self, &run->view, &run->t, run->Y, err);
  rc = gs_run_agree(&run->dist, rc, err);
  if (!rc && run->opt->resume && run->dist.size > 1) { /* the state rank 0 read back */
    gs_parallel_broadcast(&run->t, 1);
    gs_parallel_broadcast(run->Y, run->c->ode.n);
    gs_parallel_broadcast(run->resume_state, run->view.nresume);
  }
  if (!rc && run->dist.rank == 0) rc = gs_run_output_time(run, run->t, run->Y, err);
  rc = gs_run_agree(&run->dist, rc, err);
  if (!rc && run->dist.size > 1) { /* an observer may have ended the run already */
    double stop = run->stop;
    gs_parallel_broadcast(&stop, 1);
    run->stop = stop != 0;
  }
  return rc;
}

/* Every observer's finish, in order (the timings last see the others' time
 * as the final write); the first failure of a run that had succeeded. */
static int finish_observers(gs_run *run, int rc, gs_error *err) {
  const double start = gs_run_now();
  run->view.wall_seconds = start - run->start;
  for (size_t i = 0; i < run->nobs; i++) {
    run->phase[GS_PH_FINISH] = gs_run_now() - start;
    if (!run->obs[i].type->finish) continue;
    gs_error ferr = {0};
    int frc = run->obs[i].type->finish(run->obs[i].self, &run->view, rc == GS_OK, &ferr);
    if (!rc && frc) {
      *err = ferr;
      rc = frc;
    }
  }
  return rc;
}

int gs_case_run(gs_case *c, const gs_run_options *opt_in, double *yout, gs_run_report *rep_out,
                gs_error *err) {
  const gs_run_options opt = opt_in ? *opt_in : (gs_run_options){.progress = -1};
  gs_run_report rep;
  memset(&rep, 0, sizeof rep);
  gs_run run;
  memset(&run, 0, sizeof run);
  run.c = c;
  run.opt = &opt;
  run.rep = &rep;
  run.t = c->t0;
  run.ev = c->eval; /* the whole model, with the case's noise floor */
  run.start = gs_run_now();
  run.view = (gs_run_view){.c = c, .t_end = c->times[c->ntimes - 1], .resumed = opt.resume};
  const size_t n = c->ode.n;
  /* zeros: the marks of fresh integrators, the start time's */
  run.view.nresume = gs_run_resume_size(c);
  run.resume_state = gs_calloc(run.view.nresume, sizeof(double), err);
  run.view.resume = run.resume_state;
  int rc = (run.Y = gs_malloc(n * sizeof(double), err)) && run.resume_state ? GS_OK : GS_ENOMEM;
  if (!rc) memcpy(run.Y, c->y0, n * sizeof(double));
  /* under MPI each rank evaluates its own block of compartments */
  if (!rc) rc = gs_dist_init(&run.dist, &c->model, opt.one_process, err);
  if (!rc && run.dist.size > 1 && gs_model_couples_all(&c->model))
    rc = gs_error_set(err, GS_EINPUT, "this case's exchange network couples every compartment, "
                                      "which runs on one process: run it without mpirun");
  if (rc) {
    gs_dist_free(&run.dist);
    free(run.Y);
    free(run.resume_state);
    return rc;
  }
  rc = gs_run_agree(&run.dist, add_observers(&run, err), err);
  if (!rc) rc = start_observers(&run, err);
  run.strategy = pick_strategy(&run);
  if (!rc && !run.stop)
    rc = gs_run_agree(&run.dist, run.strategy->create(&run, &run.strategy_self, err), err);
  if (!rc && !run.stop && opt.resume) run.strategy->resume(run.strategy_self, &run);
  if (!rc && !run.stop) rc = run.strategy->advance(run.strategy_self, &run, err);
  rc = finish_observers(&run, rc, err);
  rc = gs_run_agree(&run.dist, rc, err);
  gs_run_stats(&run, &rep.stats);
  if (run.strategy_self) run.strategy->free(run.strategy_self);
  for (size_t i = 0; i < run.nown; i++)
    if (run.obs[i].type->free) run.obs[i].type->free(run.obs[i].self);
  free(run.obs);
  rep.t_end = run.t;
  rep.stopped = run.stop && run.t < run.view.t_end;
  rep.wall_seconds = gs_run_now() - run.start;
  /* only rank 0's state is whole (and every rank's after a stop) */
  if (yout && run.dist.size > 1 && !rc && !run.stop) gs_parallel_broadcast(run.Y, n);
  if (yout) memcpy(yout, run.Y, n * sizeof(double));
  gs_dist_free(&run.dist);
  if (rep_out) *rep_out = rep;
  free(run.Y);
  free(run.resume_state);
  return rc;
}
