/* The sectional model: grid + registered mechanisms; full right-hand side. */
#include <omp.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "gransim/distribution.h"
#include "gransim/pbm.h"
#include "gransim/threads.h"
#include "pbm/sums.h"

extern const gs_mech_type gs_mech_aggregation, gs_mech_breakage, gs_mech_growth,
    gs_mech_liquid_addition, gs_mech_consolidation, gs_mech_feed, gs_mech_transfer, gs_mech_spray,
    gs_mech_pore_consolidation, gs_mech_layering, gs_mech_nucleation, gs_mech_drying,
    gs_mech_fluid_bed, gs_mech_exchange, gs_mech_impeller_schedule;

/* Adding a mechanism is one file and one line here. */
static const gs_mech_type *const registry[] = {
    &gs_mech_aggregation, &gs_mech_breakage, &gs_mech_growth, &gs_mech_liquid_addition,
    &gs_mech_consolidation, &gs_mech_feed, &gs_mech_transfer, &gs_mech_spray,
    &gs_mech_pore_consolidation, &gs_mech_layering, &gs_mech_nucleation, &gs_mech_drying,
    &gs_mech_fluid_bed, &gs_mech_exchange, &gs_mech_impeller_schedule, NULL};

const gs_mech_type *const *gs_mech_types(void) { return registry; }

const gs_mech_type *gs_mech_lookup(const char *name) {
  return gs_registry_find((const void *const *)registry, name);
}

int gs_model_init(gs_model *m, gs_grid *grid, gs_error *err) {
  memset(m, 0, sizeof *m);
  m->nslots = omp_get_max_threads();
  m->grid = *grid;
  memset(grid, 0, sizeof *grid);
  m->nnum = m->nstate = m->scalar_at = m->grid.ncomp * m->grid.ncells;
  m->nvol = m->grid.dim;
  m->nledger = m->grid.ncomp * 2 * (size_t)m->nvol;
  m->size_axes = (1 << m->grid.dim) - 1;
  strcpy(m->dir, ".");
  m->size_volume = gs_malloc(m->grid.ncells * sizeof(double), err);
  if (!m->size_volume) return GS_ENOMEM;
  memcpy(m->size_volume, m->grid.volume, m->grid.ncells * sizeof(double));
  m->disc = gs_calloc(1, sizeof *m->disc, err);
  if (!m->disc) return GS_ENOMEM;
  m->disc->tolerance = GS_DISC_TOLERANCE;
  return GS_OK;
}

int gs_model_set_carried(gs_model *m, const char *const *names, int n, gs_error *err) {
  if (m->nmech)
    return gs_error_set(err, GS_EINPUT, "carried quantities must be declared before mechanisms");
  if (n < 0 || n > GS_MAX_CARRIED)
    return gs_error_set(err, GS_EINPUT, "at most %d carried quantities", GS_MAX_CARRIED);
  for (int q = 0; q < n; q++) {
    if (gs_grid_axis_by_name(&m->grid, names[q]) >= 0 || gs_model_carried_index(m, names[q]) >= 0)
      return gs_error_set(err, GS_EINPUT, "carried quantity '%s' repeats a name", names[q]);
    snprintf(m->carried[q], sizeof m->carried[q], "%s", names[q]);
    m->ncarried = q + 1;
  }
  m->nvol = m->grid.dim + m->ncarried;
  m->nstate = m->scalar_at = m->nnum * (1 + (size_t)m->ncarried);
  m->nledger = m->grid.ncomp * 2 * (size_t)m->nvol;
  return GS_OK;
}

int gs_model_carried_index(const gs_model *m, const char *name) {
  for (int q = 0; q < m->ncarried; q++)
    if (!strcmp(m->carried[q], name)) return q;
  return -1;
}

const char *gs_model_vol_name(const gs_model *m, int k) {
  return k < m->grid.dim ? m->grid.axis[k].name : m->carried[k - m->grid.dim];
}

