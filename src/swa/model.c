/* The SWA model: coordinates, densities, cached-property columns, the
 * registry of process types, and small helpers for process keys. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/swa.h"

extern const gs_swa_process_type gs_swa_coagulation, gs_swa_breakage, gs_swa_feed,
    gs_swa_transfer, gs_swa_nucleation, gs_swa_penetration;

/* Adding a process is one file and one line here. */
static const gs_swa_process_type *const registry[] = {
    &gs_swa_coagulation, &gs_swa_breakage,   &gs_swa_feed,
    &gs_swa_transfer,    &gs_swa_nucleation, &gs_swa_penetration, NULL};

const gs_swa_process_type *const *gs_swa_process_types(void) { return registry; }

int gs_swa_model_add_prop(gs_swa_model *m, gs_swa_prop_fn fn, const void *ctx) {
  if (m->nprop >= GS_SWA_MAX_PROP) return -1;
  m->prop_fn[m->nprop] = fn;
  m->prop_ctx[m->nprop] = ctx;
  return m->nprop++;
}

int gs_swa_coord_by_name(const gs_swa_model *m, const char *name) {
  for (int k = 0; k < m->ncoord; k++)
    if (!strcmp(m->coord[k], name)) return k;
  return -1;
}

double gs_swa_mass(const gs_swa_model *m, const double *x) {
  double s = 0;
  for (int k = 0; k < m->ncoord; k++) s += m->density[k] * x[k];
  return s;
}

double gs_swa_size(const gs_swa_model *m, const double *x) {
  double s = 0;
  for (int k = 0; k < m->ncoord; k++)
    if (m->size_mask & (1u << k)) s += x[k];
  return s;
}

static void coord_list(const gs_swa_model *m, char *buf, size_t n) {
  buf[0] = '\0';
  for (int k = 0; k < m->ncoord; k++) {
    if (k) strncat(buf, ", ", n - strlen(buf) - 1);
    strncat(buf, m->coord[k], n - strlen(buf) - 1);
  }
}

int gs_swa_coord_key(gs_cfg_node *node, const char *key, const gs_swa_model *m,
                     const char *def, int *out, gs_error *err) {
  const char *name = NULL;
  int rc = gs_cfg_string_opt(node, key, def, &name, err);
  if (rc) return rc;
  *out = name ? gs_swa_coord_by_name(m, name) : -1;
  if (*out < 0) {
    char known[512];
    coord_list(m, known, sizeof known);
    gs_cfg_node *n = gs_cfg_get(node, key);
    if (n) return gs_cfg_fail(n, err, "expected a particle coordinate: one of %s", known);
    char hint[640];
    snprintf(hint, sizeof hint, "(the default coordinate '%s' does not exist; coordinates: %s)", def ? def : "", known);
    return gs_cfg_missing(node, key, hint, err);
  }
  return GS_OK;
}

int gs_swa_coord_mask(gs_cfg_node *node, const char *key, const gs_swa_model *m, unsigned def,
                      unsigned *out, gs_error *err) {
  gs_cfg_node *list = gs_cfg_get(node, key);
  *out = def;
  if (!list) return GS_OK;
  if (gs_cfg_require_kind(list, GS_CFG_SEQ, err)) return GS_EINPUT;
  if (gs_cfg_size(list) == 0) return gs_cfg_fail(list, err, "expected at least one coordinate name");
  *out = 0;
  for (size_t i = 0; i < gs_cfg_size(list); i++) {
    const char *nm = gs_cfg_scalar(gs_cfg_item(list, i));
    int k = nm ? gs_swa_coord_by_name(m, nm) : -1;
    if (k < 0) {
      char known[512];
      coord_list(m, known, sizeof known);
      return gs_cfg_fail(gs_cfg_item(list, i), err, "expected a particle coordinate: one of %s", known);
    }
    *out |= 1u << k;
  }
  return GS_OK;
}

int gs_swa_per_comp(gs_cfg_node *node, const char *key, int required, double def, double lo,
                    int lo_strict, const gs_swa_model *m, double *out, gs_error *err) {
  return gs_cfg_per_comp(node, key, required, def, lo, lo_strict, m->ncomp, out, err);
}
