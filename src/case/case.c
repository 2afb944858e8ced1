/* Case files: read and validate every section, build the model, initial
 * state, integrator, output times and checks.  docs/case-files.md documents
 * every key read here. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/case.h"
#include "gransim/distribution.h"
#include "case/limits.h"

/* ---- grid ------------------------------------------------------------------ */
static int read_axis(gs_cfg_node *n, gs_axis *ax, gs_error *err) {
  static const char *const types[] = {"linear", "geometric", "edges", NULL};
  const char *name = NULL;
  int type = 0, rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_string_req(n, "name", &name, err);
  if (!rc && (strlen(name) == 0 || strlen(name) >= GS_NAME_LEN || strpbrk(name, " ,/\t")))
    rc = gs_cfg_fail(gs_cfg_get(n, "name"), err, "expected a name of 1-%d characters without spaces, commas or '/'", GS_NAME_LEN - 1);
  if (!rc && !gs_cfg_get(n, "type")) rc = gs_cfg_missing(n, "type", "(linear, geometric or edges)", err);
  if (!rc) rc = gs_cfg_enum_opt(n, "type", types, 0, &type, err);
  if (rc) return rc;
  if (type == 0) {
    double lo, hi;
    long cells;
    rc = gs_cfg_double_range(n, "min", 1, 0, 0, 0, HUGE_VAL, 0, &lo, err);
    if (!rc) rc = gs_cfg_double_range(n, "max", 1, 0, lo, 1, HUGE_VAL, 0, &hi, err);
    if (!rc) rc = gs_cfg_long_range(n, "cells", 1, 0, 1, 100000, &cells, err);
    if (!rc) rc = gs_axis_linear(ax, name, lo, hi, (size_t)cells, err);
  } else if (type == 1) {
    double lo, ratio = 0, hi = 0;
    long cells;
    int zero_first;
    rc = gs_cfg_double_range(n, "min", 1, 0, 0, 1, HUGE_VAL, 0, &lo, err);
    if (!rc) rc = gs_cfg_long_range(n, "cells", 1, 0, 1, 100000, &cells, err);
    if (!rc) rc = gs_cfg_bool_opt(n, "zero_first", 0, &zero_first, err);
    if (!rc && !!gs_cfg_get(n, "ratio") == !!gs_cfg_get(n, "max"))
      rc = gs_cfg_fail(n, err, "a geometric axis needs exactly one of 'ratio' or 'max'");
    if (!rc && gs_cfg_get(n, "ratio")) rc = gs_cfg_double_range(n, "ratio", 1, 0, 1, 1, HUGE_VAL, 0, &ratio, err);
    if (!rc && gs_cfg_get(n, "max")) {
      rc = gs_cfg_double_range(n, "max", 1, 0, lo, 1, HUGE_VAL, 0, &hi, err);
      ratio = pow(hi / lo, 1.0 / (double)(cells - (zero_first ? 1 : 0) > 0 ? cells - (zero_first ? 1 : 0) : 1));
    }
    /* with zero_first, `cells` counts the extra [0, min] cell */
    if (!rc && zero_first && cells < 2) rc = gs_cfg_fail(gs_cfg_get(n, "cells"), err, "expected at least 2 cells with zero_first");
    if (!rc) rc = gs_axis_geometric(ax, name, lo, ratio, (size_t)cells - (zero_first ? 1 : 0), zero_first, err);
  } else {
    double *edges = NULL, *pivots = NULL;
    size_t ne = 0, np = 0;
    rc = gs_cfg_doubles_req(n, "edges", 0, &edges, &ne, err);
    if (!rc && gs_cfg_get(n, "pivots")) {
      rc = gs_cfg_doubles_req(n, "pivots", 0, &pivots, &np, err);
      if (!rc && np + 1 != ne)
        rc = gs_cfg_fail(gs_cfg_get(n, "pivots"), err, "expected %zu pivots (one per cell), got %zu", ne ? ne - 1 : 0, np);
    }
    if (!rc) rc = gs_axis_from_edges(ax, name, edges, ne, pivots, err);
    free(edges);
    free(pivots);
  }
  if (rc == GS_EINPUT && strncmp(err->msg, gs_cfg_file(n), strlen(gs_cfg_file(n))))
    gs_error_prefix(err, "%s:%d: %s: ", gs_cfg_file(n), gs_cfg_line(n), gs_cfg_path(n));
  if (!rc) rc = gs_cfg_check_unused(n, err);
  return rc;
}

