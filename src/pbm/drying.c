/* Per-granule drying rates; see drying.h.
 *
 * Chaudhury (2015) eq. 2.19 gives the bed's evaporation
 *     m_evap = gamma A_wet k_mass rho_air (x_sat(T_bed) - x_air)
 * with A_wet = eta A_p (eq. 2.20) and k_mass = 2 D_water / D (a Sherwood
 * number of 2).  Applied granule by granule (A_p = sum N pi d^2, the bed
 * area eq. 2.21 lumps), a granule of diameter d loses liquid volume at
 *     E(d) = gamma eta 2 pi D_water d rho_air (x_sat - x_air) / rho_liquid,
 * d = (6 V / pi)^(1/3) from the granule volume used for sizes (grid.size_axes).
 * The bed temperature and the air's humidity are either fixed keys or, with
 * `bed`, set by the quasi-steady humidity and heat balances of the bed
 * (gs_bed_solve); the balances' accumulation terms are not integrated yet
 * (docs/models.md). */
#include <math.h>
#include <stdlib.h>

#include "pbm/drying.h"

double gs_vapour_pressure(double T) {
  /* Buck (1996) over liquid water: p = 611.21 exp((18.678 - theta/234.5) theta/(257.14 + theta)) Pa,
   * theta in C; within 0.05 % of the steam tables from 0 to 100 C */
  const double theta = T - 273.15;
  return 611.21 * exp((18.678 - theta / 234.5) * theta / (257.14 + theta));
}

double gs_saturation_humidity(double T, double P) {
  const double p = gs_vapour_pressure(T);
  return 0.621945 * p / (P - p); /* 0.621945 = M_water / M_air */
}

/* The heat balance's residual at bed temperature T (W): what the air brings
 * minus evaporation and losses (eqs. 2.24-2.25 with dT/dt = dx/dt = 0);
 * decreasing in T.  *x, *evap: the outlet humidity and evaporation there. */
static double heat_residual(const gs_bed *b, double K, double T, double *x, double *evap) {
  const double xs = gs_saturation_humidity(T, b->P);
  /* humidity balance, eq. 2.18 at steady state: air (x - xin) = K (xs - x) */
  const double gap = fmax(xs - b->xin, 0.0); /* no condensation */
  *evap = b->air * K * gap / (b->air + K);  /* = K (xs - x), without its cancellation when K >> air */
  *x = b->xin + *evap / b->air;
  const double g1 = b->air * (b->cpa * (b->Tin - T) +
                              b->cpv * (b->xin * (b->Tin - b->Tref) - *x * (T - b->Tref)));
  return g1 - *evap * b->dH - b->loss;
}

double gs_bed_solve(const gs_bed *b, double wet, double *T, double *x) {
  const double K = b->k0 * wet;
  double lo = 274.15, hi = b->Tin, evap;
  if (heat_residual(b, K, lo, x, &evap) <= 0) { /* losses beyond what the air brings: the bed's floor */
    *T = lo;
    return evap;
  }
  /* bisection to the last bit: deterministic, and the residual is monotone */
  for (int i = 0; i < 200; i++) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;
    if (heat_residual(b, K, mid, x, &evap) > 0) lo = mid;
    else hi = mid;
  }
  *T = lo;
  heat_residual(b, K, lo, x, &evap); /* *x and the evaporation at the root */
  return evap;
}

int gs_bed_rates(const gs_bed *b, size_t ncells, const double *N, int hold, double *drive,
                 double *G) {
  if (!hold || isnan(*drive)) {
    double wet = 0, T, x;
    for (size_t c = 0; c < ncells; c++) wet += N[c] * b->d[c];
    *drive = 0;
    if (wet > 0) {
      gs_bed_solve(b, wet, &T, &x);
      *drive = fmax(gs_saturation_humidity(T, b->P) - x, 0.0);
    }
  }
  if (!(*drive > 0)) return 0;
  const double k = b->k0 * *drive / b->rho_l;
  for (size_t c = 0; c < ncells; c++) G[c] = -k * b->d[c];
  return 1;
}

void gs_bed_free(gs_bed *b) {
  if (b) free(b->d);
  free(b);
}

int gs_drying_transfer_read(gs_cfg_node *node, double *k0, double *rho_l, double *P, gs_error *err) {
  double gamma, eta, Dw, rho_air;
  int rc = gs_cfg_double_range(node, "correction", 0, 1, 0, 1, 1e3, 0, &gamma, err);
  if (!rc) rc = gs_cfg_double_range(node, "wetted_fraction", 0, 1, 0, 1, 1, 0, &eta, err);
  if (!rc) rc = gs_cfg_double_range(node, "diffusivity", 0, 2.6e-5, 0, 1, 1e-3, 0, &Dw, err);
  if (!rc) rc = gs_cfg_double_range(node, "air_density", 0, 1.18, 0, 1, 100, 0, &rho_air, err);
  if (!rc) rc = gs_cfg_double_range(node, "liquid_density", 0, 1000, 0, 1, 1e5, 0, rho_l, err);
  if (!rc) rc = gs_cfg_double_range(node, "pressure", 0, 101325, 1e3, 0, 1e7, 0, P, err);
  *k0 = gamma * eta * 2 * M_PI * Dw * rho_air;
  return rc;
}

