/* Flow through the compartments.
 *   feed:     particles enter one compartment at a constant rate with a given
 *             distribution (a distribution spec whose `number` is per second),
 *             during [start, end).
 *   transfer: each compartment c loses particles at rate k_c N to compartment
 *             c+1; the last one discharges them as product.  k_c is `rate`
 *             (1/s), 1/`residence_time`, or `velocity`/`length` (the v dt / d
 *             of Sampat et al. 2018), each a number or one value per compartment.
 * Both book the volume they move in the ledger of the compartments involved,
 * so the balance held = fed - discharged is checked per compartment.
 * Carried quantities (gs_model.carried) move with the particles: transfer
 * moves Q_q at the same rate k_c Q_q; fed particles carry `carried_ratio`
 * (per quantity, volume per unit of the particle's volume, e.g. gas
 * e/(1 - e) for porosity e). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/distribution.h"
#include "gransim/pbm.h"
#include "pbm/sums.h"

typedef struct {
  size_t comp;
  double start, end;
  double *rate;             /* ncells: particles per second per cell */
  double volume[GS_MAX_VOL]; /* volume per second per axis and carried quantity */
  double ratio[GS_MAX_CARRIED]; /* carried volume per unit particle volume */
} feed_t;

static void feed_free(void *self) {
  feed_t *F = self;
  if (F) free(F->rate);
  free(F);
}

static int feed_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  const gs_grid *g = &m->grid;
  feed_t *F = gs_calloc(1, sizeof *F, err);
  if (!F) return GS_ENOMEM;
  long comp = 1;
  gs_cfg_node *dist = NULL;
  F->rate = gs_calloc(g->ncells, sizeof(double), err);
  int rc = F->rate ? GS_OK : GS_ENOMEM;
  if (!rc) rc = gs_cfg_long_range(node, "compartment", 0, 1, 1, (long)g->ncomp, &comp, err);
  if (!rc) rc = gs_cfg_double_range(node, "start", 0, 0, -HUGE_VAL, 0, HUGE_VAL, 0, &F->start, err);
  if (!rc) rc = gs_cfg_double_range(node, "end", 0, HUGE_VAL, F->start, 1, HUGE_VAL, 0, &F->end, err);
  if (!rc) rc = gs_cfg_map_req(node, "distribution", &dist, err);
  if (!rc) rc = gs_distribution_add(dist, g, F->rate, 0, m->disc, err);
  gs_cfg_node *ratios = rc ? NULL : gs_cfg_get(node, "carried_ratio");
  if (ratios) {
    rc = gs_cfg_require_kind(ratios, GS_CFG_MAP, err);
    for (int q = 0; !rc && q < m->ncarried; q++)
      rc = gs_cfg_double_range(ratios, m->carried[q], 0, 0, 0, 0, HUGE_VAL, 0, &F->ratio[q], err);
    if (!rc) rc = gs_cfg_check_unused(ratios, err);
  }
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    feed_free(F);
    return rc;
  }
  F->comp = (size_t)comp - 1;
  for (size_t c = 0; c < g->ncells; c++) {
    for (int k = 0; k < g->dim; k++) F->volume[k] += F->rate[c] * g->x[c * (size_t)g->dim + (size_t)k];
    for (int q = 0; q < m->ncarried; q++) F->volume[g->dim + q] += F->rate[c] * F->ratio[q] * g->volume[c];
  }
  *self = F;
  return GS_OK;
}

static void feed_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                       const double *y, double *dydt, double *dledger) {
  (void)y;
  const feed_t *F = self;
  const gs_grid *g = &m->grid;
  if (comp != F->comp || !gs_window_on(ev, F->start, F->end, t)) return;
  double *d = gs_eval_numbers(m, ev, dydt, F->comp);
  for (size_t c = 0; c < g->ncells; c++) d[c] += F->rate[c];
  for (int q = 0; q < m->ncarried; q++) {
    if (F->ratio[q] == 0.0) continue;
    double *dq = gs_eval_carried(m, ev, dydt, F->comp, q);
    for (size_t c = 0; c < g->ncells; c++) dq[c] += F->rate[c] * F->ratio[q] * g->volume[c];
  }
  double *ledger = gs_eval_ledger(m, ev, dledger, F->comp);
  for (int k = 0; k < m->nvol; k++) ledger[k] += F->volume[k];
}

static double feed_switch(void *self, double t) {
  const feed_t *F = self;
  return gs_window_next_switch(F->start, F->end, t);
}

typedef struct {
  double *k; /* per compartment rate [1/s] */
} transfer_t;

static void transfer_free(void *self) {
  transfer_t *T = self;
  if (T) free(T->k);
  free(T);
}

