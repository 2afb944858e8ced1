/* See h5_setup.h. */
#include "output/h5_setup.h"

#include <hdf5.h>
#include <stdio.h>
#include <string.h>

void gs_h5_setup(void) {
  H5dont_atexit(); /* refused once the library runs: harmless */
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

typedef struct {
  char *buf;
  size_t len;
} cause_t;

/* The file driver's reads and writes say "file write failed: time = ...,
 * filename = ..., errno = 27, error message = 'File too large', buf = ..."
 * over two lines: only "file write failed: File too large" is kept of those. */
static herr_t first_cause(unsigned n, const H5E_error2_t *e, void *data) {
  const cause_t *c = data;
  if (n || !e->desc) return 0;
  const char *sys = strstr(e->desc, "error message = '"), *colon = strchr(e->desc, ':');
  if (sys && colon) {
    sys += strlen("error message = '");
    const char *end = strchr(sys, '\'');
    snprintf(c->buf, c->len, "%.*s: %.*s", (int)(colon - e->desc), e->desc,
             (int)(end ? end - sys : 200), sys);
  } else {
    snprintf(c->buf, c->len, "%s", e->desc);
  }
  return 0;
}

void gs_h5_cause(char *buf, size_t len) {
  if (!len) return;
  buf[0] = '\0';
  cause_t c = {buf, len};
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, first_cause, &c);
}