double *gs_drying_diameters(const gs_model *m, int liquid, gs_error *err) {
  const gs_grid *g = &m->grid;
  double *d = gs_malloc(g->ncells * sizeof(double), err);
  if (!d) return NULL;
  /* granules at the first liquid pivot cannot lose liquid in the upwind
   * scheme: they take no part in the bed's evaporation either */
  const size_t n = g->axis[liquid].n, stride = g->stride[liquid];
  for (size_t c = 0; c < g->ncells; c++)
    d[c] = (c / stride) % n == 0 ? 0.0 : cbrt(6 * m->size_volume[c] / M_PI);
  return d;
}

static int read_bed(gs_cfg_node *node, const gs_model *m, int liquid, gs_bed *b, gs_error *err) {
  int rc = gs_cfg_double_range(node, "inlet_temperature", 1, 0, 274.15, 0, 473.15, 0, &b->Tin, err);
  if (!rc) rc = gs_cfg_double_range(node, "inlet_humidity", 1, 0, 0, 0, 0.5, 0, &b->xin, err);
  if (!rc) rc = gs_cfg_double_range(node, "air_flow", 1, 0, 0, 1, 1e4, 0, &b->air, err);
  if (!rc) rc = gs_cfg_double_range(node, "heat_loss", 0, 0, 0, 0, 1e9, 0, &b->loss, err);
  if (!rc) rc = gs_cfg_double_range(node, "spray_temperature", 0, 293.15, 274.15, 0, 373.15, 0, &b->Tref, err);
  if (!rc) rc = gs_cfg_double_range(node, "latent_heat", 0, 2.27e6, 0, 1, 1e8, 0, &b->dH, err);
  if (!rc) rc = gs_cfg_double_range(node, "air_heat_capacity", 0, 1006, 0, 1, 1e5, 0, &b->cpa, err);
  if (!rc) rc = gs_cfg_double_range(node, "vapour_heat_capacity", 0, 1996, 0, 1, 1e5, 0, &b->cpv, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) return rc;
  b->d = gs_drying_diameters(m, liquid, err);
  return b->d ? GS_OK : GS_ENOMEM;
}

int gs_drying_read(gs_cfg_node *node, const gs_model *m, int liquid, double *G, gs_bed **bed,
                   gs_error *err) {
  double T = 0, x = 0, rho_l, P;
  gs_cfg_node *bn = gs_cfg_get(node, "bed");
  *bed = NULL;
  int rc = GS_OK;
  if (bn && (gs_cfg_get(node, "bed_temperature") || gs_cfg_get(node, "air_humidity")))
    return gs_cfg_fail(bn, err, "bed: give either 'bed' (inlet air; the bed's balances set its temperature "
                                "and humidity) or 'bed_temperature' and 'air_humidity', not both");
  if (!bn) {
    rc = gs_cfg_double_range(node, "bed_temperature", 1, 0, 274.15, 0, 373.15, 0, &T, err);
    if (!rc) rc = gs_cfg_double_range(node, "air_humidity", 1, 0, 0, 0, 0.5, 0, &x, err);
  }
  double k0;
  if (!rc) rc = gs_drying_transfer_read(node, &k0, &rho_l, &P, err);
  if (rc) return rc;
  if (bn) {
    gs_bed *b = gs_calloc(1, sizeof *b, err);
    if (!b) return GS_ENOMEM;
    *b = (gs_bed){.P = P, .k0 = k0, .rho_l = rho_l};
    rc = gs_cfg_require_kind(bn, GS_CFG_MAP, err);
    if (!rc) rc = read_bed(bn, m, liquid, b, err);
    if (rc) {
      gs_bed_free(b);
      return rc;
    }
    *bed = b;
    return GS_OK;
  }
  const double xsat = gs_saturation_humidity(T, P);
  if (!(xsat > x))
    return gs_cfg_fail(gs_cfg_get(node, "air_humidity"), err,
                       "air_humidity: at or above saturation (%g kg/kg at bed_temperature %g K): no drying", xsat, T);
  const double k = k0 * (xsat - x) / rho_l;
  for (size_t c = 0; c < m->grid.ncells; c++) G[c] = -k * cbrt(6 * m->size_volume[c] / M_PI);
  return GS_OK;
}
