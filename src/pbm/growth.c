/* Growth mechanisms along one axis, all using the upwind scheme of
 * growth_scheme.h:
 *   growth          G = G0 + sigma * x_axis                (keys axis, constant, linear)
 *   liquid_addition G_l = Q(comp) w / sum(N w)             spray shared by a registered rule: w = s,
 *                                                          solid volume (Sampat et al. 2018, eq. 5), or
 *                                                          w = V psi (De et al. 2025, eqs. 7-9), in
 *                                                          [start, end) (liquid_share.h)
 *   consolidation   G_g = -c (s+l+g)(1-e_min)/s * max(0, l + g - e_min s/(1-e_min))
 *                   (Chaudhury 2015, eq. 2.12 with the sign of "negative growth"; see docs/models.md)
 *   drying          G_l = -E(d) per granule, evaporation driven by the humidity difference
 *                   (Chaudhury 2015, eqs. 2.19-2.22; drying.c), in [start, end) */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"
#include "pbm/drying.h"
#include "pbm/growth_scheme.h"
#include "pbm/liquid_share.h"
#include "pbm/schedule.h"

enum { KIND_GROWTH, KIND_LIQUID, KIND_CONSOLIDATION, KIND_DRYING };

typedef struct {
  int kind, axis, liquid, gas;
  int solid[GS_MAX_DIM]; /* 1 for axes that are solid */
  double g0, sigma;      /* growth */
  gs_liquid_inflow inflow; /* liquid_addition: the sprayed volume per second */
  gs_liquid_share share;   /* liquid_addition: how it is shared */
  double *weight;          /* liquid_addition: per cell, the share rule's weight of one granule */
  double start, end;
  double c, emin;        /* consolidation */
  double *G;             /* per cell rates (workspace / precomputed) */
  size_t row_len;        /* liquid_addition: stride of the slots' rows, whole pages (GS_APART) */
  double *solid_vol;     /* per cell solid volume */
  double *work;          /* preconditioner: 2 * cells along the axis */
  gs_bed *bed;           /* drying with the bed's balances (NULL: fixed conditions) */
  double *drive;         /* bed: per compartment, the humidity difference of the last evaluation */
  gs_schedule sched;     /* liquid_addition: phases scaling the rates (none: [start, end) at 1) */
} grow_t;

static void grow_free(void *self) {
  grow_t *G = self;
  if (!G) return;
  gs_liquid_inflow_free(&G->inflow);
  gs_liquid_share_free(&G->share);
  free(G->weight);
  free(G->G);
  free(G->solid_vol);
  free(G->work);
  gs_bed_free(G->bed);
  free(G->drive);
  gs_schedule_free(&G->sched);
  free(G);
}

/* Solid axes: key solid_axes, default every axis that is not liquid or gas. */
static int solid_axes(gs_cfg_node *node, const gs_grid *g, grow_t *G, gs_error *err) {
  gs_cfg_node *list = gs_cfg_get(node, "solid_axes");
  memset(G->solid, 0, sizeof G->solid);
  if (!list) {
    for (int k = 0; k < g->dim; k++) G->solid[k] = k != G->liquid && k != G->gas;
  } else {
    if (gs_cfg_require_kind(list, GS_CFG_SEQ, err)) return GS_EINPUT;
    for (size_t i = 0; i < gs_cfg_size(list); i++) {
      const char *nm = gs_cfg_scalar(gs_cfg_item(list, i));
      int k = nm ? gs_grid_axis_by_name(g, nm) : -1;
      if (k < 0) return gs_cfg_fail(gs_cfg_item(list, i), err, "expected the name of a grid axis");
      G->solid[k] = 1;
    }
  }
  G->solid_vol = gs_malloc(g->ncells * sizeof(double), err);
  if (!G->solid_vol) return GS_ENOMEM;
  for (size_t c = 0; c < g->ncells; c++) {
    double s = 0;
    for (int k = 0; k < g->dim; k++)
      if (G->solid[k]) s += g->x[c * (size_t)g->dim + (size_t)k];
    G->solid_vol[c] = s;
  }
  return GS_OK;
}

