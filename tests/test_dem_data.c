/* DEM dump reader and reducer (include/gransim/dem_data.h): the Hertz contact
 * time against an independent integration, a synthetic dump with known
 * contacts and impacts (exact C_ij, rates, fits), the bundled CoriMix dumps
 * against the independent integer tables of
 * the reference code's reading notes (section 6), the kernel-table
 * round trip, and bad input. */
#include <dirent.h>
#include <gsl/gsl_cdf.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_integration.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "gransim/cfg.h"
#include "gransim/dem.h"
#include "gransim/dem_data.h"
#include "gransim/grid.h"
#include "gransim/kernel.h"

/* ---- temporary directories ------------------------------------------------ */
static void write_file(const char *dir, const char *name, const char *text) {
  char path[512];
  snprintf(path, sizeof path, "%s/%s", dir, name);
  FILE *fp = fopen(path, "w");
  if (!fp) { perror(path); exit(2); }
  fputs(text, fp);
  fclose(fp);
}

static void remove_dir(const char *dir) {
  DIR *dp = opendir(dir);
  if (!dp) return;
  char path[512];
  for (struct dirent *e; (e = readdir(dp));) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    unlink(path);
  }
  closedir(dp);
  rmdir(dir);
}

static char *make_dir(void) {
  static char buf[8][64];
  static int k = 0;
  char *d = buf[k++ % 8];
  strcpy(d, "/tmp/gs_demdata_XXXXXX");
  if (!mkdtemp(d)) { perror("mkdtemp"); exit(2); }
  return d;
}

/* ---- 1. Hertz contact time --------------------------------------------------- */
static double inv_sqrt_integrand(double u, void *p) {
  (void)p;
  return 1 / sqrt(1 - pow(u, 2.5));
}

typedef struct { double m, kh, c, estar, reff; } impact_prm;

/* m x'' = -4/3 E* sqrt(R) x^1.5 - gamma x', gamma = c sqrt(2 E* sqrt(R x) m) */
static int impact_rhs(double t, const double y[], double f[], void *p) {
  (void)t;
  const impact_prm *q = p;
  double x = fmax(y[0], 0);
  double gamma = q->c * sqrt(2 * q->estar * sqrt(q->reff * x) * q->m);
  f[0] = y[1];
  f[1] = (-q->kh * x * sqrt(x) - gamma * y[1]) / q->m;
  return GSL_SUCCESS;
}

/* Duration until the overlap returns to 0, by GSL's RK8PD with a fixed fine output step. */
static double integrate_contact(double m, double reff, double estar, double v, double c) {
  impact_prm q = {m, 4.0 / 3.0 * estar * sqrt(reff), c, estar, reff};
  gsl_odeiv2_system sys = {impact_rhs, NULL, 2, &q};
  double scale = pow(m * m / (reff * estar * estar * v), 0.2), h = scale * 1e-4;
  gsl_odeiv2_driver *drv = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, h * 1e-2, 1e-13, 1e-13);
  double t = 0, y[2] = {0, v}, tprev = 0, xprev = 0;
  for (int i = 1; i < 1000000; i++) {
    double ti = i * h;
    if (gsl_odeiv2_driver_apply(drv, &t, ti, y) != GSL_SUCCESS) break;
    if (y[0] <= 0) { /* cubic-free: linear interpolation inside a tiny step */
      gsl_odeiv2_driver_free(drv);
      return tprev + (ti - tprev) * xprev / (xprev - y[0]);
    }
    tprev = ti;
    xprev = y[0];
  }
  gsl_odeiv2_driver_free(drv);
  return NAN;
}

