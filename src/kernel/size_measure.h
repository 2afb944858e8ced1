/* Per-cell size measure shared by kernels and selection functions: the sum
 * of a chosen set of axes (default: all axes = granule volume). */
#ifndef GRANSIM_SIZE_MEASURE_H
#define GRANSIM_SIZE_MEASURE_H
#include "gransim/cfg.h"
#include "gransim/grid.h"

/* Reads optional key "axes" (list of axis names) from node and returns a
 * malloc'ed array of g->ncells sizes (sum of the chosen coordinates). */
double *gs_size_measure(gs_cfg_node *node, const gs_grid *g, gs_error *err);
/* The same, also giving the chosen axes (bit k: axis k), so that the size of
 * a point off the pivots (a particle) can be taken with gs_size_of. */
double *gs_size_measure_mask(gs_cfg_node *node, const gs_grid *g, unsigned *mask, gs_error *err);
/* Reads "axes" alone into a mask (all axes when absent). */
int gs_size_axes(gs_cfg_node *node, const gs_grid *g, unsigned *mask, gs_error *err);
/* Sum of the coordinates x[k] (k < dim) chosen by mask, in axis order (the
 * order every cell's measure is summed in). */
double gs_size_of(unsigned mask, int dim, const double *x);

/* A kernel's beta0: a number >= 0 (read as before lists were allowed, so
 * its messages are unchanged), or a list of one per compartment; *out is
 * malloc'ed with g->ncomp entries, *differ set when they are not all equal. */
int gs_kernel_beta0(gs_cfg_node *node, int required, double def, const gs_grid *g, double **out,
                    int *differ, gs_error *err);
#endif
