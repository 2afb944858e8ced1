/* The jump loop of one run: exponential waiting times from the total
 * (majorant) rate of all processes in all compartments (McGuire et al. 2018, eqs. 28,
 * 62, 63), LPDA checkpoints, doubling after every event. */
#include <gsl/gsl_randist.h>
#include <math.h>

#include "swa/sim.h"

int gs_swa_sim_advance(gs_swa_sim *s, double t_end, gs_error *err) {
  const gs_swa_model *m = s->m;
  size_t np = m->nproc, nz = m->ncomp;
  while (s->t < t_end) {
    double total = 0;
    for (size_t p = 0; p < np; p++) {
      const gs_swa_process *pr = &m->proc[p];
      for (size_t z = 0; z < nz; z++) {
        double r = pr->type->rate ? pr->type->rate(pr->self, s, z) : 0;
        s->rates[p * nz + z] = r;
        total += r;
      }
    }
    double stop = fmin(t_end, s->next_checkpoint);
    double dt = total > 0 ? -log1p(-gsl_rng_uniform(s->rng)) / total : HUGE_VAL;
    if (s->t + dt >= stop) {
      /* No event before the stop: the process is memoryless, so the waiting
       * time can be drawn afresh from there. */
      s->t = stop;
      if (stop == s->next_checkpoint) {
        gs_swa_sim_sync(s);
        s->next_checkpoint += m->lpda_interval;
      }
      continue;
    }
    s->t += dt;
    double u = gsl_rng_uniform(s->rng) * total, acc = 0;
    size_t pick = 0, last = 0;
    for (; pick < np * nz; pick++) {
      double r = s->rates[pick];
      if (!(r > 0)) continue;
      last = pick;
      acc += r;
      if (u < acc) break;
    }
    if (pick == np * nz) pick = last; /* u landed on round-off above the sum */
    size_t p = pick / nz, z = pick % nz;
    int rc = m->proc[p].type->jump(m->proc[p].self, s, z, err);
    if (rc) {
      gs_error_prefix(err, "%s at t = %g in compartment %zu: ", m->proc[p].label, s->t, z + 1);
      return rc;
    }
    s->stats.jumps++;
    for (size_t k = 0; k < nz; k++) gs_swa_maintain(s, k);
  }
  return GS_OK;
}
