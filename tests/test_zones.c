/* Zones from DEM particle frames (src/demdata/zones.c, kmeans.c) on
 * synthetic frames with a known answer: particles in two separated clouds
 * (positions 5 mm apart by 10 cm, velocities apart) hop between them with
 * probability p = k dt per frame interval, so that the crossing estimator's
 * expectation is exactly k.  Checks: every particle-frame is put in its own
 * cloud (exactly); k = 2 is chosen by the silhouette among 2..6; the rates
 * lie within 3 standard errors (fixed seed), and over 20 seeds their
 * z-scores have mean within 3/sqrt(20) of 0 and spread near 1 (the standard
 * error is honest); hold-ups, speeds and centres are the clouds'. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>

#include "check.h"
#include "demdata/zones.h"

enum { NP = 200, NF = 300 };
static const double DT = 0.005, K12 = 2.0, K21 = 3.0, R = 1e-3;

/* Frames of NP particles; truth[f * NP + i] their cloud (0 low, 1 high). */
static void synth(unsigned long seed, gs_zone_frames *fr, int *truth) {
  gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
  gsl_rng_set(r, seed);
  int state[NP];
  for (int i = 0; i < NP; i++) state[i] = i % 3 == 0; /* a third high, near the stationary 2/5 */
  for (int f = 0; f < NF; f++) {
    gs_zone_frame F = {.t = 1.0 + f * DT, .n = NP};
    F.id = malloc(NP * sizeof(long));
    F.x = malloc(3 * NP * sizeof(double));
    F.v = malloc(3 * NP * sizeof(double));
    F.volume = malloc(NP * sizeof(double));
    for (int j = 0; j < NP; j++) {
      const int i = (j * 7 + f) % NP; /* rows in a different order every frame: matched by id */
      F.id[j] = 1000 + i;
      truth[f * NP + j] = state[i];
      for (int a = 0; a < 3; a++) {
        F.x[3 * j + a] = (a == 2 && state[i] ? 0.1 : 0) + gsl_ran_gaussian(r, 0.005);
        F.v[3 * j + a] = (a == 0 && state[i] ? 0.5 : 0) + gsl_ran_gaussian(r, 0.02);
      }
      F.volume[j] = 4.0 / 3.0 * M_PI * R * R * R;
    }
    gs_zone_frames_add(fr, &F, NULL);
    for (int i = 0; i < NP; i++)
      if (gsl_rng_uniform(r) < (state[i] ? K21 : K12) * DT) state[i] = !state[i];
  }
  gsl_rng_free(r);
}

int main(void) {
  int *truth = malloc(NP * NF * sizeof(int));
  double zsum[2] = {0}, zsq[2] = {0};
  const int nseeds = 20;
  for (int s = 0; s < nseeds; s++) {
    gs_zone_frames fr = {0};
    gs_error err = {0};
    synth(100 + (unsigned long)s, &fr, truth);
    gs_zones z;
    CHECK(gs_zone_frames_sort(&fr, &err) == 0);
    if (gs_zones_identify(&fr, s == 0 ? 0 : 2, 6, 1.0, 1, &z, &err)) {
      fprintf(stderr, "identify failed: %s\n", err.msg);
      check_failures++;
      gs_zone_frames_free(&fr);
      continue;
    }
    size_t wrong = 0;
    for (size_t i = 0; i < z.nsample; i++) wrong += z.label[i] != (size_t)truth[i];
    CHECK(z.k == 2 && wrong == 0);
    const double k[2] = {K12, K21};
    for (int d = 0; d < 2 && z.k == 2; d++) {
      const double est = z.rate[d ? 2 : 1], sd = z.rate_sd[d ? 2 : 1], zs = (est - k[d]) / sd;
      zsum[d] += zs;
      zsq[d] += zs * zs;
      if (s == 0) {
        printf("seed %d: k chosen %zu (silhouette k=2 %.3f, k=3 %.3f), misassigned %zu of %zu; K12 = %.4g +- %.2g "
               "(true %g), K21 = %.4g +- %.2g (true %g)\n",
               s, z.k, z.sil_by_k[2], z.sil_by_k[3], wrong, z.nsample, z.rate[1], z.rate_sd[1], K12, z.rate[2],
               z.rate_sd[2], K21);
        CHECK(fabs(zs) < 3);
      }
    }
    if (s == 0 && z.k == 2) {
      CHECK(z.sil_by_k[2] > z.sil_by_k[3]);
      /* hold-ups: the frames' mean counts, exactly */
      double low = 0;
      for (size_t i = 0; i < z.nsample; i++) low += truth[i] == 0;
      CHECK(fabs(z.holdup[0] - low / NF) < 1e-9 && fabs(z.holdup[0] + z.holdup[1] - NP) < 1e-9);
      CHECK(fabs(z.solid[1] - z.holdup[1] * 4.0 / 3.0 * M_PI * R * R * R) < 1e-12 * z.solid[1]);
      CHECK(fabs(z.centre[5] - 0.1) < 1e-3 && fabs(z.centre[2]) < 1e-3);
      /* speed: mean |v| of a 3-D gaussian of sd 0.02 around 0 is 0.02 sqrt(8/pi) */
      CHECK(fabs(z.speed[0] - 0.02 * sqrt(8 / M_PI)) < 0.002);
      CHECK(fabs(z.speed[1] - 0.5) < 0.01);
      CHECK(gs_zones_write(&z, &fr, "/nonexistent/dir/x.yaml", &err) != 0);
    }
    gs_zones_free(&z);
    gs_zone_frames_free(&fr);
  }
  for (int d = 0; d < 2; d++) {
    const double mean = zsum[d] / nseeds, spread = sqrt(zsq[d] / nseeds - mean * mean);
    printf("K%s over %d seeds: z-scores mean %.3f, spread %.3f\n", d ? "21" : "12", nseeds, mean, spread);
    CHECK(fabs(mean) < 3 / sqrt(nseeds));
    CHECK(spread > 0.6 && spread < 1.5);
  }
  free(truth);
  TEST_EXIT();
}
