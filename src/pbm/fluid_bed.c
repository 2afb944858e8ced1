/* Mechanism `fluid_bed`: a batch fluid bed's air and heat balances as ODE
 * state beside the population balance (Chaudhury 2015, eqs. 2.16-2.28),
 * with the granules' liquid evaporating by its driving force (eq. 2.19,
 * granule by granule as `drying`, drying.c).
 *
 * State per compartment (gs_eval_scalars), the bed being well mixed (one
 * temperature T for solid, liquid and air, the outlet air's):
 *   H  the enthalpy of the bed's contents, J, relative to liquid water,
 *      solid and dry air at T_ref:  H = C (T - T_ref) + W dH_vap,
 *      C = m_s c_s + m_l c_l + M_air c_air + W c_vap
 *   W  the water vapour in the bed's air, kg (outlet humidity x = W/M_air)
 * and the integrals of the flows that change them, so that
 *   W - W0 = vapour in - vapour out + evaporated
 *   H - H0 = heat in - heat out - heat lost
 * hold to round-off (checked at every output time, like the volume ledger).
 * m_s and m_l are the population's solid and liquid masses (its axes), so
 * sprayed liquid enters at T_ref with no enthalpy and evaporation moves
 * water from the granules into W at no change of H: T follows from H
 * algebraically.  Derivation and the thesis's misprints: docs/models.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"
#include "pbm/drying.h"
#include "pbm/growth_scheme.h"
#include "pbm/schedule.h"

enum { S_H, S_W, S_EVAP, S_VIN, S_VOUT, S_QIN, S_QOUT, S_QLOST, NSCALAR };

enum { P_T, P_X, P_FLOW }; /* a phase's values: inlet temperature, humidity, dry air flow */

typedef struct {
  int liquid;
  double rho_s, rho_l, cs, cl, ca, cv, dH, Tref, P, k0;
  double Mair, loss, UA, Tamb, T0, x0;
  gs_schedule air; /* inlet air phases */
  double *d;     /* ncells: diameter of the granules that dry (0 at the first liquid pivot) */
  double *svol;  /* ncells: solid volume of the cell's granules */
  double *G;     /* rows of per-cell rates, one per slot (gs_eval.slot) */
  size_t row_len;
  size_t first;  /* its first scalar */
  double *init;  /* ncomp * 2: H0 and W0 */
} bed_t;

static void bed_free(void *self) {
  bed_t *B = self;
  if (!B) return;
  gs_schedule_free(&B->air);
  free(B->d);
  free(B->svol);
  free(B->G);
  free(B->init);
  free(B);
}

/* Vapour pressure capped below the total pressure: at and above the boiling
 * point the air's capacity is then large but finite, and evaporation is
 * limited by the mass transfer (Buck's equation is for 0-100 C). */
static double x_sat(const bed_t *B, double T) {
  const double p = fmin(gs_vapour_pressure(T), 0.99 * B->P);
  return 0.621945 * p / (B->P - p);
}

/* What one compartment's state says: solid and liquid masses, T, x. */
typedef struct {
  double ms, ml, C, T, x, wet; /* wet = sum N d over the granules that dry */
} bed_view;

static bed_view view_of(const bed_t *B, const gs_grid *g, const double *N, const double *s) {
  bed_view v = {0};
  const int dim = g->dim;
  for (size_t c = 0; c < g->ncells; c++) {
    if (N[c] == 0.0) continue;
    v.ms += N[c] * B->svol[c];
    v.ml += N[c] * g->x[c * (size_t)dim + (size_t)B->liquid];
    v.wet += N[c] * B->d[c];
  }
  v.ms *= B->rho_s;
  v.ml *= B->rho_l;
  const double W = s[S_W];
  v.C = v.ms * B->cs + v.ml * B->cl + B->Mair * B->ca + W * B->cv;
  v.T = B->Tref + (s[S_H] - W * B->dH) / v.C;
  v.x = W / B->Mair;
  return v;
}

