/* Tabulated kernel: beta = beta0 * C[class(a)][class(b)], with C read from a
 * CSV file.  This is the entry point for DEM-derived collision frequencies.
 *
 * File format (text, '#' starts a comment line, blank lines ignored):
 *   edges, e0, e1, ..., en     class edges of the size measure, increasing
 *   C00, C01, ..., C0(n-1)     n rows of n values, symmetric and >= 0
 *   ...
 * Keys: file (one file, or a list with one file per compartment), beta0
 * (default 1), measure: volume | diameter (what the edges measure; default
 * volume), axes (which grid axes make the volume; default all).  Grid cells
 * outside the classes take the nearest class; a warning says how many. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/kernel.h"
#include "kernel/size_measure.h"

typedef struct {
  double beta0;
  size_t nclass, ncomp, ncells;
  int per_comp;    /* one file per compartment */
  double *table;   /* ncomp * nclass * nclass */
  size_t *cls;     /* per cell: class index */
} table_kernel;

static void table_free(void *self) {
  table_kernel *k = self;
  free(k->table);
  free(k->cls);
  free(k);
}

/* Split a CSV line into numbers; returns count or -1 (bad token at *bad). */
static long parse_numbers(char *line, double *out, long max, char **bad) {
  long n = 0;
  for (char *tok = strtok(line, ", \t\r\n"); tok; tok = strtok(NULL, ", \t\r\n")) {
    char *end;
    errno = 0;
    double v = strtod(tok, &end);
    if (*end || errno || !isfinite(v)) {
      *bad = tok;
      return -1;
    }
    if (n < max) out[n] = v;
    n++;
  }
  return n;
}

typedef struct {
  double *edges;
  size_t n;
  double *c;
} table_file;

static int read_table(const char *path, table_file *tf, gs_error *err) {
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot open kernel table: %s", path, strerror(errno));
  char line[65536];
  int lineno = 0, rc = GS_OK;
  size_t row = 0, cap = 4096;
  double *vals = gs_malloc(cap * sizeof(double), err);
  memset(tf, 0, sizeof *tf);
  while (!rc && vals && fgets(line, sizeof line, fp)) {
    lineno++;
    char *s = line + strspn(line, " \t");
    if (*s == '#' || *s == '\n' || *s == '\r' || !*s) continue;
    char *bad = NULL;
    if (!tf->edges) {
      if (strncmp(s, "edges", 5)) {
        rc = gs_error_set(err, GS_EINPUT, "%s:%d: expected a first line 'edges, e0, e1, ...'", path, lineno);
        break;
      }
      long n = parse_numbers(s + 5, vals, (long)cap, &bad);
      if (n < 2 || n > (long)cap) {
        rc = gs_error_set(err, GS_EINPUT, "%s:%d: edges: %s", path, lineno,
                          bad ? "value is not a number" : "need 2 or more edges");
        break;
      }
      tf->n = (size_t)n - 1;
      tf->edges = gs_malloc((size_t)n * sizeof(double), err);
      tf->c = gs_malloc(tf->n * tf->n * sizeof(double), err);
      if (!tf->edges || !tf->c) { rc = GS_ENOMEM; break; }
      memcpy(tf->edges, vals, (size_t)n * sizeof(double));
      for (size_t i = 1; i <= tf->n; i++)
        if (!(tf->edges[i] > tf->edges[i - 1]) || tf->edges[i - 1] < 0)
          rc = gs_error_set(err, GS_EINPUT, "%s:%d: edges must be >= 0 and increasing (edge %zu = %g)",
                            path, lineno, i, tf->edges[i]);
      continue;
    }
    long n = parse_numbers(s, vals, (long)cap, &bad);
    if (n < 0) rc = gs_error_set(err, GS_EINPUT, "%s:%d: '%s' is not a number", path, lineno, bad);
    else if (row >= tf->n) rc = gs_error_set(err, GS_EINPUT, "%s:%d: more than %zu rows (one per class)", path, lineno, tf->n);
    else if ((size_t)n != tf->n) rc = gs_error_set(err, GS_EINPUT, "%s:%d: row has %ld values, expected %zu (one per class)", path, lineno, n, tf->n);
    for (size_t j = 0; !rc && j < tf->n; j++) {
      if (vals[j] < 0) rc = gs_error_set(err, GS_EINPUT, "%s:%d: value %g in column %zu is negative", path, lineno, vals[j], j);
      tf->c[row * tf->n + j] = vals[j];
    }
    row++;
  }
  fclose(fp);
  free(vals);
  if (!rc && !tf->edges) rc = gs_error_set(err, GS_EINPUT, "%s: no 'edges' line", path);
  if (!rc && row != tf->n) rc = gs_error_set(err, GS_EINPUT, "%s: %zu rows, expected %zu (one per class)", path, row, tf->n);
  for (size_t i = 0; !rc && i < tf->n; i++)
    for (size_t j = 0; !rc && j < i; j++) {
      double a = tf->c[i * tf->n + j], b = tf->c[j * tf->n + i];
      if (fabs(a - b) > 1e-9 * fmax(fabs(a), fabs(b)))
        rc = gs_error_set(err, GS_EINPUT, "%s: table is not symmetric: C[%zu][%zu] = %g but C[%zu][%zu] = %g", path, i, j, a, j, i, b);
    }
  if (rc) { free(tf->edges); free(tf->c); tf->edges = tf->c = NULL; }
  return rc;
}

