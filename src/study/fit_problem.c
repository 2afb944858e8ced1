/* The case against measured batches as residuals: shared by the fit's
 * least squares and the optimiser's objective (study_internal.h). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/run.h"
#include "study/study_internal.h"

/* Records the model's value of every data column at the data's times. */
typedef struct {
  const gs_fit_problem *fc;
  const gs_fit_map *map;
  const gs_fit_data *d;
  const gs_case *c;
  double *row;   /* one time's outputs (out.ncol) */
  double *model; /* ntimes x ncols */
  char *seen;
} fit_obs;

static int fit_obs_output(void *self, const gs_run_view *run, double t, const double *Y, int *stop,
                          gs_error *err) {
  (void)run, (void)stop, (void)err;
  fit_obs *o = self;
  const gs_fit_data *d = o->d;
  const gs_model *m = &o->c->model;
  const double last = o->c->times[o->c->ntimes - 1];
  for (size_t i = 0; i < d->ntimes; i++) {
    const double ti = isinf(d->times[i]) ? last : d->times[i];
    if (!(fabs(t - ti) <= 1e-12 * fmax(1, fabs(t)))) continue;
    gs_study_outputs_eval(&o->fc->out, m, t, Y, o->row);
    for (size_t j = 0; j < d->ncols; j++) {
      double *v = &o->model[i * d->ncols + j];
      if (o->map->col[j] != GS_FIT_SIEVE) *v = o->row[o->map->col[j]];
      else gs_sieve_fractions(m, Y, o->map->comp[j], o->map->sieve + 2 * j, 1, v);
    }
    o->seen[i] = 1;
  }
  return GS_OK;
}

static const gs_observer_type fit_obs_type = {.name = "fit", .output = fit_obs_output};

/* The design of batch b at parameter values x: the batch's keys, then the
 * parameters'; text[np] holds the values' text. */
static void batch_design(const gs_fit_problem *fc, const gs_fit_batch *b, const double *x,
                         char **keys, char **values, char (*text)[40], gs_design *d) {
  for (size_t k = 0; k < b->nset; k++) keys[k] = b->keys[k], values[k] = b->values[k];
  for (size_t k = 0; k < fc->np; k++) {
    keys[b->nset + k] = fc->params[k].key;
    if (x) snprintf(text[k], sizeof text[k], "%.17g", x[k]);
    values[b->nset + k] = x ? text[k] : NULL;
  }
  *d = (gs_design){.nkeys = b->nset + (x ? fc->np : 0), .nruns = 1, .keys = keys, .values = values};
}

/* One batch's run: model values [ntimes x ncols]. */
static int batch_run(gs_fit_problem *fc, size_t bi, const double *x, double *model, gs_error *err) {
  const gs_fit_batch *b = &fc->bs->batch[bi];
  const gs_fit_data *data = &b->data;
  char **keys = malloc((b->nset + fc->np + 1) * sizeof *keys);
  char **values = malloc((b->nset + fc->np + 1) * sizeof *values);
  char(*text)[40] = malloc((fc->np ? fc->np : 1) * sizeof *text);
  gs_case c;
  fit_obs obs = {.fc = fc, .map = &fc->map[bi], .d = data, .c = &c, .model = model};
  obs.row = calloc(fc->out.ncol ? fc->out.ncol : 1, sizeof *obs.row);
  obs.seen = calloc(data->ntimes, 1);
  int rc = GS_OK;
  if (!keys || !values || !text || !obs.row || !obs.seen) {
    rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  } else {
    gs_design d;
    batch_design(fc, b, x, keys, values, text, &d);
    rc = gs_study_case(fc->base, &d, 0, &c, err);
    if (!rc) {
      rc = gs_study_outputs_fit(&fc->out, &c.model, err);
      gs_observer ob = {.type = &fit_obs_type, .self = &obs};
      gs_run_options opt = {.progress = 0, .observers = &ob, .nobservers = 1};
      gs_run_report rep;
      if (!rc) rc = gs_case_run(&c, &opt, NULL, &rep, err);
      gs_case_free(&c);
    }
    for (size_t i = 0; !rc && i < data->ntimes; i++)
      if (!obs.seen[i]) /* gs_fit_problem_init checked the times: a run that stopped early */
        rc = gs_error_set(err, GS_ENUMERIC, "%s:%zu: the run gave no output at time %g",
                          data->path, data->lines[i], data->times[i]);
    if (rc) {
      char what[512] = "";
      for (size_t k = 0, at = 0; k < d.nkeys && at < sizeof what; k++)
        at += (size_t)snprintf(what + at, sizeof what - at, "%s%s=%s", k ? ", " : "", keys[k],
                               values[k]);
      gs_error_prefix(err, "batch '%s', the model at %s: ", b->name, what);
    }
  }
  free(keys);
  free(values);
  free(text);
  free(obs.row);
  free(obs.seen);
  return rc;
}

