/* Layering of fines onto granules (Chaudhury 2015, eq. 2.14; Wang et al. 2006):
 * every granule's solid grows along one solid axis at
 *     G = G_max · M_p / (k_layer · M + M_p) · exp(-alpha (x_w - x_wc)^2),
 * M_p the fines' solid and M all the solid of the compartment (volumes along
 * the axis: one solid density, so the ratio of masses is that of volumes),
 * x_w = l / s the granule's liquid-to-solid volume ratio.  Moved with the
 * upwind pivot transfer of growth_scheme.h, so the solid the granules gain
 * is sum G N exactly.
 *
 * Where the layered solid comes from (the thesis leaves it open, its §7
 * item 7): `source: fines` takes it from the fines cells of the same
 * compartment (pivot along the axis <= fines_max), each losing particles at
 * rate (sum G N / M_p) N_c, so the compartment's solid is conserved to
 * round-off (the growth books +sum G N, the fines -sum G N; fines' other
 * coordinates are booked as leaving).  As the fines run out M_p -> 0 and
 * the rate with it: smoothly, for k_layer > 0.  `source: external` takes it
 * from a powder feed outside the model: the Monod factor is 1 and the
 * solid is booked as coming in (this is growth at the rate law of eq. 2.14,
 * and at alpha = 0 growth at constant rate G_max). */
#include <math.h>
#include <stdlib.h>

#include "gransim/pbm.h"
#include "pbm/fines.h"
#include "pbm/growth_scheme.h"

typedef struct {
  int axis, from_fines;
  double k, start, end;
  gs_fines fines;   /* from_fines: the source cells */
  double *base;     /* ncells: G_max · moisture factor; 0 for fines (they are the powder) */
  double *G;        /* rows of this compartment's rates, one per scratch slot */
  size_t row_len;
  double *work;     /* preconditioner: 2 * cells along the axis */
} layer_t;

static void layer_free(void *self) {
  layer_t *L = self;
  if (!L) return;
  gs_fines_free(&L->fines);
  free(L->base);
  free(L->G);
  free(L->work);
  free(L);
}

static int layer_read(gs_cfg_node *node, const gs_model *m, layer_t *L, gs_error *err) {
  static const char *const sources[] = {"external", "fines", NULL};
  const gs_grid *g = &m->grid;
  double gmax, alpha, xwc, fmax;
  int liquid = -1;
  if (m->ncarried > 0) /* particles moving between cells would leave their load behind */
    return gs_cfg_fail(node, err, "layering grows along an axis and cannot be combined with carried "
                                  "quantities (grid.carried)");
  int rc = gs_growth_axis_key(node, g, "axis", gs_grid_axis_by_name(g, "solid") >= 0 ? "solid" : NULL,
                              &L->axis, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "source", sources, 1, &L->from_fines, err);
  if (!rc) rc = gs_cfg_double_range(node, "max_rate", 1, 0, 0, 0, HUGE_VAL, 0, &gmax, err);
  if (!rc && L->from_fines) {
    rc = gs_cfg_double_range(node, "fines_max", 1, 0, 0, 0, HUGE_VAL, 0, &fmax, err);
    if (!rc) rc = gs_cfg_double_range(node, "k_layer", 0, 1, 0, 1, HUGE_VAL, 0, &L->k, err);
    if (!rc) rc = gs_fines_init(&L->fines, g, L->axis, fmax, node, "fines_max", err);
  } else if (!rc) { /* an external powder: optionally the smallest cells do not layer */
    rc = gs_cfg_double_range(node, "fines_max", 0, -HUGE_VAL, -HUGE_VAL, 0, HUGE_VAL, 0, &fmax, err);
  }
  if (!rc) rc = gs_cfg_double_range(node, "moisture_width", 0, 0, 0, 0, HUGE_VAL, 0, &alpha, err);
  if (!rc) rc = gs_cfg_double_range(node, "critical_moisture", 0, 0, 0, 0, HUGE_VAL, 0, &xwc, err);
  if (!rc && alpha > 0)
    rc = gs_growth_axis_key(node, g, "liquid_axis", "liquid", &liquid, err);
  if (!rc) rc = gs_mech_read_window(node, &L->start, &L->end, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) return rc;
  L->base = gs_malloc(g->ncells * sizeof(double), err);
  if (!L->base) return GS_ENOMEM;
  for (size_t c = 0; c < g->ncells; c++) {
    const double *x = g->x + c * (size_t)g->dim, s = x[L->axis];
    double xw = liquid >= 0 && s > 0 ? x[liquid] / s : 0.0;
    L->base[c] = s <= fmax ? 0.0 : gmax * exp(-alpha * (xw - xwc) * (xw - xwc));
  }
  return GS_OK;
}

