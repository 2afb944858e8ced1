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

int gs_cfd_check_terminal(const char *drag, gs_cfd_check *out, gs_error *err) {
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
  gs_cfd_params gp = {.lo = {0, 0, 0}, .hi = {0.002, 0.002, H}, .n = {1, 1, 30}, .rho = RHO_AIR,
                      .mu = MU_AIR, .u_inlet = 0, .dt = 1e-3, .gravity = {0, 0, -G}, .drag = dt,
                      .coupling = GS_CFD_ONE_WAY};
  if (!rc && !(g = gs_cfd_create(&gp, err))) rc = err->code;
  if (!rc) rc = gs_cfd_attach(g, dem, err);
  if (!rc) rc = gs_dem_run(dem, 15000, err);
  if (!rc) {
    gs_dem_view v;
    gs_dem_get_view(dem, &v);
    const fall f = {.schiller = !strcmp(drag, "gidaspow"), .d = d, .rho_p = glass.density};
    *out = (gs_cfd_check){.got = -v.vz[0], .want = terminal_speed(&f), .tol = 0.02};
    snprintf(out->name, sizeof out->name, "terminal velocity, %s", drag);
    snprintf(out->unit, sizeof out->unit, "m/s");
    snprintf(out->detail, sizeof out->detail,
             "glass sphere d = 0.3 mm, 2500 kg/m3, in air, after 1.5 s of fall from rest (%s C_D)",
             f.schiller ? "Schiller-Naumann" : "Dallavalle");
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
