/* The sectional model: grid + registered mechanisms; full right-hand side. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"

extern const gs_mech_type gs_mech_aggregation, gs_mech_breakage, gs_mech_growth,
    gs_mech_liquid_addition, gs_mech_consolidation, gs_mech_feed, gs_mech_transfer;

/* Adding a mechanism is one file and one line here. */
static const gs_mech_type *const registry[] = {
    &gs_mech_aggregation, &gs_mech_breakage, &gs_mech_growth, &gs_mech_liquid_addition,
    &gs_mech_consolidation, &gs_mech_feed, &gs_mech_transfer, NULL};

const gs_mech_type *const *gs_mech_types(void) { return registry; }

const gs_mech_type *gs_mech_lookup(const char *name) {
  for (size_t i = 0; registry[i]; i++)
    if (!strcmp(registry[i]->name, name)) return registry[i];
  return NULL;
}

int gs_model_init(gs_model *m, gs_grid *grid, gs_error *err) {
  memset(m, 0, sizeof *m);
  m->grid = *grid;
  memset(grid, 0, sizeof *grid);
  m->nstate = m->grid.ncomp * m->grid.ncells;
  m->nledger = m->grid.ncomp * 2 * (size_t)m->grid.dim;
  m->size_axes = (1 << m->grid.dim) - 1;
  strcpy(m->dir, ".");
  m->size_volume = gs_malloc(m->grid.ncells * sizeof(double), err);
  if (!m->size_volume) return GS_ENOMEM;
  memcpy(m->size_volume, m->grid.volume, m->grid.ncells * sizeof(double));
  return GS_OK;
}

int gs_model_add_mechanism(gs_model *m, const char *type, gs_cfg_node *node, const char *label,
                           gs_error *err) {
  const gs_mech_type *t = gs_mech_lookup(type);
  if (!t) return gs_error_set(err, GS_EINPUT, "unknown mechanism type '%s'", type);
  gs_mechanism *grown = realloc(m->mech, (m->nmech + 1) * sizeof *grown);
  if (!grown) return gs_error_set(err, GS_ENOMEM, "out of memory");
  m->mech = grown;
  gs_mechanism *mech = &m->mech[m->nmech];
  memset(mech, 0, sizeof *mech);
  mech->type = t;
  snprintf(mech->label, sizeof mech->label, "%s", label ? label : type);
  int rc = t->create(node, m, &mech->self, err);
  if (rc) return rc;
  m->nmech++;
  return GS_OK;
}

void gs_model_free(gs_model *m) {
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->free) m->mech[i].type->free(m->mech[i].self);
  free(m->mech);
  free(m->size_volume);
  gs_grid_free(&m->grid);
  memset(m, 0, sizeof *m);
}

int gs_model_has_preconditioner(const gs_model *m) {
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->precondition) return 1;
  return 0;
}

void gs_model_precondition(const gs_model *m, double t, const double *y, double gamma,
                           const double *r, double *z) {
  memcpy(z, r, (m->nstate + m->nledger) * sizeof(double));
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->precondition)
      m->mech[i].type->precondition(m->mech[i].self, m, t, y, gamma, z);
}

void gs_model_rhs(const gs_model *m, double t, const double *y, double *dydt, double *dledger) {
  memset(dydt, 0, m->nstate * sizeof(double));
  memset(dledger, 0, m->nledger * sizeof(double));
  for (size_t i = 0; i < m->nmech; i++)
    m->mech[i].type->rhs(m->mech[i].self, m, t, y, dydt, dledger);
}