/* Shared with the SWA solver: the grid section without the sectional model. */
int gs_case_read_grid_only(gs_cfg_node *root, gs_grid *g, int *size_axes, gs_cfg_node **section,
                           gs_error *err) {
  gs_cfg_node *grid = NULL, *axes = NULL;
  long ncomp = 1;
  gs_axis ax[GS_MAX_DIM];
  memset(ax, 0, sizeof ax);
  memset(g, 0, sizeof *g);
  int rc = gs_cfg_map_req(root, "grid", &grid, err);
  if (!rc) rc = gs_cfg_seq_req(grid, "axes", &axes, err);
  if (!rc && (gs_cfg_size(axes) < 1 || gs_cfg_size(axes) > GS_MAX_DIM))
    rc = gs_cfg_fail(axes, err, "expected 1 to %d axes, got %zu", GS_MAX_DIM, gs_cfg_size(axes));
  if (!rc) rc = gs_cfg_long_range(grid, "compartments", 0, 1, 1, 1000000, &ncomp, err);
  int dim = rc ? 0 : (int)gs_cfg_size(axes), built = 0;
  for (; !rc && built < dim; built++) rc = read_axis(gs_cfg_item(axes, (size_t)built), &ax[built], err);
  if (!rc) {
    rc = gs_grid_init(g, ax, dim, (size_t)ncomp, err);
    if (rc == GS_EINPUT) gs_error_prefix(err, "%s:%d: grid.axes: ", gs_cfg_file(axes), gs_cfg_line(axes));
  }
  if (rc) {
    for (int k = 0; k < built; k++) gs_axis_free(&ax[k]);
    return rc;
  }
  *size_axes = (1 << dim) - 1;
  *section = grid;
  gs_cfg_node *sizes = gs_cfg_get(grid, "size_axes");
  if (sizes) {
    if ((rc = gs_cfg_require_kind(sizes, GS_CFG_SEQ, err))) return rc;
    *size_axes = 0;
    for (size_t i = 0; i < gs_cfg_size(sizes); i++) {
      const char *nm = gs_cfg_scalar(gs_cfg_item(sizes, i));
      int k = nm ? gs_grid_axis_by_name(g, nm) : -1;
      if (k < 0) return gs_cfg_fail(gs_cfg_item(sizes, i), err, "expected the name of a grid axis");
      *size_axes |= 1 << k;
    }
  }
  return GS_OK;
}

static int read_grid(gs_cfg_node *root, gs_model *m, gs_error *err) {
  gs_cfg_node *grid = NULL;
  gs_grid g;
  int size_axes = 0;
  int rc = gs_case_read_grid_only(root, &g, &size_axes, &grid, err);
  if (rc) {
    gs_grid_free(&g);
    return rc;
  }
  int dim = g.dim;
  rc = gs_model_init(m, &g, err);
  if (!rc && size_axes != m->size_axes) {
    m->size_axes = size_axes;
    for (size_t c = 0; c < m->grid.ncells; c++) {
      double v = 0;
      for (int k = 0; k < dim; k++)
        if (m->size_axes & (1 << k)) v += m->grid.x[c * (size_t)dim + (size_t)k];
      m->size_volume[c] = v;
    }
  }
  gs_cfg_node *carried = rc ? NULL : gs_cfg_get(grid, "carried");
  if (carried) {
    if ((rc = gs_cfg_require_kind(carried, GS_CFG_SEQ, err))) return rc;
    const char *names[GS_MAX_CARRIED];
    size_t n = gs_cfg_size(carried);
    if (n > GS_MAX_CARRIED)
      return gs_cfg_fail(carried, err, "expected at most %d carried quantities, got %zu", GS_MAX_CARRIED, n);
    for (size_t i = 0; i < n; i++) {
      names[i] = gs_cfg_scalar(gs_cfg_item(carried, i));
      if (!names[i] || !*names[i] || strlen(names[i]) >= GS_NAME_LEN)
        return gs_cfg_fail(gs_cfg_item(carried, i), err, "expected a name (e.g. liquid, gas)");
    }
    rc = gs_model_set_carried(m, names, (int)n, err);
    if (rc == GS_EINPUT) gs_error_prefix(err, "%s:%d: grid.carried: ", gs_cfg_file(carried), gs_cfg_line(carried));
  }
  if (!rc) rc = gs_cfg_check_unused(grid, err);
  return rc;
}