int gs_fit_problem_residuals(gs_fit_problem *fc, const double *x, double *r, double *model,
                             gs_error *err) {
  double *own = model ? NULL : malloc(fc->nresid * sizeof *own);
  double *mv = model ? model : own;
  if (!mv) return gs_error_set(err, GS_ENOMEM, "out of memory");
  int rc = GS_OK;
  for (size_t bi = 0; bi < fc->bs->n && !rc; bi++) {
    const gs_fit_data *d = &fc->bs->batch[bi].data;
    const gs_fit_map *map = &fc->map[bi];
    double *mb = mv + map->off;
    rc = batch_run(fc, bi, x, mb, err);
    for (size_t i = 0; !rc && i < d->ntimes; i++)
      for (size_t j = 0; j < d->ncols; j++) {
        const size_t q = i * d->ncols + j;
        r[map->off + q] = (mb[q] - d->values[q]) / map->scale[j];
      }
  }
  free(own);
  return rc;
}

void gs_fit_problem_free(gs_fit_problem *fc) {
  for (size_t b = 0; fc->map && fc->bs && b < fc->bs->n; b++) {
    free(fc->map[b].col);
    free(fc->map[b].sieve);
    free(fc->map[b].comp);
    free(fc->map[b].scale);
    free(fc->map[b].porosity);
  }
  free(fc->map);
  gs_study_outputs_free(&fc->out);
  memset(fc, 0, sizeof *fc);
}

/* ---- checks before any run -------------------------------------------------- */

/* The start: the case's own value of each parameter where it lies inside
 * its range, else the range's middle; also checks that the keys exist. */
static int start_values(const gs_cfg *base, const gs_study_axis *params, size_t np, double *x0,
                        gs_error *err) {
  gs_cfg *probe = gs_cfg_copy(base, err);
  if (!probe) return err->code;
  int rc = GS_OK;
  for (size_t k = 0; k < np && !rc; k++) {
    gs_cfg_node *node = gs_cfg_find(probe, params[k].key, err);
    double x;
    if (!node || gs_cfg_kind_of(node) != GS_CFG_SCALAR)
      rc = node ? gs_error_set(err, GS_EINPUT, "key '%s' is not a single value", params[k].key)
                : gs_error_prefix(err, "--params %s: ", params[k].key);
    else if (gs_cfg_node_double(node, &x, err)) rc = gs_error_prefix(err, "key '%s': ", params[k].key);
    else x0[k] = x > params[k].lo && x < params[k].hi ? x : gs_study_axis_value(&params[k], 0.5);
  }
  gs_cfg_free(probe);
  return rc;
}

/* The batch's keys exist, are not fitted, and its case builds; its data
 * times are output times of that case. */
