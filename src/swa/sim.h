/* The state of one SWA run (private to src/swa): compartments of particles
 * stored particle-major (the coordinates of a particle are contiguous, since
 * every jump reads or writes whole particles), with their weights, LPDA time
 * stamps and the Fenwick tree of cached properties. */
#ifndef GS_SWA_SIM_H
#define GS_SWA_SIM_H

#include <gsl/gsl_rng.h>

#include "gransim/swa.h"
#include "swa/fenwick.h"

typedef struct swa_comp {
  size_t n;
  double *x;     /* nmax * ncoord */
  double *w;     /* nmax */
  double *stamp; /* nmax LPDA time stamps (NULL without continuous processes) */
  gs_fenwick tree;
  double vsamp;
  double gain; /* weight scale of inflowing particles (merge contractions), 1 at start */
} swa_comp;

struct gs_swa_sim {
  const gs_swa_model *m;
  gsl_rng *rng;
  double t;
  double next_checkpoint;
  swa_comp *comp;
  gs_swa_stats stats;
  double *rates; /* nproc * ncomp scratch */
};

/* Doubling when a compartment falls below nmin (called after every event). */
void gs_swa_maintain(gs_swa_sim *s, size_t z);
/* External liquid left after dt of penetration (a0, b0 > 0; see process_penetration.c). */
double gs_swa_penetration_left(double a0, double b0, double k, double kappa, double dt);

#endif
