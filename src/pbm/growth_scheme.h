/* Conservative first-order upwind transfer between neighbouring pivots for
 * growth along one axis (liquid addition, layering, consolidation as
 * negative growth, drying).  With rate G at a pivot, particles move to the
 * next pivot in the direction of growth at rate |G| N / (pivot spacing), so
 *   - number is conserved exactly,
 *   - d/dt sum N x_axis = sum G N exactly (the physical growth of volume),
 *   - densities stay non-negative (the loss of a cell is proportional to N).
 * At the last pivot, growing particles leave the grid (booked as lost); at
 * the first pivot shrinking particles stay (they cannot be represented lower). */
#ifndef GRANSIM_GROWTH_SCHEME_H
#define GRANSIM_GROWTH_SCHEME_H
#include "gransim/grid.h"

/* N, d: one compartment; G: rate per cell (NULL entries not allowed);
 * exchanged, lost: this compartment's ledger entries per axis (may be NULL).
 * d NULL: only the ledger's rates. */
void gs_growth_apply(const gs_grid *g, int axis, const double *G, const double *N, double *d,
                     double *exchanged, double *lost);

/* Solve (I - gamma J) z = r in place for one compartment, J the Jacobian of
 * gs_growth_apply with these rates G: a tridiagonal system along each line
 * of the axis (bidiagonal when G has one sign), solved exactly by the Thomas
 * algorithm, which is stable here because I - gamma J is column diagonally
 * dominant.  zexchanged, zlost (per axis, may be NULL): this compartment's
 * ledger entries of z, solved too (their rows of J are the ledger's rates), so
 * that the solve conserves volume as the growth does.  work: 2 * (cells along
 * the axis) doubles. */
void gs_growth_solve(const gs_grid *g, int axis, const double *G, double gamma, double *z,
                     double *zexchanged, double *zlost, double *work);

/* Helpers of the mechanisms that grow along an axis (growth.c, layering.c,
 * nucleation.c).  The grid axis named by key (default def; NULL: required)
 * into *out, with an error naming the key when the grid has no such axis. */
#include "gransim/cfg.h"
int gs_growth_axis_key(gs_cfg_node *node, const gs_grid *g, const char *key, const char *def,
                       int *out, gs_error *err);
/* The time window [start, end) of keys `start` (default 0) and `end`
 * (default unbounded, > start). */
int gs_mech_read_window(gs_cfg_node *node, double *start, double *end, gs_error *err);
#endif
