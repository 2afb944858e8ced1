/* Whole chunks of an HDF5 dataset written straight to the file
 * (H5Dwrite_chunk), deflated here with zlib when the dataset has the deflate
 * filter.
 *
 * Why: the result file's large series (/number, /carried) are chunked by up
 * to 64 KiB of output times, and every commit writes whole rows.  Through
 * H5Dwrite, HDF5 iterates the selections and runs its filter pipeline chunk
 * by chunk, setting zlib up again for every chunk; for small cases that
 * cost a sizeable share of the whole run (docs/performance.md).
 * Written directly, a chunk is one pwrite plus an index entry, and one zlib
 * stream is reset between chunks instead of rebuilt.  The file is the same
 * as H5Dwrite would make it: the deflate filter's chunks are zlib streams
 * (compress2 format), and a chunk that does not shrink is stored raw with the
 * (optional) filter marked skipped in its mask, as HDF5 itself would. */
#ifndef GRANSIM_IO_CHUNK_WRITER_H
#define GRANSIM_IO_CHUNK_WRITER_H

#include <hdf5.h>
#include <stddef.h>

typedef struct gs_chunk_writer gs_chunk_writer;

/* NULL when out of memory or when zlib cannot start. */
gs_chunk_writer *gs_chunk_writer_new(void);
void gs_chunk_writer_free(gs_chunk_writer *w);

/* 1 when rows of float64 can go to the file as they are in memory (the
 * file type is little-endian IEEE; so must the native double be). */
int gs_chunk_direct_ok(void);

/* Writes `count` chunks of `values` doubles each, one per index start,
 * start + 1, ... along the first dimension (the dataset's chunks are one row
 * long and span the other dimensions); deflated (level `level`) when
 * `deflate`, raw otherwise.  The dataset must already be extended.  Returns
 * a negative value on failure, as HDF5 calls do. */
herr_t gs_chunk_write_rows(gs_chunk_writer *w, hid_t ds, hsize_t start, hsize_t count,
                           size_t values, const double *rows, int deflate, int level);

/* Rows [start, start + count) of a dataset without filters whose chunks
 * are `chunk_rows` rows of `values` doubles, start a multiple of
 * chunk_rows: whole chunks, the last one padded with zeros past the rows
 * given (beyond the dataset's extent, where no reader looks; a later write
 * of those rows replaces them).  The small series of the result file: one
 * H5Dwrite of a few rows costs many times a direct chunk. */
herr_t gs_chunk_write_blocks(gs_chunk_writer *w, hid_t ds, hsize_t start, hsize_t count,
                             size_t chunk_rows, size_t values, const double *rows);

/* The same for one row deflated in pieces, so that a caller can interleave
 * other work (rank 0 of an MPI run writes while it waits for the others,
 * and a large row takes milliseconds to deflate): gs_chunk_row_begin(w, bytes,
 * level), then gs_chunk_row_feed() over consecutive spans of the row, then
 * gs_chunk_row_write() with the whole row (stored raw when zlib failed or
 * did not shrink it).  The compressed chunk is the one gs_chunk_write_rows
 * makes. */
void gs_chunk_row_begin(gs_chunk_writer *w, size_t bytes, int level);
void gs_chunk_row_feed(gs_chunk_writer *w, const void *span, size_t n, int last);
herr_t gs_chunk_row_write(gs_chunk_writer *w, hid_t ds, hsize_t index, size_t values,
                          const double *row);

#endif