static int table_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                        gs_error *err) {
  static const char *const measures[] = {"volume", "diameter", NULL};
  table_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  int measure = 0, rc;
  double *size = NULL;
  table_file tf = {0};
  rc = gs_cfg_double_range(node, "beta0", 0, 1.0, 0, 0, HUGE_VAL, 0, &k->beta0, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "measure", measures, 0, &measure, err);
  if (!rc && !(size = gs_size_measure(node, g, err))) rc = err->code;
  gs_cfg_node *files = rc ? NULL : gs_cfg_get(node, "file");
  if (!rc && !files) rc = gs_cfg_fail(node, err, "missing key 'file' (the kernel table)");
  size_t nfiles = files && gs_cfg_kind_of(files) == GS_CFG_SEQ ? gs_cfg_size(files) : 1;
  if (!rc && nfiles != 1 && nfiles != g->ncomp)
    rc = gs_cfg_fail(files, err, "expected one file, or one per compartment (%zu)", g->ncomp);
  k->ncomp = g->ncomp;
  k->ncells = g->ncells;
  k->per_comp = nfiles > 1;
  for (size_t f = 0; !rc && f < nfiles; f++) {
    gs_cfg_node *fn = gs_cfg_kind_of(files) == GS_CFG_SEQ ? gs_cfg_item(files, f) : files;
    const char *name = gs_cfg_scalar(fn);
    if (!name) { rc = gs_cfg_fail(fn, err, "expected a file name"); break; }
    char path[4096];
    snprintf(path, sizeof path, "%s%s%s", name[0] == '/' ? "" : dir, name[0] == '/' ? "" : "/", name);
    rc = read_table(path, &tf, err);
    if (rc) { gs_error_prefix(err, "%s:%d: %s: ", gs_cfg_file(fn), gs_cfg_line(fn), gs_cfg_path(fn)); break; }
    if (!k->table) {
      k->nclass = tf.n;
      k->table = gs_malloc(g->ncomp * tf.n * tf.n * sizeof(double), err);
      k->cls = gs_malloc(g->ncells * sizeof(size_t), err);
      if (!k->table || !k->cls) rc = GS_ENOMEM;
      size_t outside = 0;
      for (size_t c = 0; !rc && c < g->ncells; c++) {
        double s = measure == 1 ? gs_diameter(size[c]) : size[c];
        size_t i = 0;
        while (i + 1 < tf.n && s >= tf.edges[i + 1]) i++;
        if (s < tf.edges[0] || s > tf.edges[tf.n]) outside++;
        k->cls[c] = i;
      }
      if (outside)
        fprintf(stderr, "gransim: warning: %s: %zu of %zu grid cells lie outside the table's classes "
                "[%g, %g] and use the nearest class\n", path, outside, g->ncells, tf.edges[0], tf.edges[tf.n]);
    } else if (tf.n != k->nclass) {
      rc = gs_cfg_fail(fn, err, "has %zu classes but the first table has %zu", tf.n, k->nclass);
    }
    for (size_t c = 0; !rc && c < (nfiles == 1 ? g->ncomp : 1); c++) {
      size_t comp = nfiles == 1 ? c : f;
      memcpy(k->table + comp * tf.n * tf.n, tf.c, tf.n * tf.n * sizeof(double));
    }
    free(tf.edges);
    free(tf.c);
    tf.edges = tf.c = NULL;
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  free(size);
  if (rc) { table_free(k); return rc; }
  *self = k;
  return GS_OK;
}

static void table_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1, double *out) {
  const table_kernel *k = self;
  const double *row = k->table + (comp * k->nclass + k->cls[a]) * k->nclass;
  for (size_t b = b0; b < b1; b++) out[b - b0] = k->beta0 * row[k->cls[b]];
}

static int table_per_compartment(const void *self) {
  return ((const table_kernel *)self)->per_comp;
}

const gs_kernel_type gs_kernel_table = {"table", "beta0 * C[class][class'] from a CSV file (DEM collision frequencies)",
                                        table_create, table_row, table_free, table_per_compartment};
