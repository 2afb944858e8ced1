/* Measured data for fits and optimisation: the CSV of one batch and the
 * batches file that lists several, each with its own recipe (see
 * gransim/study.h). */
#include "gransim/study.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- one batch's CSV ------------------------------------------------------ */

void gs_fit_data_free(gs_fit_data *d) {
  if (!d) return;
  for (size_t j = 0; d->names && j < d->ncols; j++) free(d->names[j]);
  free(d->names);
  free(d->times);
  free(d->values);
  free(d->lines);
  free(d->path);
  memset(d, 0, sizeof *d);
}

/* Fields of one CSV line (no quoting: the data are numbers and plain names). */
static size_t split_fields(char *line, char **field, size_t max) {
  size_t n = 0;
  line[strcspn(line, "\r\n")] = '\0';
  for (char *p = line; n < max;) {
    field[n++] = p;
    p = strchr(p, ',');
    if (!p) break;
    *p++ = '\0';
  }
  return n;
}

/* A header field without its unit and surrounding blanks: summary.csv
 * writes "d50 [m]", and data taken from it may keep the units. */
static void strip_unit(char *f) {
  size_t n = strlen(f);
  char *b = n && f[n - 1] == ']' ? strstr(f, " [") : NULL;
  if (b) *b = '\0';
  n = strlen(f);
  while (n && (f[n - 1] == ' ' || f[n - 1] == '\t')) f[--n] = '\0';
  size_t lead = strspn(f, " \t");
  memmove(f, f + lead, strlen(f + lead) + 1);
}

static int read_header(gs_fit_data *d, char **field, size_t nf, const char *path, size_t lineno,
                       gs_error *err) {
  for (size_t j = 0; j < nf; j++) strip_unit(field[j]);
  if (nf < 2 || strcmp(field[0], "time"))
    return gs_error_set(err, GS_EINPUT,
                        "%s:%zu: expected a header 'time,NAME,...' (e.g. time,M0,d50_c1)", path,
                        lineno);
  for (size_t j = 1; j < nf; j++) {
    if (!field[j][0])
      return gs_error_set(err, GS_EINPUT, "%s:%zu: column %zu has no name", path, lineno, j + 1);
    for (size_t q = 1; q < j; q++)
      if (!strcmp(field[j], field[q]))
        return gs_error_set(err, GS_EINPUT, "%s:%zu: column %zu '%s' repeats column %zu", path,
                            lineno, j + 1, field[j], q + 1);
  }
  d->header_line = lineno;
  d->ncols = nf - 1;
  d->names = calloc(d->ncols, sizeof *d->names);
  for (size_t j = 0; d->names && j < d->ncols; j++)
    if (!(d->names[j] = strdup(field[j + 1]))) return gs_error_set(err, GS_ENOMEM, "out of memory");
  return d->names ? GS_OK : gs_error_set(err, GS_ENOMEM, "out of memory");
}

static int read_row(gs_fit_data *d, char **field, size_t nf, const char *path, size_t lineno,
                    gs_error *err) {
  if (nf != d->ncols + 1)
    return gs_error_set(err, GS_EINPUT, "%s:%zu: %zu fields, the header has %zu", path, lineno, nf,
                        d->ncols + 1);
  double *t = realloc(d->times, (d->ntimes + 1) * sizeof *t);
  if (t) d->times = t;
  double *v = realloc(d->values, (d->ntimes + 1) * d->ncols * sizeof *v);
  if (v) d->values = v;
  size_t *l = realloc(d->lines, (d->ntimes + 1) * sizeof *l);
  if (l) d->lines = l;
  if (!t || !v || !l) return gs_error_set(err, GS_ENOMEM, "out of memory");
  if (d->ntimes && isinf(d->times[d->ntimes - 1]))
    return gs_error_set(err, GS_EINPUT, "%s:%zu: a row after the time 'end' (line %zu): end is the last",
                        path, lineno, d->lines[d->ntimes - 1]);
  for (size_t j = 0; j <= d->ncols; j++) {
    char *end;
    errno = 0;
    double x = strtod(field[j], &end);
    if (j == 0 && !strcmp(field[j], "end")) /* the run's last output time, whatever it is */
      x = INFINITY, end = field[j] + 3;
    while (end != field[j] && (*end == ' ' || *end == '\t')) end++;
    if (end == field[j] || *end || !(isfinite(x) || (j == 0 && x == INFINITY && !strcmp(field[j], "end"))))
      return gs_error_set(err, GS_EINPUT, "%s:%zu: column %zu (%s) = '%s': expected a finite number",
                          path, lineno, j + 1, j ? d->names[j - 1] : "time", field[j]);
    if (j == 0 && d->ntimes && !(x > d->times[d->ntimes - 1]))
      return gs_error_set(err, GS_EINPUT,
                          "%s:%zu: column 1 (time) = %g: times must increase (line %zu has %g)",
                          path, lineno, x, d->lines[d->ntimes - 1], d->times[d->ntimes - 1]);
    if (j == 0) d->times[d->ntimes] = x;
    else d->values[d->ntimes * d->ncols + j - 1] = x;
  }
  d->lines[d->ntimes++] = lineno;
  return GS_OK;
}