double gs_model_held(const gs_model *m, const double *y, size_t comp, int k) {
  const gs_grid *g = &m->grid;
  if (k < g->dim)
    return gs_dot_strided(gs_model_numbers_c(m, y, comp), g->x + k, (size_t)g->dim, g->ncells);
  return gs_sum(gs_model_carried_c(m, y, comp, k - g->dim), g->ncells);
}

int gs_model_add_mechanism(gs_model *m, const char *type, gs_cfg_node *node, const char *label,
                           gs_error *err) {
  const gs_mech_type *t = gs_mech_lookup(type);
  if (!t) {
    char known[512];
    gs_registry_names((const void *const *)registry, known, sizeof known);
    return gs_error_set(err, GS_EINPUT, "unknown mechanism type '%s'; expected one of: %s", type,
                        known);
  }
  gs_mechanism *grown = realloc(m->mech, (m->nmech + 1) * sizeof *grown);
  if (!grown) return gs_error_set(err, GS_ENOMEM, "out of memory");
  m->mech = grown;
  gs_mechanism *mech = &m->mech[m->nmech];
  memset(mech, 0, sizeof *mech);
  mech->type = t;
  snprintf(mech->label, sizeof mech->label, "%s", label ? label : type);
  mech->scalar_first = m->nscalar;
  int rc = t->create(node, m, &mech->self, err);
  if (rc) return rc;
  m->nmech++;
  if (t->nscalars) { /* its scalars join the state, after the carried totals */
    mech->nscalar = t->nscalars(mech->self);
    m->nscalar += (size_t)mech->nscalar;
    m->nstate = m->scalar_at + m->grid.ncomp * m->nscalar;
  }
  return GS_OK;
}

int gs_model_ncolumns(const gs_model *m) {
  int n = 0;
  for (size_t i = 0; i < m->nmech; i++)
    for (const gs_mech_column *c = m->mech[i].type->columns; c && c->name; c++) n++;
  return n;
}

const gs_mech_column *gs_model_column(const gs_model *m, int k) {
  for (size_t i = 0; i < m->nmech; i++)
    for (const gs_mech_column *c = m->mech[i].type->columns; c && c->name; c++)
      if (k-- == 0) return c;
  return NULL;
}

void gs_model_report(const gs_model *m, size_t comp, double t, const double *y, double *values) {
  for (size_t i = 0; i < m->nmech; i++) {
    const gs_mech_type *ty = m->mech[i].type;
    if (!ty->columns) continue;
    ty->report(m->mech[i].self, m, comp, t, y, values);
    for (const gs_mech_column *c = ty->columns; c->name; c++) values++;
  }
}

int gs_model_notes(const gs_model *m, char *msg, size_t n) {
  int count = 0;
  size_t used = 0;
  if (n) msg[0] = '\0';
  for (size_t i = 0; i < m->nmech; i++) {
    char note[512];
    const gs_mechanism *mech = &m->mech[i];
    if (!mech->type->describe || !mech->type->describe(mech->self, note, sizeof note)) continue;
    int w = snprintf(msg + used, used < n ? n - used : 0, "%s%s: %s", count ? "\n" : "", mech->label, note);
    if (w > 0) used = used + (size_t)w < n ? used + (size_t)w : n;
    count++;
  }
  return count;
}

void gs_model_initial_scalars(const gs_model *m, double *y, double *accuracy) {
  for (size_t i = 0; i < m->nmech; i++) {
    const gs_mechanism *mech = &m->mech[i];
    if (!mech->nscalar) continue;
    for (size_t comp = 0; comp < m->grid.ncomp; comp++) {
      const size_t at = comp * m->nscalar + mech->scalar_first;
      mech->type->initial(mech->self, m, comp, y, y + m->scalar_at + at, accuracy + at);
    }
  }
}