static void test_hertz(void) {
  /* elastic: t = tau0 (3/4)^(2/5) (m^2/(R E^2 v))^(1/5), tau0 = 2 xi_max int_0^1 du/sqrt(1-u^(5/2)) */
  gsl_integration_workspace *w = gsl_integration_workspace_alloc(1000);
  gsl_function F = {inv_sqrt_integrand, NULL};
  double I, abserr;
  gsl_integration_qags(&F, 0, 1, 0, 1e-12, 1000, w, &I, &abserr);
  gsl_integration_workspace_free(w);
  double tau0 = 2 * pow(1.25, 0.4) * I;
  CHECK_REL(tau0 * pow(0.75, 0.4), 2.868, 2e-4);
  double m = 500 * 4.0 / 3.0 * M_PI * pow(0.002, 3), meff = m / 2, reff = 0.001;
  double estar = 8e6 / (2 * (1 - 0.04));
  double v = 0.5;
  double scale = pow(meff * meff / (reff * estar * estar * v), 0.2);
  CHECK_REL(gs_dem_hertz_contact_time(meff, reff, estar, v, 1), 2.868 * scale, 1e-15);
  CHECK_REL(gs_dem_hertz_contact_time(meff, reff, estar, v, 0), 2.868 * scale, 1e-15);
  CHECK_REL(integrate_contact(meff, reff, estar, v, 0), tau0 * pow(0.75, 0.4) * scale, 1e-5);
  /* damped (LIGGGHTS damping for e = 0.4): against the dimensional ODE */
  double c = gs_dem_damping_coefficient(0.4, GS_DEM_DAMPING_LIGGGHTS);
  double td = gs_dem_hertz_contact_time(meff, reff, estar, v, 0.4);
  CHECK_REL(td, integrate_contact(meff, reff, estar, v, c), 2e-4);
  fprintf(stderr, "hertz: damped (e = 0.4) / elastic contact duration = %.4f\n", td / (2.868 * scale));
  CHECK(td > 2.868 * scale && td < 1.5 * 2.868 * scale); /* the unclamped damping force holds on longer */
  /* v^(-1/5) scaling */
  CHECK_REL(gs_dem_hertz_contact_time(meff, reff, estar, 32 * v, 0.4), td / 2, 1e-12);
  CHECK(isnan(gs_dem_hertz_contact_time(meff, reff, estar, 0, 0.4)));
}

/* ---- 2. synthetic dumps ------------------------------------------------------------- */
/* 7 atoms: ids 1-4 type 1 (r 1 mm), 5-6 type 2 (r 1.5 mm), 7 type 3 (r 2 mm).  Contacts (owner
 * first): 1-2 (1-1), 1-5 (1-2), 6-3 (2-1), 7-1 (3-1), 5-6 (2-2): K11 = 1, K12 = 2, K13 = 1,
 * K22 = 1.  The contact columns are tallied as LAMMPS compute contact/atom on type groups
 * does (both atoms, in the column of the owner's type).  Columns deliberately out of the
 * LIGGGHTS order. */
static const char *syn_coll100 =
    "ITEM: TIMESTEP\n100\nITEM: NUMBER OF ATOMS\n7\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
    "ITEM: ATOMS id type radius c_cc_1 c_cc_2 c_cc_3 x y z vx vy vz f_fppacc\n"
    "1 1 0.001 2 0 1 0 0 0 0 0 0 5\n"
    "2 1 0.001 1 0 0 0 0 0 0 0 0 5\n"
    "3 1 0.001 0 1 0 0 0 0 0 0 0 5\n"
    "4 1 0.001 0 0 0 0 0 0 1 0 0 5\n"
    "5 2 0.0015 1 1 0 0 0 0 0 0 0 5\n"
    "6 2 0.0015 0 2 0 0 0 0 0 0 0 5\n"
    "7 3 0.002 0 0 1 0 0 0 0 0 0 5\n";
static const char *syn_coll200 =
    "ITEM: TIMESTEP\n200\nITEM: NUMBER OF ATOMS\n7\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
    "ITEM: ATOMS id type radius c_cc_1 c_cc_2 c_cc_3 x y z vx vy vz f_fppacc\n"
    "4 1 0.001 0 0 0 0 0 0 0 0 0 5\n3 1 0.001 0 0 0 0 0 0 0 0 0 5\n2 1 0.001 0 0 0 0 0 0 0 0 0 5\n"
    "1 1 0.001 0 0 0 0 0 0 0 0 0 5\n7 3 0.002 0 0 0 0 0 0 0 0 0 5\n6 2 0.0015 0 0 0 0 0 0 0 0 0 5\n"
    "5 2 0.0015 0 0 0 0 0 0 0 0 0 5\n";
/* relative speeds 1, 32, 1, 32, 1; a sixth neighbour pair without overlap or velocities */
static const char *syn_pp100 =
    "ITEM: TIMESTEP\n100\nITEM: NUMBER OF ENTRIES\n6\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
    "ITEM: ENTRIES c_ppc[1] c_ppc[2] c_ppc[3] c_ppc[4] c_ppc[5] c_ppc[6] c_ppc[7] c_ppc[8] c_ppc[9] "
    "c_ppc[10] c_ppc[11] c_ppc[12] c_ppc[13] c_ppc[14]\n"
    "1 0 0 0 0 0 1 2 0 0 0 0 1e-7 1e-5\n"
    "0 32 0 0 0 0 1 5 0 0 0 0 1e-7 1e-5\n"
    "0 0 0 0 0 1 6 3 0 0 0 0 1e-7 1e-5\n"
    "0 0 0 0 -32 0 7 1 0 0 0 0 1e-7 1e-5\n"
    "0.5 0 0 -0.5 0 0 5 6 0 0 0 0 1e-7 1e-5\n"
    "0 0 0 0 0 0 2 4 0 0 0 0 0 0\n";
