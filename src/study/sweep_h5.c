/* DIR/sweep.h5 (see sweep_h5.h): one dataset per column, one entry per
 * finished run in run order:
 *   /run (float64, from 1: exact), /status ("ok" | "error"), /error (message or "")
 *   /params/<key>   float64 when every value is a number, else strings
 *   /outputs/<name> float64 (nan for failed runs)
 * each with the attributes `units` (the column's in sweep.csv; "" for text)
 * and `dimensions` ("run"). */
#include "study/sweep_h5.h"

#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "output/h5_setup.h"
#include "output/units.h"
#include "study/study_internal.h"

/* Splits a journal line in place: fields[0..nplain) at commas, then the rest
 * (the quoted error) unquoted into *error. */
static void split_row(char *line, char **fields, size_t nplain, char **error) {
  char *p = line;
  for (size_t i = 0; i < nplain; i++) {
    fields[i] = p;
    p += strcspn(p, ",\n");
    if (*p) *p++ = '\0';
  }
  *error = p;
  p[strcspn(p, "\n")] = '\0';
  if (*p == '"') { /* "..." with "" for a quote */
    char *w = p;
    for (char *r = p + 1; *r; r++) {
      if (*r == '"' && r[1] == '"') r++;
      else if (*r == '"') break;
      *w++ = *r;
    }
    *w = '\0';
  }
}

static int write_doubles(hid_t loc, const char *name, const double *v, hsize_t n) {
  hid_t space = H5Screate_simple(1, &n, NULL);
  hid_t ds = H5Dcreate2(loc, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  int bad = ds < 0 || H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0;
  if (ds >= 0) H5Dclose(ds);
  H5Sclose(space);
  return bad;
}

static int write_strings(hid_t loc, const char *name, const char **v, hsize_t n) {
  hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  hid_t space = H5Screate_simple(1, &n, NULL);
  hid_t ds = H5Dcreate2(loc, name, type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  int bad = ds < 0 || H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v) < 0;
  if (ds >= 0) H5Dclose(ds);
  H5Sclose(space);
  H5Tclose(type);
  return bad;
}

int gs_sweep_write_h5(const char *dir, const gs_design *d, const gs_study_outputs *o,
                      char *const *rows, gs_error *err) {
  const size_t nplain = 2 + d->nkeys + o->ncol, nk = d->nkeys;
  size_t n = 0;
  for (size_t r = 0; r < d->nruns; r++) n += rows[r] != NULL;
  char **copy = calloc(n ? n : 1, sizeof *copy), **fields = calloc((n ? n : 1) * nplain, sizeof *fields);
  const char **errors = calloc(n ? n : 1, sizeof *errors), **text = calloc(n ? n : 1, sizeof *text);
  double *num = calloc(n ? n : 1, sizeof *num);
  if (!copy || !fields || !errors || !text || !num) {
    free(copy), free(fields), free(errors), free(text), free(num);
    return gs_error_set(err, GS_ENOMEM, "out of memory writing sweep.h5");
  }
  for (size_t r = 0, i = 0; r < d->nruns; r++)
    if (rows[r] && (copy[i] = strdup(rows[r]))) {
      char *e;
      split_row(copy[i], fields + i * nplain, nplain, &e);
      errors[i++] = e;
    }
  char path[4096], tmp[4096];
  snprintf(path, sizeof path, "%s/sweep.h5", dir);
  snprintf(tmp, sizeof tmp, "%s/.sweep.h5.partial", dir);
  gs_h5_setup();
  hid_t f = H5Fcreate(tmp, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  int bad = f < 0;
  hid_t gp = bad ? -1 : H5Gcreate2(f, "params", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  hid_t go = bad ? -1 : H5Gcreate2(f, "outputs", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  bad |= gp < 0 || go < 0;
  for (size_t c = 0; c < nplain && !bad; c++) {
    int numeric = c != 1;
    for (size_t i = 0; i < n; i++) {
      char *end;
      text[i] = fields[i * nplain + c];
      num[i] = strtod(text[i], &end);
      numeric &= end != text[i] && !*end;
    }
    if (c == 0) bad |= write_doubles(f, "run", num, n) || gs_h5_describe(f, "run", "1", "run") < 0; /* run numbers are exact in float64 */
    else if (c == 1) bad |= write_strings(f, "status", text, n) || gs_h5_describe(f, "status", "", "run") < 0;
    else if (c < 2 + nk) {
      const char *key = d->keys[c - 2];
      bad |= numeric ? write_doubles(gp, key, num, n) : write_strings(gp, key, text, n);
      bad |= !bad && gs_h5_describe(gp, key, numeric ? gs_study_key_unit(key) : "", "run") < 0;
    } else {
      const size_t i = c - 2 - nk;
      bad |= write_doubles(go, o->names[i], num, n) || gs_h5_describe(go, o->names[i], o->units[i], "run") < 0;
    }
  }
  if (!bad) bad |= write_strings(f, "error", errors, n) || gs_h5_describe(f, "error", "", "run") < 0;
  if (gp >= 0) H5Gclose(gp);
  if (go >= 0) H5Gclose(go);
  char cause[256] = "";
  if (bad) gs_h5_cause(cause, sizeof cause);
  if (f >= 0 && H5Fclose(f) < 0) bad = 1;
  if (!bad && rename(tmp, path)) bad = 1;
  if (bad) remove(tmp);
  for (size_t i = 0; i < n; i++) free(copy[i]);
  free(copy), free(fields), free(errors), free(text), free(num);
  return bad ? gs_error_set(err, GS_EIO, "cannot write '%s'%s%s", path, cause[0] ? ": " : "", cause)
             : GS_OK;
}