int gs_fit_data_read(const char *path, gs_fit_data *d, gs_error *err) {
  memset(d, 0, sizeof *d);
  FILE *f = fopen(path, "r");
  if (!f) return gs_error_set(err, GS_EIO, "cannot read data file '%s': %s", path, strerror(errno));
  char *line = NULL, *field[256];
  size_t cap = 0, lineno = 0;
  int rc = (d->path = strdup(path)) ? GS_OK : gs_error_set(err, GS_ENOMEM, "out of memory");
  while (!rc && getline(&line, &cap, f) > 0) {
    lineno++;
    if (line[0] == '#' || line[strspn(line, " \t\r\n")] == '\0') continue;
    size_t nf = split_fields(line, field, 256);
    rc = d->names ? read_row(d, field, nf, path, lineno, err)
                  : read_header(d, field, nf, path, lineno, err);
  }
  free(line);
  fclose(f);
  if (!rc && !d->ntimes) rc = gs_error_set(err, GS_EINPUT, "%s: no data rows", path);
  if (rc) gs_fit_data_free(d);
  return rc;
}

/* ---- sieve columns ---------------------------------------------------------- */

int gs_fit_sieve_column(const char *name, double *lo, double *hi, size_t *comp) {
  if (strncmp(name, "sieve_", 6)) return 0;
  char *end;
  *lo = strtod(name + 6, &end);
  if (end == name + 6 || *end != '_') return -1;
  const char *h = end + 1;
  *hi = strtod(h, &end);
  if (end == h) return -1;
  *comp = 0;
  if (*end) {
    char *tail;
    unsigned long j = strncmp(end, "_c", 2) ? 0 : strtoul(end + 2, &tail, 10);
    if (!j || *tail || end[2] < '0' || end[2] > '9') return -1;
    *comp = j;
  }
  if (!(*lo >= 0) || !(*hi > *lo) || isinf(*lo)) return -1;
  *lo *= 1e-6;
  *hi *= 1e-6;
  return 1;
}

/* ---- batches ---------------------------------------------------------------- */

void gs_fit_batches_free(gs_fit_batches *bs) {
  if (!bs) return;
  for (size_t i = 0; bs->batch && i < bs->n; i++) {
    gs_fit_batch *b = &bs->batch[i];
    for (size_t k = 0; b->keys && k < b->nset; k++) free(b->keys[k]);
    for (size_t k = 0; b->values && k < b->nset; k++) free(b->values[k]);
    free(b->keys);
    free(b->values);
    free(b->key_lines);
    free(b->name);
    free(b->where);
    gs_fit_data_free(&b->data);
  }
  free(bs->batch);
  free(bs->sieves);
  free(bs->path);
  memset(bs, 0, sizeof *bs);
}

int gs_fit_batches_single(const char *data_path, gs_fit_batches *bs, gs_error *err) {
  memset(bs, 0, sizeof *bs);
  bs->batch = calloc(1, sizeof *bs->batch);
  if (!bs->batch) return gs_error_set(err, GS_ENOMEM, "out of memory");
  bs->n = 1;
  gs_fit_batch *b = bs->batch;
  int rc = gs_fit_data_read(data_path, &b->data, err);
  if (!rc && (!(b->name = strdup(data_path)) || !(b->where = strdup(data_path))))
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (rc) gs_fit_batches_free(bs);
  return rc;
}

static char *dup_join(const char *dir, const char *name) {
  size_t n = strlen(dir) + strlen(name) + 2;
  char *s = malloc(n);
  if (s) snprintf(s, n, "%s%s%s", name[0] == '/' || !dir[0] ? "" : dir,
                  name[0] == '/' || !dir[0] ? "" : "/", name);
  return s;
}

