/* Compaction T_comp of McGuire et al. (2018, eqs. 16-21), in the physically consistent
 * form (docs/models.md, "SWA twin-screw model"): the porosity moves a
 * fraction k of the way to eps_min, the pore saturation l_i/p is kept, and
 * liquid squeezed out of the shrinking pores becomes external liquid. */
#ifndef GS_SWA_COMPACTION_H
#define GS_SWA_COMPACTION_H

#include "gransim/swa.h"

typedef struct gs_swa_compaction {
  int on;
  int solid, ext, in, pores; /* coordinates */
  double min_porosity;
  double *rate; /* k_comp per compartment */
} gs_swa_compaction;

/* Read an optional `compaction` map of node (off when absent). */
int gs_swa_compaction_read(gs_cfg_node *node, const gs_swa_model *m, gs_swa_compaction *c,
                           gs_error *err);
void gs_swa_compaction_free(gs_swa_compaction *c);
/* Apply to x (compartment z); mass and solid are unchanged. */
void gs_swa_compact(const gs_swa_compaction *c, size_t z, double *x);
/* Read the four role coordinates (solid, external_liquid, internal_liquid, pores). */
int gs_swa_roles(gs_cfg_node *node, const gs_swa_model *m, int *solid, int *ext, int *in,
                 int *pores, gs_error *err);

#endif