static const char *syn_pp200 =
    "ITEM: TIMESTEP\n200\nITEM: NUMBER OF ENTRIES\n0\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
    "ITEM: ENTRIES c_ppc[1] c_ppc[2] c_ppc[3] c_ppc[4] c_ppc[5] c_ppc[6] c_ppc[7] c_ppc[8] c_ppc[9] "
    "c_ppc[10] c_ppc[11] c_ppc[12] c_ppc[13] c_ppc[14]\n";
/* wall contacts: class 1 at relative speeds 1 (shell), 2 (impeller), 4 (shell) and one resting;
 * class 2 at 3 (shell) */
static const char *syn_imp100 =
    "ITEM: TIMESTEP\n100\nITEM: NUMBER OF ENTRIES\n5\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
    "ITEM: ENTRIES c_pwc[1] c_pwc[2] c_pwc[3] c_pwc[4] c_pwc[5] c_pwc[6] c_pwc[7] c_pwc[8] c_pwc[9] "
    "c_pwc[10] c_pwc[11] c_pwc[12] c_pwc[13] c_pwc[14]\n"
    "0 0 0 0.6 0.8 0 0 11 1 0 0 1 1e-7 1e-5\n"
    "0 10 0 0 12 0 1 12 2 0 0 1 1e-7 1e-5\n"
    "0 0 0 0 0 -4 0 13 3 0 0 1 1e-7 1e-5\n"
    "0 0 0 1e-6 0 0 0 14 4 0 0 1 1e-7 1e-5\n"
    "0 0 0 3 0 0 0 15 5 0 0 1 1e-7 1e-5\n";
static const char *syn_imp200 =
    "ITEM: TIMESTEP\n200\nITEM: NUMBER OF ENTRIES\n0\nITEM: BOX BOUNDS ff ff ff\n0 1\n0 1\n0 1\n"
    "ITEM: ENTRIES c_pwc[1] c_pwc[2] c_pwc[3] c_pwc[4] c_pwc[5] c_pwc[6] c_pwc[7] c_pwc[8] c_pwc[9] "
    "c_pwc[10] c_pwc[11] c_pwc[12] c_pwc[13] c_pwc[14]\n";

static const char *write_synthetic(void) {
  const char *dir = make_dir();
  write_file(dir, "collision100.atom", syn_coll100);
  write_file(dir, "collision200.atom", syn_coll200);
  write_file(dir, "ppcoll100.atom", syn_pp100);
  write_file(dir, "ppcoll200.atom", syn_pp200);
  write_file(dir, "impact100.atom", syn_imp100);
  write_file(dir, "impact200.atom", syn_imp200);
  write_file(dir, "notes.txt", "not a dump\n");
  return dir;
}

static void check_synthetic_c(const gs_dem_data *d, double tc) {
  /* snapshot 1: E = K / tc; C_ij = E/(N_i N_j), C_ii = 2 E/N_i^2; snapshot 2: 0 */
  const double want[9] = {2 * (1 / tc) / 16, (2 / tc) / 8, (1 / tc) / 4,
                          (2 / tc) / 8,      2 * (1 / tc) / 4, 0,
                          (1 / tc) / 4,      0,                0};
  for (int k = 0; k < 9; k++) {
    CHECK_REL(d->collision[k], want[k] / 2, 1e-14);
    CHECK_REL(d->collision_sd[k], want[k] / sqrt(2), 1e-14);
  }
  const double K[9] = {1, 2, 1, 2, 1, 0, 1, 0, 0};
  for (int k = 0; k < 9; k++) CHECK_REL(d->contacts[k], K[k] / 2, 1e-15);
}

