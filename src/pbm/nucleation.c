/* Nucleation from the spray in the drop-controlled regime: every droplet
 * that lands forms one nucleus holding the droplet's liquid and the solid
 * it wets.  A droplet of diameter d_d holds V_d = pi d_d^3 / 6 of liquid;
 * its nucleus holds l_n = V_d, s_n = V_d / R of solid (R the nucleus
 * liquid-to-solid volume ratio) and, given a nucleus porosity e, the gas
 * g_n = e s_n / (1 - e) - l_n that fills the rest of its pores.  The spray
 * Q (liquid volume per unit time) makes Q / V_d droplets per unit time.
 *
 * Nuclei are placed at the point (s_n, l_n, g_n) by the lever rule, which
 * conserves their number and every volume: on a grid with a pivot there
 * they all land in that cell.  The liquid is the spray's, booked as coming
 * in.  The solid (`source`):
 *   external: a powder outside the model, booked as coming in;
 *   fines:    the fines of the same compartment (pivot along the solid axis
 *             <= fines_max).  A droplet forms a nucleus where it lands on
 *             fines, so with the spray shared in proportion to solid volume
 *             (as `spray` and `liquid_addition` share it) the nucleation
 *             rate is (Q / V_d) M_p / M, and the fines are taken at rate
 *             (Q s_n / (V_d M)) N_c, exactly the solid the nuclei receive:
 *             the compartment's solid is conserved to round-off.  The
 *             droplets landing on granules are not this mechanism's: spray
 *             them with `spray` or `liquid_addition`. */
#include <math.h>
#include <stdlib.h>

#include "gransim/pbm.h"
#include "pbm/fines.h"
#include "pbm/growth_scheme.h"
#include "pbm/lever.h"

typedef struct {
  int from_fines, solid;
  double *q;                   /* spray rate per compartment */
  double start, end, vdrop;
  gs_fines fines;
  double *place;               /* ncells: share of the nuclei per cell (sum 1) */
  double *qplace[GS_MAX_CARRIED]; /* ncells: carried volume per nucleus formed, per cell */
  double vol[GS_MAX_VOL];      /* volume of each coordinate per nucleus, as placed */
} nuc_t;

static void nuc_free(void *self) {
  nuc_t *U = self;
  if (!U) return;
  gs_fines_free(&U->fines);
  free(U->q);
  free(U->place);
  for (int q = 0; q < GS_MAX_CARRIED; q++) free(U->qplace[q]);
  free(U);
}

/* The coordinate named `name` (key `key`): axis k (*axis) or carried q
 * (*carried), or neither (-1, -1); an error if the key was given and names
 * neither. */
static int coordinate(gs_cfg_node *node, const gs_model *m, const char *key, const char *def,
                      int *axis, int *carried, gs_error *err) {
  const char *name;
  int rc = gs_cfg_string_opt(node, key, def, &name, err);
  if (rc) return rc;
  *axis = gs_grid_axis_by_name(&m->grid, name);
  *carried = gs_model_carried_index(m, name);
  if (*axis < 0 && *carried < 0 && gs_cfg_get(node, key))
    return gs_cfg_fail(gs_cfg_get(node, key), err, "expected a grid axis or a carried quantity");
  return GS_OK;
}

/* The nucleus (v on the axes, load[] carried per nucleus) from the keys. */
static int nucleus(gs_cfg_node *node, const gs_model *m, nuc_t *U, double *v, double *load,
                   gs_error *err) {
  const gs_grid *g = &m->grid;
  double d, ratio, eps;
  int la, lq, ga, gq;
  int rc = gs_cfg_double_range(node, "droplet_diameter", 1, 0, 1e-7, 0, 1e-2, 0, &d, err);
  if (!rc) rc = gs_cfg_double_range(node, "liquid_solid_ratio", 1, 0, 0, 1, 1e3, 0, &ratio, err);
  if (!rc) rc = gs_cfg_double_range(node, "porosity", 0, 0, 0, 1, 1, 1, &eps, err);
  if (!rc && !gs_cfg_get(node, "porosity")) eps = 0; /* no gas in the nuclei */
  if (!rc) rc = coordinate(node, m, "liquid", "liquid", &la, &lq, err);
  if (!rc && la < 0 && lq < 0)
    rc = gs_cfg_fail(node, err, "needs a liquid coordinate: a grid axis or carried quantity named 'liquid' (or set 'liquid')");
  if (!rc) rc = coordinate(node, m, "gas", "gas", &ga, &gq, err);
  if (rc) return rc;
  U->vdrop = M_PI * d * d * d / 6;
  const double s = U->vdrop / ratio, gas = eps > 0 ? eps * s / (1 - eps) - U->vdrop : 0.0;
  if (gas < 0)
    return gs_cfg_fail(gs_cfg_get(node, "porosity"), err,
                       "porosity: the droplet's liquid (%g) does not fit in the nucleus' pores (%g); raise "
                       "porosity or liquid_solid_ratio", U->vdrop, eps * s / (1 - eps));
  if (gas > 0 && ga < 0 && gq < 0)
    return gs_cfg_fail(gs_cfg_get(node, "porosity"), err, "porosity needs a gas coordinate (axis or carried 'gas')");
  for (int k = 0; k < g->dim; k++) v[k] = k == U->solid ? s : k == la ? U->vdrop : k == ga ? gas : 0.0;
  for (int q = 0; q < m->ncarried; q++) load[q] = q == lq ? U->vdrop : q == gq ? gas : 0.0;
  return GS_OK;
}

