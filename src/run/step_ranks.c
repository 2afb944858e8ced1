/* Stepping strategy "ranks": the compartments spread over MPI ranks in
 * contiguous blocks, every rank integrating its own block with the same
 * steps (an integrator of its own on its packed part of the state, which
 * agrees every step's size and acceptance with the others, gs_ode.reduce_max)
 * and exchanging the compartment at each block's end (transfer flows
 * downstream only).  Rank 0 alone checks and writes the whole state at
 * output times, which it collects from the others.
 *
 * Output times are held: the checks, the observers and the failure
 * agreement of an output time wait for the first step agreement after it
 * (post_output_time), where rank 0 has sent every message of the step and is
 * usually early; a failure of rank 0 there reaches the others one step later
 * (between_steps), so they never wait for its checks and writing.
 *
 * Rebalancing, between steps (gs_ode.between_steps).  The cost of each
 * compartment over a window of evaluations is what the model measured of
 * each compartment's rates (gs_eval.comp_seconds), plus an even share of the
 * rest of its rank's busy seconds (integrator work, not the waits for other
 * ranks); rank 0's seconds at output times count as work of rank 0 alone.
 * The ranks sum these without waiting and decide one step later, on
 * identical numbers, so every rank takes the same decision without an
 * agreement of its own.  When the best contiguous split for those costs
 * promises a slowest rank at least solver.rebalance cheaper than the
 * measured one, the integrators return early, the ranks take the split and
 * rebuild their integrators, which carry on with the old step size,
 * counters and interval (gs_integrator_type.carry): not a single step
 * changes, so the results are the same for any split (a rebuilt RK
 * integrator evaluates f once more at the start of its first step, so the
 * count of evaluations grows by one per move).  Deciding between steps
 * rather than at output times follows the granulation front as it moves
 * downstream, which coarse output intervals miss. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/parallel.h"
#include "run/run_internal.h"

#define MIN_EVALS 20        /* the shortest window */
#define MAX_EVALS 2000      /* the longest */
#define WINDOW_SECONDS 0.02 /* a window holds about this much work of the slowest rank */
/* a move must pay for itself within this many windows like the last one */
#define MOVE_PAYBACK_WINDOWS 4
/* rank 0's answer at an output time where an observer ended the run, agreed
 * like a failure (above every error code) */
#define STOP_CODE 100

typedef struct {
  gs_run *run;
  gs_dist *dist;
  gs_integrator own; /* this rank's integrator on its packed part */
  gs_ode ode;
  double *yl, *scale; /* the packed part of the state and its error-control scale */
  int bad;            /* a rate was not finite: at bad_t, full-state entry bad_index */
  double bad_t;
  size_t bad_index;
  double switch_reached;
  double t_rhs, t_exchange; /* seconds in the model's rates, and in the boundary exchange */
  double t_written; /* rank 0's own work at output times (checks, copies, writes) */
  double t_idle;    /* rank 0's observers' work in the waits */
  /* seconds advancing the state, and in step agreements (waiting, and rank
   * 0's idle work) */
  double t_advance, t_agree;
  /* rebalancing: busy and output seconds at the last measurement; the costs
   * measured (rebalance_measure), a split's lo; moves taken */
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
  /* an output time held for the first step agreement after it */
  int output_held;
  double held_t;
  int out_rc; /* rank 0's first failure at an output time, and its message */
  gs_error out_err;
  double *stop_Y; /* rank 0: the state where an observer ended the run, and its time */
  double stop_t;
  int has_idle;   /* this rank's observers have work for the waits */
  double t_held; /* seconds of held output times spent inside the advances */
  long moves_tried; /* GRANSIM_TEST_MOVE_COMPARTMENTS only */
} ranks_t;

/* The model's rates on this rank's packed part yl of the state: the model
 * reads and writes the packed vectors directly (gs_eval.view_lo), with the
 * previous rank's last compartment, which transfer brings in, as its halo. */
static int local_rhs(void *ctx, double t, const double *yl, double *fl) {
  ranks_t *g = ctx;
  gs_run *run = g->run;
  const gs_model *m = &run->c->model;
  gs_dist *d = g->dist;
  const double start = gs_run_now();
  gs_eval *ev = &run->ev;
  ev->comp_lo = ev->view_lo = d->lo[d->rank];
  ev->comp_hi = d->lo[d->rank + 1];
  ev->view_carried = d->len[0];
  ev->view_scalars = d->len[0] + d->len[1] + d->len[2]; /* after the ledger in the packed vector */
  ev->halo = gs_dist_sync(d, yl);
  const double synced = gs_run_now();
  ev->in_integrator = 1;
  gs_model_rhs(m, ev, t, yl, fl, fl + d->len[0] + d->len[1]);
  ev->in_integrator = 0;
  g->t_exchange += synced - start;
  g->t_rhs += gs_run_now() - synced;
  g->rhs_calls++;
  gs_run_during(run, t); /* rank 0 holds the observers */
  const size_t i = gs_run_first_nonfinite(fl, d->nlocal);
  if (i == d->nlocal) return 0;
  g->bad = 1;
  g->bad_t = t;
  g->bad_index = gs_dist_full_index(d, i);
  return 1;
}

