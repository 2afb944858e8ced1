/* The run driver: integrate a case over its output times, check the state
 * after each output interval, write outputs, report progress. */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "gransim/case.h"
#include "gransim/output.h"
#include "gransim/parallel.h"
#include "output/deferred_output.h"
#include "run/compartment_steps.h"
#include "pbm/all_finite.h"
#include "run/distributed.h"

/* Describe cell `cell` of compartment `comp`: "compartment 2, cell (3, 5) [solid = ..., ...]". */
static void describe_cell(const gs_model *m, size_t comp, size_t cell, char *buf, size_t len) {
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

/* Output times rank 0 may hold back under MPI (fewer when their copies would
 * exceed DEFER_BYTES): when they come faster than rank 0 can write them in
 * its waits, the oldest is written at once. */
#define DEFER_DEPTH 4
#define DEFER_BYTES ((size_t)64 << 20)

typedef struct {
  gs_case *c;
  gs_eval ev;    /* the evaluation of this process's compartments */
  gs_dist *dist; /* the compartments of each MPI rank */
  double *Y; /* under MPI: the full state, this rank's part current after each advance */
  double bad_t;
  size_t bad_index; /* in the full vector */
  int bad;
  double t_rhs, t_exchange; /* seconds in the model's rates, and in the MPI boundary exchange */
  double t_written; /* rank 0's own work at output times (checks, copies, writes) */
  /* under MPI, rank 0's output times written while it waits at step
   * agreements (deferred_output.h); the first failure of such a write, kept
   * for the next output time; seconds of writing inside the steps */
  gs_deferred_output *deferred;
  int deferred_rc;
  gs_error deferred_err;
  double t_deferred;
  /* seconds advancing the state, and in step agreements (waiting, and
   * rank 0's deferred writing) */
  double t_advance, t_agree;
  /* rebalancing (MPI): busy and output seconds at the last measurement;
   * the costs measured (rebalance_measure), a split's lo; moves taken */
  double busy_mark, written_mark, *spent;
  size_t *split_lo;
  long window_evals, evals_needed; /* evaluations in the last window, and in the next */
  long steps_seen, posted_at;      /* steps taken, and when the last window was summed */
  int move_wanted;
  double move_seconds; /* the last move took (the slowest rank) */
  /* the failure agreement of the last output time (gs_dist_max_lagged):
   * posted after step lagged_posted_at, and its outcome once known */
  long lagged_posted_at;
  int stop_code;
  double advance_start, t_advance_now; /* the advance in progress began; busy then */
  long rhs_calls, calls_mark; /* this rank's evaluations (the same count on every rank) */
  /* under MPI, an output time whose checks and copy (rank 0) and failure
   * agreement (every rank) wait for the first step agreement after it
   * (post_output_time); the run loop's state they need; seconds of it spent
   * inside the advances */
  int output_held;
  double held_t;
  gs_output *out;
  const double *M1_0;
  double *ymax_seen;
  gs_run_report *rep;
  int *out_rc;
  gs_error *out_err;
  double t_held;
  long rebalanced, moves_tried; /* moves_tried: GRANSIM_TEST_MOVE_COMPARTMENTS only */
} guard_t;

/* Page faults of this process so far: each costs ~14 µs on the project's VM,
 * so --timings shows those a run takes. */
static long minor_faults(void) {
  struct rusage ru;
  return getrusage(RUSAGE_SELF, &ru) ? 0 : ru.ru_minflt;
}

static double now_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Flag the first non-finite rate (index i of f is entry full(i) of the state). */
static int check_rates(guard_t *gd, double t, const double *f, size_t n, const gs_dist *local) {
  if (gs_all_finite(f, n)) return 0;
  for (size_t i = 0; i < n; i++)
    if (!isfinite(f[i])) {
      gd->bad = 1;
      gd->bad_t = t;
      gd->bad_index = local ? gs_dist_full_index(local, i) : i;
      return 1;
    }
  return 0;
}

/* Right-hand side with a guard against non-finite rates. */
static int guarded_rhs(void *ctx, double t, const double *y, double *dydt) {
  guard_t *gd = ctx;
  const gs_model *m = &gd->c->model;
  const double start = now_seconds();
  gd->ev.in_integrator = 1;
  gs_model_rhs(m, &gd->ev, t, y, dydt, dydt + m->nstate);
  gd->ev.in_integrator = 0;
  gd->t_rhs += now_seconds() - start;
  return check_rates(gd, t, dydt, m->nstate + m->nledger, NULL);
}

/* The same on this MPI rank's packed part yl of the state: the model reads
 * and writes the packed vectors directly (gs_eval.view_lo), with the
 * previous rank's last compartment, which transfer brings in, as its halo. */
static int local_rhs(void *ctx, double t, const double *yl, double *fl) {
  guard_t *gd = ctx;
  const gs_model *m = &gd->c->model;
  gs_dist *d = gd->dist;
  const double start = now_seconds();
  gs_eval *ev = &gd->ev;
  ev->comp_lo = ev->view_lo = d->lo[d->rank];
  ev->comp_hi = d->lo[d->rank + 1];
  ev->view_carried = d->len[0];
  ev->halo = gs_dist_sync(d, yl);
  const double synced = now_seconds();
  ev->in_integrator = 1;
  gs_model_rhs(m, ev, t, yl, fl, fl + d->len[0] + d->len[1]);
  ev->in_integrator = 0;
  gd->t_exchange += synced - start;
  gd->t_rhs += now_seconds() - synced;
  gd->rhs_calls++;
  return check_rates(gd, t, fl, d->nlocal, d);
}

/* The case's preconditioner, reached through the guard's case. */
static int guarded_psolve(void *ctx, double t, const double *y, double gamma, const double *r,
                          double *z) {
  guard_t *gd = ctx;
  gs_model_precondition(&gd->c->model, &gd->ev, t, y, gamma, r, z);
  return 0;
}

static void guarded_hold(void *ctx, int on) {
  guard_t *gd = ctx;
  gd->ev.hold = on;
}

/* One piece of a deferred output time (rank 0, waiting for the others at
 * a step agreement); 1 while more is left. */
static int write_piece(void *ctx) {
  guard_t *gd = ctx;
  if (gd->deferred_rc || !gs_deferred_output_pending(gd->deferred)) return 0;
  const double start = now_seconds();
  gd->deferred_rc = gs_deferred_output_work(gd->deferred, &gd->deferred_err);
  gd->t_deferred += now_seconds() - start;
  return !gd->deferred_rc && gs_deferred_output_pending(gd->deferred);
}

/* Step agreement across MPI ranks, where rank 0 writes held output times
 * while the others have not arrived (every rank makes the same
 * non-blocking call). */
static double post_output_time(guard_t *g);

static double guarded_max(void *ctx, double v) {
  guard_t *gd = ctx;
  gd->t_held += post_output_time(gd);
  const double start = now_seconds();
  v = gs_dist_max_while(gd->dist, v, gd->deferred ? write_piece : NULL, gd);
  gd->t_agree += now_seconds() - start;
  return v;
}

static int between_steps(void *ctx);

/* What advances the state: the case's integrator on the full vector, or,
 * under MPI, an integrator of this rank's own on its packed part, or with
 * solver.steps: per_compartment one integrator per compartment. */
typedef struct {
  gs_comp_steps *cs; /* per-compartment steps only */
  gs_integrator own; /* MPI only */
  gs_integrator *it;
  gs_ode ode;
  gs_dist *local; /* MPI only */
  double *yl, *scale;
} stepper_t;

static int stepper_init(stepper_t *s, gs_case *c, gs_dist *d, guard_t *guard, gs_error *err) {
  memset(s, 0, sizeof *s);
  s->ode = c->ode;
  s->ode.ctx = guard;
  s->ode.rates_checked = 1; /* guarded_rhs and local_rhs check every rate */
  if (c->per_compartment) {
    if (d->size > 1)
      return gs_error_set(err, GS_EINPUT,
                          "solver.steps: per_compartment runs in one process (its compartments "
                          "take their own steps one after the other); run it without mpirun, or "
                          "use steps: shared on %d MPI ranks",
                          d->size);
    return gs_comp_steps_create(c, &s->cs, err);
  }
  if (d->size < 2) {
    s->it = &c->integrator;
    s->ode.f = guarded_rhs;
    if (s->ode.psolve) s->ode.psolve = guarded_psolve;
    if (s->ode.hold) s->ode.hold = guarded_hold;
    return GS_OK;
  }
  s->local = d;
  s->yl = gs_malloc(d->nlocal * sizeof(double), err);
  s->scale = gs_malloc(d->nlocal * sizeof(double), err);
  if (!s->yl || !s->scale) return GS_ENOMEM;
  gs_dist_pack(d, c->abs_scale, s->scale);
  /* numbers and carried volumes come first in the packed vector too */
  s->ode = (gs_ode){d->nlocal, local_rhs, guard, s->scale, d->len[0] + d->len[1], NULL, NULL, guarded_max, 1, between_steps, 0, NULL};
  s->it = &s->own;
  return gs_integrator_create(&c->integrator_setup, &s->ode, &s->own, err);
}

static int stepper_advance(stepper_t *s, double *t, double t_out, double *Y, gs_error *err) {
  if (!s->local) return s->it->type->advance(s->it->self, &s->ode, t, t_out, Y, err);
  gs_dist_pack(s->local, Y, s->yl);
  int rc = s->it->type->advance(s->it->self, &s->ode, t, t_out, s->yl, err);
  guard_t *g = s->ode.ctx; /* if no step agreement did: Y still holds that time */
  g->t_held += post_output_time(g);
  gs_dist_unpack(s->local, s->yl, Y);
  return rc;
}

static void stepper_free(stepper_t *s) {
  gs_comp_steps_free(s->cs);
  if (s->local) gs_integrator_free(&s->own);
  free(s->yl);
  free(s->scale);
}

/* Every rank leaves together: when another rank failed, say so here. */
static int agree(gs_dist *d, int rc, gs_error *err) {
  if (d->size < 2) return rc;
  int worst = (int)gs_dist_max(d, (double)rc);
  if (worst && !rc) rc = gs_error_set(err, worst, "the run failed on another MPI rank");
  return rc;
}

static int check_state(const gs_case *c, const double *Y, const double *M1_0, double t,
                       double *ymax_seen, gs_run_report *rep, gs_error *err) {
  const gs_model *m = &c->model;
  const gs_grid *g = &m->grid;
  const int nvol = m->nvol;
  char where[512];
  double ymax = *ymax_seen; /* largest number seen so far in the run */
  /* the vectorised test, and the search for the culprit only when it fails
   * (isfinite and a libm fmax call per value: ~2-3 µs more per output time
   * of the CoriMix example, rank 0's work under MPI) */
  const int finite = gs_all_finite(Y, m->nstate);
  for (size_t i = 0; !finite && i < m->nstate; i++)
    if (!isfinite(Y[i])) {
      size_t j = i < m->nnum ? i : (i - m->nnum) % m->nnum;
      describe_cell(m, (i < m->nnum ? i : (i - m->nnum) / g->ncells / (size_t)m->ncarried) % g->ncomp,
                    j % g->ncells, where, sizeof where);
      return gs_error_set(err, GS_ENUMERIC, "numerical failure at t = %g: %s: %s is %g", t, where,
                          i < m->nnum ? "number" : "a carried volume", Y[i]);
    }
  for (size_t i = 0; i < m->nnum; i++) {
    const double a = fabs(Y[i]);
    ymax = a > ymax ? a : ymax; /* fmax, all being finite */
  }
  *ymax_seen = ymax;
  /* an absolute floor: a state that is still (nearly) empty has only round-off */
  const double floor_abs = fmax(1e-30, c->checks.negative_floor);
  for (size_t i = 0; i < m->nnum; i++)
    if (Y[i] < -c->checks.negative_tolerance * ymax - floor_abs) {
      describe_cell(m, i / g->ncells, i % g->ncells, where, sizeof where);
      return gs_error_set(err, GS_ENUMERIC,
                          "numerical failure at t = %g: %s: number %g is negative beyond round-off "
                          "(%g of the largest number %g; checks.negative_tolerance = %g). Tighten "
                          "solver.rtol/atol or check the rates",
                          t, where, Y[i], -Y[i] / ymax, ymax, c->checks.negative_tolerance);
    }
  /* carried volumes: the same rule per quantity; the absolute floor is that of
   * the numbers in volume units (the integrator's scale for carried totals) */
  const double qfloor = fmax(1e-30, c->checks.negative_floor * (m->ncarried ? c->abs_scale[m->nnum] : 1.0));
  for (int q = 0; q < m->ncarried; q++) {
    double qmax = 0;
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *Q = gs_model_carried_c(m, Y, comp, q);
      for (size_t cell = 0; cell < g->ncells; cell++) {
        const double a = fabs(Q[cell]);
        qmax = a > qmax ? a : qmax;
      }
    }
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *Q = gs_model_carried_c(m, Y, comp, q);
      for (size_t cell = 0; cell < g->ncells; cell++)
        if (Q[cell] < -c->checks.negative_tolerance * qmax - qfloor) {
          describe_cell(m, comp, cell, where, sizeof where);
          return gs_error_set(err, GS_ENUMERIC,
                              "numerical failure at t = %g: %s: carried %s %g is negative beyond "
                              "round-off (%g of the largest %g; checks.negative_tolerance = %g)",
                              t, where, m->carried[q], Q[cell], -Q[cell] / qmax, qmax,
                              c->checks.negative_tolerance);
        }
    }
  }
  const double *L = Y + m->nstate;
  double worst_frac = 0;
  int worst_k = -1, worst_sign = 0;
  for (int k = 0; k < nvol; k++) {
    double scale = 0, lost = 0;
    double held[g->ncomp];
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *led = L + comp * 2 * (size_t)nvol;
      held[comp] = gs_model_held(m, Y, comp, k);
      scale += M1_0[comp * (size_t)nvol + (size_t)k] + fabs(held[comp]) + fabs(led[k]);
      lost += led[nvol + k];
    }
    if (!(scale > 0)) continue;
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *led = L + comp * 2 * (size_t)nvol;
      double expect = M1_0[comp * (size_t)nvol + (size_t)k] + led[k] - led[nvol + k];
      double rel = fabs(held[comp] - expect) / scale;
      if (rel > rep->max_balance_error) rep->max_balance_error = rel;
      if (rel > c->checks.mass_tolerance)
        return gs_error_set(err, GS_ENUMERIC,
                            "numerical failure at t = %g: volume balance of '%s' broken in "
                            "compartment %zu: held %.12g, expected %.12g (initial + exchanged - "
                            "lost); relative error %.3g > checks.mass_tolerance = %g",
                            t, gs_model_vol_name(m, k), comp + 1, held[comp], expect, rel,
                            c->checks.mass_tolerance);
    }
    double frac = fabs(lost) / scale;
    if (frac > worst_frac) {
      worst_frac = frac;
      worst_k = k;
      worst_sign = lost > 0;
    }
  }
  if (worst_frac > rep->max_loss) rep->max_loss = worst_frac;
  if (worst_k >= 0 && worst_frac > c->checks.max_loss) {
    /* carried volumes are lost with the particles beyond the grid: name the axes */
    const gs_axis *ax = &g->axis[worst_k < g->dim ? worst_k : 0];
    return gs_error_set(err, GS_ENUMERIC,
                        "at t = %g, a fraction %.3g of the volume of '%s' has crossed the grid "
                        "boundaries (%s), more than checks.max_loss = %g. Extend axis '%s' (now "
                        "[%g, %g]) or raise checks.max_loss",
                        t, worst_frac, gs_model_vol_name(m, worst_k),
                        worst_sign ? "lost beyond the last pivot" : "created below the first pivot",
                        c->checks.max_loss, ax->name, ax->edges[0], ax->edges[ax->n]);
  }
  return GS_OK;
}

