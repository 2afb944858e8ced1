/* Registry of time integrators and the settings every integrator accepts.
 *
 * Adding an integrator is one file and one line in the registry below.  The
 * common keys are read here so that all types validate them the same way and
 * a case can switch `method` without touching the rest of the solver map:
 *
 *   rtol                  relative tolerance, 0 < rtol < 1 (default 1e-6)
 *   atol                  absolute tolerance in the units of the state vector
 *                         (default GS_INTEGRATOR_ATOL, 1e-12; a case scales its
 *                         default to its own numbers through abs_scale).  Number densities can be tiny
 *                         (1e-12 mol is a typical magnitude), so atol must be
 *                         chosen well below the smallest density that matters;
 *                         a component is resolved to about atol * abs_scale[i].
 *   initial_step          first step (default: chosen by the integrator)
 *   min_step, max_step    step bounds (default 0 and unlimited)
 *   max_steps_per_output  steps allowed within one advance() (default 1e7)
 *
 * Integrators that have no use for a key (euler ignores the tolerances) still
 * consume it, so unknown-key checking stays meaningful. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/integrator.h"

extern const gs_integrator_type gs_integrator_auto, gs_integrator_rk, gs_integrator_cvode,
    gs_integrator_euler;

/* Defined here, used by the integrator types (declared again in each type's
 * file because this module has no private header). */
int gs_integrator_common_keys(gs_cfg_node *solver, double *rtol, double *atol,
                              double *initial_step, double *min_step, double *max_step,
                              long *max_steps, gs_error *err);

static const gs_integrator_type *const registry[] = {
    &gs_integrator_auto, &gs_integrator_rk, &gs_integrator_cvode, &gs_integrator_euler, NULL};

const gs_integrator_type *const *gs_integrator_types(void) { return registry; }

const gs_integrator_type *gs_integrator_lookup(const char *name) {
  return gs_registry_find((const void *const *)registry, name);
}

/* A step-size key that is optional and has no numeric default: NAN when
 * absent, so each integrator can substitute its own default. */
static int gs_step_key(gs_cfg_node *solver, const char *key, int allow_zero, double *out,
                       gs_error *err) {
  return gs_cfg_double_range(solver, key, 0, (double)NAN, 0.0, !allow_zero, HUGE_VAL, 0, out, err);
}

/* initial_step must lie within [min_step, max_step] when they are given. */
static int gs_step_bounds_consistent(gs_cfg_node *solver, double h0, double hmin, double hmax,
                                     gs_error *err) {
  if (hmin > hmax)
    return gs_cfg_fail(gs_cfg_get(solver, "min_step"), err,
                       "min_step must not exceed max_step = %g", hmax);
  if (h0 < hmin)
    return gs_cfg_fail(gs_cfg_get(solver, "initial_step"), err,
                       "initial_step must not be below min_step = %g", hmin);
  if (h0 > hmax)
    return gs_cfg_fail(gs_cfg_get(solver, "initial_step"), err,
                       "initial_step must not exceed max_step = %g", hmax);
  return GS_OK; /* comparisons with NAN (absent keys) are false: nothing to check */
}

int gs_integrator_common_keys(gs_cfg_node *solver, double *rtol, double *atol,
                              double *initial_step, double *min_step, double *max_step,
                              long *max_steps, gs_error *err) {
  int rc = gs_cfg_double_range(solver, "rtol", 0, 1e-6, 0.0, 1, 1.0, 1, rtol, err);
  if (!rc) rc = gs_cfg_double_range(solver, "atol", 0, GS_INTEGRATOR_ATOL, 0.0, 1, HUGE_VAL, 0, atol, err);
  if (!rc) rc = gs_step_key(solver, "initial_step", 0, initial_step, err);
  if (!rc) rc = gs_step_key(solver, "min_step", 1, min_step, err);
  if (!rc) rc = gs_step_key(solver, "max_step", 0, max_step, err);
  if (!rc)
    rc = gs_cfg_long_range(solver, "max_steps_per_output", 0, 10000000L, 1, LONG_MAX, max_steps,
                           err);
  if (!rc) rc = gs_step_bounds_consistent(solver, *initial_step, *min_step, *max_step, err);
  return rc;
}

/* "rk (summary); cvode (summary); ..." for the unknown-method message. */
static void gs_list_methods(char *buf, size_t size) {
  size_t used = 0;
  buf[0] = '\0';
  for (size_t i = 0; registry[i] && used < size; i++) {
    int w = snprintf(buf + used, size - used, "%s%s (%s)", i ? "; " : "", registry[i]->name,
                     registry[i]->summary);
    if (w < 0) break;
    used += (size_t)w;
  }
}

static int gs_pick_method(gs_cfg_node *solver, const gs_integrator_type **type, gs_error *err) {
  const char *name = NULL;
  int rc = gs_cfg_string_opt(solver, "method", "auto", &name, err);
  if (rc) return rc;
  *type = gs_integrator_lookup(name);
  if (*type) return GS_OK;
  char list[1024];
  gs_list_methods(list, sizeof list);
  return gs_cfg_fail(gs_cfg_get(solver, "method"), err,
                     "unknown integrator method; expected one of: %s", list);
}

/* The system must be usable before any integrator looks at it. */
static int gs_check_ode(const gs_ode *ode, gs_error *err) {
  if (!ode || !ode->f || ode->n == 0)
    return gs_error_set(err, GS_EINPUT, "integrator: the ODE system is empty or has no f");
  if (ode->npositive > ode->n)
    return gs_error_set(err, GS_EINPUT, "integrator: npositive = %zu exceeds n = %zu",
                        ode->npositive, ode->n);
  for (size_t i = 0; ode->abs_scale && i < ode->n; i++)
    if (!(ode->abs_scale[i] >= 0) || !isfinite(ode->abs_scale[i]))
      return gs_error_set(err, GS_EINPUT, "integrator: abs_scale[%zu] = %g must be finite and >= 0",
                          i, ode->abs_scale[i]);
  return GS_OK;
}

int gs_integrator_setup_read(gs_cfg_node *solver, gs_integrator_setup *out, gs_error *err) {
  out->type = NULL;
  out->settings = NULL;
  int rc = solver ? gs_cfg_require_kind(solver, GS_CFG_MAP, err) : GS_OK;
  const gs_integrator_type *type = NULL;
  if (!rc) rc = gs_pick_method(solver, &type, err);
  if (!rc) rc = type->read(solver, &out->settings, err);
  if (!rc) out->type = type;
  return rc;
}

void gs_integrator_setup_free(gs_integrator_setup *setup) {
  if (setup->type && setup->type->free_settings) setup->type->free_settings(setup->settings);
  else free(setup->settings);
  setup->settings = NULL;
  setup->type = NULL;
}

int gs_integrator_create(const gs_integrator_setup *setup, const gs_ode *ode, gs_integrator *out,
                         gs_error *err) {
  out->type = NULL;
  out->self = NULL;
  int rc = gs_check_ode(ode, err);
  if (!rc && !setup->type)
    rc = gs_error_set(err, GS_EINPUT, "integrator: no method was read for this system");
  void *self = NULL;
  if (!rc) rc = setup->type->create(setup->settings, ode, &self, err);
  if (rc) return rc;
  out->type = setup->type;
  out->self = self;
  return GS_OK;
}

void gs_integrator_free(gs_integrator *it) {
  if (!it) return;
  if (it->type && it->self) it->type->free(it->self);
  it->type = NULL;
  it->self = NULL;
}
