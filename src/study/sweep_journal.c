/* The journal of a sweep, DIR/runs.csv (src/study/sweep.c): read back on
 * --resume.  See study_internal.h. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#include "study/study_internal.h"

/* Whether header lines a and b name the same columns, units aside: a
 * journal written before the headers gave units ("d50_c1" for "d50_c1 [m]")
 * resumes, its rows being the same. */
static int same_columns(const char *a, const char *b) {
  for (;;) {
    size_t na = strcspn(a, ",\n"), nb = strcspn(b, ",\n");
    const char *ua = na && a[na - 1] == ']' ? memchr(a, '[', na) : NULL;
    const char *ub = nb && b[nb - 1] == ']' ? memchr(b, '[', nb) : NULL;
    size_t ka = ua && ua > a + 1 && ua[-1] == ' ' ? (size_t)(ua - a) - 1 : na;
    size_t kb = ub && ub > b + 1 && ub[-1] == ' ' ? (size_t)(ub - b) - 1 : nb;
    if (ka != kb || strncmp(a, b, ka)) return 0;
    a += na;
    b += nb;
    if (*a != *b) return 0;
    if (*a != ',') return 1;
    a++;
    b++;
  }
}

int gs_sweep_journal_read(const char *path, const char *header, const gs_design *d, char **row,
                          size_t *nfinished, gs_error *err) {
  FILE *f = fopen(path, "r");
  if (!f) return gs_error_set(err, GS_EIO, "cannot read '%s': %s", path, strerror(errno));
  char *line = NULL;
  size_t cap = 0, lineno = 0;
  long good_end = 0;
  ssize_t len;
  int rc = GS_OK;
  while (!rc && (len = getline(&line, &cap, f)) > 0) {
    lineno++;
    if (line[len - 1] != '\n') break; /* torn: dropped below */
    if (lineno == 1) {
      if (strcmp(line, header) && !same_columns(line, header))
        rc = gs_error_set(err, GS_EINPUT,
                          "cannot resume: '%s' was written by a sweep with other keys or outputs "
                          "(header %.*s; this sweep's %.*s)",
                          path, (int)len - 1, line, (int)strlen(header) - 1, header);
    } else {
      char *p = line, *end;
      unsigned long r = strtoul(p, &end, 10);
      if (end == p || *end != ',' || r < 1 || r > d->nruns) {
        rc = gs_error_set(err, GS_EINPUT, "cannot resume: '%s' line %zu: run %.*s is not in this sweep (1..%zu)",
                          path, lineno, (int)(end - p), p, d->nruns);
        break;
      }
      p = strchr(end + 1, ','); /* past the status */
      for (size_t k = 0; k < d->nkeys && p && !rc; k++) {
        const char *v = d->values[(r - 1) * d->nkeys + k];
        size_t vl = strlen(v);
        if (strncmp(p + 1, v, vl) || (p[1 + vl] != ',' && p[1 + vl] != '\n'))
          rc = gs_error_set(err, GS_EINPUT,
                            "cannot resume: '%s' line %zu: run %lu has another %s than this "
                            "sweep's %s (a different design or seed)",
                            path, lineno, r, d->keys[k], v);
        p = strchr(p + 1, ',');
      }
      if (!rc && !row[r - 1]) {
        if (!(row[r - 1] = strdup(line))) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
        else ++*nfinished;
      }
    }
    if (!rc) good_end = ftell(f);
  }
  free(line);
  fclose(f);
  if (!rc && truncate(path, good_end))
    rc = gs_error_set(err, GS_EIO, "cannot cut the torn last row of '%s': %s", path, strerror(errno));
  return rc;
}

