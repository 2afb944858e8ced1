/* The discretisation report of an SWA case (gransim/swa.h, gs_swa_disc):
 * every distribution as its computational particles hold it, against what
 * was asked, with the error that sampling alone would make. */
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "swa/sim.h"
#include "swa/spec.h"

/* A represented value further from the requested one than this many
 * standard errors is not sampling noise (a normal deviate exceeds 5 sigma
 * with probability 6e-7): with the tolerance also exceeded, it is refused. */
#define DISC_SIGMAS 5.0
/* A distribution is compared on a sample of at most about this many draws,
 * so that reading a case stays fast (a second or so). */
#define SAMPLE_DRAWS 1e7
/* The feeds are compared on samples of at most this many draws in all. */
#define FEED_SAMPLE 1e6

/* Relative standard errors of a sample of n draws with moments mo:
 * number mean(w), volume mean(w x_k) and the mean size, their ratio
 * (first-order variance of a ratio estimator).  No draw (n = 0): nothing is
 * random, the distribution is certainly missing (sigma 0). */
static void sampling_error(const gs_swa_moments *mo, int nc, double n, double *sigma) {
  sigma[0] = n > 0 ? sqrt(fmax(mo->ew2 - 1, 0) / n) : 0;
  for (int k = 0; k < nc; k++) {
    const double mu = mo->mu[k];
    double vol = 0, mean = 0;
    if (mu > 0) {
      vol = fmax(mo->ew2x2[k] / (mu * mu) - 1, 0);
      mean = fmax((mo->ew2x2[k] - 2 * mu * mo->ew2x[k] + mu * mu * mo->ew2) / (mu * mu), 0);
    }
    sigma[1 + k] = n > 0 ? sqrt(vol / n) : 0;
    sigma[1 + nc + k] = n > 0 ? sqrt(mean / n) : 0;
  }
}

/* The relative errors of r: number, volumes, mean sizes (0 where nothing was asked). */
static void errors(int nc, const gs_swa_disc *r, double *e) {
  e[0] = r->number[0] > 0 ? fabs(r->number[1] / r->number[0] - 1) : 0;
  for (int k = 0; k < nc; k++) {
    const double *v = r->volume[k];
    e[1 + k] = v[0] > 0 ? fabs(v[1] / v[0] - 1) : 0;
    e[1 + nc + k] = v[0] > 0 && r->number[1] > 0
                        ? fabs((v[1] / r->number[1]) / (v[0] / r->number[0]) - 1)
                        : e[1 + k];
  }
}

double gs_swa_disc_error(const gs_swa_case *c, const gs_swa_disc *r) {
  double e[1 + 2 * GS_SWA_MAX_COORD], worst = 0;
  errors(c->model.ncoord, r, e);
  for (int q = 0; q < 1 + 2 * c->model.ncoord; q++) worst = fmax(worst, e[q]);
  return worst;
}

static double largest_sigma(int nc, const gs_swa_disc *r) {
  double s = 0;
  for (int q = 0; q < 1 + 2 * nc; q++) s = fmax(s, r->sigma[q]);
  return s;
}

void gs_swa_disc_format(const gs_swa_case *c, const gs_swa_disc *r, char *buf, size_t len) {
  const gs_swa_model *m = &c->model;
  size_t at = (size_t)snprintf(buf, len, "%s: the particles hold number %.6g (asked %.6g)", r->key,
                               r->number[1], r->number[0]);
  for (int k = 0; k < m->ncoord && at < len; k++)
    if (r->volume[k][0] > 0 || r->volume[k][1] > 0)
      at += (size_t)snprintf(buf + at, len - at, ", volume of '%s' %.6g (asked %.6g)", m->coord[k],
                             r->volume[k][1], r->volume[k][0]);
  const double sigma = largest_sigma(m->ncoord, r);
  if (at < len)
    snprintf(buf + at, len - at,
             "; largest relative error %.2g, expected from sampling %.2g (one standard error of "
             "%.0f particles)%s (discretisation.tolerance %g)",
             gs_swa_disc_error(c, r), sigma, r->particles,
             sigma > c->disc_tolerance ? ", above the tolerance: the runs' confidence intervals "
                                         "carry it; more solver.particles or solver.runs reduce it"
                                       : "",
             c->disc_tolerance);
}