static int check_batch(const gs_fit_problem *fc, const gs_fit_batch *b, gs_case *c, gs_error *err) {
  for (size_t k = 0; k < b->nset; k++)
    for (size_t q = 0; q < fc->np; q++)
      if (!strcmp(b->keys[k], fc->params[q].key))
        return gs_error_set(err, GS_EINPUT,
                            "%s: batch '%s' sets '%s', which the fit estimates (--params): a "
                            "batch's recipe is given, not fitted",
                            b->where, b->name, b->keys[k]);
  gs_cfg *probe = gs_cfg_copy(fc->base, err);
  if (!probe) return err->code;
  int rc = GS_OK;
  for (size_t k = 0; k < b->nset && !rc; k++)
    if (!gs_cfg_find(probe, b->keys[k], err))
      rc = gs_error_prefix(err, "%s:%d: batch '%s': unknown key '%s': ", fc->bs->path ? fc->bs->path : b->where,
                           b->key_lines ? b->key_lines[k] : 0, b->name, b->keys[k]);
  gs_cfg_free(probe);
  if (rc) return rc;
  char **keys = malloc((b->nset + fc->np + 1) * sizeof *keys),
       **values = malloc((b->nset + fc->np + 1) * sizeof *values);
  gs_design d;
  if (!keys || !values) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  if (!rc) {
    batch_design(fc, b, NULL, keys, values, NULL, &d);
    if ((rc = gs_study_case(fc->base, &d, 0, c, err)))
      gs_error_prefix(err, "%s: batch '%s': ", b->where, b->name);
  }
  free(keys);
  free(values);
  if (rc) return rc;
  const gs_fit_data *data = &b->data;
  const double t0 = c->times[0], tend = c->times[c->ntimes - 1];
  char whose[300] = "the case";
  if (fc->bs->path) snprintf(whose, sizeof whose, "batch '%s'", b->name);
  for (size_t i = 0; i < data->ntimes && !rc; i++) {
    const double t = data->times[i];
    int found = isinf(t); /* end: the run's last output time */
    for (size_t q = 0; q < c->ntimes && !found; q++)
      found = fabs(t - c->times[q]) <= 1e-12 * fmax(1, fabs(t));
    if (found) continue;
    if (t < t0 || t > tend)
      rc = gs_error_set(err, GS_EINPUT,
                        "%s:%zu: column 1 (time) = %g is outside the run of %s (%g to %g)",
                        data->path, data->lines[i], t, whose, t0, tend);
    else
      rc = gs_error_set(err, GS_EINPUT,
                        "%s:%zu: column 1 (time) = %g is not an output time of %s: list the "
                        "data's times in output.times",
                        data->path, data->lines[i], t, whose);
  }
  if (rc) gs_case_free(c);
  return rc;
}

/* The sieve column j of data: its class, checked against the declared
 * sieves and the case's compartments. */
static int map_sieve(const gs_fit_batches *bs, const gs_fit_data *d, size_t j, size_t ncomp,
                     gs_fit_map *map, gs_error *err) {
  double lo, hi;
  size_t comp;
  const char *name = d->names[j];
  if (gs_fit_sieve_column(name, &lo, &hi, &comp) < 0)
    return gs_error_set(err, GS_EINPUT,
                        "%s:%zu: column %zu '%s': expected a sieve class sieve_<LO>_<HI> or "
                        "sieve_<LO>_<HI>_c<j>, 0 <= LO < HI in micrometres (HI may be inf)",
                        d->path, d->header_line, j + 2, name);
  if (!comp && ncomp > 1)
    return gs_error_set(err, GS_EINPUT,
                        "%s:%zu: column %zu '%s': the case has %zu compartments: name one (%s_c1)",
                        d->path, d->header_line, j + 2, name, ncomp, name);
  if (comp > ncomp)
    return gs_error_set(err, GS_EINPUT, "%s:%zu: column %zu '%s': the case has %zu compartment%s",
                        d->path, d->header_line, j + 2, name, ncomp, ncomp == 1 ? "" : "s");
  if (bs->sieves) {
    int found = 0;
    for (size_t k = 0; k + 1 < bs->nsieves && !found; k++) {
      const double a = bs->sieves[k], b = bs->sieves[k + 1];
      found = fabs(lo - a) <= 1e-6 * a && (isinf(b) ? isinf(hi) : fabs(hi - b) <= 1e-6 * b);
    }
    if (!found) {
      char list[512] = "";
      for (size_t k = 0, at = 0; k + 1 < bs->nsieves && at < sizeof list; k++)
        at += (size_t)snprintf(list + at, sizeof list - at, "%s%g_%g", k ? ", " : "",
                               bs->sieves[k] * 1e6, bs->sieves[k + 1] * 1e6);
      return gs_error_set(err, GS_EINPUT,
                          "%s:%zu: column %zu '%s' is not a class of the sieves (%s:%d); their "
                          "classes in micrometres: %s",
                          d->path, d->header_line, j + 2, name, bs->path, bs->sieves_line, list);
    }
  }
  for (size_t q = 0; q < j; q++) /* classes of one compartment must not overlap */
    if (map->col[q] == GS_FIT_SIEVE && map->comp[q] == (comp ? comp - 1 : 0) &&
        lo < map->sieve[2 * q + 1] && map->sieve[2 * q] < hi)
      return gs_error_set(err, GS_EINPUT, "%s:%zu: column %zu '%s' overlaps column %zu '%s'",
                          d->path, d->header_line, j + 2, name, q + 2, d->names[q]);
  map->col[j] = GS_FIT_SIEVE;
  map->sieve[2 * j] = lo;
  map->sieve[2 * j + 1] = hi;
  map->comp[j] = comp ? comp - 1 : 0;
  return GS_OK;
}

