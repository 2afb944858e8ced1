/* The outputs a study gathers from a run's final state, and the case of one
 * run (see gransim/study.h). */
#include "gransim/study.h"
#include "study/study_internal.h"
#include "output/units.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Statistics of a column; the per-compartment ones are summary.csv's. */
enum { W_M0_ALL, W_M1_ALL, W_M0, W_M1, W_M2, W_D10, W_D50, W_D90, W_MEAN, W_TOTAL, W_POROSITY,
       W_LIQUID_CONTENT, W_MECH, W_MOISTURE };

/* The volume coordinate called name, or -1. */
static int vol_index(const gs_model *m, const char *name) {
  for (int k = 0; k < m->nvol; k++)
    if (!strcmp(gs_model_vol_name(m, k), name)) return k;
  return -1;
}

/* Porosity and moisture need coordinates named solid and liquid (gas is
 * optional: without it the pores hold only liquid). */
static int has_pores(const gs_model *m) {
  return vol_index(m, "solid") >= 0 && vol_index(m, "liquid") >= 0;
}

static const char *const fixed_names[] = {"M0", "M1", "M2", "d10", "d50", "d90"};

int gs_study_case(const gs_cfg *base, const gs_design *d, size_t r, gs_case *c, gs_error *err) {
  memset(c, 0, sizeof *c);
  gs_cfg *cfg = gs_cfg_copy(base, err);
  if (!cfg) return err->code ? err->code : GS_ENOMEM;
  int rc = GS_OK;
  for (size_t k = 0; k < d->nkeys && !rc; k++)
    rc = gs_cfg_set(cfg, d->keys[k], d->values[r * d->nkeys + k], err);
  if (rc) {
    gs_cfg_free(cfg);
    return rc;
  }
  rc = gs_case_from_cfg(cfg, c, err); /* takes cfg over, also on failure */
  if (rc) {
    gs_case_free(c);
    memset(c, 0, sizeof *c);
  }
  return rc;
}

/* The unit of a column: summary.csv's for its statistic, the mechanism's
 * for a mechanism's column, 1 for moisture (a volume ratio). */
static const char *unit_of(const gs_model *m, int what, int index, const char *stat) {
  if (what == W_MECH) return gs_model_column(m, index)->unit;
  if (what == W_MOISTURE) return "1";
  if (what == W_M1_ALL) return gs_summary_unit("M1");
  const char *u = gs_summary_unit(stat);
  return u ? u : "1";
}

static int add_col(gs_study_outputs *o, const gs_model *m, int what, int index, size_t comp,
                   const char *fmt, const char *a, gs_error *err) {
  char name[128];
  if (comp == (size_t)-1) snprintf(name, sizeof name, fmt, a);
  else snprintf(name, sizeof name, fmt, a, comp + 1);
  size_t i = o->ncol++;
  o->names[i] = malloc(strlen(name) + 1);
  if (!o->names[i]) return gs_error_set(err, GS_ENOMEM, "out of memory for output names");
  strcpy(o->names[i], name);
  o->units[i] = unit_of(m, what, index, a);
  o->what[i] = what;
  o->index[i] = index;
  o->comp[i] = comp;
  return GS_OK;
}

