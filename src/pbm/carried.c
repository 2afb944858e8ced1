/* Mechanisms that act on carried quantities (gs_model.carried), the lumped
 * liquid and gas per solid bin of Sampat et al. (2018):
 *   spray               dL_c/dt = Q(comp) N_c w_c / sum(N w) during [start, end):
 *                       the spray shared by a registered rule (liquid_share.h):
 *                       w = s, solid volume (eq. 5, the default), or w = V psi,
 *                       V = s + l + g the granule's gross volume (De et al. 2025)
 *   pore_consolidation  per particle dg/dt = -k V (1 - e_min)/s max(0, g + l - s e_min/(1 - e_min))
 *                       (eq. 13 with the sign of a loss; V = s + l + g), so the
 *                       porosity (l + g)/V relaxes to e_min and stops there (the
 *                       excess is capped at g: liquid alone cannot drive gas negative)
 * s is the solid volume of the cell (sum of the grid axes), l = L_c/N_c and
 * g = G_c/N_c the liquid and gas a particle carries.  Both book what they add
 * or remove as exchanged volume of the carried quantity in the ledger. */
#include <math.h>
#include <stdlib.h>

#include "gransim/pbm.h"
#include "pbm/liquid_share.h"
#include "pbm/sums.h"

enum { SPRAY, PORE_CONSOLIDATION };

typedef struct {
  int kind, liquid, gas; /* carried indices (-1 if absent) */
  gs_liquid_inflow inflow; /* spray: volume per second */
  gs_liquid_share share;   /* spray: how it is shared */
  double start, end;
  double k, emin;        /* consolidation */
} carried_t;

static void carried_free(void *self) {
  carried_t *C = self;
  if (C) {
    gs_liquid_inflow_free(&C->inflow);
    gs_liquid_share_free(&C->share);
  }
  free(C);
}

/* A carried quantity named by key (default def). */
static int carried_key(gs_cfg_node *node, const gs_model *m, const char *key, const char *def,
                       int *out, gs_error *err) {
  const char *name;
  int rc = gs_cfg_string_opt(node, key, def, &name, err);
  if (rc) return rc;
  *out = gs_model_carried_index(m, name);
  if (*out >= 0) return GS_OK;
  gs_cfg_node *n = gs_cfg_get(node, key);
  return gs_cfg_fail(n ? n : node, err,
                     "needs a carried quantity named '%s' (grid.carried; or set '%s')", name, key);
}

static int carried_create(gs_cfg_node *node, const gs_model *m, void **self, int kind,
                          gs_error *err) {
  carried_t *C = gs_calloc(1, sizeof *C, err);
  if (!C) return GS_ENOMEM;
  C->kind = kind;
  C->liquid = C->gas = -1;
  int rc = carried_key(node, m, "liquid", "liquid", &C->liquid, err);
  if (!rc && kind == SPRAY) {
    rc = gs_cfg_double_range(node, "start", 0, 0, -HUGE_VAL, 0, HUGE_VAL, 0, &C->start, err);
    if (!rc) rc = gs_cfg_double_range(node, "end", 0, HUGE_VAL, C->start, 1, HUGE_VAL, 0, &C->end, err);
    if (!rc) rc = gs_liquid_inflow_read(node, m->grid.ncomp, C->start, C->end, &C->inflow, err);
    if (!rc) rc = gs_liquid_share_read(node, &C->share, err);
  } else if (!rc) {
    rc = carried_key(node, m, "gas", "gas", &C->gas, err);
    if (!rc) rc = gs_cfg_double_range(node, "rate", 1, 0, 0, 0, HUGE_VAL, 0, &C->k, err);
    if (!rc) rc = gs_cfg_double_range(node, "min_porosity", 1, 0, 0, 0, 1, 1, &C->emin, err);
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    carried_free(C);
    return rc;
  }
  *self = C;
  return GS_OK;
}

/* The weight of cell c's granules together, N_c w_c: w of the rule for a
 * granule of the cell's solid volume and its gross volume with the liquid
 * and gas it carries (all carried quantities). */
