/* Particle distributions of an SWA case, sampled exactly (no grid): the
 * sectional distribution specs (point, cell, exponential, gamma; see
 * docs/case-files.md) and `diameters`, a feed size distribution given as
 * volume fractions q3 over logarithmic diameter sections (McGuire et al. 2018, eqs.
 * 3-5), sampled with equal weights (EWI) or uniformly in diameter with
 * weights proportional to the number density (VWI, eqs. 69-70). */
#ifndef GS_SWA_SPEC_H
#define GS_SWA_SPEC_H

#include <gsl/gsl_rng.h>

#include "gransim/swa.h"

typedef struct gs_swa_spec {
  int type; /* SPEC_* */
  double number;
  double at[GS_SWA_MAX_COORD], mean[GS_SWA_MAX_COORD], shape[GS_SWA_MAX_COORD];
  int ncoord;
  /* diameters */
  int coord;          /* coordinate receiving the primary's volume */
  int variable;       /* VWI */
  double mean_weight; /* w-bar */
  double dmin, dmax;
  size_t nsec;
  double *edges;      /* nsec + 1 */
  double *cnum;       /* cumulative number fraction per section (nsec) */
  double *dens;       /* q0 coefficient c_k of section k: q0(d) = c_k d^-3 */
  double vmean;       /* number-mean particle volume */
} gs_swa_spec;

/* Read a spec map (its `number` optional when number_key is NULL).  For the
 * grid-cell type the case grid gives the pivots (g may be NULL otherwise). */
int gs_swa_spec_read(gs_cfg_node *n, const gs_swa_model *m, const gs_grid *g,
                     const int *grid_coord, const char *number_key, gs_swa_spec *sp,
                     gs_error *err);
void gs_swa_spec_free(gs_swa_spec *sp);
/* What one draw (x, w) contributes, in expectation: the number estimate is
 * mean(w), the volume estimate of coordinate k mean(w x_k); ew2 = E[w^2],
 * mu[k] = E[w x_k], ew2x[k] = E[w^2 x_k], ew2x2[k] = E[w^2 x_k^2], from which
 * the variance of a sample's estimates follows (src/swa/disc.c). */
typedef struct gs_swa_moments {
  double ew2, mu[GS_SWA_MAX_COORD], ew2x[GS_SWA_MAX_COORD], ew2x2[GS_SWA_MAX_COORD];
} gs_swa_moments;
void gs_swa_spec_moments(const gs_swa_spec *sp, gs_swa_moments *mo);
/* Draw one particle: x (ncoord values) and its weight relative to the mean (1 for equal weights). */
void gs_swa_spec_sample(const gs_swa_spec *sp, gsl_rng *r, double *x, double *w);

#endif
