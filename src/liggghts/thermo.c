/* LIGGGHTS' thermo lines: see lig_internal.h. */
#include <stdio.h>
#include <stdlib.h>

#include "liggghts/lig_internal.h"

int gs_lig_thermo_add(gs_lig_thermo *th, const char *line, double dt) {
  double step, atoms, ke, rke, cpu;
  char extra;
  if (sscanf(line, "%lf %lf %lf %lf %lf %c", &step, &atoms, &ke, &rke, &cpu, &extra) != 5) return 0;
  if (th->n == th->cap) {
    size_t cap = th->cap ? 2 * th->cap : 256;
    double *r = realloc(th->row, cap * 5 * sizeof(double));
    if (!r) return -1;
    th->row = r;
    th->cap = cap;
  }
  double *r = th->row + 5 * th->n++;
  r[0] = step * dt, r[1] = atoms, r[2] = ke, r[3] = rke, r[4] = cpu;
  return 1;
}