/* One entry of batches: name, data (relative to the batches file), set. */
static int read_batch(gs_cfg_node *node, const char *dir, gs_fit_batch *b, gs_error *err) {
  const char *name, *data;
  gs_cfg_node *set;
  int rc = gs_cfg_require_kind(node, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_string_req(node, "name", &name, err);
  if (!rc) rc = gs_cfg_string_req(node, "data", &data, err);
  if (rc) return rc;
  set = gs_cfg_get(node, "set");
  if ((rc = gs_cfg_check_unused(node, err))) return rc;
  char where[600];
  snprintf(where, sizeof where, "%s:%d", gs_cfg_file(node), gs_cfg_line(node));
  if (!(b->name = strdup(name)) || !(b->where = strdup(where)))
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  if (set) {
    if ((rc = gs_cfg_require_kind(set, GS_CFG_MAP, err))) return rc;
    b->nset = gs_cfg_size(set);
    b->keys = calloc(b->nset ? b->nset : 1, sizeof *b->keys);
    b->values = calloc(b->nset ? b->nset : 1, sizeof *b->values);
    b->key_lines = calloc(b->nset ? b->nset : 1, sizeof *b->key_lines);
    if (!b->keys || !b->values || !b->key_lines) return gs_error_set(err, GS_ENOMEM, "out of memory");
    for (size_t k = 0; k < b->nset; k++) {
      gs_cfg_node *v = gs_cfg_value_at(set, k);
      const char *text = gs_cfg_scalar(v);
      if (!text) return gs_cfg_fail(v, err, "expected a single value for the dotted key");
      b->key_lines[k] = gs_cfg_line(v);
      if (!(b->keys[k] = strdup(gs_cfg_key_at(set, k))) || !(b->values[k] = strdup(text)))
        return gs_error_set(err, GS_ENOMEM, "out of memory");
    }
  }
  char *path = dup_join(dir, data);
  if (!path) return gs_error_set(err, GS_ENOMEM, "out of memory");
  rc = gs_fit_data_read(path, &b->data, err);
  free(path);
  if (rc) gs_error_prefix(err, "%s: batch '%s': ", where, b->name);
  return rc;
}

/* sieves: increasing diameters >= 0 [m], the last may be .inf (the
 * oversize class of a sieve analysis). */
static int read_sieves(gs_cfg_node *root, gs_fit_batches *bs, gs_error *err) {
  gs_cfg_node *node = gs_cfg_get(root, "sieves");
  if (!node) return GS_OK;
  int rc = gs_cfg_require_kind(node, GS_CFG_SEQ, err);
  const size_t n = gs_cfg_size(node);
  if (!rc && n < 2) rc = gs_cfg_fail(node, err, "expected at least 2 sieve diameters [m]");
  if (!rc && !(bs->sieves = malloc(n * sizeof *bs->sieves)))
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t k = 0; k < n && !rc; k++) {
    gs_cfg_node *item = gs_cfg_item(node, k);
    const char *text = gs_cfg_scalar(item);
    if (k == n - 1 && text && (!strcmp(text, ".inf") || !strcmp(text, "inf")))
      bs->sieves[k] = INFINITY;
    else if ((rc = gs_cfg_node_double(item, &bs->sieves[k], err)))
      break;
    if (!(bs->sieves[k] >= 0) || (k && !(bs->sieves[k] > bs->sieves[k - 1])))
      rc = gs_cfg_fail(item, err, "expected increasing diameters >= 0 [m], the last may be .inf");
  }
  if (rc) return rc;
  bs->nsieves = n;
  bs->sieves_line = gs_cfg_line(node);
  return GS_OK;
}

int gs_fit_batches_read(const char *path, gs_fit_batches *bs, gs_error *err) {
  memset(bs, 0, sizeof *bs);
  gs_cfg *cfg = gs_cfg_load_file(path, err);
  if (!cfg) return err->code;
  gs_cfg_node *root = gs_cfg_root(cfg), *list = NULL;
  int rc = root ? gs_cfg_require_kind(root, GS_CFG_MAP, err)
                : gs_error_set(err, GS_EINPUT, "%s: empty file: expected 'batches:'", path);
  if (!rc) rc = read_sieves(root, bs, err);
  if (!rc) rc = gs_cfg_seq_req(root, "batches", &list, err);
  if (!rc) rc = gs_cfg_check_unused(root, err);
  if (!rc && !gs_cfg_size(list)) rc = gs_cfg_fail(list, err, "expected at least one batch");
  if (!rc && !(bs->batch = calloc(gs_cfg_size(list), sizeof *bs->batch)))
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t i = 0; !rc && i < gs_cfg_size(list); i++) {
    bs->n++;
    rc = read_batch(gs_cfg_item(list, i), gs_cfg_dir(cfg), &bs->batch[i], err);
    for (size_t q = 0; !rc && q < i; q++)
      if (!strcmp(bs->batch[q].name, bs->batch[i].name))
        rc = gs_error_set(err, GS_EINPUT, "%s: batch name '%s' repeats the batch at %s",
                          bs->batch[i].where, bs->batch[i].name, bs->batch[q].where);
  }
  if (!rc && !(bs->path = strdup(path))) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  gs_cfg_free(cfg);
  if (rc) gs_fit_batches_free(bs);
  return rc;
}
