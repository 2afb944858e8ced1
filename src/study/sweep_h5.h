/* DIR/sweep.h5: the sweep's table as HDF5 datasets, for Python and MATLAB
 * users (src/study/sweep_h5.c). */
#ifndef GRANSIM_STUDY_SWEEP_H5_H
#define GRANSIM_STUDY_SWEEP_H5_H

#include "gransim/study.h"

/* rows[r]: run r's journal line, NULL for a run not finished (left out).
 * Written as DIR/.sweep.h5.partial, renamed into place. */
int gs_sweep_write_h5(const char *dir, const gs_design *d, const gs_study_outputs *o,
                      char *const *rows, gs_error *err);

#endif