static int map_batch(gs_fit_problem *fc, const gs_fit_data *d, size_t ncomp, gs_fit_map *map,
                     gs_error *err) {
  const size_t n = d->ncols ? d->ncols : 1;
  map->col = calloc(n, sizeof *map->col);
  map->sieve = calloc(2 * n, sizeof *map->sieve);
  map->comp = calloc(n, sizeof *map->comp);
  map->scale = calloc(n, sizeof *map->scale);
  map->porosity = calloc(n, 1);
  if (!map->col || !map->sieve || !map->comp || !map->scale || !map->porosity)
    return gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t j = 0; j < d->ncols; j++) {
    double lo, hi;
    size_t comp;
    int rc;
    if (gs_fit_sieve_column(d->names[j], &lo, &hi, &comp)) rc = map_sieve(fc->bs, d, j, ncomp, map, err);
    else if ((rc = gs_study_outputs_find(&fc->out, d->names[j], "data column", &map->col[j], err)))
      gs_error_prefix(err, "%s:%zu: column %zu: ", d->path, d->header_line, j + 2);
    if (rc) return rc;
    map->porosity[j] = map->col[j] != GS_FIT_SIEVE && !strncmp(fc->out.names[map->col[j]], "porosity_c", 10);
  }
  return GS_OK;
}

/* Residual scales: the RMS of each column name's values over all batches,
 * one RMS over every sieve value (a PSD is one quantity: its classes'
 * squared errors add as the thesis's SSE does), 1 where all are 0. */
static void scales(gs_fit_problem *fc) {
  const gs_fit_batches *bs = fc->bs;
  for (size_t b = 0; b < bs->n; b++) {
    const gs_fit_data *d = &bs->batch[b].data;
    for (size_t j = 0; j < d->ncols; j++) {
      const int sieve = fc->map[b].col[j] == GS_FIT_SIEVE;
      double ss = 0;
      size_t n = 0;
      for (size_t q = 0; q < bs->n; q++) {
        const gs_fit_data *e = &bs->batch[q].data;
        for (size_t k = 0; k < e->ncols; k++) {
          if (sieve ? fc->map[q].col[k] != GS_FIT_SIEVE : strcmp(e->names[k], d->names[j])) continue;
          for (size_t t = 0; t < e->ntimes; t++) ss += pow(e->values[t * e->ncols + k], 2);
          n += e->ntimes;
        }
      }
      fc->map[b].scale[j] = ss > 0 ? sqrt(ss / (double)n) : 1;
    }
  }
}