/* A piece of rank 0's observers' work, while it waits for the others. */
static int idle_piece(void *ctx) {
  ranks_t *g = ctx;
  const double start = gs_run_now();
  int more = gs_run_idle(g->run);
  g->t_idle += gs_run_now() - start;
  return more;
}

/* An output time held, at the first step agreement after it (every rank, in
 * the same order among the collective calls): rank 0 collects the other
 * blocks and hands the state to the observers, and every rank posts its
 * failure agreement.  The state of that time stays in Y until the next
 * advance returns (the integrators work on their packed copies). */
static double post_output_time(ranks_t *g) {
  if (!g->output_held) return 0;
  g->output_held = 0;
  gs_run *run = g->run;
  const double start = gs_run_now();
  if (g->dist->rank == 0) gs_dist_collect(g->dist, run->Y); /* the others sent at that time */
  if (g->dist->rank == 0 && !g->out_rc) {
    /* all of it is rank 0's own work for the rebalancing (the checks and
     * the copy it holds, which the others would otherwise wait for) */
    const double out_start = gs_run_now();
    g->out_rc = gs_run_output_time(run, g->held_t, run->Y, &g->out_err);
    /* the others run on until they learn it: keep this time's state */
    const size_t n = run->c->ode.n;
    if (!g->out_rc && run->stop && (g->stop_Y = malloc(n * sizeof(double)))) {
      memcpy(g->stop_Y, run->Y, n * sizeof(double));
      g->stop_t = g->held_t;
      g->out_rc = STOP_CODE;
    } else if (!g->out_rc && run->stop) {
      g->out_rc = gs_error_set(&g->out_err, GS_ENOMEM, "out of memory");
    }
    g->t_written += gs_run_now() - out_start;
  }
  /* the last one was agreed one step after it was posted (between_steps) */
  const int earlier = (int)gs_dist_max_lagged(g->dist, (double)g->out_rc);
  if (earlier && !g->stop_code) g->stop_code = earlier;
  g->lagged_posted_at = g->steps_seen;
  return gs_run_now() - start;
}

static double agreed_max(void *ctx, double v) {
  ranks_t *g = ctx;
  g->t_held += post_output_time(g);
  const double start = gs_run_now();
  v = gs_dist_max_while(g->dist, v, g->has_idle ? idle_piece : NULL, g);
  g->t_agree += gs_run_now() - start;
  return v;
}

/* Each rank's costs over the window, summed over the ranks without
 * waiting: per compartment, then each rank's writing. */
