/* Independent runs in parallel (MPI ranks and OpenMP over runs, per-run
 * seeds), ensemble means and 90 % confidence half-widths c = 1.64
 * sqrt(sum_r (M_r - mean)^2) / n_runs (McGuire et al. 2018, eqs. 64-65), and the result
 * files.  Run r is executed by rank r % size, OpenMP spreads a rank's runs over
 * its threads.  Every run keeps its own observations in run-major arrays that
 * are zero for the runs other ranks execute; summing them over the ranks
 * (adding zeros is exact) gives every rank every run's observations, which
 * are then reduced in run order, so the results do not depend on the number
 * of ranks or threads.  Only rank 0 writes files and prints progress. */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/progress.h"
#include "gransim/parallel.h"
#include "swa/output.h"
#include "swa/sim.h"

#define CI_FACTOR 1.64

/* splitmix64: decorrelated 32-bit seeds for the runs of one case seed */
unsigned long gs_swa_run_seed(uint64_t seed, size_t run) {
  uint64_t z = seed * 0x9E3779B97F4A7C15ull + (uint64_t)run + 1;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  unsigned long s = (unsigned long)(z & 0xffffffffu);
  return s ? s : 1;
}

/* Bin compartment z of a run on the case grid: numbers per cell and outside. */
static void bin(const gs_swa_case *c, gs_swa_sim *s, size_t z, double *hist, double *outside) {
  const gs_grid *g = &c->grid;
  const swa_comp *cp = &s->comp[z];
  size_t nc = (size_t)c->model.ncoord;
  for (size_t i = 0; i < cp->n; i++) {
    const double *x = cp->x + i * nc;
    double n = cp->w[i] / cp->vsamp;
    size_t idx[GS_MAX_DIM];
    int in = 1;
    for (int a = 0; a < g->dim && in; a++) {
      idx[a] = gs_axis_locate(&g->axis[a], x[c->bin_coord[a]]);
      in = idx[a] != GS_NOWHERE;
    }
    if (in) hist[gs_grid_index(g, idx)] += n;
    else *outside += n;
  }
}

static void summary_row(const gs_swa_model *m, const gs_swa_summary *s, double *row) {
  row[0] = s->m0;
  row[1] = s->m1;
  row[2] = s->m2;
  row[3] = s->d10;
  row[4] = s->d50;
  row[5] = s->d90;
  for (int k = 0; k < m->ncoord; k++) {
    row[6 + k] = s->mean[k];
    row[6 + m->ncoord + k] = s->total[k];
  }
}

/* The progress line of a rank's runs: their simulated seconds added up
 * (runs x span in all), advanced as each run passes an output time; only
 * OpenMP's master thread rewrites it (it runs runs too, so it passes output
 * times often enough). */
typedef struct {
  int on;
  double reached; /* simulated seconds of this rank's runs so far (atomic) */
  size_t done, mine; /* runs finished, of this rank's */
  gs_progress line;
} swa_progress;

static void swa_progress_tick(swa_progress *p, double dt) {
  if (!p->on) return;
#pragma omp atomic
  p->reached += dt;
  if (omp_get_thread_num() != 0) return;
  double reached;
  size_t done;
#pragma omp atomic read
  reached = p->reached;
#pragma omp atomic read
  done = p->done;
  char extra[64];
  snprintf(extra, sizeof extra, "%zu of %zu runs done", done, p->mine);
  gs_progress_update(&p->line, p->line.t0 + reached, extra, 0);
}

/* One run: obs [time][comp][col], hist [time][comp][cell], extra [time][comp][2],
 * sieve [time][comp][class]. */
static int one_run(const gs_swa_case *c, size_t r, double *obs, double *hist, double *extra,
                   double *sieve, gs_swa_stats *stats, swa_progress *prog, gs_error *err) {
  const gs_swa_model *m = &c->model;
  size_t nz = m->ncomp, ncol = (size_t)gs_swa_ncolumns(m), ncells = c->grid.ncells;
  gs_swa_sim *s = gs_swa_sim_alloc(m, gs_swa_run_seed(c->seed, r), err);
  if (!s) return err->code;
  s->max_jumps = gs_swa_case_max_jumps(c);
  int rc = gs_swa_case_init_run(c, s, err);
  for (size_t t = 0; !rc && t < c->ntimes; t++) {
    rc = gs_swa_sim_advance(s, c->times[t], err);
    if (rc) break;
    if (t) swa_progress_tick(prog, c->times[t] - c->times[t - 1]);
    gs_swa_sim_sync(s);
    for (size_t z = 0; z < nz; z++) {
      gs_swa_summary sm;
      gs_swa_summarize(s, z, &sm);
      summary_row(m, &sm, obs + (t * nz + z) * ncol);
      double *e = extra + (t * nz + z) * 2;
      bin(c, s, z, hist + (t * nz + z) * ncells, &e[0]);
      e[1] = (double)gs_swa_count(s, z);
      if (c->nsieve) gs_swa_sieve(s, z, c->sieves, c->nsieve, sieve + (t * nz + z) * c->nsieve);
    }
  }
  if (rc) gs_error_prefix(err, "run %zu: ", r + 1);
  *stats = gs_swa_sim_stats(s);
  gs_swa_sim_free(s);
  return rc;
}

