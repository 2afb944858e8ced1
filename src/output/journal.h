/* The commit journal of a run's result files: DIR/.result.journal.
 *
 * HDF5 (without SWMR) rewrites its metadata in place and in no particular
 * order, so a kill in the middle of a flush can leave a file whose committed
 * rows can no longer be read (a chunk index pointing past the end the
 * superblock records).  A resume therefore never reads the partial
 * result.h5: every output time also goes, as one record, to this
 * append-only file, and a commit appends a commit record after them.  Every
 * record carries a CRC-32 (zlib) of its contents, so a record torn by a kill
 * is recognised, and a reader trusts the rows up to the last intact commit
 * record and nothing after it.
 *
 * Layout (native byte order; the file lives only as long as the run):
 *   header:  "GSJRNL01", u64 values per row, u64 header bytes, the caller's
 *            header bytes, u32 CRC-32 of all of it
 *   row:     u32 'R', u32 CRC-32 of (index, values), u64 index, the values
 *   commit:  u32 'C', u32 CRC-32 of count, u64 count of rows it commits
 * A kill only ever leaves a file whose prefix up to some write is intact
 * (the records are written in order, each after the one before), which is
 * what the last intact commit record relies on. */
#ifndef GRANSIM_OUTPUT_JOURNAL_H
#define GRANSIM_OUTPUT_JOURNAL_H

#include <stddef.h>
#include <stdint.h>

#include "gransim/error.h"

typedef struct gs_journal gs_journal;

/* A new journal with the caller's header bytes and rows of row_values
 * doubles, written to path_new and renamed to path once the header is on
 * the disk (a kill before leaves no journal under path). */
gs_journal *gs_journal_create(const char *path_new, const char *path, const void *head,
                              size_t nhead, size_t row_values, gs_error *err);
/* Appends the row of one output time, in pieces (their lengths add up to
 * the row's values).  Rows count only once committed. */
int gs_journal_append(gs_journal *j, const double *const *pieces, const size_t *lens, int npieces,
                      gs_error *err);
/* Commits every row appended so far: after them, a commit record, and both
 * handed to the system (a kill of the process loses neither). */
int gs_journal_commit(gs_journal *j, gs_error *err);
/* Rows committed so far. */
uint64_t gs_journal_committed(const gs_journal *j);

/* Opens a killed run's journal: checks every record, takes the rows up to
 * the last intact commit record, cuts off what follows (a torn or
 * uncommitted tail) and continues appending there.  *head (malloc'ed, free
 * it) and *nhead: the header bytes; *row_values: doubles per row. */
gs_journal *gs_journal_reopen(const char *path, void **head, size_t *nhead, size_t *row_values,
                              gs_error *err);
/* Reads committed row `index` (0-based) into row. */
int gs_journal_read(gs_journal *j, uint64_t index, double *row, gs_error *err);

/* Closes the file (the journal stays on the disk); frees j. */
int gs_journal_close(gs_journal *j, gs_error *err);

#endif