/* ---- initial state, mechanisms -------------------------------------------- */
/* carried_ratio: {name: volume per unit particle volume, ...} (absent: 0). */
static int read_carried_ratio(gs_cfg_node *n, const gs_model *m, double *ratio, gs_error *err) {
  gs_cfg_node *r = gs_cfg_get(n, "carried_ratio");
  for (int q = 0; q < GS_MAX_CARRIED; q++) ratio[q] = 0;
  if (!r) return GS_OK;
  int rc = gs_cfg_require_kind(r, GS_CFG_MAP, err);
  for (int q = 0; !rc && q < m->ncarried; q++)
    rc = gs_cfg_double_range(r, m->carried[q], 0, 0, 0, 0, HUGE_VAL, 0, &ratio[q], err);
  if (!rc) rc = gs_cfg_check_unused(r, err);
  return rc;
}

static int read_initial_one(gs_cfg_node *n, gs_model *m, double *y, gs_error *err) {
  long comp = 1;
  double ratio[GS_MAX_CARRIED];
  const size_t nc = m->grid.ncells;
  int rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_long_range(n, "compartment", 0, 1, 1, (long)m->grid.ncomp, &comp, err);
  if (!rc) rc = read_carried_ratio(n, m, ratio, err);
  double *added = rc ? NULL : gs_calloc(nc, sizeof(double), err);
  if (!rc && !added) rc = GS_ENOMEM;
  if (!rc) rc = gs_distribution_add(n, &m->grid, added, 0, m->disc, err);
  for (size_t c = 0; !rc && c < nc; c++) {
    y[(size_t)(comp - 1) * nc + c] += added[c];
    for (int q = 0; q < m->ncarried; q++)
      gs_model_carried(m, y, (size_t)(comp - 1), q)[c] += ratio[q] * added[c] * m->grid.volume[c];
  }
  free(added);
  return rc;
}

/* discretisation: {tolerance}: the largest relative error of number, volume
 * or mean size with which the grid may hold a distribution of the case. */
int gs_case_read_disc_tolerance(gs_cfg_node *root, double *tolerance, gs_error *err) {
  gs_cfg_node *n = gs_cfg_get(root, "discretisation");
  int rc = n ? gs_cfg_require_kind(n, GS_CFG_MAP, err) : GS_OK;
  if (!rc) rc = gs_cfg_double_range(n, "tolerance", 0, GS_DISC_TOLERANCE, 0, 1, HUGE_VAL, 0, tolerance, err);
  if (!rc && n) rc = gs_cfg_check_unused(n, err);
  return rc;
}

static int read_initial(gs_cfg_node *root, gs_model *m, double *y, gs_error *err) {
  gs_cfg_node *init = gs_cfg_get(root, "initial");
  if (!init) return GS_OK; /* empty granulator, e.g. filled by a feed */
  if (gs_cfg_kind_of(init) != GS_CFG_SEQ) return read_initial_one(init, m, y, err);
  for (size_t i = 0; i < gs_cfg_size(init); i++) {
    int rc = read_initial_one(gs_cfg_item(init, i), m, y, err);
    if (rc) return rc;
  }
  return GS_OK;
}

static int read_mechanisms(gs_cfg_node *root, gs_model *m, gs_error *err) {
  gs_cfg_node *list = gs_cfg_get(root, "mechanisms");
  if (!list) return GS_OK;
  int rc = gs_cfg_require_kind(list, GS_CFG_SEQ, err);
  for (size_t i = 0; !rc && i < gs_cfg_size(list); i++) {
    gs_cfg_node *n = gs_cfg_item(list, i);
    const char *type = NULL;
    rc = gs_cfg_require_kind(n, GS_CFG_MAP, err);
    if (!rc) rc = gs_cfg_string_req(n, "type", &type, err);
    if (!rc && !gs_mech_lookup(type)) {
      char known[512] = "";
      const gs_mech_type *const *all = gs_mech_types();
      for (size_t k = 0; all[k]; k++) {
        if (k) strncat(known, ", ", sizeof known - strlen(known) - 1);
        strncat(known, all[k]->name, sizeof known - strlen(known) - 1);
      }
      rc = gs_cfg_fail(gs_cfg_get(n, "type"), err, "unknown mechanism; expected one of: %s", known);
    }
    char label[64];
    snprintf(label, sizeof label, "mechanisms[%zu] (%s)", i, type ? type : "?");
    if (!rc) rc = gs_model_add_mechanism(m, type, n, label, err);
  }
  return rc;
}