/* mean and CI over runs of n values laid out run-major */
static void reduce(const double *v, size_t runs, size_t n, double *mean, double *ci) {
  for (size_t i = 0; i < n; i++) {
    double mu = 0, ss = 0;
    for (size_t r = 0; r < runs; r++) mu += v[r * n + i];
    mu /= (double)runs;
    for (size_t r = 0; r < runs; r++) ss += (v[r * n + i] - mu) * (v[r * n + i] - mu);
    mean[i] = mu;
    if (ci) ci[i] = CI_FACTOR * sqrt(ss) / (double)runs;
  }
}

/* Collective: every rank calls it with its own status.  If any rank failed,
 * every rank returns the failure of the lowest failing rank, with its code and
 * message (sent as doubles summed with zeros from the other ranks: exact). */
static int agree(int rc, gs_error *err) {
  int size = gs_parallel_size(), rank = gs_parallel_rank();
  if (size < 2) return rc;
  double k = gs_parallel_max(rc ? (double)(size - rank) : 0.0);
  if (k == 0) return GS_OK;
  int from = size - (int)k;
  enum { NMSG = sizeof err->msg };
  double buf[1 + NMSG] = {0};
  if (rank == from) {
    buf[0] = rc;
    for (size_t i = 0; i < NMSG && err->msg[i]; i++) buf[1 + i] = (unsigned char)err->msg[i];
  }
  gs_parallel_sum(buf, 1 + NMSG);
  err->code = (int)buf[0];
  for (size_t i = 0; i < NMSG; i++) err->msg[i] = (char)(unsigned char)buf[1 + i];
  err->msg[NMSG - 1] = '\0';
  if (!err->msg[0]) snprintf(err->msg, sizeof err->msg, "a run failed on rank %d", from);
  return err->code;
}

