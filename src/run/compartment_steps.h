/* Per-compartment time steps (`solver.steps: per_compartment`).
 *
 * The compartments of a model are coupled only downstream: transfer moves
 * compartment c's particles into c + 1 at a rate k_c N_c, and nothing flows
 * back.  So each compartment can be integrated over a stretch of time on its
 * own, with its own adaptive steps, once the one before it has been: the
 * dynamic sequential-modular scheme of flowsheet simulators.  A compartment
 * whose contents barely change takes long steps instead of the shortest
 * steps any compartment needs (the CoriMix example: 3 414 compartment
 * evaluations instead of 4 x 1 239).
 *
 * Conservation stays exact (to round-off) although the steps differ: the
 * integrator steps each compartment's outflow -k_c N on its own
 * (gs_ode.ndecay; exponentially or explicitly, solver.outflow) and says
 * what every step removed, defined by the step's balance; that leaves the
 * ledger, and a compartment that feeds another adds it / k_c to Z, the
 * integral of its numbers and carried totals, so k_c Z is exactly what its
 * steps discharged.  Z through its step ends is a piecewise
 * quintic Hermite curve Z_H (values Z, slopes N, second derivatives f).
 * The next compartment, on a step [s, s + h] of its own, takes as its
 * inflow k_c P'(t), P the quintic Hermite interpolant of Z_H on [s, s + h]:
 * P' is a quartic, so the weights of a Runge-Kutta step of order >= 5
 * integrate it exactly, and a step receives
 * k_c (Z_H(s + h) - Z_H(s)), which telescopes over the steps to what the
 * upstream compartment discharged.  Every stretch ends checking that (the
 * received volumes are integrated alongside, in the local vector).
 *
 * The stretches are those of the run driver (between output times and rate
 * switches); each compartment restarts its integral there, so the record of
 * step ends kept for the next compartment is one stretch long.
 *
 * Threads (OpenMP's, at most one per compartment) each own a contiguous
 * block of compartments, split by their measured cost, take their
 * (compartment, stretch) pieces in order, and follow the compartment before
 * through a stretch: a step waits only until that one has published a step
 * end at or past its own end.  Every compartment's steps and rates are
 * those of one caller (mechanisms keep scratch per slot, gs_eval.slot), so
 * results are identical bit for bit whatever the number of threads. */
#ifndef GRANSIM_PBM_COMPARTMENT_STEPS_H
#define GRANSIM_PBM_COMPARTMENT_STEPS_H

#include <stdio.h>

#include "gransim/case.h"
#include "gransim/error.h"
#include "gransim/integrator.h"

typedef struct gs_comp_steps gs_comp_steps;

/* One integrator per compartment of the case (the case's integrator setup, method
 * rk), each on its own packed vector. */
int gs_comp_steps_create(gs_case *c, gs_comp_steps **out, gs_error *err);
/* A stretch of time without a rate switch inside: [t0, t1]; jumped: f
 * jumps at t0 (gs_ode.jumped). */
typedef struct {
  double t0, t1;
  int jumped;
  /* 1: it ends at an output time, where each compartment's integrator is
   * marked (gs_integrator_type.mark; gs_comp_steps_marks) and starts the
   * next stretch as a resumed run would */
  int mark;
  unsigned long era; /* gs_eval.era of its evaluations: output times before it */
} gs_stretch;
/* Called once per stretch k, in order, when every compartment is done with
 * it: t = st[k].t1, Y the full state then (read only).  Non-zero (with err
 * filled) stops the run. */
typedef int (*gs_stretch_done_fn)(void *ctx, size_t k, double t, const double *Y, gs_error *err);
/* Advance the full state Y through the stretches st[0..nst) (consecutive:
 * st[k].t1 = st[k + 1].t0; Y holds the state at st[0].t0), every
 * compartment on its own, the threads sharing the (compartment, stretch)
 * tasks; done (may be NULL) sees each stretch's end.  On success Y is the
 * state at st[nst - 1].t1; on failure the error of the earliest stretch
 * (then compartment) that failed. */
int gs_comp_steps_run(gs_comp_steps *s, const gs_stretch *st, size_t nst, double *Y,
                      gs_stretch_done_fn done, void *ctx, gs_error *err);
/* One stretch from *t to stop (no rate switch inside); jumped: f jumps at *t
 * (gs_ode.jumped).  On success *t = stop. */
int gs_comp_steps_advance(gs_comp_steps *s, double *t, double stop, double *Y, int jumped,
                          gs_error *err);
/* During done(k) for a stretch with mark set (and after the run, for its
 * last stretch): the compartments' marks at its end (ncomp *
 * GS_INTEGRATOR_MARK values). */
const double *gs_comp_steps_marks(const gs_comp_steps *s, size_t k);
/* A resumed run: every compartment's integrator takes its mark. */
void gs_comp_steps_resume(gs_comp_steps *s, const double *marks);
/* The same for compartments [lo, hi) only (those a rank takes over). */
void gs_comp_steps_resume_comps(gs_comp_steps *s, const double *marks, size_t lo, size_t hi);
/* Seconds spent passing complete stretches to done_fn (and, on ranks,
 * sending or receiving output times' blocks). */
double gs_comp_steps_output_seconds(const gs_comp_steps *s);
/* Steps and evaluations summed over the compartments (each evaluation is
 * one compartment's rates); last_step: the last compartment's. */
void gs_comp_steps_stats(const gs_comp_steps *s, gs_integrator_stats *st);
/* Compartment comp's own counts. */
void gs_comp_steps_comp_stats(const gs_comp_steps *s, size_t comp, gs_integrator_stats *st);
/* Seconds compartment comp spent in its rates, and in its tasks (waits
 * excluded). */
void gs_comp_steps_comp_seconds(const gs_comp_steps *s, size_t comp, double *rates, double *tasks);
/* Seconds threads waited for the compartment before (summed). */
double gs_comp_steps_wait_seconds(const gs_comp_steps *s);
/* Threads that share the compartments. */
int gs_comp_steps_threads(const gs_comp_steps *s);
/* Seconds spent in the model's rates so far (per thread, on average). */
double gs_comp_steps_rhs_seconds(const gs_comp_steps *s);
/* After a failed advance: 1 when a rate was not finite, with its time and
 * index in the full state vector. */
int gs_comp_steps_bad_rate(const gs_comp_steps *s, double *t, size_t *full_index);
/* The largest relative mismatch seen at the end of a stretch between what a
 * compartment discharged and what the next one received (round-off). */
double gs_comp_steps_worst_coupling(const gs_comp_steps *s);
void gs_comp_steps_free(gs_comp_steps *s);
/* --timings: where each thread's time went. */
void gs_comp_steps_print_threads(const gs_comp_steps *s, FILE *f);

#endif