static void bed_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                      const double *y, double *dydt, double *dledger) {
  bed_t *B = self;
  const gs_grid *g = &m->grid;
  const double *N = gs_eval_numbers_c(m, ev, y, comp);
  const double *s = gs_eval_scalars_c(m, ev, y, comp) + B->first;
  double *ds = gs_eval_scalars(m, ev, dydt, comp) + B->first;
  const bed_view v = view_of(B, g, N, s);
  /* evaporation by the driving force x_sat(T) - x (none into saturated air:
   * the model has no condensation) */
  const double drive = fmax(x_sat(B, v.T) - v.x, 0.0);
  double evap = 0;
  if (drive > 0 && v.wet > 0) {
    double *G = B->G + (ev->slot > 0 ? (size_t)ev->slot : 0) * B->row_len;
    const double k = B->k0 * drive / B->rho_l;
    double vol = 0; /* the liquid volume the scheme removes: sum G N, in its order */
    for (size_t c = 0; c < g->ncells; c++) {
      G[c] = -k * B->d[c];
      if (G[c] != 0.0 && N[c] != 0.0) vol -= G[c] * N[c];
    }
    double *led = gs_eval_ledger(m, ev, dledger, comp);
    gs_growth_apply(g, B->liquid, G, N, gs_eval_numbers(m, ev, dydt, comp), led, led + m->nvol);
    evap = B->rho_l * vol;
  }
  const gs_phase *ph = gs_schedule_at(&B->air, ev, t);
  const double air = ph ? ph->value[P_FLOW] : 0, Tin = ph ? ph->value[P_T] : B->Tref;
  const double xin = ph ? ph->value[P_X] : 0;
  const double hin = air * (B->ca * (Tin - B->Tref) + xin * (B->dH + B->cv * (Tin - B->Tref)));
  const double hout = air * (B->ca * (v.T - B->Tref) + v.x * (B->dH + B->cv * (v.T - B->Tref)));
  const double lost = B->loss + B->UA * (v.T - B->Tamb);
  ds[S_H] += hin - hout - lost;
  ds[S_W] += air * (xin - v.x) + evap;
  ds[S_EVAP] += evap;
  ds[S_VIN] += air * xin;
  ds[S_VOUT] += air * v.x;
  ds[S_QIN] += hin;
  ds[S_QOUT] += hout;
  ds[S_QLOST] += lost;
}

static int bed_nscalars(void *self) {
  (void)self;
  return NSCALAR;
}

static void bed_initial(void *self, const gs_model *m, size_t comp, const double *y, double *s,
                        double *accuracy) {
  bed_t *B = self;
  const double W = B->x0 * B->Mair;
  double zero[NSCALAR] = {0};
  zero[S_W] = W;
  bed_view v = view_of(B, &m->grid, gs_model_numbers_c(m, y, comp), zero);
  s[S_W] = W;
  s[S_H] = v.C * (B->T0 - B->Tref) + W * B->dH;
  B->init[2 * comp] = s[S_H];
  B->init[2 * comp + 1] = W;
  /* temperatures to 1 uK, humidities to 1e-10 kg/kg: far below what the
   * balances' inputs are known to, far above round-off */
  const double energy = 1e-6 * v.C, water = 1e-10 * B->Mair;
  const double acc[NSCALAR] = {energy, water, water, water, water, energy, energy, energy};
  memcpy(accuracy, acc, sizeof acc);
}

static const gs_mech_column columns[] = {
    {"bed_temperature", "K"},   {"outlet_humidity", "kg/kg"}, {"moisture", "kg/kg"},
    {"evaporation_rate", "kg/s"}, {"evaporated", "kg"},        {"vapour_out", "kg"},
    {"inlet_temperature", "K"}, {"air_flow", "kg/s"},         {NULL, NULL}};

static void bed_report(void *self, const gs_model *m, size_t comp, double t, const double *y,
                       double *out) {
  const bed_t *B = self;
  const gs_grid *g = &m->grid;
  const double *N = gs_model_numbers_c(m, y, comp);
  const double *s = gs_model_scalars_c(m, y, comp) + B->first;
  const bed_view v = view_of(B, g, N, s);
  const double drive = fmax(x_sat(B, v.T) - v.x, 0.0);
  const gs_phase *ph = gs_schedule_at(&B->air, NULL, t);
  out[0] = v.T;
  out[1] = v.x;
  out[2] = v.ms > 0 ? v.ml / v.ms : NAN;
  out[3] = B->k0 * drive * v.wet;
  out[4] = s[S_EVAP];
  out[5] = s[S_VOUT] - s[S_VIN]; /* net: what the air took out of the bed */
  out[6] = ph ? ph->value[P_T] : NAN;
  out[7] = ph ? ph->value[P_FLOW] : 0;
}

