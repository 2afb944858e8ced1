/* Validation cases of the gas phase and its coupling (docs/validation-cfd.md):
 * each builds a DEM and a gas phase through the public APIs, runs them and
 * returns the simulated figure with its reference, which is computed here
 * from the textbook formula, independently of src/cfd/drag.c. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

#include "gransim/cfd.h"
#include "gransim/cfg.h"

#define RHO_AIR 1.2
#define MU_AIR 1.8e-5
#define G 9.81

static const gs_cfd_drag_type *find_drag(const char *name, gs_error *err) {
  const gs_cfd_drag_type *t = gs_registry_find((const void *const *)gs_cfd_drags, name);
  if (!t) gs_error_set(err, GS_EINPUT, "no drag law '%s'", name);
  return t;
}

/* ---- terminal velocity --------------------------------------------------- */
typedef struct {
  int schiller; /* 1: Schiller-Naumann, 0: Dallavalle */
  double d, rho_p;
} fall;

static double cd_single(const fall *f, double re) {
  if (f->schiller) return re < 1000 ? 24 / re * (1 + 0.15 * pow(re, 0.687)) : 0.44;
  return (0.63 + 4.8 / sqrt(re)) * (0.63 + 4.8 / sqrt(re));
}

/* weight less buoyancy minus drag at speed U */
static double balance(double U, void *par) {
  const fall *f = par;
  const double re = RHO_AIR * f->d * U / MU_AIR;
  return (f->rho_p - RHO_AIR) * M_PI / 6 * f->d * f->d * f->d * G -
         0.5 * cd_single(f, re) * RHO_AIR * M_PI / 4 * f->d * f->d * U * U;
}

static double terminal_speed(const fall *f) {
  gsl_function F = {balance, (void *)f};
  gsl_root_fsolver *s = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
  gsl_root_fsolver_set(s, &F, 1e-6, 100);
  double x = 0;
  for (int it = 0; it < 200; it++) {
    gsl_root_fsolver_iterate(s);
    x = gsl_root_fsolver_root(s);
    if (gsl_root_test_interval(gsl_root_fsolver_x_lower(s), gsl_root_fsolver_x_upper(s), 0, 1e-13) ==
        GSL_SUCCESS)
      break;
  }
  gsl_root_fsolver_free(s);
  return x;
}

static const gs_dem_material glass = {.E = 5e6, .nu = 0.25, .e = 0.5, .mu_s = 0.3, .mu_r = 0, .density = 2500};

int gs_cfd_check_terminal(const char *drag, int coupling, gs_cfd_check *out, gs_error *err) {
  const gs_cfd_drag_type *dt = find_drag(drag, err);
  if (!dt) return err->code;
  const double d = 3e-4, H = 3.0;
  /* a narrow box and a wide skin keep the DEM's cell grid and list rebuilds
   * small for a particle crossing metres */
  gs_dem_params p = {.dt = 1e-4, .gravity = {0, 0, -G}, .skin = 1e-2, .lo = {0, 0, 0},
                     .hi = {0.002, 0.002, H}, .nclass = 1};
  gs_dem *dem = gs_dem_alloc(&p, err);
  if (!dem) return err->code;
  gs_cfd *g = NULL;
  int rc = GS_OK;
  /* soft, so that the DEM step needs no contact resolution it never uses */
  gs_dem_material soft = glass;
  soft.E = 1e4;
  const int type = gs_dem_add_type(dem, &soft, 0, err);
  const double x0[3] = {0.001, 0.001, H - 0.05};
  if (type < 0 || gs_dem_add_particle(dem, type, d / 2, x0, NULL, NULL, err) < 0) rc = err->code;
  /* two-way: cells of 15 mm (50 diameters, the most allowed) */
  gs_cfd_params gp = {.lo = {0, 0, 0}, .hi = {0.002, 0.002, H}, .n = {1, 1, coupling == GS_CFD_ONE_WAY ? 30 : 200},
                      .rho = RHO_AIR, .mu = MU_AIR, .u_inlet = 0, .dt = 1e-3, .gravity = {0, 0, -G}, .drag = dt,
                      .coupling = coupling};
  if (!rc && !(g = gs_cfd_create(&gp, err))) rc = err->code;
  if (!rc) rc = gs_cfd_attach(g, dem, err);
  if (!rc) rc = gs_dem_run(dem, 15000, err);
  if (!rc) {
    gs_dem_view v;
    gs_dem_get_view(dem, &v);
    const fall f = {.schiller = !strcmp(drag, "gidaspow"), .d = d, .rho_p = glass.density};
    *out = (gs_cfd_check){.got = -v.vz[0], .want = terminal_speed(&f), .tol = 0.02};
    snprintf(out->name, sizeof out->name, "terminal velocity, %s, %s", drag,
             coupling == GS_CFD_ONE_WAY ? "one-way" : "two-way");
    snprintf(out->unit, sizeof out->unit, "m/s");
    snprintf(out->detail, sizeof out->detail,
             "glass sphere d = 0.3 mm, 2500 kg/m3, in air, after 1.5 s of fall from rest (%s C_D); "
             "a 2 x 2 mm column of %s cells",
             f.schiller ? "Schiller-Naumann" : "Dallavalle", coupling == GS_CFD_ONE_WAY ? "100 mm" : "15 mm");
  }
  gs_cfd_free(g);
  gs_dem_free(dem);
  return rc;
}

