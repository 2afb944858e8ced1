/* Per-cell size measure shared by kernels and selection functions: the sum
 * of a chosen set of axes (default: all axes = granule volume). */
#ifndef GRANSIM_SIZE_MEASURE_H
#define GRANSIM_SIZE_MEASURE_H
#include "gransim/cfg.h"
#include "gransim/grid.h"

/* Reads optional key "axes" (list of axis names) from node and returns a
 * malloc'ed array of g->ncells sizes (sum of the chosen coordinates). */
double *gs_size_measure(gs_cfg_node *node, const gs_grid *g, gs_error *err);
#endif