int gs_study_outputs_init(gs_study_outputs *o, const gs_model *m, const char *const *extra,
                          size_t nextra, gs_error *err) {
  memset(o, 0, sizeof *o);
  const size_t nc = m->grid.ncomp;
  const int nvol = m->nvol;
  size_t cap = 1 + (size_t)nvol + 3 * nc + nextra * nc;
  o->names = gs_calloc(cap, sizeof *o->names, err);
  o->units = gs_calloc(cap, sizeof *o->units, err);
  o->what = gs_calloc(cap, sizeof *o->what, err);
  o->index = gs_calloc(cap, sizeof *o->index, err);
  o->comp = gs_calloc(cap, sizeof *o->comp, err);
  o->ncomp = nc;
  o->nvol = nvol;
  o->nmech_col = gs_model_ncolumns(m);
  if (!o->names || !o->units || !o->what || !o->index || !o->comp) {
    gs_study_outputs_free(o);
    return GS_ENOMEM;
  }
  int rc = add_col(o, m, W_M0_ALL, 0, (size_t)-1, "%s", "M0", err);
  for (int k = 0; k < nvol && !rc; k++)
    rc = add_col(o, m, W_M1_ALL, k, (size_t)-1, "M1_%s", gs_model_vol_name(m, k), err);
  for (int w = W_D10; w <= W_D90 && !rc; w++)
    for (size_t j = 0; j < nc && !rc; j++)
      rc = add_col(o, m, w, 0, j, "%s_c%zu", fixed_names[w - W_M0], err);
  for (size_t e = 0; e < nextra && !rc; e++) {
    int what = -1, index = 0;
    int dup = !strcmp(extra[e], "d10") || !strcmp(extra[e], "d50") || !strcmp(extra[e], "d90");
    for (size_t f = 0; f < e; f++) dup |= !strcmp(extra[e], extra[f]);
    if (dup) continue; /* gathered already: one column per name */
    for (int w = W_M0; w <= W_D90; w++)
      if (!strcmp(extra[e], fixed_names[w - W_M0])) what = w;
    for (int k = 0; k < nvol && what < 0; k++) {
      char name[96];
      snprintf(name, sizeof name, "mean_%s", gs_model_vol_name(m, k));
      if (!strcmp(extra[e], name)) what = W_MEAN, index = k;
      snprintf(name, sizeof name, "total_%s", gs_model_vol_name(m, k));
      if (!strcmp(extra[e], name)) what = W_TOTAL, index = k;
    }
    int liquid, gas;
    const int pores = gs_model_pore_coordinates(m, &liquid, &gas);
    if (what < 0 && pores && !strcmp(extra[e], "porosity")) what = W_POROSITY;
    if (what < 0 && pores && !strcmp(extra[e], "liquid_content")) what = W_LIQUID_CONTENT;
    for (int k = 0; k < gs_model_ncolumns(m) && what < 0; k++)
      if (!strcmp(extra[e], gs_model_column(m, k)->name)) what = W_MECH, index = k;
    if (what < 0 && has_pores(m) && !strcmp(extra[e], "moisture")) what = W_MOISTURE;
    if (what < 0) {
      char known[1024] = "M0, M1, M2, d10, d50, d90";
      size_t at = strlen(known);
      for (int k = 0; k < nvol && at < sizeof known; k++)
        at += (size_t)snprintf(known + at, sizeof known - at, ", mean_%s, total_%s",
                               gs_model_vol_name(m, k), gs_model_vol_name(m, k));
      if (pores && at < sizeof known) at += (size_t)snprintf(known + at, sizeof known - at, ", porosity, liquid_content");
      for (int k = 0; k < gs_model_ncolumns(m) && at < sizeof known; k++)
        at += (size_t)snprintf(known + at, sizeof known - at, ", %s", gs_model_column(m, k)->name);
      if (has_pores(m) && at < sizeof known) at += (size_t)snprintf(known + at, sizeof known - at, ", moisture");
      rc = gs_error_set(err, GS_EINPUT, "--outputs: unknown summary column '%s'; known: %s",
                        extra[e], known);
    }
    for (size_t j = 0; j < nc && !rc; j++) rc = add_col(o, m, what, index, j, "%s_c%zu", extra[e], err);
  }
  if (rc) gs_study_outputs_free(o);
  return rc;
}

int gs_study_outputs_fit(const gs_study_outputs *o, const gs_model *m, gs_error *err) {
  if (m->grid.ncomp != o->ncomp)
    return gs_error_set(err, GS_EINPUT,
                        "the variation changes the number of compartments (%zu, the case has %zu): "
                        "the runs of a study must share the outputs' columns",
                        m->grid.ncomp, o->ncomp);
  if (m->nvol != o->nvol)
    return gs_error_set(err, GS_EINPUT,
                        "the variation changes the volume coordinates (%d, the case has %d): the "
                        "runs of a study must share the outputs' columns",
                        m->nvol, o->nvol);
  if (gs_model_ncolumns(m) != o->nmech_col)
    return gs_error_set(err, GS_EINPUT,
                        "the variation changes the mechanisms' summary columns (%d, the case has %d): "
                        "the runs of a study must share the outputs' columns",
                        gs_model_ncolumns(m), o->nmech_col);
  return GS_OK;
}