/* ---- output times, checks, solver ----------------------------------------- */
static int read_output(gs_cfg_node *root, gs_case *c, gs_error *err) {
  static const char *const spacings[] = {"linear", "log", NULL};
  gs_cfg_node *out = NULL;
  int rc = gs_cfg_map_req(root, "output", &out, err);
  if (!rc) rc = gs_cfg_double_range(out, "start", 0, 0, -HUGE_VAL, 0, HUGE_VAL, 0, &c->t0, err);
  if (rc) return rc;
  if (gs_cfg_get(out, "times")) {
    double *t = NULL;
    size_t n = 0;
    if ((rc = gs_cfg_doubles_req(out, "times", 0, &t, &n, err))) return rc;
    c->times = gs_malloc((n + 1) * sizeof(double), err);
    if (!c->times) { free(t); return GS_ENOMEM; }
    c->times[0] = c->t0;
    c->ntimes = 1;
    for (size_t i = 0; i < n && !rc; i++) {
      if (!(t[i] >= c->times[c->ntimes - 1]))
        rc = gs_cfg_fail(gs_cfg_get(out, "times"), err, "times must increase and not precede start (%g); entry %zu is %g", c->t0, i, t[i]);
      else if (t[i] > c->times[c->ntimes - 1]) c->times[c->ntimes++] = t[i];
    }
    free(t);
    if (!rc && c->ntimes < 2) rc = gs_cfg_fail(gs_cfg_get(out, "times"), err, "expected at least one time after start");
  } else {
    double end;
    long count;
    int spacing = 0;
    rc = gs_cfg_double_range(out, "end", 1, 0, c->t0, 1, HUGE_VAL, 0, &end, err);
    if (!rc) rc = gs_cfg_long_range(out, "count", 0, 11, 2, 10000000, &count, err);
    if (!rc) rc = gs_cfg_enum_opt(out, "spacing", spacings, 0, &spacing, err);
    double first = 0;
    if (!rc && spacing == 1) rc = gs_cfg_double_range(out, "first", 1, 0, fmax(c->t0, 0.0), 1, end, 1, &first, err);
    if (rc) return rc;
    c->ntimes = (size_t)count;
    c->times = gs_malloc(c->ntimes * sizeof(double), err);
    if (!c->times) return GS_ENOMEM;
    for (size_t i = 0; i < c->ntimes; i++) {
      double f = (double)i / (double)(c->ntimes - 1);
      c->times[i] = spacing == 0 ? c->t0 + (end - c->t0) * f
                    : i == 0    ? c->t0
                                : first * pow(end / first, (double)(i - 1) / (double)(c->ntimes - 2));
    }
    c->times[c->ntimes - 1] = end;
  }
  /* wall seconds between commits of the result files (src/output/output.c) */
  if (!rc) rc = gs_cfg_double_range(out, "checkpoint", 0, 10, 0, 0, HUGE_VAL, 0, &c->checkpoint, err);
  if (!rc) rc = gs_cfg_check_unused(out, err);
  return rc;
}

static int read_checks(gs_cfg_node *root, gs_checks *k, gs_error *err) {
  gs_cfg_node *n = gs_cfg_get(root, "checks");
  int rc = n ? gs_cfg_require_kind(n, GS_CFG_MAP, err) : GS_OK;
  if (!rc) rc = gs_cfg_double_range(n, "mass_tolerance", 0, 1e-9, 0, 1, 1, 0, &k->mass_tolerance, err);
  if (!rc) rc = gs_cfg_double_range(n, "negative_tolerance", 0, 1e-6, 0, 0, 1, 0, &k->negative_tolerance, err);
  if (!rc) rc = gs_cfg_double_range(n, "max_loss", 0, 1e-6, 0, 0, 1, 0, &k->max_loss, err);
  if (!rc && n) rc = gs_cfg_check_unused(n, err);
  return rc;
}