/* Rebalancing, under MPI, between steps (gs_ode.between_steps).  The cost
 * of each compartment over a window of evaluations is what the model
 * measured of each compartment's rates (gs_eval.comp_seconds), plus an even share of the rest of its rank's busy
 * seconds (rates and integrator work, not the waits for other ranks); rank
 * 0's seconds writing results count as work of rank 0 alone.  The ranks sum
 * these without waiting and decide one step later, on identical numbers,
 * so every rank takes the same decision without an agreement of its own.
 * When the best contiguous split for those costs promises a slowest rank at
 * least c->rebalance cheaper than the measured one, the integrators return
 * early, the ranks take the split and rebuild their integrators, which
 * carry on with the old step size, counters and interval
 * (gs_integrator_type.carry): not a single step changes, so the results are
 * the same for any split (a rebuilt RK integrator evaluates f once more at
 * the start of its first step, so the count of evaluations grows by one per
 * move).  Deciding between steps rather than at output times follows the
 * granulation front as it moves downstream: in the 32-compartment case the
 * 18 output intervals had been too coarse for it. */
#define MIN_EVALS 20        /* the shortest window */
#define MAX_EVALS 2000      /* the longest */
#define WINDOW_SECONDS 0.02 /* a window holds about this much work of the slowest rank */
/* a move must pay for itself within this many windows like the last one */
#define MOVE_PAYBACK_WINDOWS 4