double gs_model_balance(const gs_model *m, const double *y, char *msg, size_t n) {
  double worst = 0;
  char one[256];
  for (size_t i = 0; i < m->nmech; i++) {
    if (!m->mech[i].type->balance) continue;
    for (size_t comp = 0; comp < m->grid.ncomp; comp++) {
      const double e = m->mech[i].type->balance(m->mech[i].self, m, comp, y, one, sizeof one);
      if (!(e <= worst) && !isnan(worst)) { /* NaN is the worst, and stays */
        worst = e;
        snprintf(msg, n, "%s, compartment %zu: %s", m->mech[i].label, comp + 1, one);
      }
    }
  }
  return worst;
}

void gs_model_free(gs_model *m) {
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->free) m->mech[i].type->free(m->mech[i].self);
  free(m->mech);
  free(m->size_volume);
  if (m->disc) gs_disc_log_free(m->disc);
  free(m->disc);
  gs_grid_free(&m->grid);
  memset(m, 0, sizeof *m);
}

double gs_window_next_switch(double start, double end, double t) {
  if (t < start) return start;
  if (t < end) return end;
  return INFINITY;
}

int gs_window_on(const gs_eval *ev, double start, double end, double t) {
  /* every evaluation of an advance belongs to its interval, also one whose
   * time rounded past it (GSL's last stage at t0 + (t1 - t0) can be t1 plus
   * an ulp) */
  if (ev->switch_lo <= ev->switch_hi) t = 0.5 * (ev->switch_lo + ev->switch_hi);
  return t >= start && t < end;
}

double gs_model_next_switch(const gs_model *m, double t) {
  double next = INFINITY;
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->next_switch)
      next = fmin(next, m->mech[i].type->next_switch(m->mech[i].self, t));
  return next;
}

double gs_model_transfer_rate(const gs_model *m, size_t comp) {
  double k = 0;
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->outflow_rate) k += m->mech[i].type->outflow_rate(m->mech[i].self, comp);
  return k;
}

int gs_model_couples_all(const gs_model *m) {
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->couples_all) return 1;
  return 0;
}

void gs_model_conserve(const gs_model *m, double *v) {
  for (size_t comp = 0; comp < m->grid.ncomp; comp++) {
    double *led = v + m->nstate + comp * 2 * (size_t)m->nvol;
    for (int k = 0; k < m->nvol; k++) led[k] = gs_model_held(m, v, comp, k) + led[m->nvol + k];
  }
}

int gs_model_has_preconditioner(const gs_model *m) {
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->precondition) return 1;
  return 0;
}

void gs_eval_init(gs_eval *ev, const gs_model *m) {
  *ev = (gs_eval){.comp_lo = 0,
                  .comp_hi = m->grid.ncomp,
                  .view_lo = 0,
                  .view_carried = m->nnum,
                  .view_scalars = m->scalar_at,
                  .switch_lo = 1, /* no interval: windows decide at t */
                  .switch_hi = 0,
                  .slot = -1};
}

/* ev, or the whole model's context in *own when ev is NULL. */
static const gs_eval *context(const gs_model *m, const gs_eval *ev, gs_eval *own) {
  if (ev) return ev;
  gs_eval_init(own, m);
  return own;
}

void gs_model_precondition(const gs_model *m, const gs_eval *ev, double t, const double *y,
                           double gamma, const double *r, double *z) {
  gs_eval own;
  ev = context(m, ev, &own);
  memcpy(z, r, (m->nstate + m->nledger) * sizeof(double));
  for (size_t i = 0; i < m->nmech; i++)
    if (m->mech[i].type->precondition)
      for (size_t comp = ev->comp_lo; comp < ev->comp_hi; comp++)
        m->mech[i].type->precondition(m->mech[i].self, m, ev, comp, t, y, gamma, z,
                                      gs_eval_ledger(m, ev, z + m->nstate, comp));
}

