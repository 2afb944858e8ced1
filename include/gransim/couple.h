/* gransim — coupled PBM-DEM cases (`gransim couple`, docs/case-files.md).
 *
 * One case file holds the sectional PBM case, a `dem:` section (a `gransim
 * dem` case, inline or a file name) and a `coupling:` section.  With
 * `mode: one_way` (uni-directional coupling, Sampat et al. 2018) the DEM runs
 * once, its size classes derived from the PBM grid, until the steady-state
 * detector fires; its tables become the PBM's `table` kernel and `dem_impact`
 * selection, and the PBM runs with them.  With `mode: two_way` (De et al.
 * 2025) the PBM runs in stretches that a trigger ends (coupling.trigger), each
 * with the tables of a fresh DEM of the population at its start (DIR/cycle-N/,
 * DIR/cycles.csv).  Stages are resumable: the DEM's tables appear atomically,
 * the PBM resumes from its partial files. */
#ifndef GRANSIM_COUPLE_H
#define GRANSIM_COUPLE_H

#include <stddef.h>

#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_couple_options {
  const char *out_dir; /* DIR: DIR/dem/ the DEM stage (two-way: DIR/cycle-N/), DIR/result.h5 the PBM */
  int resume;          /* skip a complete DEM stage, resume the PBM from its partial files */
  int progress;        /* progress lines on stderr */
  int ranks;            /* MPI ranks of every LIGGGHTS DEM stage (<= 0: the machine's cores) */
  const char *launcher; /* starts LIGGGHTS instead of `mpirun -np ranks`, e.g. "srun -n 64" (NULL: mpirun) */
} gs_couple_options;

/* Validate a coupled case without running it: the coupling section, the
 * derived classes, the DEM case built with them and the PBM case read with
 * placeholder tables of the derived classes.  desc: one line describing it. */
int gs_couple_check(const char *path, char *desc, size_t n, gs_error *err);
/* gs_couple_check, and opt's LIGGGHTS options (ranks, launcher) refused,
 * naming dem.engine, when the DEM section runs on the embedded engine, where
 * they cannot act (opt NULL: none given). */
int gs_couple_check_options(const char *path, const gs_couple_options *opt, char *desc, size_t n, gs_error *err);
/* Run a coupled case into opt->out_dir. */
int gs_couple_run(const char *path, const gs_couple_options *opt, gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