/* The case's ODE system: the whole model in the full layout, in the case's
 * own evaluation context. */
static int model_ode(void *ctx, double t, const double *y, double *dydt) {
  gs_case *c = ctx;
  c->eval.in_integrator = 1;
  gs_model_rhs(&c->model, &c->eval, t, y, dydt, dydt + c->model.nstate);
  c->eval.in_integrator = 0;
  return 0;
}

static int model_psolve(void *ctx, double t, const double *y, double gamma, const double *r,
                        double *z) {
  gs_case *c = ctx;
  gs_model_precondition(&c->model, &c->eval, t, y, gamma, r, z);
  return 0;
}

static void model_conserve(void *ctx, double *v) {
  gs_case *c = ctx;
  gs_model_conserve(&c->model, v);
}

static void model_hold(void *ctx, int on) {
  gs_case *c = ctx;
  c->eval.hold = on;
}

/* Absolute-tolerance scale of the ledger entries of axis k: the coordinate
 * of a typical particle (the initial mean, else the geometric mean of the
 * positive pivots), so that the ledger is resolved to atol particles' worth
 * of volume, or to a share of the balance it serves (LEDGER_SHARE, below)
 * where that is looser.  The ledger takes part in the error control because implicit
 * integrators solve their Newton systems only in the components that do:
 * left out, its entries would drift and break the volume balance. */
static double ledger_scale(const gs_model *m, const double *y0, int k) {
  const gs_grid *g = &m->grid;
  double n = 0, v = 0;
  for (size_t i = 0; i < m->nnum; i++) {
    n += y0[i];
    v += y0[i] * g->x[(i % g->ncells) * (size_t)g->dim + (size_t)k];
  }
  if (n > 0 && v > 0) return v / n;
  double logsum = 0;
  size_t count = 0;
  for (size_t i = 0; i < g->axis[k].n; i++)
    if (g->axis[k].pivots[i] > 0) {
      logsum += log(g->axis[k].pivots[i]);
      count++;
    }
  return count ? exp(logsum / (double)count) : 1.0;
}

/* The volume of every coordinate k (axes, then carried quantities) the run
 * handles: what the case holds at the start plus what the rates at the
 * start would bring in over the run (feeds, binder sprayed).  0 on failure
 * (out of memory, with err set). */
static int case_volumes(gs_case *c, double V[GS_MAX_VOL], gs_error *err) {
  const gs_model *m = &c->model;
  const size_t n = m->nstate + m->nledger;
  double *f = gs_calloc(n, sizeof(double), err);
  if (!f) return 0;
  c->eval.in_integrator = 1;
  gs_model_rhs(m, &c->eval, c->t0, c->y0, f, f + m->nstate);
  c->eval.in_integrator = 0;
  const double span = c->times[c->ntimes - 1] - c->t0;
  for (int k = 0; k < m->nvol; k++) {
    double total = 0, rate = 0;
    for (size_t comp = 0; comp < m->grid.ncomp; comp++) {
      total += gs_model_held(m, c->y0, comp, k);
      rate += gs_model_held(m, f, comp, k);
    }
    V[k] = total + fmax(rate, 0.0) * span;
  }
  free(f);
  return 1;
}

/* The default absolute tolerance of a case without solver.atol, in
 * particles: rtol times the smallest, over the grid's axes, of the case's
 * volume of that coordinate (case_volumes) divided by the axis' largest
 * pivot, i.e. a cell at the top of the grid holding atol particles carries
 * rtol of the volume (docs/models.md, "Default tolerances").  A fixed 1e-12
 * particles had made BDF steps resolve 1e-20 of a batch's particles and
 * crawl. */
static double default_atol(const gs_case *c, double rtol, const double V[GS_MAX_VOL]) {
  const gs_grid *g = &c->model.grid;
  double atol = HUGE_VAL;
  for (int k = 0; k < g->dim; k++) {
    const double top = g->axis[k].pivots[g->axis[k].n - 1];
    if (V[k] > 0 && top > 0 && isfinite(V[k])) atol = fmin(atol, rtol * V[k] / top);
  }
  return atol < HUGE_VAL && atol > 0 ? atol : GS_INTEGRATOR_ATOL;
}