static int grow_create_kind(gs_cfg_node *node, const gs_model *m, void **self, int kind,
                            gs_error *err) {
  const gs_grid *g = &m->grid;
  grow_t *G = gs_calloc(1, sizeof *G, err);
  if (!G) return GS_ENOMEM;
  G->kind = kind;
  G->liquid = G->gas = -1;
  /* liquid_addition recomputes the rates per compartment: one row per slot
   * (gs_eval.slot), on pages of their own as threads write them at once;
   * the others' stay in the first */
  const int per_comp = kind == KIND_LIQUID || (kind == KIND_DRYING && gs_cfg_get(node, "bed"));
  const size_t rows = per_comp && m->nslots > 1 ? (size_t)m->nslots : 1;
  G->row_len = rows > 1 ? gs_doubles_apart(g->ncells) : g->ncells;
  G->G = rows > 1 ? gs_calloc_apart(rows * G->row_len * sizeof(double), err)
                  : gs_calloc(g->ncells, sizeof(double), err);
  int rc = G->G ? GS_OK : GS_ENOMEM;
  if (!rc && m->ncarried > 0) /* particles moving between cells would leave their load behind */
    rc = gs_cfg_fail(node, err, "growth along an axis cannot be combined with carried quantities "
                                "(grid.carried); use spray / pore_consolidation for carried liquid and gas");
  if (!rc && kind == KIND_GROWTH) {
    rc = gs_growth_axis_key(node, g, "axis", NULL, &G->axis, err);
    if (!rc) rc = gs_cfg_double_opt(node, "constant", 0, &G->g0, err);
    if (!rc) rc = gs_cfg_double_opt(node, "linear", 0, &G->sigma, err);
    if (!rc) rc = gs_mech_read_window(node, &G->start, &G->end, err);
    for (size_t c = 0; !rc && c < g->ncells; c++)
      G->G[c] = G->g0 + G->sigma * g->x[c * (size_t)g->dim + (size_t)G->axis];
  } else if (!rc && kind == KIND_LIQUID) {
    rc = gs_growth_axis_key(node, g, "liquid_axis", "liquid", &G->liquid, err);
    G->axis = G->liquid;
    G->gas = gs_grid_axis_by_name(g, "gas");
    if (!rc && gs_cfg_get(node, "schedule")) { /* phases scale per-compartment rates */
      size_t nq = 0;
      rc = gs_spray_schedule(node, g, &G->inflow.q, &nq, &G->sched, err);
      if (!rc && nq != 1 && nq != g->ncomp)
        rc = gs_cfg_fail(gs_cfg_get(node, "schedule"), err, "expected one rate or one per compartment (%zu)",
                         g->ncomp);
      for (size_t i = 0; !rc && i < nq; i++)
        if (G->inflow.q[i] < 0) rc = gs_cfg_fail(gs_cfg_get(node, "schedule"), err, "rates must be >= 0");
      if (!rc && nq == 1 && g->ncomp > 1) {
        double *all = realloc(G->inflow.q, g->ncomp * sizeof(double));
        if (!all) rc = GS_ENOMEM;
        else {
          G->inflow.q = all;
          for (size_t i = 1; i < g->ncomp; i++) G->inflow.q[i] = G->inflow.q[0];
        }
      }
      if (!rc) { /* the schedule's phases switch it */
        G->start = G->sched.phase[0].start;
        G->end = G->sched.phase[G->sched.n - 1].end;
      }
    } else {
      if (!rc) rc = gs_mech_read_window(node, &G->start, &G->end, err);
      if (!rc) rc = gs_liquid_inflow_read(node, g->ncomp, G->start, G->end, &G->inflow, err);
    }
    if (!rc) rc = gs_liquid_share_read(node, &G->share, err);
    if (!rc) rc = solid_axes(node, g, G, err);
    /* a granule's gross volume is the sum of all its coordinates (solid,
     * liquid, gas): the envelope a droplet hits */
    if (!rc && !(G->weight = gs_malloc(g->ncells * sizeof(double), err))) rc = GS_ENOMEM;
    for (size_t c = 0; !rc && c < g->ncells; c++)
      G->weight[c] = G->share.type->weight(&G->share, G->solid_vol[c], g->volume[c]);
  } else if (!rc && kind == KIND_DRYING) {
    for (size_t i = 0; !rc && i < m->nmech; i++) /* fluid_bed evaporates the liquid itself */
      if (!strcmp(m->mech[i].type->name, "fluid_bed"))
        rc = gs_cfg_fail(node, err, "drying cannot join fluid_bed (%s), which evaporates the granules' "
                                    "liquid itself", m->mech[i].label);
    if (!rc) rc = gs_growth_axis_key(node, g, "liquid_axis", "liquid", &G->liquid, err);
    G->axis = G->liquid;
    if (!rc) rc = gs_drying_read(node, m, G->liquid, G->G, &G->bed, err);
    if (!rc && G->bed && !(G->drive = gs_malloc(g->ncomp * sizeof(double), err))) rc = GS_ENOMEM;
    for (size_t i = 0; !rc && G->bed && i < g->ncomp; i++) G->drive[i] = NAN; /* none yet */
    if (!rc) rc = gs_mech_read_window(node, &G->start, &G->end, err);
  } else if (!rc) {
    rc = gs_growth_axis_key(node, g, "liquid_axis", "liquid", &G->liquid, err);
    if (!rc) rc = gs_growth_axis_key(node, g, "gas_axis", "gas", &G->gas, err);
    G->axis = G->gas;
    if (!rc) rc = gs_cfg_double_range(node, "rate", 1, 0, 0, 0, HUGE_VAL, 0, &G->c, err);
    if (!rc) rc = gs_cfg_double_range(node, "min_porosity", 1, 0, 0, 0, 1, 1, &G->emin, err);
    if (!rc) rc = solid_axes(node, g, G, err);
    for (size_t c = 0; !rc && c < g->ncells; c++) {
      const double *x = g->x + c * (size_t)g->dim;
      double s = G->solid_vol[c], l = x[G->liquid], gas = x[G->gas];
      double excess = l + gas - G->emin * s / (1 - G->emin);
      G->G[c] = (s > 0 && excess > 0) ? -G->c * (s + l + gas) * (1 - G->emin) / s * excess : 0.0;
    }
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (!rc && !(G->work = gs_malloc(2 * g->axis[G->axis].n * sizeof(double), err))) rc = GS_ENOMEM;
  if (rc) {
    grow_free(G);
    return rc;
  }
  *self = G;
  return GS_OK;
}

static int active(const grow_t *G, const gs_eval *ev, double t) {
  return G->kind == KIND_CONSOLIDATION || gs_window_on(ev, G->start, G->end, t);
}

/* Rates of compartment comp at t (in this caller's row of G->G), or NULL
 * when nothing grows there. */
static const double *compartment_rates(grow_t *G, const gs_model *m, const gs_eval *ev,
                                       size_t comp, double t, const double *N) {
  const gs_grid *g = &m->grid;
  if (G->kind != KIND_LIQUID && !G->bed) return G->G; /* precomputed */
  double *rates = G->G + (ev->slot > 0 ? (size_t)ev->slot : 0) * G->row_len;
  if (G->bed) return gs_bed_rates(G->bed, g->ncells, N, ev->hold, &G->drive[comp], rates) ? rates : NULL;
  /* share the spray by the rule's weights */
  double solid = 0, wsum = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    solid += N[c] * G->solid_vol[c];
    wsum += N[c] * G->weight[c];
  }
  const double q =
      gs_liquid_inflow_rate(&G->inflow, comp, solid) * (G->sched.n ? gs_schedule_value(&G->sched, ev, t) : 1.0);
  if (!(wsum > 0) || q == 0.0) return NULL;
  double per = q / wsum;
  for (size_t c = 0; c < g->ncells; c++) rates[c] = per * G->weight[c];
  return rates;
}

