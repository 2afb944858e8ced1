/* gransim — LIGGGHTS as an engine behind a `gransim dem` case (dem.engine:
 * liggghts): the case's keys become a LIGGGHTS 3.8 deck, the deck runs under
 * mpirun, and its dumps are reduced (src/demdata) into the tables the
 * embedded engine writes.  How each key maps: docs/design-notes.md,
 * "LIGGGHTS engine". */
#ifndef GRANSIM_LIGGGHTS_H
#define GRANSIM_LIGGGHTS_H

#include <stdio.h>

#include "gransim/dem.h"
#include "gransim/error.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
  int ranks;            /* MPI ranks (<= 0: the machine's cores) */
  const char *launcher; /* command that starts LIGGGHTS, e.g. "srun -n 64" (NULL: mpirun -np ranks) */
  const char *binary;   /* the LIGGGHTS executable (NULL: $GRANSIM_LIGGGHTS or "liggghts") */
  int progress;         /* a progress line on stderr from LIGGGHTS' thermo output */
  int dry_run;          /* write the folder (deck, bed, meshes, run.sh) without running */
  int reduce_only;      /* reduce the dumps of a finished run in the folder (e.g. from a cluster) */
} gs_lig_options;

/* Write the deck of case c to fp.  data_file: the initial bed's data file
 * (read_data), or NULL when the case has no fill.  exclusion: "read" for the
 * real run (each mesh reads ex_<wall>.txt), or NULL for none.  Fails naming
 * the key when the case holds something a deck cannot express. */
int gs_lig_write_deck(const gs_dem_case *c, FILE *fp, const char *data_file, const char *exclusion,
                      gs_error *err);
/* Whether the deck can express case c (for `gransim dem --check`). */
int gs_lig_check(const gs_dem_case *c, gs_error *err);
/* Write the deck, the initial bed and copies of the meshes into
 * out_dir/liggghts, run it, and reduce its dumps into out_dir's tables.  A
 * failed run's error holds LIGGGHTS' error line, the deck line it refers to
 * and the last lines of its output; no table is written then.  dry_run: the
 * folder and its run.sh only (the exclusion runs and the run, for a cluster
 * job).  reduce_only: the tables from the folder's dumps, refused unless its
 * log.liggghts shows a finished run. */
int gs_lig_case_run(gs_dem_case *c, const char *out_dir, const gs_lig_options *opt, gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
