/* LIGGGHTS' thermo lines: see lig_internal.h. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "liggghts/lig_internal.h"

size_t gs_lig_thermo_cols(const gs_dem_case *c) { return GS_LIG_THERMO_COLS + c->nwall_src; }

/* The numbers of line into x (at most max), or 0 when anything else is on it. */
static size_t numbers(const char *line, double *x, size_t max) {
  size_t n = 0;
  for (const char *p = line;;) {
    char *end;
    double v = strtod(p, &end);
    if (end == p) {
      while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n') p++;
      return *p ? 0 : n;
    }
    if (n == max) return 0;
    x[n++] = v;
    p = end;
  }
}

int gs_lig_thermo_step(const gs_lig_thermo *th, const char *line, double *step) {
  double x[GS_LIG_THERMO_COLS + 64];
  const size_t nc = th->ncol;
  if (nc < GS_LIG_THERMO_COLS || nc > sizeof x / sizeof x[0] || numbers(line, x, nc) != nc) return 0;
  *step = x[0];
  return 1;
}

int gs_lig_thermo_add(gs_lig_thermo *th, const char *line, double dt, double out_every, double cpu_acc[2]) {
  double x[GS_LIG_THERMO_COLS + 64];
  const size_t nc = th->ncol;
  if (nc < GS_LIG_THERMO_COLS || nc > sizeof x / sizeof x[0] || numbers(line, x, nc) != nc) return 0;
  const double step = x[0], cpu = x[4];
  if (!isfinite(step) || !(dt > 0)) return 0;
  if (cpu < cpu_acc[0]) cpu_acc[1] += cpu_acc[0];
  cpu_acc[0] = cpu;
  const double out_k = fmax(1, round(out_every / dt));
  if (fmod(step, out_k) != 0 || (th->n && step * dt <= th->row[nc * (th->n - 1)])) return 0;
  if (th->n == th->cap) {
    size_t cap = th->cap ? 2 * th->cap : 256;
    double *r = realloc(th->row, cap * nc * sizeof(double));
    if (!r) return -1;
    th->row = r;
    th->cap = cap;
  }
  double *r = th->row + nc * th->n++;
  for (size_t k = 0; k < nc; k++) r[k] = x[k];
  r[0] = step * dt, r[4] = cpu + cpu_acc[1];
  return 1;
}