/* Each rank's costs over the window, summed over the ranks without
 * waiting: per compartment, then each rank's writing. */
static void rebalance_measure(gs_case *c, gs_dist *d, guard_t *g) {
  gs_model *m = &c->model;
  const size_t ncomp = m->grid.ncomp;
  g->window_evals = g->rhs_calls - g->calls_mark;
  g->calls_mark = g->rhs_calls;
  memset(g->spent, 0, (ncomp + (size_t)d->size) * sizeof(double));
  /* busy: advancing the state, less the waits for other ranks (boundary
   * messages and step agreements): the rates and the integrator's own
   * vector work, which grows with the block too (a quarter of the
   * 32-compartment case) */
  const double busy = g->t_advance_now - g->t_exchange - g->t_agree - g->t_held;
  const double written = g->t_written + gs_deferred_output_seconds(g->deferred);
  const size_t own_lo = d->lo[d->rank], own_hi = d->lo[d->rank + 1];
  double measured = 0;
  double *comp_seconds = g->ev.comp_seconds;
  for (size_t j = own_lo; j < own_hi; j++) measured += comp_seconds[j];
  const double rest = fmax(0.0, busy - g->busy_mark - measured) / (double)(own_hi - own_lo);
  for (size_t j = own_lo; j < own_hi; j++) g->spent[j] = comp_seconds[j] + rest;
  memset(comp_seconds, 0, ncomp * sizeof(double));
  g->spent[ncomp + (size_t)d->rank] = written - g->written_mark;
  g->busy_mark = busy;
  g->written_mark = written;
  gs_dist_sum_post(d, g->spent, ncomp + (size_t)d->size); /* zeros elsewhere: exact */
}

