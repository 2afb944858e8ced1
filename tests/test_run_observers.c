/* The run driver's observers (include/gransim/run.h):
 *  - a caller's observer sees every output time, in order, with the state
 *    of each, and the run's start first;
 *  - an observer that ends the run at an output time leaves the run there:
 *    report.stopped, report.t_end that time, and the final state equal bit
 *    for bit to the state an uninterrupted run had at that time;
 *  - an observer's error stops the run with its message;
 * for each stepping strategy: shared steps, per-compartment steps, and (run
 * on several MPI ranks by tests/mpi_observers.sh) compartments over ranks. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/parallel.h"
#include "pbm_testlib.h"

/* Three compartments in series, fed, with aggregation and a spray window:
 * rate switches inside the output intervals. */
static const char *CASE =
    "grid:\n"
    "  axes: [{name: solid, type: geometric, min: 1.0e-3, ratio: 2, cells: 16},\n"
    "         {name: liquid, type: geometric, min: 1.0e-4, ratio: 2, cells: 8}]\n"
    "  compartments: 3\n"
    "initial: {type: point, number: 100, at: [0.01, 0.002], compartment: 1}\n"
    "mechanisms:\n"
    "  - {type: aggregation, kernel: {type: constant, beta0: 1.0e-3}}\n"
    "  - {type: transfer, rate: 0.5}\n"
    "  - {type: feed, compartment: 1, start: 0.3, end: 1.7,\n"
    "     distribution: {type: point, number: 5, at: [0.01, 0.002]}}\n"
    "  - {type: liquid_addition, rate: 1.0e-3, start: 0.5, end: 1.2}\n"
    "solver: {method: rk, rtol: 1.0e-7, atol: 1.0e-9%s}\n"
    "output: {end: 2, count: 9}\n";

typedef struct {
  size_t n;      /* state length */
  size_t calls;  /* output times seen */
  double t[16];  /* their times */
  double *Y[16]; /* and states */
  size_t stop_at; /* end the run at this call (0: never) */
  int fail_at;    /* fail at this call (0: never) */
} recorder;

static int record_output(void *self, const gs_run_view *view, double t, const double *Y, int *stop,
                         gs_error *err) {
  (void)view;
  recorder *r = self;
  if (r->calls < 16) {
    r->t[r->calls] = t;
    r->Y[r->calls] = malloc(r->n * sizeof(double));
    memcpy(r->Y[r->calls], Y, r->n * sizeof(double));
  }
  r->calls++;
  if ((size_t)r->fail_at == r->calls)
    return gs_error_set(err, GS_ENUMERIC, "recorder: asked to fail at t = %g", t);
  if (r->stop_at == r->calls) *stop = 1;
  return GS_OK;
}

static const gs_observer_type recorder_type = {.name = "recorder", .output = record_output};

static void recorder_free(recorder *r) {
  for (size_t i = 0; i < r->calls && i < 16; i++) free(r->Y[i]);
}

/* One run with a recorder; returns the final state (malloc'ed) or NULL. */
static double *run_with(const char *steps, recorder *r, gs_run_report *rep, int *rc,
                        gs_error *err) {
  char *yaml = tl_fmt(CASE, steps);
  gs_case c;
  if (tl_case(yaml, &c)) {
    free(yaml);
    return NULL;
  }
  free(yaml);
  r->n = c.model.nstate + c.model.nledger;
  double *y = calloc(r->n, sizeof(double));
  gs_observer obs = {&recorder_type, r};
  gs_run_options opt = {.observers = &obs, .nobservers = 1};
  *rc = gs_case_run(&c, &opt, y, rep, err);
  gs_case_free(&c);
  return y;
}

static void test_strategy(const char *steps, const char *label) {
  const int root = gs_parallel_rank() == 0;
  gs_error err = {0};
  gs_run_report rep;
  int rc;
  recorder full = {0};
  double *yfull = run_with(steps, &full, &rep, &rc, &err);
  CHECK(rc == GS_OK && !rep.stopped && rep.t_end == 2.0);
  if (root) {
    /* the start and every output time after it, in order */
    CHECK(full.calls == 9);
    for (size_t i = 1; i < full.calls && i < 16; i++) CHECK(full.t[i] > full.t[i - 1]);
    CHECK(full.t[0] == 0.0 && full.t[full.calls - 1] == 2.0);
    CHECK(memcmp(full.Y[full.calls - 1], yfull, full.n * sizeof(double)) == 0);
  } else {
    CHECK(full.calls == 0); /* observers run where the whole state is */
  }
  /* end the run at the 4th output time: t = full.t[3] */
  recorder part = {.stop_at = 4};
  double *ypart = run_with(steps, &part, &rep, &rc, &err);
  double t_stop = root ? full.t[3] : 0;
  gs_parallel_broadcast(&t_stop, 1);
  printf("%s: %zu output times; stopped at t = %g (asked %g), stopped = %d\n", label, full.calls,
         rep.t_end, t_stop, rep.stopped);
  CHECK(rc == GS_OK && rep.stopped && rep.t_end == t_stop);
  if (root) CHECK(part.calls == 4);
  /* every rank ends with the whole state of that time */
  double *ystop = malloc(full.n * sizeof(double));
  if (root) memcpy(ystop, full.Y[3], full.n * sizeof(double));
  gs_parallel_broadcast(ystop, full.n);
  CHECK(memcmp(ystop, ypart, full.n * sizeof(double)) == 0);
  /* an observer's failure stops the run with its message, on every rank */
  recorder bad = {.fail_at = 5};
  double *ybad = run_with(steps, &bad, &rep, &rc, &err);
  CHECK(rc == GS_ENUMERIC);
  if (root) CHECK(strstr(err.msg, "recorder: asked to fail") != NULL);
  else CHECK(strstr(err.msg, "another MPI rank") != NULL);
  free(ystop);
  free(yfull);
  free(ypart);
  free(ybad);
  recorder_free(&full);
  recorder_free(&part);
  recorder_free(&bad);
}

int main(int argc, char **argv) {
  gs_parallel_init(&argc, &argv);
  test_strategy("", "shared steps");
  if (gs_parallel_size() == 1) test_strategy(", steps: per_compartment", "per-compartment steps");
  gs_parallel_finalize();
  TEST_EXIT();
}
