/* Breakage:  dn/dt = -S(v) n(v) + int_v b(v|u) S(u) n(u) du
 * for binary and multiple breakage.  A fragment keeps its parent's
 * composition: it is a fraction z of the parent, distributed as b(z) (a
 * registered daughter distribution), so in d dimensions fragments of the
 * parent at pivot X lie on the segment z X, 0 < z < 1.
 *
 * Discretisation, precomputed per parent cell: the z-range is cut where z X
 * crosses a cell edge of any axis (and, for fixed pivot, a pivot), so each
 * piece ("packet") lies in one cell; its number and mean position follow
 * exactly from the closed-form partial integrals of b.  Then
 *  - cell average: packets landing in each cell are pooled per right-hand
 *    side and the pool is placed with the lever rule (Kumar et al. 2008);
 *  - fixed pivot: each packet is placed with the lever rule at its own mean
 *    (in 1-D this equals Kumar & Ramkrishna's integrals exactly, since the
 *    lever weights are linear within a packet).
 * Number of fragments and the volume of every coordinate are conserved;
 * fragments below the first pivot are clamped to it (number conserved, the
 * created volume booked in the ledger as negative loss, see lever.h).
 * Carried quantities (cell average only): a parent's load leaves with it and
 * each packet receives the share of it equal to its share of the parent's
 * volume (fragments keep the parent's composition, so also its liquid and
 * gas per unit solid); pooled loads are placed with the particles' lever
 * weights, so every carried volume is conserved. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "gransim/kernel.h"
#include "gransim/pbm.h"
#include "pbm/lever.h"

enum { CELL_AVERAGE = 0, FIXED_PIVOT = 1 };

typedef struct {
  size_t cell;          /* target cell (CA) or destination node (FP) */
  double count;         /* fragments per breakage event */
  double vol[GS_MAX_DIM]; /* CA: volume per coordinate per event; FP: unused */
  double share;           /* CA: fraction of the parent's volume (and load) per event */
} packet_t;

typedef struct {
  gs_selection sel;
  gs_daughter dau;
  int scheme, dim;
  size_t ncells, ncomp;
  double *rate;         /* S per cell */
  size_t *first;        /* ncells+1: packets of parent k are [first[k], first[k+1]) */
  packet_t *pk;
  double *excess;       /* FP: volume removed by clamping (lever.h), per parent and axis */
  /* CA workspace per slot (gs_eval.slot), two pools each: from parents of
   * positive count, then negative (integration noise; pooled together, the
   * two can cancel in the count but not in the volume, and the pool's mean
   * then lies anywhere on the grid) */
  double *births, *vol; /* 2 ncells and 2 dim*ncells */
  int nc;               /* carried quantities */
  double *cbirth;       /* 2 nc*ncells pooled loads */
  size_t births_len, vol_len, cbirth_len; /* per-slot strides, whole pages (GS_APART) */
} brk_t;

static void brk_free(void *self) {
  brk_t *B = self;
  if (!B) return;
  gs_selection_free(&B->sel);
  gs_daughter_free(&B->dau);
  free(B->rate);
  free(B->first);
  free(B->pk);
  free(B->excess);
  free(B->births);
  free(B->vol);
  free(B->cbirth);
  free(B);
}

