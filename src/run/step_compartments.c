/* Stepping strategy "per_compartment": every compartment takes its own
 * steps (compartment_steps.h), the threads sharing (compartment, stretch)
 * tasks.  The run is cut into stretches between output times and rate
 * switches; the threads reach the output times one after the other while
 * others advance later stretches, and the thread that completes a stretch
 * ending at an output time hands its state to the observers.  On several
 * MPI ranks each rank advances its block of compartments so, the records
 * crossing between the blocks and the output times' blocks going to rank 0
 * (compartment_ranks.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/parallel.h"
#include "run/compartment_ranks.h"
#include "run/compartment_steps.h"
#include "run/run_internal.h"

/* done_fn's answer when an observer ended the run: the stretches after it
 * stop like after a failure, without being one. */
#define STOPPED (-1)

typedef struct {
  gs_run *run;
  gs_comp_steps *cs;
  gs_stretch *st; /* the run's stretches */
  int *is_output; /* per stretch: its end is an output time */
  size_t nst;
  int running;    /* counters are being written by the threads */
  gs_comp_ranks *ranks; /* on several MPI ranks */
  int have_total;       /* on several ranks, after the run: total, every rank's steps */
  gs_integrator_stats total;
  size_t base; /* the first stretch of the piece of the run in progress */
  /* rebalancing on ranks (NULL: none): per compartment its task seconds
   * at the last decision, and rank 0's output seconds; the costs since then
   * (compartments, then each rank's own work); a split's lo */
  double *cost_mark, out_mark, *spent;
  size_t *split_lo;
  long moves_tried; /* GRANSIM_TEST_MOVE_COMPARTMENTS only */
} comps_t;


static int comps_create(gs_run *run, void **self, gs_error *err) {
  comps_t *s = gs_calloc(1, sizeof *s, err);
  if (!s) return GS_ENOMEM;
  s->run = run;
  *self = s;
  int rc = gs_comp_steps_create(run->c, &s->cs, err);
  /* collective: every rank creates its transport, whatever the others' rc */
  if (run->dist.size > 1) {
    rc = gs_run_agree(&run->dist, rc, err);
    if (!rc) rc = gs_comp_ranks_create(s->cs, &run->c->model, &run->dist, &s->ranks, err);
    const size_t ncomp = run->c->model.grid.ncomp;
    if (!rc && run->c->rebalance >= 0) {
      s->cost_mark = gs_calloc(ncomp, sizeof(double), err);
      s->spent = gs_calloc(ncomp + (size_t)run->dist.size, sizeof(double), err);
      s->split_lo = gs_calloc((size_t)run->dist.size + 1, sizeof(size_t), err);
      if (!s->cost_mark || !s->spent || !s->split_lo) rc = GS_ENOMEM;
    }
    rc = gs_run_agree(&run->dist, rc, err);
  }
  return rc;
}

/* The stretches from run->t to the last output time. */
static int cut_stretches(comps_t *s, gs_error *err) {
  const gs_case *c = s->run->c;
  size_t cap = 64;
  s->st = gs_malloc(cap * sizeof *s->st, err);
  s->is_output = gs_malloc(cap * sizeof *s->is_output, err);
  if (!s->st || !s->is_output) return GS_ENOMEM;
  double at = s->run->t, switch_reached = NAN;
  unsigned long era = 0;
  for (size_t i = 0; i < c->ntimes; i++) {
    if (c->times[i] <= at) continue;
    while (at < c->times[i]) {
      const double next_switch = gs_model_next_switch(&c->model, at);
      const double stop = fmin(c->times[i], next_switch);
      if (s->nst == cap) {
        cap *= 2;
        gs_stretch *s2 = realloc(s->st, cap * sizeof *s->st);
        if (s2) s->st = s2;
        int *o2 = s2 ? realloc(s->is_output, cap * sizeof *s->is_output) : NULL;
        if (o2) s->is_output = o2;
        if (!o2) return gs_error_set(err, GS_ENOMEM, "out of memory for the run's stretches");
      }
      const int output = stop == c->times[i];
      s->st[s->nst] = (gs_stretch){at, stop, at == switch_reached, output, era};
      s->is_output[s->nst++] = output;
      era += (unsigned long)output;
      if (stop == next_switch) switch_reached = stop;
      at = stop;
    }
  }
  return GS_OK;
}

static int stretch_done(void *ctx, size_t k, double t, const double *Y, gs_error *err) {
  comps_t *s = ctx;
  gs_run *run = s->run;
  if (!s->is_output[s->base + k]) return GS_OK;
  const double start = gs_run_now();
  memcpy(run->resume_state, gs_comp_steps_marks(s->cs, k), run->view.nresume * sizeof(double));
  int rc = gs_run_output_time(run, t, Y, err);
  run->phase[GS_PH_OUTPUTS] += gs_run_now() - start;
  if (!rc && run->stop) { /* the state of this output time is the run's end */
    memcpy(run->Y, Y, run->c->ode.n * sizeof(double));
    run->t = t;
    return STOPPED;
  }
  return rc;
}

