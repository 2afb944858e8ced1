/* Semi-mechanistic aggregation kernel of Chaudhury (2015), ch. 4, eqs. 4.1-4.9:
 *   beta = B0 C_ab Psi(St_v <= St*) (A_wet/A_total)_a (A_wet/A_total)_b
 * with the viscous Stokes number of Ennis et al. (1991), the surface liquid
 * as one spherical-cap droplet per particle, and the surface liquid a
 * function of the particle's liquid and pore gas (docs/models.md: spraying
 * raises l, consolidation lowers g and squeezes pore liquid out, so the
 * kernel stays a function of the two cells and serves both solvers).
 * C_ab = 1, or a DEM collision frequency per class pair read from a CSV
 * file (src/kernel/class_table.h), as the `table` kernel reads them. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/kernel.h"
#include "kernel/class_table.h"
#include "kernel/semimech.h"
#include "kernel/size_measure.h"

#define SEMIMECH_PI 3.14159265358979323846

double gs_semimech_phi(double theta) {
  const double c = cos(theta), s = sin(theta);
  return s * s * s / (2 - 3 * c + c * c * c);
}

double gs_semimech_surface_liquid(const gs_semimech_params *p, double l, double g) {
  const double hold = p->pore_ratio * g;
  if (l <= hold) return p->surface_fraction * l;
  return l - hold + p->surface_fraction * hold;
}

void gs_semimech_droplet(double V, double phi, double *radius, double *area, double *depth) {
  if (!(V > 0)) {
    *radius = *area = *depth = 0;
    return;
  }
  *radius = cbrt(3 * V * phi / SEMIMECH_PI);
  *area = SEMIMECH_PI * *radius * *radius;
  *depth = 1.5 * V / *area;
}

gs_semimech_particle gs_semimech_particle_of(const gs_semimech_params *p, double s, double l,
                                             double g) {
  gs_semimech_particle q = {.d = gs_diameter(s + l + g), .m = p->rho_solid * s + p->rho_liquid * l};
  double r, area, depth, total = SEMIMECH_PI * q.d * q.d;
  gs_semimech_droplet(gs_semimech_surface_liquid(p, l, g), p->phi, &r, &area, &depth);
  q.wet = total > 0 ? fmin(area / total, 1.0) : 0.0;
  q.h0 = depth;
  return q;
}

double gs_semimech_stokes(const gs_semimech_params *p, const gs_semimech_particle *a,
                          const gs_semimech_particle *b, double u0) {
  const double m = 2 * a->m * b->m / (a->m + b->m), d = 2 * a->d * b->d / (a->d + b->d);
  return 8 * m * u0 / (3 * SEMIMECH_PI * p->viscosity * d * d);
}

/* Psi = 1 when St_v <= St* = 2 ln(lambda / h_a): the pair's liquid layer is
 * the mean of the two depths (Ennis's h for equal layers), the asperity
 * height that of the pair's harmonic-mean diameter. */
double gs_semimech_pair(const gs_semimech_params *p, const gs_semimech_particle *a,
                        const gs_semimech_particle *b, double u0) {
  const double area = a->wet * b->wet;
  if (!(area > 0)) return 0.0;
  const double d = 2 * a->d * b->d / (a->d + b->d);
  const double lambda = 0.5 * (a->h0 + b->h0), ha = fmin(p->asperity_fraction * d, p->asperity_max);
  if (!(lambda > ha)) return 0.0;
  return gs_semimech_stokes(p, a, b, u0) <= 2 * log(lambda / ha) ? area : 0.0;
}

typedef struct {
  gs_semimech_params p;
  double *beta0, *u0, *bound; /* per compartment; bound = B0 max C */
  int differ;                 /* beta0 or u0 differ between compartments */
  int dim, liquid, gas;       /* axes; gas -1: no gas axis (g = 0) */
  gs_semimech_particle *cell; /* per cell */
  size_t nclass;              /* 0: no collision table (C = 1) */
  double *collisions, *edges; /* nclass x nclass; nclass + 1 edges */
  size_t *cls;                /* per cell: class */
  int diameter;               /* the edges measure diameters */
} semimech_kernel;

