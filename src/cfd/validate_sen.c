/* The qualitative results of Sen et al. (2014) for a sprayed fluid bed
 * (CFD-DEM-PBM), measured on runs of the lab bed of examples/fluid-bed-cfd.yaml
 * and two variants of it: heterogeneous particle speeds, a wetter spray zone,
 * growth rising with the spray rate and with the gas velocity.  The case is
 * embedded so that an installed gransim needs no example file. */
#define _GNU_SOURCE
#include <errno.h>
#include <ftw.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gransim/cfd.h"
#include "gransim/cfg.h"
#include "gransim/dem.h"

/* examples/fluid-bed-cfd.yaml without its comments and VTK output, and with
 * 2 gas cells across instead of 4, half the gas work.  The drag closure needs
 * cells of at least 2 particle diameters along every axis, so the bed's depth
 * (one 10 mm cell, either way) stops a run whose aggregates reach 5 mm.  Without the example's dem.threads_from: one thread, so that
 * the figures (a chaotic flow, which the DEM's per-thread force sums perturb)
 * do not depend on the machine's core count. */
static const char bed_case[] =
    "dem:\n"
    "  time_step: 2.5e-5\n"
    "  duration: 0.8\n"
    "  gravity: [0, 0, -9.81]\n"
    "  box: {lo: [-0.005, -0.005, -0.005], hi: [0.045, 0.015, 0.205]}\n"
    "  skin: 4.0e-4\n"
    "  seed: 3\n"
    "materials:\n"
    "  - {name: powder, E: 1.0e6, nu: 0.25, e: 0.5, mu_s: 0.5, mu_r: 0.05, density: 1030}\n"
    "  - {name: steel, E: 1.0e6, nu: 0.25, e: 0.5, mu_s: 0.5, mu_r: 0.05}\n"
    "classes:\n"
    "  - {name: primary, radius: 1.0e-3, material: powder}\n"
    "walls:\n"
    "  - {name: distributor, plane: {point: [0, 0, 0], normal: [0, 0, 1]}, material: steel}\n"
    "  - {name: screen, plane: {point: [0, 0, 0.2], normal: [0, 0, -1]}, material: steel}\n"
    "  - {name: left, plane: {point: [0, 0, 0], normal: [1, 0, 0]}, material: steel}\n"
    "  - {name: right, plane: {point: [0.04, 0, 0], normal: [-1, 0, 0]}, material: steel}\n"
    "  - {name: front, plane: {point: [0, 0, 0], normal: [0, 1, 0]}, material: steel}\n"
    "  - {name: back, plane: {point: [0, 0.01, 0], normal: [0, -1, 0]}, material: steel}\n"
    "fill:\n"
    "  - region: {box: {lo: [0.001, 0.001, 0.001], hi: [0.039, 0.009, 0.1]}}\n"
    "    count: 2000\n"
    "gas:\n"
    "  box: {lo: [0, 0, 0], hi: [0.04, 0.01, 0.2]}\n"
    "  cells: [2, 1, 20]\n"
    "  inlet_velocity: 1.8\n"
    "  time_step: 5.0e-4\n"
    "  drag: di_felice\n"
    "  output: {every: 0.05}\n"
    "spray:\n"
    "  point: [0.02, 0.005, 0.1]\n"
    "  axis: [0, 0, -1]\n"
    "  half_angle: 5\n"
    "  droplet_diameter: 1.26e-3\n"
    "  mass_rate: 8.0e-3\n"
    "  density: 1000\n"
    "  speed: 2.0\n"
    "  start: 0.4\n"
    "granulation:\n"
    "  every: 0.05\n"
    "  rule: {type: constant, efficiency: 0.05, min_liquid_content: 0.2}\n"
    "  solid_classes: {count: 8}\n"
    "  liquid_classes: {count: 8}\n"
    "statistics:\n"
    "  sample_every: 0.01\n"
    "output:\n"
    "  every: 0.05\n";

#define T_SPEED 0.7   /* [s] the speeds are taken there, in the sprayed bed */
#define ZONE_R 0.01   /* [m] "under the nozzle": within this distance of its axis */
#define NOZZLE_X 0.02 /* [m] the nozzle axis (spray.point) */
#define NOZZLE_Y 0.005

typedef struct {
  gs_dem_case *c;
  int have_speed;
  double p10, p50, p90;             /* speed percentiles at T_SPEED [m/s] */
  double liq_zone, liq_rest;        /* mean l/(s+l) by volume at the end */
  size_t n_zone, n_rest;
  double d_mean;                    /* number-mean diameter at the end [m] */
} bed_figures;