static void grow_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                       const double *y, double *dydt, double *dledger) {
  grow_t *G = self;
  if (!active(G, ev, t)) return;
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  const double *rates = compartment_rates(G, m, ev, comp, t, N);
  double *ledger = gs_eval_ledger(m, ev, dledger, comp);
  if (rates)
    gs_growth_apply(&m->grid, G->axis, rates, N, gs_eval_numbers(m, ev, dydt, comp), ledger,
                    ledger + m->nvol);
}

/* Exact inverse of I - gamma J for the transfer along the axis with the
 * rates frozen at y (the spray's dependence on the total solid volume, a
 * rank-one term, is left to the Krylov iterations). */
static void grow_precondition(void *self, const gs_model *m, const gs_eval *ev, size_t comp,
                              double t, const double *y, double gamma, double *z, double *zledger) {
  grow_t *G = self;
  if (!active(G, ev, t)) return;
  const double *rates = compartment_rates(G, m, ev, comp, t, gs_eval_numbers_c(m, ev, y, comp));
  if (rates)
    gs_growth_solve(&m->grid, G->axis, rates, gamma, gs_eval_numbers(m, ev, z, comp), zledger,
                    zledger + m->nvol, G->work);
}

static double grow_switch(void *self, double t) {
  const grow_t *G = self;
  if (G->sched.n) return gs_schedule_next_switch(&G->sched, t);
  return G->kind == KIND_CONSOLIDATION ? INFINITY : gs_window_next_switch(G->start, G->end, t);
}