/* On several ranks: the steps of every rank's compartments (collective). */
static void total_stats(comps_t *s, const gs_run *run) {
  gs_integrator_stats mine;
  gs_comp_steps_stats(s->cs, &mine);
  const int last = run->dist.rank == run->dist.size - 1;
  double v[4] = {(double)mine.steps, (double)mine.rejected, (double)mine.rhs_evals, last ? mine.last_step : 0.0};
  gs_parallel_sum(v, 4);
  s->total = mine;
  s->total.steps = (long)v[0];
  s->total.rejected = (long)v[1];
  s->total.rhs_evals = (long)v[2];
  s->total.last_step = v[3];
  s->have_total = 1;
}

/* Where the piece of the run that starts at stretch `from` ends: on ranks
 * that rebalance, at the first output time at or after 1/16, 1/8, 1/4 and
 * 1/2 of the stretches, when there are at least CUT_MIN_STRETCHES.  Every
 * cut drains the ranks' pipeline (a rank starts a stretch about when the
 * rank before has finished it, so at a cut each waits about one stretch of
 * the other's work), so the cuts are few and only where a stretch is a
 * small part of the run.  A decision applies the last piece's costs to the
 * next, so it lags costs that move (the filling of a long chain, where
 * cutting every 1/8 gained no more than its cuts cost); it is exact once
 * they settle, and the doubling schedule keeps deciding on ever longer,
 * steadier windows. */
#define CUT_MIN_STRETCHES 64
static const size_t cut_at[] = {1, 2, 4, 8}; /* sixteenths of the run */
static size_t piece_end(const comps_t *s, size_t from) {
  if (!s->spent || (s->nst < CUT_MIN_STRETCHES && !gs_run_test_moves())) return s->nst;
  size_t target = s->nst; /* the first of the fractions past from */
  for (size_t i = 0; i < sizeof cut_at / sizeof *cut_at && target == s->nst; i++)
    if (s->nst * cut_at[i] / 16 > from) target = s->nst * cut_at[i] / 16;
  if (gs_run_test_moves()) target = from + 1; /* tests: every output time */
  for (size_t k = target - 1; k + 1 < s->nst; k++)
    if (s->is_output[k]) return k + 1;
  return s->nst;
}

/* Between two pieces of the run, on every rank (collective): each rank's
 * task seconds per compartment since the last decision (waits excluded) and
 * rank 0's output seconds, summed over the ranks; when the contiguous split
 * whose slowest rank is cheapest for those costs (gs_dist_best_split)
 * beats the measured slowest rank by solver.rebalance, the ranks take it.
 * The piece ended at an output time, where rank 0 holds the whole state
 * and every compartment's integrator mark: both go to every rank, and a
 * compartment a rank takes over resumes from its mark, as a run resumed
 * there would; its steps are those of one process. */
static void rebalance(comps_t *s, gs_run *run) {
  if (!s->spent) return;
  gs_dist *d = &run->dist;
  const gs_model *m = &run->c->model;
  const size_t ncomp = m->grid.ncomp, nr = (size_t)d->size;
  const size_t lo = d->lo[d->rank], hi = d->lo[d->rank + 1];
  memset(s->spent, 0, (ncomp + nr) * sizeof(double));
  for (size_t j = lo; j < hi; j++) {
    double rates, tasks;
    gs_comp_steps_comp_seconds(s->cs, j, &rates, &tasks);
    s->spent[j] = tasks - s->cost_mark[j];
    s->cost_mark[j] = tasks;
  }
  const double out = gs_comp_steps_output_seconds(s->cs);
  s->spent[ncomp + (size_t)d->rank] = out - s->out_mark;
  s->out_mark = out;
  gs_parallel_sum(s->spent, ncomp + nr); /* zeros elsewhere: exact */
  double slowest = 0;
  for (size_t r = 0; r < nr; r++) {
    double block = s->spent[ncomp + r];
    for (size_t j = d->lo[r]; j < d->lo[r + 1]; j++) block += s->spent[j];
    slowest = fmax(slowest, block);
  }
  const double largest = gs_dist_best_split(d, s->spent, s->spent + ncomp, s->split_lo);
  if (gs_run_test_moves()) {
    /* tests only: one block boundary moved at every decision, whatever the
     * costs, so that tests can check that moves change no result */
    size_t *nlo = s->split_lo;
    memcpy(nlo, d->lo, (nr + 1) * sizeof *nlo);
    const size_t b = 1 + (size_t)(s->moves_tried++ % (long)(nr - 1));
    if (nlo[b] - nlo[b - 1] > 1) nlo[b]--;
    else if (nlo[b + 1] - nlo[b] > 1) nlo[b]++;
  } else if (!(largest < (1 - run->c->rebalance) * slowest)) {
    return;
  }
  if (!memcmp(s->split_lo, d->lo, (nr + 1) * sizeof *d->lo)) return;
  gs_parallel_broadcast(run->Y, m->nstate + m->nledger);
  gs_parallel_broadcast(run->resume_state, run->view.nresume);
  gs_dist_resplit(d, s->split_lo);
  gs_comp_ranks_resplit(s->ranks, d->lo);
  const size_t nlo = d->lo[d->rank], nhi = d->lo[d->rank + 1];
  /* the compartments this rank takes over, before and after its old block */
  if (nlo < lo) gs_comp_steps_resume_comps(s->cs, run->resume_state, nlo, lo < nhi ? lo : nhi);
  if (nhi > hi) gs_comp_steps_resume_comps(s->cs, run->resume_state, hi > nlo ? hi : nlo, nhi);
  run->rep->rebalanced++;
}