/* Lever weights of one nucleus, and the volumes they place. */
static int place_nucleus(gs_cfg_node *node, const gs_model *m, nuc_t *U, const double *v,
                         const double *load, gs_error *err) {
  const gs_grid *g = &m->grid;
  U->place = gs_calloc(g->ncells, sizeof(double), err);
  for (int q = 0; U->place && q < m->ncarried; q++)
    if (!(U->qplace[q] = gs_calloc(g->ncells, sizeof(double), err))) return GS_ENOMEM;
  if (!U->place) return GS_ENOMEM;
  if (gs_lever_place_carried(g, GS_NOWHERE, v, 1.0, U->place, NULL, m->ncarried, load, U->qplace) > 0)
    return gs_cfg_fail(gs_cfg_get(node, "droplet_diameter"), err,
                       "droplet_diameter: the nucleus (solid %g, liquid %g) lies outside the grid; "
                       "extend the axes or change droplet_diameter / liquid_solid_ratio", v[U->solid],
                       U->vdrop);
  for (size_t c = 0; c < g->ncells; c++)
    for (int k = 0; k < g->dim; k++) U->vol[k] += U->place[c] * g->x[c * (size_t)g->dim + (size_t)k];
  for (int q = 0; q < m->ncarried; q++)
    for (size_t c = 0; c < g->ncells; c++) U->vol[g->dim + q] += U->qplace[q][c];
  return GS_OK;
}

static int nuc_read(gs_cfg_node *node, const gs_model *m, nuc_t *U, gs_error *err) {
  static const char *const sources[] = {"external", "fines", NULL};
  const gs_grid *g = &m->grid;
  double v[GS_MAX_DIM], load[GS_MAX_CARRIED], fmax = 0;
  U->q = gs_malloc(g->ncomp * sizeof(double), err);
  if (!U->q) return GS_ENOMEM;
  int rc = gs_cfg_per_comp(node, "rate", 1, 0, 0, 0, g->ncomp, U->q, err);
  if (!rc) rc = gs_growth_axis_key(node, g, "solid_axis", gs_grid_axis_by_name(g, "solid") >= 0 ? "solid" : NULL,
                                   &U->solid, err);
  if (!rc) rc = gs_cfg_enum_opt(node, "source", sources, 1, &U->from_fines, err);
  if (!rc && U->from_fines) rc = gs_cfg_double_range(node, "fines_max", 1, 0, 0, 0, HUGE_VAL, 0, &fmax, err);
  if (!rc) rc = nucleus(node, m, U, v, load, err);
  if (!rc) rc = gs_mech_read_window(node, &U->start, &U->end, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (!rc) rc = place_nucleus(node, m, U, v, load, err);
  if (!rc && U->from_fines) rc = gs_fines_init(&U->fines, g, U->solid, fmax, node, "fines_max", err);
  if (!rc && U->from_fines && v[U->solid] <= fmax)
    rc = gs_cfg_fail(gs_cfg_get(node, "fines_max"), err, "fines_max: the nuclei (solid %g) would be fines themselves",
                     v[U->solid]);
  return rc;
}

static int nuc_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  nuc_t *U = gs_calloc(1, sizeof *U, err);
  if (!U) return GS_ENOMEM;
  int rc = nuc_read(node, m, U, err);
  if (rc) {
    nuc_free(U);
    return rc;
  }
  *self = U;
  return GS_OK;
}

static void nuc_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                      const double *y, double *dydt, double *dledger) {
  const nuc_t *U = self;
  if (!gs_window_on(ev, U->start, U->end, t) || U->q[comp] == 0.0) return;
  const gs_grid *g = &m->grid;
  double rate = U->q[comp] / U->vdrop, take = 0; /* nuclei per unit time */
  if (U->from_fines) {
    double fine, total;
    gs_fines_volumes(&U->fines, g, gs_eval_numbers_c(m, ev, y, comp), &fine, &total);
    if (!(fine > 0) || !(total > 0)) return;
    take = rate * U->vol[U->solid] / total; /* = nuclei's solid rate / M_p */
    rate *= fine / total;
  }
  double *dN = gs_eval_numbers(m, ev, dydt, comp), *ledger = gs_eval_ledger(m, ev, dledger, comp);
  for (size_t c = 0; c < g->ncells; c++) dN[c] += rate * U->place[c];
  for (int q = 0; q < m->ncarried; q++) {
    double *dQ = gs_eval_carried(m, ev, dydt, comp, q);
    for (size_t c = 0; U->vol[g->dim + q] != 0.0 && c < g->ncells; c++) dQ[c] += rate * U->qplace[q][c];
  }
  for (int k = 0; k < m->nvol; k++) ledger[k] += rate * U->vol[k];
  gs_fines_take(&U->fines, m, ev, comp, y, take, dydt, dledger);
}

static double nuc_switch(void *self, double t) {
  const nuc_t *U = self;
  return gs_window_next_switch(U->start, U->end, t);
}

const gs_mech_type gs_mech_nucleation = {
    .name = "nucleation",
    .summary = "drop-controlled nucleation from the spray: one nucleus per droplet, its solid from fines or a feed",
    .create = nuc_create,
    .rates = nuc_rates,
    .free = nuc_free,
    .next_switch = nuc_switch,
};