static int growth_create(gs_cfg_node *n, const gs_model *m, void **s, gs_error *e) {
  return grow_create_kind(n, m, s, KIND_GROWTH, e);
}
static int liquid_create(gs_cfg_node *n, const gs_model *m, void **s, gs_error *e) {
  return grow_create_kind(n, m, s, KIND_LIQUID, e);
}
static int consol_create(gs_cfg_node *n, const gs_model *m, void **s, gs_error *e) {
  return grow_create_kind(n, m, s, KIND_CONSOLIDATION, e);
}
static int drying_create(gs_cfg_node *n, const gs_model *m, void **s, gs_error *e) {
  return grow_create_kind(n, m, s, KIND_DRYING, e);
}

const gs_mech_type gs_mech_growth = {
    .name = "growth",
    .summary = "growth along an axis, G = constant + linear * x",
    .create = growth_create,
    .rates = grow_rates,
    .free = grow_free,
    .precondition = grow_precondition,
    .next_switch = grow_switch,
};
const gs_mech_type gs_mech_liquid_addition = {
    .name = "liquid_addition",
    .summary = "liquid spray along a liquid axis, shared by solid volume (Sampat et al. 2018) or absorption (De et al. 2025)",
    .create = liquid_create,
    .rates = grow_rates,
    .free = grow_free,
    .precondition = grow_precondition,
    .next_switch = grow_switch,
};
const gs_mech_type gs_mech_consolidation = {
    .name = "consolidation",
    .summary = "loss of gas down to a minimum porosity (Chaudhury 2015, eq. 2.12, corrected sign)",
    .create = consol_create,
    .rates = grow_rates,
    .free = grow_free,
    .precondition = grow_precondition,
    .next_switch = grow_switch,
};
const gs_mech_type gs_mech_drying = {
    .name = "drying",
    .summary = "evaporation of granules' liquid, bed temperature and humidity fixed or from the bed's balances (Chaudhury 2015, eqs. 2.18-2.25)",
    .create = drying_create,
    .rates = grow_rates,
    .free = grow_free,
    .precondition = grow_precondition,
    .next_switch = grow_switch,
};