static void semimech_free(void *self) {
  semimech_kernel *k = self;
  free(k->beta0);
  free(k->u0);
  free(k->bound);
  free(k->cell);
  free(k->collisions);
  free(k->edges);
  free(k->cls);
  free(k);
}

/* The particle at coordinates x: solid = every axis but the liquid and gas. */
static gs_semimech_particle semimech_at_point(const semimech_kernel *k, const double *x) {
  double s = 0, l = x[k->liquid], g = k->gas >= 0 ? x[k->gas] : 0.0;
  for (int i = 0; i < k->dim; i++)
    if (i != k->liquid && i != k->gas) s += x[i];
  return gs_semimech_particle_of(&k->p, s, l, g);
}

static size_t semimech_class(const semimech_kernel *k, const double *x) {
  double v = gs_size_of((1u << k->dim) - 1, k->dim, x), s = k->diameter ? gs_diameter(v) : v;
  size_t i = 0;
  while (i + 1 < k->nclass && s >= k->edges[i + 1]) i++;
  return i;
}

static int read_axis(gs_cfg_node *node, const gs_grid *g, const char *key, const char *def,
                     int optional, int *axis, gs_error *err) {
  const char *name = NULL;
  int rc = gs_cfg_string_opt(node, key, def, &name, err);
  if (rc) return rc;
  *axis = gs_grid_axis_by_name(g, name);
  if (*axis >= 0) return GS_OK;
  gs_cfg_node *n = gs_cfg_get(node, key);
  if (!n && optional) return GS_OK;
  return n ? gs_cfg_fail(n, err, "expected the name of a grid axis")
           : gs_cfg_fail(node, err, "the semi_mechanistic kernel needs a grid axis named '%s' (or set %s)",
                         def, key);
}

/* Each compartment's u0 from the fragment `gransim compartments` wrote (its
 * `velocity`, the zones' mean DEM speeds), so that the zones the exchange
 * mechanism reads and the speeds the Stokes criterion uses come from one file. */
static int read_fragment_velocity(gs_cfg_node *v, const char *dir, size_t ncomp, double *u0, gs_error *err) {
  gs_cfg_node *fn = gs_cfg_get(v, "fragment");
  if (!fn) return gs_cfg_fail(v, err, "expected a number, a list of one per compartment [m/s] or "
                                      "{fragment: FILE} (a fragment of gransim compartments)");
  int rc = gs_cfg_check_unused(v, err);
  gs_cfg *cfg = rc ? NULL : gs_cfg_fragment_load(fn, dir, ncomp, err);
  if (!cfg) return rc ? rc : GS_EINPUT;
  rc = gs_cfg_per_comp(gs_cfg_root(cfg), "velocity", 1, 0, 0, 1, ncomp, u0, err);
  gs_cfg_free(cfg);
  if (rc) gs_error_prefix(err, "%s:%d: %s (the fragment's velocity): ", gs_cfg_file(fn), gs_cfg_line(fn), gs_cfg_path(fn));
  return rc;
}

/* u0: `velocity` (per compartment, or the fragment's), or the impeller's tip
 * speed times a fraction. */