/* Columns [lo, hi) of o into values[0..hi - lo). */
static void eval_range(const gs_study_outputs *o, const gs_model *m, size_t lo, size_t hi, double t,
                       const double *y, double *values) {
  const size_t nc = m->grid.ncomp, nm = (size_t)o->nmech_col;
  gs_summary *s = calloc(nc, sizeof *s);
  double *mech = calloc(nc * nm + 1, sizeof *mech);
  if (!s || !mech) { /* no memory for the statistics: the row says so, the run still counts */
    for (size_t i = lo; i < hi; i++) values[i - lo] = NAN;
    free(s);
    free(mech);
    return;
  }
  for (size_t j = 0; j < nc; j++) gs_summarize(m, y, j, &s[j]);
  for (size_t j = 0; nm && j < nc; j++) gs_model_report(m, j, t, y, mech + j * nm);
  for (size_t i = lo; i < hi; i++) {
    const gs_summary *c = &s[o->comp[i] < nc ? o->comp[i] : 0];
    double v = 0;
    switch (o->what[i]) {
    case W_M0_ALL:
      for (size_t j = 0; j < nc; j++) v += s[j].m0;
      break;
    case W_M1_ALL:
      for (size_t j = 0; j < nc; j++) v += s[j].total[o->index[i]];
      break;
    case W_M0: v = c->m0; break;
    case W_M1: v = c->m1; break;
    case W_M2: v = c->m2; break;
    case W_D10: v = c->d10; break;
    case W_D50: v = c->d50; break;
    case W_D90: v = c->d90; break;
    case W_MEAN: v = c->mean[o->index[i]]; break;
    case W_POROSITY: v = c->porosity; break;
    case W_LIQUID_CONTENT: v = c->liquid_content; break;
    case W_MECH: v = mech[(o->comp[i] < nc ? o->comp[i] : 0) * nm + (size_t)o->index[i]]; break;
    case W_MOISTURE: /* liquid-to-solid volume ratio of the totals */
      v = c->total[vol_index(m, "liquid")] / c->total[vol_index(m, "solid")];
      break;
    default: v = c->total[o->index[i]]; break;
    }
    values[i - lo] = v;
  }
  free(s);
  free(mech);
}

void gs_study_outputs_eval(const gs_study_outputs *o, const gs_model *m, double t, const double *y,
                           double *values) {
  eval_range(o, m, 0, o->ntimes ? o->nbase : o->ncol, t, y, values);
}

void gs_study_outputs_eval_slot(const gs_study_outputs *o, const gs_model *m, size_t k, double t,
                                const double *y, double *values) {
  const size_t nb = o->ntimes ? o->nbase : o->ncol;
  eval_range(o, m, k * nb, (k + 1) * nb, t, y, values);
}

/* Output times equal to the --at time within this relative tolerance (the
 * case's times are computed, e.g. end * i / count). */
static int same_time(double a, double b) { return fabs(a - b) <= 1e-12 * fmax(1, fmax(fabs(a), fabs(b))); }

int gs_study_outputs_add_times(gs_study_outputs *o, const double *times, size_t n, gs_error *err) {
  if (!n) return GS_OK;
  const size_t nb = o->ncol, total = nb * (n + 1);
  char **names = realloc(o->names, total * sizeof *names);
  if (names) o->names = names;
  const char **units = realloc(o->units, total * sizeof *units);
  if (units) o->units = units;
  int *what = realloc(o->what, total * sizeof *what);
  if (what) o->what = what;
  int *index = realloc(o->index, total * sizeof *index);
  if (index) o->index = index;
  size_t *comp = realloc(o->comp, total * sizeof *comp);
  if (comp) o->comp = comp;
  o->times = malloc(n * sizeof *o->times);
  if (!names || !units || !what || !index || !comp || !o->times)
    return gs_error_set(err, GS_ENOMEM, "out of memory for the outputs' times");
  for (size_t k = 0; k < n; k++) {
    if (!isfinite(times[k]) || times[k] < 0)
      return gs_error_set(err, GS_EINPUT, "--at %g: expected an output time [s] >= 0", times[k]);
    for (size_t q = 0; q < k; q++)
      if (same_time(times[q], times[k])) return gs_error_set(err, GS_EINPUT, "--at %g is given twice", times[k]);
    o->times[k] = times[k];
  }
  for (size_t k = 0; k < n; k++)
    for (size_t i = 0; i < nb; i++) {
      const size_t j = nb * (k + 1) + i;
      char name[160];
      snprintf(name, sizeof name, "%s@%.10g", o->names[i], times[k]);
      o->names[j] = malloc(strlen(name) + 1);
      if (!o->names[j]) return gs_error_set(err, GS_ENOMEM, "out of memory for output names");
      strcpy(o->names[j], name);
      o->units[j] = o->units[i], o->what[j] = o->what[i], o->index[j] = o->index[i], o->comp[j] = o->comp[i];
      o->ncol = j + 1;
    }
  o->nbase = nb;
  o->ntimes = n;
  return GS_OK;
}