int gs_fit_problem_init(gs_fit_problem *fc, const gs_cfg *base, const gs_study_axis *params,
                        size_t np, const gs_fit_batches *bs, double *x0, gs_error *err) {
  memset(fc, 0, sizeof *fc);
  *fc = (gs_fit_problem){.base = base, .params = params, .np = np, .bs = bs};
  int rc = start_values(base, params, np, x0, err);
  if (rc) return rc;
  if (!(fc->map = calloc(bs->n, sizeof *fc->map))) return gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t b = 0; b < bs->n && !rc; b++) {
    gs_case c;
    if ((rc = check_batch(fc, &bs->batch[b], &c, err))) break;
    if (b == 0) { /* the columns: every statistic, so any a data file names is there */
      gs_study_extras extra;
      gs_study_extras_all(&c.model, &extra);
      rc = gs_study_outputs_init(&fc->out, &c.model, extra.name, extra.n, err);
    } else if ((rc = gs_study_outputs_fit(&fc->out, &c.model, err))) {
      gs_error_prefix(err, "%s: batch '%s': ", bs->batch[b].where, bs->batch[b].name);
    }
    if (!rc) rc = map_batch(fc, &bs->batch[b].data, c.model.grid.ncomp, &fc->map[b], err);
    gs_case_free(&c);
    fc->map[b].off = fc->nresid;
    fc->nresid += bs->batch[b].data.ntimes * bs->batch[b].data.ncols;
  }
  if (!rc) scales(fc);
  if (rc) gs_fit_problem_free(fc);
  return rc;
}

double gs_fit_problem_r2(const gs_fit_problem *fc, double chi2) {
  const gs_fit_batches *bs = fc->bs;
  double sst = 0;
  for (size_t b = 0; b < bs->n; b++) {
    const gs_fit_data *d = &bs->batch[b].data;
    for (size_t j = 0; j < d->ncols; j++) {
      double mean = 0;
      size_t cnt = 0;
      for (size_t q = 0; q < bs->n; q++) {
        const gs_fit_data *e = &bs->batch[q].data;
        for (size_t k = 0; k < e->ncols; k++)
          if (!strcmp(e->names[k], d->names[j]))
            for (size_t t = 0; t < e->ntimes; t++, cnt++) mean += e->values[t * e->ncols + k];
      }
      mean /= (double)cnt;
      for (size_t t = 0; t < d->ntimes; t++)
        sst += pow((d->values[t * d->ncols + j] - mean) / fc->map[b].scale[j], 2);
    }
  }
  return sst > 0 ? 1 - chi2 / sst : NAN;
}

void gs_fit_eval_free(gs_fit_eval *ev) {
  if (!ev) return;
  free(ev->model);
  free(ev->resid);
  free(ev->unit);
  memset(ev, 0, sizeof *ev);
}

int gs_fit_evaluate(const gs_cfg *base, const gs_study_axis *params, size_t np, const double *x,
                    const gs_fit_batches *bs, gs_fit_eval *ev, gs_error *err) {
  memset(ev, 0, sizeof *ev);
  gs_fit_problem fc;
  double x0[64];
  if (np > 64) return gs_error_set(err, GS_EINPUT, "at most 64 parameters (got %zu)", np);
  int rc = gs_fit_problem_init(&fc, base, params, np, bs, x0, err);
  if (rc || !x) { /* no values: the checks alone */
    if (!rc) gs_fit_problem_free(&fc);
    return rc;
  }
  ev->nresid = fc.nresid;
  ev->model = malloc((fc.nresid ? fc.nresid : 1) * sizeof *ev->model);
  ev->resid = malloc((fc.nresid ? fc.nresid : 1) * sizeof *ev->resid);
  ev->unit = malloc((fc.nresid ? fc.nresid : 1) * sizeof *ev->unit);
  if (!ev->model || !ev->resid || !ev->unit) rc = gs_error_set(err, GS_ENOMEM, "out of memory");
  for (size_t b = 0; !rc && b < bs->n; b++) { /* sieve fractions are fractions of the volume */
    const gs_fit_data *d = &bs->batch[b].data;
    const gs_fit_map *map = &fc.map[b];
    for (size_t q = 0; q < d->ntimes * d->ncols; q++)
      ev->unit[map->off + q] =
          map->col[q % d->ncols] == GS_FIT_SIEVE ? "1" : fc.out.units[map->col[q % d->ncols]];
  }
  if (!rc) rc = gs_fit_problem_residuals(&fc, x, ev->resid, ev->model, err);
  for (size_t i = 0; !rc && i < fc.nresid; i++) ev->chi2 += ev->resid[i] * ev->resid[i];
  if (!rc) ev->r2 = gs_fit_problem_r2(&fc, ev->chi2);
  gs_fit_problem_free(&fc);
  if (rc) gs_fit_eval_free(ev);
  return rc;
}