/* The requested values and sampling errors of n draws of sp, standing for
 * number particles. */
static void expect(const gs_swa_spec *sp, int nc, double number, double n, gs_swa_disc *r) {
  gs_swa_moments mo;
  gs_swa_spec_moments(sp, &mo);
  r->number[0] = number;
  for (int k = 0; k < nc; k++) r->volume[k][0] = number * mo.mu[k];
  r->particles = n;
  sampling_error(&mo, nc, n, r->sigma);
}

/* Refuses r when a quantity misses by more than the tolerance and by more
 * than DISC_SIGMAS standard errors. */
static int judge(const gs_swa_case *c, const gs_swa_disc *r, gs_error *err) {
  const int nc = c->model.ncoord;
  double e[1 + 2 * GS_SWA_MAX_COORD];
  errors(nc, r, e);
  for (int q = 0; q < 1 + 2 * nc; q++) {
    if (!(e[q] > c->disc_tolerance) || !(e[q] > DISC_SIGMAS * r->sigma[q])) continue;
    char what[GS_NAME_LEN + 32] = "number";
    double asked = r->number[0], held = r->number[1];
    if (q > 0) {
      const int k = (q - 1) % nc;
      snprintf(what, sizeof what, "%s of '%s'", q <= nc ? "volume" : "mean size", c->model.coord[k]);
      asked = r->volume[k][0];
      held = r->volume[k][1];
      if (q > nc) {
        asked /= r->number[0];
        held = r->number[1] > 0 ? held / r->number[1] : 0;
      }
    }
    return gs_error_set(err, GS_EINPUT,
                        "%s: the computational particles hold this distribution with a %s of %.6g "
                        "instead of the requested %.6g (relative error %.3g > "
                        "discretisation.tolerance = %g; sampling %.0f particles explains %.3g at "
                        "most, %g standard errors): too few particles were left for it "
                        "(solver.particles, solver.fill_fraction, the other initial entries of its "
                        "compartment) or its weights are degenerate",
                        r->key, what, held, asked, e[q], c->disc_tolerance, r->particles,
                        DISC_SIGMAS * r->sigma[q], DISC_SIGMAS);
  }
  return GS_OK;
}

/* The initial entries: every run's initial particles, drawn as the runs draw
 * them (the same streams), or those of the first runs when all of them
 * would take more than SAMPLE_DRAWS draws (the represented values are then
 * that ensemble's, and the sampling error is stated for it), or, when one
 * run alone would, a sample of each entry's particles in the first run. */