static double cell_weight(const carried_t *C, const gs_model *m, const gs_eval *ev, const double *y, size_t comp,
                          const double *N, size_t c) {
  const double s = m->grid.volume[c];
  (void)ev;
  /* round-off below zero holds no granules: a negative weight would take
   * liquid away while others receive more than the spray */
  if (!(N[c] > 0)) return 0;
  if (!C->share.type->needs_gross) return N[c] * C->share.type->weight(&C->share, s, s);
  double carried = 0;
  for (int q = 0; q < m->ncarried; q++) carried += gs_eval_carried_c(m, ev, y, comp, q)[c];
  return N[c] * C->share.type->weight(&C->share, s, s + fmax(carried, 0) / N[c]);
}

/* Compartment comp's share of the spray, by the sharing rule. */
static void spray_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                        const double *y, double *dydt, double *dledger) {
  const carried_t *C = self;
  if (!gs_window_on(ev, C->start, C->end, t)) return;
  const gs_grid *g = &m->grid;
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  const double solid = gs_dot_strided(N, g->volume, 1, g->ncells);
  const double q = gs_liquid_inflow_rate(&C->inflow, comp, solid);
  /* a compartment the material has not reached holds only the tanks-in-series
   * tail at the solver's noise floor: no granule to wet, and the whole spray
   * on a weight of round-off would load them with 1e20 times their volume */
  int reached = 0;
  for (size_t c = 0; c < g->ncells && !reached; c++) reached = N[c] > ev->noise_floor;
  if (!reached || q == 0.0) return;
  double wsum = 0;
  for (size_t c = 0; c < g->ncells; c++) wsum += cell_weight(C, m, ev, y, comp, N, c);
  if (!(wsum > 0)) return;
  double per = q / wsum, *dL = gs_eval_carried(m, ev, dydt, comp, C->liquid);
  for (size_t c = 0; c < g->ncells; c++) dL[c] += per * cell_weight(C, m, ev, y, comp, N, c);
  gs_eval_ledger(m, ev, dledger, comp)[g->dim + C->liquid] += q;
}

/* Compartment comp's loss of gas down to the minimum porosity. */
static void consolidation_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp,
                                double t, const double *y, double *dydt, double *dledger) {
  (void)t;
  const carried_t *C = self;
  const gs_grid *g = &m->grid;
  const double target = C->emin / (1 - C->emin); /* pore volume per solid volume at e_min */
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  const double *L = gs_eval_carried_c(m, ev, y, comp, C->liquid);
  const double *G = gs_eval_carried_c(m, ev, y, comp, C->gas);
  double *dG = gs_eval_carried(m, ev, dydt, comp, C->gas), lost = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    /* cells at the solver's noise floor hold no particles to speak of, and
     * their loads per particle (G / N, with N noise) are meaningless: the
     * rate, quadratic in the gas per particle, would be too */
    if (!(N[c] > ev->noise_floor) || !(G[c] > 0)) continue;
    double s = g->volume[c], l = L[c] / N[c], gas = G[c] / N[c];
    double excess = gas + l - target * s;
    if (!(excess > 0) || !(s > 0)) continue;
    double rate = C->k * (s + l + gas) * (1 - C->emin) / s * fmin(excess, gas) * N[c];
    dG[c] -= rate;
    lost += rate;
  }
  gs_eval_ledger(m, ev, dledger, comp)[g->dim + C->gas] -= lost;
}

static int spray_create(gs_cfg_node *n, const gs_model *m, void **s, gs_error *e) {
  return carried_create(n, m, s, SPRAY, e);
}
static int pore_create(gs_cfg_node *n, const gs_model *m, void **s, gs_error *e) {
  return carried_create(n, m, s, PORE_CONSOLIDATION, e);
}

static double spray_switch(void *self, double t) {
  const carried_t *C = self;
  return gs_window_next_switch(C->start, C->end, t);
}

const gs_mech_type gs_mech_spray = {
    .name = "spray",
    .summary = "liquid sprayed onto the carried liquid, shared by solid volume (Sampat et al. 2018) or absorption (De et al. 2025)",
    .create = spray_create,
    .rates = spray_rates,
    .free = carried_free,
    .next_switch = spray_switch,
};
const gs_mech_type gs_mech_pore_consolidation = {
    .name = "pore_consolidation",
    .summary = "loss of carried gas down to a minimum porosity (Sampat et al. 2018, eq. 13, sign of a loss)",
    .create = pore_create,
    .rates = consolidation_rates,
    .free = carried_free,
};