static void test_synthetic(void) {
  const char *dir = write_synthetic();
  gs_dem_options opt;
  gs_dem_options_default(&opt);
  opt.contact_time = 0.5;
  opt.quiet = 1;
  gs_error err = {0};
  gs_dem_data d;
  int rc = gs_dem_data_read(dir, &opt, &d, &err);
  CHECK(rc == 0);
  if (rc) { fprintf(stderr, "%s\n", err.msg); remove_dir(dir); return; }
  CHECK(d.nclass == 3 && d.nsnap == 2 && d.steps[0] == 100 && d.steps[1] == 200);
  CHECK(d.contacts_from == GS_DEM_CONTACTS_PPCOLL);
  CHECK_REL(d.diameter[0], 0.002, 1e-15);
  CHECK_REL(d.diameter[1], 0.003, 1e-15);
  CHECK_REL(d.diameter[2], 0.004, 1e-15);
  CHECK(d.count[0] == 4 && d.count[1] == 2 && d.count[2] == 1 && d.count_sd[0] == 0);
  CHECK(d.contact_time == 0.5 && d.pair_contact_time[5] == 0.5 && d.wall_contact_time[2] == 0.5);
  check_synthetic_c(&d, 0.5);
  /* raw per-type sums S (mean of snapshot 1 and the empty snapshot 2) */
  const double S[9] = {3, 1, 1, 1, 3, 0, 0, 0, 1};
  for (int k = 0; k < 9; k++) CHECK(d.cc_sum[k] == S[k] / 2);
  CHECK_REL(d.like_share_pp, 2.0 / 5.0, 1e-15);
  CHECK_REL(d.like_share_cc, 2.0 / 5.0, 1e-15);
  /* wall impacts: class 1 has 4 contacts (3 shell, 1 impeller) among 4 particles in snapshot 1 */
  CHECK_REL(d.impact_rate[0], 0.5 * 4 / 0.5 / 4, 1e-15);
  CHECK_REL(d.impact_rate_sd[0], 2 / sqrt(2), 1e-14);
  CHECK_REL(d.impeller_rate[0], 0.5 * 1 / 0.5 / 4, 1e-15);
  CHECK_REL(d.shell_rate[0], 0.5 * 3 / 0.5 / 4, 1e-15);
  CHECK_REL(d.impact_rate[1], 0.5 * 1 / 0.5 / 2, 1e-15);
  CHECK(d.impact_rate[2] == 0 && d.impeller_rate[1] == 0);
  CHECK(d.wall_contacts[0] == 2 && d.wall_contacts[1] == 0.5);
  /* speeds: class 1 {1, 2, 4} -> mu = sigma = ln 2; class 2 one sample; resting row left out */
  CHECK(d.nvel[0] == 3 && d.nvel[1] == 1 && d.nvel[2] == 0 && d.nresting == 1 && d.all_nvel == 4);
  CHECK_REL(d.vel_mu[0], log(2), 1e-14);
  CHECK_REL(d.vel_sigma[0], log(2), 1e-14);
  CHECK(isnan(d.vel_mu[1]) && isnan(d.vel_sigma[2]));
  double l[4] = {0, log(2), log(4), log(3)}, m = (l[0] + l[1] + l[2] + l[3]) / 4, var = 0;
  for (int k = 0; k < 4; k++) var += (l[k] - m) * (l[k] - m) / 3;
  CHECK_REL(d.all_mu, m, 1e-14);
  CHECK_REL(d.all_sigma, sqrt(var), 1e-14);
  /* P(U > u) from the class fit, or the pooled one */
  CHECK_REL(gs_dem_break_probability(&d, 0, 2.5), gsl_cdf_lognormal_Q(2.5, log(2), log(2)), 1e-14);
  CHECK_REL(gs_dem_break_probability(&d, 1, 2.5), gsl_cdf_lognormal_Q(2.5, m, sqrt(var)), 1e-14);
  CHECK_REL(gs_dem_break_probability(&d, 2, 0.7), gsl_cdf_lognormal_Q(0.7, m, sqrt(var)), 1e-14);
  CHECK_REL(gs_dem_break_probability(&d, 0, 2), 0.5, 1e-14); /* the median */
  CHECK(gs_dem_break_probability(&d, 0, 0) == 1);

  /* kernel table: edges between the diameters (in volume), read back by the `table` kernel */
  char table[128];
  snprintf(table, sizeof table, "%s/table.csv", dir);
  d.edges_volume = 1;
  CHECK(gs_dem_data_write_table(&d, table, &err) == 0);
  double ve[4];
  const double de[4] = {0.0016, 0.0025, 0.0035, 0.0046};
  for (int k = 0; k < 4; k++) ve[k] = M_PI / 6 * de[k] * de[k] * de[k];
  gs_axis ax;
  gs_grid g;
  memset(&g, 0, sizeof g);
  CHECK(gs_axis_from_edges(&ax, "solid", ve, 4, NULL, &err) == 0);
  CHECK(gs_grid_init(&g, &ax, 1, 1, &err) == 0);
  char yaml[512];
  snprintf(yaml, sizeof yaml, "type: table\nfile: %s\nmeasure: volume\nbeta0: 2\n", table);
  gs_cfg *cfg = gs_cfg_load_string(yaml, "kernel", &err);
  gs_kernel k = {0};
  rc = cfg ? gs_kernel_create(gs_cfg_root(cfg), &g, ".", &k, &err) : 1;
  CHECK(rc == 0);
  if (rc) fprintf(stderr, "%s\n", err.msg);
  else
    for (size_t a = 0; a < 3; a++) {
      double row[3];
      k.type->row(k.self, 0, a, 0, 3, row);
      for (size_t b = 0; b < 3; b++) CHECK_REL(row[b], 2 * d.collision[a * 3 + b], 1e-9);
    }
  if (!rc) gs_kernel_free(&k);
  gs_cfg_free(cfg);
  gs_grid_free(&g);
  /* explicit edges that do not increase are refused */
  double bad_edges[4] = {1, 2, 2, 3};
  d.edges = malloc(sizeof bad_edges);
  memcpy(d.edges, bad_edges, sizeof bad_edges);
  CHECK(gs_dem_data_write_table(&d, table, &err) == GS_EINPUT && strstr(err.msg, "increasing"));
  gs_dem_data_free(&d);

  /* the contact columns (LAMMPS tally) give the same contacts as the pair dumps */
  opt.contacts_from = GS_DEM_CONTACTS_CC_OWNER;
  CHECK(gs_dem_data_read(dir, &opt, &d, &err) == 0);
  check_synthetic_c(&d, 0.5);
  gs_dem_data_free(&d);

  /* Hertz durations: v_pair = (mean u^(1/5))^5 over the ppcoll rows with velocities */
  gs_dem_options_default(&opt);
  opt.quiet = 1;
  CHECK(gs_dem_data_read(dir, &opt, &d, &err) == 0);
  CHECK(d.nv_pair == 5);
  CHECK_REL(d.v_pair, pow(1.4, 5), 1e-14);
  double uw = (1 + pow(2, 0.2) + pow(4, 0.2) + pow(1e-6, 0.2) + pow(3, 0.2)) / 5;
  CHECK_REL(d.v_wall, pow(uw, 5), 1e-14);
  double m1 = 500 * 4.0 / 3.0 * M_PI * 1e-9, m2 = 500 * 4.0 / 3.0 * M_PI * pow(0.0015, 3);
  double estar = 8e6 / (2 * (1 - 0.04));
  CHECK_REL(d.pair_contact_time[1],
            gs_dem_hertz_contact_time(m1 * m2 / (m1 + m2), 0.001 * 0.0015 / 0.0025, estar, pow(1.4, 5), 0.4), 1e-14);
  CHECK(d.pair_contact_time[1] == d.pair_contact_time[3]);
  double ew = 1 / ((1 - 0.04) / 8e6 + (1 - 0.04) / 9.99e8);
  CHECK_REL(d.wall_contact_time[0], gs_dem_hertz_contact_time(m1, 0.001, ew, pow(uw, 5), 0.4), 1e-14);
  CHECK_REL(d.collision[1], 0.5 * (2 / d.pair_contact_time[1]) / 8, 1e-14);
  CHECK_REL(d.collision[0], 0.5 * 2 * (1 / d.pair_contact_time[0]) / 16, 1e-14);
  gs_dem_data_free(&d);
  remove_dir(dir);
}

