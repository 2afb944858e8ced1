/* Error reporting helpers: see include/gransim/error.h. */
#include "gransim/error.h"

#include <gsl/gsl_errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int gs_error_set(gs_error *err, int code, const char *fmt, ...) {
  if (err) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    err->code = code;
  }
  return code;
}

int gs_error_prefix(gs_error *err, const char *fmt, ...) {
  if (!err) return GS_EINPUT;
  char prefix[512];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(prefix, sizeof prefix, fmt, ap);
  va_end(ap);
  /* Shift the old message right and put the prefix in front, truncating at the end. */
  size_t plen = strlen(prefix), cap = sizeof err->msg - 1;
  if (plen > cap) plen = cap;
  size_t olen = strlen(err->msg);
  if (plen + olen > cap) olen = cap - plen;
  memmove(err->msg + plen, err->msg, olen);
  memcpy(err->msg, prefix, plen);
  err->msg[plen + olen] = '\0';
  return err->code;
}

void *gs_malloc(size_t nbytes, gs_error *err) {
  void *p = malloc(nbytes ? nbytes : 1);
  if (!p) gs_error_set(err, GS_ENOMEM, "out of memory allocating %zu bytes", nbytes);
  return p;
}

void *gs_calloc_apart(size_t nbytes, gs_error *err) {
  const size_t bytes = (nbytes ? nbytes + GS_APART - 1 : GS_APART) / GS_APART * GS_APART;
  void *p = aligned_alloc(GS_APART, bytes);
  if (p) memset(p, 0, bytes);
  else gs_error_set(err, GS_ENOMEM, "out of memory allocating %zu bytes", nbytes);
  return p;
}

void *gs_calloc(size_t count, size_t size, gs_error *err) {
  void *p = calloc(count ? count : 1, size ? size : 1);
  if (!p) gs_error_set(err, GS_ENOMEM, "out of memory allocating %zu x %zu bytes", count, size);
  return p;
}

/* The last GSL error of this thread (threads evaluate rates at once). */
static _Thread_local char gsl_reason[256];

static void gsl_record(const char *reason, const char *file, int line, int gsl_errno) {
  snprintf(gsl_reason, sizeof gsl_reason, "%s (%s, in GSL's %s:%d)", reason ? reason : "error",
           gsl_strerror(gsl_errno), file ? file : "?", line);
}

void gs_gsl_clear(void) { gsl_reason[0] = '\0'; }
const char *gs_gsl_reason(void) { return gsl_reason; }

int gs_gsl_error(gs_error *err, int code, const char *what) {
  return gs_error_set(err, code, "%s: GSL: %s", what, gsl_reason[0] ? gsl_reason : "unknown error");
}

void gs_gsl_install(void) { gsl_set_error_handler(gsl_record); }

/* Once, when the library is loaded: in a file every part of it links, so
 * no program using libgransim can reach GSL's aborting default. */
__attribute__((constructor)) static void gs_gsl_at_load(void) { gs_gsl_install(); }
