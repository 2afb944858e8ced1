/* gransim — a case: everything a run needs, read and validated from a YAML
 * case file (see docs/case-files.md for every key).
 *
 * gs_case_load validates the whole file where it is read: grid, initial
 * distribution, mechanisms with their kernels, solver, output times and
 * checks.  Any problem is reported with file, line, key, value and
 * expectation, and nothing is run. */
#ifndef GRANSIM_CASE_H
#define GRANSIM_CASE_H

#include "gransim/cfg.h"
#include "gransim/integrator.h"
#include "gransim/pbm.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_checks {
  double mass_tolerance;     /* relative error allowed in the volume balance of every axis */
  double negative_tolerance; /* negative numbers allowed down to -tol * max(N) - negative_floor */
  double negative_floor;     /* absolute allowance: 100 x the solver's atol (error-control noise) */
  double max_loss;           /* fraction of volume allowed to leave through grid boundaries */
} gs_checks;

typedef struct gs_case {
  gs_cfg *cfg;
  char title[256];
  gs_model model;
  double *y0;          /* nstate + nledger: numbers then ledger (zero) */
  double t0;
  double *times;       /* output times, increasing, times[0] = t0 */
  size_t ntimes;
  gs_ode ode;          /* the ODE system of the model (numbers + ledger), in eval */
  gs_eval eval;        /* the whole model's evaluation context (noise floor: solver.atol) */
  double *abs_scale;   /* error-control scale per component (the ledger at a typical particle's volume) */
  double atol;         /* solver.atol, or the case's default (docs/models.md, "Default tolerances") */
  gs_integrator_setup integrator_setup; /* solver.method and its keys, for more integrators */
  gs_integrator integrator;            /* of ode */
  gs_checks checks;
  double checkpoint;   /* output.checkpoint: seconds of wall time between commits */
  /* solver.rebalance: under MPI, move compartments between ranks between
   * steps when the measured costs promise a largest block this fraction
   * cheaper (0: whenever the best split differs; none (-1): never) */
  double rebalance;
  /* solver.steps: 1 = per_compartment (each compartment its own steps,
   * src/run/compartment_steps.h), 0 = shared (one step for all) */
  int per_compartment;
} gs_case;

/* Read, validate and build a case from a file, or from an already loaded
 * configuration (taken over by the case). */
int gs_case_load(const char *path, gs_case *c, gs_error *err);
int gs_case_from_cfg(gs_cfg *cfg, gs_case *c, gs_error *err);
void gs_case_free(gs_case *c);
/* The grid section without a sectional model (the SWA solver reads it so):
 * the axes and compartments into g (free with gs_grid_free, also on
 * failure), grid.size_axes as a bit mask (bit k: axis k; all axes when
 * absent), and in *section the grid map, whose other keys the caller reads
 * before gs_cfg_check_unused. */
int gs_case_read_grid_only(gs_cfg_node *root, gs_grid *g, int *size_axes, gs_cfg_node **section,
                           gs_error *err);
/* The `output` section alone (also read by the SWA solver); *times is
 * malloc'ed. */
int gs_case_read_times(gs_cfg_node *root, double *t0, double **times, size_t *ntimes,
                       gs_error *err);
/* discretisation.tolerance (default GS_DISC_TOLERANCE): the largest relative
 * error with which a case's distributions may be represented. */
int gs_case_read_disc_tolerance(gs_cfg_node *root, double *tolerance, gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
