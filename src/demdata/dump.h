/* One snapshot of a LAMMPS/LIGGGHTS text dump (`dump custom` or `dump local`):
 *   ITEM: TIMESTEP / step / ITEM: NUMBER OF ATOMS|ENTRIES / n /
 *   ITEM: BOX BOUNDS ... / 3 lines / ITEM: ATOMS|ENTRIES <names> / n rows
 * Columns are found by name; every value is read as a double.  Other ITEM
 * sections (UNITS, TIME, ...) are skipped.  A file with a second TIMESTEP is
 * refused rather than silently cut. */
#ifndef GRANSIM_DEMDATA_DUMP_H
#define GRANSIM_DEMDATA_DUMP_H
#include <stddef.h>

#include "gransim/error.h"

typedef struct {
  char *path;
  long step;
  size_t nrows, ncols;
  char **names;        /* ncols column names */
  double *v;           /* nrows * ncols, row-major */
  long first_row_line; /* line number of row 0 (rows are consecutive lines) */
} gs_dump;

int gs_dump_read(const char *path, gs_dump *d, gs_error *err);
/* Column index by exact name, or -1. */
long gs_dump_col(const gs_dump *d, const char *name);
/* Column of a `dump local` whose name ends in "[k]" (c_pwc[k]), or -1. */
long gs_dump_col_index(const gs_dump *d, int k);
void gs_dump_free(gs_dump *d);
#endif