int gs_study_outputs_times_fit(const gs_study_outputs *o, const double *times, size_t n, gs_error *err) {
  for (size_t k = 0; k < o->ntimes; k++) {
    int found = 0;
    for (size_t i = 0; i < n && !found; i++) found = same_time(times[i], o->times[k]);
    if (!found)
      return gs_error_set(err, GS_EINPUT,
                          "--at %g: not an output time of the case (its output times run from %g to %g "
                          "s, %zu in all); add it to output.times or choose one of them",
                          o->times[k], n ? times[0] : 0.0, n ? times[n - 1] : 0.0, n);
  }
  return GS_OK;
}

void gs_study_outputs_free(gs_study_outputs *o) {
  if (!o) return;
  for (size_t i = 0; o->names && i < o->ncol; i++) free(o->names[i]);
  free(o->names);
  free(o->units);
  free(o->what);
  free(o->index);
  free(o->comp);
  free(o->times);
  memset(o, 0, sizeof *o);
}

void gs_study_extras_all(const gs_model *m, gs_study_extras *x) {
  x->n = 0;
  for (size_t i = 0; i < sizeof fixed_names / sizeof *fixed_names; i++) x->name[x->n++] = fixed_names[i];
  for (int k = 0; k < m->nvol && k < 8; k++) {
    snprintf(x->buf[2 * k], sizeof x->buf[0], "mean_%s", gs_model_vol_name(m, k));
    snprintf(x->buf[2 * k + 1], sizeof x->buf[0], "total_%s", gs_model_vol_name(m, k));
    x->name[x->n++] = x->buf[2 * k];
    x->name[x->n++] = x->buf[2 * k + 1];
  }
  if (has_pores(m)) {
    x->name[x->n++] = "porosity";
    x->name[x->n++] = "moisture";
  }
}

int gs_study_outputs_find(const gs_study_outputs *o, const char *name, const char *what,
                          size_t *col, gs_error *err) {
  char alias[300]; /* one compartment: d50 means d50_c1 */
  snprintf(alias, sizeof alias, "%s_c1", name);
  for (size_t i = 0; i < o->ncol; i++)
    if (!strcmp(o->names[i], name) || (o->ncomp == 1 && !strcmp(o->names[i], alias))) {
      *col = i;
      return GS_OK;
    }
  char known[1024];
  size_t at = 0;
  for (size_t q = 0; q < o->ncol && at < sizeof known; q++)
    at += (size_t)snprintf(known + at, sizeof known - at, "%s%s", q ? ", " : "", o->names[q]);
  return gs_error_set(err, GS_EINPUT, "%s '%s' is no output of the case; known: %s", what, name,
                      known);
}

double gs_study_to_x(const gs_study_axis *a, double z, double *dxdz) {
  double s = 1 / (1 + exp(-z));
  double lo = a->log ? log(a->lo) : a->lo, hi = a->log ? log(a->hi) : a->hi;
  double u = lo + (hi - lo) * s, du = (hi - lo) * s * (1 - s);
  double x = a->log ? exp(u) : u;
  if (dxdz) *dxdz = a->log ? x * du : du;
  return x;
}

double gs_study_to_z(const gs_study_axis *a, double x) {
  double lo = a->log ? log(a->lo) : a->lo, hi = a->log ? log(a->hi) : a->hi;
  double s = ((a->log ? log(x) : x) - lo) / (hi - lo);
  return log(s / (1 - s));
}
