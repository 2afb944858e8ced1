/* Tables over size classes, shared by the tabulated kernel and the DEM
 * impact selection function (see class_table.h). */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/grid.h"
#include "gransim/kernel.h"
#include "kernel/class_table.h"

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

int gs_class_table_read(const char *path, size_t rows, gs_class_table *tf, gs_error *err) {
  FILE *fp = fopen(path, "r");
  if (!fp) return gs_error_set(err, GS_EIO, "%s: cannot open %s: %s", path, rows ? "the table" : "kernel table", strerror(errno));
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
      tf->rows = rows ? rows : tf->n;
      tf->edges = gs_malloc((size_t)n * sizeof(double), err);
      tf->c = gs_malloc(tf->rows * tf->n * sizeof(double), err);
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
    else if (row >= tf->rows) rc = gs_error_set(err, GS_EINPUT, "%s:%d: more than %zu rows", path, lineno, tf->rows);
    else if ((size_t)n != tf->n) rc = gs_error_set(err, GS_EINPUT, "%s:%d: row has %ld values, expected %zu (one per class)", path, lineno, n, tf->n);
    for (size_t j = 0; !rc && j < tf->n; j++) {
      if (!rows && vals[j] < 0) rc = gs_error_set(err, GS_EINPUT, "%s:%d: value %g in column %zu is negative", path, lineno, vals[j], j);
      tf->c[row * tf->n + j] = vals[j];
    }
    row++;
  }
  fclose(fp);
  free(vals);
  if (!rc && !tf->edges) rc = gs_error_set(err, GS_EINPUT, "%s: no 'edges' line", path);
  if (!rc && row != tf->rows) rc = gs_error_set(err, GS_EINPUT, "%s: %zu rows, expected %zu", path, row, tf->rows);
  for (size_t i = 0; !rc && !rows && i < tf->n; i++)
    for (size_t j = 0; !rc && j < i; j++) {
      double a = tf->c[i * tf->n + j], b = tf->c[j * tf->n + i];
      if (fabs(a - b) > 1e-9 * fmax(fabs(a), fabs(b)))
        rc = gs_error_set(err, GS_EINPUT, "%s: table is not symmetric: C[%zu][%zu] = %g but C[%zu][%zu] = %g", path, i, j, a, j, i, b);
    }
  if (rc) { free(tf->edges); free(tf->c); tf->edges = tf->c = NULL; }
  return rc;
}


size_t *gs_class_table_assign(const gs_class_table *tf, const double *size, size_t ncells,
                              int diameter, const char *path, gs_error *err) {
  gs_axis classes; /* the edges as an axis, to place sizes by the grid's rule */
  if (gs_axis_from_edges(&classes, "classes", tf->edges, tf->n + 1, NULL, err)) return NULL;
  size_t *cls = gs_malloc(ncells * sizeof(size_t), err), outside = 0, on_edge = 0, first = 0;
  for (size_t c = 0; cls && c < ncells; c++) {
    double s = diameter ? gs_diameter(size[c]) : size[c];
    /* [e_i, e_i+1): a size on an inner edge (to round-off) takes the class above */
    size_t i = gs_axis_locate_snapped(&classes, s);
    if (i == GS_NOWHERE) {
      outside++;
      i = s < tf->edges[0] ? 0 : tf->n - 1;
    } else if (i > 0 && fabs(s - tf->edges[i]) <= 16 * DBL_EPSILON * tf->edges[i]) {
      if (!on_edge) first = c;
      on_edge++;
    }
    cls[c] = i;
  }
  gs_axis_free(&classes);
  if (outside)
    fprintf(stderr, "gransim: warning: %s: %zu of %zu grid cells lie outside the table's classes "
            "[%g, %g] and use the nearest class\n", path, outside, ncells, tf->edges[0], tf->edges[tf->n]);
  if (on_edge)
    fprintf(stderr, "gransim: warning: %s: %zu of %zu grid cells have their %s on an edge between "
            "two classes (the first: cell %zu, %.17g) and take the class above it (classes are "
            "[e_i, e_i+1)); move the table's edges off the pivots to make the choice yours\n",
            path, on_edge, ncells, diameter ? "diameter" : "size", first,
            diameter ? gs_diameter(size[first]) : size[first]);
  return cls;
}

void gs_class_table_free(gs_class_table *tf) {
  free(tf->edges);
  free(tf->c);
  tf->edges = tf->c = NULL;
}
