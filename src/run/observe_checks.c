/* Observer: the state checks after every output time.  Non-finite or
 * negative numbers and carried volumes beyond round-off, the volume balance
 * of every coordinate in every compartment (held = initial + exchanged -
 * lost, the ledger identity) and the loss through the grid boundaries: any
 * of them stops the run with a message naming the time, compartment and
 * cell. */
#include <math.h>
#include <stdlib.h>

#include "pbm/all_finite.h"
#include "run/run_internal.h"

typedef struct {
  gs_run *run;
  double *M1_0;     /* ncomp * nvol: each compartment's volumes at the start */
  double ymax_seen; /* largest number seen so far in the run */
} checks_t;

static int check_state(const checks_t *k, const double *Y, double t, gs_error *err) {
  const gs_case *c = k->run->c;
  const gs_model *m = &c->model;
  const double *M1_0 = k->M1_0;
  gs_run_report *rep = k->run->rep;
  const gs_grid *g = &m->grid;
  const int nvol = m->nvol;
  char where[512];
  double ymax = k->ymax_seen; /* largest number seen so far in the run */
  /* the vectorised test, and the search for the culprit only when it fails
   * (a scan with isfinite and fmax per value costs more than the rest) */
  const int finite = gs_all_finite(Y, m->nstate);
  for (size_t i = m->scalar_at; !finite && i < m->nstate; i++)
    if (!isfinite(Y[i]))
      return gs_error_set(err, GS_ENUMERIC, "numerical failure at t = %g: scalar %zu of compartment "
                          "%zu (a mechanism's state) is %g", t, (i - m->scalar_at) % m->nscalar + 1,
                          (i - m->scalar_at) / m->nscalar + 1, Y[i]);
  for (size_t i = 0; !finite && i < m->scalar_at; i++)
    if (!isfinite(Y[i])) {
      size_t j = i < m->nnum ? i : (i - m->nnum) % m->nnum;
      gs_run_describe_cell(m, (i < m->nnum ? i : (i - m->nnum) / g->ncells / (size_t)m->ncarried) % g->ncomp,
                    j % g->ncells, where, sizeof where);
      return gs_error_set(err, GS_ENUMERIC, "numerical failure at t = %g: %s: %s is %g", t, where,
                          i < m->nnum ? "number" : "a carried volume", Y[i]);
    }
  for (size_t i = 0; i < m->nnum; i++) {
    const double a = fabs(Y[i]);
    ymax = a > ymax ? a : ymax; /* fmax, all being finite */
  }
  ((checks_t *)k)->ymax_seen = ymax;
  /* an absolute floor: a state that is still (nearly) empty has only round-off */
  const double floor_abs = fmax(1e-30, c->checks.negative_floor);
  for (size_t i = 0; i < m->nnum; i++)
    if (Y[i] < -c->checks.negative_tolerance * ymax - floor_abs) {
      gs_run_describe_cell(m, i / g->ncells, i % g->ncells, where, sizeof where);
      return gs_error_set(err, GS_ENUMERIC,
                          "numerical failure at t = %g: %s: number %g is negative beyond round-off "
                          "(%g of the largest number %g; checks.negative_tolerance = %g). Tighten "
                          "solver.rtol/atol or check the rates",
                          t, where, Y[i], -Y[i] / ymax, ymax, c->checks.negative_tolerance);
    }
  /* carried volumes: the same rule per quantity; the absolute floor is that of
   * the numbers in volume units (the integrator's scale for carried totals) */
  const double qfloor = fmax(1e-30, c->checks.negative_floor * (m->ncarried ? c->abs_scale[m->nnum] : 1.0));
  for (int q = 0; q < m->ncarried; q++) {
    double qmax = 0;
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *Q = gs_model_carried_c(m, Y, comp, q);
      for (size_t cell = 0; cell < g->ncells; cell++) {
        const double a = fabs(Q[cell]);
        qmax = a > qmax ? a : qmax;
      }
    }
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *Q = gs_model_carried_c(m, Y, comp, q);
      for (size_t cell = 0; cell < g->ncells; cell++)
        if (Q[cell] < -c->checks.negative_tolerance * qmax - qfloor) {
          gs_run_describe_cell(m, comp, cell, where, sizeof where);
          return gs_error_set(err, GS_ENUMERIC,
                              "numerical failure at t = %g: %s: carried %s %g is negative beyond "
                              "round-off (%g of the largest %g; checks.negative_tolerance = %g)",
                              t, where, m->carried[q], Q[cell], -Q[cell] / qmax, qmax,
                              c->checks.negative_tolerance);
        }
    }
  }
  const double *L = Y + m->nstate;
  double worst_frac = 0;
  int worst_k = -1, worst_sign = 0;
  for (int k = 0; k < nvol; k++) {
    double scale = 0, lost = 0;
    double held[g->ncomp];
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *led = L + comp * 2 * (size_t)nvol;
      held[comp] = gs_model_held(m, Y, comp, k);
      scale += M1_0[comp * (size_t)nvol + (size_t)k] + fabs(held[comp]) + fabs(led[k]);
      lost += led[nvol + k];
    }
    if (!(scale > 0)) continue;
    for (size_t comp = 0; comp < g->ncomp; comp++) {
      const double *led = L + comp * 2 * (size_t)nvol;
      double expect = M1_0[comp * (size_t)nvol + (size_t)k] + led[k] - led[nvol + k];
      double rel = fabs(held[comp] - expect) / scale;
      if (rel > rep->max_balance_error) rep->max_balance_error = rel;
      if (rel > c->checks.mass_tolerance)
        return gs_error_set(err, GS_ENUMERIC,
                            "numerical failure at t = %g: volume balance of '%s' broken in "
                            "compartment %zu: held %.12g, expected %.12g (initial + exchanged - "
                            "lost); relative error %.3g > checks.mass_tolerance = %g",
                            t, gs_model_vol_name(m, k), comp + 1, held[comp], expect, rel,
                            c->checks.mass_tolerance);
    }
    double frac = fabs(lost) / scale;
    if (frac > worst_frac) {
      worst_frac = frac;
      worst_k = k;
      worst_sign = lost > 0;
    }
  }
  /* the mechanisms' own balances (a fluid bed's water and energy) */
  char what[512];
  const double own = m->nscalar ? gs_model_balance(m, Y, what, sizeof what) : 0;
  if (own > rep->max_balance_error) rep->max_balance_error = own;
  if (!(own <= c->checks.mass_tolerance))
    return gs_error_set(err, GS_ENUMERIC, "numerical failure at t = %g: %s; relative error %.3g > "
                        "checks.mass_tolerance = %g", t, what, own, c->checks.mass_tolerance);
  if (worst_frac > rep->max_loss) rep->max_loss = worst_frac;
  if (worst_k >= 0 && worst_frac > c->checks.max_loss) {
    /* carried volumes are lost with the particles beyond the grid: name the axes */
    const gs_axis *ax = &g->axis[worst_k < g->dim ? worst_k : 0];
    return gs_error_set(err, GS_ENUMERIC,
                        "at t = %g, a fraction %.3g of the volume of '%s' has crossed the grid "
                        "boundaries (%s), more than checks.max_loss = %g. Extend axis '%s' (now "
                        "[%g, %g]) or raise checks.max_loss",
                        t, worst_frac, gs_model_vol_name(m, worst_k),
                        worst_sign ? "lost beyond the last pivot" : "created below the first pivot",
                        c->checks.max_loss, ax->name, ax->edges[0], ax->edges[ax->n]);
  }
  return GS_OK;
}

static int checks_output(void *self, const gs_run_view *view, double t, const double *Y, int *stop,
                         gs_error *err) {
  (void)view;
  (void)stop;
  return check_state(self, Y, t, err);
}

static void checks_free(void *self) {
  checks_t *k = self;
  if (k) free(k->M1_0);
  free(k);
}

static int checks_init(void *self, gs_error *err) {
  checks_t *k = self;
  const gs_model *m = &k->run->c->model;
  if (!(k->M1_0 = gs_calloc(m->grid.ncomp * (size_t)m->nvol, sizeof(double), err))) return GS_ENOMEM;
  /* the case's initial state, also when resuming: the ledger counts from it */
  for (size_t comp = 0; comp < m->grid.ncomp; comp++)
    for (int v = 0; v < m->nvol; v++)
      k->M1_0[comp * (size_t)m->nvol + (size_t)v] = gs_model_held(m, k->run->c->y0, comp, v);
  return GS_OK;
}

static const gs_observer_type checks_type = {
    .name = "checks",
    .output = checks_output,
    .free = checks_free,
};

const gs_builtin_observer gs_observe_checks = {
    .type = &checks_type,
    .size = sizeof(checks_t),
    .init = checks_init,
};
