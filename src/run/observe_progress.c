/* Observer: the progress line on standard error (time reached, share of the
 * run, steps, seconds), rewritten at every output time. */
#include <stdio.h>
#include <stdlib.h>

#include "run/run_internal.h"

typedef struct {
  gs_run *run;
  int started; /* the start time is behind: something done */
} progress_t;

static int progress_output(void *self, const gs_run_view *view, double t, const double *Y,
                           int *stop, gs_error *err) {
  (void)Y;
  (void)stop;
  (void)err;
  progress_t *p = self;
  if (!p->started) {
    p->started = 1;
    return GS_OK;
  }
  gs_integrator_stats st;
  gs_run_stats(p->run, &st);
  const double span = view->t_end - view->c->t0;
  char steps[32] = ""; /* not known while threads take their own steps */
  if (st.steps >= 0) snprintf(steps, sizeof steps, "%ld steps  ", st.steps);
  fprintf(stderr, "\rgransim: t = %-10.4g of %-10.4g (%3.0f%%)  %s%.1f s   ", t, view->t_end,
          span > 0 ? 100.0 * (t - view->c->t0) / span : 100.0, steps, view->wall_seconds);
  fflush(stderr);
  return GS_OK;
}

static int progress_finish(void *self, const gs_run_view *view, int ok, gs_error *err) {
  (void)self;
  (void)view;
  (void)ok;
  (void)err;
  fprintf(stderr, "\n");
  return GS_OK;
}

static const gs_observer_type progress_type = {
    .name = "progress",
    .output = progress_output,
    .finish = progress_finish,
    .free = free,
};

const gs_builtin_observer gs_observe_progress = {.type = &progress_type, .size = sizeof(progress_t)};
