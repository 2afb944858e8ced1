/* The gas phase inside a DEM run: the hooks that take a gas step every
 * gas.time_step of DEM time and add the held forces at every DEM step. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cfd/cfd_internal.h"

/* The DEM step must resolve the contacts: above 40 % of the Rayleigh time a
 * collision lasts only a few steps. */
#define MAX_RAYLEIGH_FRACTION 0.4

static void add_forces(const gs_dem_view *v, double *fx, double *fy, double *fz, void *user) {
  gs_cfd *g = user;
  if (!g->started && !g->failed) {
    /* the first gas step, with the particles present at the DEM's first step */
    g->started = 1;
    g->t = gs_dem_time(g->dem);
    if (gs_cfd_step(g, v, &g->fail)) g->failed = 1;
  }
  for (size_t i = 0; i < v->n; i++) {
    const long id = v->id[i];
    if (id >= g->force_cap) continue; /* entered since the last gas step */
    fx[i] += g->force[3 * id];
    fy[i] += g->force[3 * id + 1];
    fz[i] += g->force[3 * id + 2];
  }
}

static int after_step(gs_dem *d, void *user, gs_error *err) {
  gs_cfd *g = user;
  if (!g->failed && ++g->dem_count % g->dem_steps_per_gas == 0) {
    gs_dem_view v;
    gs_dem_get_view(d, &v);
    g->t = gs_dem_time(d);
    if (gs_cfd_step(g, &v, &g->fail)) g->failed = 1;
  }
  if (!g->failed) return GS_OK;
  *err = g->fail;
  return err->code ? err->code : GS_ENUMERIC;
}

int gs_cfd_attach(gs_cfd *g, gs_dem *d, gs_error *err) {
  /* the DEM step: a whole number of them per gas step */
  const double ratio = g->prm.dt / gs_dem_dt(d);
  const long k = lround(ratio);
  if (k < 1 || fabs(ratio - (double)k) > 1e-6 * ratio)
    return gs_error_set(err, GS_EINPUT,
                        "gas.time_step %g s is not a whole number of DEM time steps (%g s): %g of them",
                        g->prm.dt, gs_dem_dt(d), ratio);
  const double tr = gs_dem_rayleigh_time(d);
  if (gs_dem_dt(d) > MAX_RAYLEIGH_FRACTION * tr)
    return gs_error_set(err, GS_EINPUT,
                        "dem.time_step %g s is %.0f %% of the Rayleigh time %g s of the smallest particle: "
                        "above the limit of %.0f %% for a coupled run", gs_dem_dt(d),
                        100 * gs_dem_dt(d) / tr, tr, 100 * MAX_RAYLEIGH_FRACTION);
  g->dem = d;
  g->dem_steps_per_gas = k;
  g->par_min = gs_dem_parallel_min(d);
  g->dem_count = 0;
  g->started = 0;
  g->failed = 0;
  const gs_dem_hooks h = {.forces = add_forces, .after_step = after_step, .user = g};
  gs_dem_set_hooks(d, &h);
  return GS_OK;
}
