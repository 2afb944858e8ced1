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
  /* Jumps one gs_swa_sim_advance may take (solver.max_jumps_per_output):
   * a gelling kernel makes the rate grow without bound, and the loop would
   * otherwise run on with the time standing still. */
  uint64_t max_jumps;
};

/* The default of solver.max_jumps_per_output, and of a run not made from a
 * case: over 30 times the most jumps a bundled case takes in one output
 * interval (3.1e6, the twin-screw example at N_max 65536; docs/case-files.md),
 * and spent within a minute at the jump rates of a small ensemble. */
#define GS_SWA_MAX_JUMPS_DEFAULT 100000000L

/* Doubling when a compartment falls below nmin (called after every event). */
void gs_swa_maintain(gs_swa_sim *s, size_t z);
/* External liquid left after dt of penetration (a0, b0 > 0; see process_penetration.c). */
double gs_swa_penetration_left(double a0, double b0, double k, double kappa, double dt);

/* solver.max_jumps_per_output of a case. */
uint64_t gs_swa_case_max_jumps(const gs_swa_case *c);
/* Of an aggregation process, the name of its kernel and whether its form is
 * the product one (a kernel that gels), else NULL. */
const char *gs_swa_coag_kernel(const gs_swa_process *p, int *product);

/* The seed of run r of a case seeded with seed (decorrelated streams). */
unsigned long gs_swa_run_seed(uint64_t seed, size_t run);
/* The sample volume of compartment z at the start of a run. */
double gs_swa_case_vsamp0(const gs_swa_case *c, size_t z);
/* gs_swa_case_init_run, adding to tally (when not NULL) what each initial
 * entry i placed: tally[i * (ncoord + 2) + ...] = number, the volume of every
 * coordinate, particles drawn.  Without a run (s NULL) it draws from rng
 * what a run seeded alike would place, and places nothing; with cap > 0 an
 * entry of more particles is represented by cap draws (weighted up), so
 * that a very large ensemble is compared on a sample. */
int gs_swa_case_init_tally(const gs_swa_case *c, gs_swa_sim *s, gsl_rng *rng, double *tally,
                           size_t cap, gs_error *err);
/* The initial entries of a case: their number, and entry i's distribution
 * and key ("file:line: path"). */
size_t gs_swa_case_initial_count(const gs_swa_case *c);
const struct gs_swa_spec *gs_swa_case_initial(const gs_swa_case *c, size_t i, const char **key);
/* limits.memory_gb and limits.output_gb against what a run of the case
 * needs (src/swa/resources.c); the processes must be read. */
int gs_swa_check_limits(gs_cfg_node *root, const gs_swa_case *c, gs_error *err);
/* Build c->disc (src/swa/disc.c): the initial entries as every run samples
 * them, the feeds from a sample; refuses a distortion (gransim/swa.h). */
int gs_swa_case_disc(gs_swa_case *c, gs_error *err);

#endif
