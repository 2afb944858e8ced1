/* Reader of LAMMPS/LIGGGHTS text dumps (see dump.h). */
#include "demdata/dump.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DUMP_MAX_ROWS 100000000L /* refuse absurd headers instead of allocating them */

void gs_dump_free(gs_dump *d) {
  if (!d) return;
  for (size_t k = 0; d->names && k < d->ncols; k++) free(d->names[k]);
  free(d->names);
  free(d->v);
  free(d->path);
  memset(d, 0, sizeof *d);
}

long gs_dump_col(const gs_dump *d, const char *name) {
  for (size_t k = 0; k < d->ncols; k++)
    if (!strcmp(d->names[k], name)) return (long)k;
  return -1;
}

long gs_dump_col_index(const gs_dump *d, int k) {
  char suffix[32];
  int ls = snprintf(suffix, sizeof suffix, "[%d]", k);
  for (size_t c = 0; c < d->ncols; c++) {
    size_t ln = strlen(d->names[c]);
    if (ln > (size_t)ls && !strcmp(d->names[c] + ln - (size_t)ls, suffix)) return (long)c;
  }
  return -1;
}

static char *trim(char *s) {
  while (*s == ' ' || *s == '\t') s++;
  size_t n = strlen(s);
  while (n && (s[n - 1] == '\n' || s[n - 1] == '\r' || s[n - 1] == ' ' || s[n - 1] == '\t')) s[--n] = 0;
  return s;
}

/* A whole-line integer >= 0. */
static int parse_count(const char *s, long *out) {
  char *end;
  errno = 0;
  long v = strtol(s, &end, 10);
  while (*end == ' ' || *end == '\t') end++;
  if (end == s || *end || errno || v < 0) return -1;
  *out = v;
  return 0;
}

enum { S_ITEM, S_STEP, S_COUNT, S_BOX, S_SKIP, S_ROWS, S_DONE };

static int set_names(gs_dump *d, char *list, gs_error *err) {
  size_t cap = 16;
  d->names = gs_malloc(cap * sizeof(char *), err);
  if (!d->names) return GS_ENOMEM;
  for (char *tok = strtok(list, " \t"); tok; tok = strtok(NULL, " \t")) {
    if (d->ncols == cap) {
      char **nn = realloc(d->names, 2 * cap * sizeof(char *));
      if (!nn) return gs_error_set(err, GS_ENOMEM, "out of memory");
      d->names = nn;
      cap *= 2;
    }
    if (!(d->names[d->ncols] = strdup(tok))) return gs_error_set(err, GS_ENOMEM, "out of memory");
    d->ncols++;
  }
  return GS_OK;
}

