/* The jump loop of one run: exponential waiting times from the total
 * (majorant) rate of all processes in all compartments (McGuire et al. 2018, eqs. 28,
 * 62, 63), LPDA checkpoints, doubling after every event, and a budget of jumps
 * per call (solver.max_jumps_per_output). */
#include <gsl/gsl_randist.h>
#include <math.h>
#include <stdio.h>

#include "swa/sim.h"

/* Jumps in a row that may leave the time unchanged before a run stops.  A
 * waiting time below half a unit in the last place of t is lost, and a
 * million lost in a row take a total rate above ~28/ulp(t), ~1e17/t per
 * second: t no longer follows the process, and a run at that rate would need
 * ~1e17 jumps per second of simulated time, so it stops now. */
#define FROZEN_JUMPS 1000000u

/* The times of an interval's jumps that the message of a stopped run
 * compares: a window of a tenth of the budget at its start and at its end. */
typedef struct jump_log {
  double t0;         /* the interval's start */
  uint64_t budget;   /* s->max_jumps */
  uint64_t window;   /* jumps per window (0: the budget is too small to compare) */
  double first[2];   /* times of jumps 1 and window + 1 */
  double last;       /* time of jump budget - window */
  double rate_first; /* total rate at jump 1 */
} jump_log;

static void log_jump(jump_log *l, uint64_t k, double t, double total) {
  if (k == 1) {
    l->first[0] = t;
    l->rate_first = total;
  }
  if (l->window && k == l->window + 1) l->first[1] = t;
  if (l->window && k == l->budget - l->window) l->last = t;
}

/* A rate for ranking: one that is not a finite number ranks first. */
static double rank_of(double r) { return isfinite(r) ? r : HUGE_VAL; }

/* The process with the largest share of the total rate (-1 when the rates
 * are not finite), and its compartment with the largest rate. */
static size_t top_process(const gs_swa_sim *s, double *share, size_t *comp) {
  const size_t np = s->m->nproc, nz = s->m->ncomp;
  size_t top = 0, zt = 0;
  double best = -1, total = 0;
  for (size_t p = 0; p < np; p++) {
    double sum = 0;
    for (size_t z = 0; z < nz; z++) sum += s->rates[p * nz + z];
    total += sum;
    if (rank_of(sum) > best) {
      best = rank_of(sum);
      top = p;
    }
  }
  for (size_t z = 0; z < nz; z++)
    if (rank_of(s->rates[top * nz + z]) > rank_of(s->rates[top * nz + zt])) zt = z;
  *share = isfinite(total) ? (total > 0 ? best / total : 0) : -1;
  *comp = zt;
  return top;
}

enum { BUDGET, FROZEN, INFINITE };

/* The error of a run stopped after k jumps of the interval (why: the budget
 * spent, the time frozen for FROZEN_JUMPS jumps, or a total rate that is no
 * longer a finite number).  It says where the run stands, whether the rate
 * diverges, which process gives most of the rate, and what to change.  The
 * rate is said to diverge when it overflows or the time stands still, or
 * when the last tenth of the budget took under a thousandth of the simulated
 * time of the first tenth: a rate grown a thousandfold within one interval. */
