/* The fines of a compartment as a source of solid (layering, nucleation):
 * cells whose coordinate along one solid axis is at or below a threshold
 * (a volume, not "the 7th bin" of Chaudhury (2015) eq. 2.14, so that the
 * fines do not change with the grid).  A mechanism that builds solid out of
 * fines takes them away at a rate proportional to their number, k N_c, so
 * that they run out smoothly, and books what leaves (every axis and carried
 * quantity of the fines taken) as exchanged volume; the solid it puts
 * elsewhere it books as coming in, so the compartment's solid balance nets
 * to round-off and the ledger identity holds for every coordinate. */
#ifndef GRANSIM_PBM_FINES_H
#define GRANSIM_PBM_FINES_H
#include "gransim/pbm.h"

typedef struct gs_fines {
  int axis;               /* the solid axis the fines are measured on */
  unsigned char *is_fine; /* ncells: 1 for a fines cell */
} gs_fines;

/* Mark the cells with pivot along axis <= max (node: the map, for errors
 * naming `key` when no cell qualifies). */
int gs_fines_init(gs_fines *f, const gs_grid *g, int axis, double max, gs_cfg_node *node,
                  const char *key, gs_error *err);
void gs_fines_free(gs_fines *f);
/* Volume along the axis held by the fines (*fine) and by all cells (*total)
 * of one compartment's numbers N. */
void gs_fines_volumes(const gs_fines *f, const gs_grid *g, const double *N, double *fine,
                      double *total);
/* Take fines away at rate k N_c (and k Q_c of each carried quantity),
 * booking every coordinate they hold as leaving the compartment. */
void gs_fines_take(const gs_fines *f, const gs_model *m, const gs_eval *ev, size_t comp,
                   const double *y, double k, double *dydt, double *dledger);
#endif
