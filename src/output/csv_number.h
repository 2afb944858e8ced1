/* A number of summary.csv: the text printf's "%.10g" gives, written ~3.5x
 * faster (56 against 200 ns here).  Rank 0 formats 16 numbers per
 * compartment at every output time; through fprintf that was ~12 µs of the
 * ~75 µs an output time of the CoriMix example costs it, on the other
 * ranks' path under MPI. */
#ifndef GRANSIM_IO_CSV_NUMBER_H
#define GRANSIM_IO_CSV_NUMBER_H

#include <stddef.h>

/* Longest text gs_csv_number writes, with its terminating NUL. */
#define GS_CSV_NUMBER_MAX 32

/* Writes x as snprintf(buf, GS_CSV_NUMBER_MAX, "%.10g", x) would, byte for
 * byte, and returns its length. */
size_t gs_csv_number(double x, char *buf);

#endif
