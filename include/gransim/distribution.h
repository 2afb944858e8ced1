/* gransim — particle distributions for initial conditions and feeds.
 *
 * A distribution spec is a case-file map with a `type` and `number` (total
 * number; for feeds, number per second):
 *   point        at: [x per axis]                 all particles at one point
 *   cell         index: [i per axis] (1-based)    all particles in one cell
 *   exponential  mean: [m per axis]               product of exponentials
 *   gamma        mean: [m per axis], shape: [k per axis]   product of Gamma(k, m/k)
 * Continuous distributions are discretised axis by axis so that, per cell,
 * number and first moment are conserved (each cell's content is placed on
 * the neighbouring pivots by the lever rule).  The spec must be covered by
 * the grid: if more than `coverage` (default 1e-6) of the number or volume
 * along an axis lies outside the grid's edges, it is an error. */
#ifndef GRANSIM_DISTRIBUTION_H
#define GRANSIM_DISTRIBUTION_H

#include "gransim/cfg.h"
#include "gransim/grid.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Discretise the spec in node onto the cells of one compartment and ADD it to
 * dst (ncells entries).  Calls gs_cfg_check_unused(node) unless keep_open. */
int gs_distribution_add(gs_cfg_node *node, const gs_grid *g, double *dst, int keep_open,
                        gs_error *err);

#ifdef __cplusplus
}
#endif
#endif