int gs_swa_case_run(gs_swa_case *c, const char *out_dir, int progress, double *mean_out,
                    double *ci_out, gs_swa_report *rep, gs_error *err) {
  const gs_swa_model *m = &c->model;
  size_t runs = c->runs, nz = m->ncomp, nt = c->ntimes;
  size_t ncol = (size_t)gs_swa_ncolumns(m), ncells = c->grid.ncells;
  size_t nobs = nt * nz * ncol, nhist = nt * nz * ncells, nextra = nt * nz * 2;
  size_t nsv = nt * nz * c->nsieve;
  if ((double)runs * (double)nhist > 5e7)
    return gs_error_set(err, GS_EINPUT,
                        "%s: %zu runs x %zu output times x %zu compartments x %zu grid cells is too many "
                        "binned values to keep (limit 5e7): use a coarser grid or fewer output times",
                        gs_cfg_name(c->cfg), runs, nt, nz, ncells);
  double *obs = gs_calloc(runs * nobs, sizeof(double), err);
  double *hist = gs_calloc(runs * nhist, sizeof(double), err);
  double *extra = gs_calloc(runs * nextra, sizeof(double), err);
  double *st = gs_calloc(runs * 4, sizeof(double), err); /* per run: jumps, fictitious, doublings, contractions */
  double *mean = gs_calloc(nobs, sizeof(double), err), *ci = gs_calloc(nobs, sizeof(double), err);
  double *hm = gs_calloc(nhist, sizeof(double), err), *hc = gs_calloc(nhist, sizeof(double), err);
  double *em = gs_calloc(nextra, sizeof(double), err);
  double *sv = gs_calloc(runs * nsv, sizeof(double), err);
  gs_swa_report R = {0};
  R.sieve_mean = gs_calloc(nsv, sizeof(double), err);
  R.sieve_ci = gs_calloc(nsv, sizeof(double), err);
  int rc = (!obs || !hist || !extra || !st || !mean || !ci || !hm || !hc || !em || !sv || !R.sieve_mean ||
            !R.sieve_ci) ? GS_ENOMEM : GS_OK;
  int rank = gs_parallel_rank(), size = gs_parallel_size();
  size_t mine = runs / (size_t)size + ((size_t)rank < runs % (size_t)size); /* runs r with r % size == rank */
  if (rank) progress = 0;
  double wall0 = omp_get_wtime();
  swa_progress prog = {.on = progress, .mine = mine};
  const double span = c->times[nt - 1] - c->times[0];
  if (progress) gs_progress_start(&prog.line, "gransim swa", "run-s", 0.0, span * (double)mine);
  gs_error first = {0};
  if (!rc && mine) {
#pragma omp parallel for schedule(dynamic, 1)
    for (size_t k = 0; k < mine; k++) {
      size_t r = (size_t)rank + k * (size_t)size;
      gs_error e = {0};
      int failed;
#pragma omp atomic read
      failed = first.code;
      if (failed) continue;
      gs_swa_stats s1 = {0};
      int code = one_run(c, r, obs + r * nobs, hist + r * nhist, extra + r * nextra, sv + r * nsv, &s1,
                         &prog, &e);
      double *sr = st + 4 * r;
      sr[0] = (double)s1.jumps;
      sr[1] = (double)s1.fictitious;
      sr[2] = (double)s1.doublings;
      sr[3] = (double)s1.contractions;
#pragma omp critical(gs_swa_runs)
      {
        if (code && !first.code) first = e;
#pragma omp atomic
        prog.done++;
      }
    }
    if (progress) {
      char extra[64];
      snprintf(extra, sizeof extra, "%zu of %zu runs done", prog.done, mine);
      gs_progress_update(&prog.line, prog.reached, extra, 1);
      gs_progress_end(&prog.line);
    }
    if (first.code) {
      *err = first;
      rc = first.code;
    }
  }
  /* every rank gets here: agree on failures, then gather every run's observations */
  rc = agree(rc, err);
  if (!rc) {
    gs_parallel_sum(obs, runs * nobs);
    gs_parallel_sum(hist, runs * nhist);
    gs_parallel_sum(extra, runs * nextra);
    gs_parallel_sum(sv, runs * nsv);
    gs_parallel_sum(st, runs * 4);
  }
  if (!rc) {
    reduce(obs, runs, nobs, mean, ci);
    reduce(sv, runs, nsv, R.sieve_mean, R.sieve_ci);
    reduce(hist, runs, nhist, hm, hc);
    double *parts = gs_calloc(nt * nz, sizeof(double), err), *outs = gs_calloc(nt * nz, sizeof(double), err);
    reduce(extra, runs, nextra, em, NULL);
    for (size_t i = 0; parts && outs && i < nt * nz; i++) {
      outs[i] = em[2 * i];
      parts[i] = em[2 * i + 1];
    }
    for (size_t r = 0; r < runs; r++) { /* counts < 2^53 are exact as doubles */
      R.stats.jumps += (uint64_t)st[4 * r];
      R.stats.fictitious += (uint64_t)st[4 * r + 1];
      R.stats.doublings += (uint64_t)st[4 * r + 2];
      R.stats.contractions += (uint64_t)st[4 * r + 3];
    }
    R.runs = runs;
    gs_swa_results res = {mean, ci, hm, hc, outs, parts, R.sieve_mean, R.sieve_ci, R.stats};
    if (!parts || !outs) rc = GS_ENOMEM;
    else if (out_dir && rank == 0) rc = gs_swa_write(c, out_dir, &res, err);
    free(parts);
    free(outs);
    if (mean_out) memcpy(mean_out, mean, nobs * sizeof(double));
    if (ci_out) memcpy(ci_out, ci, nobs * sizeof(double));
    rc = agree(rc, err); /* rank 0's write, and memory on any rank */
  }
  R.wall_seconds = omp_get_wtime() - wall0;
  if (rep) *rep = R;
  else gs_swa_report_free(&R);
  free(sv);
  free(obs);
  free(hist);
  free(extra);
  free(st);
  free(mean);
  free(ci);
  free(hm);
  free(hc);
  free(em);
  return rc;
}

void gs_swa_report_free(gs_swa_report *r) {
  free(r->sieve_mean);
  free(r->sieve_ci);
  r->sieve_mean = r->sieve_ci = NULL;
}
