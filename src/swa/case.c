/* SWA cases: the same case files as the sectional engine, selected with
 * `solver: {method: swa, ...}`.  The grid section gives the compartments and
 * the bins of the output distributions (each axis names a particle
 * coordinate); `initial`, `mechanisms` (SWA process types) and `output` have
 * the sectional meaning.  docs/case-files.md documents every key. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/case.h"
#include "gransim/distribution.h"
#include "gransim/kernel.h"
#include "swa/sim.h"
#include "swa/spec.h"

/* The private part of a case (gs_swa_case.initial): the initial entries,
 * and the solver settings that only the runs read. */
typedef struct initial_set {
  size_t n;
  gs_swa_spec *spec;
  size_t *comp;
  char (*key)[160]; /* "file:line: path" of each entry */
  uint64_t max_jumps; /* solver.max_jumps_per_output */
} initial_set;

uint64_t gs_swa_case_max_jumps(const gs_swa_case *c) {
  const initial_set *set = c->initial;
  return set && set->max_jumps ? set->max_jumps : (uint64_t)GS_SWA_MAX_JUMPS_DEFAULT;
}

size_t gs_swa_case_initial_count(const gs_swa_case *c) {
  const initial_set *set = c->initial;
  return set ? set->n : 0;
}

const gs_swa_spec *gs_swa_case_initial(const gs_swa_case *c, size_t i, const char **key) {
  const initial_set *set = c->initial;
  *key = set->key[i];
  return &set->spec[i];
}

/* Look a key up without noting it as asked for, so that the "expected one
 * of" lists of the sectional reader are unchanged by this peek. */
static gs_cfg_node *peek(gs_cfg_node *map, const char *key) {
  if (!map || gs_cfg_kind_of(map) != GS_CFG_MAP) return NULL;
  for (size_t i = 0; i < gs_cfg_size(map); i++)
    if (!strcmp(gs_cfg_key_at(map, i), key)) return gs_cfg_value_at(map, i);
  return NULL;
}

int gs_swa_case_wanted(gs_cfg *cfg) {
  gs_cfg_node *root = gs_cfg_root(cfg);
  gs_cfg_node *method = peek(peek(root, "solver"), "method");
  const char *s = method ? gs_cfg_scalar(method) : NULL;
  return s && !strcmp(s, "swa");
}

