/* Inception (McGuire et al. 2018, eqs. 29-37, 68-70): particles enter a compartment at
 * a physical rate R (per unit time; or mass_rate / (density * mean particle
 * volume) for a `diameters` distribution).  A computational particle with
 * weight w-bar * (relative weight of the sample) enters at rate R V / w-bar,
 * so every estimate receives R per unit time in expectation. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "swa/sim.h"
#include "swa/spec.h"

typedef struct feed {
  size_t comp;
  double rate; /* physical particles per unit time */
  double start, end;
  gs_swa_spec spec;
  char key[160]; /* "file:line: path" of the distribution */
} feed;

static void feed_free(void *self) {
  feed *f = self;
  if (!f) return;
  gs_swa_spec_free(&f->spec);
  free(f);
}

static int feed_create(gs_cfg_node *node, gs_swa_model *m, void **self, gs_error *err) {
  feed *f = gs_calloc(1, sizeof *f, err);
  if (!f) return GS_ENOMEM;
  *self = f;
  long comp = 1;
  gs_cfg_node *d = NULL;
  int rc = gs_cfg_long_range(node, "compartment", 0, 1, 1, (long)m->ncomp, &comp, err);
  f->comp = (size_t)(comp - 1);
  if (!rc) rc = gs_cfg_map_req(node, "distribution", &d, err);
  if (!rc) rc = gs_swa_spec_read(d, m, NULL, NULL, NULL, &f->spec, err);
  if (!rc) snprintf(f->key, sizeof f->key, "%s:%d: %s", gs_cfg_file(d), gs_cfg_line(d), gs_cfg_path(d));
  if (!rc && !!gs_cfg_get(node, "rate") == !!gs_cfg_get(node, "mass_rate"))
    rc = gs_cfg_fail(node, err, "a feed needs exactly one of 'rate' (particles per unit time) or 'mass_rate'");
  if (!rc && gs_cfg_get(node, "rate")) rc = gs_cfg_double_range(node, "rate", 1, 0, 0, 0, HUGE_VAL, 0, &f->rate, err);
  if (!rc && gs_cfg_get(node, "mass_rate")) {
    double mr;
    rc = gs_cfg_double_range(node, "mass_rate", 1, 0, 0, 0, HUGE_VAL, 0, &mr, err);
    if (!rc && f->spec.nsec == 0) rc = gs_cfg_fail(gs_cfg_get(node, "mass_rate"), err, "mass_rate needs a distribution of type diameters");
    if (!rc && !(m->density[f->spec.coord] > 0))
      rc = gs_cfg_fail(gs_cfg_get(node, "mass_rate"), err, "mass_rate needs a density > 0 for coordinate '%s'", m->coord[f->spec.coord]);
    if (!rc) f->rate = mr / (m->density[f->spec.coord] * f->spec.vmean); /* eq. 6 */
  }
  if (!rc) rc = gs_cfg_double_opt(node, "start", -HUGE_VAL, &f->start, err);
  if (!rc) rc = gs_cfg_double_range(node, "end", 0, HUGE_VAL, f->start, 1, HUGE_VAL, 0, &f->end, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  return rc;
}

static double feed_rate(const void *self, const gs_swa_sim *s, size_t z) {
  const feed *f = self;
  if (z != f->comp || s->t < f->start || s->t >= f->end) return 0;
  return f->rate * gs_swa_vsamp(s, z) / (f->spec.mean_weight * gs_swa_gain(s, z)); /* eq. 37 */
}

static int feed_jump(const void *self, gs_swa_sim *s, size_t z, gs_error *err) {
  const feed *f = self;
  double x[GS_SWA_MAX_COORD], w;
  gs_swa_spec_sample(&f->spec, s->rng, x, &w);
  if (!(w > 0)) {
    gs_swa_fictitious(s); /* VWI: a diameter where the feed has no particles */
    return GS_OK;
  }
  return gs_swa_add(s, z, x, w * f->spec.mean_weight * gs_swa_gain(s, z), err);
}

static const gs_swa_spec *feed_inflow(const void *self, const char **key, size_t *comp,
                                      double *rate, double window[2]) {
  const feed *f = self;
  *key = f->key;
  *comp = f->comp;
  *rate = f->rate;
  window[0] = f->start;
  window[1] = f->end;
  return &f->spec;
}

const gs_swa_process_type gs_swa_feed = {
    .name = "feed",
    .summary = "inception of particles into a compartment; equal (EWI) or variable (VWI) weights",
    .create = feed_create,
    .rate = feed_rate,
    .jump = feed_jump,
    .free = feed_free,
    .inflow = feed_inflow,
};
