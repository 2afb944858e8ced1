/* Observer: the result files (result.h5, summary.csv).  It opens them at the
 * start, or reads back an interrupted run's and moves the start there, writes
 * every output time, and commits them at the end (none are left on
 * failure).  On several MPI ranks rank 0 holds output times back and writes
 * them in pieces while it waits for the other ranks (deferred_output.h). */
#include <math.h>
#include <stdlib.h>

#include "gransim/output.h"
#include "output/deferred_output.h"
#include "run/run_internal.h"

/* Output times rank 0 may hold back under MPI (fewer when their copies would
 * exceed DEFER_BYTES): when they come faster than rank 0 can write them in
 * its waits, the oldest is written at once. */
#define DEFER_DEPTH 4
#define DEFER_BYTES ((size_t)64 << 20)

typedef struct {
  gs_run *run;
  gs_output *out;
  gs_deferred_output *deferred;
  double resumed_t; /* the time read back (not written again), or NAN */
  /* the first failure of a piece written while waiting, kept for the next
   * output time or the end */
  int idle_rc;
  gs_error idle_err;
} output_t;

static int output_start(void *self, const gs_run_view *view, double *t, double *Y,
                        gs_error *err) {
  output_t *o = self;
  const gs_case *c = view->c;
  const gs_model *m = &c->model;
  const char *dir = o->run->opt->out_dir;
  /* on resume, the integrators' marks go where the strategy reads them
   * (gs_strategy_type.resume) */
  o->out = view->resumed ? gs_output_resume(dir, m, view->nresume, t, Y, Y + m->nstate,
                                            o->run->resume_state, err)
                         : gs_output_open(dir, m, gs_cfg_source(c->cfg), gs_cfg_name(c->cfg),
                                          view->nresume, err);
  if (!o->out) return err->code;
  if (view->resumed) o->resumed_t = *t;
  gs_output_set_checkpoint(o->out, c->checkpoint);
  if (o->run->dist.size > 1) {
    size_t fit = DEFER_BYTES / ((m->nstate + m->nledger + view->nresume) * sizeof(double));
    int depth = fit < 1 ? 1 : fit < DEFER_DEPTH ? (int)fit : DEFER_DEPTH;
    if (!(o->deferred = gs_deferred_output_create(o->out, m, view->nresume, depth, err)))
      return GS_ENOMEM;
  }
  return GS_OK;
}

static int output_output(void *self, const gs_run_view *view, double t, const double *Y,
                         int *stop, gs_error *err) {
  (void)stop;
  output_t *o = self;
  const gs_model *m = &view->c->model;
  if (o->idle_rc) { /* a write in the waits failed */
    *err = o->idle_err;
    return o->idle_rc;
  }
  if (t == o->resumed_t) { /* the time read back is in the files already */
    o->resumed_t = NAN;
    return GS_OK;
  }
  if (!o->deferred) return gs_output_write(o->out, m, t, Y, Y + m->nstate, view->resume, err);
  int rc = gs_deferred_output_push(o->deferred, t, Y, view->resume, err);
  /* held times may not delay a due commit: a killed run loses no more than
   * output.checkpoint promises (0: every output time commits) */
  if (!rc && gs_output_commit_due(o->out)) rc = gs_deferred_output_drain(o->deferred, err);
  return rc;
}

static int output_idle(void *self) {
  output_t *o = self;
  if (o->idle_rc || !o->deferred || !gs_deferred_output_pending(o->deferred)) return 0;
  o->idle_rc = gs_deferred_output_work(o->deferred, &o->idle_err);
  return !o->idle_rc && gs_deferred_output_pending(o->deferred);
}

static int output_finish(void *self, const gs_run_view *view, int ok, gs_error *err) {
  output_t *o = self;
  int rc = GS_OK;
  if (ok && o->idle_rc) {
    *err = o->idle_err;
    rc = o->idle_rc;
  }
  if (ok && !rc && o->deferred) rc = gs_deferred_output_drain(o->deferred, err);
  if (o->out) {
    gs_error ferr;
    /* stopped early to be continued: the journal stays (gs_run_options.hold_on_stop) */
    const int hold = ok && !rc && o->run->opt->hold_on_stop && o->run->stop && o->run->t < view->t_end;
    int frc = hold ? gs_output_hold(o->out, &ferr) : gs_output_finish(o->out, ok && !rc, &ferr);
    o->out = NULL;
    if (ok && !rc && frc) {
      *err = ferr;
      rc = frc;
    }
  }
  return rc;
}

static void output_free(void *self) {
  output_t *o = self;
  if (!o) return;
  gs_deferred_output_free(o->deferred);
  if (o->out) gs_output_finish(o->out, 0, &(gs_error){0});
  free(o);
}

static int output_init(void *self, gs_error *err) {
  (void)err;
  ((output_t *)self)->resumed_t = NAN;
  return GS_OK;
}

static const gs_observer_type output_type = {
    .name = "output",
    .start = output_start,
    .output = output_output,
    .idle = output_idle,
    .finish = output_finish,
    .free = output_free,
};

const gs_builtin_observer gs_observe_output = {
    .type = &output_type,
    .size = sizeof(output_t),
    .init = output_init,
};
