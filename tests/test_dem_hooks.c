/* gs_dem_hooks (include/gransim/dem.h): an external force added at every step
 * moves a free sphere exactly as the same body force would (velocity Verlet
 * with a constant force is exact: x = x0 + v0 t + a t^2/2), forces are found by
 * particle id after the engine reorders its particles, after_step is called
 * once per step and its error stops gs_dem_run at that step. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "check.h"
#include "gransim/dem.h"

typedef struct {
  double f[3];   /* force per unit mass, added by id */
  long calls;    /* after_step calls */
  long stop_at;  /* after_step fails at this step (0: never) */
} hook_state;

static void add(const gs_dem_view *v, double *fx, double *fy, double *fz, void *user) {
  const hook_state *h = user;
  for (size_t i = 0; i < v->n; i++) {
    const double k = v->id[i] == 0 ? 1 : 2; /* particle 0 one unit, the other two */
    fx[i] += k * v->m[i] * h->f[0];
    fy[i] += k * v->m[i] * h->f[1];
    fz[i] += k * v->m[i] * h->f[2];
  }
}

static int after(gs_dem *d, void *user, gs_error *err) {
  hook_state *h = user;
  h->calls++;
  if (h->stop_at && gs_dem_step_count(d) == h->stop_at)
    return gs_error_set(err, GS_ENUMERIC, "stopped by the hook at step %ld", gs_dem_step_count(d));
  return GS_OK;
}

int main(void) {
  gs_dem_params p = {.dt = 1e-4, .gravity = {0, 0, -9.81}, .skin = 1e-3, .lo = {-1, -1, -1}, .hi = {1, 1, 1},
                     .nclass = 1};
  gs_error err = {0};
  gs_dem *d = gs_dem_alloc(&p, &err);
  const gs_dem_material m = {.E = 1e6, .nu = 0.25, .e = 0.5, .mu_s = 0.3, .mu_r = 0, .density = 1000};
  const int t = gs_dem_add_type(d, &m, 0, &err);
  const double x0[3] = {0.5, 0, 0}, x1[3] = {-0.5, 0, 0}, v0[3] = {0, 0.1, 0};
  CHECK(gs_dem_add_particle(d, t, 1e-3, x0, v0, NULL, &err) == 0);
  CHECK(gs_dem_add_particle(d, t, 1e-3, x1, v0, NULL, &err) == 1);
  hook_state h = {.f = {0.3, 0, 9.81}};
  const gs_dem_hooks hooks = {.forces = add, .after_step = after, .user = &h};
  gs_dem_set_hooks(d, &hooks);
  CHECK(gs_dem_run(d, 1000, &err) == GS_OK);
  CHECK(h.calls == 1000);
  gs_dem_view v;
  gs_dem_get_view(d, &v);
  const double T = 0.1;
  for (size_t i = 0; i < v.n; i++) {
    const double k = v.id[i] == 0 ? 1 : 2, xs = v.id[i] == 0 ? 0.5 : -0.5;
    CHECK_REL(v.x[i], xs + 0.5 * k * 0.3 * T * T, 1e-9);
    CHECK_REL(v.y[i], 0.1 * T, 1e-9);
    /* particle 0: the hook cancels gravity; particle 1: twice gravity upwards */
    CHECK_ABS(v.z[i], v.id[i] == 0 ? 0 : 0.5 * 9.81 * T * T, 1e-9);
  }
  /* an error from after_step stops the run at that step */
  h.stop_at = 1500;
  CHECK(gs_dem_run(d, 1000, &err) == GS_ENUMERIC);
  CHECK(strstr(err.msg, "step 1500") != NULL);
  CHECK(gs_dem_step_count(d) == 1500);
  /* without hooks, gravity alone (after the first half step, which still
   * uses the forces of the last step, the hook's among them) */
  gs_dem_set_hooks(d, NULL);
  gs_dem_get_view(d, &v);
  const double vz0 = v.vz[0];
  CHECK(gs_dem_run(d, 100, &err) == GS_OK);
  gs_dem_get_view(d, &v);
  for (size_t i = 0; i < v.n; i++)
    if (v.id[i] == 0) CHECK_REL(v.vz[i], vz0 - 9.81 * (0.01 - 0.5e-4), 1e-9);
  gs_dem_free(d);
  TEST_EXIT();
}