/* ---- 3. bad input ------------------------------------------------------------------ */
static void expect_error(const char *dir, const gs_dem_options *opt, const char *w1, const char *w2) {
  gs_error err = {0};
  gs_dem_data d;
  int rc = gs_dem_data_read(dir, opt, &d, &err);
  CHECK(rc != 0);
  if (!rc) { gs_dem_data_free(&d); return; }
  if (!strstr(err.msg, w1) || (w2 && !strstr(err.msg, w2))) {
    fprintf(stderr, "message '%s' lacks '%s' / '%s'\n", err.msg, w1, w2 ? w2 : "");
    CHECK(!"error message");
  }
}

static void test_bad_input(void) {
  gs_dem_options opt;
  gs_dem_options_default(&opt);
  opt.contact_time = 1;
  opt.quiet = 1;
  const char *dir = make_dir();
  expect_error(dir, &opt, "no pair of collision", NULL);
  expect_error("/nonexistent/dumps", &opt, "/nonexistent/dumps", "cannot open");
  write_file(dir, "impact100.atom", syn_imp100);
  write_file(dir, "ppcoll100.atom", syn_pp100);
  /* missing radius column */
  char *t = strdup(syn_coll100);
  char *p = strstr(t, "radius");
  memcpy(p, "radiux", 6);
  write_file(dir, "collision100.atom", t);
  expect_error(dir, &opt, "collision100.atom:9:", "no column 'radius'");
  /* truncated after 5 of 7 rows */
  strcpy(t, syn_coll100);
  p = strstr(t, "5 2 0.0015");
  *p = 0;
  write_file(dir, "collision100.atom", t);
  expect_error(dir, &opt, "collision100.atom:13:", "truncated");
  /* cut in the middle of a row */
  strcpy(t, syn_coll100);
  p = strstr(t, "5 2 0.0015");
  p[8] = 0;
  write_file(dir, "collision100.atom", t);
  expect_error(dir, &opt, "collision100.atom:14:", "has 3 values, expected 13");
  /* not a number */
  strcpy(t, syn_coll100);
  p = strstr(t, "3 1 0.001 0 1 0");
  p[12] = 'x';
  write_file(dir, "collision100.atom", t);
  expect_error(dir, &opt, "collision100.atom:12:", "column 'c_cc_2'");
  /* fractional contact count, bad type */
  {
    char frac[4096];
    const char *row = strstr(syn_coll100, "3 1 0.001"), *next = strchr(row, '\n');
    snprintf(frac, sizeof frac, "%.*s3 1 0.001 0 1.5 0 0 0 0 0 0 0 5%s", (int)(row - syn_coll100), syn_coll100, next);
    write_file(dir, "collision100.atom", frac);
  }
  expect_error(dir, &opt, "collision100.atom:12:", "contact count");
  strcpy(t, syn_coll100);
  p = strstr(t, "3 1 0.001");
  p[2] = '4';
  write_file(dir, "collision100.atom", t);
  expect_error(dir, &opt, "collision100.atom:12:", "expected an integer 1..3");
  free(t);
  /* an impact on an atom that is not in the snapshot */
  write_file(dir, "collision100.atom", syn_coll100);
  t = strdup(syn_imp100);
  p = strstr(t, "0 15 5 ");
  p[5] = '9';
  write_file(dir, "impact100.atom", t);
  expect_error(dir, &opt, "impact100.atom:14:", "no such atom");
  free(t);
  /* a local dump with the wrong number of columns */
  write_file(dir, "impact100.atom", syn_coll100);
  expect_error(dir, &opt, "impact100.atom:9:", "expected the 14");
  /* missing NUMBER OF ATOMS */
  write_file(dir, "impact100.atom", syn_imp100);
  write_file(dir, "collision100.atom", "ITEM: TIMESTEP\n100\nITEM: ATOMS id type\n1 1\n");
  expect_error(dir, &opt, "collision100.atom:3:", "before ITEM: NUMBER OF ATOMS");
  /* two snapshots in one file */
  char two[4096];
  snprintf(two, sizeof two, "%s%s", syn_coll100, syn_coll100);
  write_file(dir, "collision100.atom", two);
  expect_error(dir, &opt, "collision100.atom:17:", "second snapshot");
  /* ppcoll demanded but missing for a step */
  write_file(dir, "collision100.atom", syn_coll100);
  write_file(dir, "collision200.atom", syn_coll200);
  write_file(dir, "impact200.atom", syn_imp200);
  opt.contacts_from = GS_DEM_CONTACTS_PPCOLL;
  expect_error(dir, &opt, "ppcoll200.atom", "missing");
  opt.contacts_from = GS_DEM_CONTACTS_AUTO;
  gs_error err = {0};
  gs_dem_data d;
  CHECK(gs_dem_data_read(dir, &opt, &d, &err) == 0 && d.contacts_from == GS_DEM_CONTACTS_CC_OWNER);
  gs_dem_data_free(&d);
  opt.contact_time = 0;
  opt.youngs = -1;
  expect_error(dir, &opt, "Young's modulus", NULL);
  remove_dir(dir);
}