/* The decision on the last window, into g->split_lo; 1 for a move.  The
 * next window is sized to hold WINDOW_SECONDS of the slowest rank's work:
 * shorter ones are mostly timing noise on a shared machine (the CoriMix
 * example's output intervals hold ~1 ms of rates each; deciding on each had
 * moved compartments back and forth up to 11 times). */
static int rebalance_decide(gs_case *c, gs_dist *d, guard_t *g) {
  const size_t ncomp = c->model.grid.ncomp;
  const int nr = d->size;
  size_t *lo = g->split_lo;
  gs_dist_sum_finish(d);
  double slowest = 0;
  for (int r = 0; r < nr; r++) {
    double block = g->spent[ncomp + (size_t)r];
    for (size_t j = d->lo[r]; j < d->lo[r + 1]; j++) block += g->spent[j];
    slowest = fmax(slowest, block);
  }
  const double evals = slowest > 0 ? WINDOW_SECONDS * (double)g->window_evals / slowest : MAX_EVALS;
  g->evals_needed = evals < MIN_EVALS ? MIN_EVALS : evals > MAX_EVALS ? MAX_EVALS : (long)evals;
  double largest = gs_dist_best_split(d, g->spent, g->spent + ncomp, lo);
  if (getenv("GRANSIM_TEST_MOVE_COMPARTMENTS")) {
    /* tests only: a move at every decision whatever the costs, one block
     * boundary after the other, so that tests/mpi_sectional.sh can check
     * that moves change no result without depending on timings */
    memcpy(lo, d->lo, ((size_t)nr + 1) * sizeof *lo);
    int b = 1 + (int)(g->moves_tried++ % (long)(nr - 1));
    if (lo[b] - lo[b - 1] > 1) lo[b]--;
    else if (lo[b + 1] - lo[b] > 1) lo[b]++;
    return 1;
  }
  /* worth it when the window would have been faster by more than the
   * threshold, and the gain of a few such windows exceeds what a move costs
   * (the last one's, agreed) */
  return memcmp(lo, d->lo, ((size_t)nr + 1) * sizeof *lo) && largest < (1 - c->rebalance) * slowest &&
         MOVE_PAYBACK_WINDOWS * (slowest - largest) > g->move_seconds;
}

/* gs_ode.between_steps of the MPI integrators: measure when a window is
 * full, decide one step later (by then the sum has long arrived; every rank
 * counts the same steps and evaluations, so all do the same). */
static int between_steps(void *ctx) {
  guard_t *g = ctx;
  g->steps_seen++;
  if (g->stop_code) return 1;
  /* the last output time's failures, one step after it (every rank posted
   * its part at that step's agreement): a failure stops every rank here,
   * not one whole output interval later */
  if (g->dist->lagged_pending && g->steps_seen > g->lagged_posted_at &&
      (g->stop_code = (int)gs_dist_max_lagged_finish(g->dist)))
    return 1;
  if (!g->spent) return 0; /* no rebalancing */
  if (!g->dist->sum_pending) {
    if (getenv("GRANSIM_TEST_MOVE_COMPARTMENTS") || g->rhs_calls - g->calls_mark >= g->evals_needed) {
      g->t_advance_now = g->t_advance + (now_seconds() - g->advance_start);
      rebalance_measure(g->c, g->dist, g);
      g->posted_at = g->steps_seen;
    }
    return 0;
  }
  if (g->steps_seen == g->posted_at) return 0;
  return g->move_wanted = rebalance_decide(g->c, g->dist, g);
}

/* The move decided between steps.  Y: this rank's block is current (the
 * integrator returned early); rank 0 collects the others' and sends the
 * whole state to every rank, which then takes its new block. */
static int rebalance_move(gs_case *c, gs_dist *d, stepper_t *s, guard_t *g, double *Y,
                          gs_error *err) {
  gs_model *m = &c->model;
  const double start = now_seconds();
  g->move_wanted = 0;
  /* the advance has posted a held output time already (stepper_advance);
   * were one left, its block would have to be received before the move's */
  g->t_held += post_output_time(g);
  gs_dist_collect(d, Y);
  gs_parallel_broadcast(Y, m->nstate + m->nledger);
  stepper_t old = *s; /* old.own is the old integrator (old.it points into *s) */
  /* the old vectors go first, so that the new ones reuse their pages (Y
   * holds the whole state now) */
  free(old.yl);
  free(old.scale);
  old.yl = old.scale = NULL;
  if (old.own.type->release) old.own.type->release(old.own.self);
  gs_dist_resplit(d, g->split_lo);
  int rc = stepper_init(s, c, d, g, err);
  if (!rc) s->it->type->carry(s->it->self, old.own.self);
  stepper_free(&old);
  g->rebalanced++;
  rc = agree(d, rc, err);
  /* fresh integrator vectors cost page faults: 1-11 ms per move in the
   * 32-compartment case */
  g->move_seconds = gs_dist_max(d, now_seconds() - start);
  return rc;
}

