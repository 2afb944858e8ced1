/* SI units of the result files' quantities (units.c): the summary columns
 * (summary.csv's header names them, `d50 [m]`) and the `units` and
 * `dimensions` attributes of result.h5's datasets, one scheme and one
 * attribute type for the sectional and the stochastic solver. */
#ifndef GRANSIM_OUTPUT_UNITS_H
#define GRANSIM_OUTPUT_UNITS_H
#include <hdf5.h>
#include <stddef.h>

/* The unit of a summary column (`ci_` columns: that of the statistic):
 * time s, M0 1, M1 m^3, M2 m^6, d10/d50/d90 m, mean_ and total_ of a volume
 * coordinate m^3; NULL for `compartment`, an index. */
const char *gs_summary_unit(const char *column);
/* summary.csv's header field of a column: "NAME [UNIT]", or NAME alone. */
void gs_summary_header(const char *column, char *buf, size_t n);
/* Fixed-length UTF-8 string attribute (replaced when it exists). */
herr_t gs_h5_str_attr(hid_t loc, const char *name, const char *value);
/* Scalar 64-bit integer attribute. */
herr_t gs_h5_i64_attr(hid_t loc, const char *name, long long value);
/* The attributes `units` (SI) and `dimensions` (comma-separated names of the
 * axes, slowest first) of dataset `path` below loc. */
herr_t gs_h5_describe(hid_t loc, const char *path, const char *units, const char *dimensions);
#endif
