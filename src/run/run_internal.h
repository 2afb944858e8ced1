/* The run in progress, shared by the driver (driver.c), its stepping
 * strategies (step_*.c) and its built-in observers (observe_*.c). */
#ifndef GRANSIM_RUN_INTERNAL_H
#define GRANSIM_RUN_INTERNAL_H

#include <stdio.h>

#include "gransim/run.h"
#include "run/distributed.h"

/* --timings phases of one rank (integrator = advance minus rates, exchange
 * and step agreements, i.e. the integrator's own vector work, packing and
 * rate checks; waits = step agreements, less the observers' idle work,
 * which counts as outputs). */
enum { GS_PH_RHS, GS_PH_EXCHANGE, GS_PH_INTEGRATOR, GS_PH_WAITS, GS_PH_OUTPUTS, GS_PH_FINISH, GS_PH_N };

/* A stepping strategy: how the state advances through the output times. */
typedef struct gs_strategy_type {
  const char *name;
  int (*create)(gs_run *run, void **self, gs_error *err);
  /* Advance run->Y from run->t through every output time after it, calling
   * gs_run_output_time with the state at each (on rank 0 under MPI, which
   * may do so later, while the next steps run).  Returns at the last output
   * time, at the first failure, or at the output time an observer stopped
   * the run at (run->stop); run->t and run->Y are then that time's. */
  int (*advance)(void *self, gs_run *run, gs_error *err);
  /* Exact resume: at every output time the strategy marks its integrators
   * (gs_integrator_type.mark) into run->resume_state before the observers
   * see it; resume hands a resumed run's integrators what was read back
   * (after create, before advance). */
  void (*resume)(void *self, gs_run *run);
  /* Steps, rejections and evaluations so far. */
  void (*stats)(const void *self, gs_integrator_stats *st);
  /* Optional: its part of --timings (after the phase table). */
  void (*print_timings)(const void *self, const gs_run *run, FILE *f);
  void (*free)(void *self);
} gs_strategy_type;

extern const gs_strategy_type gs_step_shared, gs_step_ranks, gs_step_compartments;

struct gs_run {
  gs_case *c;
  const gs_run_options *opt;
  gs_run_report *rep;
  gs_dist dist;    /* the compartments of each MPI rank (one rank without MPI) */
  double *Y;       /* the full state (under MPI current in this rank's block, and on rank 0
                    * at output times) */
  double t;        /* the time Y holds */
  double *resume_state; /* the integrators' marks at the output time observed (gs_run_view.resume) */
  gs_eval ev;      /* the evaluation of this process's compartments */
  double start;    /* wall clock at the start */
  const gs_strategy_type *strategy;
  void *strategy_self;
  gs_observer *obs; /* this process's observers (none on ranks other than 0) */
  size_t nobs, nown; /* nown: the first ones, built in, freed by the run */
  gs_run_view view;
  int stop;          /* an observer ended the run at the last output time */
  double phase[GS_PH_N];
  long faults_start; /* page faults before the run */
  int has_during;    /* an observer has a `during` */
  double next_during; /* wall clock when the next `during` call is due */
};

/* Values of run->resume_state: one integrator's mark, or one per
 * compartment under per-compartment steps. */
size_t gs_run_resume_size(const gs_case *c);
/* Marks integrator it into run->resume_state + offset and opens a new era
 * of the evaluation's discrete choices (gs_eval.era): what every strategy
 * does at an output time. */
void gs_run_mark(gs_run *run, const gs_integrator *it, size_t offset);
/* Every observer at output time t (in order); sets run->stop when one asks. */
int gs_run_output_time(gs_run *run, double t, const double *Y, gs_error *err);
/* From a strategy's rates (on the process and thread of the output times):
 * the observers' `during` with the time t reached, when one is due (every
 * GS_RUN_DURING_EVERY wall seconds; otherwise one clock read). */
#define GS_RUN_DURING_EVERY 0.2
void gs_run_during(gs_run *run, double t);
/* A piece of the observers' idle work; 1 while more is left. */
int gs_run_idle(gs_run *run);
/* Steps so far, through the strategy. */
void gs_run_stats(const gs_run *run, gs_integrator_stats *st);

/* "compartment 2, cell (3, 5) [solid = ..., ...]" for messages. */
void gs_run_describe_cell(const gs_model *m, size_t comp, size_t cell, char *buf, size_t len);
/* The message for a rate that was not finite at time t, entry index of the
 * full state vector (numbers, carried, ledger). */
int gs_run_rate_failure(const gs_model *m, double t, size_t index, gs_error *err);
/* Index of the first non-finite entry of f (n entries), or n. */
size_t gs_run_first_nonfinite(const double *f, size_t n);
double gs_run_now(void);
/* Tests only: GRANSIM_TEST_MOVE_COMPARTMENTS set and not "0" makes the
 * strategies on MPI ranks move a block boundary at every decision, whatever
 * the costs, so that tests can check that moves change no result. */
int gs_run_test_moves(void);
/* Every rank leaves together: when another rank failed, say so here. */
int gs_run_agree(gs_dist *d, int rc, gs_error *err);

/* The built-in observers. */
/* The built-in observers: the driver allocates each one's state (zeroed,
 * `size` bytes, whose first member is `gs_run *run`, set before `init`). */
typedef struct gs_builtin_observer {
  const gs_observer_type *type;
  size_t size;
  /* Optional: the rest of the state; on failure the type's free is called. */
  int (*init)(void *self, gs_error *err);
} gs_builtin_observer;
extern const gs_builtin_observer gs_observe_checks, gs_observe_output, gs_observe_progress,
    gs_observe_timings;

#endif
