/* The impeller speed as a schedule (Chaudhury 2015: the impeller speed of a
 * batch recipe) that shear-dependent mechanisms follow:
 *   - type: impeller_schedule
 *     phases: [{start, end, speed}]      rpm per phase; the impeller stands between phases
 *     reference_speed: N_ref             rpm at which the inner shear_rate is given
 *     mechanism: {type: aggregation | breakage, ...}
 * One inner mechanism is built per phase from the same map, with the
 * semi_mechanistic kernel's `impeller_speed` set to the phase's speed and a
 * shear selection's `shear_rate` G scaled to G N / N_ref (the shear rate of a
 * high-shear mixer follows the impeller speed).  The rates of the phase on
 * at t are those of its mechanism; between phases there are none (no
 * impeller, no shear-driven events).  The kernels stay tabulated per phase,
 * so a schedule costs its phases' tables, not a kernel evaluation per step. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/pbm.h"
#include "pbm/schedule.h"

typedef struct {
  const gs_mech_type *inner;
  gs_schedule s;
  void **self; /* one inner mechanism per phase */
} impeller_t;

static void impeller_free(void *p) {
  impeller_t *I = p;
  if (!I) return;
  for (size_t i = 0; I->self && i < I->s.n; i++)
    if (I->self[i]) I->inner->free(I->self[i]);
  free(I->self);
  gs_schedule_free(&I->s);
  free(I);
}

/* The inner mechanism's maps that hold a speed-dependent key: `impeller_speed`
 * (set to N) or `shear_rate` (scaled by N / N_ref, its value at N_ref in *g). */
typedef struct {
  gs_cfg_node *speed_map, *shear_map;
  double g;
} speed_keys;

static int find_keys(gs_cfg_node *mech, speed_keys *k, gs_error *err) {
  memset(k, 0, sizeof *k);
  for (size_t i = 0; i < gs_cfg_size(mech); i++) {
    const char *key = gs_cfg_key_at(mech, i);
    gs_cfg_node *sub = gs_cfg_get(mech, key);
    if (gs_cfg_kind_of(sub) != GS_CFG_MAP) continue;
    if (gs_cfg_get(sub, "velocity") && gs_cfg_get(sub, "beta0"))
      return gs_cfg_fail(gs_cfg_get(sub, "velocity"), err,
                         "under an impeller_schedule give 'impeller_speed' (any value: each phase sets it) "
                         "with 'impeller_diameter' instead of 'velocity'");
    if (gs_cfg_get(sub, "impeller_speed")) k->speed_map = sub;
    if (gs_cfg_get(sub, "shear_rate")) {
      k->shear_map = sub;
      if (gs_cfg_double_range(sub, "shear_rate", 1, 0, 0, 1, HUGE_VAL, 0, &k->g, err)) return GS_EINPUT;
    }
  }
  return GS_OK;
}

static int set_number(gs_cfg_node *map, const char *key, double v, gs_error *err) {
  char text[64];
  snprintf(text, sizeof text, "%.17g", v);
  return gs_cfg_set_scalar(map, key, text, err);
}

