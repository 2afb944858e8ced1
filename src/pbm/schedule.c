/* Schedules of a rate; see schedule.h. */
#include <math.h>
#include <stdlib.h>

#include "pbm/schedule.h"

int gs_schedule_read(gs_cfg_node *list, const gs_phase_key *keys, int nkeys, gs_schedule *s,
                     gs_error *err) {
  s->phase = NULL;
  s->n = 0;
  int rc = gs_cfg_require_kind(list, GS_CFG_SEQ, err);
  const size_t n = rc ? 0 : gs_cfg_size(list);
  if (!rc && !n) rc = gs_cfg_fail(list, err, "expected at least one phase {start, end, %s...}", keys[0].key);
  if (!rc && !(s->phase = gs_calloc(n, sizeof *s->phase, err))) rc = GS_ENOMEM;
  for (size_t i = 0; !rc && i < n; i++) {
    gs_cfg_node *p = gs_cfg_item(list, i);
    gs_phase *ph = &s->phase[i];
    rc = gs_cfg_require_kind(p, GS_CFG_MAP, err);
    if (!rc) rc = gs_cfg_double_range(p, "start", 1, 0, 0, 0, 1e9, 0, &ph->start, err);
    if (!rc) rc = gs_cfg_double_range(p, "end", 1, 0, ph->start, 1, 1e9, 0, &ph->end, err);
    for (int k = 0; !rc && k < nkeys; k++)
      rc = gs_cfg_double_range(p, keys[k].key, keys[k].required, keys[k].def, keys[k].lo, 0, keys[k].hi, 0,
                               &ph->value[k], err);
    if (!rc) rc = gs_cfg_check_unused(p, err);
    if (!rc && i > 0 && ph->start < s->phase[i - 1].end)
      rc = gs_cfg_fail(gs_cfg_get(p, "start"), err,
                       "phase %zu begins at %g s, before phase %zu ends (%g s): phases are given in "
                       "time order and may not overlap", i + 1, ph->start, i, s->phase[i - 1].end);
    s->n = i + 1;
  }
  if (rc) gs_schedule_free(s);
  return rc;
}

void gs_schedule_free(gs_schedule *s) {
  free(s->phase);
  s->phase = NULL;
  s->n = 0;
}

const gs_phase *gs_schedule_at(const gs_schedule *s, const gs_eval *ev, double t) {
  for (size_t i = 0; i < s->n; i++)
    if (ev ? gs_window_on(ev, s->phase[i].start, s->phase[i].end, t)
           : t >= s->phase[i].start && t < s->phase[i].end)
      return &s->phase[i];
  for (size_t i = 0; !ev && i < s->n; i++) /* at its end: the phase that led there */
    if (s->phase[i].end == t) return &s->phase[i];
  return NULL;
}

double gs_schedule_value(const gs_schedule *s, const gs_eval *ev, double t) {
  const gs_phase *p = gs_schedule_at(s, ev, t);
  return p ? p->value[0] : 0;
}

double gs_schedule_next_switch(const gs_schedule *s, double t) {
  double next = INFINITY;
  for (size_t i = 0; i < s->n; i++)
    next = fmin(next, gs_window_next_switch(s->phase[i].start, s->phase[i].end, t));
  return next;
}

double gs_schedule_integral(const gs_schedule *s) {
  double sum = 0;
  for (size_t i = 0; i < s->n; i++) sum += s->phase[i].value[0] * (s->phase[i].end - s->phase[i].start);
  return sum;
}

int gs_spray_schedule(gs_cfg_node *node, const gs_grid *g, double **q, size_t *nq, gs_schedule *s,
                      gs_error *err) {
  /* rate -1: not given (a rate is >= 0) */
  static const gs_phase_key keys[] = {{"rate", 0, -1, 0, HUGE_VAL}, {"weight", 0, 1, 0, 1e6}};
  gs_cfg_node *list = gs_cfg_get(node, "schedule");
  if (gs_cfg_get(node, "rate") || gs_cfg_get(node, "start") || gs_cfg_get(node, "end"))
    return gs_cfg_fail(list, err, "give either 'rate' (with 'start', 'end') or 'schedule', not both");
  double ratio = 0, solid = 0, rho = 0;
  const int by_ratio = gs_cfg_get(node, "liquid_solid_ratio") != NULL;
  int rc = gs_schedule_read(list, keys, 2, s, err);
  if (!rc && by_ratio) {
    rc = gs_cfg_double_range(node, "liquid_solid_ratio", 1, 0, 0, 1, 10, 0, &ratio, err);
    if (!rc) rc = gs_cfg_double_range(node, "solid_mass", 1, 0, 0, 1, 1e6, 0, &solid, err);
    if (!rc) rc = gs_cfg_double_range(node, "liquid_density", 0, 1000, 0, 1, 1e5, 0, &rho, err);
  }
  double weighted = 0;
  for (size_t i = 0; !rc && i < s->n; i++) {
    gs_cfg_node *p = gs_cfg_item(list, i);
    gs_phase *ph = &s->phase[i];
    if (by_ratio && gs_cfg_get(p, "rate"))
      rc = gs_cfg_fail(gs_cfg_get(p, "rate"), err, "with liquid_solid_ratio the rates follow from it: give "
                       "phases a 'weight' (relative rate) instead");
    else if (!by_ratio && !gs_cfg_get(p, "rate"))
      rc = gs_cfg_missing(p, "rate", "(liquid volume per second; or give liquid_solid_ratio and solid_mass)", err);
    else if (!by_ratio && gs_cfg_get(p, "weight"))
      rc = gs_cfg_fail(gs_cfg_get(p, "weight"), err, "'weight' goes with liquid_solid_ratio; give a 'rate' alone");
    weighted += ph->value[1] * (ph->end - ph->start);
  }
  if (!rc && by_ratio && !(weighted > 0))
    rc = gs_cfg_fail(list, err, "the phases' weights are all 0: nothing would be sprayed");
  /* liquid_solid_ratio: the liquid volume ratio m_s / rho_l, shared by weight x duration */
  for (size_t i = 0; !rc && by_ratio && i < s->n; i++)
    s->phase[i].value[0] = ratio * solid / rho * s->phase[i].value[1] / weighted;
  /* every compartment sprays the schedule's rate */
  if (!rc && !(*q = gs_malloc(g->ncomp * sizeof **q, err))) rc = GS_ENOMEM;
  for (size_t i = 0; !rc && i < g->ncomp; i++) (*q)[i] = 1;
  *nq = rc ? 0 : g->ncomp;
  if (rc) gs_schedule_free(s);
  return rc;
}