int gs_dump_read(const char *path, gs_dump *d, gs_error *err) {
  memset(d, 0, sizeof *d);
  d->step = -1;
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot open DEM dump: %s", path, strerror(errno));
  if (!(d->path = strdup(path))) {
    fclose(fp);
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  }
  char *buf = NULL;
  size_t cap = 0;
  long lineno = 0, n = -1, boxleft = 0;
  size_t row = 0;
  int state = S_ITEM, rc = GS_OK;
  while (!rc && getline(&buf, &cap, fp) != -1) {
    lineno++;
    char *s = trim(buf);
    if (state == S_SKIP && !strncmp(s, "ITEM:", 5)) state = S_ITEM;
    switch (state) {
    case S_SKIP:
      break;
    case S_DONE:
      if (!*s) break;
      if (!strncmp(s, "ITEM: TIMESTEP", 14))
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: a second snapshot; one snapshot per file is expected "
                          "(LIGGGHTS: dump with '*' in the file name)", path, lineno);
      else
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: unexpected text after the %ld rows announced by "
                          "NUMBER OF ATOMS/ENTRIES: '%.40s'", path, lineno, n, s);
      break;
    case S_ITEM: {
      if (!*s) break;
      if (strncmp(s, "ITEM:", 5)) {
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: expected an 'ITEM: ...' line, found '%.40s'", path, lineno, s);
        break;
      }
      char *item = trim(s + 5);
      if (!strcmp(item, "TIMESTEP")) state = S_STEP;
      else if (!strcmp(item, "NUMBER OF ATOMS") || !strcmp(item, "NUMBER OF ENTRIES")) state = S_COUNT;
      else if (!strncmp(item, "BOX BOUNDS", 10)) { state = S_BOX; boxleft = 3; }
      else if (!strncmp(item, "ATOMS", 5) || !strncmp(item, "ENTRIES", 7)) {
        int atoms = item[0] == 'A';
        if (n < 0) {
          rc = gs_error_set(err, GS_EINPUT, "%s:%ld: ITEM: %s before ITEM: NUMBER OF %s", path, lineno,
                            atoms ? "ATOMS" : "ENTRIES", atoms ? "ATOMS" : "ENTRIES");
          break;
        }
        if ((rc = set_names(d, item + (atoms ? 5 : 7), err))) break;
        if (!d->ncols) {
          rc = gs_error_set(err, GS_EINPUT, "%s:%ld: ITEM: %s without column names", path, lineno, item);
          break;
        }
        d->nrows = (size_t)n;
        d->first_row_line = lineno + 1;
        if (!(d->v = gs_malloc((d->nrows ? d->nrows : 1) * d->ncols * sizeof(double), err))) { rc = GS_ENOMEM; break; }
        state = n ? S_ROWS : S_DONE;
      } else state = S_SKIP; /* UNITS, TIME, ...: not needed */
      break;
    }
    case S_STEP:
      if (parse_count(s, &d->step))
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: expected the time step (an integer >= 0) after "
                          "ITEM: TIMESTEP, found '%.40s'", path, lineno, s);
      state = S_ITEM;
      break;
    case S_COUNT:
      if (parse_count(s, &n) || n > DUMP_MAX_ROWS)
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: expected the number of rows (an integer 0..%ld) after "
                          "ITEM: NUMBER OF ATOMS/ENTRIES, found '%.40s'", path, lineno, DUMP_MAX_ROWS, s);
      state = S_ITEM;
      break;
    case S_BOX:
      if (--boxleft == 0) state = S_ITEM;
      break;
    case S_ROWS: {
      double *out = d->v + row * d->ncols;
      size_t k = 0;
      char *p = s;
      while (!rc) {
        while (*p == ' ' || *p == '\t') p++;
        if (!*p) break;
        char *end;
        errno = 0;
        double x = strtod(p, &end);
        if (end == p || (*end && *end != ' ' && *end != '\t') || !isfinite(x)) {
          char *tok_end = p + strcspn(p, " \t");
          *tok_end = 0;
          rc = gs_error_set(err, GS_EINPUT, "%s:%ld: row %zu: '%.40s' in column '%s' is not a finite number",
                            path, lineno, row + 1, p, k < d->ncols ? d->names[k] : "(extra)");
          break;
        }
        if (k < d->ncols) out[k] = x;
        k++;
        p = end;
      }
      if (rc) break;
      if (k != d->ncols) {
        rc = gs_error_set(err, GS_EINPUT, "%s:%ld: row %zu has %zu values, expected %zu (one per column "
                          "of the ITEM line at line %ld)%s", path, lineno, row + 1, k, d->ncols,
                          d->first_row_line - 1, k ? "" : "; rows must be consecutive lines");
        break;
      }
      if (++row == d->nrows) state = S_DONE;
      break;
    }
    }
  }
  free(buf);
  if (!rc && ferror(fp)) rc = gs_error_set(err, GS_EIO, "%s: read error: %s", path, strerror(errno));
  fclose(fp);
  if (!rc && state == S_ROWS)
    rc = gs_error_set(err, GS_EINPUT, "%s:%ld: file ends after %zu of the %zu rows announced by NUMBER OF "
                      "ATOMS/ENTRIES (truncated file?)", path, lineno, row, d->nrows);
  else if (!rc && state != S_DONE)
    rc = gs_error_set(err, GS_EINPUT, "%s:%ld: file ends before its ITEM: ATOMS/ENTRIES rows (expected "
                      "TIMESTEP, NUMBER OF ATOMS|ENTRIES, BOX BOUNDS and ATOMS|ENTRIES sections)", path, lineno);
  else if (!rc && d->step < 0)
    rc = gs_error_set(err, GS_EINPUT, "%s: no ITEM: TIMESTEP section", path);
  if (rc) gs_dump_free(d);
  return rc;
}
