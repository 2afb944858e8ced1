/* A number of summary.csv: the text printf's "%.10g" gives, written several
 * times faster.  Rank 0 formats 16 numbers per compartment at every output
 * time, and under MPI that work lies on the other ranks' path; through
 * fprintf it was a sizeable part of an output time's cost
 * (docs/performance.md). */
#ifndef GRANSIM_IO_CSV_NUMBER_H
#define GRANSIM_IO_CSV_NUMBER_H

#include <stddef.h>

/* Longest text gs_csv_number writes, with its terminating NUL. */
#define GS_CSV_NUMBER_MAX 32

/* Writes x as snprintf(buf, GS_CSV_NUMBER_MAX, "%.10g", x) would, byte for
 * byte, and returns its length. */
size_t gs_csv_number(double x, char *buf);

#endif