static int read_solver(gs_cfg_node *root, gs_swa_case *c, int size_axes, gs_error *err) {
  gs_swa_model *m = &c->model;
  const gs_grid *g = &c->grid;
  gs_cfg_node *n = gs_cfg_get(root, "solver");
  const char *method;
  long particles, runs, seed, max_jumps;
  int rc = gs_cfg_string_req(n, "method", &method, err);
  if (!rc) rc = gs_cfg_long_range(n, "particles", 0, 4096, 16, 1L << 26, &particles, err);
  if (!rc) rc = gs_cfg_long_range(n, "runs", 0, 10, 1, 100000, &runs, err);
  if (!rc) rc = gs_cfg_long_range(n, "seed", 0, 1, 0, 4294967295L, &seed, err);
  if (!rc) rc = gs_cfg_long_range(n, "max_jumps_per_output", 0, GS_SWA_MAX_JUMPS_DEFAULT, 1, LONG_MAX, &max_jumps, err);
  if (!rc) rc = gs_cfg_double_range(n, "fill_fraction", 0, 0.75, 0, 1, 1, 0, &m->fill_fraction, err);
  if (!rc) rc = gs_cfg_double_range(n, "doubling_fraction", 0, 0.375, 0, 0, 0.5, 0, &m->nmin_fraction, err);
  if (!rc) rc = gs_cfg_double_range(n, "reference_number", 0, 0, 0, 0, HUGE_VAL, 0, &m->reference_number, err);
  if (!rc) rc = gs_cfg_double_range(n, "lpda_interval", 0, 0, 0, 0, HUGE_VAL, 0, &m->lpda_interval, err);
  static const char *const contractions[] = {"merge", "drop", NULL};
  if (!rc) rc = gs_cfg_enum_opt(n, "contraction", contractions, GS_SWA_MERGE, &m->contraction, err);
  if (rc) return rc;
  m->nmax = (size_t)particles;
  ((initial_set *)c->initial)->max_jumps = (uint64_t)max_jumps;
  c->runs = (size_t)runs;
  c->seed = (uint64_t)seed;
  m->ncomp = g->ncomp;
  /* coordinates: the grid axes unless listed */
  gs_cfg_node *list = gs_cfg_get(n, "coordinates");
  if (list) {
    if ((rc = gs_cfg_require_kind(list, GS_CFG_SEQ, err))) return rc;
    if (gs_cfg_size(list) < 1 || gs_cfg_size(list) > GS_SWA_MAX_COORD)
      return gs_cfg_fail(list, err, "expected 1 to %d coordinate names", GS_SWA_MAX_COORD);
    for (size_t k = 0; k < gs_cfg_size(list); k++) {
      const char *nm = gs_cfg_scalar(gs_cfg_item(list, k));
      if (!nm || !*nm || strlen(nm) >= GS_NAME_LEN || strpbrk(nm, " ,/\t"))
        return gs_cfg_fail(gs_cfg_item(list, k), err, "expected a name of 1-%d characters without spaces, commas or '/'", GS_NAME_LEN - 1);
      if (gs_swa_coord_by_name(m, nm) >= 0) return gs_cfg_fail(gs_cfg_item(list, k), err, "coordinate named twice");
      snprintf(m->coord[m->ncoord++], GS_NAME_LEN, "%s", nm);
    }
  } else {
    for (int a = 0; a < g->dim; a++) snprintf(m->coord[m->ncoord++], GS_NAME_LEN, "%s", g->axis[a].name);
  }
  c->bin_coord = gs_calloc((size_t)g->dim, sizeof(int), err);
  if (!c->bin_coord) return GS_ENOMEM;
  for (int a = 0; a < g->dim; a++) {
    c->bin_coord[a] = gs_swa_coord_by_name(m, g->axis[a].name);
    if (c->bin_coord[a] < 0)
      return gs_cfg_fail(list, err, "grid axis '%s' is not a particle coordinate (with the swa solver each grid axis bins one coordinate)",
                         g->axis[a].name);
  }
  /* granule volume: the coordinates of the grid's size_axes, unless listed */
  unsigned def = 0;
  for (int a = 0; a < g->dim; a++)
    if (size_axes & (1 << a)) def |= 1u << c->bin_coord[a];
  if ((rc = gs_swa_coord_mask(n, "size_coordinates", m, def, &m->size_mask, err))) return rc;
  for (int k = 0; k < m->ncoord; k++) m->density[k] = 1;
  if (gs_cfg_get(n, "densities")) {
    double *d = NULL;
    size_t cnt = 0;
    rc = gs_cfg_doubles_req(n, "densities", 1, &d, &cnt, err);
    if (!rc && cnt != 1 && cnt != (size_t)m->ncoord)
      rc = gs_cfg_fail(gs_cfg_get(n, "densities"), err, "expected one density or one per coordinate (%d), got %zu", m->ncoord, cnt);
    double tot = 0;
    for (int k = 0; !rc && k < m->ncoord; k++) {
      m->density[k] = d[cnt == 1 ? 0 : (size_t)k];
      tot += m->density[k];
      if (!(m->density[k] >= 0)) rc = gs_cfg_fail(gs_cfg_get(n, "densities"), err, "expected densities >= 0");
    }
    if (!rc && !(tot > 0)) rc = gs_cfg_fail(gs_cfg_get(n, "densities"), err, "expected at least one density > 0");
    free(d);
    if (rc) return rc;
  }
  if (gs_cfg_get(n, "sieves")) {
    size_t ne = 0;
    if ((rc = gs_cfg_doubles_req(n, "sieves", 0, &c->sieves, &ne, err))) return rc;
    if (ne < 2) return gs_cfg_fail(gs_cfg_get(n, "sieves"), err, "expected at least 2 sieve diameters");
    for (size_t k = 0; k < ne; k++)
      if (!(c->sieves[k] > 0) || (k && !(c->sieves[k] > c->sieves[k - 1])))
        return gs_cfg_fail(gs_cfg_get(n, "sieves"), err, "expected increasing diameters > 0 (entry %zu is %g)", k, c->sieves[k]);
    c->nsieve = ne - 1;
  }
  m->nprop = 1; /* column 0: the weight */
  return gs_cfg_check_unused(n, err);
}

