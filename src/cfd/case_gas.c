/* The `gas` section of a DEM case (docs/case-files.md, "Gas phase"): read,
 * validated, and turned into a gas phase attached to the case's DEM. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "cfd/cfd_internal.h"
#include "gransim/cfg.h"

static int vec3(gs_cfg_node *map, const char *key, double out[3], gs_error *err) {
  double *v = NULL;
  size_t n = 0;
  int rc = gs_cfg_doubles_req(map, key, 0, &v, &n, err);
  if (!rc && n != 3) rc = gs_cfg_fail(gs_cfg_get(map, key), err, "expected 3 numbers [x, y, z], got %zu", n);
  for (size_t a = 0; a < 3 && !rc; a++) out[a] = v[a];
  free(v);
  return rc;
}

static int read_gas(gs_cfg_node *gas, const gs_dem_params *dp, double duration, gs_cfd_params *p,
                    double *every, double *vtk_every, gs_error *err) {
  int rc = gs_cfg_require_kind(gas, GS_CFG_MAP, err);
  /* required: the DEM box usually encloses the walls with room to spare,
   * and gas there would flow around the bed */
  gs_cfg_node *box = NULL;
  for (int a = 0; a < 3; a++) p->gravity[a] = dp->gravity[a];
  if (!rc) rc = gs_cfg_map_req(gas, "box", &box, err);
  if (box && !(rc = vec3(box, "lo", p->lo, err)) &&
      !(rc = vec3(box, "hi", p->hi, err)) && !(rc = gs_cfg_check_unused(box, err)))
    for (int a = 0; a < 3 && !rc; a++)
      if (!(p->hi[a] > p->lo[a])) rc = gs_cfg_fail(gs_cfg_get(box, "hi"), err, "expected hi > lo on every axis");
  double *cells = NULL;
  size_t nc = 0;
  if (!rc) rc = gs_cfg_doubles_req(gas, "cells", 0, &cells, &nc, err);
  if (!rc && nc != 3) rc = gs_cfg_fail(gs_cfg_get(gas, "cells"), err, "expected 3 cell counts [nx, ny, nz]");
  for (size_t a = 0; a < 3 && !rc; a++) {
    if (!(cells[a] >= 1 && cells[a] <= 4096 && cells[a] == floor(cells[a])))
      rc = gs_cfg_fail(gs_cfg_get(gas, "cells"), err, "expected whole numbers from 1 to 4096");
    else
      p->n[a] = (int)cells[a];
  }
  free(cells);
  if (!rc) rc = gs_cfg_double_range(gas, "inlet_velocity", 1, 0, 0, 0, HUGE_VAL, 0, &p->u_inlet, err);
  if (!rc) rc = gs_cfg_double_range(gas, "time_step", 1, 0, 0, 1, HUGE_VAL, 0, &p->dt, err);
  if (!rc) rc = gs_cfg_double_range(gas, "density", 0, 1.2, 0, 1, HUGE_VAL, 0, &p->rho, err);
  if (!rc) rc = gs_cfg_double_range(gas, "viscosity", 0, 1.8e-5, 0, 1, HUGE_VAL, 0, &p->mu, err);
  const char *drag = NULL;
  if (!rc) rc = gs_cfg_string_opt(gas, "drag", "di_felice", &drag, err);
  if (!rc && !(p->drag = gs_registry_find((const void *const *)gs_cfd_drags, drag))) {
    char known[256];
    gs_registry_names((const void *const *)gs_cfd_drags, known, sizeof known);
    rc = gs_cfg_fail(gs_cfg_get(gas, "drag"), err, "expected a drag law: %s", known);
  }
  static const char *const couplings[] = {"two_way", "one_way", NULL};
  if (!rc) rc = gs_cfg_enum_opt(gas, "coupling", couplings, GS_CFD_TWO_WAY, &p->coupling, err);
  gs_cfg_node *sol = rc ? NULL : gs_cfg_get(gas, "solver");
  p->tol = 1e-10;
  long iters = 500;
  if (sol && !(rc = gs_cfg_require_kind(sol, GS_CFG_MAP, err)) &&
      !(rc = gs_cfg_double_range(sol, "tolerance", 0, 1e-10, 0, 1, 1, 1, &p->tol, err)) &&
      !(rc = gs_cfg_long_range(sol, "max_iterations", 0, 500, 1, 100000, &iters, err)))
    rc = gs_cfg_check_unused(sol, err);
  p->max_iter = (int)iters;
  gs_cfg_node *out = rc ? NULL : gs_cfg_get(gas, "output");
  *every = duration / 100;
  *vtk_every = 0;
  if (out && !(rc = gs_cfg_require_kind(out, GS_CFG_MAP, err)) &&
      !(rc = gs_cfg_double_range(out, "every", 0, *every, 0, 1, HUGE_VAL, 0, every, err)) &&
      !(rc = gs_cfg_double_range(out, "vtk_every", 0, 0, 0, 0, HUGE_VAL, 0, vtk_every, err)))
    rc = gs_cfg_check_unused(out, err);
  if (!rc) rc = gs_cfg_check_unused(gas, err);
  return rc;
}

gs_cfd *gs_cfd_case_create(gs_dem_case *c, const char *out_dir, gs_error *err) {
  gs_cfg_node *gas = gs_dem_case_gas(c);
  if (!gas) return gs_error_set(err, GS_EINPUT, "the case has no gas section"), NULL;
  gs_dem *d = gs_dem_case_sim(c);
  gs_dem_params dp;
  gs_dem_get_params(d, &dp);
  gs_cfd_params p = {0};
  double every, vtk_every;
  if (read_gas(gas, &dp, gs_dem_case_duration(c), &p, &every, &vtk_every, err)) return NULL;
  gs_cfd *g = gs_cfd_create(&p, err);
  if (!g) return NULL;
  if (gs_cfd_attach(g, d, err) || (out_dir && gs_cfd_set_output(g, out_dir, every, vtk_every, err))) {
    gs_cfd_free(g);
    return NULL;
  }
  return g;
}
