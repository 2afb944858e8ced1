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
#include "kernel/class_table.h"
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

static int table_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                        gs_error *err) {
  static const char *const measures[] = {"volume", "diameter", NULL};
  table_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  int measure = 0, rc;
  double *size = NULL;
  gs_class_table tf = {0};
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
    rc = gs_class_table_read(path, 0, &tf, err);
    if (rc) { gs_error_prefix(err, "%s:%d: %s: ", gs_cfg_file(fn), gs_cfg_line(fn), gs_cfg_path(fn)); break; }
    if (!k->table) {
      k->nclass = tf.n;
      k->table = gs_malloc(g->ncomp * tf.n * tf.n * sizeof(double), err);
      k->cls = gs_class_table_assign(&tf, size, g->ncells, measure == 1, path, err);
      if (!k->table || !k->cls) rc = GS_ENOMEM;
    } else if (tf.n != k->nclass) {
      rc = gs_cfg_fail(fn, err, "has %zu classes but the first table has %zu", tf.n, k->nclass);
    }
    for (size_t c = 0; !rc && c < (nfiles == 1 ? g->ncomp : 1); c++) {
      size_t comp = nfiles == 1 ? c : f;
      memcpy(k->table + comp * tf.n * tf.n, tf.c, tf.n * tf.n * sizeof(double));
    }
    gs_class_table_free(&tf);
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

const gs_kernel_type gs_kernel_table = {
    .name = "table",
    .summary = "beta0 * C[class][class'] from a CSV file (DEM collision frequencies)",
    .create = table_create,
    .row = table_row,
    .free = table_free,
    .per_compartment = table_per_compartment,
};
