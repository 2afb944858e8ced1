/* Observer: the progress line on standard error (core/progress.h): the time
 * reached, the share of the run, the rate in simulated seconds per wall
 * second and the time left, with the steps taken.  It is rewritten at every
 * output time and, through `during`, from the integrator's evaluations of
 * the rates between them, so that a long interval between two output times
 * does not leave the terminal silent (a user saw nothing for 5 minutes when
 * it was only rewritten at output times). */
#include <stdio.h>
#include <stdlib.h>

#include "core/progress.h"
#include "run/run_internal.h"

typedef struct {
  gs_run *run;
  int started; /* the line has its start (after a resume: the time resumed from) */
  double last_t; /* the last output time */
  gs_progress line;
} progress_t;

static void progress_show(progress_t *p, const gs_run_view *view, double t, int force) {
  if (!p->started) {
    gs_progress_start(&p->line, "gransim", "s", t, view->t_end);
    p->started = 1;
    return;
  }
  gs_integrator_stats st;
  gs_run_stats(p->run, &st);
  char steps[32] = ""; /* not known while threads take their own steps */
  if (st.steps >= 0) snprintf(steps, sizeof steps, "%ld steps", st.steps);
  gs_progress_update(&p->line, t, steps, force);
}

static int progress_output(void *self, const gs_run_view *view, double t, const double *Y,
                           int *stop, gs_error *err) {
  (void)Y;
  (void)stop;
  (void)err;
  progress_t *p = self;
  p->last_t = t;
  progress_show(p, view, t, 0);
  return GS_OK;
}

static void progress_during(void *self, const gs_run_view *view, double t) {
  progress_show(self, view, t, 1); /* the driver throttles these */
}

static int progress_finish(void *self, const gs_run_view *view, int ok, gs_error *err) {
  (void)err;
  progress_t *p = self;
  if (p->started && ok) progress_show(p, view, p->last_t, 1); /* the end, whatever the throttle */
  if (p->started) gs_progress_end(&p->line);
  return GS_OK;
}

static const gs_observer_type progress_type = {
    .name = "progress",
    .output = progress_output,
    .during = progress_during,
    .finish = progress_finish,
    .free = free,
};

const gs_builtin_observer gs_observe_progress = {.type = &progress_type, .size = sizeof(progress_t)};