static int cmp_double(const void *a, const void *b) {
  const double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double percentile(const double *sorted, size_t n, double q) {
  const double at = q * (double)(n - 1);
  const size_t i = (size_t)at;
  return i + 1 < n ? sorted[i] + (at - (double)i) * (sorted[i + 1] - sorted[i]) : sorted[n - 1];
}

/* every statistics sample: the speeds once at T_SPEED, liquid and size at
 * every sample (the last one, at the end of the run, is kept) */
static int observe(const gs_dem_sample *s, void *user, int *open_window, int *stop, gs_error *err) {
  (void)open_window, (void)stop;
  bed_figures *f = user;
  gs_dem_view v;
  gs_dem_get_view(gs_dem_case_sim(f->c), &v);
  if (v.n == 0) return 0;
  if (!f->have_speed && s->t >= T_SPEED - 1e-9) {
    double *u = malloc(v.n * sizeof *u);
    if (!u) {
      gs_error_set(err, GS_ENOMEM, "qualitative bed: out of memory");
      return 1;
    }
    for (size_t i = 0; i < v.n; i++) u[i] = sqrt(v.vx[i] * v.vx[i] + v.vy[i] * v.vy[i] + v.vz[i] * v.vz[i]);
    qsort(u, v.n, sizeof *u, cmp_double);
    f->p10 = percentile(u, v.n, 0.1), f->p50 = percentile(u, v.n, 0.5), f->p90 = percentile(u, v.n, 0.9);
    f->have_speed = 1;
    free(u);
  }
  double lz = 0, lr = 0, d = 0;
  size_t nz = 0, nr = 0;
  for (size_t i = 0; i < v.n; i++) {
    const double l = v.vl[i] / (v.vs[i] + v.vl[i]);
    if (hypot(v.x[i] - NOZZLE_X, v.y[i] - NOZZLE_Y) < ZONE_R) lz += l, nz++;
    else lr += l, nr++;
    d += 2 * v.r[i];
  }
  f->liq_zone = nz ? lz / (double)nz : 0, f->liq_rest = nr ? lr / (double)nr : 0;
  f->n_zone = nz, f->n_rest = nr, f->d_mean = d / (double)v.n;
  return 0;
}

static int rm_entry(const char *path, const struct stat *sb, int flag, struct FTW *ftw) {
  (void)sb, (void)flag, (void)ftw;
  return remove(path);
}

/* one run of the bed at this spray rate [kg/s] and gas velocity [m/s], its
 * outputs in a scratch folder removed afterwards */
static int run_bed(double mass_rate, double inlet, bed_figures *f, gs_error *err) {
  memset(f, 0, sizeof *f);
  gs_cfg *cfg = gs_cfg_load_string(bed_case, "fluid bed of Sen et al. (validate-cfd)", err);
  if (!cfg) return 1;
  char v[32];
  snprintf(v, sizeof v, "%.17g", mass_rate);
  if (gs_cfg_set(cfg, "spray.mass_rate", v, err)) return gs_cfg_free(cfg), 1;
  snprintf(v, sizeof v, "%.17g", inlet);
  if (gs_cfg_set(cfg, "gas.inlet_velocity", v, err)) return gs_cfg_free(cfg), 1;
  gs_dem_case *c = gs_dem_case_from_cfg(cfg, err);
  if (!c) return 1;
  const char *tmp = getenv("TMPDIR");
  char dir[4096];
  snprintf(dir, sizeof dir, "%s/gransim-sen-XXXXXX", tmp && *tmp ? tmp : "/tmp");
  if (!mkdtemp(dir)) {
    gs_error_set(err, GS_EIO, "%s: %s", dir, strerror(errno));
    gs_dem_case_free(c);
    return 1;
  }
  int rc = 1;
  gs_cfd *gas = gs_cfd_case_create(c, dir, err);
  if (gas) {
    f->c = c;
    gs_dem_case_set_observer(c, &(gs_dem_observer){.sample = observe, .user = f});
    rc = gs_dem_case_run(c, dir, 0, err);
    gs_cfd_free(gas);
  }
  gs_dem_case_free(c);
  nftw(dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
  if (!rc && !f->have_speed) {
    gs_error_set(err, GS_ENUMERIC, "no statistics sample at %.2f s", T_SPEED);
    rc = 1;
  }
  /* say which of the three runs failed */
  if (rc) gs_error_prefix(err, "sprayed bed of Sen et al. at %g g/s and %g m/s: ", mass_rate * 1e3, inlet);
  return rc;
}

int gs_cfd_check_sen(gs_cfd_check out[4], gs_error *err) {
  bed_figures base, slow_spray, slow_gas;
  if (run_bed(8e-3, 1.8, &base, err) || run_bed(4e-3, 1.8, &slow_spray, err) ||
      run_bed(8e-3, 1.2, &slow_gas, err))
    return 1;
  out[0] = (gs_cfd_check){.name = "heterogeneous particle speeds (p90 / p10)", .got = base.p90 / base.p10,
                          .want = GS_SEN_SPEED_RATIO, .tol = 0, .unit = ""};
  snprintf(out[0].detail, sizeof out[0].detail,
           "speed at %.1f s, 10th/50th/90th percentile %.3f/%.3f/%.3f m/s; 8 g/s, 1.8 m/s", T_SPEED, base.p10,
           base.p50, base.p90);
  out[1] = (gs_cfd_check){.name = "a wetter spray zone (l/(s+l) under the nozzle / elsewhere)",
                          .got = base.liq_zone / base.liq_rest, .want = GS_SEN_ZONE_RATIO, .tol = 0, .unit = ""};
  snprintf(out[1].detail, sizeof out[1].detail,
           "at 0.8 s, within 10 mm of the nozzle axis %.4f (%zu particles) against %.4f (%zu)", base.liq_zone,
           base.n_zone, base.liq_rest, base.n_rest);
  out[2] = (gs_cfd_check){.name = "growth rising with the spray rate (d at 8 g/s vs 4 g/s)",
                          .got = base.d_mean * 1e3, .want = slow_spray.d_mean * 1e3, .tol = 0, .unit = "mm"};
  snprintf(out[2].detail, sizeof out[2].detail, "number-mean diameter at 0.8 s, 1.8 m/s, from 2 mm");
  out[3] = (gs_cfd_check){.name = "growth rising with the gas velocity (d at 1.8 vs 1.2 m/s)",
                          .got = base.d_mean * 1e3, .want = slow_gas.d_mean * 1e3, .tol = 0, .unit = "mm"};
  snprintf(out[3].detail, sizeof out[3].detail, "number-mean diameter at 0.8 s, 8 g/s, from 2 mm");
  return 0;
}