static double bed_balance(void *self, const gs_model *m, size_t comp, const double *y, char *msg,
                          size_t n) {
  const bed_t *B = self;
  const double *s = gs_model_scalars_c(m, y, comp) + B->first;
  const double H0 = B->init[2 * comp], W0 = B->init[2 * comp + 1];
  const double w_expect = W0 + s[S_VIN] - s[S_VOUT] + s[S_EVAP];
  const double w_scale = W0 + fabs(s[S_W]) + s[S_VIN] + s[S_VOUT] + s[S_EVAP];
  const double h_expect = H0 + s[S_QIN] - s[S_QOUT] - s[S_QLOST];
  const double h_scale = fabs(H0) + fabs(s[S_H]) + s[S_QIN] + s[S_QOUT] + fabs(s[S_QLOST]);
  const double ew = w_scale > 0 ? fabs(s[S_W] - w_expect) / w_scale : 0;
  const double eh = h_scale > 0 ? fabs(s[S_H] - h_expect) / h_scale : 0;
  if (!(ew <= eh))
    snprintf(msg, n, "water balance of the bed's air broken: vapour %.12g kg, expected %.12g "
             "(initial + in - out + evaporated)", s[S_W], w_expect);
  else
    snprintf(msg, n, "energy balance of the bed broken: enthalpy %.12g J, expected %.12g "
             "(initial + in - out - lost)", s[S_H], h_expect);
  return isnan(ew) || isnan(eh) ? NAN : fmax(ew, eh);
}

static double bed_switch(void *self, double t) {
  const bed_t *B = self;
  return gs_schedule_next_switch(&B->air, t);
}

/* The inlet air's phases; air above saturation is refused (no such air).
 * 274.15-473.15 K: liquid water in the bed, and the hottest inlet air of
 * pharmaceutical fluid beds with margin. */
static int read_air(gs_cfg_node *node, bed_t *B, gs_error *err) {
  static const gs_phase_key keys[] = {{"temperature", 1, 0, 274.15, 473.15},
                                      {"humidity", 1, 0, 0, 0.5},
                                      {"air_flow", 1, 0, 0, 1e4}};
  gs_cfg_node *list = gs_cfg_get(node, "air");
  if (!list)
    return gs_cfg_missing(node, "air", "(a list of inlet air phases {start, end, temperature, humidity, air_flow})", err);
  int rc = gs_schedule_read(list, keys, 3, &B->air, err);
  for (size_t i = 0; !rc && i < B->air.n; i++) {
    const double *v = B->air.phase[i].value;
    if (!(v[P_X] < x_sat(B, v[P_T])))
      rc = gs_cfg_fail(gs_cfg_get(gs_cfg_item(list, i), "humidity"), err,
                       "inlet air at %g K holds at most %.4g kg water / kg dry air (saturation at "
                       "pressure %g Pa), not %g", v[P_T], x_sat(B, v[P_T]), B->P, v[P_X]);
  }
  return rc;
}

