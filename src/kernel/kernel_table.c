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
 * outside the classes take the nearest class; a warning says how many.
 * A particle off the pivots (stochastic solver) takes the class of its own
 * size measure, the same way; the majorant is the constant beta0 max C of
 * its compartment, a true bound as every pair's beta is an entry of C.
 *
 * `times` composes the table with another registered kernel:
 * beta = beta0 C[class][class'] * beta_times(a, b), e.g. the Madec
 * liquid-content kernel, which is De et al.'s (2025) eq. 5 (f_c from the
 * DEM times Madec's beta0 (V + V') [...]).  The other kernel is created and
 * evaluated by its own type, so its formula lives in one place; the
 * majorant is its form with the coefficient times beta0 max C. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/kernel.h"
#include "kernel/class_table.h"
#include "kernel/size_measure.h"

typedef struct {
  double *beta0;   /* per compartment */
  size_t nclass, ncomp, ncells;
  int per_comp;    /* one file per compartment, or beta0 differs between compartments */
  double *table;   /* ncomp * nclass * nclass */
  size_t *cls;     /* per cell: class index */
  double *edges;   /* nclass + 1 class edges (of the first file) */
  int diameter, dim;
  unsigned axes;   /* axes of the size measure */
  double *bound;   /* per compartment: beta0 max C */
  gs_kernel times; /* the kernel the table multiplies (type NULL: none) */
  double *coef;    /* per compartment: the composed majorant's coefficient */
} table_kernel;

static void table_free(void *self) {
  table_kernel *k = self;
  free(k->beta0);
  free(k->edges);
  free(k->bound);
  free(k->table);
  free(k->cls);
  free(k->coef);
  gs_kernel_free(&k->times);
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
  int differ = 0;
  rc = gs_kernel_beta0(node, 0, 1.0, g, &k->beta0, &differ, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "measure", measures, 0, &measure, err);
  if (!rc && !(size = gs_size_measure_mask(node, g, &k->axes, err))) rc = err->code;
  gs_cfg_node *files = rc ? NULL : gs_cfg_get(node, "file");
  if (!rc && !files) rc = gs_cfg_missing(node, "file", "(the kernel table)", err);
  size_t nfiles = files && gs_cfg_kind_of(files) == GS_CFG_SEQ ? gs_cfg_size(files) : 1;
  if (!rc && nfiles != 1 && nfiles != g->ncomp)
    rc = gs_cfg_fail(files, err, "expected one file, or one per compartment (%zu)", g->ncomp);
  k->ncomp = g->ncomp;
  k->ncells = g->ncells;
  k->per_comp = nfiles > 1 || differ;
  k->diameter = measure == 1;
  k->dim = g->dim;
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
      k->edges = gs_malloc((tf.n + 1) * sizeof(double), err);
      if (!k->table || !k->cls || !k->edges) rc = GS_ENOMEM;
      else memcpy(k->edges, tf.edges, (tf.n + 1) * sizeof(double));
    } else if (tf.n != k->nclass) {
      rc = gs_cfg_fail(fn, err, "has %zu classes but the first table has %zu", tf.n, k->nclass);
    }
    for (size_t c = 0; !rc && c < (nfiles == 1 ? g->ncomp : 1); c++) {
      size_t comp = nfiles == 1 ? c : f;
      memcpy(k->table + comp * tf.n * tf.n, tf.c, tf.n * tf.n * sizeof(double));
    }
    gs_class_table_free(&tf);
  }
  gs_cfg_node *times = rc ? NULL : gs_cfg_get(node, "times");
  if (times) {
    rc = gs_cfg_require_kind(times, GS_CFG_MAP, err);
    if (!rc) rc = gs_kernel_create(times, g, dir, &k->times, err);
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  free(size);
  if (!rc && !(k->bound = gs_malloc(g->ncomp * sizeof(double), err))) rc = GS_ENOMEM;
  if (!rc && k->times.type && !(k->coef = gs_malloc(g->ncomp * sizeof(double), err))) rc = GS_ENOMEM;
  if (rc) { table_free(k); return rc; }
  gs_kernel_form inner = {.kind = GS_KERNEL_FORM_CONSTANT};
  if (k->times.type) k->times.type->form(k->times.self, &inner);
  for (size_t z = 0; z < g->ncomp; z++) {
    const double *c = k->table + z * k->nclass * k->nclass;
    double top = 0;
    for (size_t i = 0; i < k->nclass * k->nclass; i++) top = fmax(top, c[i]);
    k->bound[z] = k->beta0[z] * top;
    if (k->coef) k->coef[z] = k->bound[z] * inner.coef[z];
  }
  *self = k;
  return GS_OK;
}

static void table_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1, double *out) {
  const table_kernel *k = self;
  const double *row = k->table + (comp * k->nclass + k->cls[a]) * k->nclass;
  const double beta0 = k->beta0[comp]; /* hoisted: out might alias it as far as the compiler knows */
  for (size_t b = b0; b < b1; b++) out[b - b0] = beta0 * row[k->cls[b]];
  if (!k->times.type) return;
  double f[256]; /* the other kernel's row in pieces on the stack: rows may be filled by several threads */
  for (size_t s = b0; s < b1; s += 256) {
    const size_t e = s + 256 < b1 ? s + 256 : b1;
    k->times.type->row(k->times.self, comp, a, s, e, f);
    for (size_t b = s; b < e; b++) out[b - b0] *= f[b - s];
  }
}

/* Class of a point, as gs_class_table_assign places cells (nearest class outside). */
static size_t table_class(const table_kernel *k, const double *x) {
  double v = gs_size_of(k->axes, k->dim, x), s = k->diameter ? gs_diameter(v) : v;
  size_t i = 0;
  while (i + 1 < k->nclass && s >= k->edges[i + 1]) i++;
  return i;
}

static double table_at(const void *self, size_t comp, const double *x, const double *y) {
  const table_kernel *k = self;
  const double c = k->beta0[comp] * k->table[(comp * k->nclass + table_class(k, x)) * k->nclass + table_class(k, y)];
  return k->times.type ? c * k->times.type->at(k->times.self, comp, x, y) : c;
}

static void table_form(const void *self, gs_kernel_form *out) {
  const table_kernel *k = self;
  if (k->times.type) { /* beta0 C <= bound: the other kernel's majorant times it */
    k->times.type->form(k->times.self, out);
    out->coef = k->coef;
    out->exact = 0;
    return;
  }
  *out = (gs_kernel_form){.kind = GS_KERNEL_FORM_CONSTANT, .coef = k->bound, .axes = 0, .exact = 0};
}

static int table_per_compartment(const void *self) {
  const table_kernel *k = self;
  const gs_kernel *t = &k->times;
  return k->per_comp || (t->type && t->type->per_compartment && t->type->per_compartment(t->self));
}

const gs_kernel_type gs_kernel_table = {
    .name = "table",
    .summary = "beta0 * C[class][class'] from a CSV file (DEM collision frequencies), times another kernel (times)",
    .create = table_create,
    .row = table_row,
    .free = table_free,
    .per_compartment = table_per_compartment,
    .at = table_at,
    .form = table_form,
};
