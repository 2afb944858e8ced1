/* Tables over size classes read from a CSV file (text; '#' starts a comment
 * line; blank lines ignored):
 *   edges, e0, e1, ..., en     n classes of a size measure, edges >= 0 increasing
 *   v00, v01, ..., v0(n-1)     then rows of n values:
 *   ...                          rows = 0: n rows, a symmetric matrix >= 0
 *                                (the kernel table); else exactly `rows` rows.
 * Errors name the file and line. */
#ifndef GRANSIM_CLASS_TABLE_H
#define GRANSIM_CLASS_TABLE_H
#include <stddef.h>

#include "gransim/error.h"

typedef struct {
  double *edges; /* n + 1 */
  size_t n, rows;
  double *c;     /* rows * n */
} gs_class_table;

int gs_class_table_read(const char *path, size_t rows, gs_class_table *tf, gs_error *err);
/* Class of each cell by its size measure (a diameter when `diameter`):
 * class i holds [e_i, e_i+1), so a size on an inner edge (to a few ulps,
 * gs_axis_locate_snapped) takes the class above it, and the last edge the
 * last class.  Cells outside the edges take the nearest class; each of the
 * two cases gives one warning on stderr. */
size_t *gs_class_table_assign(const gs_class_table *tf, const double *size, size_t ncells,
                              int diameter, const char *path, gs_error *err);
void gs_class_table_free(gs_class_table *tf);
#endif