/* The ledger's entries need no finer resolution than the balance they
 * serve, which is checked relative to the coordinate's volume: their
 * absolute tolerance is at least LEDGER_SHARE * rtol * V_k.  A typical
 * particle's worth (ledger_scale) alone had the volume lost beyond a coarse
 * grid's last pivot, made of the largest particles, resolved to 1e-11 of
 * the liquid, and the 3-D Madec case at 16 cells per axis took 2 258 BDF
 * steps where 26 cells take 270 (docs/design-notes.md, "Step counts"). */
#define LEDGER_SHARE 1e-2

/* solver.atol, or the case's default (above), which the integrator gets as a
 * scale of its own default on every component (abs_scale). */
static int case_atol(gs_cfg_node *root, gs_cfg_node *solver, gs_case *c, double *atol,
                     gs_error *err) {
  gs_cfg_node *an = solver ? gs_cfg_get(solver, "atol") : NULL;
  gs_cfg_node *rn = solver ? gs_cfg_get(solver, "rtol") : NULL;
  double rtol = 1e-6;
  /* both validated again by the integrator */
  if (an && gs_cfg_node_double(an, atol, err)) return GS_EINPUT;
  if (rn && gs_cfg_node_double(rn, &rtol, err)) return GS_EINPUT;
  double V[GS_MAX_VOL];
  if (!case_volumes(c, V, err)) return GS_ENOMEM;
  if (!an) *atol = default_atol(c, rtol, V);
  const gs_model *m = &c->model;
  for (size_t i = m->nstate; i < m->nstate + m->nledger; i++) {
    const int k = (int)((i - m->nstate) % (size_t)m->nvol);
    if (*atol > 0 && isfinite(V[k]) && V[k] > 0)
      c->abs_scale[i] = fmax(c->abs_scale[i], LEDGER_SHARE * rtol * V[k] / *atol);
  }
  if (!an) {
    const double factor = *atol / GS_INTEGRATOR_ATOL;
    for (size_t i = 0; i < c->ode.n; i++) c->abs_scale[i] *= factor;
  }
  /* totals beyond what doubles hold (number: 1e308) overflow here first */
  double vmax = 0;
  for (int k = 0; k < m->nvol; k++) vmax = fmax(vmax, V[k]);
  for (size_t i = 0; i < c->ode.n; i++)
    if (!isfinite(c->abs_scale[i]))
      return gs_cfg_fail(gs_cfg_get(root, "initial"), err,
                         "the case's totals (up to %g of a coordinate's volume) overflow the "
                         "solver's error scales: give numbers and sizes that doubles hold",
                         vmax);
  return GS_OK;
}

/* The mechanisms' scalars (gs_model.nscalar) join the state after the
 * initial distributions were read: y0 grows to hold them, they get their
 * initial values, and accuracy (ncomp * nscalar, allocated) their absolute
 * accuracies. */
static int initial_scalars(gs_case *c, double **accuracy, gs_error *err) {
  gs_model *m = &c->model;
  *accuracy = NULL;
  if (!m->nscalar) return GS_OK;
  const size_t n = m->nstate + m->nledger, ns = m->grid.ncomp * m->nscalar;
  double *y = realloc(c->y0, n * sizeof *y);
  if (!y) return gs_error_set(err, GS_ENOMEM, "out of memory");
  c->y0 = y;
  /* the ledger was all zero, so the tail from the scalars on is */
  memset(y + m->scalar_at, 0, (n - m->scalar_at) * sizeof *y);
  *accuracy = gs_calloc(ns, sizeof **accuracy, err);
  if (!*accuracy) return GS_ENOMEM;
  gs_model_initial_scalars(m, y, *accuracy);
  return GS_OK;
}

