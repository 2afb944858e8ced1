/* Fixed-pivot births on non-uniform grids (geometric and any other
 * increasing pivots) for kernels of separable form, without a pass over all
 * pairs of cells (aggregation_split.c); used by aggregation_fft.c where the
 * pivots are not equally spaced. */
#ifndef GRANSIM_PBM_AGGREGATION_SPLIT_H
#define GRANSIM_PBM_AGGREGATION_SPLIT_H

#include <stddef.h>

#include "gransim/grid.h"

typedef struct gs_agg_split gs_agg_split;

/* the most terms one evaluation takes */
#define GS_SPLIT_MAX_TERMS 64

/* Per-axis tables of the grid g and scratch for nslots evaluators, each for
 * up to nphi arrays per evaluation. */
int gs_agg_split_create(const gs_grid *g, int nslots, int nphi, gs_agg_split **out, gs_error *err);
void gs_agg_split_free(gs_agg_split *S);

/* The entries of the per-axis pair lists multiplied over the axes: the work
 * per evaluation on a full grid (the pairs take ncells^2 / 2). */
double gs_agg_split_tuples(const gs_agg_split *S);

/* The births of sum_t scale[t] sum over ordered pairs of cells (a, b) of
 * X[m1[t]][a] X[m2[t]][b] (nphi arrays X over the cells, nterm terms),
 * each product placed at x_a + x_b by the fixed-pivot lever rule (clamped
 * to the last pivot inside the last cell, lost beyond its edge): the number
 * placed added to dN (NULL: totals only) and to *born, the volume lost or
 * clamped per axis added to lost[k] (NULL: not wanted). */
void gs_agg_split_births(gs_agg_split *S, int slot, int nphi, const double *const *X, int nterm,
                         const int *m1, const int *m2, const double *scale, double *dN, double *lost,
                         double *born);

#endif