static int bed_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  const gs_grid *g = &m->grid;
  bed_t *B = gs_calloc(1, sizeof *B, err);
  if (!B) return GS_ENOMEM;
  B->first = m->nscalar;
  int rc = GS_OK;
  /* one bed per compartment, and it does the evaporation itself */
  for (size_t i = 0; !rc && i < m->nmech; i++)
    if (!strcmp(m->mech[i].type->name, "fluid_bed") || !strcmp(m->mech[i].type->name, "drying"))
      rc = gs_cfg_fail(node, err, "a case takes one fluid_bed, which evaporates the granules' liquid "
                                  "itself: not with %s (%s)", m->mech[i].type->name, m->mech[i].label);
  if (!rc) rc = gs_growth_axis_key(node, g, "liquid_axis", "liquid", &B->liquid, err);
  if (!rc && m->ncarried > 0)
    rc = gs_cfg_fail(node, err, "fluid_bed dries the liquid along a grid axis; it cannot be combined "
                                "with carried quantities (grid.carried)");
  if (!rc) rc = gs_drying_transfer_read(node, &B->k0, &B->rho_l, &B->P, err);
  if (!rc) rc = gs_cfg_double_range(node, "solid_density", 1, 0, 0, 1, 1e5, 0, &B->rho_s, err);
  if (!rc) rc = gs_cfg_double_range(node, "solid_heat_capacity", 0, 1000, 0, 1, 1e5, 0, &B->cs, err);
  if (!rc) rc = gs_cfg_double_range(node, "liquid_heat_capacity", 0, 4187, 0, 1, 1e5, 0, &B->cl, err);
  if (!rc) rc = gs_cfg_double_range(node, "air_heat_capacity", 0, 1006, 0, 1, 1e5, 0, &B->ca, err);
  if (!rc) rc = gs_cfg_double_range(node, "vapour_heat_capacity", 0, 1996, 0, 1, 1e5, 0, &B->cv, err);
  if (!rc) rc = gs_cfg_double_range(node, "latent_heat", 0, 2.27e6, 0, 1, 1e8, 0, &B->dH, err);
  if (!rc) rc = gs_cfg_double_range(node, "spray_temperature", 0, 293.15, 274.15, 0, 373.15, 0, &B->Tref, err);
  if (!rc) rc = gs_cfg_double_range(node, "air_mass", 1, 0, 0, 1, 1e4, 0, &B->Mair, err);
  if (!rc) rc = gs_cfg_double_range(node, "heat_loss", 0, 0, 0, 0, 1e9, 0, &B->loss, err);
  if (!rc) rc = gs_cfg_double_range(node, "wall_coefficient", 0, 0, 0, 0, 1e9, 0, &B->UA, err);
  if (!rc) rc = gs_cfg_double_range(node, "ambient_temperature", 0, 293.15, 200, 0, 473.15, 0, &B->Tamb, err);
  if (!rc) rc = read_air(node, B, err);
  if (!rc) rc = gs_cfg_double_range(node, "initial_temperature", 0, B->air.phase[0].value[P_T], 274.15, 0, 473.15, 0, &B->T0, err);
  if (!rc) rc = gs_cfg_double_range(node, "initial_humidity", 0, B->air.phase[0].value[P_X], 0, 0, 0.5, 0, &B->x0, err);
  if (!rc && !(B->x0 < x_sat(B, B->T0)))
    rc = gs_cfg_fail(gs_cfg_get(node, "initial_humidity") ? gs_cfg_get(node, "initial_humidity") : node, err,
                     "initial_humidity %g is at or above saturation (%.4g kg/kg at initial_temperature %g K)",
                     B->x0, x_sat(B, B->T0), B->T0);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (!rc && !(B->d = gs_drying_diameters(m, B->liquid, err))) rc = GS_ENOMEM;
  if (!rc && !(B->svol = gs_calloc(g->ncells, sizeof(double), err))) rc = GS_ENOMEM;
  if (!rc && !(B->init = gs_calloc(2 * g->ncomp, sizeof(double), err))) rc = GS_ENOMEM;
  const size_t rows = m->nslots > 1 ? (size_t)m->nslots : 1;
  B->row_len = rows > 1 ? gs_doubles_apart(g->ncells) : g->ncells;
  if (!rc && !(B->G = rows > 1 ? gs_calloc_apart(rows * B->row_len * sizeof(double), err)
                               : gs_calloc(g->ncells, sizeof(double), err)))
    rc = GS_ENOMEM;
  if (rc) {
    bed_free(B);
    return rc;
  }
  /* the solid: every axis but the liquid and one named gas */
  const int gas = gs_grid_axis_by_name(g, "gas");
  for (size_t c = 0; c < g->ncells; c++)
    for (int k = 0; k < g->dim; k++)
      if (k != B->liquid && k != gas) B->svol[c] += g->x[c * (size_t)g->dim + (size_t)k];
  *self = B;
  return GS_OK;
}

const gs_mech_type gs_mech_fluid_bed = {
    .name = "fluid_bed",
    .summary = "batch fluid bed: the air's vapour and the bed's enthalpy as state, evaporation by its driving force, inlet air phases (Chaudhury 2015, eqs. 2.16-2.28)",
    .create = bed_create,
    .rates = bed_rates,
    .free = bed_free,
    .next_switch = bed_switch,
    .nscalars = bed_nscalars,
    .initial = bed_initial,
    .columns = columns,
    .report = bed_report,
    .balance = bed_balance,
};
