/* Daughter (fragment) distributions b(z) over the fraction z of the parent,
 * a registry of named types.  Each satisfies int z b = 1 (mass).
 *   uniform: b = 2                    binary, uniform (Ziff & McGrady)
 *   halves:  b = 2 delta(z - 1/2)     binary, equal halves
 *   power:   b = nu (q+1) z^q, nu = (q+2)/(q+1)   (q = exponent > -1; q = 0 is uniform)
 *   beta:    b = nu Beta(z; a, (nu-1) a)           nu fragments (>= 2 on average), shape a
 * count_below / mass_below are the closed-form partial integrals. */
#include <gsl/gsl_errno.h>
#include <gsl/gsl_sf_gamma.h>
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"

typedef struct {
  double nu, q; /* power: q exponent; beta: nu fragments, q = shape a */
} dau_t;

static int dau_make(gs_cfg_node *node, dau_t *d, int rc, void **self, gs_error *err) {
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    free(d);
    return rc;
  }
  *self = d;
  return GS_OK;
}

static void dau_free(void *self) { free(self); }
static void no_atoms(const void *self, double *z, int *n) {
  (void)self;
  (void)z;
  *n = 0;
}
static double clamp01(double z) { return z < 0 ? 0 : z > 1 ? 1 : z; }

static int uniform_create(gs_cfg_node *node, void **self, gs_error *err) {
  dau_t *d = gs_calloc(1, sizeof *d, err);
  if (!d) return GS_ENOMEM;
  d->nu = 2;
  return dau_make(node, d, GS_OK, self, err);
}
static double uniform_count(const void *s, double z) { (void)s; return 2 * clamp01(z); }
static double uniform_mass(const void *s, double z) { (void)s; z = clamp01(z); return z * z; }

static double halves_count(const void *s, double z) { (void)s; return z >= 0.5 ? 2 : 0; }
static double halves_mass(const void *s, double z) { (void)s; return z >= 0.5 ? 1 : 0; }
static void halves_atoms(const void *s, double *z, int *n) {
  (void)s;
  z[0] = 0.5;
  *n = 1;
}

static int power_create(gs_cfg_node *node, void **self, gs_error *err) {
  dau_t *d = gs_calloc(1, sizeof *d, err);
  if (!d) return GS_ENOMEM;
  int rc = gs_cfg_double_range(node, "exponent", 1, 0, -1, 1, HUGE_VAL, 0, &d->q, err);
  d->nu = (d->q + 2) / (d->q + 1);
  return dau_make(node, d, rc, self, err);
}
static double power_count(const void *s, double z) {
  const dau_t *d = s;
  return d->nu * pow(clamp01(z), d->q + 1);
}
static double power_mass(const void *s, double z) {
  const dau_t *d = s;
  return pow(clamp01(z), d->q + 2);
}

static int beta_create(gs_cfg_node *node, void **self, gs_error *err) {
  dau_t *d = gs_calloc(1, sizeof *d, err);
  if (!d) return GS_ENOMEM;
  int rc = gs_cfg_double_range(node, "fragments", 1, 0, 1, 1, HUGE_VAL, 0, &d->nu, err);
  if (!rc) rc = gs_cfg_double_range(node, "shape", 0, 1, 0, 1, HUGE_VAL, 0, &d->q, err);
  return dau_make(node, d, rc, self, err);
}
/* The regularised incomplete beta I_z(a, b).  With a large shape it lies
 * below the smallest double far into the tails, where GSL reports an
 * underflow with the value 0: that 0 is exact to round-off (the fractions
 * it is compared with sum to 1).  Any other failure gives NaN, which the
 * breakage tables refuse naming the daughters key and GSL's reason. */
static double beta_inc(double a, double b, double z) {
  gsl_sf_result r;
  int st = gsl_sf_beta_inc_e(a, b, z, &r);
  if (st == GSL_EUNDRFLW) return 0.0;
  return st == GSL_SUCCESS ? r.val : NAN;
}
/* Symmetric Beta(a, (nu-1)a) has mean 1/nu, so nu * E[z] = 1 conserves mass;
 * int_0^z z' b = I_z(a+1, (nu-1)a). */
static double beta_count(const void *s, double z) {
  const dau_t *d = s;
  return d->nu * beta_inc(d->q, (d->nu - 1) * d->q, clamp01(z));
}
static double beta_mass(const void *s, double z) {
  const dau_t *d = s;
  return beta_inc(d->q + 1, (d->nu - 1) * d->q, clamp01(z));
}

static const gs_daughter_type uniform_t = {
    .name = "uniform",
    .summary = "binary, uniform fragments: b = 2",
    .create = uniform_create,
    .count_below = uniform_count,
    .mass_below = uniform_mass,
    .atoms = no_atoms,
    .free = dau_free,
};
static const gs_daughter_type halves_t = {
    .name = "halves",
    .summary = "binary, two equal halves",
    .create = uniform_create,
    .count_below = halves_count,
    .mass_below = halves_mass,
    .atoms = halves_atoms,
    .free = dau_free,
};
static const gs_daughter_type power_t = {
    .name = "power",
    .summary = "b = nu (q+1) z^q with nu = (q+2)/(q+1)",
    .create = power_create,
    .count_below = power_count,
    .mass_below = power_mass,
    .atoms = no_atoms,
    .free = dau_free,
};
static const gs_daughter_type beta_t = {
    .name = "beta",
    .summary = "nu fragments, b = nu Beta(z; a, (nu-1) a)",
    .create = beta_create,
    .count_below = beta_count,
    .mass_below = beta_mass,
    .atoms = no_atoms,
    .free = dau_free,
};
static const gs_daughter_type *const registry[] = {&uniform_t, &halves_t, &power_t, &beta_t, NULL};

const gs_daughter_type *const *gs_daughter_types(void) { return registry; }

int gs_daughter_create(gs_cfg_node *node, gs_daughter *d, gs_error *err) {
  d->self = NULL;
  d->type = gs_registry_pick(node, (const void *const *)registry, "daughter distribution", err);
  if (!d->type) return GS_EINPUT;
  return d->type->create(node, &d->self, err);
}

void gs_daughter_free(gs_daughter *d) {
  if (d->type && d->self) d->type->free(d->self);
  d->type = NULL;
  d->self = NULL;
}
