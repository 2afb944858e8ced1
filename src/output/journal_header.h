/* What the header of a run's journal (journal.h) holds, so that a resume
 * needs nothing else: the grid and the shape of the state, to refuse a case
 * they do not fit, and the case echo written into the rebuilt result.h5. */
#ifndef GRANSIM_OUTPUT_JOURNAL_HEADER_H
#define GRANSIM_OUTPUT_JOURNAL_HEADER_H

#include <stddef.h>

#include "gransim/pbm.h"

/* The header bytes for model m, nresume values of integrator state per
 * output time, and the case text and file name (malloc'ed into *buf). */
int gs_journal_header_encode(const gs_model *m, size_t nresume, const char *text, const char *name,
                             void **buf, size_t *n, gs_error *err);
/* Checks header bytes against m and nresume (messages name `path`); *text
 * and *name point into buf. */
int gs_journal_header_check(const void *buf, size_t n, const gs_model *m, size_t nresume,
                            const char *path, const char **text, const char **name,
                            gs_error *err);

#endif