static int setup_ode(gs_cfg_node *root, gs_case *c, const double *accuracy, gs_error *err) {
  gs_model *m = &c->model;
  size_t n = m->nstate + m->nledger;
  const int dim = m->grid.dim;
  c->abs_scale = gs_malloc(n * sizeof(double), err);
  if (!c->abs_scale) return GS_ENOMEM;
  double scale[GS_MAX_VOL];
  for (int k = 0; k < dim; k++) scale[k] = ledger_scale(m, c->y0, k);
  /* carried totals and their ledger: resolved to atol particles' worth of a
   * typical particle volume (they are volumes, not numbers) */
  double vtyp = 1;
  for (int k = 0; k < dim; k++) vtyp = k ? vtyp + scale[k] : scale[k];
  for (int q = 0; q < m->ncarried; q++) scale[dim + q] = vtyp;
  for (size_t i = 0; i < n; i++)
    c->abs_scale[i] = i < m->nnum       ? 1.0
                      : i < m->nstate   ? vtyp /* scalars: set below */
                                        : scale[(i - m->nstate) % (size_t)m->nvol];
  gs_eval_init(&c->eval, m);
  c->ode = (gs_ode){.n = n,
                    .f = model_ode,
                    .ctx = c,
                    .abs_scale = c->abs_scale,
                    .npositive = m->scalar_at, /* scalars may be of either sign */
                    .psolve = gs_model_has_preconditioner(m) ? model_psolve : NULL,
                    .hold = model_hold,
                    .conserve = model_conserve};
  gs_cfg_node *solver = gs_cfg_get(root, "solver");
  if (solver && gs_cfg_require_kind(solver, GS_CFG_MAP, err)) return GS_EINPUT;
  static const char *const steps[] = {"shared", "per_compartment", NULL};
  int which = 0;
  if (solver && gs_cfg_enum_opt(solver, "steps", steps, 0, &which, err)) return GS_EINPUT;
  c->per_compartment = which == 1;
  c->rebalance = 0.05;
  gs_cfg_node *rb = solver ? gs_cfg_get(solver, "rebalance") : NULL;
  if (rb && gs_cfg_scalar(rb) && !strcmp(gs_cfg_scalar(rb), "none")) c->rebalance = -1;
  else if (rb && (gs_cfg_node_double(rb, &c->rebalance, err) || !(c->rebalance >= 0 && c->rebalance < 1)))
    return gs_cfg_fail(rb, err, "expected a fraction in [0, 1) or 'none'");
  int rc = gs_integrator_setup_read(solver, &c->integrator_setup, err);
  if (!rc) rc = case_atol(root, solver, c, &c->atol, err);
  /* scalars to their own accuracy, whatever the numbers' atol: the
   * integrator's is solver.atol if given, else GS_INTEGRATOR_ATOL */
  const double base = solver && gs_cfg_get(solver, "atol") ? c->atol : GS_INTEGRATOR_ATOL;
  for (size_t i = 0; !rc && i < m->grid.ncomp * m->nscalar; i++)
    c->abs_scale[m->scalar_at + i] = accuracy[i] / base;
  if (!rc && c->per_compartment && m->nscalar)
    return gs_cfg_fail(gs_cfg_get(solver, "steps"), err,
                       "per_compartment steps cannot carry the mechanisms' scalar state (a fluid "
                       "bed's balances): use steps: shared");
  if (!rc && c->per_compartment && gs_model_couples_all(m))
    return gs_cfg_fail(gs_cfg_get(solver, "steps"), err,
                       "per_compartment steps need flow in series (transfer); an exchange network "
                       "couples every compartment: use steps: shared");
  if (!rc && solver) rc = gs_cfg_check_unused(solver, err);
  if (!rc) rc = gs_integrator_create(&c->integrator_setup, &c->ode, &c->integrator, err);
  if (!rc && c->per_compartment && !c->integrator.type->per_compartment)
    return gs_cfg_fail(gs_cfg_get(solver, "steps"), err,
                       "per_compartment steps need method rk (the coupling of the compartments "
                       "relies on the exact quadrature of its Runge-Kutta steps), not %s",
                       c->integrator.type->name);
  return rc;
}

/* CVODE's Newton systems keep linear invariants such as the volume balance in
 * exact arithmetic (every operator they apply conserves: gs_ode.conserve and
 * the mechanisms' preconditioners), but round-off in its Newton iterations
 * can still move the balance to ~1e-10 (the 3-D Madec
 * benchmark with 101 output times: 3.9e-10; most cases ~1e-15).  Unless the
 * case sets checks.mass_tolerance, use max(1e-9, rtol) for integrators that
 * do not keep invariants exactly: it still catches any mechanism that leaks
 * mass faster than the solver tolerance. */