static int read_initial(gs_cfg_node *root, gs_swa_case *c, gs_error *err) {
  initial_set *set = c->initial;
  gs_cfg_node *init = gs_cfg_get(root, "initial");
  if (!init) return GS_OK;
  int seq = gs_cfg_kind_of(init) == GS_CFG_SEQ;
  size_t n = seq ? gs_cfg_size(init) : 1;
  set->spec = gs_calloc(n, sizeof *set->spec, err);
  set->comp = gs_calloc(n, sizeof *set->comp, err);
  set->key = gs_calloc(n, sizeof *set->key, err);
  if (!set->spec || !set->comp || !set->key) return GS_ENOMEM;
  for (size_t i = 0; i < n; i++) {
    gs_cfg_node *e = seq ? gs_cfg_item(init, i) : init;
    long comp = 1;
    int rc = gs_cfg_require_kind(e, GS_CFG_MAP, err);
    if (!rc) rc = gs_cfg_long_range(e, "compartment", 0, 1, 1, (long)c->model.ncomp, &comp, err);
    if (!rc) rc = gs_swa_spec_read(e, &c->model, &c->grid, c->bin_coord, "number", &set->spec[i], err);
    set->n = i + 1;
    set->comp[i] = (size_t)(comp - 1);
    snprintf(set->key[i], sizeof set->key[i], "%s:%d: %s", gs_cfg_file(e), gs_cfg_line(e), gs_cfg_path(e));
    if (rc) return rc;
  }
  return GS_OK;
}

static int read_mechanisms(gs_cfg_node *root, gs_swa_case *c, gs_error *err) {
  gs_swa_model *m = &c->model;
  gs_cfg_node *list = gs_cfg_get(root, "mechanisms");
  if (!list) return GS_OK;
  int rc = gs_cfg_require_kind(list, GS_CFG_SEQ, err);
  if (rc) return rc;
  m->proc = gs_calloc(gs_cfg_size(list) + 1, sizeof *m->proc, err);
  if (!m->proc) return GS_ENOMEM;
  for (size_t i = 0; !rc && i < gs_cfg_size(list); i++) {
    gs_cfg_node *node = gs_cfg_item(list, i);
    const gs_swa_process_type *t = gs_registry_pick(
        node, (const void *const *)gs_swa_process_types(), "mechanism (swa solver)", err);
    if (!t) return GS_EINPUT;
    gs_swa_process *p = &m->proc[m->nproc++];
    p->type = t;
    snprintf(p->label, sizeof p->label, "mechanisms[%zu] (%s)", i, t->name);
    rc = t->create(node, m, &p->self, err);
  }
  return rc;
}

