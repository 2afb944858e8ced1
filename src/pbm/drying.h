/* Drying of granules in a fluid bed (Chaudhury 2015, eqs. 2.19-2.22):
 * evaporation from each granule's liquid driven by the humidity difference
 * between saturated air at the bed temperature and the bed's air.  The
 * mechanism `drying` (growth.c: negative growth along the liquid axis) takes
 * its per-cell rates from here. */
#ifndef GRANSIM_PBM_DRYING_H
#define GRANSIM_PBM_DRYING_H
#include "gransim/pbm.h"

/* Saturation humidity (kg water / kg dry air) at temperature T (K) and total
 * pressure P (Pa): x = 0.622 p / (P - p), p the vapour pressure of water from
 * Buck's (1996) equation (0-100 C). */
double gs_saturation_humidity(double T, double P);

/* Read drying's keys from node (not `type`, `liquid_axis`, `start`, `end`)
 * and fill G[c] (ncells) with the rate of change of a granule's liquid
 * volume in cell c (<= 0). */
int gs_drying_read(gs_cfg_node *node, const gs_model *m, double *G, gs_error *err);
#endif
