/* The resources of an SWA case, stated before a run takes them: its memory
 * and the size of its result files against `limits` (case/limits.h). */
#include <omp.h>

#include "case/limits.h"
#include "swa/sim.h"

/* Characters of a summary.csv value (as case/limits.c counts them). */
#define CSV_CHARS 17

int gs_swa_check_limits(gs_cfg_node *root, const gs_swa_case *c, gs_error *err) {
  gs_limits lim;
  int rc = gs_limits_read(root, &lim, err);
  if (rc) return rc;
  const gs_swa_model *m = &c->model;
  const double runs = (double)c->runs, nt = (double)c->ntimes, nz = (double)m->ncomp;
  const double ncells = (double)c->grid.ncells, ncol = gs_swa_ncolumns(m), nsieve = (double)c->nsieve;
  /* per output time and compartment: the summary columns, the binned
   * numbers, the numbers outside the grid and the particle count, the sieve
   * classes (src/swa/run.c) */
  const double per_tz = ncol + ncells + 2 + nsieve;
  /* every run's observations (run-major, for results independent of the
   * ranks and threads), their means and confidence half-widths, and the
   * particles (coordinates, weight, LPDA stamp, Fenwick leaves and nodes
   * of the cached properties) of the runs in progress at once */
  const double inflight = runs < omp_get_max_threads() ? runs : omp_get_max_threads();
  const double particle = m->ncoord + 1 + (m->has_continuous != 0) + 2.0 * m->nprop;
  const double bytes = 8 * (runs * (nt * nz * per_tz + 4) + 2 * nt * nz * per_tz +
                            inflight * nz * (double)m->nmax * particle);
  if (bytes / 1e9 > lim.memory_gb)
    return gs_cfg_fail(gs_cfg_get(root, "solver"), err,
                       "a run of this case needs at least %.3g GB of memory on one process (%.0f "
                       "runs x %.0f output times x %.0f compartments x %.0f values kept per run, "
                       "and %zu particles per compartment for each of the %.0f runs in progress at "
                       "once), more than limits.memory_gb = %.3g GB%s: use fewer runs, output "
                       "times, grid cells or particles, or raise limits.memory_gb on a larger machine",
                       bytes / 1e9, runs, nt, nz, per_tz, m->nmax, inflight, lim.memory_gb,
                       lim.node ? "" : " (80 % of this machine's memory)");
  /* result.h5: mean and confidence half-width of every value; summary.csv:
   * time, compartment, the columns and their half-widths */
  const double out = nt * nz * (8 * 2 * per_tz + CSV_CHARS * (2 + 2 * ncol)) + 8 * nt;
  if (out / 1e9 > lim.output_gb)
    return gs_cfg_fail(gs_cfg_get(root, "output"), err,
                       "%.0f output times of %.0f compartments x %.0f grid cells would write %.3g GB "
                       "(result.h5 before compression and summary.csv), more than limits.output_gb "
                       "= %.3g GB: write fewer output times (output.count or output.times) or raise "
                       "limits.output_gb",
                       nt, nz, ncells, out / 1e9, lim.output_gb);
  return GS_OK;
}