static int read_velocity(gs_cfg_node *node, const char *dir, size_t ncomp, double *u0, gs_error *err) {
  gs_cfg_node *v = gs_cfg_get(node, "velocity"), *n = gs_cfg_get(node, "impeller_speed");
  if (v && n) return gs_cfg_fail(n, err, "give either velocity or impeller_speed, not both");
  if (!v && !n)
    return gs_cfg_fail(node, err, "missing key 'velocity' (m/s, or {fragment: FILE}), or 'impeller_speed' "
                                  "(rpm) with 'impeller_diameter' (m)");
  if (v && gs_cfg_kind_of(v) == GS_CFG_MAP) return read_fragment_velocity(v, dir, ncomp, u0, err);
  if (v) return gs_cfg_per_comp(node, "velocity", 1, 0, 0, 1, ncomp, u0, err);
  double rpm, diameter, fraction;
  int rc = gs_cfg_double_range(node, "impeller_speed", 1, 0, 0, 1, HUGE_VAL, 0, &rpm, err);
  if (!rc) rc = gs_cfg_double_range(node, "impeller_diameter", 1, 0, 0, 1, HUGE_VAL, 0, &diameter, err);
  if (!rc) rc = gs_cfg_double_range(node, "tip_speed_fraction", 0, 1, 0, 1, 1, 0, &fraction, err);
  for (size_t z = 0; !rc && z < ncomp; z++) u0[z] = fraction * SEMIMECH_PI * diameter * rpm / 60;
  return rc;
}

static int read_collisions(semimech_kernel *k, gs_cfg_node *node, const gs_grid *g, const char *dir,
                           gs_error *err) {
  static const char *const measures[] = {"volume", "diameter", NULL};
  gs_cfg_node *fn = gs_cfg_get(node, "collisions");
  int measure = 0;
  int rc = gs_cfg_enum_opt(node, "collisions_measure", measures, 0, &measure, err);
  if (rc || !fn) {
    gs_cfg_node *m = gs_cfg_get(node, "collisions_measure");
    return rc ? rc : m ? gs_cfg_fail(m, err, "given without 'collisions' (the DEM collision table)") : GS_OK;
  }
  const char *name = gs_cfg_scalar(fn);
  if (!name) return gs_cfg_fail(fn, err, "expected a file name (the DEM collision table)");
  char path[4096];
  snprintf(path, sizeof path, "%s%s%s", name[0] == '/' ? "" : dir, name[0] == '/' ? "" : "/", name);
  gs_class_table tf = {0};
  rc = gs_class_table_read(path, 0, &tf, err);
  if (rc) {
    gs_error_prefix(err, "%s:%d: %s: ", gs_cfg_file(fn), gs_cfg_line(fn), gs_cfg_path(fn));
    return rc;
  }
  double *size = gs_malloc(g->ncells * sizeof(double), err);
  for (size_t c = 0; size && c < g->ncells; c++) size[c] = g->volume[c];
  k->nclass = tf.n;
  k->diameter = measure == 1;
  k->cls = size ? gs_class_table_assign(&tf, size, g->ncells, k->diameter, path, err) : NULL;
  k->collisions = tf.c; /* kept: the kernel owns the table from here */
  k->edges = tf.edges;
  free(size);
  return k->cls ? GS_OK : err->code ? err->code : GS_ENOMEM;
}

