/* Observer (--timings): where each rank's time went, printed at the end by
 * rank 0 (the phase table is summed over the ranks, so every rank has this
 * observer and its finish is collective), then the strategy's own figures. */
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "gransim/parallel.h"
#include "run/run_internal.h"

/* Page faults of this process so far (a first touch of a page is costly on
 * virtual machines, so --timings shows those a run takes). */
static long minor_faults(void) {
  struct rusage ru;
  return getrusage(RUSAGE_SELF, &ru) ? 0 : ru.ru_minflt;
}

static void print_phases(const gs_dist *d, const double *mine) {
  const size_t n = (size_t)d->size * GS_PH_N;
  double *all = calloc(n, sizeof *all);
  if (!all) return;
  memcpy(all + (size_t)d->rank * GS_PH_N, mine, GS_PH_N * sizeof *mine);
  if (d->size > 1) gs_parallel_sum(all, n); /* zeros elsewhere: exact */
  if (d->rank == 0) {
    fprintf(stderr, "gransim: where the time went (s)\n  %-5s %-12s %-9s %-11s %-7s %-8s %-12s %s\n",
            "rank", "rates (RHS)", "exchange", "integrator", "waits", "outputs", "final write",
            "compartments at the end");
    for (int r = 0; r < d->size; r++) {
      const double *x = all + (size_t)r * GS_PH_N;
      char comps[48];
      snprintf(comps, sizeof comps, d->lo[r + 1] - d->lo[r] > 1 ? "%zu-%zu" : "%zu", d->lo[r] + 1,
               d->lo[r + 1]);
      fprintf(stderr, "  %-5d %-12.4f %-9.4f %-11.4f %-7.4f %-8.4f %-12.4f %s\n", r, x[GS_PH_RHS],
              x[GS_PH_EXCHANGE], x[GS_PH_INTEGRATOR], x[GS_PH_WAITS], x[GS_PH_OUTPUTS],
              x[GS_PH_FINISH], comps);
    }
  }
  free(all);
}

typedef struct {
  gs_run *run;
  long faults_start;
} timings_t;

static int timings_start(void *self, const gs_run_view *view, double *t, double *Y,
                         gs_error *err) {
  (void)view;
  (void)t;
  (void)Y;
  (void)err;
  timings_t *k = self;
  k->faults_start = minor_faults();
  return GS_OK;
}

static int timings_finish(void *self, const gs_run_view *view, int ok, gs_error *err) {
  (void)view;
  (void)ok;
  (void)err;
  timings_t *k = self;
  gs_run *run = k->run;
  print_phases(&run->dist, run->phase);
  fprintf(stderr, "  page faults while it ran: %ld on rank %d\n", minor_faults() - k->faults_start,
          run->dist.rank);
  if (run->strategy->print_timings)
    run->strategy->print_timings(run->strategy_self, run, stderr);
  return GS_OK;
}

static const gs_observer_type timings_type = {
    .name = "timings",
    .start = timings_start,
    .finish = timings_finish,
    .free = free,
};

const gs_builtin_observer gs_observe_timings = {.type = &timings_type, .size = sizeof(timings_t)};
