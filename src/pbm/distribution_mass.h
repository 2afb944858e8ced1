/* Distributions given as a mass of solid with a size distribution by mass
 * (types lognormal, normal, table; distribution_mass.c). */
#ifndef GRANSIM_PBM_DISTRIBUTION_MASS_H
#define GRANSIM_PBM_DISTRIBUTION_MASS_H
#include "gransim/distribution.h"

/* Add the distribution of node (type "lognormal", "normal" or "table") to
 * dst (one compartment's cells) and set what was asked in req (number and
 * volumes, before the grid holds it).  coverage: the largest mass fraction
 * allowed outside the grid's diameters. */
int gs_distribution_by_mass(gs_cfg_node *node, const gs_grid *g, const char *type, double coverage,
                            double *dst, gs_disc_report *req, gs_error *err);
#endif