static int comps_advance(void *self, gs_run *run, gs_error *err) {
  comps_t *s = self;
  int rc = cut_stretches(s, err);
  if (s->ranks) rc = gs_run_agree(&run->dist, rc, err);
  if (rc || !s->nst) return rc;
  const double start = gs_run_now(), outputs = run->phase[GS_PH_OUTPUTS];
  s->running = 1;
  /* on several ranks only rank 0 holds the whole state of an output time */
  const int observes = run->dist.rank == 0;
  for (size_t from = 0; !rc && from < s->nst;) {
    const size_t to = piece_end(s, from);
    s->base = from;
    rc = gs_comp_steps_run(s->cs, s->st + from, to - from, run->Y, observes ? stretch_done : NULL, s, err);
    if (!rc && to < s->nst) rebalance(s, run);
    from = to;
  }
  s->running = 0;
  if (s->ranks) {
    total_stats(s, run);
    if (rc == STOPPED) { /* every rank returns with the state rank 0 held there */
      gs_parallel_broadcast(&run->t, 1);
      gs_parallel_broadcast(run->Y, run->c->ode.n);
      run->stop = 1;
    }
  }
  const double rhs = gs_comp_steps_rhs_seconds(s->cs);
  run->phase[GS_PH_RHS] = rhs;
  run->phase[GS_PH_INTEGRATOR] = gs_run_now() - start - (run->phase[GS_PH_OUTPUTS] - outputs) - rhs;
  if (rc == STOPPED) return GS_OK; /* run->t and Y: stretch_done's */
  double bad_t;
  size_t bad_index;
  if (rc && gs_comp_steps_bad_rate(s->cs, &bad_t, &bad_index))
    return gs_run_rate_failure(&run->c->model, bad_t, bad_index, err);
  if (!rc) run->t = s->st[s->nst - 1].t1;
  return rc;
}

static void comps_resume(void *self, gs_run *run) {
  comps_t *s = self;
  gs_comp_steps_resume(s->cs, run->resume_state);
}

static void comps_stats(const void *self, gs_integrator_stats *st) {
  const comps_t *s = self;
  memset(st, 0, sizeof *st);
  if (s->running) { /* the threads write the counters: none to read */
    st->steps = -1;
    return;
  }
  if (s->have_total) *st = s->total;
  else gs_comp_steps_stats(s->cs, st);
}

static void comps_print_timings(const void *self, const gs_run *run, FILE *f) {
  const comps_t *s = self;
  const size_t lo = run->dist.lo[run->dist.rank], hi = run->dist.lo[run->dist.rank + 1];
  if (run->dist.size > 1) fprintf(f, "  rank %d, compartments %zu-%zu:\n", run->dist.rank, lo + 1, hi);
  fprintf(f, "  per-compartment steps (steps / rejected / evaluations / ms in rates / ms in tasks):");
  for (size_t comp = lo; comp < hi; comp++) {
    gs_integrator_stats st;
    gs_comp_steps_comp_stats(s->cs, comp, &st);
    double rates, tasks;
    gs_comp_steps_comp_seconds(s->cs, comp, &rates, &tasks);
    fprintf(f, "%s %ld/%ld/%ld/%.1f/%.1f", comp > lo ? "," : "", st.steps, st.rejected, st.rhs_evals,
            1e3 * rates, 1e3 * tasks);
  }
  fprintf(f, "; largest coupling mismatch %.2g; %d thread%s, waiting %.4f s in all\n",
          gs_comp_steps_worst_coupling(s->cs), gs_comp_steps_threads(s->cs),
          gs_comp_steps_threads(s->cs) == 1 ? "" : "s", gs_comp_steps_wait_seconds(s->cs));
  gs_comp_steps_print_threads(s->cs, f);
}

static void comps_free(void *self) {
  comps_t *s = self;
  if (!s) return;
  if (s->cs) {
    s->run->rep->per_compartment = 1;
    s->run->rep->worst_coupling = gs_comp_steps_worst_coupling(s->cs);
  }
  gs_comp_steps_free(s->cs);
  gs_comp_ranks_free(s->ranks);
  free(s->cost_mark);
  free(s->spent);
  free(s->split_lo);
  free(s->st);
  free(s->is_output);
  free(s);
}

const gs_strategy_type gs_step_compartments = {
    .name = "per_compartment",
    .create = comps_create,
    .advance = comps_advance,
    .resume = comps_resume,
    .stats = comps_stats,
    .print_timings = comps_print_timings,
    .free = comps_free,
};
