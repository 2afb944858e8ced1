/* Breakage selection functions S [1/s], a registry of named types:
 *   power: S = s0 * v^exponent, v the size measure (default granule volume);
 *   shear: S = sqrt(4/(15 pi)) G exp(-B / (G^2 R)), R the volume-equivalent
 *          radius (Chaudhury 2015, eq. 2.7, after Soos et al. 2006).
 * Both accept min_volume: particles whose size measure is below it do not
 * break (e.g. primary particles, whose fragments the grid cannot hold). */
#include <math.h>
#include <stdlib.h>

#include "gransim/kernel.h"
#include "kernel/size_measure.h"

typedef struct {
  double a, b;   /* power: s0, exponent; shear: G, B */
  double min_volume;
  double *size;  /* per cell size measure */
} sel_t;

static void sel_free(void *self) {
  sel_t *s = self;
  free(s->size);
  free(s);
}

static int sel_finish(gs_cfg_node *node, const gs_grid *g, sel_t *s, int rc, void **self,
                      gs_error *err) {
  if (!rc && !(s->size = gs_size_measure(node, g, err))) rc = err->code;
  if (!rc) rc = gs_cfg_double_range(node, "min_volume", 0, 0, 0, 0, HUGE_VAL, 0, &s->min_volume, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (rc) {
    sel_free(s);
    return rc;
  }
  *self = s;
  return GS_OK;
}

static int power_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                        gs_error *err) {
  (void)dir;
  sel_t *s = gs_calloc(1, sizeof *s, err);
  if (!s) return GS_ENOMEM;
  int rc = gs_cfg_double_range(node, "s0", 1, 0, 0, 0, HUGE_VAL, 0, &s->a, err);
  if (!rc) rc = gs_cfg_double_range(node, "exponent", 0, 1, -HUGE_VAL, 0, HUGE_VAL, 0, &s->b, err);
  return sel_finish(node, g, s, rc, self, err);
}

static double power_rate(const void *self, const gs_grid *g, size_t cell) {
  (void)g;
  const sel_t *s = self;
  if (s->size[cell] < s->min_volume) return 0.0;
  return s->a * pow(s->size[cell], s->b);
}

static int shear_create(gs_cfg_node *node, const gs_grid *g, const char *dir, void **self,
                        gs_error *err) {
  (void)dir;
  sel_t *s = gs_calloc(1, sizeof *s, err);
  if (!s) return GS_ENOMEM;
  int rc = gs_cfg_double_range(node, "shear_rate", 1, 0, 0, 1, HUGE_VAL, 0, &s->a, err);
  if (!rc) rc = gs_cfg_double_range(node, "b", 1, 0, 0, 0, HUGE_VAL, 0, &s->b, err);
  return sel_finish(node, g, s, rc, self, err);
}

static double shear_rate(const void *self, const gs_grid *g, size_t cell) {
  (void)g;
  const sel_t *s = self;
  if (s->size[cell] < s->min_volume) return 0.0;
  double R = 0.5 * gs_diameter(s->size[cell]);
  if (!(R > 0)) return 0.0;
  return sqrt(4.0 / (15.0 * M_PI)) * s->a * exp(-s->b / (s->a * s->a * R));
}

static const gs_selection_type power_type = {
    .name = "power",
    .summary = "S = s0 v^exponent",
    .create = power_create,
    .rate = power_rate,
    .free = sel_free,
};
static const gs_selection_type shear_type = {
    .name = "shear",
    .summary = "S = sqrt(4/(15 pi)) G exp(-B/(G^2 R)) (Chaudhury 2015, eq. 2.7)",
    .create = shear_create,
    .rate = shear_rate,
    .free = sel_free,
};
extern const gs_selection_type gs_selection_dem_impact;
static const gs_selection_type *const registry[] = {&power_type, &shear_type, &gs_selection_dem_impact,
                                                    NULL};

const gs_selection_type *const *gs_selection_types(void) { return registry; }

int gs_selection_create(gs_cfg_node *node, const gs_grid *g, const char *dir, gs_selection *s,
                        gs_error *err) {
  s->self = NULL;
  s->type = gs_registry_pick(node, (const void *const *)registry, "selection function", err);
  if (!s->type) return GS_EINPUT;
  return s->type->create(node, g, dir, &s->self, err);
}

void gs_selection_free(gs_selection *s) {
  if (s->type && s->self) s->type->free(s->self);
  s->type = NULL;
  s->self = NULL;
}