static int cmp_double(const void *a, const void *b) {
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

/* Breakpoints in z for parent cell k, sorted and unique, including 0 and 1. */
static size_t breakpoints(const brk_t *B, const gs_grid *g, size_t k, double *z) {
  size_t n = 0;
  z[n++] = 0.0;
  z[n++] = 1.0;
  for (int d = 0; d < g->dim; d++) {
    double X = g->x[k * (size_t)g->dim + (size_t)d];
    if (!(X > 0)) continue;
    const gs_axis *ax = &g->axis[d];
    for (size_t i = 0; i <= ax->n; i++) {
      double e = ax->edges[i] / X;
      if (e > 0 && e < 1) z[n++] = e;
      if (B->scheme == FIXED_PIVOT && i < ax->n) {
        double p = ax->pivots[i] / X;
        if (p > 0 && p < 1) z[n++] = p;
      }
    }
  }
  double atoms[4];
  int na = 0;
  B->dau.type->atoms(B->dau.self, atoms, &na);
  for (int i = 0; i < na; i++) z[n++] = atoms[i];
  qsort(z, n, sizeof(double), cmp_double);
  size_t m = 0;
  for (size_t i = 0; i < n; i++)
    if (!m || z[i] > z[m - 1]) z[m++] = z[i];
  return m;
}

/* Cell containing point v (clamped to the grid along each axis). */
static size_t containing_cell(const gs_grid *g, const double *v) {
  size_t idx[GS_MAX_DIM];
  for (int d = 0; d < g->dim; d++) {
    size_t i = gs_axis_locate_snapped(&g->axis[d], v[d]);
    idx[d] = i != GS_NOWHERE ? i : (v[d] < g->axis[d].edges[0] ? 0 : g->axis[d].n - 1);
  }
  return gs_grid_index(g, idx);
}

static int add_packet(brk_t *B, size_t *cap, size_t *n, packet_t p, gs_error *err) {
  if (*n == *cap) {
    *cap = *cap ? 2 * *cap : 1024;
    packet_t *grown = realloc(B->pk, *cap * sizeof *grown);
    if (!grown) return gs_error_set(err, GS_ENOMEM, "out of memory for breakage tables");
    B->pk = grown;
  }
  B->pk[(*n)++] = p;
  return GS_OK;
}

/* Packets of parent k: CA stores (cell, count, volume); FP stores node coefficients. */
static int parent_packets(brk_t *B, const gs_grid *g, size_t k, const gs_cfg_node *dn, double *z,
                          double *fp_row, size_t *cap, size_t *n, gs_error *err) {
  const int dim = g->dim;
  const double *X = g->x + k * (size_t)dim;
  size_t nz = breakpoints(B, g, k, z);
  const gs_daughter_type *dt = B->dau.type;
  if (B->scheme == FIXED_PIVOT) memset(fp_row, 0, g->ncells * sizeof(double));
  for (size_t i = 0; i + 1 < nz; i++) {
    double cnt = dt->count_below(B->dau.self, z[i + 1]) - dt->count_below(B->dau.self, z[i]);
    double mass = dt->mass_below(B->dau.self, z[i + 1]) - dt->mass_below(B->dau.self, z[i]);
    if (!isfinite(cnt) || !isfinite(mass))
      return gs_cfg_fail(dn, err,
                         "daughter distribution '%s' cannot be evaluated between fractions %.9g and "
                         "%.9g of cell %zu's volume: GSL: %s",
                         dt->name, z[i], z[i + 1], k, *gs_gsl_reason() ? gs_gsl_reason() : "not finite");
    if (!(cnt > 0)) continue;
    double zbar = mass / cnt, v[GS_MAX_DIM];
    for (int d = 0; d < dim; d++) v[d] = zbar * X[d];
    if (B->scheme == FIXED_PIVOT) {
      gs_lever_place(g, GS_NOWHERE, v, cnt, fp_row, B->excess + k * (size_t)dim);
      continue;
    }
    packet_t p = {containing_cell(g, v), cnt, {0}, mass};
    for (int d = 0; d < dim; d++) p.vol[d] = mass * X[d];
    if (add_packet(B, cap, n, p, err)) return GS_ENOMEM;
  }
  for (size_t c = 0; B->scheme == FIXED_PIVOT && c < g->ncells; c++)
    if (fp_row[c] != 0.0 && add_packet(B, cap, n, (packet_t){c, fp_row[c], {0}, 0.0}, err))
      return GS_ENOMEM;
  return GS_OK;
}

/* dn: the daughters key, named if the distribution cannot be evaluated. */
static int build_packets(brk_t *B, const gs_grid *g, const gs_cfg_node *dn, gs_error *err) {
  size_t zcap = 8;
  for (int d = 0; d < g->dim; d++) zcap += 2 * (g->axis[d].n + 1);
  double *z = gs_malloc(zcap * sizeof(double), err);
  double *fp_row = gs_calloc(g->ncells, sizeof(double), err);
  B->first = gs_calloc(g->ncells + 1, sizeof(size_t), err);
  B->excess = gs_calloc(g->ncells * (size_t)g->dim, sizeof(double), err);
  int rc = (!z || !fp_row || !B->first || !B->excess) ? GS_ENOMEM : GS_OK;
  size_t cap = 0, n = 0;
  gs_gsl_clear();
  for (size_t k = 0; !rc && k < g->ncells; k++) {
    B->first[k] = n;
    if (B->rate[k] > 0) rc = parent_packets(B, g, k, dn, z, fp_row, &cap, &n, err);
  }
  if (!rc) B->first[g->ncells] = n;
  free(z);
  free(fp_row);
  return rc;
}

static int brk_create(gs_cfg_node *node, const gs_model *m, void **self, gs_error *err) {
  static const char *const schemes[] = {"cell_average", "fixed_pivot", NULL};
  const gs_grid *g = &m->grid;
  brk_t *B = gs_calloc(1, sizeof *B, err);
  if (!B) return GS_ENOMEM;
  gs_cfg_node *sn = NULL, *dn = NULL;
  int rc = gs_cfg_enum_opt(node, "redistribution", schemes, CELL_AVERAGE, &B->scheme, err);
  if (!rc && m->ncarried && B->scheme == FIXED_PIVOT)
    rc = gs_cfg_fail(node, err, "fixed_pivot does not move carried quantities (grid.carried); use cell_average");
  if (!rc) rc = gs_cfg_map_req(node, "selection", &sn, err);
  if (!rc) rc = gs_cfg_map_req(node, "daughters", &dn, err);
  if (!rc) rc = gs_selection_create(sn, g, m->dir, &B->sel, err);
  if (!rc) rc = gs_daughter_create(dn, &B->dau, err);
  if (!rc) rc = gs_cfg_check_unused(node, err);
  B->dim = g->dim;
  B->ncells = g->ncells;
  B->ncomp = g->ncomp;
  if (!rc) {
    B->rate = gs_malloc(g->ncells * sizeof(double), err);
    const size_t nslot = m->nslots > 0 ? (size_t)m->nslots : 1;
    /* per slot, on pages of their own: threads write them at once */
    B->nc = m->ncarried;
    B->births_len = gs_doubles_apart(2 * g->ncells);
    B->vol_len = gs_doubles_apart(2 * g->ncells * (size_t)g->dim);
    B->cbirth_len = gs_doubles_apart(2 * (size_t)B->nc * g->ncells + 1);
    B->births = gs_calloc_apart(nslot * B->births_len * sizeof(double), err);
    B->vol = gs_calloc_apart(nslot * B->vol_len * sizeof(double), err);
    B->cbirth = gs_calloc_apart(nslot * B->cbirth_len * sizeof(double), err);
    if (!B->rate || !B->births || !B->vol || !B->cbirth) rc = GS_ENOMEM;
  }
  for (size_t k = 0; !rc && k < g->ncells; k++) {
    B->rate[k] = B->sel.type->rate(B->sel.self, g, k);
    if (!(B->rate[k] >= 0) || !isfinite(B->rate[k]))
      rc = gs_cfg_fail(sn, err, "selection function gives %g at cell %zu (expected a finite rate >= 0)",
                       B->rate[k], k);
  }
  if (!rc) rc = build_packets(B, g, dn, err);
  if (rc) {
    brk_free(B);
    return rc;
  }
  *self = B;
  return GS_OK;
}

/* Compartment comp's rates (dydt, dledger), or with dydt NULL its number
 * formation and depletion rates alone (birth, death). */
static void brk_compartment(brk_t *B, const gs_model *m, const gs_eval *ev, size_t comp,
                            const double *y, double *dydt, double *dledger, double *birth,
                            double *death) {
  const gs_grid *g = &m->grid;
  const int dim = B->dim;
  /* this caller's workspace (several may evaluate compartments at once) */
  const size_t slot = ev->slot > 0 ? (size_t)ev->slot : 0;
  double *births = B->births + slot * B->births_len, *vol = B->vol + slot * B->vol_len;
  double *cbirth = B->cbirth + slot * B->cbirth_len;
  {
    const double *N = gs_eval_numbers_c(m, ev, y, comp);
    double *d = dydt ? gs_eval_numbers(m, ev, dydt, comp) : NULL;
    double *lost = dledger ? gs_eval_ledger(m, ev, dledger, comp) + m->nvol : NULL;
    double born = 0, dead = 0, excess[GS_MAX_DIM] = {0};
    if (B->scheme == CELL_AVERAGE) {
      memset(births, 0, 2 * B->ncells * sizeof(double));
      memset(vol, 0, 2 * B->ncells * (size_t)dim * sizeof(double));
      memset(cbirth, 0, 2 * (size_t)B->nc * B->ncells * sizeof(double));
    }
    double *qdst[GS_MAX_CARRIED] = {NULL, NULL};
    for (int q = 0; d && q < B->nc; q++) qdst[q] = gs_eval_carried(m, ev, dydt, comp, q);
    for (size_t k = 0; k < B->ncells; k++) {
      double r = B->rate[k] * N[k];
      if (r == 0.0) continue;
      dead += r;
      if (d) d[k] -= r;
      double load[GS_MAX_CARRIED] = {0, 0}; /* carried by one parent */
      for (int q = 0; q < B->nc; q++) {
        load[q] = N[k] > 0 ? gs_eval_carried_c(m, ev, y, comp, q)[k] / N[k] : 0.0;
        if (d) qdst[q][k] -= r * load[q];
      }
      for (size_t p = B->first[k]; p < B->first[k + 1]; p++) {
        const packet_t *pk = &B->pk[p];
        if (B->scheme == FIXED_PIVOT) {
          if (d) d[pk->cell] += r * pk->count;
          born += r * pk->count;
          continue;
        }
        const size_t t = pk->cell + (r < 0 ? B->ncells : 0); /* the pool of r's sign */
        births[t] += r * pk->count;
        for (int q = 0; q < dim; q++) vol[t * (size_t)dim + (size_t)q] += r * pk->vol[q];
        for (int q = 0; q < B->nc; q++) cbirth[(size_t)q * 2 * B->ncells + t] += r * pk->share * load[q];
      }
      if (B->scheme == FIXED_PIVOT)
        for (int q = 0; q < dim; q++) excess[q] += r * B->excess[k * (size_t)dim + (size_t)q];
    }
    for (size_t t = 0; B->scheme == CELL_AVERAGE && t < 2 * B->ncells; t++) {
      double b = births[t];
      if (b == 0.0) continue;
      double vbar[GS_MAX_DIM], qtot[GS_MAX_CARRIED];
      for (int q = 0; q < dim; q++) vbar[q] = vol[t * (size_t)dim + (size_t)q] / b;
      for (int q = 0; q < B->nc; q++) qtot[q] = cbirth[(size_t)q * 2 * B->ncells + t];
      if (d) gs_lever_place_carried(g, t % B->ncells, vbar, b, d, excess, B->nc, qtot, qdst);
      born += b;
    }
    if (lost)
      for (int q = 0; q < dim; q++) lost[q] += excess[q];
    if (birth) *birth = born;
    if (death) *death = dead;
  }
}

static void brk_rhs(void *self, const gs_model *m, const gs_eval *ev, size_t comp, double t,
                    const double *y, double *dydt, double *dledger) {
  (void)t;
  brk_compartment(self, m, ev, comp, y, dydt, dledger, NULL, NULL);
}

static void brk_number_rates(void *self, const gs_model *m, const gs_eval *ev, size_t comp,
                             double t, const double *y, double *birth, double *death) {
  (void)t;
  brk_compartment(self, m, ev, comp, y, NULL, NULL, birth, death);
}

const gs_mech_type gs_mech_breakage = {
    .name = "breakage",
    .summary = "breakage with a selection function and a daughter distribution",
    .create = brk_create,
    .rates = brk_rhs,
    .number_rates = brk_number_rates,
    .free = brk_free,
};