/* ---- packed bed ----------------------------------------------------------- */
int gs_cfd_check_ergun(const char *drag, double u, gs_cfd_check *out, gs_error *err) {
  const gs_cfd_drag_type *dt = find_drag(drag, err);
  if (!dt) return err->code;
  const double d = 2e-3, W = 8e-3, H = 88e-3;
  const int nl = 4, layers = 30;
  gs_dem_params p = {.dt = 2e-5, .gravity = {0, 0, -G}, .skin = 2e-4, .lo = {-1e-3, -1e-3, -1e-3},
                     .hi = {W + 1e-3, W + 1e-3, H + 1e-3}, .nclass = 1};
  gs_dem *dem = gs_dem_alloc(&p, err);
  if (!dem) return err->code;
  gs_cfd *g = NULL;
  int rc = GS_OK;
  const int type = gs_dem_add_type(dem, &glass, 0, err);
  if (type < 0) rc = err->code;
  /* the column: floor and four side walls */
  const double pts[5][3] = {{0, 0, 0}, {0, 0, 0}, {W, W, 0}, {0, 0, 0}, {W, W, 0}};
  const double nrm[5][3] = {{0, 0, 1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  for (int w = 0; w < 5 && !rc; w++)
    if (gs_dem_add_plane(dem, "wall", pts[w], nrm[w], &glass, err) < 0) rc = err->code;
  for (int k = 0; k < layers && !rc; k++)
    for (int j = 0; j < nl && !rc; j++)
      for (int i = 0; i < nl && !rc; i++) {
        const double x[3] = {d / 2 + i * d, d / 2 + j * d, d / 2 + k * d};
        if (gs_dem_add_particle(dem, type, d / 2, x, NULL, NULL, err) < 0) rc = err->code;
      }
  gs_cfd_params gp = {.lo = {0, 0, 0}, .hi = {W, W, H}, .n = {2, 2, 22}, .rho = RHO_AIR, .mu = MU_AIR,
                      .u_inlet = u, .dt = 1e-3, .gravity = {0, 0, -G}, .drag = dt,
                      .coupling = GS_CFD_TWO_WAY};
  if (!rc && !(g = gs_cfd_create(&gp, err))) rc = err->code;
  if (!rc) rc = gs_cfd_attach(g, dem, err);
  /* the column rings after it settles (its collective modes are lightly
   * damped), so the pressure drop and the bed height are averaged over
   * 0.1 s after 0.1 s of settling, as a measurement would */
  if (!rc) rc = gs_dem_run(dem, 5000, err);
  double p_sum = 0, top_sum = 0, vs = 0;
  const int samples = 100;
  for (int k = 0; k < samples && !rc; k++) {
    rc = gs_dem_run(dem, 50, err);
    gs_dem_view v;
    gs_dem_get_view(dem, &v);
    double top = 0;
    vs = 0;
    for (size_t i = 0; i < v.n; i++) {
      top = fmax(top, v.z[i] + v.r[i]);
      vs += 4.0 / 3.0 * M_PI * v.r[i] * v.r[i] * v.r[i];
    }
    top_sum += top;
    p_sum += gs_cfd_inlet_pressure(g);
  }
  if (!rc) {
    const double top = top_sum / samples;
    const double e = 1 - vs / (W * W * top);
    const double ergun = top * (150 * MU_AIR * (1 - e) * (1 - e) * u / (e * e * e * d * d) +
                                1.75 * RHO_AIR * (1 - e) * u * u / (e * e * e * d));
    *out = (gs_cfd_check){.got = p_sum / samples - RHO_AIR * G * H, .want = ergun, .tol = 0.05};
    snprintf(out->name, sizeof out->name, "packed-bed pressure drop, %s, U = %g m/s", drag, u);
    snprintf(out->unit, sizeof out->unit, "Pa");
    snprintf(out->detail, sizeof out->detail,
             "480 glass spheres d = 2 mm, simple cubic, bed %.2f mm, void fraction %.4f; 2x2x22 cells",
             1e3 * top, e);
  }
  gs_cfd_free(g);
  gs_dem_free(dem);
  return rc;
}

/* ---- fluidisation --------------------------------------------------------- */
typedef struct {
  gs_dem *dem;
  gs_cfd *gas;
  double weight; /* bed weight less buoyancy per unit area [Pa] */
} column;

/* Wen & Yu's correlation is Ergun's balance at eps_mf about 0.40 (for these
 * particles 0.400): the check needs a bed poured that loose.  Frictionless
 * spheres settle to random close packing with the walls (0.372-0.378 for
 * two seeds), whose Ergun U_mf lies 10-14 % under Wen & Yu; a little sliding
 * friction, as real particles have, holds the pour at 0.400 (mu_s 0.05:
 * 0.405; docs/validation-cfd.md). */
static const gs_dem_material powder = {.E = 1e6, .nu = 0.25, .e = 0.5, .mu_s = 0.03, .mu_r = 0, .density = 1030};

#define NPART 1000

static int column_make(column *c, gs_error *err) {
  const double d = 2e-3, W = 14e-3, H = 0.15;
  memset(c, 0, sizeof *c);
  gs_dem_params p = {.dt = 2.5e-5, .gravity = {0, 0, -G}, .skin = 4e-4, .lo = {-1e-3, -1e-3, -1e-3},
                     .hi = {W + 1e-3, W + 1e-3, H + 1e-3}, .nclass = 1};
  if (!(c->dem = gs_dem_alloc(&p, err))) return err->code;
  const int type = gs_dem_add_type(c->dem, &powder, 0, err);
  if (type < 0) return err->code;
  const double pts[6][3] = {{0, 0, 0}, {0, 0, H}, {0, 0, 0}, {W, W, 0}, {0, 0, 0}, {W, W, 0}};
  const double nrm[6][3] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  for (int w = 0; w < 6; w++)
    if (gs_dem_add_plane(c->dem, "wall", pts[w], nrm[w], &powder, err) < 0) return err->code;
  gs_dem_region reg = {.kind = GS_DEM_REGION_BOX, .lo = {0, 0, 0}, .hi = {W, W, H - 5e-3}};
  const double r = d / 2, frac = 1;
  gs_dem_psd psd = {1, &type, &r, &r, &frac, 0, NULL, NULL};
  uint64_t seed = 11;
  long n = 0;
  double m = 0;
  if (gs_dem_insert(c->dem, &reg, &psd, NPART, HUGE_VAL, NULL, &seed, &n, &m, err)) return err->code;
  if (n != NPART) return gs_error_set(err, GS_ENUMERIC, "fluidisation check: only %ld of %d particles fit", n, NPART);
  c->weight = (powder.density - RHO_AIR) / powder.density * m * G / (W * W);
  gs_cfd_params gp = {.lo = {0, 0, 0}, .hi = {W, W, H}, .n = {2, 2, 30}, .rho = RHO_AIR, .mu = MU_AIR,
                      .u_inlet = 0, .dt = 5e-4, .gravity = {0, 0, -G}, .drag = find_drag("di_felice", err),
                      .coupling = GS_CFD_TWO_WAY};
  if (!(c->gas = gs_cfd_create(&gp, err))) return err->code;
  if (gs_cfd_attach(c->gas, c->dem, err)) return err->code;
  return gs_dem_run(c->dem, 16000, err); /* 0.4 s: poured and settled */
}

static void column_free(column *c) {
  gs_cfd_free(c->gas);
  gs_dem_free(c->dem);
}

/* Mean of the inlet pressure (less the gas column) and of twice the mean
 * particle height over `steps` DEM steps sampled every gas step. */
static int column_measure(column *c, long steps, double *dp, double *height, gs_error *err) {
  double ps = 0, hs = 0;
  long k = 0;
  for (long s = 0; s < steps; s += 20, k++) {
    int rc = gs_dem_run(c->dem, 20, err);
    if (rc) return rc;
    gs_dem_view v;
    gs_dem_get_view(c->dem, &v);
    double z = 0;
    for (size_t i = 0; i < v.n; i++) z += v.z[i];
    hs += 2 * z / (double)v.n;
    ps += gs_cfd_inlet_pressure(c->gas) - RHO_AIR * G * 0.15;
  }
  *dp = ps / (double)k;
  *height = hs / (double)k;
  return GS_OK;
}

static double wen_yu_umf(double d, double rho_p) {
  const double ar = d * d * d * RHO_AIR * (rho_p - RHO_AIR) * G / (MU_AIR * MU_AIR);
  return (sqrt(33.7 * 33.7 + 0.0408 * ar) - 33.7) * MU_AIR / (RHO_AIR * d);
}

int gs_cfd_check_fluidisation(gs_cfd_check out[4], gs_error *err) {
  column c;
  int rc = column_make(&c, err);
  const double umf = wen_yu_umf(2e-3, powder.density);
  /* the packed-bed branch: the gas raised in steps of 0.1 U_mf */
  double su2 = 0, su3 = 0, su4 = 0, spu = 0, spu2 = 0, h0 = 0, dp, h;
  int npts = 0;
  for (int k = 1; k <= 16 && !rc; k++) {
    gs_cfd_set_inlet_velocity(c.gas, 0.1 * k * umf);
    if ((rc = gs_dem_run(c.dem, 2000, err)) || (rc = column_measure(&c, 2000, &dp, &h, err))) break;
    if (k == 1) h0 = h;
    /* the packed branch ends at the first point near the bed weight: once
     * fluidised, the pressure drop levels off below the weight (the walls
     * carry part of it) and a dip under the cut-off is no packed-bed point */
    if (dp > 0.85 * c.weight) break;
    const double u = 0.1 * k * umf;
    su2 += u * u, su3 += u * u * u, su4 += u * u * u * u, spu += dp * u, spu2 += dp * u * u;
    npts++;
  }
  if (!rc && npts < 3)
    rc = gs_error_set(err, GS_ENUMERIC, "fluidisation check: only %d packed-bed points", npts);
  if (!rc) {
    /* least squares dp = a u + b u^2, then a u + b u^2 = weight */
    const double det = su2 * su4 - su3 * su3;
    const double a = (spu * su4 - spu2 * su3) / det, b = (su2 * spu2 - su3 * spu) / det;
    const double u_mf = b > 0 ? (-a + sqrt(a * a + 4 * b * c.weight)) / (2 * b) : c.weight / a;
    out[0] = (gs_cfd_check){.got = u_mf, .want = umf, .tol = 0.10};
    snprintf(out[0].name, sizeof out[0].name, "minimum fluidisation velocity");
    snprintf(out[0].unit, sizeof out[0].unit, "m/s");
    snprintf(out[0].detail, sizeof out[0].detail,
             "1000 spheres d = 2 mm (mu_s 0.03), 1030 kg/m3, in a 14 x 14 mm column, di_felice; packed "
             "void fraction %.3f, %d packed-bed points, bed weight %.1f Pa", 1 - NPART * M_PI / 6 * 8e-9 / (14e-3 * 14e-3 * h0), npts, c.weight);
  }
  const double prev0 = h0;
  double prev = prev0;
  for (int k = 0; k < 3 && !rc; k++) {
    const double f = 1.5 + 0.5 * k;
    gs_cfd_set_inlet_velocity(c.gas, f * umf);
    /* 0.4 s: the 7-diameter column slugs, and a 0.2 s window held one slug */
    if ((rc = gs_dem_run(c.dem, 8000, err)) || (rc = column_measure(&c, 16000, &dp, &h, err))) break;
    out[1 + k] = (gs_cfd_check){.got = h, .want = prev, .tol = 0};
    snprintf(out[1 + k].name, sizeof out[1 + k].name, "bed height at %.1f U_mf (above the previous)", f);
    snprintf(out[1 + k].unit, sizeof out[1 + k].unit, "m");
    snprintf(out[1 + k].detail, sizeof out[1 + k].detail,
             "twice the mean particle height over 0.4 s after 0.2 s; pressure drop %.1f Pa of %.1f", dp,
             c.weight);
    prev = h;
  }
  column_free(&c);
  return rc;
}
