/* LIGGGHTS' thermo lines: see lig_internal.h. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "liggghts/lig_internal.h"

int gs_lig_thermo_add(gs_lig_thermo *th, const char *line, double dt, double out_every, double cpu_acc[2]) {
  double step, atoms, ke, rke, cpu, hn, hm;
  char extra;
  if (sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %c", &step, &atoms, &ke, &rke, &cpu, &hn, &hm, &extra) != 7) return 0;
  if (!isfinite(step) || !(dt > 0)) return 0;
  if (cpu < cpu_acc[0]) cpu_acc[1] += cpu_acc[0];
  cpu_acc[0] = cpu;
  const double out_k = fmax(1, round(out_every / dt));
  if (fmod(step, out_k) != 0 || (th->n && step * dt <= th->row[GS_LIG_THERMO_COLS * (th->n - 1)])) return 0;
  if (th->n == th->cap) {
    size_t cap = th->cap ? 2 * th->cap : 256;
    double *r = realloc(th->row, cap * GS_LIG_THERMO_COLS * sizeof(double));
    if (!r) return -1;
    th->row = r;
    th->cap = cap;
  }
  double *r = th->row + GS_LIG_THERMO_COLS * th->n++;
  r[0] = step * dt, r[1] = atoms, r[2] = ke, r[3] = rke, r[4] = cpu + cpu_acc[1], r[5] = hn, r[6] = hm;
  return 1;
}