static int initial_reports(gs_swa_case *c, size_t nentries, gs_error *err) {
  const gs_swa_model *m = &c->model;
  const size_t nc = (size_t)m->ncoord, stride = nc + 2;
  double *tally = gs_calloc(nentries * stride + 1, sizeof *tally, err);
  gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
  int rc = tally && rng ? GS_OK : gs_error_set(err, GS_ENOMEM, "out of memory");
  /* a draw of `diameters` with equal weights scans its sections */
  size_t sections = 0;
  for (size_t i = 0; i < nentries; i++) {
    const char *key;
    const gs_swa_spec *sp = gs_swa_case_initial(c, i, &key);
    if (sp->nsec > sections) sections = sp->nsec;
  }
  const double per_run = fmin(fmax(m->fill_fraction * (double)m->nmax, 1), (double)m->nmax) *
                         (double)m->ncomp * (1 + (double)sections);
  const size_t runs = (size_t)fmax(1, fmin((double)c->runs, floor(SAMPLE_DRAWS / per_run)));
  /* one run alone too large: each entry on a sample of its particles */
  const size_t cap = per_run > SAMPLE_DRAWS ? (size_t)fmax(1, SAMPLE_DRAWS / (double)nentries / (1 + (double)sections)) : 0;
  for (size_t r = 0; !rc && r < runs; r++) {
    gsl_rng_set(rng, gs_swa_run_seed(c->seed, r));
    rc = gs_swa_case_init_tally(c, NULL, rng, tally, cap, err);
  }
  for (size_t i = 0; !rc && i < nentries; i++) {
    const double *t = tally + i * stride;
    gs_swa_disc *r = &c->disc[c->ndisc];
    const char *key = "";
    const gs_swa_spec *sp = gs_swa_case_initial(c, i, &key);
    snprintf(r->key, sizeof r->key, "%s", key);
    expect(sp, (int)nc, sp->number, t[nc + 1], r);
    r->number[1] = t[0] / (double)runs;
    for (size_t k = 0; k < nc; k++) r->volume[k][1] = t[1 + k] / (double)runs;
    c->ndisc++;
    rc = judge(c, r, err);
  }
  if (rng) gsl_rng_free(rng);
  free(tally);
  return rc;
}

/* A feed: the particles the runs are expected to feed (rate x sample volume
 * x the time it feeds within the run / the mean weight), sampled with a
 * stream no run uses. */
static int feed_report(gs_swa_case *c, const gs_swa_process *p, size_t nfeeds, gsl_rng *rng,
                       gs_error *err) {
  const gs_swa_model *m = &c->model;
  const int nc = m->ncoord;
  const char *key = "";
  size_t z = 0;
  double rate = 0, window[2] = {0, 0};
  const gs_swa_spec *sp = p->type->inflow(p->self, &key, &z, &rate, window);
  const double span = fmax(fmin(window[1], c->times[c->ntimes - 1]) - fmax(window[0], c->t0), 0);
  const double fed = rate * gs_swa_case_vsamp0(c, z) * span / sp->mean_weight * (double)c->runs;
  const double n = fmax(1, fmin(ceil(fed), FEED_SAMPLE / (double)nfeeds / (1 + (double)sp->nsec)));
  gs_swa_disc *r = &c->disc[c->ndisc++];
  snprintf(r->key, sizeof r->key, "%s", key);
  expect(sp, nc, rate, n, r);
  double sw = 0, swx[GS_SWA_MAX_COORD] = {0};
  for (double i = 0; i < n; i++) {
    double x[GS_SWA_MAX_COORD], w;
    gs_swa_spec_sample(sp, rng, x, &w);
    sw += w;
    for (int k = 0; k < nc; k++) swx[k] += w * x[k];
  }
  r->number[1] = rate * sw / n;
  for (int k = 0; k < nc; k++) r->volume[k][1] = rate * swx[k] / n;
  (void)err;
  return judge(c, r, err);
}

int gs_swa_case_disc(gs_swa_case *c, gs_error *err) {
  const gs_swa_model *m = &c->model;
  size_t nentries = gs_swa_case_initial_count(c), nfeeds = 0;
  for (size_t p = 0; p < m->nproc; p++) nfeeds += m->proc[p].type->inflow != NULL;
  c->disc = gs_calloc(nentries + nfeeds + 1, sizeof *c->disc, err);
  if (!c->disc) return GS_ENOMEM;
  int rc = initial_reports(c, nentries, err);
  if (rc || !nfeeds) return rc;
  gsl_rng *rng = gsl_rng_alloc(gsl_rng_mt19937);
  if (!rng) return gs_error_set(err, GS_ENOMEM, "out of memory");
  gsl_rng_set(rng, gs_swa_run_seed(c->seed, c->runs));
  for (size_t p = 0; !rc && p < m->nproc; p++)
    if (m->proc[p].type->inflow) rc = feed_report(c, &m->proc[p], nfeeds, rng, err);
  gsl_rng_free(rng);
  return rc;
}