static int stopped(const gs_swa_sim *s, const jump_log *l, uint64_t k, int why, double total,
                   double t_end, gs_error *err) {
  const gs_swa_model *m = s->m;
  const unsigned long long w = (unsigned long long)l->window;
  const double span_first = l->first[1] - l->first[0], span_last = s->t - l->last;
  const int diverges = why == FROZEN || (why == INFINITE && total > 0) || (why == BUDGET && w && span_last < 1e-3 * span_first);
  char what[1024];
  if (why == FROZEN)
    snprintf(what, sizeof what,
             "the simulated time stands still at t = %.9g after %llu jumps of the output interval from t = %.9g to "
             "%.9g: the jump rate diverges, and the last %u jumps did not advance the time at all (the total rate, "
             "%.3g per second at the interval's first jump, is %.3g now, so the waiting times are below the "
             "resolution %.3g of t)",
             s->t, (unsigned long long)k, l->t0, t_end, FROZEN_JUMPS, l->rate_first, total,
             nextafter(s->t, HUGE_VAL) - s->t);
  else if (why == INFINITE)
    snprintf(what, sizeof what,
             "the total jump rate is %g at t = %.9g after %llu jumps of the output interval from t = %.9g to %.9g "
             "(%.3g per second at the interval's first jump)%s",
             total, s->t, (unsigned long long)k, l->t0, t_end, l->rate_first,
             diverges ? ": the jump rate diverges" : "");
  else if (diverges)
    snprintf(what, sizeof what,
             "solver.max_jumps_per_output = %llu jumps took the run from t = %.9g only to t = %.9g on the way to "
             "the output time %.9g: the jump rate diverges, the simulated time advanced by only %.3g over the last "
             "%llu jumps against %.3g over the first %llu (the total rate grew from %.3g to %.3g per second)",
             (unsigned long long)k, l->t0, s->t, t_end, span_last, w, span_first, w, l->rate_first, total);
  else
    snprintf(what, sizeof what,
             "solver.max_jumps_per_output = %llu jumps took the run from t = %.9g only to t = %.9g on the way to "
             "the output time %.9g: at the present total rate (%.3g per second) the interval needs about %.3g "
             "jumps more",
             (unsigned long long)k, l->t0, s->t, t_end, total, total * (t_end - s->t));
  double share;
  size_t comp;
  size_t top = top_process(s, &share, &comp);
  int product = 0;
  const char *kernel = gs_swa_coag_kernel(&m->proc[top], &product);
  char who[512];
  int len = snprintf(who, sizeof who, "%s", m->proc[top].label);
  if (kernel) len += snprintf(who + len, sizeof who - (size_t)len, " with kernel %s", kernel);
  if (share >= 0)
    snprintf(who + len, sizeof who - (size_t)len, " gives %.0f %% of the rate (compartment %zu)", 100 * share, comp + 1);
  else
    snprintf(who + len, sizeof who - (size_t)len, " has a rate that is not finite (compartment %zu)", comp + 1);
  const int budget = why == BUDGET;
  const char *hint =
      product && diverges
          ? (budget ? "a kernel of product form gels at a finite time (docs/models.md), after which the swa scheme "
                      "grows particles ever faster: use a non-gelling kernel (constant or sum) or an end time before "
                      "the gel point, fewer solver.particles, or a larger solver.max_jumps_per_output"
                    : "a kernel of product form gels at a finite time (docs/models.md), after which the swa scheme "
                      "grows particles ever faster: use a non-gelling kernel (constant or sum) or an end time before "
                      "the gel point")
      : diverges ? (budget ? "its rate grows without bound: check its rate constants, or use fewer solver.particles or "
                             "a larger solver.max_jumps_per_output"
                           : "its rate grows without bound: check its rate constants")
      : budget   ? "use output times closer together, fewer solver.particles, or a larger solver.max_jumps_per_output"
                 : "its rate is not a number: check its rate constants";
  return gs_error_set(err, GS_ENUMERIC, "%s; %s: %s", what, who, hint);
}

int gs_swa_sim_advance(gs_swa_sim *s, double t_end, gs_error *err) {
  const gs_swa_model *m = s->m;
  size_t np = m->nproc, nz = m->ncomp;
  const uint64_t budget = s->max_jumps;
  jump_log seen = {.t0 = s->t, .budget = budget, .window = budget / 10};
  uint64_t k = 0;    /* jumps of this interval */
  unsigned still = 0; /* jumps in a row that left the time unchanged */
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
    if (!(total < HUGE_VAL)) return stopped(s, &seen, k, INFINITE, total, t_end, err);
    if (k == budget || still == FROZEN_JUMPS)
      return stopped(s, &seen, k, k == budget ? BUDGET : FROZEN, total, t_end, err);
    still = s->t + dt == s->t ? still + 1 : 0;
    s->t += dt;
    log_jump(&seen, ++k, s->t, total);
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
    for (size_t q = 0; q < nz; q++) gs_swa_maintain(s, q);
  }
  return GS_OK;
}