int gs_swa_case_from_cfg(gs_cfg *cfg, gs_swa_case *c, gs_error *err) {
  memset(c, 0, sizeof *c);
  c->cfg = cfg;
  gs_cfg_node *root = gs_cfg_root(cfg);
  if (!root) return gs_error_set(err, GS_EINPUT, "%s: the case file is empty", gs_cfg_name(cfg));
  const char *title = NULL, *desc;
  int rc = gs_cfg_require_kind(root, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_string_opt(root, "title", "", &title, err);
  if (!rc) snprintf(c->title, sizeof c->title, "%s", title);
  if (!rc) rc = gs_cfg_string_opt(root, "description", "", &desc, err);
  /* the grid alone: the SWA solver has no sectional state (grid.carried is
   * not read, so it is reported as an unknown key) */
  gs_cfg_node *grid = NULL;
  int size_axes = 0;
  if (!rc) rc = gs_case_read_grid_only(root, &c->grid, &size_axes, &grid, err);
  if (!rc) rc = gs_cfg_check_unused(grid, err);
  if (!rc && !(c->initial = gs_calloc(1, sizeof(initial_set), err))) rc = GS_ENOMEM;
  if (!rc) rc = read_solver(root, c, size_axes, err);
  if (!rc) {
    c->model.grid = &c->grid;
    c->model.bin_coord = c->bin_coord;
    c->model.dir = gs_cfg_dir(cfg);
  }
  if (!rc) rc = read_initial(root, c, err);
  if (!rc) rc = read_mechanisms(root, c, err);
  if (!rc) rc = gs_case_read_times(root, &c->t0, &c->times, &c->ntimes, err);
  if (!rc) rc = gs_case_read_disc_tolerance(root, &c->disc_tolerance, err);
  if (!rc) rc = gs_swa_check_limits(root, c, err);
  if (!rc) rc = gs_cfg_check_unused(root, err);
  if (!rc) {
    /* every compartment needs a sample volume: from its initial particles,
     * from reference_number, or from the first filled compartment */
    const initial_set *set = c->initial;
    if (set->n == 0 && !(c->model.reference_number > 0))
      rc = gs_error_set(err, GS_EINPUT,
                        "%s: every compartment starts empty: set solver.reference_number (the physical "
                        "number of particles that fill_fraction * particles computational particles stand for)",
                        gs_cfg_name(cfg));
  }
  if (!rc) rc = gs_swa_case_disc(c, err);
  return rc;
}

void gs_swa_case_free(gs_swa_case *c) {
  for (size_t p = 0; p < c->model.nproc; p++)
    if (c->model.proc[p].type->free) c->model.proc[p].type->free(c->model.proc[p].self);
  free(c->model.proc);
  initial_set *set = c->initial;
  if (set) {
    for (size_t i = 0; i < set->n; i++) gs_swa_spec_free(&set->spec[i]);
    free(set->spec);
    free(set->comp);
    free(set->key);
    free(set);
  }
  free(c->disc);
  free(c->bin_coord);
  free(c->sieves);
  free(c->times);
  gs_grid_free(&c->grid);
  gs_cfg_free(c->cfg);
  memset(c, 0, sizeof *c);
}

/* The fill of compartment z at the start: fill_fraction * nmax particles (at
 * least 1). */
static size_t initial_fill(const gs_swa_model *m) {
  size_t n0 = (size_t)llround(m->fill_fraction * (double)m->nmax);
  return n0 < 1 ? 1 : n0;
}

static double initial_number(const initial_set *set, size_t z) {
  double total = 0;
  for (size_t i = 0; i < set->n; i++)
    if (set->comp[i] == z) total += set->spec[i].number;
  return total;
}

double gs_swa_case_vsamp0(const gs_swa_case *c, size_t z) {
  const gs_swa_model *m = &c->model;
  const initial_set *set = c->initial;
  const double n0 = (double)initial_fill(m), total = initial_number(set, z);
  if (total > 0) return n0 / total;
  if (m->reference_number > 0) return n0 / m->reference_number;
  for (size_t y = 0; y < m->ncomp; y++) /* the first filled compartment's */
    if (initial_number(set, y) > 0) return n0 / initial_number(set, y);
  return 1;
}

int gs_swa_case_init_tally(const gs_swa_case *c, gs_swa_sim *s, gsl_rng *rng, double *tally,
                           size_t cap, gs_error *err) {
  const gs_swa_model *m = &c->model;
  const initial_set *set = c->initial;
  const size_t n0 = initial_fill(m), nc = (size_t)m->ncoord;
  if (s) {
    rng = s->rng;
    s->t = c->t0;
    s->next_checkpoint = m->lpda_interval > 0 ? c->t0 + m->lpda_interval : HUGE_VAL;
  }
  for (size_t z = 0; z < m->ncomp; z++) {
    const double total = initial_number(set, z), v = gs_swa_case_vsamp0(c, z);
    if (s) gs_swa_set_vsamp(s, z, v);
    if (!(total > 0)) continue;
    size_t placed = 0; /* the compartment starts empty, and never overflows */
    for (size_t i = 0; i < set->n; i++) {
      if (set->comp[i] != z) continue;
      size_t cnt = (size_t)llround((double)n0 * set->spec[i].number / total);
      if (cnt < 1) cnt = 1;
      if (cnt > m->nmax - placed) cnt = m->nmax - placed;
      double wbase = set->spec[i].number * v / (double)cnt, *t = tally ? tally + i * (nc + 2) : NULL;
      /* without a run, at most cap draws stand for the cnt particles */
      const size_t draws = !s && cap && cnt > cap ? cap : cnt;
      if (draws < cnt) {
        placed += cnt;
        wbase *= (double)cnt / (double)draws;
      }
      for (size_t k = 0; k < draws; k++) {
        double x[GS_SWA_MAX_COORD], w;
        gs_swa_spec_sample(&set->spec[i], rng, x, &w);
        if (t) t[nc + 1] += 1;
        if (!(w > 0)) continue; /* VWI: a diameter outside the feed distribution */
        if (draws == cnt) placed++;
        int rc = s ? gs_swa_sim_place(s, z, x, w * wbase, err) : GS_OK;
        if (rc) return rc;
        if (!t) continue;
        t[0] += w * wbase / v;
        for (size_t a = 0; a < nc; a++) t[1 + a] += w * wbase / v * x[a];
      }
    }
  }
  return GS_OK;
}

int gs_swa_case_init_run(const gs_swa_case *c, gs_swa_sim *s, gs_error *err) {
  return gs_swa_case_init_tally(c, s, NULL, NULL, 0, err);
}