/* --timings: each rank's seconds per phase, summed into one table that rank
 * 0 prints (phases: integrator = advance minus rates, exchange and step
 * agreements, i.e. the integrator's own vector work, packing and rate
 * checks; waits = step agreements, less rank 0's deferred writing, which
 * counts as outputs). */
enum { PH_RHS, PH_EXCHANGE, PH_INTEGRATOR, PH_WAITS, PH_OUTPUTS, PH_FINISH, PH_N };

/* One rank: the rates of each compartment (the model's clock of each, the
 * rest of the rate time shared evenly, as the rebalancing counts them), and what ranks owning contiguous blocks of compartments
 * could gain at most (gs_dist_speedup_bound), for 2-8 ranks and the powers
 * of two above, up to the compartments.  On several threads the clocks of
 * compartments run side by side and add up to more than the wall time:
 * nothing is printed then. */
static void print_split_bounds(const gs_model *m, const double *comp_seconds, const double *mine,
                               double total) {
  const size_t n = m->grid.ncomp;
  if (!comp_seconds || n < 2) return;
  if (omp_get_max_threads() > 1) {
    fprintf(stderr, "  (the rates per compartment and what ranks could gain: with --threads 1)\n");
    return;
  }
  double measured = 0;
  for (size_t j = 0; j < n; j++) measured += comp_seconds[j];
  const double rest = fmax(0.0, mine[PH_RHS] - measured) / (double)n;
  fprintf(stderr, "  rates per compartment (s):");
  for (size_t j = 0; j < n; j++) fprintf(stderr, " %.4f", comp_seconds[j] + rest);
  fprintf(stderr, "\n  speed-up at most, compartments split over ranks (free messages):");
  for (int nr = 2; (size_t)nr <= n; nr = nr < 8 ? nr + 1 : 2 * nr) {
    double largest;
    double bound = gs_dist_speedup_bound(comp_seconds, n, mine[PH_RHS], mine[PH_INTEGRATOR],
                                         mine[PH_FINISH], total, nr, &largest);
    fprintf(stderr, "%s %d ranks %.2fx", nr > 2 ? "," : "", nr, bound);
  }
  fprintf(stderr, "\n");
}

/* --timings with per-compartment steps: each compartment's own steps. */
static void print_compartment_steps(const gs_comp_steps *cs, size_t ncomp) {
  fprintf(stderr, "  per-compartment steps (steps / rejected / evaluations / ms in rates / ms in tasks):");
  for (size_t comp = 0; comp < ncomp; comp++) {
    gs_integrator_stats st;
    gs_comp_steps_comp_stats(cs, comp, &st);
    double rates, tasks;
    gs_comp_steps_comp_seconds(cs, comp, &rates, &tasks);
    fprintf(stderr, "%s %ld/%ld/%ld/%.1f/%.1f", comp ? "," : "", st.steps, st.rejected, st.rhs_evals,
            1e3 * rates, 1e3 * tasks);
  }
  fprintf(stderr, "; largest coupling mismatch %.2g; %d thread%s, waiting %.4f s in all\n",
          gs_comp_steps_worst_coupling(cs), gs_comp_steps_threads(cs),
          gs_comp_steps_threads(cs) == 1 ? "" : "s", gs_comp_steps_wait_seconds(cs));
}

static void print_timings(const gs_dist *d, const double *mine) {
  const size_t n = (size_t)d->size * PH_N;
  double *all = calloc(n, sizeof *all);
  if (!all) return;
  memcpy(all + (size_t)d->rank * PH_N, mine, PH_N * sizeof *mine);
  if (d->size > 1) gs_parallel_sum(all, n); /* zeros elsewhere: exact */
  if (d->rank == 0) {
    fprintf(stderr, "gransim: where the time went (s)\n  %-5s %-12s %-9s %-11s %-7s %-8s %-12s %s\n",
            "rank", "rates (RHS)", "exchange", "integrator", "waits", "outputs", "final write",
            "compartments at the end");
    for (int r = 0; r < d->size; r++) {
      const double *x = all + (size_t)r * PH_N;
      char comps[48];
      snprintf(comps, sizeof comps, d->lo[r + 1] - d->lo[r] > 1 ? "%zu-%zu" : "%zu", d->lo[r] + 1,
               d->lo[r + 1]);
      fprintf(stderr, "  %-5d %-12.4f %-9.4f %-11.4f %-7.4f %-8.4f %-12.4f %s\n", r, x[PH_RHS],
              x[PH_EXCHANGE], x[PH_INTEGRATOR], x[PH_WAITS], x[PH_OUTPUTS], x[PH_FINISH], comps);
    }
  }
  free(all);
}

static void progress(const gs_case *c, double t, double t_end, const gs_integrator_stats *st,
                     double elapsed) {
  double span = t_end - c->t0;
  fprintf(stderr, "\rgransim: t = %-10.4g of %-10.4g (%3.0f%%)  %ld steps  %.1f s   ", t, t_end,
          span > 0 ? 100.0 * (t - c->t0) / span : 100.0, st->steps, elapsed);
  fflush(stderr);
}

/* At an output time (rank 0): check the state, then write it, or under MPI
 * hold it for writing in the waits of the next steps. */
