/* CSV tables with their metadata in a JSON sidecar (csv_meta.c), so that a
 * table starts with its header line and pandas, spreadsheets and gransim's own
 * readers take it as it is. */
#ifndef GRANSIM_DEMDATA_CSV_META_H
#define GRANSIM_DEMDATA_CSV_META_H
#include <stdio.h>

#include "gransim/error.h"

/* Writes FILE.json beside FILE.csv (csv_path ends in .csv):
 *   {"file": "FILE.csv", "written_by": ..., "description": ...,
 *    "units": {"column": "unit", ...}}
 * units: pairs of column name and SI unit ("1" for counts and ratios),
 * NULL-terminated; NULL for none.  Written whole (renamed from .partial). */
int gs_csv_meta_write(const char *csv_path, const char *written_by, const char *description,
                      const char *const *units, gs_error *err);

/* A table written in memory: its writer states what it holds in "# " lines,
 * as a reader of the file would want them, and gs_csv_close moves those
 * lines (wherever they are) into the sidecar's description and writes the
 * rest, header line first, to path (renamed from path.partial). */
typedef struct {
  char path[4200];
  char *buf;
  size_t len;
  FILE *fp;
} gs_csv_out;
FILE *gs_csv_open(gs_csv_out *t, const char *path, gs_error *err);
/* gs_csv_open on DIR/NAME. */
FILE *gs_csv_open_in(gs_csv_out *t, const char *dir, const char *name, gs_error *err);
int gs_csv_close(gs_csv_out *t, const char *written_by, const char *const *units, gs_error *err);
#endif