/* ---- 4. the bundled CoriMix dumps ----------------------------------------------------- */
/* S_ij = sum over type-i atoms of c_cc_j at step 19,000,000 (reference section 6) */
static const int S19[16][16] = {
    {168, 23, 21, 16, 11, 23, 6, 10, 5, 4, 5, 3, 0, 0, 2, 0}, {19, 142, 28, 21, 9, 21, 12, 6, 5, 3, 1, 2, 0, 0, 0, 0},
    {26, 21, 161, 12, 11, 13, 7, 5, 2, 3, 2, 0, 0, 1, 2, 0},  {16, 13, 20, 137, 8, 7, 3, 14, 3, 5, 2, 3, 1, 1, 0, 0},
    {12, 9, 17, 7, 70, 9, 6, 8, 4, 0, 0, 0, 0, 0, 1, 0},      {18, 13, 17, 16, 4, 107, 12, 5, 4, 2, 4, 2, 0, 0, 0, 0},
    {10, 7, 10, 12, 7, 4, 75, 5, 2, 0, 0, 1, 1, 0, 0, 0},     {11, 13, 6, 9, 3, 0, 3, 65, 0, 3, 2, 0, 0, 0, 0, 0},
    {2, 6, 1, 5, 0, 2, 2, 1, 35, 1, 0, 0, 0, 0, 0, 0},        {6, 2, 7, 2, 1, 2, 3, 0, 0, 30, 0, 1, 0, 0, 1, 0},
    {3, 1, 2, 1, 1, 2, 2, 0, 0, 1, 21, 1, 0, 1, 0, 0},        {5, 3, 1, 1, 0, 0, 1, 0, 0, 1, 0, 16, 0, 0, 0, 0},
    {3, 2, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 4, 0, 0, 0},         {1, 1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 6, 0, 0},
    {0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 8, 0},         {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}};