static int output_time(gs_case *c, gs_output *out, guard_t *gd, double t, double *Y,
                       const double *M1_0, double *ymax_seen, gs_run_report *rep, gs_error *err) {
  const gs_model *m = &c->model;
  /* all of it is rank 0's own work for the rebalancing (the checks and the
   * copy it holds: ~0.4 ms per output time in the 32-compartment case, which
   * the others had waited for), less the pieces the deferred output counts */
  const double start = now_seconds(), pieces = gs_deferred_output_seconds(gd->deferred);
  int rc = check_state(c, Y, M1_0, t, ymax_seen, rep, err);
  if (!rc && gd->deferred_rc) { /* a deferred write failed during the steps */
    *err = gd->deferred_err;
    rc = gd->deferred_rc;
  } else if (!rc && out && gd->deferred) {
    rc = gs_deferred_output_push(gd->deferred, t, Y, err);
    /* held times may not delay a due commit: a killed run loses no more
     * than output.checkpoint promises (0: every output time commits) */
    if (!rc && gs_output_commit_due(out)) rc = gs_deferred_output_drain(gd->deferred, err);
  } else if (!rc && out) {
    rc = gs_output_write(out, m, t, Y, Y + m->nstate, err);
  }
  gd->t_written += now_seconds() - start - (gs_deferred_output_seconds(gd->deferred) - pieces);
  return rc;
}

/* An output time held under MPI, at the first step agreement after it
 * (every rank, in the same order among the collective calls): rank 0
 * collects the other blocks, checks and holds the state, and every rank
 * posts its failure agreement.  At the output time itself rank 0 had done
 * this before its first boundary message of the next interval, and the next
 * rank waited for it (~25 µs per output time, 2 ms of the example); at the
 * agreement rank 0 has sent every message of the step, and it is usually
 * early there.  The state of that time stays in Y until the next advance
 * returns (the integrators work on their packed copies). */
static double post_output_time(guard_t *g) {
  if (!g->output_held) return 0;
  g->output_held = 0;
  const double start = now_seconds();
  if (g->dist->rank == 0) gs_dist_collect(g->dist, g->Y); /* the others sent at that time */
  if (g->dist->rank == 0 && !*g->out_rc)
    *g->out_rc = output_time(g->c, g->out, g, g->held_t, g->Y, g->M1_0, g->ymax_seen, g->rep,
                             g->out_err);
  /* the last one was agreed one step after it was posted (between_steps) */
  const int earlier = (int)gs_dist_max_lagged(g->dist, (double)*g->out_rc);
  if (earlier && !g->stop_code) g->stop_code = earlier;
  g->lagged_posted_at = g->steps_seen;
  return now_seconds() - start;
}

/* The run stops for a failure at an output time: rank 0's own (rc, its
 * message in own), or another rank's (its code: agreed). */
static int failed_at_output(int rc, int agreed, const gs_error *own, gs_error *err) {
  if (!rc) return gs_error_set(err, agreed, "the run failed on another MPI rank");
  *err = *own;
  return rc;
}

/* The message for a rate that was not finite (guard.bad), naming where. */
static int rate_failure(const gs_model *m, const guard_t *gd, gs_error *err) {
  const gs_grid *g = &m->grid;
  char where[512];
  size_t idx = gd->bad_index;
  if (idx < m->nnum) describe_cell(m, idx / g->ncells, idx % g->ncells, where, sizeof where);
  else if (idx < m->nstate) snprintf(where, sizeof where, "carried volume entry %zu", idx - m->nnum);
  else snprintf(where, sizeof where, "volume ledger entry %zu", idx - m->nstate);
  return gs_error_set(err, GS_ENUMERIC, "numerical failure at t = %g: %s: the rate of change is not finite (NaN or infinity); check kernel and mechanism parameters", gd->bad_t, where);
}

/* Per-compartment steps: the run's stretches (between output times and
 * rate switches), and at each output time, which the threads reach one
 * after the other while others advance later stretches, the checks and the
 * write (stretch_done). */
typedef struct {
  gs_case *c;
  gs_output *out;
  guard_t *guard;
  const double *M1_0;
  double *ymax_seen;
  gs_run_report *rep;
  const int *is_output; /* per stretch: its end is an output time */
  int show;
  double start, t_end, t_outputs;
} stretch_run;

static int stretch_done(void *ctx, size_t k, double t, const double *Y, gs_error *err) {
  stretch_run *x = ctx;
  if (!x->is_output[k]) return GS_OK;
  const double start = now_seconds();
  int rc = output_time(x->c, x->out, x->guard, t, (double *)Y, x->M1_0, x->ymax_seen, x->rep, err);
  if (x->show) {
    double span = x->t_end - x->c->t0;
    fprintf(stderr, "\rgransim: t = %-10.4g of %-10.4g (%3.0f%%)  %.1f s   ", t, x->t_end,
            span > 0 ? 100.0 * (t - x->c->t0) / span : 100.0, now_seconds() - x->start);
    fflush(stderr);
  }
  x->t_outputs += now_seconds() - start;
  return rc;
}

static int run_stretches(gs_case *c, gs_comp_steps *cs, stretch_run *x, double *t, double *Y,
                         gs_error *err) {
  gs_model *m = &c->model;
  size_t cap = 64, n = 0;
  gs_stretch *st = gs_malloc(cap * sizeof *st, err);
  int *is_output = gs_malloc(cap * sizeof *is_output, err);
  int rc = st && is_output ? GS_OK : GS_ENOMEM;
  double at = *t, switch_reached = NAN;
  for (size_t i = 0; !rc && i < c->ntimes; i++) {
    if (c->times[i] <= at) continue;
    while (!rc && at < c->times[i]) {
      const double next_switch = gs_model_next_switch(m, at);
      const double stop = fmin(c->times[i], next_switch);
      if (n == cap) {
        cap *= 2;
        gs_stretch *s2 = realloc(st, cap * sizeof *st);
        if (s2) st = s2;
        int *o2 = s2 ? realloc(is_output, cap * sizeof *is_output) : NULL;
        if (o2) is_output = o2;
        if (!o2) rc = gs_error_set(err, GS_ENOMEM, "out of memory for the run's stretches");
        if (rc) break;
      }
      st[n] = (gs_stretch){at, stop, at == switch_reached};
      is_output[n++] = stop == c->times[i];
      if (stop == next_switch) switch_reached = stop;
      at = stop;
    }
  }
  x->is_output = is_output;
  if (!rc) rc = gs_comp_steps_run(cs, st, n, Y, stretch_done, x, err);
  if (!rc && n) *t = st[n - 1].t1;
  free(st);
  free(is_output);
  return rc;
}

