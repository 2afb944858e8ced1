/* Per-granule drying rates; see drying.h.
 *
 * Chaudhury (2015) eq. 2.19 gives the bed's evaporation
 *     m_evap = gamma A_wet k_mass rho_air (x_sat(T_bed) - x_air)
 * with A_wet = eta A_p (eq. 2.20) and k_mass = 2 D_water / D (a Sherwood
 * number of 2).  Applied granule by granule (A_p = sum N pi d^2, the bed
 * area eq. 2.21 lumps), a granule of diameter d loses liquid volume at
 *     E(d) = gamma eta 2 pi D_water d rho_air (x_sat - x_air) / rho_liquid,
 * d = (6 V / pi)^(1/3) from the granule volume used for sizes (grid.size_axes).
 * Here the bed temperature and the air's humidity are fixed keys: the
 * lumped gas and bed balances (eqs. 2.16-2.28) are not integrated yet
 * (docs/models.md). */
#include <math.h>

#include "pbm/drying.h"

double gs_saturation_humidity(double T, double P) {
  /* Buck (1996) over liquid water: p = 611.21 exp((18.678 - theta/234.5) theta/(257.14 + theta)) Pa,
   * theta in C; within 0.05 % of the steam tables from 0 to 100 C */
  const double theta = T - 273.15;
  const double p = 611.21 * exp((18.678 - theta / 234.5) * theta / (257.14 + theta));
  return 0.621945 * p / (P - p); /* 0.621945 = M_water / M_air */
}

int gs_drying_read(gs_cfg_node *node, const gs_model *m, double *G, gs_error *err) {
  double T, x, gamma, eta, Dw, rho_air, rho_l, P;
  int rc = gs_cfg_double_range(node, "bed_temperature", 1, 0, 274.15, 0, 373.15, 0, &T, err);
  if (!rc) rc = gs_cfg_double_range(node, "air_humidity", 1, 0, 0, 0, 0.5, 0, &x, err);
  if (!rc) rc = gs_cfg_double_range(node, "correction", 0, 1, 0, 1, 1e3, 0, &gamma, err);
  if (!rc) rc = gs_cfg_double_range(node, "wetted_fraction", 0, 1, 0, 1, 1, 0, &eta, err);
  if (!rc) rc = gs_cfg_double_range(node, "diffusivity", 0, 2.6e-5, 0, 1, 1e-3, 0, &Dw, err);
  if (!rc) rc = gs_cfg_double_range(node, "air_density", 0, 1.18, 0, 1, 100, 0, &rho_air, err);
  if (!rc) rc = gs_cfg_double_range(node, "liquid_density", 0, 1000, 0, 1, 1e5, 0, &rho_l, err);
  if (!rc) rc = gs_cfg_double_range(node, "pressure", 0, 101325, 1e3, 0, 1e7, 0, &P, err);
  if (rc) return rc;
  const double xsat = gs_saturation_humidity(T, P);
  if (!(P > 0) || !(xsat > x))
    return gs_cfg_fail(gs_cfg_get(node, "air_humidity"), err,
                       "air_humidity: at or above saturation (%g kg/kg at bed_temperature %g K): no drying", xsat, T);
  const double k = gamma * eta * 2 * M_PI * Dw * rho_air * (xsat - x) / rho_l;
  for (size_t c = 0; c < m->grid.ncells; c++) G[c] = -k * cbrt(6 * m->size_volume[c] / M_PI);
  return GS_OK;
}
