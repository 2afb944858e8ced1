/* Liquid penetration (McGuire et al. 2018, eqs. 23-24), a continuous process deferred
 * with LPDA: r = k l_e (p - l_i) moves external liquid into the pores.  With
 * a = l_e, b = p - l_i: da/dt = -k a b, db/dt = -kappa k a b (kappa = 2 when
 * the pores shrink with the penetrated liquid, as printed; 1 otherwise), so
 * C = b - kappa a is constant and a(t) has a closed form (no ODE steps). */
#include <math.h>
#include <stdlib.h>

#include "swa/compaction.h"
#include "swa/sim.h"

typedef struct pen {
  double *k;
  int shrink;
  int solid, ext, in, pores;
} pen;

static void pen_free(void *self) {
  pen *p = self;
  if (p) free(p->k);
  free(p);
}

static int pen_create(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err) {
  pen *p = gs_calloc(1, sizeof *p, err);
  if (!p) return GS_ENOMEM;
  *self = p;
  p->k = gs_calloc(m->ncomp, sizeof(double), err);
  if (!p->k) return GS_ENOMEM;
  int rc = gs_swa_per_comp(node, "rate", 1, 0, 0, 0, m, p->k, err);
  if (!rc) rc = gs_cfg_bool_opt(node, "pore_shrinkage", 1, &p->shrink, err);
  if (!rc) rc = gs_swa_roles(node, m, &p->solid, &p->ext, &p->in, &p->pores, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  m->has_continuous = 1;
  return rc;
}

/* External liquid left after dt, for a0 > 0, b0 > 0. */
double gs_swa_penetration_left(double a0, double b0, double k, double kappa, double dt) {
  double c = b0 - kappa * a0;
  if (c == 0) return a0 / (1 + kappa * k * a0 * dt);
  if (c > 0) {
    double e = exp(-k * c * dt);
    return c * a0 * e / (c + kappa * a0 * (1 - e));
  }
  double e = exp(k * c * dt); /* c < 0: written with the decaying exponential */
  return c * a0 / (c * e + kappa * a0 * (e - 1));
}

static void pen_advance(const void *self, size_t z, double *x, double dt) {
  const pen *p = self;
  double a0 = x[p->ext], b0 = x[p->pores] - x[p->in];
  if (!(a0 > 0) || !(b0 > 0) || !(p->k[z] > 0)) return;
  double kappa = p->shrink ? 2 : 1;
  double a = gs_swa_penetration_left(a0, b0, p->k[z], kappa, dt);
  double d = a0 - (a > 0 ? a : 0);
  x[p->ext] -= d;
  x[p->in] += d;
  if (p->shrink) x[p->pores] -= d;
}

const gs_swa_process_type gs_swa_penetration = {
    .name = "penetration",
    .summary = "liquid penetration into the pores, continuous (LPDA, closed form)",
    .create = pen_create,
    .advance = pen_advance,
    .free = pen_free,
};