static const double N19[16] = {363, 352, 325, 290, 210, 229, 153, 141, 81, 62, 39, 22, 13, 10, 4, 2};
static const double IMP19[16] = {58, 75, 72, 73, 36, 53, 20, 47, 25, 10, 5, 3, 1, 0, 0, 1};

static int find_data(char *out, size_t n) {
  const char *src = getenv("GRANSIM_SOURCE_DIR");
  /* bundled with the examples; without GRANSIM_SOURCE_DIR the test runs in tests/ */
  snprintf(out, n, "%s/examples/data/corimix/dem_dumps", src ? src : "..");
  DIR *dp = opendir(out);
  if (!dp) return 0;
  closedir(dp);
  return 1;
}

static void test_corimix(void) {
  char data[1024];
  if (!find_data(data, sizeof data)) {
    fprintf(stderr, "the bundled CoriMix dumps are missing: %s\n", data);
    CHECK(0);
    return;
  }
  /* one snapshot, step 19,000,000 */
  const char *dir = make_dir();
  char from[2048], to[256];
  const char *names[3] = {"collision19000000.atom", "impact19000000.atom", "ppcoll19000000.atom"};
  for (int k = 0; k < 3; k++) {
    snprintf(from, sizeof from, "%s/%s", data, names[k]);
    if (from[0] != '/') { /* make the link absolute */
      char cwd[512];
      char tmp[2048];
      if (getcwd(cwd, sizeof cwd) && (size_t)snprintf(tmp, sizeof tmp, "%s/%s", cwd, from) < sizeof from) strcpy(from, tmp);
    }
    snprintf(to, sizeof to, "%s/%s", dir, names[k]);
    CHECK(symlink(from, to) == 0);
  }
  gs_dem_options opt;
  gs_dem_options_default(&opt);
  opt.contact_time = 1;
  opt.contacts_from = GS_DEM_CONTACTS_CC_PARTNER;
  gs_error err = {0};
  gs_dem_data d;
  int rc = gs_dem_data_read(dir, &opt, &d, &err);
  CHECK(rc == 0);
  if (rc) { fprintf(stderr, "%s\n", err.msg); remove_dir(dir); return; }
  CHECK(d.nclass == 16 && d.nsnap == 1 && d.steps[0] == 19000000);
  double wall = 0;
  for (int i = 0; i < 16; i++) {
    CHECK(d.count[i] == N19[i]);
    CHECK(d.wall_contacts[i] == IMP19[i]);
    CHECK_REL(d.diameter[i], 0.004, 1e-12);
    wall += d.wall_contacts[i];
    double row = 0, want = 0;
    for (int j = 0; j < 16; j++) {
      CHECK(d.cc_sum[i * 16 + j] == S19[i][j]);
      row += d.cc_sum[i * 16 + j];
      want += S19[i][j];
      CHECK(d.collision[i * 16 + j] == d.collision[j * 16 + i]);
    }
    CHECK(row == want);
  }
  CHECK(wall == 479);
  /* the naive reading reproduces the reference code's diagonal, C_ii = S_ii / N_i^2 (t_c = 1 s) */
  CHECK_REL(d.collision[0], 1.27496e-3, 1e-5);
  CHECK_REL(d.collision[14 * 16 + 14], 0.5, 1e-14);
  CHECK_REL(d.collision[1], 0.5 * (23 + 19) / (363.0 * 352.0), 1e-14);
  gs_dem_data_free(&d);
  /* LAMMPS tally: K_12 = S_12 + S_21, K_11 = (R_1 - sum_j!=1 (S_1j + S_j1)) / 2 = (297 - 261) / 2 */
  opt.contacts_from = GS_DEM_CONTACTS_CC_OWNER;
  CHECK(gs_dem_data_read(dir, &opt, &d, &err) == 0);
  CHECK(d.contacts[0] == 18 && d.contacts[1] == 42);
  CHECK_REL(d.collision[0], 2 * 18 / (363.0 * 363.0), 1e-14);
  CHECK_REL(d.collision[1], 42 / (363.0 * 352.0), 1e-14);
  gs_dem_data_free(&d);
  /* pair dumps (counted independently with a script): 1046 contacts, K_11 = 29, K_12 = 49 */
  opt.contacts_from = GS_DEM_CONTACTS_AUTO;
  CHECK(gs_dem_data_read(dir, &opt, &d, &err) == 0);
  CHECK(d.contacts_from == GS_DEM_CONTACTS_PPCOLL);
  double tot = 0, unlike = 0;
  for (int i = 0; i < 16; i++)
    for (int j = i; j < 16; j++) { tot += d.contacts[i * 16 + j]; if (j > i) unlike += d.contacts[i * 16 + j]; }
  CHECK(tot == 1046);
  CHECK(unlike == 932); /* = sum of all S_ij / 2: the contact columns hold exactly the unlike-type contacts */
  CHECK(d.contacts[0] == 29 && d.contacts[1] == 49);
  CHECK_REL(d.collision[0], 2 * 29 / (363.0 * 363.0), 1e-14);
  gs_dem_data_free(&d);
  remove_dir(dir);

  /* all nine snapshots, Hertz durations */
  gs_dem_options_default(&opt);
  rc = gs_dem_data_read(data, &opt, &d, &err);
  CHECK(rc == 0);
  if (rc) { fprintf(stderr, "%s\n", err.msg); return; }
  CHECK(d.nsnap == 9 && d.steps[0] == 18600000 && d.steps[8] == 19000000);
  CHECK(d.contacts_from == GS_DEM_CONTACTS_PPCOLL);
  CHECK(d.v_pair > 0.01 && d.v_pair < 10 && d.v_wall > 0.1 && d.v_wall < 100);
  double m = 500 * 4.0 / 3.0 * M_PI * pow(0.002, 3);
  CHECK_REL(d.contact_time, gs_dem_hertz_contact_time(m / 2, 0.001, 8e6 / (2 * 0.96), d.v_pair, 0.4), 1e-12);
  CHECK(d.contact_time > 1e-5 && d.contact_time < 1e-2);
  /* identical spheres, types only labels: a well-mixed bed has C_ii = C_ij under the PBM
   * convention (C_ii = 2 E_ii / N_i^2).  Classes 1-8 (>= 139 particles): the mean diagonal is
   * within 30 % of the mean off-diagonal value; a convention off by 2 would fail. */
  double dsum = 0, osum = 0;
  for (int i = 0; i < 8; i++)
    for (int j = 0; j < 8; j++) *(i == j ? &dsum : &osum) += d.collision[i * 16 + j];
  double ratio = (dsum / 8) / (osum / 56);
  CHECK(ratio > 0.7 && ratio < 1.3);
  fprintf(stderr, "corimix: t_c = %.4g s (v = %.4g m/s), mean C_ii / mean C_ij (classes 1-8) = %.3f\n",
          d.contact_time, d.v_pair, ratio);
  double cnt = 0, sd = 0;
  for (int i = 0; i < 16; i++) {
    cnt += d.count[i];
    sd += d.count_sd[i];
    CHECK(d.impact_rate[i] >= 0 && d.impact_rate_sd[i] >= 0);
    CHECK_REL(d.impact_rate[i], d.impeller_rate[i] + d.shell_rate[i], 1e-12);
    if (d.nvel[i] >= 2)
      CHECK_REL(gs_dem_break_probability(&d, (size_t)i, 3.0), gsl_cdf_lognormal_Q(3.0, d.vel_mu[i], d.vel_sigma[i]), 1e-14);
    for (int j = 0; j < 16; j++) {
      CHECK(d.collision[i * 16 + j] == d.collision[j * 16 + i]);
      CHECK(d.collision_sd[i * 16 + j] >= 0);
    }
  }
  CHECK(cnt > 2000 && cnt < 2500 && sd > 0);
  gs_dem_data_free(&d);
}

int main(void) {
  test_hertz();
  test_synthetic();
  test_bad_input();
  test_corimix();
  TEST_EXIT();
}
