/* gransim — running a case: the output-time loop, its stepping strategies
 * and its observers.
 *
 * gs_case_run advances a case's state through its output times with one
 * stepping strategy (shared steps on one process, compartments over MPI
 * ranks, or per-compartment steps; chosen from the case's typed solver
 * settings and the number of ranks) and hands the state at every output time
 * to a list of observers: the state checks, the result files, the progress
 * line and the timings, then any the caller adds.  An observer may end the
 * run early (a segment of a coupled run that stops when some property of the
 * state has changed enough). */
#ifndef GRANSIM_RUN_H
#define GRANSIM_RUN_H

#include "gransim/case.h"
#include "gransim/integrator.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_run gs_run;

/* What a run exposes to its observers. */
typedef struct gs_run_view {
  const gs_case *c;
  double t_end;        /* the last output time */
  double wall_seconds; /* since the run started */
  long steps;          /* steps taken so far (summed over compartments with per-compartment steps) */
  int resumed;         /* the run continues an interrupted one (opt->resume) */
  /* At an output time: the integrators' state (nresume values) that a run
   * resumed from this time needs besides Y to take the same steps; the
   * output observer keeps it in the journal of the result files. */
  const double *resume;
  size_t nresume;
} gs_run_view;

/* An observer of a run: registered type, called on the process that holds the
 * whole state (rank 0 under MPI). */
typedef struct gs_observer_type {
  const char *name;
  /* Optional: before the first output time.  May move the run's start
   * (resume: *t and Y read back from partial result files). */
  int (*start)(void *self, const gs_run_view *run, double *t, double *Y, gs_error *err);
  /* At each output time, in order (also at the start time): t, the full
   * state Y (numbers, carried, ledger; read only).  Setting *stop = 1 ends
   * the run after this output time (gs_run_report.stopped). */
  int (*output)(void *self, const gs_run_view *run, double t, const double *Y, int *stop,
                gs_error *err);
  /* Optional: while the process waits for others (MPI step agreements), a
   * piece of work left from earlier output times; returns 1 while more is
   * left.  Errors are kept and returned at the next output or finish. */
  int (*idle)(void *self);
  /* Optional: between output times, at most a few times a wall second, the
   * time t the integrator has reached (its latest evaluation of the rates,
   * which may lie a step ahead of the last accepted one; the state is not
   * whole then, so none is given).  For a progress line through long
   * intervals. */
  void (*during)(void *self, const gs_run_view *run, double t);
  /* Optional: at the end, ok = 1 when the run succeeded. */
  int (*finish)(void *self, const gs_run_view *run, int ok, gs_error *err);
  void (*free)(void *self);
} gs_observer_type;

typedef struct gs_observer {
  const gs_observer_type *type;
  void *self;
} gs_observer;

typedef struct gs_run_options {
  const char *out_dir; /* where result.h5 and summary.csv go (NULL: no files) */
  int resume;          /* continue an interrupted run from its partial files */
  int progress;        /* -1 auto (when stderr is a terminal), 0 off, 1 on */
  int timings;         /* 1: print where each (MPI) rank spent its time, at the end */
  /* 1: this process runs the case alone, whatever the MPI ranks (the ranks
   * of a sweep each run their own cases) */
  int one_process;
  /* 1: a run an observer stops before its last output time keeps its result
   * files partial, everything committed to the journal, so that a run with
   * resume = 1 (of the same grid, the mechanisms' data may differ) continues
   * it exactly where it stopped; 0: the stopped run publishes them */
  int hold_on_stop;
  /* more observers, called after the built-in ones (owned by the caller:
   * their free is not called) */
  const gs_observer *observers;
  size_t nobservers;
} gs_run_options;

typedef struct gs_run_report {
  double t_end;
  gs_integrator_stats stats;
  double wall_seconds;
  double max_balance_error; /* largest relative volume-balance error seen */
  double max_loss;          /* largest fraction of volume lost through boundaries */
  long rebalanced;          /* under MPI: times the compartments moved between ranks */
  /* solver.steps: per_compartment (stats then sum the compartments' own
   * steps and evaluations, an evaluation being one compartment's rates), and
   * the largest relative mismatch between what a compartment discharged and
   * the next received in a stretch */
  int per_compartment;
  double worst_coupling;
  int stopped; /* an observer ended the run at t_end, before the last output time */
} gs_run_report;

/* Integrate the case over its output times, checking after every output time
 * for non-finite or negative numbers, the volume balance of every axis and
 * the loss through grid boundaries, and writing outputs.  On failure returns
 * GS_ENUMERIC (or GS_EIO) with a message naming the time, compartment and
 * cell, and leaves no result files.  y (may be NULL) receives the final state. */
int gs_case_run(gs_case *c, const gs_run_options *opt, double *y, gs_run_report *report,
                gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
