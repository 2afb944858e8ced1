/* Fines as a source of solid; see fines.h. */
#include <stdlib.h>

#include "pbm/fines.h"

int gs_fines_init(gs_fines *f, const gs_grid *g, int axis, double max, gs_cfg_node *node,
                  const char *key, gs_error *err) {
  f->axis = axis;
  f->is_fine = gs_calloc(g->ncells, 1, err);
  if (!f->is_fine) return GS_ENOMEM;
  size_t n = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    f->is_fine[c] = g->x[c * (size_t)g->dim + (size_t)axis] <= max;
    n += f->is_fine[c];
  }
  if (n == 0 || n == g->ncells) {
    gs_cfg_node *k = gs_cfg_get(node, key);
    return gs_cfg_fail(k ? k : node, err, "%s: no cell of axis '%s' is fines (pivot <= %g) or every cell is",
                       key, g->axis[axis].name, max);
  }
  return GS_OK;
}

void gs_fines_free(gs_fines *f) {
  free(f->is_fine);
  f->is_fine = NULL;
}

void gs_fines_volumes(const gs_fines *f, const gs_grid *g, const double *N, double *fine,
                      double *total) {
  const size_t dim = (size_t)g->dim;
  const double *x = g->x + f->axis;
  double a = 0, b = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    double v = N[c] * x[c * dim];
    b += v;
    if (f->is_fine[c]) a += v;
  }
  *fine = a;
  *total = b;
}

void gs_fines_take(const gs_fines *f, const gs_model *m, const gs_eval *ev, size_t comp,
                   const double *y, double k, double *dydt, double *dledger) {
  if (!(k > 0)) return;
  const gs_grid *g = &m->grid;
  const size_t dim = (size_t)g->dim;
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  double *dN = gs_eval_numbers(m, ev, dydt, comp), *ledger = gs_eval_ledger(m, ev, dledger, comp);
  double out[GS_MAX_VOL] = {0};
  for (size_t c = 0; c < g->ncells; c++) {
    if (!f->is_fine[c] || N[c] == 0.0) continue;
    double r = k * N[c];
    dN[c] -= r;
    for (size_t a = 0; a < dim; a++) out[a] += r * g->x[c * dim + a];
  }
  for (int q = 0; q < m->ncarried; q++) {
    const double *Q = gs_eval_carried_c(m, ev, y, comp, q);
    double *dQ = gs_eval_carried(m, ev, dydt, comp, q);
    for (size_t c = 0; c < g->ncells; c++) {
      if (!f->is_fine[c] || Q[c] == 0.0) continue;
      dQ[c] -= k * Q[c];
      out[dim + (size_t)q] += k * Q[c];
    }
  }
  for (int a = 0; a < m->nvol; a++) ledger[a] -= out[a];
}
