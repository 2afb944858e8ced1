/* gransim — result files.
 *
 * gs_output writes DIR/result.h5 (HDF5) and DIR/summary.csv.  Both are written
 * to temporary names (".result.h5.partial", ".summary.csv.partial") and only
 * renamed into place by gs_output_finish(ok = 1): a failed or killed run never
 * leaves a half-written result under the final names.
 *
 * result.h5 layout:
 *   /grid/<axis name>/edges, /grid/<axis name>/pivots   (float64)
 *   /grid attributes: dim, ncomp, ncells, axis_names
 *   /time                          (ntimes)
 *   /number                        (ntimes, ncomp, n0[, n1[, n2]]) particle numbers per cell
 *   /summary/<column>              (ntimes, ncomp) every summary.csv column
 *   /ledger                        (ntimes, ncomp, 2*dim) external and lost volume per axis
 *   /case  attribute "text": the case file as read; attribute "file": its name
 *   attributes on /: gransim_version, status ("complete"), ntimes (output
 *   times completely written: the commit mark a resume trusts)
 * The datasets are extendible along time; output times are committed (written,
 * flushed, counted in the attribute ntimes) in checkpoints, see
 * gs_output_set_checkpoint.
 *
 * summary.csv: one row per output time and compartment:
 *   time,compartment,M0,M1,M2,d10,d50,d90,mean_<axis>...,total_<axis>...
 * M1 and M2 are moments of the granule volume (sum of the size axes). */
#ifndef GRANSIM_OUTPUT_H
#define GRANSIM_OUTPUT_H

#include "gransim/pbm.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gs_output gs_output;

/* mkdir -p DIR: every missing folder of the path, then insist on a folder
 * (GS_EIO naming it otherwise).  For the commands that write into DIR. */
int gs_output_mkdir_p(const char *dir, gs_error *err);

/* Create DIR if needed and open the partial files.  case_text/case_name are
 * stored as the case echo. */
gs_output *gs_output_open(const char *dir, const gs_model *m, const char *case_text,
                          const char *case_name, size_t nresume, gs_error *err);
/* Append one output time: state y (nstate), ledger (nledger) and the
 * integrators' state (nresume values, as given to gs_output_open; NULL when
 * 0), which only the journal keeps, for a resume. */
int gs_output_write(gs_output *o, const gs_model *m, double t, const double *y,
                    const double *ledger, const double *resume, gs_error *err);
/* The same in gs_output_parts(o) pieces, for a caller that fills idle
 * moments (an MPI rank waiting for the others): a compartment's summary and
 * CSV row, one large series' row (the largest piece: deflating it takes the
 * longest, so it stands alone to keep the pieces short), then the small
 * series' rows with the commit when it is due (gs_output_set_checkpoint).
 * Parts 0, 1, ... in order, with the same t, y and ledger, none of another
 * output time in between (refused otherwise); gs_output_finish refuses to
 * publish an output time that is only partly written. */
int gs_output_parts(const gs_output *o);
int gs_output_write_part(gs_output *o, const gs_model *m, double t, const double *y,
                         const double *ledger, const double *resume, int part, gs_error *err);
/* Commit buffered output times once `seconds` of wall time have passed since
 * the last commit (and when 64 MiB are buffered, and at the end); 0 (the
 * default) commits every output time.  A killed run keeps what was committed. */
void gs_output_set_checkpoint(gs_output *o, double seconds);
/* 1 when that much wall time has passed since the last commit: output times
 * held back by the caller should be written now, so that a killed run loses
 * no more than the checkpoint promises. */
int gs_output_commit_due(const gs_output *o);
/* Checkpoint/restart: read the journal (DIR/.result.journal) left by an
 * interrupted run of the same case (same grid and nresume; checked) up to its
 * last commit, rebuild the partial files from it, read back the last
 * committed time, state, ledger and integrator state into *t, y, ledger,
 * resume, and continue appending after it.  Fails with a clear message if
 * there is nothing to resume or the grid differs. */
gs_output *gs_output_resume(const char *dir, const gs_model *m, size_t nresume, double *t,
                            double *y, double *ledger, double *resume, gs_error *err);
/* ok = 1: close and rename into place, then delete the journal (a kill
 * before that leaves it, and --resume publishes again); ok = 0: close and
 * delete the partial files and the journal.  Frees o in both cases. */
int gs_output_finish(gs_output *o, int ok, gs_error *err);
/* Commit every output time written and close, keeping the partial files
 * and the journal: gs_output_resume continues from the last time written
 * (a run an observer stopped to change the model and go on).  Frees o. */
int gs_output_hold(gs_output *o, gs_error *err);
/* Add (or replace) a double dataset of rank dims at path (groups made as
 * needed) in the published file h5_path, with its `units` and `dimensions`
 * attributes (the coupling's /coupling/cycles). */
int gs_output_add_dataset(const char *h5_path, const char *path, int rank, const unsigned long long *dims,
                          const double *data, const char *units, const char *dimensions, gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