static int semimech_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                           gs_error *err) {
  semimech_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  gs_semimech_params *p = &k->p;
  double theta = 0, saturation = 0;
  k->u0 = gs_calloc(g->ncomp, sizeof(double), err);
  k->bound = gs_calloc(g->ncomp, sizeof(double), err);
  k->cell = gs_calloc(g->ncells, sizeof *k->cell, err);
  int differ = 0, rc = k->u0 && k->bound && k->cell ? GS_OK : GS_ENOMEM;
  if (!rc) rc = gs_kernel_beta0(node, 1, 0, g, &k->beta0, &differ, err);
  if (!rc) rc = read_velocity(node, dir, g->ncomp, k->u0, err);
  if (!rc) rc = gs_cfg_double_range(node, "viscosity", 1, 0, 0, 1, HUGE_VAL, 0, &p->viscosity, err);
  if (!rc) rc = gs_cfg_double_range(node, "contact_angle", 1, 0, 0, 1, 180, 1, &theta, err);
  if (!rc) rc = gs_cfg_double_range(node, "solid_density", 1, 0, 0, 1, HUGE_VAL, 0, &p->rho_solid, err);
  if (!rc) rc = gs_cfg_double_range(node, "liquid_density", 0, 1000, 0, 1, HUGE_VAL, 0, &p->rho_liquid, err);
  if (!rc) rc = gs_cfg_double_range(node, "critical_saturation", 1, 0, 0, 0, 1, 1, &saturation, err);
  if (!rc) rc = gs_cfg_double_range(node, "surface_fraction", 0, 0, 0, 0, 1, 0, &p->surface_fraction, err);
  if (!rc) rc = gs_cfg_double_range(node, "asperity_fraction", 0, 0.02, 0, 1, HUGE_VAL, 0, &p->asperity_fraction, err);
  if (!rc) rc = gs_cfg_double_range(node, "asperity_max", 0, 3e-6, 0, 1, HUGE_VAL, 0, &p->asperity_max, err);
  if (!rc) rc = read_axis(node, g, "liquid_axis", "liquid", 0, &k->liquid, err);
  if (!rc) rc = read_axis(node, g, "gas_axis", "gas", 1, &k->gas, err);
  if (!rc && (k->gas == k->liquid || g->dim - 1 - (k->gas >= 0) < 1))
    rc = gs_cfg_fail(node, err, "the semi_mechanistic kernel needs a solid axis besides distinct liquid and gas axes");
  if (!rc) rc = read_collisions(k, node, g, dir, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    semimech_free(k);
    return rc;
  }
  p->phi = gs_semimech_phi(theta * SEMIMECH_PI / 180);
  p->pore_ratio = saturation / (1 - saturation);
  k->dim = g->dim;
  for (size_t c = 0; c < g->ncells; c++) k->cell[c] = semimech_at_point(k, g->x + c * (size_t)g->dim);
  double top = k->nclass ? 0.0 : 1.0; /* max C */
  for (size_t i = 0; i < k->nclass * k->nclass; i++) top = fmax(top, k->collisions[i]);
  for (size_t z = 0; z < g->ncomp; z++) {
    k->bound[z] = k->beta0[z] * top;
    differ |= k->u0[z] != k->u0[0];
  }
  k->differ = differ;
  *self = k;
  return GS_OK;
}

static void semimech_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1,
                         double *out) {
  const semimech_kernel *k = self;
  const double beta0 = k->beta0[comp], u0 = k->u0[comp];
  for (size_t b = b0; b < b1; b++) {
    const double pa = gs_semimech_pair(&k->p, &k->cell[a], &k->cell[b], u0);
    out[b - b0] = pa > 0 ? beta0 * pa * (k->nclass ? k->collisions[k->cls[a] * k->nclass + k->cls[b]] : 1.0)
                         : 0.0;
  }
}

static double semimech_at(const void *self, size_t comp, const double *x, const double *y) {
  const semimech_kernel *k = self;
  const gs_semimech_particle a = semimech_at_point(k, x), b = semimech_at_point(k, y);
  const double pa = gs_semimech_pair(&k->p, &a, &b, k->u0[comp]);
  if (!(pa > 0)) return 0.0;
  const double c = k->nclass ? k->collisions[semimech_class(k, x) * k->nclass + semimech_class(k, y)] : 1.0;
  return k->beta0[comp] * pa * c;
}

/* Psi <= 1 and each wetted fraction <= 1, so beta <= B0 max C for every pair. */
static void semimech_form(const void *self, gs_kernel_form *out) {
  const semimech_kernel *k = self;
  *out = (gs_kernel_form){.kind = GS_KERNEL_FORM_CONSTANT, .coef = k->bound, .axes = 0, .exact = 0};
}

static int semimech_per_compartment(const void *self) {
  return ((const semimech_kernel *)self)->differ;
}

const gs_kernel_type gs_kernel_semimech = {
    .name = "semi_mechanistic",
    .summary = "B0 C Psi(St_v <= St*) wetted-area fractions, surface liquid from l and g (Chaudhury 2015)",
    .create = semimech_create,
    .row = semimech_row,
    .free = semimech_free,
    .per_compartment = semimech_per_compartment,
    .at = semimech_at,
    .form = semimech_form,
};