static void implicit_mass_tolerance(gs_cfg_node *root, gs_case *c) {
  gs_cfg_node *checks = gs_cfg_get(root, "checks");
  if (c->integrator.type->exact_invariants || (checks && gs_cfg_get(checks, "mass_tolerance")))
    return;
  gs_cfg_node *solver = gs_cfg_get(root, "solver");
  gs_cfg_node *rn = solver ? gs_cfg_get(solver, "rtol") : NULL;
  double rtol = 1e-6;
  if (rn) gs_cfg_node_double(rn, &rtol, NULL);
  c->checks.mass_tolerance = fmax(1e-9, rtol);
}

/* Numbers are controlled to an absolute accuracy atol (in the RMS norm of the
 * integrator), so small negative values of a few atol are integration noise,
 * not a failure. */
static void negative_floor(gs_case *c) {
  c->checks.negative_floor = 100 * c->atol;
  c->eval.noise_floor = c->atol;
}

int gs_case_read_times(gs_cfg_node *root, double *t0, double **times, size_t *ntimes,
                       gs_error *err) {
  gs_case tmp;
  memset(&tmp, 0, sizeof tmp);
  int rc = read_output(root, &tmp, err);
  *t0 = tmp.t0;
  *times = tmp.times;
  *ntimes = tmp.ntimes;
  return rc;
}

int gs_case_from_cfg(gs_cfg *cfg, gs_case *c, gs_error *err) {
  memset(c, 0, sizeof *c);
  c->cfg = cfg;
  gs_cfg_node *root = gs_cfg_root(cfg);
  if (!root) return gs_error_set(err, GS_EINPUT, "%s: the case file is empty", gs_cfg_name(cfg));
  const char *title = NULL;
  int rc = gs_cfg_require_kind(root, GS_CFG_MAP, err);
  if (!rc) rc = gs_cfg_string_opt(root, "title", "", &title, err);
  if (!rc) snprintf(c->title, sizeof c->title, "%s", title);
  const char *desc;
  if (!rc) rc = gs_cfg_string_opt(root, "description", "", &desc, err);
  gs_limits lim;
  if (!rc) rc = read_grid(root, &c->model, err);
  if (!rc) rc = gs_limits_read(root, &lim, err);
  if (!rc) rc = gs_limits_check_memory(&lim, root, &c->model, err);
  if (!rc) snprintf(c->model.dir, sizeof c->model.dir, "%s", gs_cfg_dir(cfg));
  if (!rc) {
    c->y0 = gs_calloc(c->model.nstate + c->model.nledger, sizeof(double), err);
    if (!c->y0) rc = GS_ENOMEM;
  }
  if (!rc) rc = gs_case_read_disc_tolerance(root, &c->model.disc->tolerance, err);
  if (!rc) rc = read_initial(root, &c->model, c->y0, err);
  if (!rc) rc = read_mechanisms(root, &c->model, err);
  if (!rc) rc = read_output(root, c, err);
  if (!rc) rc = gs_limits_check_output(&lim, root, &c->model, c->ntimes, err);
  if (!rc) rc = read_checks(root, &c->checks, err);
  double *accuracy = NULL;
  if (!rc) rc = initial_scalars(c, &accuracy, err);
  if (!rc) rc = setup_ode(root, c, accuracy, err);
  free(accuracy);
  if (!rc) implicit_mass_tolerance(root, c);
  if (!rc) negative_floor(c);
  if (!rc) rc = gs_cfg_check_unused(root, err);
  return rc;
}

int gs_case_load(const char *path, gs_case *c, gs_error *err) {
  memset(c, 0, sizeof *c);
  gs_cfg *cfg = gs_cfg_load_file(path, err);
  if (!cfg) return err->code;
  return gs_case_from_cfg(cfg, c, err);
}

void gs_case_free(gs_case *c) {
  gs_integrator_free(&c->integrator);
  gs_integrator_setup_free(&c->integrator_setup);
  gs_model_free(&c->model);
  free(c->y0);
  free(c->times);
  free(c->abs_scale);
  gs_cfg_free(c->cfg);
  memset(c, 0, sizeof *c);
}
