/* gransim — error reporting.
 *
 * Every fallible function returns an int status (GS_OK on success) and, on
 * failure, fills a caller-owned gs_error with a complete, human-readable
 * message.  Messages about case files always name the file, the line, the key,
 * the offending value and what was expected. */
#ifndef GRANSIM_ERROR_H
#define GRANSIM_ERROR_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

enum gs_status {
  GS_OK = 0,
  GS_EINPUT = 1,   /* invalid case file, table or argument */
  GS_ENUMERIC = 2, /* NaN, negative density, lost mass, integrator failure */
  GS_EIO = 3,      /* file could not be read or written */
  GS_ENOMEM = 4    /* allocation failed */
};

typedef struct gs_error {
  int code;
  char msg[2048];
} gs_error;

/* Set *err (if non-NULL) to code and a printf-formatted message; returns code. */
int gs_error_set(gs_error *err, int code, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Prefix an existing message with context ("while reading X: ..."); returns err->code. */
int gs_error_prefix(gs_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* GSL reports errors through one process-wide handler whose default aborts.
 * libgransim replaces it when loaded (a constructor in src/core/error.c) by
 * one that records the error of the calling thread and returns, so every GSL
 * call's status is the caller's to turn into a gransim error with the key or
 * file it concerns.  gs_gsl_reason gives the last recorded reason ("" if
 * none since gs_gsl_clear); gs_gsl_error sets *err to "what: GSL: reason". */
void gs_gsl_clear(void);
const char *gs_gsl_reason(void);
int gs_gsl_error(gs_error *err, int code, const char *what);
/* Install the handler again (after a caller replaced it). */
void gs_gsl_install(void);

/* malloc/calloc that set GS_ENOMEM in *err on failure (return NULL). */
void *gs_malloc(size_t nbytes, gs_error *err);
void *gs_calloc(size_t count, size_t size, gs_error *err);
/* Data that different threads write must lie whole 4 KiB pages apart, not
 * just whole cache lines: the cores' prefetchers fetch the lines next to
 * those they miss (never across a 4 KiB page), and a neighbouring line that
 * another core is writing then moves between the cores at every write.  The
 * cost is largest where the cores sit on different core complexes, where
 * two threads can end up slower than one (measurements: docs/performance.md,
 * "Eleventh session: pages, not lines"). */
#define GS_APART ((size_t)4096)
/* Zeroed memory on a page boundary, in whole pages, for arrays that threads
 * write in separate parts (free with free()); and a count of doubles rounded
 * up to whole pages, for the stride between those parts. */
void *gs_calloc_apart(size_t nbytes, gs_error *err);
static inline size_t gs_doubles_apart(size_t n) {
  const size_t per = GS_APART / sizeof(double);
  return (n + per - 1) / per * per;
}

#ifdef __cplusplus
}
#endif
#endif