int gs_case_run(gs_case *c, const gs_run_options *opt, double *yout, gs_run_report *rep_out,
                gs_error *err) {
  gs_model *m = &c->model;
  const gs_grid *g = &m->grid;
  const size_t n = c->ode.n;
  gs_run_report rep;
  memset(&rep, 0, sizeof rep);
  double *Y = gs_malloc(n * sizeof(double), err);
  double *M1_0 = gs_calloc(g->ncomp * (size_t)m->nvol, sizeof(double), err);
  if (!Y || !M1_0) {
    free(Y);
    free(M1_0);
    return GS_ENOMEM;
  }
  memcpy(Y, c->y0, n * sizeof(double));
  for (size_t comp = 0; comp < g->ncomp; comp++)
    for (int k = 0; k < m->nvol; k++) M1_0[comp * (size_t)m->nvol + (size_t)k] = gs_model_held(m, c->y0, comp, k);
  double t = c->t0, ymax_seen = 0;
  /* under MPI each rank evaluates its own block of compartments; rank 0
   * alone checks the whole state at output times and writes files and
   * progress (the others hold only their own block current) */
  gs_dist dist;
  int rc = gs_dist_init(&dist, m, err);
  if (rc) {
    free(Y);
    free(M1_0);
    return rc;
  }
  const int root = dist.rank == 0;
  int show = root && (opt && opt->progress >= 0 ? opt->progress : isatty(STDERR_FILENO));
  gs_output *out = NULL;
  if (opt && opt->out_dir && root) {
    out = opt->resume ? gs_output_resume(opt->out_dir, m, &t, Y, Y + m->nstate, err)
                      : gs_output_open(opt->out_dir, m, gs_cfg_source(c->cfg), gs_cfg_name(c->cfg), err);
    if (!out) rc = err->code;
    gs_output_set_checkpoint(out, c->checkpoint);
  }
  rc = agree(&dist, rc, err);
  if (!rc && opt && opt->resume && dist.size > 1) { /* the state rank 0 read back */
    gs_parallel_broadcast(&t, 1);
    gs_parallel_broadcast(Y, n);
  }
  if (!rc) rc = check_state(c, Y, M1_0, t, &ymax_seen, &rep, err);
  if (!rc && out && !(opt && opt->resume)) rc = gs_output_write(out, m, t, Y, Y + m->nstate, err);
  rc = agree(&dist, rc, err);
  guard_t guard;
  memset(&guard, 0, sizeof guard);
  guard.c = c;
  guard.ev = c->eval; /* the whole model, with the case's noise floor */
  guard.dist = &dist;
  guard.Y = Y;
  guard.M1_0 = M1_0;
  guard.ymax_seen = &ymax_seen;
  guard.rep = &rep;
  double phase[PH_N] = {0};
  stepper_t step;
  memset(&step, 0, sizeof step);
  if (!rc) rc = agree(&dist, stepper_init(&step, c, &dist, &guard, err), err);
  /* the compartments' own costs, for the rebalancing */
  if (!rc && dist.size > 1 && c->rebalance >= 0 &&
      (!(guard.ev.comp_seconds = gs_calloc(g->ncomp, sizeof(double), err)) ||
       !(guard.spent = gs_calloc(g->ncomp + (size_t)dist.size, sizeof(double), err)) ||
       !(guard.split_lo = gs_calloc((size_t)dist.size + 1, sizeof(size_t), err))))
    rc = GS_ENOMEM;
  /* --timings on one rank: each compartment's own rates, for the bound on
   * what a split over ranks could gain (print_timings) */
  if (!rc && dist.size == 1 && opt && opt->timings && g->ncomp > 1 &&
      !(guard.ev.comp_seconds = gs_calloc(g->ncomp, sizeof(double), err)))
    rc = GS_ENOMEM;
  guard.evals_needed = MIN_EVALS;
  if (!rc && step.it && !step.it->type->carry) { /* cvode: no rebalancing */
    free(guard.spent);
    guard.spent = NULL;
  }
  /* rank 0 of several holds output times back, to write them while it waits */
  if (!rc && out && dist.size > 1) {
    size_t fit = DEFER_BYTES / (n * sizeof(double));
    int depth = fit < 1 ? 1 : fit < DEFER_DEPTH ? (int)fit : DEFER_DEPTH;
    if (!(guard.deferred = gs_deferred_output_create(out, m, depth, err))) rc = GS_ENOMEM;
  }
  rc = agree(&dist, rc, err);
  int out_rc = GS_OK; /* rank 0's first failure at an output time, and its message */
  gs_error out_err = {0};
  guard.out = out;
  guard.out_rc = &out_rc;
  guard.out_err = &out_err;
  double start = now_seconds(), t_end = c->times[c->ntimes - 1];
  const long faults_start = minor_faults();
  gs_integrator_stats st = {0};
  double switch_reached = NAN; /* the switch time the last advance ended at */
  if (!rc && step.cs) {
    stretch_run x = {c, out, &guard, M1_0, &ymax_seen, &rep, NULL, show, start, t_end, 0};
    const double before = gs_comp_steps_rhs_seconds(step.cs), run_start = now_seconds();
    rc = run_stretches(c, step.cs, &x, &t, Y, err);
    guard.t_rhs += gs_comp_steps_rhs_seconds(step.cs) - before;
    guard.t_advance += now_seconds() - run_start - x.t_outputs;
    phase[PH_OUTPUTS] += x.t_outputs;
    if (rc && gs_comp_steps_bad_rate(step.cs, &guard.bad_t, &guard.bad_index)) {
      guard.bad = 1;
      rc = rate_failure(m, &guard, err);
    }
    gs_comp_steps_stats(step.cs, &st);
  }
  for (size_t i = 0; !rc && !step.cs && i < c->ntimes; i++) {
    if (c->times[i] <= t) continue;
    /* stop at every time where a rate switches on or off (spray windows,
     * feeds): an integrator cannot step over a jump in f to tolerance */
    const double advance_start = guard.advance_start = now_seconds();
    while (!rc && t < c->times[i]) {
      const double next_switch = gs_model_next_switch(m, t);
      const double stop = fmin(c->times[i], next_switch);
      guard.ev.switch_lo = t; /* windows decide once for the interval (gs_window_on) */
      guard.ev.switch_hi = stop;
      step.ode.jumped = t == switch_reached;
      rc = stepper_advance(&step, &t, stop, Y, err);
      guard.ev.switch_lo = 1;
      guard.ev.switch_hi = 0;
      if (!rc && t == next_switch) switch_reached = t;
      if (!rc && guard.stop_code) rc = failed_at_output(out_rc, guard.stop_code, &out_err, err);
      if (!rc && guard.move_wanted) rc = rebalance_move(c, &dist, &step, &guard, Y, err);
    }
    const double outputs_start = now_seconds();
    guard.t_advance += outputs_start - advance_start;
    if (rc && guard.bad) rc = rate_failure(m, &guard, err);
    if (dist.size > 1) {
      /* the checks and the failure agreement wait for the next step's
       * agreement (post_output_time); rank 0's failure then reaches the
       * others one step later, so that they never wait for its checks and
       * writing (until then rank 0 steps on with them and writes nothing
       * more).  Integrator failures are agreed already: hold only a good
       * state. */
      if (!rc) {
        if (!root) gs_dist_collect(&dist, Y); /* sent without waiting */
        guard.output_held = 1;
        guard.held_t = t;
      }
    } else if (!rc && !out_rc) {
      out_rc = output_time(c, out, &guard, t, Y, M1_0, &ymax_seen, &rep, &out_err);
      if (out_rc) rc = failed_at_output(out_rc, out_rc, &out_err, err);
    }
    phase[PH_OUTPUTS] += now_seconds() - outputs_start;
    if (step.it && step.it->type) /* not after a failed rebuild */
      step.it->type->get_stats(step.it->self, &st);
    if (show) progress(c, t, t_end, &st, now_seconds() - start);
  }
  if (show) fprintf(stderr, "\n");
  phase[PH_OUTPUTS] += post_output_time(&guard); /* the last output time: no step after it */
  const int late = dist.size > 1 ? (int)gs_dist_max_lagged_finish(&dist) : 0;
  gs_dist_sum_finish(&dist); /* a rebalancing sum still in flight writes into guard.spent */
  /* rank 0's failure came first: rank 0 says so, the others that it failed
   * there (not what went wrong in the steps they took after it) */
  if (late || guard.stop_code || out_rc)
    rc = failed_at_output(out_rc, late ? late : guard.stop_code ? guard.stop_code : out_rc, &out_err, err);
  const double finish_start = now_seconds();
  /* after the loop, not at the last output time: that one may be skipped
   * (equal to the time reached), and held times must not be lost */
  if (!rc && guard.deferred_rc) {
    rc = guard.deferred_rc;
    *err = guard.deferred_err;
  }
  if (!rc && guard.deferred) rc = gs_deferred_output_drain(guard.deferred, err);
  if (out) {
    gs_error ferr;
    int frc = gs_output_finish(out, rc == GS_OK, &ferr);
    if (!rc && frc) {
      *err = ferr;
      rc = frc;
    }
  }
  rc = agree(&dist, rc, err);
  phase[PH_FINISH] = now_seconds() - finish_start;
  phase[PH_RHS] = guard.t_rhs;
  phase[PH_EXCHANGE] = guard.t_exchange;
  phase[PH_INTEGRATOR] = guard.t_advance - guard.t_rhs - guard.t_exchange - guard.t_agree - guard.t_held;
  phase[PH_WAITS] = guard.t_agree - guard.t_deferred;
  phase[PH_OUTPUTS] += guard.t_deferred + guard.t_held;
  if (opt && opt->timings) {
    print_timings(&dist, phase);
    fprintf(stderr, "  page faults while it ran: %ld on rank %d\n", minor_faults() - faults_start, dist.rank);
    if (dist.size == 1 && !step.cs) print_split_bounds(m, guard.ev.comp_seconds, phase, now_seconds() - start);
    if (step.cs) print_compartment_steps(step.cs, g->ncomp);
    if (step.cs) gs_comp_steps_print_threads(step.cs, stderr);
  }
  rep.per_compartment = step.cs != NULL;
  if (step.cs) rep.worst_coupling = gs_comp_steps_worst_coupling(step.cs);
  stepper_free(&step);
  gs_deferred_output_free(guard.deferred);
  free(guard.ev.comp_seconds);
  free(guard.spent);
  free(guard.split_lo);
  gs_dist_free(&dist);
  rep.t_end = t;
  rep.stats = st;
  rep.rebalanced = guard.rebalanced;
  rep.wall_seconds = now_seconds() - start;
  if (yout && dist.size > 1 && !rc) gs_parallel_broadcast(Y, n); /* only rank 0's is whole */
  if (yout) memcpy(yout, Y, n * sizeof(double));
  if (rep_out) *rep_out = rep;
  free(Y);
  free(M1_0);
  return rc;
}