static void rebalance_measure(ranks_t *g) {
  gs_dist *d = g->dist;
  const size_t ncomp = g->run->c->model.grid.ncomp;
  g->window_evals = g->rhs_calls - g->calls_mark;
  g->calls_mark = g->rhs_calls;
  memset(g->spent, 0, (ncomp + (size_t)d->size) * sizeof(double));
  /* busy: advancing the state, less the waits for other ranks (boundary
   * messages and step agreements): the rates and the integrator's own
   * vector work, which grows with the block too */
  const double busy = g->t_advance_now - g->t_exchange - g->t_agree - g->t_held;
  const double written = g->t_written + g->t_idle;
  const size_t own_lo = d->lo[d->rank], own_hi = d->lo[d->rank + 1];
  double *comp_seconds = g->run->ev.comp_seconds, measured = 0;
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
 * shorter ones are mostly timing noise on a shared machine (deciding on
 * each output interval of the CoriMix example had moved compartments back
 * and forth up to 11 times). */
static int rebalance_decide(ranks_t *g) {
  gs_dist *d = g->dist;
  const size_t ncomp = g->run->c->model.grid.ncomp;
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
  if (gs_run_test_moves()) {
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
  return memcmp(lo, d->lo, ((size_t)nr + 1) * sizeof *lo) &&
         largest < (1 - g->run->c->rebalance) * slowest &&
         MOVE_PAYBACK_WINDOWS * (slowest - largest) > g->move_seconds;
}

/* gs_ode.between_steps: the last output time's failure agreement, and the
 * rebalancing (measure when a window is full, decide one step later: by then
 * the sum has long arrived; every rank counts the same steps and
 * evaluations, so all do the same). */
static int between_steps(void *ctx) {
  ranks_t *g = ctx;
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
    if (gs_run_test_moves() || g->rhs_calls - g->calls_mark >= g->evals_needed) {
      g->t_advance_now = g->t_advance + (gs_run_now() - g->advance_start);
      rebalance_measure(g);
      g->posted_at = g->steps_seen;
    }
    return 0;
  }
  if (g->steps_seen == g->posted_at) return 0;
  return g->move_wanted = rebalance_decide(g);
}

/* This rank's integrator on its block (numbers and carried volumes come
 * first in the packed vector too). */
static int build_integrator(ranks_t *g, gs_error *err) {
  gs_case *c = g->run->c;
  gs_dist *d = g->dist;
  g->yl = gs_malloc(d->nlocal * sizeof(double), err);
  g->scale = gs_malloc(d->nlocal * sizeof(double), err);
  if (!g->yl || !g->scale) return GS_ENOMEM;
  gs_dist_pack(d, c->abs_scale, g->scale);
  g->ode = (gs_ode){.n = d->nlocal,
                    .f = local_rhs,
                    .ctx = g,
                    .abs_scale = g->scale,
                    .npositive = d->len[0] + d->len[1],
                    .reduce_max = agreed_max,
                    .rates_checked = 1,
                    .between_steps = between_steps};
  return gs_integrator_create(&c->integrator_setup, &g->ode, &g->own, err);
}

/* The move decided between steps.  Y: this rank's block is current (the
 * integrator returned early); rank 0 collects the others' and sends the
 * whole state to every rank, which then takes its new block. */
static int rebalance_move(ranks_t *g, gs_error *err) {
  gs_run *run = g->run;
  const gs_model *m = &run->c->model;
  gs_dist *d = g->dist;
  const double start = gs_run_now();
  g->move_wanted = 0;
  /* the advance has posted a held output time already; were one left, its
   * block would have to be received before the move's */
  g->t_held += post_output_time(g);
  gs_dist_collect(d, run->Y);
  gs_parallel_broadcast(run->Y, m->nstate + m->nledger);
  gs_integrator old = g->own;
  /* the old vectors go first, so that the new ones reuse their pages (Y
   * holds the whole state now) */
  free(g->yl);
  free(g->scale);
  g->yl = g->scale = NULL;
  if (old.type->release) old.type->release(old.self);
  gs_dist_resplit(d, g->split_lo);
  int rc = build_integrator(g, err);
  if (!rc) g->own.type->carry(g->own.self, old.self);
  gs_integrator_free(&old);
  run->rep->rebalanced++;
  rc = gs_run_agree(d, rc, err);
  /* fresh integrator vectors cost page faults */
  g->move_seconds = gs_dist_max(d, gs_run_now() - start);
  return rc;
}

static int ranks_create(gs_run *run, void **self, gs_error *err) {
  gs_case *c = run->c;
  const size_t ncomp = c->model.grid.ncomp;
  if (!c->integrator_setup.type->ranks)
    return gs_error_set(err, GS_EINPUT,
                        "integrator %s: a state spread over several MPI ranks needs solver.method "
                        "rk or euler (or run on one rank)",
                        c->integrator_setup.type->name);
  ranks_t *g = gs_calloc(1, sizeof *g, err);
  if (!g) return GS_ENOMEM;
  *self = g;
  g->run = run;
  g->dist = &run->dist;
  g->switch_reached = NAN;
  g->evals_needed = MIN_EVALS;
  for (size_t i = 0; i < run->nobs; i++)
    if (run->obs[i].type->idle) g->has_idle = 1;
  int rc = build_integrator(g, err);
  /* the compartments' own costs, for the rebalancing (not for integrators
   * that cannot carry on where another stopped) */
  if (!rc && c->rebalance >= 0 && g->own.type->carry &&
      (!(run->ev.comp_seconds = gs_calloc(ncomp, sizeof(double), err)) ||
       !(g->spent = gs_calloc(ncomp + (size_t)g->dist->size, sizeof(double), err)) ||
       !(g->split_lo = gs_calloc((size_t)g->dist->size + 1, sizeof(size_t), err))))
    rc = GS_ENOMEM;
  return rc;
}

/* The run stops for a failure at an output time: rank 0's own (its message
 * kept), or another rank's (its code: agreed). */
static int failed_at_output(const ranks_t *g, int agreed, gs_error *err) {
  if (g->out_rc == STOP_CODE || agreed == STOP_CODE) return STOP_CODE;
  if (!g->out_rc) return gs_error_set(err, agreed, "the run failed on another MPI rank");
  *err = g->out_err;
  return g->out_rc;
}

static int ranks_advance(void *self, gs_run *run, gs_error *err) {
  ranks_t *g = self;
  gs_case *c = run->c;
  const gs_model *m = &c->model;
  gs_dist *d = g->dist;
  const int root = d->rank == 0;
  int rc = GS_OK;
  for (size_t i = 0; !rc && i < c->ntimes; i++) {
    if (c->times[i] <= run->t) continue;
    const double advance_start = g->advance_start = gs_run_now();
    while (!rc && run->t < c->times[i]) {
      const double next_switch = gs_model_next_switch(m, run->t);
      const double stop = fmin(c->times[i], next_switch);
      run->ev.switch_lo = run->t; /* windows decide once for the interval (gs_window_on) */
      run->ev.switch_hi = stop;
      g->ode.jumped = run->t == g->switch_reached;
      gs_dist_pack(d, run->Y, g->yl);
      rc = g->own.type->advance(g->own.self, &g->ode, &run->t, stop, g->yl, err);
      /* if no step agreement did: Y still holds that time */
      g->t_held += post_output_time(g);
      gs_dist_unpack(d, g->yl, run->Y);
      run->ev.switch_lo = 1;
      run->ev.switch_hi = 0;
      if (!rc && run->t == next_switch) g->switch_reached = run->t;
      if (!rc && g->stop_code) rc = failed_at_output(g, g->stop_code, err);
      if (!rc && g->move_wanted) rc = rebalance_move(g, err);
    }
    const double outputs_start = gs_run_now();
    g->t_advance += outputs_start - advance_start;
    if (rc && g->bad) rc = gs_run_rate_failure(m, g->bad_t, g->bad_index, err);
    /* every rank (the steps are agreed, so the marks are the same); rank 0's
     * observers see them when they take the held output time, before the
     * next output time marks again */
    if (!rc) gs_run_mark(run, &g->own, 0);
    /* the checks and the failure agreement wait for the next step's
     * agreement (post_output_time); integrator failures are agreed already:
     * hold only a good state */
    if (!rc) {
      if (!root) gs_dist_collect(d, run->Y); /* sent without waiting */
      g->output_held = 1;
      g->held_t = run->t;
    }
    run->phase[GS_PH_OUTPUTS] += gs_run_now() - outputs_start;
  }
  /* the last output time: no step after it */
  run->phase[GS_PH_OUTPUTS] += post_output_time(g);
  const int late = (int)gs_dist_max_lagged_finish(d);
  gs_dist_sum_finish(d); /* a rebalancing sum still in flight writes into g->spent */
  /* rank 0's failure came first: rank 0 says so, the others that it failed
   * there (not what went wrong in the steps they took after it) */
  if (late || g->stop_code || g->out_rc)
    rc = failed_at_output(g, late ? late : g->stop_code ? g->stop_code : g->out_rc, err);
  if (rc == STOP_CODE) {
    /* an observer ended the run at an output time: every rank returns
     * there, with the whole state rank 0 held (the others ran on) */
    run->t = g->stop_t;
    if (root) memcpy(run->Y, g->stop_Y, c->ode.n * sizeof(double));
    gs_parallel_broadcast(&run->t, 1);
    gs_parallel_broadcast(run->Y, c->ode.n);
    run->stop = 1;
    rc = GS_OK;
  }
  run->phase[GS_PH_RHS] = g->t_rhs;
  run->phase[GS_PH_EXCHANGE] = g->t_exchange;
  run->phase[GS_PH_INTEGRATOR] = g->t_advance - g->t_rhs - g->t_exchange - g->t_agree - g->t_held;
  run->phase[GS_PH_WAITS] = g->t_agree - g->t_idle;
  run->phase[GS_PH_OUTPUTS] += g->t_idle + g->t_held;
  return rc;
}

static void ranks_resume(void *self, gs_run *run) {
  ranks_t *g = self;
  g->own.type->resume(g->own.self, run->resume_state);
}

static void ranks_stats(const void *self, gs_integrator_stats *st) {
  const ranks_t *g = self;
  if (g->own.type) g->own.type->get_stats(g->own.self, st); /* not after a failed rebuild */
  else memset(st, 0, sizeof *st);
}

static void ranks_free(void *self) {
  ranks_t *g = self;
  if (!g) return;
  gs_integrator_free(&g->own);
  free(g->yl);
  free(g->scale);
  free(g->spent);
  free(g->split_lo);
  free(g->stop_Y);
  free(g->run->ev.comp_seconds);
  g->run->ev.comp_seconds = NULL;
  free(g);
}

const gs_strategy_type gs_step_ranks = {
    .name = "ranks",
    .create = ranks_create,
    .advance = ranks_advance,
    .resume = ranks_resume,
    .stats = ranks_stats,
    .free = ranks_free,
};
