/* Brownian coagulation (Friedlander 2000, ch. 7; docs/models.md), on the
 * volume v of a size measure (default the granule volume, key "axes"):
 *   continuum (Smoluchowski):
 *     beta = K_c (1/d + 1/d')(d + d') = K_c (2 + r + 1/r),  r = (v/v')^(1/3),
 *     K_c = 2 kT / (3 mu)
 *   free molecular:
 *     beta = K_f (1/v + 1/v')^(1/2) (v^(1/3) + v'^(1/3))^2,
 *     K_f = (3/(4 pi))^(1/6) (6 kT / rho_p)^(1/2)
 * K is beta0 when given, else computed from temperature, viscosity or
 * particle density (SI: the volume axes then in m^3).
 *
 * Both diverge as a partner's volume goes to 0, so volumes are taken no
 * smaller than v_lo (key min_volume; default the smallest positive pivot
 * volume of the grid).  Every pivot lies at or above it, so row() is the
 * formula itself.  A particle below it (stochastic solver: sampled initial
 * states, fragments) is one the grid cannot describe; its pairs take the
 * kernel of the clamped volumes w = max(v, v_lo) times (v + v') / (w + w')
 * (<= 1), which keeps the majorant below true for every state, however far
 * the population moves: beta <= coef (w + w') (v + v') / (w + w').
 *
 * Majorant, sum form coef (v + v') on volumes v <= v' = t v at or above v_lo:
 *   continuum: 2 + r + 1/r <= 3 + t^(1/3) <= 2 (1 + t)  (t >= 1), so
 *     beta <= 2 K_c (v + v') / v <= (2 K_c / v_lo) (v + v');
 *   free molecular: beta = K_f v^(1/6) (1 + 1/t)^(1/2) (1 + t^(1/3))^2 with
 *     (1 + 1/t)^(1/2) <= 2^(1/2), (1 + t^(1/3))^2 <= 2 (1 + t^(2/3)) <= 2 (1 + t),
 *     so beta <= 2^(3/2) K_f v^(-5/6) (v + v') <= 2^(3/2) K_f v_lo^(-5/6) (v + v').
 * Equality holds for equal volumes at v_lo in both; the sum form does not
 * need an upper size.  Its acceptance falls as the population grows past
 * v_lo (roughly v_lo / mean volume): the price of a bound that holds for
 * every state. */
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"
#include "kernel/size_measure.h"

#define GS_BOLTZMANN 1.380649e-23 /* J/K, exact in SI since 2019 */

enum { CONTINUUM = 0, FREE_MOLECULAR = 1 };

typedef struct {
  double *beta0; /* per compartment: K_c or K_f */
  double *bound; /* per compartment: the majorant's coefficient */
  int differ;    /* beta0 differs between compartments */
  int regime, dim;
  unsigned axes;   /* the axes of the volume */
  double v_lo;     /* smallest volume taken */
  double *cbrt_v;  /* per cell: v^(1/3) (clamped) */
  double *inv;     /* per cell: 1 / v^(1/3) (continuum) or 1 / v (free molecular), clamped */
} brownian_kernel;

static void brownian_free(void *self) {
  brownian_kernel *k = self;
  free(k->beta0);
  free(k->bound);
  free(k->cbrt_v);
  free(k->inv);
  free(k);
}

/* beta / K between volumes given by their cube roots c and `inv` (1/c in
 * the continuum regime, 1/v in the free-molecular one).  Both are per-cell
 * numbers on the grid, so a continuum row is additions and multiplications
 * alone. */
static inline double brownian_pair(int regime, double ca, double ia, double cb, double ib) {
  if (regime == CONTINUUM) return (ca + cb) * (ia + ib);
  return sqrt(ia + ib) * (ca + cb) * (ca + cb);
}

/* The per-cell number `inv` of a (clamped) volume w with cube root c. */
static double brownian_inv(int regime, double c, double w) { return regime == CONTINUUM ? 1.0 / c : 1.0 / w; }

/* The prefactor: beta0 (a number or one per compartment), or from the
 * physical properties of the regime; not both. */
static int brownian_prefactor(gs_cfg_node *node, const gs_grid *g, brownian_kernel *k,
                              gs_error *err) {
  const char *prop = k->regime == CONTINUUM ? "viscosity" : "density";
  const char *other = k->regime == CONTINUUM ? "density" : "viscosity";
  gs_cfg_node *stray = gs_cfg_get(node, other);
  if (stray)
    return gs_cfg_fail(stray, err, "not a key of the %s regime (it takes %s)",
                       k->regime == CONTINUUM ? "continuum" : "free_molecular", prop);
  if (gs_cfg_get(node, "beta0")) {
    gs_cfg_node *n = gs_cfg_get(node, prop);
    if (!n) n = gs_cfg_get(node, "temperature");
    if (n) return gs_cfg_fail(n, err, "give beta0 or the physical properties, not both");
    return gs_kernel_beta0(node, 1, 0, g, &k->beta0, &k->differ, err);
  }
  double T = 0, p = 0;
  int rc = gs_cfg_double_range(node, "temperature", 0, 293.15, 0, 1, HUGE_VAL, 0, &T, err);
  if (!rc && !gs_cfg_get(node, prop))
    return gs_cfg_fail(node, err, "the brownian kernel needs beta0 or %s", prop);
  if (!rc) rc = gs_cfg_double_range(node, prop, 1, 0, 0, 1, HUGE_VAL, 0, &p, err);
  if (rc) return rc;
  double K = k->regime == CONTINUUM ? 2 * GS_BOLTZMANN * T / (3 * p)
                                    : pow(3 / (4 * M_PI), 1.0 / 6) * sqrt(6 * GS_BOLTZMANN * T / p);
  k->beta0 = gs_malloc(g->ncomp * sizeof(double), err);
  if (!k->beta0) return GS_ENOMEM;
  for (size_t z = 0; z < g->ncomp; z++) k->beta0[z] = K;
  return GS_OK;
}

