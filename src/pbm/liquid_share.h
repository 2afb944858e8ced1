/* How the liquid sprayed into a compartment is shared over its granules and
 * how much is sprayed: what the mechanisms `liquid_addition` (liquid as a
 * grid axis) and `spray` (liquid carried per cell) have in common
 * (docs/models.md, "Liquid inflow and how it is shared").
 *
 * Sharing rules are registered types (key `share: {type: ...}`): a granule
 * of solid volume s and gross volume V receives Q w / sum(N w) of the
 * inflow Q, with w its weight:
 *   solid_volume  w = s                  (Sampat et al. 2018, eq. 5; the default)
 *   absorption    w = V psi(d)           (De et al. 2025, eqs. 7-9: droplets are
 *                                         caught in proportion to granule volume
 *                                         times the absorption probability psi)
 * The inflow Q is `rate` [m^3/s] (one, or one per compartment), the paper's
 * droplets `{rate [1/s], volume [m^3]}`, or `liquid_solid_ratio` spread over
 * the spray's window [start, end): Q = LS (rho_s / rho_l) S / (end - start)
 * with S the compartment's solid volume (constant in a batch, where
 * aggregation and liquid addition conserve it). */
#ifndef GRANSIM_PBM_LIQUID_SHARE_H
#define GRANSIM_PBM_LIQUID_SHARE_H

#include <stddef.h>

#include "gransim/cfg.h"

typedef struct gs_liquid_share gs_liquid_share;

typedef struct {
  const char *name;
  const char *summary;
  /* its keys besides `type` (validated; unknown keys are the caller's check) */
  int (*read)(gs_cfg_node *n, gs_liquid_share *s, gs_error *err);
  /* the weight of one granule of solid volume s and gross volume V */
  double (*weight)(const gs_liquid_share *s, double solid, double gross);
  /* 1 when the weight depends on more than the solid volume */
  int needs_gross;
} gs_liquid_share_type;

struct gs_liquid_share {
  const gs_liquid_share_type *type;
  double psi;             /* absorption: constant probability (when npsi == 0) */
  size_t npsi;            /* absorption: classes of the table */
  double *psi_edges;      /* npsi + 1 granule diameters [m] */
  double *psi_values;     /* npsi probabilities */
};

extern const gs_liquid_share_type gs_share_solid_volume, gs_share_absorption;
extern const gs_liquid_share_type *const gs_liquid_shares[];

/* Key `share` of the mechanism's node (default solid_volume). */
int gs_liquid_share_read(gs_cfg_node *node, gs_liquid_share *s, gs_error *err);
void gs_liquid_share_free(gs_liquid_share *s);

typedef struct {
  double *q;       /* per compartment [m^3/s], or NULL with a ratio */
  double per_solid; /* liquid_solid_ratio: Q = per_solid * S */
} gs_liquid_inflow;

/* The inflow keys of node (exactly one form); start and end are the
 * mechanism's window, read before (a ratio needs a finite end). */
int gs_liquid_inflow_read(gs_cfg_node *node, size_t ncomp, double start, double end, gs_liquid_inflow *f,
                          gs_error *err);
/* Compartment comp's inflow [m^3/s] when its solid volume is solid. */
double gs_liquid_inflow_rate(const gs_liquid_inflow *f, size_t comp, double solid);
void gs_liquid_inflow_free(gs_liquid_inflow *f);

#endif