/* A number or a list of one value per compartment, all > 0. */
static int per_compartment(gs_cfg_node *node, const char *key, size_t ncomp, double **out,
                           gs_error *err) {
  size_t n = 0;
  int rc = gs_cfg_doubles_req(node, key, 1, out, &n, err);
  if (rc) return rc;
  gs_cfg_node *kn = gs_cfg_get(node, key);
  if (n != 1 && n != ncomp)
    return gs_cfg_fail(kn, err, "expected one value or one per compartment (%zu), got %zu", ncomp, n);
  for (size_t i = 0; i < n; i++)
    if (!((*out)[i] > 0)) return gs_cfg_fail(kn, err, "values must be > 0");
  if (n == 1) {
    double *all = realloc(*out, ncomp * sizeof(double));
    if (!all) return gs_error_set(err, GS_ENOMEM, "out of memory");
    for (size_t i = 1; i < ncomp; i++) all[i] = all[0];
    *out = all;
  }
  return GS_OK;
}

static int transfer_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  size_t ncomp = m->grid.ncomp;
  transfer_t *T = gs_calloc(1, sizeof *T, err);
  if (!T) return GS_ENOMEM;
  double *a = NULL, *b = NULL;
  int rc = GS_OK, given = !!gs_cfg_get(node, "rate") + !!gs_cfg_get(node, "residence_time") +
                          !!gs_cfg_get(node, "velocity");
  if (given != 1)
    rc = gs_cfg_fail(node, err, "give exactly one of 'rate', 'residence_time' or 'velocity' (with 'length')");
  else if (gs_cfg_get(node, "rate"))
    rc = per_compartment(node, "rate", ncomp, &T->k, err);
  else if (gs_cfg_get(node, "residence_time")) {
    rc = per_compartment(node, "residence_time", ncomp, &T->k, err);
    for (size_t i = 0; !rc && i < ncomp; i++) T->k[i] = 1.0 / T->k[i];
  } else {
    rc = per_compartment(node, "velocity", ncomp, &a, err);
    if (!rc) rc = per_compartment(node, "length", ncomp, &b, err);
    if (!rc) {
      T->k = a;
      a = NULL;
      for (size_t i = 0; i < ncomp; i++) T->k[i] /= b[i];
    }
  }
  free(a);
  free(b);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    transfer_free(T);
    return rc;
  }
  *self = T;
  return GS_OK;
}

/* Compartment comp's rates and ledger: what leaves it, and what comes in
 * from the one before.  It writes only its own entries. */
static void transfer_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp,
                           double t, const double *y, double *dydt, double *dledger) {
  (void)t;
  const transfer_t *T = self;
  const gs_grid *g = &m->grid;
  const size_t n = g->ncells, dim = (size_t)g->dim;
  double *ledger = gs_eval_ledger(m, ev, dledger, comp);
  for (int from = comp > 0 ? -1 : 0; from <= 0; from++) { /* -1: inflow from comp - 1 */
    const size_t sc = from == 0 ? comp : comp - 1;        /* source compartment */
    const double k = T->k[sc], sign = from == 0 ? -1.0 : 1.0;
    const double *N = from == 0 ? gs_eval_numbers_c(m, ev, y, sc) : gs_eval_upstream_c(m, ev, y, comp, -1);
    double moved[GS_MAX_VOL];
    gs_add_scaled(gs_eval_numbers(m, ev, dydt, comp), N, sign * k, n);
    for (size_t a = 0; a < dim; a++) moved[a] = k * gs_dot_strided(N, g->x + a, dim, n);
    for (int q = 0; q < m->ncarried; q++) {
      const double *Q = from == 0 ? gs_eval_carried_c(m, ev, y, sc, q) : gs_eval_upstream_c(m, ev, y, comp, q);
      gs_add_scaled(gs_eval_carried(m, ev, dydt, comp, q), Q, sign * k, n);
      moved[dim + (size_t)q] = k * gs_sum(Q, n);
    }
    for (int a = 0; a < m->nvol; a++) ledger[a] += sign * moved[a];
  }
}

static double transfer_outflow(void *self, size_t comp) {
  return ((const transfer_t *)self)->k[comp];
}

const gs_mech_type gs_mech_feed = {
    .name = "feed",
    .summary = "particles fed into a compartment at a constant rate",
    .create = feed_create,
    .rates = feed_rates,
    .free = feed_free,
    .next_switch = feed_switch,
};
const gs_mech_type gs_mech_transfer = {
    .name = "transfer",
    .summary = "flow to the next compartment at rate k N; out of the last as product",
    .create = transfer_create,
    .rates = transfer_rates,
    .free = transfer_free,
    .outflow_rate = transfer_outflow,
};