double gs_model_seconds(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Every mechanism's rates of one compartment, in the order of the case
 * file (so a compartment's sums are the same whoever evaluates it), timed
 * when the context asks. */
static void compartment_rhs(const gs_model *m, const gs_eval *ev, size_t comp, double t,
                            const double *y, double *dydt, double *dledger) {
  const double start = ev->comp_seconds ? gs_model_seconds() : 0;
  for (size_t i = 0; i < m->nmech; i++)
    m->mech[i].type->rates(m->mech[i].self, m, ev, comp, t, y, dydt, dledger);
  if (ev->comp_seconds) ev->comp_seconds[comp] += gs_model_seconds() - start;
}

/* Threads take whole compartments when the case has several and enough
 * cells; with fewer, the region and the uneven compartments cost more than
 * they save, and a mechanism may split a single compartment over the team
 * instead (slot -1).  The choice depends on the whole case, not on an MPI
 * rank's block, so that moving compartments between ranks never switches a
 * compartment between the two (its sums would be added in another order). */
static int threads_over_compartments(const gs_model *m, const gs_eval *ev) {
  return ev->slot < 0 && m->grid.ncomp > 1 && m->nslots > 1 &&
         gs_threads_for(m->grid.ncells * m->grid.ncomp, 4096) > 1;
}

void gs_model_rhs(const gs_model *m, const gs_eval *ev, double t, const double *y, double *dydt,
                  double *dledger) {
  gs_eval own;
  ev = context(m, ev, &own);
  const size_t lo = ev->comp_lo, nc = ev->comp_hi - ev->comp_lo, n = m->grid.ncells;
  const size_t nq = (size_t)m->ncarried * n, nl = 2 * (size_t)m->nvol;
  if (nc == m->grid.ncomp && ev->view_lo == 0) {
    memset(dydt, 0, m->nstate * sizeof(double));
    memset(dledger, 0, m->nledger * sizeof(double));
  } else { /* a part: only its compartments are written and read back */
    memset(gs_eval_numbers(m, ev, dydt, lo), 0, nc * n * sizeof(double));
    if (nq) memset(gs_eval_carried(m, ev, dydt, lo, 0), 0, nc * nq * sizeof(double));
    memset(gs_eval_ledger(m, ev, dledger, lo), 0, nc * nl * sizeof(double));
    if (m->nscalar) memset(gs_eval_scalars(m, ev, dydt, lo), 0, nc * m->nscalar * sizeof(double));
  }
  if (threads_over_compartments(m, ev)) {
#pragma omp parallel for schedule(dynamic, 1) num_threads(m->nslots)
    for (size_t comp = ev->comp_lo; comp < ev->comp_hi; comp++) {
      gs_eval mine = *ev;
      mine.slot = omp_get_thread_num();
      compartment_rhs(m, &mine, comp, t, y, dydt, dledger);
    }
  } else {
    for (size_t comp = ev->comp_lo; comp < ev->comp_hi; comp++)
      compartment_rhs(m, ev, comp, t, y, dydt, dledger);
  }
}

void gs_mech_rhs(const gs_model *m, const gs_mechanism *mech, const gs_eval *ev, double t,
                 const double *y, double *dydt, double *dledger) {
  gs_eval own;
  ev = context(m, ev, &own);
  for (size_t comp = ev->comp_lo; comp < ev->comp_hi; comp++)
    mech->type->rates(mech->self, m, ev, comp, t, y, dydt, dledger);
}

int gs_mech_number_rates(const gs_model *m, const gs_mechanism *mech, const gs_eval *ev, double t,
                         const double *y, double *birth, double *death) {
  gs_eval own;
  ev = context(m, ev, &own);
  for (size_t comp = ev->comp_lo; comp < ev->comp_hi; comp++) {
    birth[comp] = death[comp] = 0;
    if (mech->type->number_rates)
      mech->type->number_rates(mech->self, m, ev, comp, t, y, &birth[comp], &death[comp]);
  }
  return mech->type->number_rates != NULL;
}