static int layer_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  const gs_grid *g = &m->grid;
  layer_t *L = gs_calloc(1, sizeof *L, err);
  if (!L) return GS_ENOMEM;
  int rc = layer_read(node, m, L, err);
  /* the rates are recomputed per compartment: one row per slot, on pages
   * of their own as threads write them at once */
  const size_t rows = m->nslots > 1 ? (size_t)m->nslots : 1;
  L->row_len = rows > 1 ? gs_doubles_apart(g->ncells) : g->ncells;
  if (!rc) {
    L->G = rows > 1 ? gs_calloc_apart(rows * L->row_len * sizeof(double), err)
                    : gs_calloc(g->ncells, sizeof(double), err);
    L->work = gs_malloc(2 * g->axis[L->axis].n * sizeof(double), err);
    if (!L->G || !L->work) rc = GS_ENOMEM;
  }
  if (rc) {
    layer_free(L);
    return rc;
  }
  *self = L;
  return GS_OK;
}

/* Compartment comp's rates in this caller's row, and in *take the rate
 * coefficient at which the fines are consumed; NULL when nothing layers. */
static const double *layer_rates(layer_t *L, const gs_model *m, const gs_eval *ev, const double *N,
                                 double *take) {
  const gs_grid *g = &m->grid;
  double f = 1, den = 1;
  *take = 0;
  if (L->from_fines) {
    double fine, total;
    gs_fines_volumes(&L->fines, g, N, &fine, &total);
    den = L->k * total + fine;
    if (!(fine > 0) || !(den > 0)) return NULL; /* no powder left to layer */
    f = fine / den;
  }
  double *G = L->G + (ev->slot > 0 ? (size_t)ev->slot : 0) * L->row_len, layered = 0;
  for (size_t c = 0; c < g->ncells; c++) {
    G[c] = f * L->base[c];
    layered += L->base[c] * N[c];
  }
  /* fines taken at (sum G N / M_p) N_c = (sum base N / den) N_c: finite as M_p -> 0 */
  if (L->from_fines) *take = layered / den;
  return G;
}

static void layer_rhs(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                      const double *y, double *dydt, double *dledger) {
  layer_t *L = self;
  if (!gs_window_on(ev, L->start, L->end, t)) return;
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  double take;
  const double *G = layer_rates(L, m, ev, N, &take);
  if (!G) return;
  double *ledger = gs_eval_ledger(m, ev, dledger, comp);
  gs_growth_apply(&m->grid, L->axis, G, N, gs_eval_numbers(m, ev, dydt, comp), ledger,
                  ledger + m->nvol);
  gs_fines_take(&L->fines, m, ev, comp, y, take, dydt, dledger);
}

/* The growth part's exact inverse with the rates frozen at y (the fines'
 * sink and the Monod factor's dependence on y are left to the Krylov
 * iterations). */
static void layer_precondition(void *self, const gs_model *m, const gs_eval *ev, size_t comp,
                               double t, const double *y, double gamma, double *z, double *zledger) {
  layer_t *L = self;
  if (!gs_window_on(ev, L->start, L->end, t)) return;
  double take;
  const double *G = layer_rates(L, m, ev, gs_eval_numbers_c(m, ev, y, comp), &take);
  if (G)
    gs_growth_solve(&m->grid, L->axis, G, gamma, gs_eval_numbers(m, ev, z, comp), zledger,
                    zledger + m->nvol, L->work);
}

static double layer_switch(void *self, double t) {
  const layer_t *L = self;
  return gs_window_next_switch(L->start, L->end, t);
}

const gs_mech_type gs_mech_layering = {
    .name = "layering",
    .summary = "layering of fines onto granules along a solid axis (Chaudhury 2015, eq. 2.14)",
    .create = layer_create,
    .rates = layer_rhs,
    .free = layer_free,
    .precondition = layer_precondition,
    .next_switch = layer_switch,
};
