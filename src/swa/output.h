/* Result files of an SWA run: DIR/result.h5 and DIR/summary.csv, written
 * under temporary names and renamed only when complete (like the sectional
 * outputs, see include/gransim/output.h).
 *
 * summary.csv: time,compartment,M0,M1,M2,d10,d50,d90,mean_<c>...,total_<c>...,
 *   then ci_<column> for each: the ensemble mean and the 90 % CI half-width.
 * result.h5: /grid/<axis>/edges|pivots, /time, /number (ntimes, ncomp,
 *   cells...) ensemble-mean number per grid cell (particles binned by the
 *   coordinates the grid axes name), /number_ci, /outside (numbers outside
 *   the grid), /summary/<col>, /summary_ci/<col>, /particles (mean count of
 *   computational particles), with solver.sieves /sieve/edges and
 *   /sieve/mass_fraction[_ci] (ntimes, ncomp, classes), /discretisation (the
 *   distributions as asked and as the particles hold them, gs_swa_disc), /case (attributes text, file), and root
 *   attributes gransim_version, solver = "swa", runs, particles, seed,
 *   jumps, fictitious, status = "complete". */
#ifndef GS_SWA_OUTPUT_H
#define GS_SWA_OUTPUT_H

#include "gransim/swa.h"

typedef struct gs_swa_results {
  const double *mean, *ci;           /* [time][comp][col] */
  const double *hist, *hist_ci;      /* [time][comp][cell] */
  const double *outside, *particles; /* [time][comp] */
  const double *sieve, *sieve_ci;    /* [time][comp][class], with solver.sieves */
  gs_swa_stats stats;
} gs_swa_results;

int gs_swa_write(const gs_swa_case *c, const char *dir, const gs_swa_results *r, gs_error *err);

#endif
