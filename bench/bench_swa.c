/* Benchmarks of the SWA solver (run by bench/swa_run).
 *
 *   bench_swa jumps [N_MAX] [SESSIONS]
 *     Coagulation jumps per second on one thread, constant kernel, N_max
 *     particles (default 65536): the weighted scheme (swa) and, as the
 *     baseline measured in the same run, direct simulation (dsa).  Each
 *     session starts a fresh ensemble (not timed) and runs to tau = 1000.
 *
 *   bench_swa sieve CASE [--ref FILE] [--save FILE]
 *     Runs CASE (all its runs, on the OpenMP threads) and prints one line:
 *     cpu_s wall_s jumps cbar sse, where cbar is the mean 90 % CI half-width of
 *     the sieve mass fractions of the last compartment at the last time (McGuire et al.
 *     2018, eq. 66) and sse the squared distance of their mean to the fractions
 *     in FILE (eq. 67; nan without --ref).  --save writes the mean fractions
 *     (the high-precision solution for later --ref).  A run that fails (e.g.
 *     the nucleation instability at small N_max) prints "unstable: reason". */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gransim/swa.h"

static int load(const char *text, const char *path, gs_swa_case *c) {
  gs_error e = {0};
  gs_cfg *cfg = text ? gs_cfg_load_string(text, "bench.yaml", &e) : gs_cfg_load_file(path, &e);
  if (!cfg || gs_swa_case_from_cfg(cfg, c, &e)) {
    fprintf(stderr, "bench_swa: %s\n", e.msg);
    return 1;
  }
  return 0;
}

static int jumps(long nmax, int sessions) {
  const char *scheme[2] = {"swa", "dsa"};
  double rate[2] = {0, 0};
  for (int k = 0; k < 2; k++) {
    char yaml[1024];
    snprintf(yaml, sizeof yaml,
             "grid:\n  axes: [{name: v, type: geometric, min: 1e-3, max: 1e3, cells: 10}]\n"
             "initial: {type: exponential, number: 1e6, mean: 1}\n"
             "mechanisms:\n  - {type: aggregation, scheme: %s, kernel: {type: constant, beta0: 1e-6}}\n"
             "solver: {method: swa, particles: %ld}\noutput: {end: 1000}\n",
             scheme[k], nmax);
    gs_swa_case c;
    if (load(yaml, NULL, &c)) return 1;
    double secs = 0;
    unsigned long long n = 0;
    for (int s = 0; s < sessions; s++) {
      gs_error e = {0};
      gs_swa_sim *sim = gs_swa_sim_alloc(&c.model, (uint64_t)s + 1, &e);
      if (!sim || gs_swa_case_init_run(&c, sim, &e)) return 1;
      double t0 = omp_get_wtime();
      if (gs_swa_sim_advance(sim, 1000, &e)) {
        fprintf(stderr, "bench_swa: %s\n", e.msg);
        return 1;
      }
      secs += omp_get_wtime() - t0;
      gs_swa_stats st = gs_swa_sim_stats(sim);
      n += st.jumps - st.fictitious;
      gs_swa_sim_free(sim);
    }
    rate[k] = (double)n / secs;
    printf("  %s: %llu coagulation events in %.2f s: %.3g jumps/s\n", scheme[k], n, secs, rate[k]);
    gs_swa_case_free(&c);
  }
  printf("  N_max %ld, constant kernel, one thread: swa %.3g jumps/s (target 2e6: %s), %.2fx the dsa baseline measured in this run\n",
         nmax, rate[0], rate[0] >= 2e6 ? "met" : "NOT met", rate[0] / rate[1]);
  return 0;
}

static int sieve(const char *path, const char *ref, const char *save) {
  gs_swa_case c;
  if (load(NULL, path, &c)) return 1;
  if (!c.nsieve) {
    fprintf(stderr, "bench_swa: %s has no solver.sieves\n", path);
    return 1;
  }
  gs_error e = {0};
  gs_swa_report rep = {0};
  clock_t c0 = clock();
  int rc = gs_swa_case_run(&c, NULL, 0, NULL, NULL, &rep, &e);
  double cpu = (double)(clock() - c0) / CLOCKS_PER_SEC;
  if (rc) {
    printf("unstable: %s\n", e.msg);
    gs_swa_report_free(&rep);
    gs_swa_case_free(&c);
    return 0;
  }
  size_t k = c.nsieve, off = ((c.ntimes - 1) * c.model.ncomp + c.model.ncomp - 1) * k;
  const double *mu = rep.sieve_mean + off, *ci = rep.sieve_ci + off;
  double cbar = 0, sse = NAN;
  for (size_t j = 0; j < k; j++) cbar += ci[j] / (double)k;
  if (ref) {
    FILE *fp = fopen(ref, "r");
    if (fp) {
      sse = 0;
      for (size_t j = 0; j < k; j++) {
        double r;
        if (fscanf(fp, "%lf", &r) != 1) sse = NAN;
        else sse += (r - mu[j]) * (r - mu[j]);
      }
      fclose(fp);
    }
  }
  if (save) {
    FILE *fp = fopen(save, "w");
    for (size_t j = 0; fp && j < k; j++) fprintf(fp, "%.10g\n", mu[j]);
    if (fp) fclose(fp);
  }
  printf("%.3f %.3f %llu %.5g %.5g\n", cpu, rep.wall_seconds, (unsigned long long)rep.stats.jumps, cbar, sse);
  gs_swa_report_free(&rep);
  gs_swa_case_free(&c);
  return 0;
}

int main(int argc, char **argv) {
  if (argc >= 2 && !strcmp(argv[1], "jumps"))
    return jumps(argc > 2 ? atol(argv[2]) : 65536, argc > 3 ? atoi(argv[3]) : 8);
  if (argc >= 3 && !strcmp(argv[1], "sieve")) {
    const char *ref = NULL, *save = NULL;
    for (int i = 3; i + 1 < argc; i += 2) {
      if (!strcmp(argv[i], "--ref")) ref = argv[i + 1];
      else if (!strcmp(argv[i], "--save")) save = argv[i + 1];
    }
    return sieve(argv[2], ref, save);
  }
  fprintf(stderr, "usage: bench_swa jumps [N_MAX] [SESSIONS] | bench_swa sieve CASE [--ref FILE] [--save FILE]\n");
  return 2;
}