static int impeller_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  impeller_t *I = gs_calloc(1, sizeof *I, err);
  if (!I) return GS_ENOMEM;
  static const gs_phase_key keys[] = {{"speed", 1, 0, 0, 1e6}};
  gs_cfg_node *phases = NULL, *mech = NULL;
  const char *type = NULL;
  double nref = 0;
  speed_keys k;
  int rc = gs_cfg_seq_req(node, "phases", &phases, err);
  if (!rc) rc = gs_schedule_read(phases, keys, 1, &I->s, err);
  for (size_t i = 0; !rc && i < I->s.n; i++)
    if (!(I->s.phase[i].value[0] > 0))
      rc = gs_cfg_fail(gs_cfg_item(phases, i), err, "speed must be > 0 rpm (leave a gap for a standing impeller)");
  if (!rc) rc = gs_cfg_map_req(node, "mechanism", &mech, err);
  if (!rc) rc = gs_cfg_string_req(mech, "type", &type, err);
  if (!rc && !(I->inner = gs_mech_lookup(type)))
    rc = gs_cfg_fail(gs_cfg_get(mech, "type"), err, "unknown mechanism type '%s'", type);
  if (!rc && (I->inner->nscalars || I->inner->couples_all || !I->inner->rates))
    rc = gs_cfg_fail(gs_cfg_get(mech, "type"), err, "'%s' cannot follow an impeller schedule (aggregation or "
                                                    "breakage can)", type);
  if (!rc) rc = find_keys(mech, &k, err);
  if (!rc && !k.speed_map && !k.shear_map) { /* its own message first: a misspelt key, did you mean */
    void *probe = NULL;
    rc = I->inner->create(mech, m, &probe, err);
    if (!rc) {
      I->inner->free(probe);
      rc = gs_cfg_fail(mech, err, "the mechanism follows no impeller speed: expected kernel.impeller_speed "
                                  "(semi_mechanistic) or selection.shear_rate (shear)");
    }
  }
  if (!rc && k.shear_map) rc = gs_cfg_double_range(node, "reference_speed", 1, 0, 0, 1, HUGE_VAL, 0, &nref, err);
  else if (!rc && gs_cfg_get(node, "reference_speed"))
    rc = gs_cfg_fail(gs_cfg_get(node, "reference_speed"), err, "reference_speed scales a shear selection's "
                                                               "shear_rate, which this mechanism has not");
  if (!rc) rc = gs_cfg_check_unused(node, err);
  if (!rc && !(I->self = gs_calloc(I->s.n, sizeof(void *), err))) rc = GS_ENOMEM;
  for (size_t i = 0; !rc && i < I->s.n; i++) {
    const double n = I->s.phase[i].value[0];
    if (k.speed_map) rc = set_number(k.speed_map, "impeller_speed", n, err);
    if (!rc && k.shear_map) rc = set_number(k.shear_map, "shear_rate", k.g * n / nref, err);
    if (!rc) rc = I->inner->create(mech, m, &I->self[i], err);
  }
  if (rc) {
    impeller_free(I);
    return rc;
  }
  *self = I;
  return GS_OK;
}

/* The phase's inner mechanism at t, or NULL while the impeller stands. */
static void *on(const impeller_t *I, const gs_eval *ev, double t) {
  const gs_phase *p = gs_schedule_at(&I->s, ev, t);
  return p ? I->self[p - I->s.phase] : NULL;
}

static void impeller_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                           const double *y, double *dydt, double *dledger) {
  const impeller_t *I = self;
  void *in = on(I, ev, t);
  if (in) I->inner->rates(in, m, ev, comp, t, y, dydt, dledger);
}

static void impeller_number_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                                  const double *y, double *birth, double *death) {
  const impeller_t *I = self;
  void *in = on(I, ev, t);
  *birth = *death = 0;
  if (in && I->inner->number_rates) I->inner->number_rates(in, m, ev, comp, t, y, birth, death);
}

static void impeller_precondition(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                                  const double *y, double gamma, double *z, double *zledger) {
  const impeller_t *I = self;
  void *in = on(I, ev, t);
  if (in && I->inner->precondition) I->inner->precondition(in, m, ev, comp, t, y, gamma, z, zledger);
}

static double impeller_switch(void *self, double t) {
  const impeller_t *I = self;
  double next = gs_schedule_next_switch(&I->s, t);
  for (size_t i = 0; I->inner->next_switch && i < I->s.n; i++)
    next = fmin(next, I->inner->next_switch(I->self[i], t));
  return next;
}

const gs_mech_type gs_mech_impeller_schedule = {
    .name = "impeller_schedule",
    .summary = "an aggregation or breakage following a schedule of impeller speeds",
    .create = impeller_create,
    .rates = impeller_rates,
    .number_rates = impeller_number_rates,
    .free = impeller_free,
    .precondition = impeller_precondition,
    .next_switch = impeller_switch,
};
