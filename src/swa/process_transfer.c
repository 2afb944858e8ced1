/* Transport between compartments (McGuire et al. 2018, eqs. 58-61): every particle of
 * compartment z leaves at rate k_z = 1 / tau_z; it enters z + 1 with its
 * weight scaled by V_{z+1} / V_z (so it stands for the same real number),
 * and leaves the system from the last compartment (product). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "swa/sim.h"

typedef struct transfer {
  double *k;
} transfer;

static void transfer_free(void *self) {
  transfer *t = self;
  if (t) free(t->k);
  free(t);
}

static int transfer_create(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err) {
  transfer *t = gs_calloc(1, sizeof *t, err);
  if (!t) return GS_ENOMEM;
  *self = t;
  t->k = gs_calloc(m->ncomp, sizeof(double), err);
  if (!t->k) return GS_ENOMEM;
  int has_rate = !!gs_cfg_get(node, "rate"), has_tau = !!gs_cfg_get(node, "residence_time");
  if (has_rate == has_tau)
    return gs_cfg_fail(node, err, "a transfer needs exactly one of 'rate' or 'residence_time'");
  int rc = gs_swa_per_comp(node, has_rate ? "rate" : "residence_time", 1, 0, 0, 1, m, t->k, err);
  for (size_t z = 0; !rc && !has_rate && z < m->ncomp; z++) t->k[z] = 1 / t->k[z];
  if (!rc) rc = gs_cfg_check_unused(node, err);
  return rc;
}

static double transfer_rate(const void *self, const gs_swa_sim *s, size_t z) {
  const transfer *t = self;
  return t->k[z] * (double)gs_swa_count(s, z);
}

static int transfer_jump(const void *self, gs_swa_sim *s, size_t z, gs_error *err) {
  (void)self;
  size_t i = gs_swa_select(s, z, -1);
  if (i == GS_NOWHERE) {
    gs_swa_fictitious(s);
    return GS_OK;
  }
  if (z + 1 < s->m->ncomp) {
    double x[GS_SWA_MAX_COORD];
    memcpy(x, gs_swa_x(s, z, i), (size_t)s->m->ncoord * sizeof(double));
    double w = gs_swa_w(s, z, i) * gs_swa_vsamp(s, z + 1) / gs_swa_vsamp(s, z);
    gs_swa_remove(s, z, i);
    return gs_swa_add(s, z + 1, x, w, err);
  }
  gs_swa_remove(s, z, i);
  return GS_OK;
}

const gs_swa_process_type gs_swa_transfer = {
    .name = "transfer",
    .summary = "transport to the next compartment, weights scaled by the sample volumes",
    .create = transfer_create,
    .rate = transfer_rate,
    .jump = transfer_jump,
    .free = transfer_free,
};