static int brownian_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                           gs_error *err) {
  (void)dir;
  static const char *const regimes[] = {"continuum", "free_molecular", NULL};
  brownian_kernel *k = gs_calloc(1, sizeof *k, err);
  if (!k) return GS_ENOMEM;
  k->dim = g->dim;
  double *size = NULL;
  int rc = gs_cfg_enum_opt(node, "regime", regimes, CONTINUUM, &k->regime, err);
  if (!rc) rc = brownian_prefactor(node, g, k, err);
  if (!rc && !(size = gs_size_measure_mask(node, g, &k->axes, err))) rc = err->code;
  double lo = HUGE_VAL;
  for (size_t c = 0; !rc && c < g->ncells; c++)
    if (size[c] > 0 && size[c] < lo) lo = size[c];
  if (!rc && lo == HUGE_VAL) rc = gs_cfg_fail(node, err, "no cell of the grid has a positive volume");
  if (!rc) rc = gs_cfg_double_range(node, "min_volume", 0, lo, 0, 1, lo, 0, &k->v_lo, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (!rc) {
    k->cbrt_v = gs_malloc(g->ncells * sizeof(double), err);
    k->inv = gs_malloc(g->ncells * sizeof(double), err);
    k->bound = gs_malloc(g->ncomp * sizeof(double), err);
    if (!k->cbrt_v || !k->inv || !k->bound) rc = GS_ENOMEM;
  }
  if (rc) {
    free(size);
    brownian_free(k);
    return rc;
  }
  for (size_t c = 0; c < g->ncells; c++) {
    double v = fmax(size[c], k->v_lo);
    k->cbrt_v[c] = cbrt(v);
    k->inv[c] = brownian_inv(k->regime, k->cbrt_v[c], v);
  }
  free(size);
  const double f = k->regime == CONTINUUM ? 2.0 / k->v_lo : pow(2.0, 1.5) * pow(k->v_lo, -5.0 / 6);
  for (size_t z = 0; z < g->ncomp; z++) k->bound[z] = k->beta0[z] * f;
  *self = k;
  return GS_OK;
}

static void brownian_row(const void *self, size_t comp, size_t a, size_t b0, size_t b1,
                         double *out) {
  const brownian_kernel *k = self;
  const double K = k->beta0[comp], ca = k->cbrt_v[a], ia = k->inv[a];
  const double *cb = k->cbrt_v, *ib = k->inv;
  if (k->regime == CONTINUUM)
    for (size_t b = b0; b < b1; b++) out[b - b0] = K * brownian_pair(CONTINUUM, ca, ia, cb[b], ib[b]);
  else
    for (size_t b = b0; b < b1; b++) out[b - b0] = K * brownian_pair(FREE_MOLECULAR, ca, ia, cb[b], ib[b]);
}

static int brownian_per_compartment(const void *self) {
  return ((const brownian_kernel *)self)->differ;
}

/* Continuum rows are two additions and two multiplications per pair on
 * per-cell arrays, cheaper than reading a table; free-molecular rows take a
 * square root per pair and keep the table. */
static int brownian_cheap_row(const void *self) {
  return ((const brownian_kernel *)self)->regime == CONTINUUM;
}

static double brownian_at(const void *self, size_t comp, const double *x, const double *y) {
  const brownian_kernel *k = self;
  const double vx = gs_size_of(k->axes, k->dim, x), vy = gs_size_of(k->axes, k->dim, y);
  const double wx = fmax(vx, k->v_lo), wy = fmax(vy, k->v_lo);
  const double cx = cbrt(wx), cy = cbrt(wy);
  const double beta = k->beta0[comp] * brownian_pair(k->regime, cx, brownian_inv(k->regime, cx, wx), cy,
                                                     brownian_inv(k->regime, cy, wy));
  /* below v_lo: scaled with the volume (see the majorant above) */
  return vx >= k->v_lo && vy >= k->v_lo ? beta : beta * ((vx + vy) / (wx + wy));
}

static void brownian_form(const void *self, gs_kernel_form *out) {
  const brownian_kernel *k = self;
  *out = (gs_kernel_form){.kind = GS_KERNEL_FORM_SUM, .coef = k->bound, .axes = k->axes, .exact = 0};
}

const gs_kernel_type gs_kernel_brownian = {
    .name = "brownian",
    .summary = "Brownian: continuum K(1/d+1/d')(d+d') or free molecular K(1/v+1/v')^1/2 (v^1/3+v'^1/3)^2",
    .create = brownian_create,
    .row = brownian_row,
    .free = brownian_free,
    .per_compartment = brownian_per_compartment,
    .cheap_row = brownian_cheap_row,
    .at = brownian_at,
    .form = brownian_form,
};
